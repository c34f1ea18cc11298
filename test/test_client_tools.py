"""rotation_client's tools: the angle hint, echo, set, param, play, tf-demo."""

from contextlib import redirect_stdout
import csv
import io
import json
import math
import os
import re
import subprocess
import sys
import threading
import time

from bag_helpers import REAL, tf_chain_messages, write_bag
from conftest import console_script, DISCOVERY_TIMEOUT, NodeProcess, REPO, RUN, script_env
from conftest import TIMEOUT
from doc_blocks import assert_doc_output
import pytest
from rot_tools.io import interface
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from scipy.spatial.transform import Rotation
from test_client import approx, CLIENT, DIGITS, interrupt, one_line_error, popen, send_until
import yaml

HINT = ('rotation_client: hint: an angle of 30 rad is more than 2π: if it is in degrees, '
        'add --deg\n')


@pytest.fixture(scope='module')
def node(tmp_path_factory, here):
    """Return the name of a rotation_node process (default parameters) for this module."""
    process = NodeProcess(tmp_path_factory.mktemp('tools'))
    here.answered('orientation', 0, 0, 0, 1, '--node', process.name, '--timeout', 20)
    yield process.name
    process.kill()


def wait_subscribed(tester, topic):
    """Wait until something (the client under test) subscribes to ``topic``."""
    tester.spin_until(lambda: tester.node.count_subscribers(topic) > 0, DISCOVERY_TIMEOUT,
                      f'a subscription on {topic}')


# The angle hint


@pytest.mark.parametrize('args, hint', [
    (('ZYX', 30, 20, 10), HINT),
    (('xyz', 10, -30, 20), HINT),
    (('ZYX', 30, 20, 10, '--deg'), ''),
    (('ZYX', 6.2, -6.2, 1), ''),
])
def test_angle_hint(here, node, args, hint):
    """Radians typed beyond 2π: one hint line on stderr after the answer, status 0."""
    result = here('euler', *args, '--node', node)
    assert result.returncode == 0 and result.stderr == hint, result.stderr
    assert yaml.safe_load(result.stdout)['answer']['euler_angles']['unit'] == 'rad'


# echo


def test_echo_once_prints_the_answer(here, node, tester):
    echo = popen('echo', 'rpy', '--once', '--json', '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/rpy')
    sent = here.answered('orientation', 0, math.sin(0.2), 0, math.cos(0.2), '--node', node)
    send_until(lambda: echo.poll() is not None, lambda: here.answered(
        'orientation', 0, math.sin(0.2), 0, math.cos(0.2), '--node', node))
    out, err = echo.communicate(timeout=60)
    assert echo.returncode == 0 and err == '', err
    data = json.loads(out)
    assert data['frame_id'] == 'map' and set(data) == {'stamp', 'frame_id', 'rpy'}
    assert data['stamp']['sec'] >= sent['input']['stamp']['sec']
    assert data['rpy'] == {'roll': 0.0, 'pitch': pytest.approx(0.4, **DIGITS), 'yaw': 0.0,
                           'unit': 'rad'}


def test_echo_count_prints_each_message(here, node, tester):
    echo = popen('echo', 'quaternion', '--count', 3, '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/quaternion')
    for angle in (0.1, 0.2):
        here.answered('euler', 'ZYX', angle, 0, 0, '--node', node)
    send_until(lambda: echo.poll() is not None,
               lambda: here.answered('euler', 'ZYX', 0.3, 0, 0, '--node', node))
    out, err = echo.communicate(timeout=60)
    assert echo.returncode == 0 and err == '', err
    documents = list(yaml.safe_load_all(out))
    assert len(documents) == 3
    # Each in the order sent (an input is sent until answered, so one may come twice), the
    # last one the last sent.
    z = [d['quaternion']['z'] for d in documents]
    assert z == sorted(z) and z[-1] == approx(math.sin(0.15))
    assert all(min(abs(v - math.sin(angle / 2)) for angle in (0.1, 0.2, 0.3)) < 1e-12
               for v in z)


def test_echo_into_a_pipe_closed_early_ends_quietly(node, tester):
    """rotation_client echo rpy | head -1: status 141 (SIGPIPE's), no traceback."""
    from geometry_msgs.msg import QuaternionStamped
    from rclpy.qos import qos_profile_sensor_data
    echo = popen('echo', 'rpy', '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/rpy')
    pub = tester.publisher(f'{node}/orientation', QuaternionStamped,
                           qos_profile_sensor_data)
    msg = QuaternionStamped()
    msg.header.frame_id, msg.quaternion.w = 'map', 1.0

    def publish_until(done):
        for _ in range(200):
            if done():
                return
            msg.header.stamp.sec += 1
            pub.publish(msg)
            tester.spin_for(0.05)

    first = []
    reader = threading.Thread(target=lambda: first.append(echo.stdout.readline()), daemon=True)
    reader.start()
    publish_until(lambda: first)
    reader.join(timeout=30)
    assert first == ['---\n']
    echo.stdout.close()  # as head does once it has its lines
    publish_until(lambda: echo.poll() is not None)
    err = echo.stderr.read()
    assert (echo.wait(timeout=30), err) == (141, '')


def test_echo_unknown_output_and_unreachable(here, node):
    line = one_line_error(here('echo', 'nothing'), 2)
    assert "argument OUTPUT: invalid choice: 'nothing'" in line
    line = one_line_error(here('echo', 'rpy', '--count', '0'), 2)
    assert "--count: must be a whole number >= 1, got '0'" in line
    absent = f'/{RUN}/nobody/rot_tools'
    line = one_line_error(here('echo', 'rpy', '--node', absent, '--timeout', 1), 1)
    assert line.startswith(f'rotation_client: cannot reach node {absent}')


class StreamDuringCall:
    """A Client whose node publishes a stream (stamps 1, 2, ...) from the moment echo asks it."""

    def __init__(self):
        from types import SimpleNamespace
        self.callbacks = []
        self.sent = 0
        self.node = SimpleNamespace(get_publishers_info_by_topic=lambda topic: [])

    def publish(self):
        from geometry_msgs.msg import Vector3Stamped
        self.sent += 1
        msg = Vector3Stamped()
        msg.header.stamp.sec = self.sent
        for callback in self.callbacks:
            callback(msg)

    def subscribe(self, msg_type, topic, callback, qos):
        from types import SimpleNamespace
        self.callbacks.append(callback)
        return SimpleNamespace(topic_name=topic, get_publisher_count=lambda: 1)

    def topic(self, name):
        return f'/rot_tools/{name}'

    def parameters(self, names):
        self.publish()
        return {'euler_sequence': 'ZYX', 'angle_unit': 'rad'}

    def spin_until(self, done, seconds):
        if not done():
            self.publish()
        return done()


def test_echo_prints_a_stream_from_its_start():
    """Echo subscribes before it asks the node anything: the stream's first message is printed."""
    from rot_tools.ros.client.arguments import parse_args
    from rot_tools.ros.client.rotation_client import COMMANDS
    out = io.StringIO()
    with redirect_stdout(out):
        COMMANDS['echo'](StreamDuringCall(), parse_args(['echo', 'rpy', '--once']))
    assert yaml.safe_load(out.getvalue())['stamp'] == {'sec': 1, 'nanosec': 0}


@pytest.fixture(scope='module')
def diagnosed(tmp_path_factory, here):
    """Return (name, its /diagnostics topic) of a rotation_node whose /diagnostics is remapped."""
    topic = f'/{RUN}/diagnosed/diagnostics'
    process = NodeProcess(tmp_path_factory.mktemp('diagnosed'), '-r', f'/diagnostics:={topic}')
    here.answered('orientation', 0, 0, 0, 1, '--node', process.name, '--timeout', 20)
    yield process.name, topic
    process.kill()


def test_echo_of_a_topic_of_another_type_prints_it_whole(here, diagnosed):
    """Echo rpy --topic /diagnostics: the node publishes a DiagnosticArray there, printed whole."""
    name, topic = diagnosed
    data = here.answered('echo', 'rpy', '--topic', topic, '--once', '--node', name,
                         '--timeout', 20)
    assert set(data) == {'header', 'status'}
    inputs = [s for s in data['status'] if s['name'] == 'rot_tools: inputs']
    assert [s['hardware_id'] for s in inputs] == [name] and inputs[0]['level'] == 0


def test_diagnostics_prints_each_status(here, diagnosed):
    """One block per status: its level as a word, its message, its values by key."""
    name, topic = diagnosed
    result = here('diagnostics', '--once', '--topic', topic, '--timeout', 20)
    assert (result.returncode, result.stderr) == (0, '')
    imu, inputs = yaml.safe_load_all(result.stdout)
    assert (imu['name'], imu['level'], imu['hardware_id']) == (
        'rot_tools: imu conventions', 'STALE', '')
    assert imu['message'].startswith('0.0 s of ~/imu in the last 10 s')
    assert (inputs['name'], inputs['level'], inputs['hardware_id']) == (
        'rot_tools: inputs', 'OK', name)
    assert inputs['values'][f'{name}/orientation'].endswith(' msg/s, 0 refused')
    assert set(inputs['values']) == {f'{name}/{row.name}' for row in interface.INPUTS}
    shown = re.sub(r'(\n  sec: )\d+(\n  nanosec: )\d+', r'\1...\2...', result.stdout)
    shown = re.sub(r'(: )[\d.]+( msg/s)', r'\1...\2', shown.replace(name, '/rot_tools'))
    assert_doc_output('client-diagnostics', '$ rotation_client diagnostics --once\n'
                      + re.sub(r'last \d+ s', 'last ... s', shown))


def test_diagnostics_with_nothing_published(here, namespace):
    line = one_line_error(here('diagnostics', '--topic', f'{namespace}/diagnostics',
                               '--timeout', 1), 1)
    assert line == (f'rotation_client: nothing on {namespace}/diagnostics within 1 s (no '
                    'publisher: is rotation_node running, with ROS_DOMAIN_ID '
                    f"{os.environ['ROS_DOMAIN_ID']}?)")


# set


def set_line(result):
    assert result.returncode == 0 and result.stderr == '', result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 1
    return lines[0]


@pytest.fixture
def restored(node, tester):
    """Return the module's node; its parameters set back to their defaults after the test."""
    from rclpy.parameter import Parameter
    yield node
    defaults = {'angle_unit': 'rad', 'euler_sequence': 'ZYX',
                'quaternion_tolerance': QUATERNION_TOLERANCE, 'publish_markers': True}
    results = tester.set_parameters(node, [Parameter(name, value=value)
                                           for name, value in defaults.items()])
    assert all(result.successful for result in results)


def test_set_types_values_as_the_node_declares_them(here, restored):
    name = restored
    assert set_line(here('set', 'angle_unit', 'deg', '--node', name)) == (
        f"node {name}: angle_unit = 'deg'")
    # An integer for a double, digits for a string, 'false' for a bool; 1e-2, which YAML (and
    # so ros2 param set) reads as a string, for a double.
    assert set_line(here('set', 'quaternion_tolerance', '1', '--node', name)) == (
        f'node {name}: quaternion_tolerance = 1.0')
    assert set_line(here('set', 'quaternion_tolerance', '1e-2', '--node', name)) == (
        f'node {name}: quaternion_tolerance = 0.01')
    assert here('param', 'get', 'quaternion_tolerance', '--node', name).stdout == (
        'Double value is: 0.01\n')
    assert set_line(here('set', 'euler_sequence', 'xyz', '--node', name)) == (
        f"node {name}: euler_sequence = 'xyz'")
    assert set_line(here('set', 'publish_markers', 'false', '--node', name)) == (
        f'node {name}: publish_markers = False')
    answer = here.answered('euler', 'xyz', 90, 0, 0, '--deg', '--node', name)
    assert answer['input']['unit'] == 'deg' and answer['input']['sequence'] == 'xyz'
    assert answer['answer']['euler_angles']['angles'] == approx([90, 0, 0])
    assert 'markers' not in answer['answer']


@pytest.mark.parametrize('args, why', [
    (('angle_unit', 'degrees'), "node {node} refused angle_unit = 'degrees': angle_unit "
     "'degrees' is not 'rad' or 'deg'"),
    (('quaternion_tolerance', '-1'), 'node {node} refused quaternion_tolerance = -1.0: '
     'Parameter quaternion_tolerance out of range'),
    (('nothing', '1'), "node {node} has no parameter 'nothing'"),
])
def test_set_refused_is_the_nodes_reason(here, node, args, why):
    line = one_line_error(here('set', *args, '--node', node), 1)
    assert line.startswith('rotation_client: ' + why.format(node=node)), line


@pytest.mark.parametrize('value, why', [
    ('0.' + '0' * 130_000 + '1', 'is below the smallest double, 4.9e-324: it would be sent as 0'),
    ('1e-400', 'is below the smallest double, 4.9e-324: it would be sent as 0'),
    ('1' + '0' * 400, 'is beyond the largest double, 1.798e+308: it would be sent as infinity'),
    ('-1e309', 'is beyond the largest double, 1.798e+308: it would be sent as infinity'),
])
def test_set_a_double_float64_cannot_hold(here, node, value, why):
    """A number typed that float64 rounds to 0 or infinity: one line, exit 2, nothing sent."""
    line = one_line_error(here('set', 'quaternion_tolerance', value, '--node', node), 2)
    shown = repr(value) if len(value) <= 40 else f'{value[:40]!r}… ({len(value)} characters)'
    assert line == (f'rotation_client: parameter quaternion_tolerance of node {node} is a '
                    f'double: {shown} {why}')


def test_set_refused_long_value_is_shortened(here, node):
    """The node's refusal of a 131 KB value: the value cut to its first 40 characters."""
    value = 'x' * 131_072
    line = one_line_error(here('set', 'euler_sequence', value, '--node', node), 1)
    short = f"{'x' * 40}… (131072 characters)"
    assert line.startswith(f"rotation_client: node {node} refused euler_sequence = '{short}': ")
    assert 'x' * 41 not in line and len(line) < 400, line


@pytest.mark.parametrize('args, why', [
    (('quaternion_tolerance', 'abc'), "'abc' is not a number"),
    (('quaternion_tolerance', 'true'), "'true' is not a number"),
    (('publish_markers', '1'), "'1' is not true or false"),
    (('publish_markers', 'maybe'), "'maybe' is not true or false"),
])
def test_set_a_value_that_does_not_fit_the_type(here, node, args, why):
    """One line naming the parameter's type, exit 2; nothing is sent."""
    kind = 'double' if args[0] == 'quaternion_tolerance' else 'boolean'
    line = one_line_error(here('set', *args, '--node', node), 2)
    assert line == (f'rotation_client: parameter {args[0]} of node {node} is a {kind}: {why}')


# param get / list


def test_param_get_prints_as_ros2_param_get(here, node):
    lines = {name: here('param', 'get', name, '--node', node)
             for name in ('quaternion_tolerance', 'angle_unit', 'publish_markers')}
    assert {name: (r.returncode, r.stdout, r.stderr) for name, r in lines.items()} == {
        'quaternion_tolerance': (0, f'Double value is: {QUATERNION_TOLERANCE}\n', ''),
        'angle_unit': (0, 'String value is: rad\n', ''),
        'publish_markers': (0, 'Boolean value is: True\n', '')}
    hidden = here('param', 'get', 'marker_scale', '--hide-type', '--node', node)
    assert (hidden.returncode, hidden.stdout) == (0, '1.0\n')
    assert here.answered('--json', 'param', 'get', 'euler_sequence', '--node', node) == {
        'name': 'euler_sequence', 'type': 'string', 'value': 'ZYX'}
    line = one_line_error(here('param', 'get', 'nothing', '--node', node), 1)
    assert line == f"rotation_client: node {node} has no parameter 'nothing'"


def test_param_list_prints_as_ros2_param_list(here, node):
    """Every parameter of the node (rclpy's own too), sorted, indented by two spaces."""
    from rot_tools.ros.node.rotation_node import PARAMETERS, RCLPY_PARAMETERS
    names = sorted([*PARAMETERS, *RCLPY_PARAMETERS])
    result = here('param', 'list', '--node', node)
    assert (result.returncode, result.stderr) == (0, '')
    assert result.stdout == ''.join(f'  {name}\n' for name in names)
    typed = here('param', 'list', '--param-type', '--node', node).stdout.splitlines()
    assert [line.split(' (type: ')[0] for line in typed] == [f'  {name}' for name in names]
    assert '  quaternion_tolerance (type: double)' in typed
    assert '  publish_markers (type: boolean)' in typed
    assert here.answered('param', 'list', '--json', '--node', node) == names
    absent = f'/{RUN}/nobody/rot_tools'
    line = one_line_error(here('param', 'list', '--node', absent, '--timeout', 1), 1)
    assert line.startswith(f'rotation_client: cannot reach node {absent}: not found')


@pytest.mark.parametrize('args, message', [
    (('param',), 'the following arguments are required: VERB'),
    (('param', 'get'), 'the following arguments are required: NAME'),
    (('param', 'set', 'x', '1'), "argument VERB: invalid choice: 'set'"),
    (('param', 'list', 'x'), 'unrecognized arguments: x'),
])
def test_param_bad_arguments(here, args, message):
    line = one_line_error(here(*args), 2)
    assert line.startswith('rotation_client: error: ') and message in line, line


# play

JACKAL = {'/imu/data': 'imu', '/jackal_velocity_controller/odom': 'odometry'}
"""The recording's topics and the node's inputs they are remapped onto."""
JACKAL_TYPES = ('sensor_msgs/msg/Imu', 'nav_msgs/msg/Odometry')

SUMMARY = re.compile(r'played (\d+) messages of (\S+) in [\d.]+ s \(rate ([\d.]+)\): (.*) '
                     r'\(([\d.]+) s to ([\d.]+) s of the recording\)\n')


def remaps(mapping):
    """Return the ROS arguments that remap each topic of ``mapping`` onto its value."""
    return ('--ros-args',
            *[word for topic, to in mapping.items() for word in ('-r', f'{topic}:={to}')])


def collect(tester, topic, count, seconds=TIMEOUT):
    """Spin until ``count`` messages of ``topic`` arrived or ``seconds`` passed; return them."""
    deadline = time.monotonic() + seconds
    while len(tester.received[topic]) < count and time.monotonic() < deadline:
        tester.spin_once()
    return tester.received[topic]


def bag_csv(*args):
    """Return {(frame_id, stamp text): row} of ``rot-tools bag REAL ARGS --csv -`` (all digits)."""
    command = console_script('rot-tools', 'rot_tools.cli.main') + [
        'bag', str(REAL), *map(str, args), '--precision', '17', '--csv', '-']
    result = subprocess.run(command, capture_output=True, text=True, timeout=120,
                            env=script_env(command), stdin=subprocess.DEVNULL)
    assert result.returncode == 0, result.stderr
    return {(row['frame_id'], row['stamp']): row for row in csv.DictReader(io.StringIO(
        result.stdout))}


def test_play_drives_the_node_as_rot_tools_bag_reads_it(here, node, tester):
    """Each ~/quaternion of a played second of the Jackal bag is what ``rot-tools bag`` reads."""
    from geometry_msgs.msg import QuaternionStamped
    from rclpy.qos import QoSProfile
    topic = f'{node}/quaternion'
    tester.subscribe(topic, QuaternionStamped, QoSProfile(depth=1000))
    tester.wait_matched([topic])
    slice_ = ('--topics', *JACKAL, '--start', 10, '--end', 11, '--rate', 2)
    result = here('play', REAL, *slice_,
                  *remaps({bag: f'{node}/{name}' for bag, name in JACKAL.items()}))
    assert (result.returncode, result.stderr) == (0, '')
    shown = ' '.join(['play', '../shared/data/jackal_imu_odometry.bag', *map(str, slice_),
                      *remaps({bag: f'/rot_tools/{name}' for bag, name in JACKAL.items()})])
    assert_doc_output('client-play', f'$ rotation_client {shown}\n' + re.sub(
        r' in [\d.]+ s ', ' in ... s ', result.stdout.replace(
            str(REAL), '../shared/data/jackal_imu_odometry.bag').replace(node, '/rot_tools')))
    *plan, summary = result.stdout.splitlines(keepends=True)
    assert plan == [f'playing {bag} ({msgtype}) on {node}/{name}\n'
                    for (bag, name), msgtype in zip(JACKAL.items(), JACKAL_TYPES)]
    total, bag, rate, counts, first, last = SUMMARY.fullmatch(summary).groups()
    assert (bag, rate, first, last) == (str(REAL), '2', '10', '11')
    expected = bag_csv('--start', 10, '--end', 11)
    assert len(expected) == int(total) == 102
    assert counts == ', '.join(f'{t} {sum(r["topic"] == t for r in expected.values())}'
                               for t in JACKAL)
    received = collect(tester, topic, len(expected))
    # Best effort into the node: a message may be lost on a loaded machine, not most.
    assert len(received) >= len(expected) // 2, (len(received), len(expected))
    for msg in received:
        stamp = msg.header.stamp
        row = expected[msg.header.frame_id, f'{stamp.sec}.{stamp.nanosec:09d}']
        q = msg.quaternion
        assert [q.x, q.y, q.z, q.w] == pytest.approx(
            [float(row[k]) for k in ('qx', 'qy', 'qz', 'qw')], abs=1e-12)


def test_play_a_rosbag2_bag_with_tf(here, tester, namespace, tmp_path):
    """A rosbag2 bag's /tf and /tf_static arrive whole, /tf_static transient local."""
    from rot_tools.ros.tf_input import TF_QOS, TF_STATIC_QOS
    from tf2_msgs.msg import TFMessage
    messages, _, _ = tf_chain_messages(n=10)
    bag = write_bag(tmp_path / 'tf_bag', messages, storage='mcap')
    for name, qos in (('tf', TF_QOS), ('tf_static', TF_STATIC_QOS)):
        tester.subscribe(f'{namespace}/{name}', TFMessage, qos)
    result = here('play', bag, '--rate', 50,
                  *remaps({'/tf': f'{namespace}/tf', '/tf_static': f'{namespace}/tf_static'}))
    assert (result.returncode, result.stderr) == (0, '')
    assert ': /tf_static 1, /tf 10 (0 s to 1.4 s of the recording)' in result.stdout
    got = collect(tester, f'{namespace}/tf', 10) + collect(tester, f'{namespace}/tf_static', 1)
    sent = [msg for topic, _, _, msg in sorted(messages, key=lambda m: (m[0] == '/tf', m[2]))]
    assert len(got) == len(sent) == 11
    for msg, original in zip(got[10:] + got[:10], sent):
        assert [(t.header.frame_id, t.child_frame_id, t.header.stamp.sec, t.header.stamp.nanosec,
                 t.transform.rotation.w, t.transform.translation.z) for t in msg.transforms] == [
            (t.header.frame_id, t.child_frame_id, t.header.stamp.sec, t.header.stamp.nanosec,
             t.transform.rotation.w, t.transform.translation.z) for t in original.transforms]


class FakeReader:
    """Recorded messages for Player.play: (topic, stamp ns) each, a std_msgs/String."""

    start_time = 1_000_000_000

    def __init__(self, stamps):
        from types import SimpleNamespace
        self.connection = SimpleNamespace(topic='/chatter', msgtype='std_msgs/msg/String',
                                          ext=SimpleNamespace(latching=0))
        self.stamps = stamps

    def messages(self, connections, start=None, stop=None):
        return ((self.connection, stamp, b'') for stamp in self.stamps
                if (start is None or stamp >= start) and (stop is None or stamp < stop))

    def deserialize(self, raw, msgtype):
        from types import SimpleNamespace
        return SimpleNamespace(data='hello')


def test_no_message_is_published_before_its_time():
    """Each message waits (spinning) for its recorded offset from the first, over the rate."""
    from rot_tools.ros.client.bag_player import Player
    from std_msgs.msg import String

    class Publisher:

        def __init__(self):
            self.times = []

        def publish(self, msg):
            assert msg.data == 'hello'
            self.times.append(time.monotonic())

        def wait_for_all_acked(self, timeout):
            return True

    publisher = Publisher()

    def spin_until(done, seconds):
        while not done():
            time.sleep(0.001)
        return True
    stamps = [FakeReader.start_time + k
              for k in (0, 10_000_000, 10_000_000, 90_000_000, 200_000_000)]
    reader = FakeReader(stamps)
    player = Player(lambda cls, topic, qos: publisher, spin_until,
                    {'/chatter': (String, [reader.connection])})
    played = player.play(reader, 4.0, start=stamps[1])
    assert played.counts == {'/chatter': 4} and (played.first, played.last) == (0.01, 0.2)
    offsets = [t - publisher.times[0] for t in publisher.times]
    assert all(offset >= (stamp - stamps[1]) / 4e9 for offset, stamp in zip(offsets, stamps[1:]))


def test_play_refusals(here, monkeypatch, tmp_path):
    """Each is one line: exit 2 for what was given, 1 for nothing listening or no rosbags."""
    from rot_tools.io import bag_read
    line = one_line_error(here('play', REAL, '--topics', '/nope'), 2)
    assert line == (f'rotation_client: {REAL} has no topic /nope: its topics are /imu/data, '
                    '/jackal_velocity_controller/odom')
    text = tmp_path / 'notes.txt'
    text.write_text('not a bag\n')
    assert one_line_error(here('play', text), 2).startswith(f'rotation_client: {text}: not a bag')
    assert one_line_error(here('play', REAL, '--start', 5, '--end', 2), 2) == (
        'rotation_client: error: --end 2 is before --start 5')
    monkeypatch.setattr(bag_read, 'rosbags_missing', lambda: 'rosbags')
    assert one_line_error(here('play', REAL), 1) == (
        "rotation_client: play needs the rosbags library (rosbags is missing), the 'bag' extra: "
        "pip install -e '.[bag]' in the rot_tools checkout")


def play_unheard(here, node):
    """Play /imu/data to nobody (1 s); return (exit status, stdout, the stderr line)."""
    result = here('play', REAL, '--topics', '/imu/data', '--timeout', 1, '--node', node)
    assert result.stdout == 'playing /imu/data (sensor_msgs/msg/Imu)\n'
    assert result.stderr.count('\n') == 1, result.stderr
    return result.returncode, result.stderr


def test_play_to_nobody_advises_a_remap(here, node):
    """The node is up, nothing listens to the bag's topics: remap them onto its inputs."""
    assert play_unheard(here, node) == (1, (
        'rotation_client: no subscription on /imu/data within 1 s: remap the topics onto the '
        f"node's inputs (--ros-args -r /imu/data:={node}/imu)\n"))


def test_play_with_the_node_down_says_so(here):
    absent = f'/{RUN}/nobody/rot_tools'
    domain = os.environ['ROS_DOMAIN_ID']
    assert play_unheard(here, absent) == (1, (
        f'rotation_client: no subscription on /imu/data within 1 s, and node {absent} is not '
        f'running (not found with ROS_DOMAIN_ID {domain})\n'))


@pytest.mark.parametrize('rate', ['1e-320', '0.0009', '1001', 'inf', 'nan', '-1'])
def test_play_refuses_a_rate_beyond_its_range(here, rate):
    line = one_line_error(here('play', REAL, '--rate', rate), 2)
    assert line.endswith(f"--rate: must be a number from 0.001 to 1000, got '{rate}'"), line


def test_play_interrupted_exits_130_quietly(tester, namespace):
    """Ctrl-C while the whole recording plays: exit 130 within 1 s, nothing printed."""
    from sensor_msgs.msg import Imu
    topic = f'{namespace}/imu'
    tester.subscribe(topic, Imu)
    play = popen('play', REAL, '--topics', '/imu/data', *remaps({'/imu/data': topic}))
    tester.wait_messages(topic, 5, DISCOVERY_TIMEOUT)
    assert interrupt(play) == (130, f'playing /imu/data (sensor_msgs/msg/Imu) on {topic}\n', '')


# tf-demo


def remapped(namespace):
    """Return the ROS arguments that move /tf and /tf_static into ``namespace``."""
    return ('--ros-args', '-r', f'/tf:={namespace}/tf',
            '-r', f'/tf_static:={namespace}/tf_static')


def test_tf_demo_publishes_the_tree(here, tester, namespace):
    from rot_tools.ros.tf_input import TF_QOS, TF_STATIC_QOS
    from tf2_msgs.msg import TFMessage
    tester.subscribe(f'{namespace}/tf', TFMessage, TF_QOS)
    tester.subscribe(f'{namespace}/tf_static', TFMessage, TF_STATIC_QOS)
    demo = popen('tf-demo', *remapped(namespace))
    try:
        line = demo.stdout.readline()
        assert line == (f'publishing map -> odom -> base_link -> camera on {namespace}/tf and '
                        f'{namespace}/tf_static until Ctrl-C\n')
        static = tester.wait_messages(f'{namespace}/tf_static', 1, DISCOVERY_TIMEOUT)[0]
        edges = {(t.header.frame_id, t.child_frame_id): t.transform for t in static.transforms}
        camera = edges['base_link', 'camera']
        q = camera.rotation
        assert Rotation.from_quat([q.x, q.y, q.z, q.w]).as_euler('ZYX', degrees=True) == approx(
            [0, 15, 0])
        assert set(edges) == {('map', 'odom'), ('base_link', 'camera')}
        moving = tester.wait_messages(f'{namespace}/tf', 5, DISCOVERY_TIMEOUT)
        for msg in moving:
            (t,) = msg.transforms
            assert (t.header.frame_id, t.child_frame_id) == ('odom', 'base_link')
            q, b = t.transform.rotation, t.transform.translation
            yaw = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_euler('ZYX')[0]
            # On the circle of radius 1 about (0, 1, 0), facing along it.
            assert [b.x, b.y, b.z] == pytest.approx([math.sin(yaw), 1 - math.cos(yaw), 0],
                                                    abs=1e-12)
        result = here('tf', 'map', 'camera', '--once', '--deg', '--timeout', 20,
                      *remapped(namespace))
        assert result.returncode == 0, result.stderr
        report = yaml.safe_load(result.stdout)
        assert report['chain'] == ['map', 'odom', 'base_link', 'camera']
        assert (report['rpy']['roll'], report['rpy']['pitch']) == (0.0, 15.0)
        command = "rotation_client tf map camera --once --deg | sed -n '1,3p;/^rpy:/,/pitch:/p'"
        lines = result.stdout.splitlines(keepends=True)
        rpy = lines.index('rpy:\n')
        assert_doc_output('readme-tf', ('$ rotation_client tf-demo &\n' + line).replace(
            namespace, '') + f'$ {command}\n' + ''.join(lines[:3] + lines[rpy:rpy + 3]))
    finally:
        stopped = interrupt(demo)
    assert stopped == (130, '', '')


def test_tf_demo_for_a_duration(here, namespace):
    result = here('tf-demo', '--duration', 1, *remapped(namespace))
    assert result.returncode == 0 and result.stderr == '', result.stderr
    assert result.stdout.endswith(f'{namespace}/tf_static for 1 s\n')


def test_tf_demo_without_tf2_msgs():
    """One line and exit 1 when tf2_msgs does not import."""
    probe = (
        'import sys\n'
        'class Refuse:\n'
        '    def find_spec(self, name, path=None, target=None):\n'
        "        if name.split('.')[0] == 'tf2_msgs':\n"
        "            raise ImportError('refused: ' + name)\n"
        'sys.meta_path.insert(0, Refuse())\n'
        'from rot_tools.ros.client.rotation_client import main\n'
        "sys.exit(main(['tf-demo']))\n")
    command = [sys.executable, '-c', probe]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60,
                            env=script_env(command), cwd=REPO)
    assert result.returncode == 1 and result.stdout == ''
    assert result.stderr.count('\n') == 1
    assert result.stderr.startswith('rotation_client: tf2_msgs is not importable'), (
        result.stderr)


# Ctrl-C


def test_echo_interrupted_exits_130_quietly(here, node, tester):
    echo = popen('echo', 'rpy', '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/rpy')
    first = []
    reader = threading.Thread(target=lambda: first.append(echo.stdout.readline()), daemon=True)
    reader.start()
    send_until(lambda: first, lambda: here.answered('orientation', 0, 0, 0, 1, '--node', node))
    status, out, err = interrupt(echo)
    assert (status, err) == (130, '')
    assert first == ['---\n']


# doc/client.md's examples of echo, set and param


def test_doc_examples(here, node, tester):
    shown = (node, '/rot_tools')
    echo = popen('echo', 'rpy', '--once', '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/rpy')
    send_until(lambda: echo.poll() is not None,
               lambda: here.answered('pose', 1, 0, 0.5, 0, 0, 1, 0, '--node', node))
    out, err = echo.communicate(timeout=60)
    assert echo.returncode == 0, err
    text = '$ rotation_client echo rpy --once\n' + out
    assert_doc_output('client-echo', _stamps_elided(text))
    lines = []
    for args in (('set', 'angle_unit', 'deg'), ('set', 'angle_unit', 'degrees'),
                 ('euler', 'ZYX', 30, 20, 10)):
        result = here(*args, '--node', node)
        lines.append(f'$ rotation_client {" ".join(map(str, args))}'
                     + (' > /dev/null' if args[0] == 'euler' else '') + '\n')
        lines.append(('' if args[0] == 'euler' else result.stdout) + result.stderr)
        if result.returncode:
            lines.append(f'$ echo $?\n{result.returncode}\n')
    here('set', 'angle_unit', 'rad', '--node', node)
    assert_doc_output('client-set', ''.join(lines).replace(*shown))
    lines = []
    for args in (('param', 'get', 'quaternion_tolerance'),
                 ('set', 'quaternion_tolerance', '1e-2'), ('set', 'quaternion_tolerance', 'abc'),
                 ('param', 'list')):
        result = here(*args, '--node', node)
        lines.append(f'$ rotation_client {" ".join(args)}\n{result.stdout}{result.stderr}')
        if result.returncode:
            lines.append(f'$ echo $?\n{result.returncode}\n')
    here('set', 'quaternion_tolerance', QUATERNION_TOLERANCE, '--node', node)
    assert_doc_output('client-param', ''.join(lines).replace(*shown))


def _stamps_elided(text):
    return re.sub(r'(\n\s*sec: )\d+(\n\s*nanosec: )\d+', r'\1...\2...', text)


# A full disk


@pytest.mark.parametrize('args', [
    ('--version',), ('describe',), ('param', 'list'), ('param', 'get', 'angle_unit'),
    ('set', 'angle_unit', 'rad'), ('orientation', 0, 0, 0, 1), ('play', REAL),
    ('tf-demo', '--duration', 1, '--ros-args', '-r', f'/tf:=/{RUN}/full/tf', '-r',
     f'/tf_static:=/{RUN}/full/tf_static'),
])
def test_a_full_disk_is_one_line(node, args):
    """rotation_client ... > /dev/full: one line on stderr, exit 1, no traceback."""
    command = CLIENT + [*map(str, args), '--node', node, '--timeout', '20']
    if '--ros-args' in args:  # --node and --timeout before the ROS arguments
        at = args.index('--ros-args')
        command = CLIENT + [*map(str, args[:at]), '--node', node, *args[at:]]
    with open('/dev/full', 'w') as full:
        result = subprocess.run(command, stdout=full, stderr=subprocess.PIPE, text=True,
                                timeout=60, env=script_env(command), stdin=subprocess.DEVNULL)
    assert (result.returncode, result.stderr) == (
        1, 'rotation_client: cannot write to stdout: No space left on device\n')
