# Quick start on a machine with Python 3.11 or 3.12 (no ROS installed; 3.11 when both are):
#   make run          set up .venv and start rotation_node
#   make test         set up both venvs and run every test in each, side by side (CI):
#                     .venv (Python 3.11, the pinned versions of requirements*.txt) and
#                     .venv-stock (Python 3.12 with Ubuntu 24.04's NumPy, SciPy and pytest,
#                     requirements-stock*.txt)
#   make test-pinned  only the .venv suite (the quick one for development)
#   make test-stock   only the .venv-stock suite
#   make bench        set up .venv with bench/requirements.txt and run bench/run_all.py
# Each venv gets tf2_msgs (TFMessage), built from vendor/tf2_msgs by tools/build_tf2_msgs.py
# unless it imports already (it needs a C/C++ compiler and make; cmake comes from PyPI).
# Each set-up step leaves a stamp file in its venv, so a second run installs nothing unless
# a requirements file or the packaging files changed. `make clean` removes both venvs.

PYTHON ?= $(shell tools/find_python.sh 3.11 || tools/find_python.sh 3.12 || echo python3.11)
STOCK_PYTHON ?= $(shell tools/find_python.sh 3.12)
VENV := .venv
BIN := $(VENV)/bin
PIP := $(BIN)/python -m pip --disable-pip-version-check --no-input
STOCK_VENV := .venv-stock
STOCK_BIN := $(STOCK_VENV)/bin
STOCK_PIP := $(STOCK_BIN)/python -m pip --disable-pip-version-check --no-input
PYTEST_ARGS ?=
NODE_ARGS ?=
# compat: a path entry for the checkout instead of an import hook, so that a directory named
# rot_tools in the current directory (the clone itself, seen from its parent) cannot shadow
# the package with an empty namespace package. --use-pep517: without it pip 23.2 falls back
# to `setup.py develop` whenever the `wheel` package is installed, and setup.cfg's [develop]
# script_dir (for colcon) then puts the console scripts in lib/rot_tools instead of $(BIN).
EDITABLE := --no-build-isolation --use-pep517 --config-settings editable_mode=compat -e .
PACKAGING := setup.py setup.cfg package.xml Makefile
TF2_MSGS := requirements-build.txt tools/build_tf2_msgs.py vendor/tf2_msgs/CMakeLists.txt \
	vendor/tf2_msgs/package.xml vendor/tf2_msgs/msg/TFMessage.msg

.PHONY: run test test-pinned test-stock bench venv test-venv test-venv-stock clean

# run also installs the optional extras the README says it does: bag (rosbags; pyarrow for
# rot-tools bag --parquet) and plot (matplotlib), at their pins in requirements-test.txt.
run: $(VENV)/.stamp-tf2_msgs $(VENV)/.stamp-extras
	$(BIN)/rotation_node $(NODE_ARGS)

$(VENV)/.stamp-extras: $(VENV)/.stamp-run requirements-test.txt
	$(PIP) install -c requirements-test.txt matplotlib rosbags pyarrow
	touch $@

# Both venvs are set up and both suites run side by side (most of a suite's time is spent
# waiting for child processes and DDS, not computing); each one's output is printed when it
# ends, and both run to the end even when one fails. Without Python 3.12 only the pinned
# suite runs, after a note saying so (in CI, CI=true, that is an error instead).
test:
	@if [ -n "$(STOCK_PYTHON)" ] || [ -n "$$CI" ]; then \
	  $(MAKE) --no-print-directory -j2 --output-sync=target -k test-pinned test-stock; \
	else \
	  echo 'make test: no Python 3.12 found (python3.12 on PATH or in pyenv), so the suite' \
	    'on the stock versions is skipped; install Python 3.12 or pass' \
	    'STOCK_PYTHON=/path/to/python3.12 to run it too.'; \
	  $(MAKE) --no-print-directory test-pinned; \
	fi

# The package's bytecode first, as an install writes it: the tests start hundreds of
# rot-tools and rotation_node processes, and without it (PYTHONDONTWRITEBYTECODE) each one
# compiles the source again.
test-pinned: $(VENV)/.stamp-test
	$(BIN)/python -m compileall -q rot_tools
	$(BIN)/python -m pytest -p no:cacheprovider $(PYTEST_ARGS)

test-stock: $(STOCK_VENV)/.stamp-test
	$(STOCK_BIN)/python -m compileall -q rot_tools
	$(STOCK_BIN)/python -m pytest -p no:cacheprovider $(PYTEST_ARGS)

bench: $(VENV)/.stamp-tf2_msgs
	@if [ -f bench/requirements.txt ]; then \
	  $(PIP) install -r bench/requirements.txt; \
	else \
	  echo 'make bench: bench/requirements.txt not found; installing nothing extra.'; \
	fi
	@if [ ! -f bench/run_all.py ]; then \
	  echo 'make bench: bench/run_all.py not found; there is no benchmark to run yet.' >&2; \
	  exit 1; \
	fi
	$(BIN)/python bench/run_all.py

venv: $(VENV)/.stamp-tf2_msgs

test-venv: $(VENV)/.stamp-test

test-venv-stock: $(STOCK_VENV)/.stamp-test

# The package is installed editable, so edits to rot_tools/*.py need no reinstall. Console
# scripts land in $(BIN) (pip builds a wheel; setup.cfg's [install]/[develop] script dirs
# apply only to colcon / `setup.py install|develop`, which put them in lib/rot_tools).
$(VENV)/.stamp-run: requirements.txt $(PACKAGING)
	@command -v $(PYTHON) >/dev/null || { \
	  echo 'make: no python3.11 or python3.12 found: install one or pass PYTHON=/path/to/python3' >&2; \
	  exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(PIP) install -r requirements.txt
	$(PIP) install $(EDITABLE)
	touch $@

$(VENV)/.stamp-tf2_msgs: $(VENV)/.stamp-run $(TF2_MSGS)
	$(BIN)/python tools/build_tf2_msgs.py
	touch $@

$(VENV)/.stamp-test: $(VENV)/.stamp-tf2_msgs requirements-test.txt
	$(PIP) install -r requirements-test.txt
	$(PIP) check
	touch $@

$(STOCK_VENV)/.stamp-run: requirements-stock.txt $(PACKAGING)
	@[ -n "$(STOCK_PYTHON)" ] && command -v $(STOCK_PYTHON) >/dev/null || { \
	  echo 'make: Python 3.12 not found (python3.12 on PATH or in pyenv): install it' \
	    'or pass STOCK_PYTHON=/path/to/python3.12' >&2; \
	  exit 1; }
	$(STOCK_PYTHON) -m venv $(STOCK_VENV)
	$(STOCK_PIP) install -r requirements-stock.txt
	$(STOCK_PIP) install $(EDITABLE)
	touch $@

$(STOCK_VENV)/.stamp-tf2_msgs: $(STOCK_VENV)/.stamp-run $(TF2_MSGS)
	$(STOCK_BIN)/python tools/build_tf2_msgs.py
	touch $@

$(STOCK_VENV)/.stamp-test: $(STOCK_VENV)/.stamp-tf2_msgs requirements-stock-test.txt
	$(STOCK_PIP) install -r requirements-stock-test.txt
	$(STOCK_PIP) check
	touch $@

clean:
	rm -rf $(VENV) $(STOCK_VENV) build rot_tools.egg-info
