"""How rotation_node starts and stops: its console script, its arguments, its signals."""

import os
from pathlib import Path
import signal
import subprocess
import sys
import threading
import time

from conftest import console_script, RUN, script_env, STOP_WITHIN
import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'rot_tools'


def node_commands():
    """Both commands that start rotation_node: the console script (when installed), -m."""
    commands = {'python -m': [sys.executable, '-m', 'rot_tools.ros.node.rotation_node']}
    script = console_script('rotation_node', 'rot_tools.ros.node.rotation_node')
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


def test_console_scripts_point_at_plain_main_functions():
    from importlib.metadata import entry_points
    scripts = {ep.name: ep.value for ep in entry_points(group='console_scripts')}
    assert scripts['rotation_node'] == 'rot_tools.ros.node.rotation_node:main'
    assert scripts['rotation_client'] == 'rot_tools.ros.client.rotation_client:main'


# Signals, from the first millisecond to after the ready line

READY = 'decomposing'
"""What the node's ready line (its INFO line once it is built) says."""

FRACTIONS = {signal.SIGINT: tuple(k / 20 for k in range(0, 20, 2)),
             signal.SIGTERM: tuple(k / 20 for k in range(1, 20, 2))}
"""When to signal during the start-up: fractions of the time a first start took to its ready
line (so that the sweep covers Python's start, the imports, rclpy.init and the node's build
on a fast machine and a loaded one alike), every tenth of it for each signal, SIGINT's and
SIGTERM's interleaved (the two together every twentieth); then at the ready line and 100 ms
after it."""

ROSOUT_RACE = "Failed to publish log message to rosout: publisher's context is invalid"
"""rcl's line when a signal comes as the node logs its ready line: rclpy's handler shuts the
context down (from a thread of its own) between the line's console output and its /rosout
message."""


class Started:
    """A rotation_node process in a session of its own (so that no child could hide)."""

    def __init__(self, command, env):
        self.begin = time.monotonic()
        self.process = subprocess.Popen(command, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                        env=env, start_new_session=True)
        self.err = b''
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in iter(self.process.stderr.readline, b''):
            self.err += line

    def text(self):
        return self.err.decode(errors='replace')

    def wait_ready(self, timeout=60.0):
        """Wait for the ready line; return the seconds since the start."""
        deadline = self.begin + timeout
        while READY not in self.text():
            assert self.process.poll() is None, f'the node ended early: {self.text()}'
            assert time.monotonic() < deadline, 'no ready line'
            time.sleep(0.005)
        return time.monotonic() - self.begin

    def signal(self, sig):
        """Send ``sig``; return whether the node ended within STOP_WITHIN seconds."""
        self.process.send_signal(sig)
        try:
            self.process.wait(timeout=STOP_WITHIN)
        except subprocess.TimeoutExpired:
            return False
        return True

    def finish(self):
        """Return (status, stderr, whether a process was left in its session)."""
        status = self.process.wait(timeout=30)
        self._reader.join(timeout=5)
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
            left = True
        except ProcessLookupError:
            left = False
        return status, self.text(), left

    def kill(self):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


def signal_at(command, env, when, sig):
    """Start the node, send ``sig`` at ``when`` (seconds, or 'ready'); return what went wrong."""
    node = Started(command, env)
    try:
        if isinstance(when, str):
            node.wait_ready()
            time.sleep(0.1 if '100 ms' in when else 0.0)
        else:
            time.sleep(max(0.0, node.begin + when - time.monotonic()))
        up = READY in node.text()
        ended = node.signal(sig)
        if not ended and not up and sig == signal.SIGINT:
            # Python's own start lost it (CPython prints and drops a KeyboardInterrupt while
            # it asks whether the script is a zip archive, Modules/main.c pymain_get_importer;
            # C code of an import that clears errors drops one silently): the node came up as if
            # never signalled, as a program does whose Ctrl-C came before it ran; signalled
            # again once up, it must end as the sweep requires.
            node.wait_ready()
            up = True
            ended = node.signal(sig)
        if not ended:
            shown = when if isinstance(when, str) else f'{when * 1e3:.0f} ms'
            return f'{shown}: still running {STOP_WITHIN:g} s after the signal: {node.text()!r}'
        status, err, left = node.finish()
    finally:
        node.kill()
    shown = when if isinstance(when, str) else f'{when * 1e3:.0f} ms'
    wrong = []
    if left:
        wrong.append('a process was left in its session')
    lines = [line for line in err.splitlines()
             if READY not in line and not line.startswith(ROSOUT_RACE)]
    if up and (status, lines) != (0, []):
        wrong.append(f'status {status} and stderr {err!r} once up')
    return f'{shown}: ' + '; '.join(wrong) if wrong else None


@pytest.mark.parametrize('sig', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_a_signal_from_the_first_millisecond_to_after_the_ready_line(sig):
    """Check that a signal at any of 12 moments of its start-up and run ends the node cleanly."""
    command = NODE_COMMANDS.get('console script', NODE_COMMANDS['python -m'])
    command = [*command, '--ros-args', '-r', f'__ns:=/{RUN}/sweep_{sig.name.lower()}']
    env = script_env(command)
    first = Started(command, env)
    try:
        start_up = first.wait_ready()
    finally:
        first.kill()
    moments = [fraction * start_up for fraction in FRACTIONS[sig]] + ['ready', 'ready + 100 ms']
    wrong = [what for what in (signal_at(command, env, when, sig) for when in moments) if what]
    assert not wrong, '\n'.join(wrong)


# Arguments

BAD_ROS_ARGUMENTS = {
    'missing params file': (['--params-file', '/nonexistent/rot_tools.yaml'],
                            '/nonexistent/rot_tools.yaml'),
    'malformed params file': (['--params-file', '{malformed}'], 'malformed.yaml'),
    'bad -p': (['-p', 'foo'], '-p foo'),
    'bad -r': (['-r', 'bad'], '-r bad'),
    'node name too long': (['-r', '__node:=' + 'n' * 240], 'n' * 240),
    'unknown flag': (['--bogus'], '--bogus'),
    'parameter of the wrong type': (['-p', 'marker_scale:=abc'], 'marker_scale'),
    'invalid parameter value': (['-p', 'euler_sequence:=zyz_'], 'euler_sequence'),
}


BY_MODULE_TOO = ('bad -r', 'invalid parameter value')
"""The cases also run as ``python -m`` when the console script is installed: one that rcl
refuses as it parses, one that the node refuses as it is built."""


def ways(cases, by_module_too):
    """(how, case): every case by the console script (or -m), some by -m as well."""
    first = 'console script' if 'console script' in NODE_COMMANDS else 'python -m'
    return ([(first, case) for case in cases]
            + [('python -m', case) for case in by_module_too if first != 'python -m'])


@pytest.mark.parametrize('how, case', ways(sorted(BAD_ROS_ARGUMENTS), BY_MODULE_TOO))
def test_bad_ros_arguments_are_one_line_and_status_2(tmp_path, how, case):
    args, named = BAD_ROS_ARGUMENTS[case]
    malformed = tmp_path / 'malformed.yaml'
    malformed.write_text('rot_tools:\n  ros__parameters:\n    marker_scale: [1\n')
    args = [str(malformed) if a == '{malformed}' else a for a in args]
    proc = run(NODE_COMMANDS[how], '--ros-args', '-r', f'__ns:=/{RUN}/bad', *args)
    assert proc.returncode == 2, proc.stderr
    *logged, last = proc.stderr.splitlines()
    assert last.startswith('rotation_node: ') and named in last, last
    assert all('[rcl]' in line for line in logged), proc.stderr  # rcl's own error log line


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


@pytest.mark.parametrize('how, flag', ways(['--help', '-h', '--version'],
                                           ['--help', '--version']))
def test_help_and_version_print_and_start_nothing(tmp_path, how, flag):
    from importlib.metadata import version
    from rot_tools.io.interface import INPUTS, OUTPUTS
    from rot_tools.ros.node.rotation_node import PARAMETERS
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
    from rot_tools.ros.node.runtime import user_arguments
    assert user_arguments(argv) == remove_ros_args(argv)[1:]


def test_the_documented_bad_ros_argument_line():
    from doc_blocks import assert_doc_output, console_steps, doc_block
    ((command, _),) = console_steps(doc_block('node-bad-ros-argument'))
    assert command.startswith('rotation_node --ros-args ')
    proc = run(NODE_COMMANDS['python -m'], *command.split()[1:])
    assert proc.returncode == 2
    assert_doc_output('node-bad-ros-argument', f'$ {command}\n' + proc.stderr)
