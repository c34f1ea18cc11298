"""
How rotation_node and rotation_client start: the process runtime (rot_tools.ros.runtime).

Both ways of starting the node — its console script and ``python -m rot_tools.ros.rotation_node``
(the benchmarks use the latter) — stop cleanly on a signal even while NumPy and rclpy load,
and bad ROS arguments end them with one line and status 2. The runtime depends on nothing of
the node: the modules' import graph has no cycle.
"""

import ast
from pathlib import Path
import subprocess
import sys

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
# (0 for none) of a module of NumPy, rclpy or rot_tools, or just after rotation_node's
# ready line (the end of RotationNode.__init__: {after_ready}). Imports are counted from
# the moment the program has a SIGTERM handler: before it (the interpreter's start and the
# console script importing rot_tools.ros.entry) a signal ends it as any Python program.
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
    return module
builtins.__import__ = _import
"""

START_UP_MOMENTS = {
    **{f'import {n}': {'nth': n} for n in (1, 3, 10, 30, 60, 100, 200, 400, 800)},
    # rclpy.signals half imported: rot_tools' handler looked up its function there.
    'rclpy.signals half imported': {'module': 'rclpy.exceptions'},
    # The context shut down before the executor was made: it failed half built.
    'after the ready line': {'after_ready': True},
}
"""Moments of the start-up to signal at: 11 a signal, 22 with both signals."""


@pytest.mark.parametrize('sig', ['SIGTERM', 'SIGINT'])
@pytest.mark.parametrize('moment', sorted(START_UP_MOMENTS))
def test_a_signal_at_any_moment_of_the_start_up_exits_0_quietly(tmp_path, moment, sig):
    hook = dict({'module': '', 'nth': 0, 'after_ready': False}, **START_UP_MOMENTS[moment])
    (tmp_path / 'sitecustomize.py').write_text(SIGNAL_AT_A_MOMENT.format(sig=sig, **hook))
    command = NODE_COMMANDS.get('console script', NODE_COMMANDS['python -m'])
    proc = run(command, '--ros-args', '-r', f'__ns:=/{RUN}/startup', timeout=30,
               env_extra={'PYTHONPATH': f'{tmp_path}:{PACKAGE.parent}'})
    shown = [line for line in proc.stderr.splitlines() if 'decomposing' not in line]
    assert (proc.returncode, shown) == (0, []), proc.stderr


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
