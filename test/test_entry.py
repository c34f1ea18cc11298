"""
How rotation_node and rotation_client start: the process runtime (rot_tools.ros.runtime).

Both ways of starting the node — its console script and ``python -m rot_tools.ros.rotation_node``
(the benchmarks use the latter) — stop cleanly on a signal even while NumPy and rclpy load,
and bad ROS arguments end them with one line and status 2. The runtime depends on nothing of
the node: the modules' import graph has no cycle.
"""

import ast
import math
from pathlib import Path
import signal
import subprocess
import sys
import time

from conftest import console_script, RUN, script_env
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'rot_tools'

LIGHT = """
import sys
import rot_tools.ros.entry, rot_tools.ros.runtime
heavy = sorted(m for m in ('numpy', 'rclpy') if m in sys.modules)
print(','.join(heavy) or 'light')
"""

# A sitecustomize that sends a signal to its own process at the first import of NumPy or
# rclpy: exactly the window in which Python's default handling would end the program with
# status -15 or a KeyboardInterrupt traceback. Put on PYTHONPATH, it runs in the real
# command (console script or python -m) before the program does.
SIGNAL_AT_HEAVY_IMPORT = """
import builtins, os, signal
_real_import = builtins.__import__
_sent = []
def _import_and_signal(name, *args, **kwargs):
    if name.split('.')[0] in ('numpy', 'rclpy') and not _sent:
        _sent.append(name)
        os.kill(os.getpid(), signal.{sig})
    return _real_import(name, *args, **kwargs)
builtins.__import__ = _import_and_signal
"""


def node_commands():
    """Both commands that start rotation_node: the console script (when installed), -m."""
    commands = {'python -m': [sys.executable, '-m', 'rot_tools.ros.rotation_node']}
    script = console_script('rotation_node', 'rot_tools.ros.rotation_node')
    if script[0] != sys.executable:
        commands['console script'] = script
    return commands


NODE_COMMANDS = node_commands()


def run(command, *args, env_extra=None, timeout=60):
    """Run ``command`` + args to the end; return the CompletedProcess (text)."""
    command = [*command, *args]
    env = dict(script_env(command), **(env_extra or {}))
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout, env=env,
                          stdin=subprocess.DEVNULL)


def with_signal_hook(tmp_path, sig):
    """PYTHONPATH entries that make the next program signal itself at its heavy imports."""
    (tmp_path / 'sitecustomize.py').write_text(SIGNAL_AT_HEAVY_IMPORT.format(sig=sig))
    repo = str(PACKAGE.parent)
    return {'PYTHONPATH': f'{tmp_path}:{repo}'}


def test_entry_and_runtime_import_nothing_heavy():
    out = subprocess.run([sys.executable, '-c', LIGHT], capture_output=True, text=True,
                         timeout=60, check=True)
    assert out.stdout.strip() == 'light'


@pytest.mark.parametrize('how', sorted(NODE_COMMANDS))
@pytest.mark.parametrize('sig', ['SIGTERM', 'SIGINT'])
def test_signal_while_the_node_loads_exits_cleanly(tmp_path, how, sig):
    proc = run(NODE_COMMANDS[how], env_extra=with_signal_hook(tmp_path, sig))
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == ''


# A sitecustomize that sends a signal to its own process at one moment of the start-up:
# at the import of module {module!r} ('' for none), at the {nth}-th import statement
# (0 for none) of a module of NumPy, rclpy or rot_tools, as rclpy starts to make the node
# ({in_build}: the context shuts down, from rclpy's thread, while rcl makes it), or just after
# rotation_node's ready line (the end of RotationNode.__init__: {after_ready}). Imports are
# counted from the moment the program has a SIGTERM handler: before it (the interpreter's
# start and the console script importing rot_tools.ros.entry) a signal ends it as any Python
# program (test_signals_from_the_first_millisecond_to_after_the_ready_line).
SIGNAL_AT_A_MOMENT = """
import builtins, os, signal, sys
_real_import = builtins.__import__
_seen = []
def _signal():
    if not _seen or _seen[-1] != 'sent':
        _seen.append('sent')
        os.kill(os.getpid(), signal.{sig})
def _import(name, *args, **kwargs):
    if (name.split('.')[0] in ('numpy', 'rclpy', 'rot_tools')
            and signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL):
        _seen.append(name)
        if name == {module!r} or len(_seen) == {nth}:
            _signal()
    module = _real_import(name, *args, **kwargs)
    node = getattr(sys.modules.get('rot_tools.ros.rotation_node'), 'RotationNode', None)
    if {after_ready} and node is not None and 'patched' not in _seen:
        _seen.append('patched')
        build = node.__init__
        def build_then_signal(self, *a, **k):
            build(self, *a, **k)
            _signal()
        node.__init__ = build_then_signal
    rclpy_node = getattr(sys.modules.get('rclpy.node'), 'Node', None)
    if {in_build} and rclpy_node is not None and 'patched' not in _seen:
        _seen.append('patched')
        make = rclpy_node.__init__
        def signal_then_make(self, *a, **k):
            _signal()
            make(self, *a, **k)
        rclpy_node.__init__ = signal_then_make
    return module
builtins.__import__ = _import
"""

START_UP_MOMENTS = {
    **{f'import {n}': {'nth': n} for n in (1, 3, 10, 30, 60, 100, 200, 400, 800)},
    # rclpy.signals half imported: rot_tools' handler looked up its function there.
    'rclpy.signals half imported': {'module': 'rclpy.exceptions'},
    # The context shut down before the executor was made: it failed half built.
    'after the ready line': {'after_ready': True},
    # rclpy warned 'Failed to fini rosout publisher' (RuntimeWarning) as the node failed.
    'as rclpy makes the node': {'in_build': True},
}
"""Moments of the start-up to signal at: 12 a signal, 24 with both signals."""


@pytest.mark.parametrize('sig', ['SIGTERM', 'SIGINT'])
@pytest.mark.parametrize('moment', sorted(START_UP_MOMENTS))
def test_a_signal_at_any_moment_of_the_start_up_exits_0_quietly(tmp_path, moment, sig):
    hook = dict({'module': '', 'nth': 0, 'after_ready': False, 'in_build': False},
                **START_UP_MOMENTS[moment])
    (tmp_path / 'sitecustomize.py').write_text(SIGNAL_AT_A_MOMENT.format(sig=sig, **hook))
    command = NODE_COMMANDS.get('console script', NODE_COMMANDS['python -m'])
    proc = run(command, '--ros-args', '-r', f'__ns:=/{RUN}/startup', timeout=30,
               env_extra={'PYTHONPATH': f'{tmp_path}:{PACKAGE.parent}'})
    shown = [line for line in proc.stderr.splitlines() if 'decomposing' not in line]
    assert (proc.returncode, shown) == (0, []), proc.stderr


# A sitecustomize that sends signal {signum} to its own process at one import statement: the
# first import of {name!r} made by module {importer!r} (None: by any). A console script
# without handlers of its own before rot_tools.ros.runtime.start met these with Python's
# default (SIGINT: a KeyboardInterrupt traceback; SIGTERM: status -15); a handler that
# raises while NumPy's C extension initialises met them with an ImportError traceback.
SIGNAL_AT_AN_IMPORT = """
import builtins, os
_real_import = builtins.__import__
_sent = []
def _import(name, globals=None, locals=None, fromlist=(), level=0):
    importer = (globals or {{}}).get('__name__')
    if not _sent and name == {name!r} and {importer!r} in (None, importer):
        _sent.append(name)
        os.kill(os.getpid(), {signum})
    return _real_import(name, globals, locals, fromlist, level)
builtins.__import__ = _import
"""

EARLY_MOMENTS = {
    'entry imports the runtime': ('rot_tools.ros.entry', 'rot_tools.ros'),
    **{f'the runtime imports {name}': ('rot_tools.ros.runtime', name)
       for name in ('os', 're', 'signal', 'sys', 'importlib')},
    # NumPy's C extension imports datetime (PyCapsule_Import): an exception raised in
    # that import comes out as ImportError, and NumPy's message about a broken install.
    "NumPy's C extension imports datetime": (None, 'datetime'),
}
"""(importer, name) of the imports to signal at: 7 moments."""


@pytest.mark.parametrize('program, sig, status', [
    ('rotation_node', signal.SIGINT, 0), ('rotation_node', signal.SIGTERM, 0),
    ('rotation_client', signal.SIGINT, 130), ('rotation_client', signal.SIGTERM, -15)],
    ids=['node-SIGINT', 'node-SIGTERM', 'client-SIGINT', 'client-SIGTERM'])
@pytest.mark.parametrize('moment', sorted(EARLY_MOMENTS))
def test_a_signal_while_the_program_loads_ends_it_quietly(tmp_path, moment, program, sig,
                                                          status):
    command = console_script(program, f'rot_tools.ros.{program}')
    if command[0] == sys.executable:
        pytest.skip(f'{program} is not installed: python -m does not go through entry')
    importer, name = EARLY_MOMENTS[moment]
    (tmp_path / 'sitecustomize.py').write_text(SIGNAL_AT_AN_IMPORT.format(
        signum=int(sig), name=name, importer=importer))
    args = ['describe'] if program == 'rotation_client' else []
    proc = run(command, *args, '--ros-args', '-r', f'__ns:=/{RUN}/loads',
               env_extra={'PYTHONPATH': f'{tmp_path}:{PACKAGE.parent}'}, timeout=30)
    assert (proc.returncode, proc.stderr) == (status, ''), proc.stderr


# A sitecustomize that writes to file {path!r} the time (time.monotonic, one clock for every
# process) of the first import statement after the program's first SIGINT handler (rot_tools.
# ros.entry's) is in place: a SIGINT sent before it meets Python's own handling.
HANDLER_PROBE = """
import builtins, os, sys, time
_real_import = builtins.__import__
_seen = []
def _import(*args, **kwargs):
    signal = sys.modules.get('signal')
    if (not _seen and hasattr(signal, 'default_int_handler') and hasattr(signal, 'getsignal')
            and signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        _seen.append(time.monotonic())
        with open({path!r}, 'w') as f:
            f.write(repr(_seen[0]))
    return _real_import(*args, **kwargs)
builtins.__import__ = _import
"""

ROSOUT_RACE = "Failed to publish log message to rosout: publisher's context is invalid"
"""rcl's line when a signal comes as the node logs its ready line: rclpy's handler shuts the
context down (from a thread of its own) between the line's console output and its /rosout
message. A race of rclpy's signal handling with any log call, not of the start-up."""

SWEEP = (*range(0, 60, 5), 60, 70, 80, 100, 150, 250, 400, 600, 'ready', 'ready + 100 ms')
"""When to signal: ms after the process starts, or after rotation_node's ready line."""


def handler_at(probe):
    """Return the time HANDLER_PROBE wrote to ``probe``, or inf when there is none (yet)."""
    try:
        return float(probe.read_text())
    except (OSError, ValueError):
        return math.inf


def start_and_signal(command, env, when, sig, probe):
    """
    Start ``command``, send ``sig`` at ``when`` (SWEEP); return (status, stderr, checked).

    ``checked``: False for a SIGINT sent before the program's first handler (see
    test_signals_from_the_first_millisecond_to_after_the_ready_line). Such a SIGINT can be
    lost: CPython, before it runs a script, asks whether the script is a zip archive
    (Modules/main.c, pymain_get_importer), and a KeyboardInterrupt raised then is printed
    ("Failed checking if argv[0] is an import path entry") and the script run anyway. The
    node then starts and runs: it is sent the signal again once its handler is in place.
    """
    probe.unlink(missing_ok=True)
    proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, env=env)
    try:
        start, early = time.monotonic(), ''
        if isinstance(when, str):
            while 'decomposing' not in early:  # the node's ready line
                line = proc.stderr.readline()
                if not line:
                    break
                early += line
            time.sleep(0.1 if '100 ms' in when else 0.0)
        else:
            time.sleep(max(0.0, start + when / 1e3 - time.monotonic()))
        sent = time.monotonic()
        proc.send_signal(sig)
        try:
            _, err = proc.communicate(timeout=3.0)
        except subprocess.TimeoutExpired:
            # Still running: a node slow to start on a loaded machine, or a SIGINT lost by
            # CPython. Which, its first handler tells, once it is in place.
            deadline = time.monotonic() + 27.0
            while (proc.poll() is None and handler_at(probe) == math.inf
                   and time.monotonic() < deadline):
                time.sleep(0.05)
            if sig == signal.SIGINT and sent < handler_at(probe) < math.inf:
                proc.send_signal(sig)  # lost by CPython: the node runs
            # (raises TimeoutExpired: red)
            _, err = proc.communicate(timeout=max(1.0, deadline - time.monotonic()))
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return proc.returncode, early + err, sig != signal.SIGINT or handler_at(probe) <= sent


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_signals_from_the_first_millisecond_to_after_the_ready_line(tmp_path, sig):
    """
    A signal at any of 22 moments: status 0, or the signal's default action; no traceback.

    SIGTERM: Python's default until the program's first handler is the signal's default
    action (status -15, nothing printed). SIGINT: sent before the program's first handler
    (time.monotonic, against HANDLER_PROBE's), it meets Python's own KeyboardInterrupt —
    while the interpreter starts (site, the ROS wheels' bootstrap) nothing of a program can
    catch it; sent after, it must end the node with status 0 and nothing on stderr.
    """
    command = NODE_COMMANDS.get('console script', NODE_COMMANDS['python -m'])
    command = [*command, '--ros-args', '-r', f'__ns:=/{RUN}/sweep_{sig.name.lower()}']
    probe = tmp_path / 'handler_at'
    (tmp_path / 'sitecustomize.py').write_text(HANDLER_PROBE.format(path=str(probe)))
    env = dict(script_env(command), PYTHONPATH=f'{tmp_path}:{PACKAGE.parent}')
    wrong, checked = [], 0
    for when in SWEEP:
        status, err, check = start_and_signal(command, env, when, sig, probe)
        if not check:
            continue  # Python's own start: see the docstring
        checked += 1
        shown = [line for line in err.splitlines()
                 if 'decomposing' not in line and not line.startswith(ROSOUT_RACE)]
        if not ((status, shown) == (0, []) or (status == -sig and 'Traceback' not in err)):
            wrong.append(f'{when} ms: status {status}, stderr {err!r}')
    assert not wrong, '\n'.join(wrong)
    assert checked >= 8, f'only {checked} signals after the handler'


# rot_tools.ros.runtime.serve with a build that warns, then fails: with the context running
# (a bug: the warning shows, the error is raised), or shut down meanwhile (a signal: both are
# the shutdown's).
SERVE_A_BUILD_THAT_WARNS = """
import warnings
import rclpy
from rot_tools.ros import runtime
rclpy.init()
def make_node():
    warnings.warn('warned by the build', UserWarning)
    if {shut_down}:
        rclpy.shutdown()
    raise ValueError('not built')
try:
    runtime.serve(make_node)
except ValueError as exc:
    print(exc)
"""


@pytest.mark.parametrize('shut_down', [False, True], ids=['running', 'shut down'])
def test_serve_shows_the_warnings_of_the_build_unless_it_was_shut_down(shut_down):
    proc = run([sys.executable, '-c', SERVE_A_BUILD_THAT_WARNS.format(shut_down=shut_down)],
               env_extra={'PYTHONPATH': str(PACKAGE.parent)})
    assert proc.returncode == 0, proc.stderr
    if shut_down:
        assert (proc.stdout, proc.stderr) == ('', '')
    else:
        assert proc.stdout == 'not built\n'
        assert 'UserWarning: warned by the build' in proc.stderr


def test_signal_while_the_client_loads_exits_with_130(tmp_path):
    command = console_script('rotation_client', 'rot_tools.ros.rotation_client')
    if command[0] == sys.executable:
        pytest.skip('rotation_client is not installed: python -m has no early handler')
    proc = run(command, 'describe', env_extra=with_signal_hook(tmp_path, 'SIGINT'))
    assert proc.returncode == 130, proc.stderr
    assert 'Traceback' not in proc.stderr


def test_console_scripts_use_the_light_entry():
    from importlib.metadata import entry_points
    scripts = {ep.name: ep.value for ep in entry_points(group='console_scripts')}
    assert scripts['rotation_node'] == 'rot_tools.ros.entry:rotation_node'
    assert scripts['rotation_client'] == 'rot_tools.ros.entry:rotation_client'


def module_names():
    """Return {dotted name: path} of every module of rot_tools (__init__ as its package)."""
    names = {}
    for path in PACKAGE.rglob('*.py'):
        parts = path.relative_to(PACKAGE.parent).with_suffix('').parts
        names['.'.join(parts[:-1] if parts[-1] == '__init__' else parts)] = path
    return names


def imports_of(module):
    """Return the rot_tools modules ``module`` (dotted) imports anywhere (in functions too)."""
    names = module_names()
    found = set()
    for node in ast.walk(ast.parse(names[module].read_text())):
        if isinstance(node, ast.ImportFrom) and (node.module or '').startswith('rot_tools'):
            found.add(node.module)
            found |= {f'{node.module}.{alias.name}' for alias in node.names} & names.keys()
        elif isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names if alias.name.startswith('rot_tools')}
    return found - {module}


def test_the_runtime_depends_on_no_module_of_the_package():
    assert imports_of('rot_tools.ros.runtime') == set()
    assert imports_of('rot_tools.ros.entry') == {'rot_tools.ros', 'rot_tools.ros.runtime'}
    assert 'rot_tools.ros.runtime' in imports_of('rot_tools.ros.rotation_node')


def test_the_package_import_graph_has_no_cycle():
    graph = {name: imports_of(name) for name in module_names()}
    done, stack = set(), []

    def visit(module):
        if module in stack:
            pytest.fail('import cycle: ' + ' -> '.join(stack[stack.index(module):] + [module]))
        if module in done:
            return
        stack.append(module)
        for dependency in sorted(graph.get(module, ())):
            visit(dependency)
        stack.pop()
        done.add(module)

    for module in sorted(graph):
        visit(module)


BAD_ROS_ARGUMENTS = {
    'missing params file': (['--params-file', '/nonexistent/rot_tools.yaml'],
                            '/nonexistent/rot_tools.yaml'),
    'malformed params file': (['--params-file', '{malformed}'], 'params file'),
    'bad -p': (['-p', 'foo'], '-p NAME:=VALUE'),
    'bad -r': (['-r', 'bad'], '-r FROM:=TO'),
    'node name too long': (['-r', '__node:=' + 'n' * 240], '__node:=NAME'),
    'unknown flag': (['--bogus'], '--bogus'),
    'parameter of the wrong type': (['-p', 'marker_scale:=abc'], 'marker_scale'),
    'invalid parameter value': (['-p', 'euler_sequence:=zyz_'], 'euler_sequence'),
}


@pytest.mark.parametrize('how', sorted(NODE_COMMANDS))
@pytest.mark.parametrize('case', sorted(BAD_ROS_ARGUMENTS))
def test_bad_ros_arguments_are_one_line_and_status_2(tmp_path, how, case):
    args, named = BAD_ROS_ARGUMENTS[case]
    malformed = tmp_path / 'malformed.yaml'
    malformed.write_text('rot_tools:\n  ros__parameters:\n    marker_scale: [1\n')
    args = [str(malformed) if a == '{malformed}' else a for a in args]
    proc = run(NODE_COMMANDS[how], '--ros-args', *args)
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.splitlines()
    assert len(lines) == 1, proc.stderr
    assert lines[0].startswith('rotation_node: ') and named in lines[0], lines[0]


# A sitecustomize that makes rclpy.init fail loudly: --help and --version must not call it.
NO_RCLPY_INIT = """
import builtins, sys
_real_import = builtins.__import__
def _import(name, *args, **kwargs):
    module = _real_import(name, *args, **kwargs)
    rclpy = sys.modules.get('rclpy')
    if hasattr(rclpy, 'init') and not hasattr(rclpy.init, 'forbidden'):
        def init(*args, **kwargs):
            raise SystemExit('rclpy.init was called')
        init.forbidden = True
        rclpy.init = init
    return module
builtins.__import__ = _import
"""


@pytest.mark.parametrize('how', sorted(NODE_COMMANDS))
@pytest.mark.parametrize('flag', ['--help', '-h', '--version'])
def test_help_and_version_print_and_start_nothing(tmp_path, how, flag):
    from importlib.metadata import version
    from rot_tools.ros.rotation_node import INPUTS, OUTPUTS, PARAMETERS
    (tmp_path / 'sitecustomize.py').write_text(NO_RCLPY_INIT)
    proc = run(NODE_COMMANDS[how], flag, '--ros-args', '-p', 'angle_unit:=deg',
               env_extra={'PYTHONPATH': f'{tmp_path}:{PACKAGE.parent}'})
    assert (proc.returncode, proc.stderr) == (0, ''), proc.stderr
    if flag == '--version':
        assert proc.stdout == f"rotation_node {version('rot_tools')}\n"
        return
    assert proc.stdout.startswith('usage: rotation_node [--help] [--version] [--ros-args')
    for kind in INPUTS + OUTPUTS:
        assert f'\n  {kind.topic} ' in proc.stdout, kind.topic
    for name in PARAMETERS:
        assert f'\n  {name} = ' in proc.stdout, name
    assert max(map(len, proc.stdout.splitlines())) <= 99


def test_the_hook_does_catch_rclpy_init(tmp_path):
    (tmp_path / 'sitecustomize.py').write_text(NO_RCLPY_INIT)
    proc = run(NODE_COMMANDS['python -m'], '--ros-args', '-p', 'angle_unit:=deg',
               env_extra={'PYTHONPATH': f'{tmp_path}:{PACKAGE.parent}'}, timeout=20)
    assert proc.returncode == 1 and 'rclpy.init was called' in proc.stderr


@pytest.mark.parametrize('args', [['foo'], ['--verbose', '--ros-args'], ['--', 'x']])
def test_arguments_outside_ros_args_are_one_line_and_status_2(args):
    proc = run(NODE_COMMANDS['python -m'], *args)
    assert proc.returncode == 2, proc.stderr
    (line,) = proc.stderr.splitlines()
    assert line.startswith('rotation_node: unknown argument ') and '--help' in line


@pytest.mark.parametrize('argv', [
    ['prog'], ['prog', '--help'], ['prog', '--ros-args', '-p', 'a:=1'],
    ['prog', 'x', '--ros-args', '-r', 'a:=b', '--', 'y', '--ros-args', '-p', 'c:=2'],
    ['prog', '--ros-args', '--params-file', str(PACKAGE.parent / 'config' / 'rot_tools.yaml'),
     '--', '--version'],
    ['prog', '--', '--ros-args', '-p', 'a:=1', '--', '--']])
def test_user_arguments_are_what_rclpy_leaves(argv):
    from rclpy.utilities import remove_ros_args
    from rot_tools.ros.runtime import user_arguments
    assert user_arguments(argv) == remove_ros_args(argv)[1:]


def test_the_documented_bad_ros_argument_line():
    from doc_blocks import assert_doc_output, console_steps, doc_block
    ((command, _),) = console_steps(doc_block('node-bad-ros-argument'))
    assert command.startswith('rotation_node --ros-args ')
    proc = run(NODE_COMMANDS['python -m'], *command.split()[1:])
    assert proc.returncode == 2
    assert_doc_output('node-bad-ros-argument', f'$ {command}\n' + proc.stderr)
