"""rotation_node's /diagnostics: an IMU's conventions and the inputs' counts."""

from pathlib import Path
import time

import conftest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped
import numpy as np
import pytest
from rclpy.qos import qos_profile_sensor_data
from rot_tools.core.imu import faults, GyroAxesCheck, GyroUnitsCheck, ImuChecks
from rot_tools.ros.node import diagnostics
from rot_tools.ros.node.rotation_node import RotationNode
from sensor_msgs.msg import Imu
from test_imu import jackal  # noqa: F401 (the module's fixture)

BAG = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'jackal_imu_odometry.bag'
MESSAGES = 15 * 50
"""The recording's first 15 s: the longest the stream may take to be OK."""


def recorded_imu():
    """Return the bag's /imu/data as (stamps (N,), Imu messages (N,)), read by rosbags."""
    highlevel = pytest.importorskip('rosbags.highlevel')
    if not BAG.exists():
        pytest.skip(f'{BAG} is not here')
    stamps, messages = [], []
    with highlevel.AnyReader([BAG]) as reader:
        connections = [c for c in reader.connections if c.topic == '/imu/data']
        for connection, _, raw in reader.messages(connections=connections):
            m = reader.deserialize(raw, connection.msgtype)
            msg = Imu()
            msg.header.frame_id = m.header.frame_id
            msg.header.stamp.sec = m.header.stamp.sec
            msg.header.stamp.nanosec = m.header.stamp.nanosec
            for name in ('orientation', 'angular_velocity', 'linear_acceleration'):
                ours, theirs = getattr(msg, name), getattr(m, name)
                for axis in 'xyzw' if name == 'orientation' else 'xyz':
                    setattr(ours, axis, float(getattr(theirs, axis)))
            for name in ('orientation_covariance', 'angular_velocity_covariance',
                         'linear_acceleration_covariance'):
                setattr(msg, name, np.asarray(getattr(m, name), dtype=np.float64))
            stamps.append(m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec)
            messages.append(msg)
            if len(messages) == MESSAGES:
                break
    return np.array(stamps), messages


def in_degrees(msg):
    """Return a copy of an Imu message whose gyro reads degrees/s."""
    copy = Imu(header=msg.header, orientation=msg.orientation,
               orientation_covariance=msg.orientation_covariance,
               linear_acceleration=msg.linear_acceleration,
               linear_acceleration_covariance=msg.linear_acceleration_covariance,
               angular_velocity_covariance=msg.angular_velocity_covariance)
    w = msg.angular_velocity
    copy.angular_velocity.x, copy.angular_velocity.y, copy.angular_velocity.z = np.degrees(
        [w.x, w.y, w.z])
    return copy


class Watched:
    """A RotationNode under test whose /diagnostics the tester collects, and its ~/imu."""

    def __init__(self, context, tester, name):
        namespace = f'/{conftest.RUN}/{name}'
        self.topic = f'{namespace}/diagnostics'
        self.node = RotationNode(context=context, namespace=namespace, cli_args=[
            '--ros-args', '-r', f'{diagnostics.TOPIC}:={self.topic}', '-p',
            'publish_markers:=false'])
        self.prefix = self.node.get_fully_qualified_name()
        tester.add_node(self.node)
        tester.subscribe(self.topic, DiagnosticArray)
        self.imu = tester.publisher(f'{self.prefix}/imu', Imu, qos_profile_sensor_data)
        self.received = tester.received[self.topic]

    def latest(self, after=0):
        """Return {status name suffix: status} of the latest array, or None (none after)."""
        if len(self.received) <= after:
            return None
        array = self.received[-1]
        return {s.name.split(': ', 1)[1]: s for s in array.status}


@pytest.fixture(scope='module')
def watched(ros_context, tester_context):
    """Two nodes, 'clean' and 'degrees', and a tester matched with both."""
    tester = conftest.Tester(tester_context, name='diagnostics_tester')
    nodes = {}
    try:
        for name in ('clean', 'degrees'):
            nodes[name] = Watched(ros_context, tester, f'diagnostics_{name}')
        tester.wait_matched([w.topic for w in nodes.values()])
        yield tester, nodes
    finally:
        for w in nodes.values():
            tester.remove_node(w.node)
            w.node.destroy_node()
        tester.close()


def values(status):
    return {kv.key: kv.value for kv in status.values}


def test_an_imu_is_stale_then_ok_and_in_degrees_a_gyro_units_warning(watched):
    """Before any input and under 5 s: STALE; the clean stream OK, degrees/s WARN."""
    tester, nodes = watched
    clean, degrees = nodes['clean'], nodes['degrees']
    first = len(clean.received)
    tester.spin_until(lambda: clean.latest(first), what='a DiagnosticArray')
    imu = clean.latest()['imu conventions']
    assert (imu.level, imu.hardware_id) == (DiagnosticStatus.STALE, '')
    assert imu.message.startswith('0.0 s of ~/imu in the last 10 s (0 messages)')
    assert values(imu) == dict.fromkeys(ImuChecks._fields, 'unknown')
    assert clean.received[-1].status[0].name == 'rot_tools: imu conventions'

    stamps, messages = recorded_imu()
    stamps = stamps - stamps[0]
    now = tester.node.get_clock().now().nanoseconds * 1e-9
    stale, verdicts = [], {}
    start = time.monotonic()
    for k, msg in enumerate(messages):
        fresh = now + stamps[k]
        msg.header.stamp.sec, msg.header.stamp.nanosec = int(fresh), int(fresh % 1 * 1e9)
        while time.monotonic() < start + stamps[k]:  # the recorded timing
            tester.spin_once()
        clean.imu.publish(msg)
        degrees.imu.publish(in_degrees(msg))
        for name, w in nodes.items():
            status = (w.latest() or {}).get('imu conventions')
            if status is None:
                continue
            if status.level == DiagnosticStatus.STALE and status.message[0] != '0':
                stale.append(status)
            elif status.level != DiagnosticStatus.STALE:
                verdicts.setdefault(name, status)
        if len(verdicts) == 2:
            break
    assert stale, 'no STALE status while under 5 s of input'
    assert set(verdicts) == {'clean', 'degrees'}, f'no verdict within {k / 50:.1f} s'
    ok, warn = verdicts['clean'], verdicts['degrees']
    assert (ok.level, ok.hardware_id) == (DiagnosticStatus.OK, 'base_link'), ok.message
    assert ok.message.startswith('no fault (')
    assert list(values(ok)) == list(ImuChecks._fields)
    assert all(v.split()[0] in ('ok', 'unknown') for v in values(ok).values()), values(ok)
    assert values(ok)['accel_units'].startswith('ok scale=')
    assert warn.level == DiagnosticStatus.WARN
    assert warn.message.startswith('gyro_units at fault ('), warn.message
    scale = float(values(warn)['gyro_units'].split('scale=')[1])
    assert values(warn)['gyro_units'].startswith('fault ')
    assert scale == pytest.approx(np.pi / 180, rel=0.03)


def test_the_inputs_status_counts_rates_and_a_refusal(watched):
    tester, nodes = watched
    clean = nodes['clean']
    pose = tester.publisher(f'{clean.prefix}/pose', PoseStamped, qos_profile_sensor_data)
    topic = f'{clean.prefix}/pose'
    zero = PoseStamped()
    zero.pose.orientation.w = 0.0  # (1 by default)
    deadline = time.monotonic() + 3 * conftest.TIMEOUT
    while not clean.node.refused_counts()['zero_quaternion']:  # (best effort: sent again)
        assert time.monotonic() < deadline, 'the zero quaternion was never refused'
        pose.publish(zero)
        tester.spin_for(0.1)
    first = len(clean.received)
    tester.spin_until(lambda: clean.latest(first), what='a DiagnosticArray after the refusal')
    inputs = clean.latest()['inputs']
    assert inputs.name == 'rot_tools: inputs' and inputs.hardware_id == clean.prefix
    assert inputs.level == DiagnosticStatus.WARN
    assert inputs.message.startswith('1 input(s) refused in the last ')
    assert values(inputs)[topic].endswith(' msg/s, 1 refused (zero_quaternion 1)')
    assert set(values(inputs)) >= {f'{clean.prefix}/{name}' for name in ('pose', 'imu')}
    assert values(inputs)[f'{clean.prefix}/imu'].endswith(' msg/s, 0 refused')


def shown(status):
    """Return a DiagnosticStatus as text: name, level by name, hardware_id; message; values."""
    levels = {DiagnosticStatus.OK: 'OK', DiagnosticStatus.WARN: 'WARN',
              DiagnosticStatus.ERROR: 'ERROR', DiagnosticStatus.STALE: 'STALE'}
    width = max(len(kv.key) for kv in status.values)
    return ''.join([f'{status.name}  [{levels[status.level]}]  {status.hardware_id}\n',
                    f'{status.message}\n',
                    *(f'  {kv.key:{width}}  {kv.value}\n' for kv in status.values)])


def test_the_documented_status_of_an_imu_in_degrees():
    """10 s of the recording, its gyro in degrees/s, as received 20 ms apart: doc/node.md."""
    from doc_blocks import assert_doc_output
    stamps, messages = recorded_imu()
    window = diagnostics.ImuWindow()
    for stamp, msg in zip(stamps[:500], messages):
        window.add(in_degrees(msg), stamp - stamps[0])
    status = diagnostics.imu_status('rot_tools', window, stamps[499] - stamps[0])
    assert status.level == DiagnosticStatus.WARN
    assert_doc_output('node-diagnostics-degrees', shown(status))


# ---- steady verdicts over a window ----------------------------------------------------------


def units(status, scale=None):
    """Return a GyroUnitsCheck of that status."""
    return GyroUnitsCheck(status=status, message=f'{status}.', scale=scale)


def axes(status, matrix):
    """Return a GyroAxesCheck of that status and matrix."""
    return GyroAxesCheck(status=status, message=f'{status}.', matrix=matrix, mirror=None,
                         negate=None)


@pytest.mark.parametrize('whole, halves, steady', [
    ('fault', ('fault', 'fault'), 'fault'),
    ('fault', ('fault', 'unknown'), 'fault'),
    ('fault', ('ok', 'fault'), 'unknown'),
    ('ok', ('ok', 'fault'), 'unknown'),
    ('ok', ('unknown', 'unknown'), 'ok'),
    ('unknown', ('fault', 'fault'), 'unknown'),
])
def test_a_check_holds_where_both_halves_bear_it_out(whole, halves, steady):
    found = diagnostics.steady(units(whole, 0.5), [units(h, 0.5) for h in halves])
    assert found.status == steady
    if steady == 'unknown' and whole != 'unknown':
        assert found.message.startswith(f'{whole} over the window, but not over both its halves')
        assert found.scale is None


def test_another_axis_map_in_a_half_leaves_the_axes_unknown():
    swap = ((0, 1, 0), (1, 0, 0), (0, 0, 1))
    negated = ((1, 0, 0), (0, 1, 0), (0, 0, -1))
    assert diagnostics.steady(axes('fault', swap), [axes('fault', swap)] * 2).status == 'fault'
    found = diagnostics.steady(axes('fault', swap), [axes('fault', swap), axes('fault', negated)])
    assert (found.status, found.matrix) == ('unknown', None)


def test_a_fault_over_half_the_window_is_not_reported():
    """10 s of the recording, its first 5 s with the gyro in degrees/s: gyro_units unknown."""
    stamps, messages = recorded_imu()
    window = diagnostics.ImuWindow()
    for k, (stamp, msg) in enumerate(zip(stamps[:500], messages)):
        window.add(in_degrees(msg) if k < 250 else msg, stamp - stamps[0])
    status = diagnostics.imu_status('rot_tools', window, stamps[499] - stamps[0])
    assert status.level == DiagnosticStatus.OK, status.message
    assert values(status)['gyro_units'] == 'unknown'


def test_a_quaternion_written_w_first_is_the_only_fault_of_every_window(jackal):  # noqa: F811
    """Every 10 s window, 5 s apart, of the recording written w-first: that fault, or unknown."""
    imu, _ = jackal
    q = np.roll(imu['q'], 1, axis=1)  # the fields x, y, z, w hold w, x, y, z
    for start in range(0, len(q) - 500, 250):
        part = slice(start, start + 500)
        checks = diagnostics.steady_checks(imu['t'][part], q[part], imu['gyro'][part],
                                           imu['accel'][part])
        assert faults(checks) in ((), ('quaternion',)), [c.message for c in checks]
        assert checks.quaternion.reading == (
            'w-first' if checks.quaternion.status == 'fault' else 'as recorded')
