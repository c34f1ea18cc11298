# Quick start on a machine with only Python 3.11 (no ROS installed):
#   make run    set up .venv and start rotation_node
#   make test   set up .venv with the test tools and run every test
#   make bench  set up .venv with bench/requirements.txt and run bench/run_all.py
# Each set-up step leaves a stamp file in .venv, so a second run installs nothing unless a
# requirements file or the packaging files changed. `make clean` removes .venv.

PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
PIP := $(BIN)/python -m pip --disable-pip-version-check --no-input
PYTEST_ARGS ?=
NODE_ARGS ?=

.PHONY: run test bench venv test-venv clean

run: $(VENV)/.stamp-run
	$(BIN)/rotation_node $(NODE_ARGS)

test: $(VENV)/.stamp-test
	$(BIN)/python -m pytest -p no:cacheprovider $(PYTEST_ARGS)

bench: $(VENV)/.stamp-run
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

venv: $(VENV)/.stamp-run

test-venv: $(VENV)/.stamp-test

# The package is installed editable, so edits to rot_tools/*.py need no reinstall. Console
# scripts land in $(BIN) (pip builds a wheel; setup.cfg's [install]/[develop] script dirs
# apply only to colcon / `setup.py install|develop`, which put them in lib/rot_tools).
$(VENV)/.stamp-run: requirements.txt setup.py setup.cfg package.xml Makefile
	@command -v $(PYTHON) >/dev/null || { \
	  echo 'make: $(PYTHON) not found: install Python 3.11 or pass PYTHON=/path/to/python3.11' >&2; \
	  exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(PIP) install -r requirements.txt
	$(PIP) install --no-build-isolation -e .
	touch $@

$(VENV)/.stamp-test: $(VENV)/.stamp-run requirements-test.txt
	$(PIP) install -r requirements-test.txt
	$(PIP) check
	touch $@

clean:
	rm -rf $(VENV) build rot_tools.egg-info
