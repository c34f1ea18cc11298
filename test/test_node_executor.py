"""The executor rotation_node runs on (rotation_node.make_executor), proved in use.

rclpy's EventsExecutor is experimental in rclpy 7.1.6: its spin() did not return after
shutdown, a callback that raises loses the rest of its subscription's queued messages, and
a task that raises crashes the process when one node is registered (rclpy#1641). The node
spins it through rotation_node.spin; these tests show, on the real executor and (where a
signal or the process matters) on the real console script:

- SIGINT and SIGTERM, 20 times each, idle and under a flood of poses: exit status 0 within
  a second, no traceback;
- both services and the parameter services answer, correctly, while ~/pose is flooded;
- a flood of bad input is refused and counted, and the node keeps serving;
- a callback that raises is logged and costs nothing else (the inputs sent with it are all
  answered; unguarded, the EventsExecutor drops the rest of the batch it was in); the node
  creates nothing the executor cannot serve safely (no clients, guard conditions or
  tasks), and the QoS events it does watch are served.

The in-process node tests (test_node.py) run on the same executor: conftest's Tester spins
nodes under test with rotation_node.make_executor.
"""

import inspect
import json
import math
import signal
import subprocess
import sys
import threading
import time

from geometry_msgs.msg import PoseStamped, TwistStamped
from nav_msgs.srv import GetPlan
import numpy as np
import pytest
from rcl_interfaces.srv import GetParameters
import rclpy
from rclpy.parameter import Parameter, parameter_value_to_python
from rclpy.qos import DurabilityPolicy, qos_profile_sensor_data, QoSProfile
from std_srvs.srv import Trigger
import yaml

from conftest import RUN, TIMEOUT
from rot_tools import rotation_node
from rot_tools.rotation_node import guard_callbacks, make_executor, RotationNode, spin

SIGNALS_EACH = 20
"""Signals of each kind the node must survive cleanly (half idle, half under a flood)."""
BATCH = 5
"""Node processes started at once (their start-up overlaps; signals go one at a time)."""
STOP_WITHIN = 1.0


def pose(q=(0.0, 0.0, 0.0, 1.0), p=(1.0, 0.0, 0.0), frame='map'):
    msg = PoseStamped()
    msg.header.frame_id = frame
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = map(float, q)
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = map(float, p)
    return msg


GOOD = [pose((0.1, -0.5, 0.3, 0.8) / np.linalg.norm((0.1, -0.5, 0.3, 0.8)), (1, 2, 3)),
        pose((0.0, 0.0, 1.0, 0.0), (0.5, 0.0, 0.0)), pose()]
BAD = [pose((math.nan, 0.0, 0.0, 1.0)), pose((0.0, 0.0, 0.0, 0.0)),
       pose((0.0, 0.0, 0.0, 2.0)), pose(p=(math.inf, 0.0, 0.0))]
"""Refused as non_finite, zero_quaternion, non_unit_quaternion, non_finite."""


FLOODER = """
import json, signal, sys, time
# SIGINT ends the flood with KeyboardInterrupt even where this process was started with
# SIGINT ignored (a background job of a non-interactive shell).
signal.signal(signal.SIGINT, signal.default_int_handler)
import rclpy
from geometry_msgs.msg import PoseStamped
from rclpy.qos import qos_profile_sensor_data
from rclpy.signals import SignalHandlerOptions
topic, rate = sys.argv[1], float(sys.argv[2])
poses = json.loads(sys.argv[3])  # (NaN and Infinity included)
# No rclpy signal handler: it would shut the context down on SIGINT before Python raises
# KeyboardInterrupt, and a publish in between would fail.
rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
node = rclpy.create_node('flooder', namespace=sys.argv[4])
pub = node.create_publisher(PoseStamped, topic, qos_profile_sensor_data)
deadline = time.monotonic() + float(sys.argv[5])
while pub.get_subscription_count() < 1:
    if time.monotonic() > deadline:
        print(f'no subscription on {pub.topic_name}', flush=True)
        sys.exit(1)
    time.sleep(0.01)
messages = []
for (q, p, frame) in poses:
    msg = PoseStamped()
    msg.header.frame_id = frame
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = q
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = p
    messages.append(msg)
print('ready', flush=True)
sent, start = 0, time.monotonic()
try:
    while True:
        due = int((time.monotonic() - start) * rate) + 1
        while sent < due:
            msg = messages[sent % len(messages)]
            msg.header.stamp.sec = 1_000_000 + sent
            pub.publish(msg)
            sent += 1
        time.sleep(0.002)
except KeyboardInterrupt:
    print(sent, flush=True)
"""


class Flood:
    """Publishes ``poses`` in turn on ``topic`` at about ``rate`` msg/s, from a process.

    A process of its own, so that the flood keeps its pace whatever this one does. Each
    message's header.stamp.sec counts up from 1_000_000, so a flooded output is told apart;
    ``sent`` is how many were published, once the flood has ended.
    """

    def __init__(self, topic, poses, rate=2000.0):
        data = json.dumps([(_quaternion(m), _position(m), m.header.frame_id) for m in poses])
        self.process = subprocess.Popen(
            [sys.executable, '-c', FLOODER, topic, str(rate), data, f'/{RUN}', str(4 * TIMEOUT)],
            stdout=subprocess.PIPE, text=True)
        self.sent = None

    def __enter__(self):
        line = self.process.stdout.readline().strip()
        assert line == 'ready', f'the flooder said {line!r}'
        return self

    def __exit__(self, *exc):
        self.process.send_signal(signal.SIGINT)
        out, _ = self.process.communicate(timeout=4 * TIMEOUT)
        assert out.split(), f'the flooder ended without a count (exit {self.process.returncode})'
        self.sent = int(out.split()[-1])


def _quaternion(msg):
    o = msg.pose.orientation
    return (o.x, o.y, o.z, o.w)


def _position(msg):
    p = msg.pose.position
    return (p.x, p.y, p.z)


def wait_until_serving(tester, process):
    """Publish a pose to the node process until its ~/screw answers (the loop is spinning)."""
    process.wait_for_stderr('decomposing')  # started (several may be starting at once)
    name = process.name
    got = []
    sub = tester.node.create_subscription(TwistStamped, f'{name}/screw', got.append, 10)
    pub = tester.publisher(f'{name}/pose', PoseStamped, qos_profile_sensor_data)
    deadline = time.monotonic() + 4 * TIMEOUT
    while not got:
        assert time.monotonic() < deadline, f'{name} never answered'
        pub.publish(pose())
        tester.spin_for(0.05)
    tester.node.destroy_subscription(sub)
    tester.node.destroy_publisher(pub)


def describe(tester, name):
    """The node's ~/describe report ({'stamp': {'sec': -1}} before any input)."""
    response = tester.call(Trigger, f'{name}/describe', Trigger.Request())
    return yaml.safe_load(response.message) if response.success else {'stamp': {'sec': -1}}


def assert_clean_exit(status, seconds, stderr):
    assert status == 0, stderr
    assert 'Traceback' not in stderr and 'KeyboardInterrupt' not in stderr, stderr
    assert seconds < STOP_WITHIN, f'took {seconds:.2f} s to stop'


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_every_signal_ends_the_node_cleanly_within_a_second(tester, node_process, signum):
    stops = []
    for first in range(0, SIGNALS_EACH, BATCH):
        processes = [node_process() for _ in range(BATCH)]
        for process in processes:
            wait_until_serving(tester, process)
        for k, process in enumerate(processes):
            if (first + k) % 2:  # every other one while it is flooded with poses
                with Flood(f'{process.name}/pose', GOOD + BAD, rate=3000.0):
                    time.sleep(0.2)
                    stops.append(process.stop(signum))
            else:
                stops.append(process.stop(signum))
    assert len(stops) == SIGNALS_EACH
    for stop in stops:
        assert_clean_exit(*stop)


def test_services_and_parameters_answer_correctly_under_a_flood(tester, node_process):
    process = node_process()
    name = process.name
    wait_until_serving(tester, process)
    goal = pose((0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 2.0))
    with Flood(f'{name}/pose', GOOD, rate=3000.0) as flood:
        deadline = time.monotonic() + 4 * TIMEOUT
        stamp = 999_999
        for i in range(5):
            # Each round starts once a newer flooded input has reached the node, so the
            # calls below are served between flooded inputs however fast they answer.
            while (report := describe(tester, name))['stamp']['sec'] <= stamp:
                assert time.monotonic() < deadline, f'no flooded input after {stamp} arrived'
            stamp = report['stamp']['sec']
            assert report['source'] == f'{name}/pose' and report['frame_id'] == 'map'
            plan = tester.call(GetPlan, f'{name}/screw_path',
                               GetPlan.Request(start=pose(p=(0, 0, 0)), goal=goal)).plan
            assert len(plan.poses) == 21
            assert plan.poses[10].pose.position.z == pytest.approx(1.0, abs=1e-12)
            unit = 'deg' if i % 2 else 'rad'
            results = tester.set_parameters(name, [Parameter('angle_unit', value=unit)])
            assert results[0].successful
            values = tester.call(GetParameters, f'{name}/get_parameters',
                                 GetParameters.Request(names=['angle_unit'])).values
            assert parameter_value_to_python(values[0]) == unit
    assert stamp - 1_000_000 < flood.sent
    assert process.process.poll() is None
    assert_clean_exit(*process.stop(signal.SIGTERM))


def test_a_flood_of_bad_input_is_refused_and_the_node_keeps_serving(tester, node_process):
    process = node_process()
    name = process.name
    wait_until_serving(tester, process)
    begin = time.monotonic()
    with Flood(f'{name}/pose', BAD, rate=3000.0) as flood:
        time.sleep(2.0)
    # Inputs are best effort and a flood beyond the node's pace loses some: every reason
    # must be counted, never more than were sent.
    reasons = ('non_finite', 'zero_quaternion', 'non_unit_quaternion')
    refused = {}
    deadline = time.monotonic() + TIMEOUT
    while not all(refused.get(r) for r in reasons):
        assert time.monotonic() < deadline, f'{refused} of {flood.sent} sent'
        response = tester.call(Trigger, f'{name}/describe', Trigger.Request())
        refused = yaml.safe_load(response.message)['refused']
    elapsed = time.monotonic() - begin  # refusals all fell within it
    assert 100 < refused['total'] <= flood.sent
    assert refused['total'] == sum(refused[r] for r in reasons)
    wait_until_serving(tester, process)  # good input is still answered
    stderr = process.err_path.read_text()
    warnings = [line for line in stderr.splitlines() if 'refused input on' in line]
    for reason in reasons:  # throttled: one warning a second for each topic and reason
        count = sum(f'/pose ({reason}):' in line for line in warnings)
        assert 1 <= count <= 1 + elapsed, (reason, warnings)
    assert len(warnings) == sum(f'/pose ({r}):' in line for line in warnings for r in reasons)
    assert_clean_exit(*process.stop(signal.SIGINT))


@pytest.fixture
def own_context():
    """A context of its own for a node spun by rotation_node.spin in a thread."""
    context = rclpy.Context()
    rclpy.init(context=context)
    yield context
    context.try_shutdown()


def test_a_raising_callback_is_logged_and_costs_no_other_message(
        tester, ros_context, namespace, monkeypatch, capfd):
    real = RotationNode._on_input

    def on_input(self, source, msg):
        if msg.header.frame_id == 'boom':
            raise RuntimeError('a bug in a callback')
        return real(self, source, msg)

    monkeypatch.setattr(RotationNode, '_on_input', on_input)
    node = RotationNode(context=ros_context, namespace=namespace)
    try:
        guard_callbacks(node)
        tester.add_node(node)  # on the node's executor (conftest)
        prefix = node.get_fully_qualified_name()
        tester.subscribe(f'{prefix}/screw', TwistStamped)
        pub = tester.publisher(f'{prefix}/pose', PoseStamped, QoSProfile(depth=10))
        received = tester.received[f'{prefix}/screw']

        def send(stamp, frame='map'):
            msg = pose(frame=frame)
            msg.header.stamp.sec = stamp
            pub.publish(msg)

        while not received:  # discovery both ways
            send(0)
            tester.spin_for(0.05)
        tester.spin_for(0.3)  # the rest of the warm-up: the queues are empty again
        for stamp in range(1, 6):  # in one go (the input queue keeps 5): the third raises
            send(stamp, 'boom' if stamp == 3 else 'map')
        tester.spin_until(lambda: received[-1].header.stamp.sec == 5,
                          what='the inputs after the failing one')
        assert [m.header.stamp.sec for m in received if m.header.stamp.sec] == [1, 2, 4, 5]
        send(6)  # and later ones
        tester.spin_until(lambda: received[-1].header.stamp.sec == 6, what='input 6')
    finally:
        tester.remove_node(node)
        node.destroy_node()
    err = capfd.readouterr().err
    assert f'subscription {prefix}/pose callback raised; the node keeps serving' in err
    assert 'RuntimeError: a bug in a callback' in err


def test_a_raising_service_callback_still_replies(tester, own_context, namespace, monkeypatch):
    def broken(self, request, response):
        raise ZeroDivisionError('a bug in a service')

    monkeypatch.setattr(RotationNode, '_on_describe', broken)
    node = RotationNode(context=own_context, namespace=namespace)
    thread = threading.Thread(target=spin, args=(node, make_executor(own_context)))
    thread.start()
    try:
        for _ in range(3):
            response = tester.call(Trigger, f'{node.get_fully_qualified_name()}/describe',
                                   Trigger.Request())
            assert response.success is False and response.message == ''
    finally:
        own_context.try_shutdown()
        thread.join(timeout=5.0)
        node.destroy_node()
    assert not thread.is_alive()


def test_the_node_has_nothing_the_events_executor_cannot_serve(ros_context, namespace):
    node = RotationNode(context=ros_context, namespace=namespace)
    try:
        # Clients bring futures and tasks (a raising task crashes the process with one
        # node, rclpy#1641), so do coroutine callbacks; guard conditions are refused by the
        # EventsExecutor. Timers are called directly, like subscriptions.
        assert not list(node.clients) and not list(node.guards)
        assert {type(w).__name__ for w in node.waitables} <= {'EventHandler'}  # QoS events
        for entity in [*node.subscriptions, *node.services, *node.timers]:
            assert not _is_coroutine(entity.callback), entity
    finally:
        node.destroy_node()


def _is_coroutine(callback):
    return inspect.iscoroutinefunction(getattr(callback, 'func', callback))


def test_a_qos_event_is_served_and_the_node_keeps_going(tester, node_process):
    """An incompatible subscriber raises a QoS event on the node's publisher (a waitable)."""
    process = node_process()
    name = process.name
    wait_until_serving(tester, process)
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    tester.node.create_subscription(TwistStamped, f'{name}/screw', lambda m: None, qos)
    stderr = process.wait_for_stderr('incompatible QoS')
    assert "topic '~/screw', requesting incompatible QoS" in stderr
    wait_until_serving(tester, process)
    assert_clean_exit(*process.stop(signal.SIGTERM))


def test_spin_returns_when_the_context_shuts_down(own_context, namespace):
    node = RotationNode(context=own_context, namespace=namespace)
    thread = threading.Thread(target=spin, args=(node, make_executor(own_context)))
    thread.start()
    time.sleep(0.3)
    begin = time.monotonic()
    own_context.try_shutdown()
    thread.join(timeout=5.0)
    assert not thread.is_alive()
    assert time.monotonic() - begin < rotation_node.SPIN_TIMEOUT + 0.5
    node.destroy_node()
