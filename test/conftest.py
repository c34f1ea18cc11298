"""Shared fixtures: an isolated DDS domain and names for this run, rclpy contexts, a tester."""

import errno
import gc
import io
import itertools
import json
import os
from pathlib import Path
import secrets
import shutil
import signal
import subprocess
import sys
import time

import pytest
from rot_tools.io import interface

os.environ['ROS_DOMAIN_ID'] = str(1 + os.getpid() % 101)
os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
os.environ.pop('ROS_LOCALHOST_ONLY', None)  # deprecated; conflicts with the range above
os.environ.pop('ROS_STATIC_PEERS', None)

RUN = f'rt{os.getpid()}_{secrets.token_hex(4)}'
"""This test run's token: the namespaces of its nodes start with /RUN."""

OUTPUTS = tuple(row.name for row in interface.OUTPUTS)
"""Published topics of rotation_node, relative to its name (rot_tools.io.interface)."""

TIMEOUT = 5.0
"""Upper bound of every wait (discovery, message, service reply); never reached when well."""

DISCOVERY_TIMEOUT = 4 * TIMEOUT
"""Upper bound of a wait for the graph (a matched publisher or subscription, a service): it
may include a node process's whole start-up (NumPy, rclpy, DDS) on a loaded machine."""

REPO = Path(__file__).resolve().parents[1]

REQUIRED = ('numpy', 'yaml', 'pytest', 'hypothesis')
"""The packages every test module may import: one missing is an error, not a skip."""

_namespaces = itertools.count(1)


def console_script(name, module):
    """Return the command of console script ``name``: next to this Python, on PATH, or -m."""
    here = Path(sys.executable).parent / name
    script = str(here) if here.exists() else shutil.which(name)
    return [script] if script else [sys.executable, '-m', module]


def script_env(command):
    """Return os.environ for ``command``: unbuffered; this checkout importable for -m."""
    env = dict(os.environ, PYTHONUNBUFFERED='1')
    if command[0] == sys.executable:
        env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(REPO), env.get('PYTHONPATH')]))
    return env


def run_cli(capsys, *args):
    """Run rot-tools on these words in this process; return (status, stdout, stderr)."""
    from rot_tools.cli.main import main
    status = main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def one_error(capsys, *args, contains=''):
    """Run rot-tools here: status 2, no stdout, one error line holding ``contains``; return it."""
    status, out, err = run_cli(capsys, *args)
    assert (status, out) == (2, ''), err
    assert err.count('\n') == 1 and err.startswith('rot-tools: error: '), err
    assert contains in err, err
    return err


def strict_json(text):
    """Parse JSON text; NaN and Infinity, which json.loads accepts by default, fail."""
    def refuse(name):
        raise ValueError(f'{name} is not JSON')
    return json.loads(text, parse_constant=refuse)


def rss_mb(pid='self'):
    """Return the resident set size in MB of process ``pid``, this one by default."""
    with open(f'/proc/{pid}/status', encoding='ascii') as f:
        for line in f:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    pytest.fail(f'no VmRSS in /proc/{pid}/status')


def live_pids(*, parent=None, session=None):
    """Return the pids of the live processes (zombies excepted) of a parent or a session."""
    found = []
    for entry in Path('/proc').iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / 'stat').read_text().rsplit(')', 1)[1].split()
            except OSError:
                continue  # gone meanwhile
            if fields[0] != 'Z' and (parent is None or int(fields[1]) == parent) and (
                    session is None or int(fields[3]) == session):
                found.append(int(entry.name))
    return found


STOP_WITHIN = 10.0
"""Seconds a signalled process may take to end: a generous bound that a hang fails."""


def assert_clean_exit(status, stderr):
    """Check a node process's end: status 0, no traceback."""
    assert status == 0, stderr
    assert 'Traceback' not in stderr and 'KeyboardInterrupt' not in stderr, stderr


class NodeProcess:
    """rotation_node in a child process, in a namespace of this run; ``name`` its full name."""

    def __init__(self, tmp_path, *ros_args, env_extra=None):
        namespace = f'/{RUN}/p{next(_namespaces)}'
        self.name = f'{namespace}/rot_tools'
        self.out_path = tmp_path / f'{namespace[1:].replace("/", "_")}.out'
        self.err_path = tmp_path / f'{namespace[1:].replace("/", "_")}.err'
        args = console_script('rotation_node', 'rot_tools.ros.node.rotation_node') + [
            '--ros-args', '-r', f'__ns:={namespace}', *ros_args]
        with open(self.out_path, 'w') as out, open(self.err_path, 'w') as err:
            self.process = subprocess.Popen(args, stdout=out, stderr=err,
                                            env=dict(script_env(args), **(env_extra or {})))

    def stop(self, signum=signal.SIGTERM):
        """Send ``signum``; return (exit status, stderr) once the node has ended."""
        self.process.send_signal(signum)
        try:
            status = self.process.wait(timeout=STOP_WITHIN)
        except subprocess.TimeoutExpired:
            self.kill()
            pytest.fail(f'rotation_node still ran {STOP_WITHIN:g} s after signal {signum}')
        return status, self.err_path.read_text()

    def kill(self):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()

    def wait_for_stderr(self, text, timeout=TIMEOUT * 4):
        """Wait until ``text`` appears in the process's stderr; return all of it."""
        deadline = time.monotonic() + timeout
        while text not in self.err_path.read_text():
            if time.monotonic() > deadline or self.process.poll() is not None:
                pytest.fail(f'{text!r} not in stderr of rotation_node:\n'
                            + self.err_path.read_text())
            time.sleep(0.05)
        return self.err_path.read_text()


class Tester:
    """A test-side rclpy node in ``context``, spun on demand; every wait bounded by ``timeout``."""

    def __init__(self, context, name='tester'):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.context = context
        self.node = rclpy.create_node(name, namespace=f'/{RUN}', context=context)
        self.executors = [SingleThreadedExecutor(context=context)]
        self.executors[0].add_node(self.node)
        self.received = {}
        self._subscriptions = {}
        self.logs = []

    def close(self):
        """Destroy the executors, collect their last wait, then destroy the test node."""
        for executor in self.executors:
            executor.remove_node(self.node)
            executor.shutdown(timeout_sec=1.0)
        gc.collect()
        self.node.destroy_node()

    def add_node(self, node):
        """Spin ``node`` with the tester; another context's node on an executor of its own."""
        from rclpy.executors import SingleThreadedExecutor
        if node.context is self.context:
            self.executors[0].add_node(node)
        else:
            executor = SingleThreadedExecutor(context=node.context)
            executor.add_node(node)
            self.executors.append(executor)

    def remove_node(self, node):
        """Stop spinning ``node``."""
        for executor in self.executors:
            if node in executor.get_nodes():
                executor.remove_node(node)

    def spin_once(self):
        """Let every executor handle what is ready (waiting at most 10 ms in all)."""
        timeout = 0.01 / len(self.executors)
        for executor in self.executors:
            executor.spin_once(timeout_sec=timeout)

    def spin_until(self, predicate, timeout=TIMEOUT, what='condition'):
        """Spin until predicate() is true; fail the test after ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() > deadline:
                pytest.fail(f'timed out after {timeout} s waiting for {what}')
            self.spin_once()

    def spin_for(self, seconds):
        """Spin for a fixed time (only to show that nothing *more* arrives)."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.spin_once()

    # -- topics ------------------------------------------------------------------------

    def subscribe(self, topic, msg_type, qos=10):
        """Collect every message of ``topic`` in self.received[topic]."""
        self.received[topic] = []
        self._subscriptions[topic] = self.node.create_subscription(
            msg_type, topic, self.received[topic].append, qos)

    def subscribe_outputs(self, prefix):
        """Subscribe (reliable, depth 10, like the node) to the node's outputs."""
        from rot_tools.ros.message_types import message_class
        for row in interface.OUTPUTS:
            self.subscribe(f'{prefix}/{row.name}', message_class(row.type_name))

    def subscribe_rosout(self):
        """Collect /rosout (reliable, transient local, like the rosout publishers)."""
        from rcl_interfaces.msg import Log
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(Log, '/rosout', self.logs.append, qos)

    def wait_matched(self, topics=None):
        """Wait until each collected topic (default: all) has a matched publisher."""
        for topic in topics or self._subscriptions:
            sub = self._subscriptions[topic]
            self.spin_until(lambda sub=sub: sub.get_publisher_count() > 0,
                            DISCOVERY_TIMEOUT, f'a publisher on {topic}')

    def publisher(self, topic, msg_type, qos=10):
        """Create a publisher on ``topic``; return it once a subscription has matched it."""
        pub = self.node.create_publisher(msg_type, topic, qos)
        self.spin_until(lambda: pub.get_subscription_count() > 0,
                        DISCOVERY_TIMEOUT, f'a subscription on {topic}')
        return pub

    def wait_messages(self, topic, count=1, timeout=TIMEOUT):
        """Wait until ``count`` messages of ``topic`` have arrived; return them all."""
        self.spin_until(lambda: len(self.received[topic]) >= count, timeout,
                        f'{count} message(s) on {topic}')
        return self.received[topic]

    # -- services ----------------------------------------------------------------------

    def call(self, srv_type, name, request, timeout=2.0, attempts=5):
        """Call a service, a bounded wait per attempt (Fast DDS may drop a first reply)."""
        client = self.node.create_client(srv_type, name)
        try:
            self.spin_until(lambda: client.service_is_ready(), DISCOVERY_TIMEOUT,
                            f'service {name}')
            for _ in range(attempts):
                future = client.call_async(request)
                deadline = time.monotonic() + timeout
                while not future.done() and time.monotonic() < deadline:
                    self.spin_once()
                if future.done():
                    return future.result()
                client.remove_pending_request(future)
            pytest.fail(f'no reply from {name} in {attempts} attempts of {timeout} s')
        finally:
            self.node.destroy_client(client)

    def set_parameters(self, node_name, parameters):
        """Set rclpy Parameters of ``node_name`` by ~/set_parameters; return its results."""
        from rcl_interfaces.srv import SetParameters
        request = SetParameters.Request(
            parameters=[p.to_parameter_msg() for p in parameters])
        return self.call(SetParameters, f'{node_name}/set_parameters', request).results


class SkippableModule(pytest.Module):
    """A test module, skipped when it imports a package this machine does not have."""

    def collect(self):
        try:
            return super().collect()
        except self.CollectError as error:
            missing = error.__cause__
            if isinstance(missing, ModuleNotFoundError) and optional(missing.name or ''):
                pytest.skip(f'needs {missing.name}, not installed', allow_module_level=True)
            raise


def optional(module):
    """Tell whether a test module may be skipped for lack of ``module``: not a required one."""
    top = module.split('.')[0]
    local = top == 'rot_tools' or (REPO / 'test' / f'{top}.py').exists()
    return top not in REQUIRED and not local


def pytest_pycollect_makemodule(module_path, parent):
    """Collect every test module as a SkippableModule."""
    return SkippableModule.from_parent(parent, path=module_path)


def _context():
    rclpy = pytest.importorskip('rclpy')
    context = rclpy.Context()
    rclpy.init(context=context)
    return context


@pytest.fixture
def savefig_fills_the_disk(monkeypatch):
    """Make matplotlib's Figure.savefig write half the picture, then fail as a full disk does."""
    pytest.importorskip('matplotlib')
    from matplotlib.figure import Figure
    real_savefig = Figure.savefig

    def half_then_full(fig, target, **kwargs):
        picture = io.BytesIO()
        real_savefig(fig, picture, **{'format': 'png', **kwargs})
        half = picture.getvalue()[:len(picture.getvalue()) // 2]
        if hasattr(target, 'write'):
            target.write(half)
        else:
            Path(target).write_bytes(half)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(Figure, 'savefig', half_then_full)


@pytest.fixture(scope='session')
def ros_context():
    """Initialise an rclpy context (a DDS participant) for the nodes under test."""
    context = _context()
    yield context
    context.try_shutdown()


@pytest.fixture(scope='session')
def tester_context():
    """Initialise another context (DDS participant) for the test side: real DDS between."""
    context = _context()
    yield context
    context.try_shutdown()


@pytest.fixture(scope='module')
def here(ros_context):
    """Run rotation_client's commands in this process (test_client.Here), one runner a module."""
    from test_client import Here
    runner = Here(ros_context)
    yield runner
    runner.close()


@pytest.fixture
def namespace():
    """Give each test a namespace of its own, below this run's: /RUN/tN."""
    return f'/{RUN}/t{next(_namespaces)}'


@pytest.fixture
def node_process(tmp_path):
    """Start rotation_node processes: start(*ros_args, env_extra=None); kill them after."""
    pytest.importorskip('rclpy')
    started = []

    def start(*ros_args, env_extra=None):
        started.append(NodeProcess(tmp_path, *ros_args, env_extra=env_extra))
        return started[-1]

    yield start
    for process in started:
        process.kill()


@pytest.fixture
def tester(tester_context):
    """Create a Tester in the test-side context; destroy it after the test."""
    t = Tester(tester_context)
    yield t
    t.close()
