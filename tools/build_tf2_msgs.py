"""
Build vendor/tf2_msgs (TFMessage) into the running Python's environment, if it lacks one.

PyPI carries the ROS 2 Jazzy wheels of rclpy and the common interfaces but no tf2_msgs. Run
with a virtual environment's Python (`make run` and `make test` do it), this script:

1. does nothing when ``tf2_msgs.msg.TFMessage`` already imports with its type support (a
   sourced ROS install, or an earlier build);
2. otherwise checks for a C and a C++ compiler, make and the Python headers, and says in one
   line what to install when one is missing;
3. installs the pinned rosidl / ament build wheels and cmake (requirements-build.txt);
4. configures, builds and installs vendor/tf2_msgs with the environment as the install
   prefix, so that nothing needs sourcing afterwards.

The build's output goes to ``<prefix>/tf2_msgs-build.log``; its last lines are printed when it
fails. Exit status 0 when TFMessage imports at the end, 1 otherwise.
"""

import os
from pathlib import Path
import shutil
import subprocess
import sys
import sysconfig
import time

REPO = Path(__file__).resolve().parents[1]
SOURCE = REPO / 'vendor' / 'tf2_msgs'
REQUIREMENTS = REPO / 'requirements-build.txt'
PREFIX = Path(sys.prefix)
LOG = PREFIX / 'tf2_msgs-build.log'
BUILD_DIR = PREFIX / 'tf2_msgs-build'
IMPORT_CHECK = (
    'from tf2_msgs.msg import TFMessage\n'
    'TFMessage.__class__.__import_type_support__()\n'
    'assert TFMessage._TYPE_SUPPORT is not None, "no type support"\n')
INSTALL_HINT = 'on Debian/Ubuntu: sudo apt install build-essential'


def importable():
    """Return True when TFMessage and its C type support load in a fresh interpreter."""
    result = subprocess.run([sys.executable, '-c', IMPORT_CHECK], stdin=subprocess.DEVNULL,
                            capture_output=True)
    return result.returncode == 0


def missing_tool():
    """Return the one line naming what this machine lacks for the build, or None."""
    compilers = [('C compiler', 'CC', ('cc', 'gcc', 'clang')),
                 ('C++ compiler', 'CXX', ('c++', 'g++', 'clang++'))]
    for what, variable, names in compilers:
        given = os.environ.get(variable, '').split()
        if given and shutil.which(given[0]):
            continue
        if not any(shutil.which(name) for name in names):
            return (f'building tf2_msgs needs a {what} (none of {", ".join(names)} is on '
                    f'PATH): install one ({INSTALL_HINT}), then run make again')
    if not shutil.which('make'):
        return (f'building tf2_msgs needs make: install it ({INSTALL_HINT}), '
                'then run make again')
    include = Path(sysconfig.get_paths()['include'])
    if not (include / 'Python.h').is_file():
        version = f'{sys.version_info.major}.{sys.version_info.minor}'
        return (f'building tf2_msgs needs the headers of Python {version} ({include}/Python.h '
                f'is missing): install them (on Debian/Ubuntu: sudo apt install '
                f'python{version}-dev), then run make again')
    return None


def run(command, log):
    """Run ``command`` with its output appended to ``log``; return its exit status."""
    log.write(f'$ {" ".join(map(str, command))}\n')
    log.flush()
    # Only this environment's ROS packages: never a sourced ROS install's (another Python).
    env = dict(os.environ, AMENT_PREFIX_PATH=str(PREFIX), CMAKE_PREFIX_PATH=str(PREFIX))
    return subprocess.run(list(map(str, command)), stdin=subprocess.DEVNULL, stdout=log,
                          stderr=subprocess.STDOUT, env=env).returncode


def fail(message):
    """Print ``message`` and the log's tail to stderr; return exit status 1."""
    lines = LOG.read_text(errors='replace').splitlines() if LOG.is_file() else []
    tail = '\n'.join(lines[-40:])
    print(f'{tail}\n{sys.argv[0]}: {message} (full output: {LOG})', file=sys.stderr)
    return 1


def build():
    """Install the build tools, then configure, build and install vendor/tf2_msgs."""
    cmake = Path(sys.executable).with_name('cmake')
    jobs = str(os.cpu_count() or 1)
    steps = [
        ('installing the build tools',
         [sys.executable, '-m', 'pip', 'install', '--disable-pip-version-check', '--no-input',
          '-r', REQUIREMENTS]),
        ('configuring',
         [cmake, '-S', SOURCE, '-B', BUILD_DIR, '-G', 'Unix Makefiles',
          f'-DCMAKE_INSTALL_PREFIX={PREFIX}', f'-DCMAKE_PREFIX_PATH={PREFIX}',
          f'-DPython3_EXECUTABLE={sys.executable}',
          '-DBUILD_TESTING=OFF', '-DCMAKE_BUILD_TYPE=Release']),
        ('building', [cmake, '--build', BUILD_DIR, '--parallel', jobs]),
        ('installing', [cmake, '--install', BUILD_DIR]),
    ]
    shutil.rmtree(BUILD_DIR, ignore_errors=True)
    with open(LOG, 'w') as log:
        for what, command in steps:
            if run(command, log) != 0:
                return fail(f'tf2_msgs: {what} failed')
    shutil.rmtree(BUILD_DIR, ignore_errors=True)
    return 0


def main():
    """Build tf2_msgs unless it imports already; return the exit status."""
    if importable():
        print(f'tf2_msgs: TFMessage already imports in {PREFIX}; nothing to build')
        return 0
    problem = missing_tool()
    if problem:
        print(f'{sys.argv[0]}: {problem}', file=sys.stderr)
        return 1
    begin = time.monotonic()
    print(f'tf2_msgs: building TFMessage into {PREFIX} (about a minute; log: {LOG})',
          flush=True)
    status = build()
    if status:
        return status
    if not importable():
        return fail('tf2_msgs was built and installed but does not import')
    print(f'tf2_msgs: built and installed in {time.monotonic() - begin:.0f} s')
    return 0


if __name__ == '__main__':
    sys.exit(main())
