"""rotation_node over real DDS, against the math module and scipy's Rotation."""

import math
import time

from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, QuaternionStamped
from geometry_msgs.msg import TransformStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from nav_msgs.srv import GetPlan
import numpy as np
import pytest
from rcl_interfaces.msg import Log, ParameterType
from rclpy.exceptions import InvalidParameterValueException
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, qos_profile_sensor_data, ReliabilityPolicy
from rclpy.serialization import serialize_message
from rot_tools import (
    euler_to_matrix, matrix_to_euler, matrix_to_rotvec, quaternion_to_matrix,
    rotvec_to_matrix, screw_exp, screw_from_transform, screw_interpolate, screw_log)
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.io import interface
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.io.report import transform_report
from rot_tools.ros.message_types import message_class
from rot_tools.ros.node import rotation_node
from rot_tools.ros.node.rotation_node import REFUSAL_REASONS, RotationNode
from rot_tools.ros.node.screw_path import MAX_PATH_STEPS
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import Imu
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker
import yaml

ATOL = 1e-12
INPUTS = {row.name: message_class(row.type_name) for row in interface.INPUTS}
"""Every input of the node, by name: its message class."""
ALWAYS = ('rotation_matrix', 'quaternion', 'axis_angle', 'euler_angles', 'rpy', 'screw')
"""Outputs published for every accepted input (screw_axis only for a non-identity one,
rodrigues only away from θ = π)."""
STAMPED = ALWAYS[1:]
"""Those that carry the input's header (all but the MultiArray rotation_matrix)."""


# Messages and expected values


def pose_stamped(q=(0.0, 0.0, 0.0, 1.0), p=(0.0, 0.0, 0.0), frame='map', stamp=0):
    """Build a PoseStamped with quaternion q = (x, y, z, w) and position p."""
    msg = PoseStamped()
    msg.header.frame_id = frame
    msg.header.stamp.sec = stamp
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = map(float, p)
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = map(float, q)
    return msg


def transform_stamped(q, t=(0.0, 0.0, 0.0), frame='map'):
    """Build a TransformStamped with rotation q = (x, y, z, w) and translation t."""
    msg = TransformStamped()
    msg.header.frame_id = frame
    msg.child_frame_id = 'body'
    tr = msg.transform.translation
    tr.x, tr.y, tr.z = map(float, t)
    r = msg.transform.rotation
    r.x, r.y, r.z, r.w = map(float, q)
    return msg


def euler_stamped(angles, frame='map'):
    """Build a Vector3Stamped holding three Euler angles."""
    msg = Vector3Stamped()
    msg.header.frame_id = frame
    msg.vector.x, msg.vector.y, msg.vector.z = map(float, angles)
    return msg


def set_pose(pose, q, p):
    """Fill a geometry_msgs/Pose with position p and orientation q = (x, y, z, w)."""
    pose.position.x, pose.position.y, pose.position.z = map(float, p)
    o = pose.orientation
    o.x, o.y, o.z, o.w = map(float, q)


def pose_with_covariance(q, p=(0.0, 0.0, 0.0), frame='map', covariance=None):
    """Build a PoseWithCovarianceStamped; its covariance all zeros (unknown) unless given."""
    msg = PoseWithCovarianceStamped()
    msg.header.frame_id = frame
    set_pose(msg.pose.pose, q, p)
    if covariance is not None:
        msg.pose.covariance = np.ravel(covariance).tolist()
    return msg


def odometry(q, p=(0.0, 0.0, 0.0), frame='odom', covariance=None):
    """Build an Odometry of base_link in ``frame``; its twist is Inf (unused by the node)."""
    msg = Odometry()
    msg.header.frame_id = frame
    msg.child_frame_id = 'base_link'
    set_pose(msg.pose.pose, q, p)
    msg.twist.twist.linear.x = math.inf
    if covariance is not None:
        msg.pose.covariance = np.ravel(covariance).tolist()
    return msg


def imu(q, frame='imu_link', orientation_covariance0=0.0, covariance=None):
    """Build an Imu with orientation q; angular velocity NaN (unused by the node)."""
    msg = Imu()
    msg.header.frame_id = frame
    o = msg.orientation
    o.x, o.y, o.z, o.w = map(float, q)
    if covariance is not None:
        msg.orientation_covariance = np.ravel(covariance).tolist()
    else:
        msg.orientation_covariance[0] = orientation_covariance0
    msg.angular_velocity.z = math.nan
    return msg


def quaternion_stamped(q, frame='map'):
    """Build a QuaternionStamped."""
    msg = QuaternionStamped()
    msg.header.frame_id = frame
    o = msg.quaternion
    o.x, o.y, o.z, o.w = map(float, q)
    return msg


def xyz(v):
    """Return a geometry_msgs Vector3 / Point as a NumPy array."""
    return np.array([v.x, v.y, v.z])


def quat(q):
    """Return a geometry_msgs Quaternion as a NumPy array (x, y, z, w)."""
    return np.array([q.x, q.y, q.z, q.w])


def check_outputs(out, stamp, frame, R, b, seq='ZYX', degrees=False, scale=1.0,
                  marker=True):
    """Every output of one input equals the math module's value for (R, b)."""
    matrix = out['rotation_matrix']
    assert [(d.label, d.size, d.stride) for d in matrix.layout.dim] == [
        ('rows', 3, 9), ('cols', 3, 3)]
    assert matrix.layout.data_offset == 0
    np.testing.assert_allclose(np.reshape(matrix.data, (3, 3)), R, rtol=0, atol=ATOL)
    for name in STAMPED + (('screw_axis',) if marker else ()):
        assert out[name].header.stamp.sec == stamp
        assert out[name].header.frame_id == frame
    # scipy's canonical quaternion has the node's sign rule (w > 0, else first non-zero > 0)
    np.testing.assert_allclose(quat(out['quaternion'].quaternion),
                               Rotation.from_matrix(R).as_quat(canonical=True),
                               rtol=0, atol=ATOL)
    np.testing.assert_allclose(xyz(out['axis_angle'].vector), matrix_to_rotvec(R),
                               rtol=0, atol=ATOL)
    angles, _ = matrix_to_euler(R, seq)
    np.testing.assert_allclose(xyz(out['euler_angles'].vector),
                               np.degrees(angles) if degrees else angles,
                               rtol=0, atol=ATOL * (180 if degrees else 1))
    # ~/rpy: x, y, z = roll, pitch, yaw (REP 103), for every sequence: scipy's extrinsic 'xyz'
    # where it is unique; at gimbal lock the library's rule (yaw 0, roll the free angle).
    rpy, lock = matrix_to_euler(R, RPY_SEQUENCE)
    if not lock:
        np.testing.assert_allclose(rpy, Rotation.from_matrix(R).as_euler('xyz'), rtol=0,
                                   atol=1e-10)
    np.testing.assert_allclose(xyz(out['rpy'].vector), np.degrees(rpy) if degrees else rpy,
                               rtol=0, atol=ATOL * (180 if degrees else 1))
    twist = out['screw'].twist
    np.testing.assert_allclose(np.concatenate([xyz(twist.angular), xyz(twist.linear)]),
                               screw_log(R, b), rtol=0, atol=ATOL * (1 + np.linalg.norm(b)))
    if marker:
        screw = screw_from_transform(R, b)
        m = out['screw_axis']
        assert (m.type, m.action) == (Marker.ARROW, Marker.ADD)
        assert quat(m.pose.orientation).tolist() == [0.0, 0.0, 0.0, 1.0]
        assert m.color.a > 0 and m.scale.x > 0 and m.scale.y > 0
        assert len(m.points) == 2
        # The axis point is |b|/θ away for small θ: compare relative to its size.
        size = 1.0 + np.linalg.norm(screw.point)
        np.testing.assert_allclose(xyz(m.points[0]), screw.point, rtol=0, atol=ATOL * size)
        np.testing.assert_allclose(xyz(m.points[1]) - xyz(m.points[0]),
                                   scale * screw.direction, rtol=0, atol=ATOL * size * 10)


# The rig: node under test + tester


class Rig:
    """rotation_node under test (own context) and the tester, matched both ways."""

    def __init__(self, tester, node):
        self.tester = tester
        self.node = node
        self.prefix = node.get_fully_qualified_name()
        tester.add_node(node)
        tester.subscribe_outputs(self.prefix)
        if self.topic('rpy') not in tester.received:  # (conftest's list may lack it)
            tester.subscribe(self.topic('rpy'), Vector3Stamped)
        tester.subscribe_rosout()
        self.pubs = {name: tester.node.create_publisher(msg_type, f'{self.prefix}/{name}', 10)
                     for name, msg_type in INPUTS.items()}
        tester.spin_until(self._matched, what=f'discovery of {self.prefix}')
        self._stamp = 0

    def _matched(self):
        ours = self.prefix + '/'
        return (all(p.get_subscription_count() > 0 for p in self.pubs.values())
                and all(s.get_publisher_count() > 0 for s in self.tester._subscriptions.values())
                and all(s.get_publisher_count() > 0 for s in self.node.subscriptions
                        if s.topic_name.startswith(ours))
                and all(p.get_subscription_count() > 0 for p in self.node.publishers
                        if p.topic_name.startswith(ours)))

    def topic(self, name):
        return f'{self.prefix}/{name}'

    def send(self, kind, msg):
        """Publish msg on ~/kind with a fresh stamp (sec); return the stamp."""
        self._stamp += 1
        msg.header.stamp.sec = self._stamp
        self.pubs[kind].publish(msg)
        return self._stamp

    def outputs(self, stamp, marker=True):
        """Wait for the outputs of the input stamped ``stamp``; return {output: msg}."""
        names = ALWAYS + (('screw_axis',) if marker else ())
        for name in names:
            self.tester.wait_messages(self.topic(name), 1)
        self.tester.spin_until(
            lambda: all(self.received(n)[-1].header.stamp.sec == stamp for n in names[1:]),
            what=f'outputs of input {stamp}')
        return {name: self.received(name)[-1] for name in names}

    def output_of(self, name, stamp):
        """Wait for output ``name`` (one message) of the input stamped ``stamp``; return it."""
        def stamped(msg):
            return (msg.markers[0] if name == 'markers' else msg).header.stamp.sec == stamp
        self.tester.spin_until(lambda: any(map(stamped, self.received(name))),
                               what=f'~/{name} of input {stamp}')
        (msg,) = filter(stamped, self.received(name))
        return msg

    def roundtrip(self, kind, msg, marker=True):
        """send() then outputs()."""
        return self.outputs(self.send(kind, msg), marker)

    def received(self, name):
        return self.tester.received[self.topic(name)]

    def clear(self):
        for name in ALWAYS + ('screw_axis',):
            self.received(name).clear()

    def call(self, srv_type, name, request):
        return self.tester.call(srv_type, self.topic(name), request)

    def describe(self):
        return self.call(Trigger, 'describe', Trigger.Request())

    def report(self):
        response = self.describe()
        assert response.success, response.message
        return yaml.safe_load(response.message)

    def report_or_note(self):
        """Return ~/describe's YAML document, with or without an accepted input."""
        return yaml.safe_load(self.describe().message)

    def screw_path(self, start, goal, tolerance=0.0):
        request = GetPlan.Request(start=start, goal=goal, tolerance=float(tolerance))
        return self.call(GetPlan, 'screw_path', request).plan

    def node_logs(self, level=None):
        name = self.node.get_logger().name
        return [log for log in self.tester.logs
                if log.name == name and (level is None or log.level == level)]


@pytest.fixture
def make_rig(ros_context, tester, namespace):
    """Make Rigs: each call starts a fresh RotationNode with the given parameter overrides."""
    nodes = []

    def make(**parameters):
        node = RotationNode(
            context=ros_context, namespace=namespace,
            parameter_overrides=[Parameter(k, value=v) for k, v in parameters.items()])
        nodes.append(node)
        return Rig(tester, node)

    yield make
    for node in nodes:
        tester.remove_node(node)
        node.destroy_node()


@pytest.fixture
def rig(make_rig):
    return make_rig()


RNG = np.random.default_rng(20251121)


def random_quaternion():
    q = RNG.normal(size=4)
    return q / np.linalg.norm(q)


# Topics

POSE_CASES = {
    'general': (random_quaternion(), RNG.normal(size=3) * 2.0),
    'half_turn_x': ((1.0, 0.0, 0.0, 0.0), (0.3, -1.0, 2.0)),
    'half_turn_oblique': ((0.6, 0.0, 0.8, 0.0), (1.0, 2.0, 3.0)),
    'tiny_angle': ((math.sin(0.5e-9), 0.0, 0.0, math.cos(0.5e-9)), (0.0, 5.0, 1.0)),
    'pure_rotation': ((0.0, math.sin(0.4), 0.0, math.cos(0.4)), (0.0, 0.0, 0.0)),
    'pure_translation': ((0.0, 0.0, 0.0, 1.0), (1.0, -2.0, 0.5)),
    'gimbal_lock': ((0.0, math.sin(math.pi / 4), 0.0, math.cos(math.pi / 4)), (1.0, 0, 0)),
}


@pytest.mark.parametrize('case', POSE_CASES)
def test_pose_outputs(rig, case):
    q, p = POSE_CASES[case]
    stamp = rig.send('pose', pose_stamped(q, p, frame='odom'))
    out = rig.outputs(stamp)
    check_outputs(out, stamp, 'odom', quaternion_to_matrix(q), np.asarray(p, float))


@pytest.mark.parametrize('case', ['general', 'half_turn_oblique', 'pure_translation'])
def test_transform_outputs(rig, case):
    q, t = POSE_CASES[case]
    stamp = rig.send('transform', transform_stamped(q, t, frame='world'))
    check_outputs(rig.outputs(stamp), stamp, 'world', quaternion_to_matrix(q),
                  np.asarray(t, float))


@pytest.mark.parametrize('angles', [(0.5, 0.2, 0.1), (-3.0, 1.2, 2.9), (1.0, math.pi / 2, 0.0)])
def test_euler_outputs(rig, angles):
    stamp = rig.send('euler', euler_stamped(angles, frame='base_link'))
    out = rig.outputs(stamp)
    R = euler_to_matrix(angles, 'ZYX')
    check_outputs(out, stamp, 'base_link', R, np.zeros(3))
    if angles[1] != math.pi / 2:  # away from gimbal lock the angles come back as sent
        np.testing.assert_allclose(xyz(out['euler_angles'].vector), angles, rtol=0, atol=ATOL)


ROBOT_INPUTS = {  # kind: (build(q, p), carries a position)
    'pose_with_covariance': (lambda q, p: pose_with_covariance(q, p, frame='map'), True),
    'odometry': (lambda q, p: odometry(q, p, frame='map'), True),
    'imu': (lambda q, p: imu(q, frame='map'), False),
    'orientation': (lambda q, p: quaternion_stamped(q, frame='map'), False),
}


def check_against_scipy(out, q, b):
    """Return the outputs of an input with orientation q and position b, against scipy."""
    rotation = Rotation.from_quat(q)  # normalises q; (x, y, z, w) order, as ROS
    np.testing.assert_allclose(np.reshape(out['rotation_matrix'].data, (3, 3)),
                               rotation.as_matrix(), rtol=0, atol=ATOL)
    np.testing.assert_allclose(quat(out['quaternion'].quaternion),
                               rotation.as_quat(canonical=True), rtol=0, atol=ATOL)
    np.testing.assert_allclose(xyz(out['axis_angle'].vector), rotation.as_rotvec(),
                               rtol=0, atol=ATOL)
    if abs(rotation.as_matrix()[2, 0]) < 0.99:  # away from gimbal lock, one answer
        np.testing.assert_allclose(xyz(out['euler_angles'].vector), rotation.as_euler('ZYX'),
                                   rtol=0, atol=ATOL)
    if not b.any():  # a pure rotation about an axis through the origin: twist = (θ·l̂, 0)
        np.testing.assert_allclose(xyz(out['screw'].twist.angular), rotation.as_rotvec(),
                                   rtol=0, atol=ATOL)
        assert xyz(out['screw'].twist.linear).tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize('case', ['general', 'half_turn_oblique', 'tiny_angle', 'gimbal_lock'])
@pytest.mark.parametrize('kind', ROBOT_INPUTS)
def test_robot_input_outputs(rig, kind, case):
    build, positioned = ROBOT_INPUTS[kind]
    q, p = POSE_CASES[case]
    b = np.asarray(p, float) if positioned else np.zeros(3)
    stamp = rig.send(kind, build(q, p))
    out = rig.outputs(stamp)
    check_outputs(out, stamp, 'map', quaternion_to_matrix(q), b)
    check_against_scipy(out, q, b)
    report = rig.report()
    assert report['source'] == rig.topic(kind)
    assert report['source_type'] == {
        'pose_with_covariance': 'geometry_msgs/msg/PoseWithCovarianceStamped',
        'odometry': 'nav_msgs/msg/Odometry', 'imu': 'sensor_msgs/msg/Imu',
        'orientation': 'geometry_msgs/msg/QuaternionStamped'}[kind]
    assert report['translation'] == pytest.approx(b.tolist(), rel=1e-11, abs=1e-12)
    q_report = report['quaternion']
    assert [q_report[k] for k in 'xyzw'] == pytest.approx(
        Rotation.from_quat(q).as_quat(canonical=True).tolist(), rel=1e-11, abs=1e-12)


def test_rpy_whatever_the_euler_sequence(make_rig):
    # An IMU rolled 5°, pitched −10° and yawed 30° (REP 103: about the fixed x, y, z axes):
    # ~/rpy carries them as x, y, z in angle_unit, with euler_sequence ZXZ; ~/describe too.
    q = Rotation.from_euler('xyz', [5.0, -10.0, 30.0], degrees=True).as_quat()
    rig = make_rig(euler_sequence='ZXZ', angle_unit='deg')
    out = rig.roundtrip('imu', imu(q))
    np.testing.assert_allclose(xyz(out['rpy'].vector), [5.0, -10.0, 30.0], rtol=0, atol=1e-12)
    assert out['rpy'].header == out['euler_angles'].header
    np.testing.assert_allclose(
        xyz(out['euler_angles'].vector),
        np.degrees(matrix_to_euler(quaternion_to_matrix(q), 'ZXZ')[0]), rtol=0, atol=1e-12)
    rpy = rig.report()['rpy']
    assert list(rpy) == ['roll', 'pitch', 'yaw', 'unit'] and rpy['unit'] == 'deg'
    np.testing.assert_allclose([rpy['roll'], rpy['pitch'], rpy['yaw']], [5.0, -10.0, 30.0],
                               rtol=0, atol=1e-10)
    assert set_one(rig.node, 'angle_unit', 'rad').successful
    out = rig.roundtrip('orientation', quaternion_stamped(q))
    np.testing.assert_allclose(xyz(out['rpy'].vector), np.radians([5.0, -10.0, 30.0]),
                               rtol=0, atol=1e-15)


def test_odometry_yaw_in_degrees(make_rig):
    """Check that the question users ask most: a robot's roll, pitch, yaw from its odometry."""
    rig = make_rig(angle_unit='deg')
    yaw, pitch, roll = math.radians(30.0), math.radians(-10.0), math.radians(5.0)
    # q of Rot_z(yaw) Rot_y(pitch) Rot_x(roll), the product of the three half-angle forms
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    q = (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
         cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)
    out = rig.roundtrip('odometry', odometry(q, (2.0, 1.0, 0.0)))
    np.testing.assert_allclose(xyz(out['euler_angles'].vector), [30.0, -10.0, 5.0],
                               rtol=0, atol=1e-12)
    np.testing.assert_allclose(quat(out['quaternion'].quaternion), q, rtol=0, atol=ATOL)
    assert out['euler_angles'].header.frame_id == 'odom'


@pytest.mark.parametrize('seq, angles, degrees', [
    ('ZYX', (30.0, 20.0, 10.0), True), ('xyz', (0.3, -1.2, 2.5), False),
    ('ZXZ', (-2.0, 0.4, 3.0), False), ('yxy', (100.0, 170.0, -45.0), True)])
def test_quaternion_of_euler_input(make_rig, seq, angles, degrees):
    """~/quaternion of Euler input is the quaternion to paste into a Pose (vs scipy)."""
    rig = make_rig(euler_sequence=seq, angle_unit='deg' if degrees else 'rad')
    out = rig.roundtrip('euler', euler_stamped(angles))
    expected = Rotation.from_euler(seq, angles, degrees=degrees).as_quat(canonical=True)
    np.testing.assert_allclose(quat(out['quaternion'].quaternion), expected, rtol=0, atol=ATOL)


@pytest.mark.parametrize('q, expected', [
    ((0.0, 0.0, -1.0, 0.0), (0.0, 0.0, 1.0, 0.0)),  # half turn: first non-zero made positive
    ((0.0, -0.6, 0.8, 0.0), (0.0, 0.6, -0.8, 0.0)),
    ((0.1, 0.2, -0.3, -0.9), (-0.1, -0.2, 0.3, 0.9)),  # w < 0: the whole q flips
    ((0.0, 0.0, 0.0, -1.0), (0.0, 0.0, 0.0, 1.0)),
])
def test_quaternion_output_has_the_canonical_sign(rig, q, expected):
    q = np.array(q) / np.linalg.norm(q)
    expected = np.array(expected) / np.linalg.norm(expected)
    stamp = rig.send('orientation', quaternion_stamped(q))
    out = rig.outputs(stamp, marker=not np.allclose(np.abs(q), [0, 0, 0, 1]))
    np.testing.assert_allclose(quat(out['quaternion'].quaternion), expected, rtol=0, atol=ATOL)


def test_identity_has_no_marker(rig):
    rig.send('pose', pose_stamped((0, 0, 0, 1)))
    stamp = rig.send('euler', euler_stamped((0.0, 0.0, 0.0)))
    out = rig.outputs(stamp, marker=False)
    check_outputs(out, stamp, 'map', np.eye(3), np.zeros(3), marker=False)
    later = rig.send('pose', pose_stamped((0, 0, 1, 0)))
    rig.outputs(later)
    markers = rig.received('screw_axis')  # the identity's DELETEs: test_node_markers.py
    assert [m.header.stamp.sec for m in markers if m.action == Marker.ADD] == [later]


def test_rodrigues_vector_is_tan_half_angle_times_axis(rig):
    """~/rodrigues = tan(θ/2)·l̂, cross-checked with scipy's rotation vector."""
    q, p = POSE_CASES['general']
    stamp = rig.send('pose', pose_stamped(q, p))
    rig.outputs(stamp)
    rig.tester.spin_until(lambda: rig.received('rodrigues')
                          and rig.received('rodrigues')[-1].header.stamp.sec == stamp,
                          what='~/rodrigues')
    rotvec = Rotation.from_quat(q).as_rotvec()
    angle = np.linalg.norm(rotvec)
    np.testing.assert_allclose(xyz(rig.received('rodrigues')[-1].vector),
                               math.tan(angle / 2) * rotvec / angle, rtol=1e-12, atol=ATOL)


def test_no_rodrigues_vector_at_half_turn_but_every_other_output(rig):
    stamp = rig.send('pose', pose_stamped((1.0, 0.0, 0.0, 0.0), (0.3, -1.0, 2.0)))
    out = rig.outputs(stamp)
    check_outputs(out, stamp, 'map', quaternion_to_matrix((1.0, 0.0, 0.0, 0.0)),
                  np.array([0.3, -1.0, 2.0]))
    later = rig.roundtrip('pose', pose_stamped((0, 0, 0.6, 0.8)))['screw'].header.stamp.sec
    rig.tester.spin_until(lambda: rig.received('rodrigues'), what='~/rodrigues')
    assert [m.header.stamp.sec for m in rig.received('rodrigues')] == [later]
    report = rig.report()
    assert report['refused']['rodrigues_at_pi'] == report['refused']['total'] == 1
    assert 'infinite at θ = π' in report['last_refusals']['rodrigues_at_pi']['message']


@pytest.mark.parametrize('kind', ['pose', 'transform'])
def test_half_turn_outputs_share_one_axis_sign(rig, kind):
    """At θ = π the axis sign is free; every output of one input must use the same one."""
    build = pose_stamped if kind == 'pose' else transform_stamped
    for q, p in [((1, 0, 0, 0), (0, 1, 2)), ((0, -0.6, 0.8, 0), (1, 2, 3)),
                 ((-0.48, 0.6, 0.64, 0), (-1, 0.5, 4)), ((0, 0, -1, 0), (0, 0, 2))]:
        out = rig.roundtrip(kind, build(q, p))
        R, b = quaternion_to_matrix(q), np.asarray(p, float)
        rotvec = xyz(out['axis_angle'].vector)
        twist = np.concatenate([xyz(out['screw'].twist.angular),
                                xyz(out['screw'].twist.linear)])
        arrow = xyz(out['screw_axis'].points[1]) - xyz(out['screw_axis'].points[0])
        assert np.linalg.norm(rotvec) == pytest.approx(math.pi, abs=ATOL)
        np.testing.assert_allclose(twist[:3], rotvec, rtol=0, atol=ATOL)
        np.testing.assert_allclose(arrow * math.pi, rotvec, rtol=0, atol=10 * ATOL)
        np.testing.assert_allclose(rotvec_to_matrix(rotvec), R, rtol=0, atol=ATOL)
        R_twist, b_twist = screw_exp(twist)
        np.testing.assert_allclose(R_twist, R, rtol=0, atol=ATOL)
        np.testing.assert_allclose(b_twist, b, rtol=0, atol=10 * ATOL)


def test_qos_of_inputs_and_outputs(rig):
    graph = rig.tester.node
    for name in INPUTS:
        (info,) = graph.get_subscriptions_info_by_topic(rig.topic(name))
        assert info.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT
        assert info.qos_profile.durability == DurabilityPolicy.VOLATILE
    for name in ALWAYS + ('screw_axis',):
        (info,) = graph.get_publishers_info_by_topic(rig.topic(name))
        assert info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
        assert info.qos_profile.durability == DurabilityPolicy.VOLATILE


def test_sensor_data_publisher_is_served(rig):
    pub = rig.tester.node.create_publisher(PoseStamped, rig.topic('pose'),
                                           qos_profile_sensor_data)
    rig.tester.spin_until(lambda: pub.get_subscription_count() > 0, what='matching')
    q, p = POSE_CASES['general']
    msg = pose_stamped(q, p)
    msg.header.stamp.sec = 4242
    # Best effort both ways: resend until the node has seen one.
    deadline = time.monotonic() + 5.0
    while not rig.received('screw') and time.monotonic() < deadline:
        pub.publish(msg)
        rig.tester.spin_for(0.1)
    out = rig.outputs(4242)
    check_outputs(out, 4242, 'map', quaternion_to_matrix(q), p)


# Bad input


BAD_INPUTS = {
    'pose_nan_position': ('pose', pose_stamped((0, 0, 0, 1), (math.nan, 0, 0)),
                          'non_finite', 'pose.position.x is nan'),
    'pose_inf_position': ('pose', pose_stamped((0, 0, 0, 1), (0, 0, -math.inf)),
                          'non_finite', 'pose.position.z is -inf'),
    'pose_nan_orientation': ('pose', pose_stamped((0, 0, 0, math.nan)),
                             'non_finite', 'pose.orientation.w is nan'),
    'pose_zero_quaternion': ('pose', pose_stamped((0, 0, 0, 0)),
                             'zero_quaternion', 'pose.orientation is the zero quaternion'),
    'pose_long_quaternion': ('pose', pose_stamped((0, 0, 0, 1.5)),
                             'non_unit_quaternion', 'norm 1.5'),
    'pose_just_beyond_tolerance': ('pose', pose_stamped(np.array([0, 0, 0.6, 0.8]) * 1.0011),
                                   'non_unit_quaternion', 'quaternion_tolerance 0.001'),
    'pose_huge_quaternion': ('pose', pose_stamped((1e300, 1e300, 0, 0)),
                             'non_unit_quaternion', 'norm'),
    'pose_overflowing_position': ('pose', pose_stamped((0, 0, math.sin(0.05), math.cos(0.05)),
                                                       (1e308, -1e308, 0)),
                                  'not_decomposable', 'overflows float64'),
    'transform_nan_translation': ('transform', transform_stamped((0, 0, 0, 1), (0, math.nan, 0)),
                                  'non_finite', 'transform.translation.y is nan'),
    'transform_inf_rotation': ('transform', transform_stamped((math.inf, 0, 0, 1)),
                               'non_finite', 'transform.rotation.x is inf'),
    'transform_zero_quaternion': ('transform', transform_stamped((0, 0, 0, 0)),
                                  'zero_quaternion', 'transform.rotation is the zero quaternion'),
    'transform_short_quaternion': ('transform', transform_stamped((0, 0.5, 0, 0)),
                                   'non_unit_quaternion', 'norm 0.5'),
    'euler_nan': ('euler', euler_stamped((0.1, math.nan, 0.3)),
                  'non_finite', 'vector.y is nan'),
    'euler_inf': ('euler', euler_stamped((math.inf, 0, 0)),
                  'non_finite', 'vector.x is inf'),
    'pose_with_covariance_nan_position': (
        'pose_with_covariance', pose_with_covariance((0, 0, 0, 1), (0, math.nan, 0)),
        'non_finite', 'pose.pose.position.y is nan'),
    'pose_with_covariance_inf_orientation': (
        'pose_with_covariance', pose_with_covariance((0, -math.inf, 0, 1)),
        'non_finite', 'pose.pose.orientation.y is -inf'),
    'pose_with_covariance_zero_quaternion': (
        'pose_with_covariance', pose_with_covariance((0, 0, 0, 0)),
        'zero_quaternion', 'pose.pose.orientation is the zero quaternion'),
    'pose_with_covariance_long_quaternion': (
        'pose_with_covariance', pose_with_covariance((0, 1, 0, 1)),
        'non_unit_quaternion', 'norm 1.41421356'),
    'odometry_inf_position': ('odometry', odometry((0, 0, 0, 1), (math.inf, 0, 0)),
                              'non_finite', 'pose.pose.position.x is inf'),
    'odometry_nan_orientation': ('odometry', odometry((0, 0, math.nan, 1)),
                                 'non_finite', 'pose.pose.orientation.z is nan'),
    'odometry_zero_quaternion': ('odometry', odometry((0, 0, 0, 0), (1, 2, 3)),
                                 'zero_quaternion', 'zero quaternion'),
    'odometry_short_quaternion': ('odometry', odometry((0, 0, 0.3, 0.3)),
                                  'non_unit_quaternion', 'norm 0.424264069'),
    'imu_no_orientation': ('imu', imu((0, 0, 0, 0), orientation_covariance0=-1.0),
                           'no_orientation', 'orientation_covariance[0] is -1'),
    'imu_no_orientation_with_unit_q': ('imu', imu((0, 0, 0, 1), orientation_covariance0=-1.0),
                                       'no_orientation', 'no orientation estimate'),
    'imu_nan_orientation': ('imu', imu((math.nan, 0, 0, 1)),
                            'non_finite', 'orientation.x is nan'),
    'imu_zero_quaternion': ('imu', imu((0, 0, 0, 0)),
                            'zero_quaternion', 'orientation is the zero quaternion'),
    'imu_long_quaternion': ('imu', imu((0, 0, 0, 1.01)),
                            'non_unit_quaternion', 'norm 1.01'),
    'orientation_inf': ('orientation', quaternion_stamped((0, 0, 0, math.inf)),
                        'non_finite', 'quaternion.w is inf'),
    'orientation_zero_quaternion': ('orientation', quaternion_stamped((0, 0, 0, 0)),
                                    'zero_quaternion', 'quaternion is the zero quaternion'),
    'orientation_far_from_unit': ('orientation', quaternion_stamped((3, 0, 0, 4)),
                                  'non_unit_quaternion', 'norm 5'),
}
GOOD_INPUTS = {
    'pose': pose_stamped((0, 0, 0.6, 0.8), (1, 0, 0)),
    'transform': transform_stamped((0, 0, 0.6, 0.8), (1, 0, 0)),
    'euler': euler_stamped((1.0, 0.0, 0.0)),
    'pose_with_covariance': pose_with_covariance((0, 0.6, 0, 0.8), (0, 0, 1)),
    'odometry': odometry((0.6, 0, 0, 0.8), (0, 1, 0)),
    'imu': imu((0, 0, math.sqrt(0.5), math.sqrt(0.5))),
    'orientation': quaternion_stamped((0.5, 0.5, 0.5, 0.5)),
}
"""A message of each kind that has outputs, screw axis and Rodrigues vector included."""


@pytest.mark.parametrize('case', BAD_INPUTS)
def test_bad_input_is_refused(rig, case):
    kind, bad, reason, why = BAD_INPUTS[case]
    rig.send(kind, bad)
    # The next good message on the same topic is processed after the bad one.
    stamp = rig.send(kind, GOOD_INPUTS[kind])
    rig.outputs(stamp)
    for name in ALWAYS + ('screw_axis',):
        assert len(rig.received(name)) == 1, f'{name} published for refused input'
    refused = rig.report()['refused']
    assert refused['total'] == 1
    assert refused[reason] == 1
    assert set(refused) == {'total', *REFUSAL_REASONS}
    rig.tester.spin_until(lambda: rig.node_logs(Log.WARN), what='the warning on /rosout')
    (warning,) = rig.node_logs(Log.WARN)
    assert why in warning.msg and reason in warning.msg and rig.topic(kind) in warning.msg


@pytest.mark.parametrize('damage', [
    lambda data: data[:40], lambda data: b'\x00\x07' + data[2:],
    lambda data: data[:12] + b'\xff' + data[13:],
], ids=['truncated', 'xcdr2', 'frame_id_length'])
def test_bytes_that_are_not_the_message_never_reach_the_node(rig, damage):
    # rclpy cannot make a PoseStamped of them: nothing refused, nothing logged, the next served.
    rig.pubs['pose'].publish(damage(serialize_message(GOOD_INPUTS['pose'])))
    rig.outputs(rig.send('pose', GOOD_INPUTS['pose']))
    assert rig.report()['refused']['total'] == 0
    assert rig.node_logs(Log.WARN) == rig.node_logs(Log.ERROR) == []


def test_huge_finite_euler_angles_are_accepted(rig):
    angles = (1e300, -1e299, 123456789.0)
    out = rig.roundtrip('euler', euler_stamped(angles))
    check_outputs(out, out['screw'].header.stamp.sec, 'map', euler_to_matrix(angles),
                  np.zeros(3))


def test_burst_of_bad_input_throttles_warnings_and_keeps_serving(rig):
    bad = {'pose': 'pose_nan_position', 'euler': 'euler_nan',
           'transform': 'transform_nan_translation',
           'pose_with_covariance': 'pose_with_covariance_zero_quaternion',
           'odometry': 'odometry_short_quaternion', 'imu': 'imu_no_orientation',
           'orientation': 'orientation_far_from_unit'}
    begin = time.monotonic()
    for _ in range(8):
        for kind, case in bad.items():
            rig.send(kind, BAD_INPUTS[case][1])
    for kind, good in GOOD_INPUTS.items():
        rig.roundtrip(kind, good)
    elapsed = time.monotonic() - begin
    refused = rig.report()['refused']
    # Best-effort inputs: a burst may lose samples on the way, never gain any.
    reasons = {BAD_INPUTS[case][2] for case in bad.values()}
    assert 0 < refused['total'] == sum(refused[r] for r in reasons) <= 8 * len(bad)
    rig.tester.spin_until(lambda: rig.node_logs(Log.WARN), what='a warning')
    # Throttled to one warning per second for each topic and reason.
    warnings = [log.msg.partition(':')[0] for log in rig.node_logs(Log.WARN)]
    for key in set(warnings):
        assert warnings.count(key) <= 1 + elapsed, key


def test_refusal_warnings_are_throttled_per_topic_and_reason(rig):
    """A fast stream of bad IMU messages does not silence a slow bad odometry stream."""
    bad_imu = imu((0, 0, 0, 1), orientation_covariance0=-1.0)
    bad_odometry = odometry((0, 0, 0, 1), (math.nan, 0, 0))
    imu_warning = f"refused input on {rig.topic('imu')} (no_orientation): "
    odometry_warning = (f"refused input on {rig.topic('odometry')} (non_finite): "
                        'pose.pose.position.x is nan')

    def warnings(text):
        return [log for log in rig.node_logs(Log.WARN) if log.msg.startswith(text)]

    begin = time.monotonic()
    end = math.inf
    sent = 0
    while time.monotonic() < end:  # the IMU at 50 Hz, until 1.5 s after its first warning
        rig.send('imu', bad_imu)
        sent += 1
        if sent == 5:
            rig.tester.spin_until(lambda: warnings(imu_warning), what="the IMU's warning")
            end = time.monotonic() + 1.5
            for _ in range(3):  # within the IMU's throttled second
                rig.send('odometry', bad_odometry)
        rig.tester.spin_for(0.02)
    rig.tester.spin_until(lambda: warnings(odometry_warning), what="the odometry's warning")
    elapsed = time.monotonic() - begin
    rig.tester.spin_for(0.2)
    assert len(warnings(odometry_warning)) == 1  # three refused in one second: one warning
    assert 2 <= len(warnings(imu_warning)) <= 1 + elapsed  # throttled, per second
    assert len(rig.node_logs(Log.WARN)) == len(warnings(imu_warning)) + 1
    refused = rig.report_or_note()['refused']
    assert refused['non_finite'] == 3 and 0 < refused['no_orientation'] <= sent
    assert refused['total'] == 3 + refused['no_orientation']


# ~/describe


def test_describe_before_any_input(rig):
    response = rig.describe()
    assert not response.success
    data = yaml.safe_load(response.message)
    assert list(data) == ['note', 'refused', 'last_refusals']
    assert data['note'].startswith('Nothing has been accepted yet on')
    for kind in INPUTS:
        assert rig.topic(kind) in data['note']
    assert data['note'].endswith('(0 inputs refused).')
    assert data['refused'] == {'total': 0, **dict.fromkeys(REFUSAL_REASONS, 0)}
    assert data['last_refusals'] == {}


def test_describe_before_any_accepted_input_counts_refusals(rig):
    msg = imu((0, 0, 0, 0), orientation_covariance0=-1.0)
    msg.header.stamp.nanosec = 77
    stamp = rig.send('imu', msg)
    rig.tester.spin_until(lambda: rig.node.refused_counts()['total'] == 1,
                          what='the refusal')
    response = rig.describe()
    assert not response.success
    data = yaml.safe_load(response.message)
    assert data['note'].endswith('(1 input refused).')
    assert data['refused']['total'] == data['refused']['no_orientation'] == 1
    assert data['last_refusals'] == {'no_orientation': {
        'source': rig.topic('imu'), 'stamp': {'sec': stamp, 'nanosec': 77},
        'message': 'orientation_covariance[0] is -1: the IMU gives no orientation estimate'}}


def test_the_documented_describe_before_any_accepted_input(rig):
    from doc_blocks import assert_doc_output
    msg = pose_stamped((0.0, 0.0, 0.0, 1.0 / math.sqrt(2.0)))
    msg.header.stamp.sec = 7
    rig.pubs['pose'].publish(msg)
    rig.tester.spin_until(lambda: rig.node.refused_counts()['total'] == 1, what='the refusal')
    response = rig.describe()
    assert not response.success
    # As the docs show it: the node at its default name, /rot_tools.
    assert_doc_output('node-describe-nothing-yet',
                      response.message.replace(rig.prefix + '/', '/rot_tools/'))


def test_describe_carries_the_latest_refusal_of_each_reason(rig):
    # The sentence the node logs, as data: what was wrong and by how much, per reason.
    half = 1.0 / math.sqrt(2.0)
    first = rig.send('pose', pose_stamped((0.0, 0.0, 0.0, half)))
    rig.send('pose', pose_stamped((0.0, 0.0, math.nan, 1.0)))
    latest = rig.send('orientation', quaternion_stamped((0.0, 0.0, 0.0, 0.5)))
    rig.tester.spin_until(lambda: rig.node.refused_counts()['total'] == 3, what='refusals')
    rig.roundtrip('pose', pose_stamped((0, 0, 0.6, 0.8)))
    report = rig.report()
    assert report['refused']['non_unit_quaternion'] == 2
    assert list(report)[-2:] == ['refused', 'last_refusals']
    assert report['last_refusals'] == {
        'non_finite': {'source': rig.topic('pose'), 'stamp': {'sec': first + 1, 'nanosec': 0},
                       'message': 'pose.orientation.z is nan'},
        'non_unit_quaternion': {
            'source': rig.topic('orientation'), 'stamp': {'sec': latest, 'nanosec': 0},
            'message': 'quaternion has norm 0.5, off 1 by 0.5 > quaternion_tolerance 0.001'}}


def test_describe_cuts_a_huge_refusal_sentence(rig):
    start, goal = PoseStamped(), PoseStamped()
    start.header.frame_id, goal.header.frame_id = 'a' * 100_000, 'map'
    start.pose.orientation.w = goal.pose.orientation.w = 1.0
    assert rig.screw_path(start, goal).poses == []
    (entry,) = rig.report_or_note()['last_refusals'].values()
    assert len(entry['message']) == rotation_node.MAX_REFUSAL_TEXT
    assert entry['message'].startswith("start is in frame 'aaa") and entry['message'][-1] == '…'


def assert_report_close(actual, expected):
    """Compare a parsed YAML report to transform_report's data (12 significant digits)."""
    if isinstance(expected, dict):
        assert list(actual) == list(expected)
        for key in expected:
            assert_report_close(actual[key], expected[key])
    elif isinstance(expected, list):
        assert len(actual) == len(expected)
        for a, e in zip(actual, expected):
            assert_report_close(a, e)
    elif isinstance(expected, float):
        assert actual == pytest.approx(expected, rel=1e-11, abs=1e-12)
    else:
        assert actual == expected


def test_describe_reports_the_latest_input(rig):
    rig.roundtrip('euler', euler_stamped((0.5, 0.2, 0.1)))
    q, t = POSE_CASES['general']
    msg = transform_stamped(q, t, frame='odom')
    msg.header.stamp.nanosec = 250
    out = rig.roundtrip('transform', msg)
    report = rig.report()
    assert report['source'] == rig.topic('transform')
    assert report['stamp'] == {'sec': out['screw'].header.stamp.sec, 'nanosec': 250}
    assert report['frame_id'] == 'odom'
    expected = transform_report(quaternion_to_matrix(q), t, 'ZYX', False)
    assert_report_close({k: report[k] for k in expected}, expected)
    assert list(report) == ['source', 'source_type', 'stamp', 'frame_id', *expected, 'refused',
                            'last_refusals']
    assert report['source_type'] == 'geometry_msgs/msg/TransformStamped'
    assert report['refused'] == {'total': 0, **dict.fromkeys(REFUSAL_REASONS, 0)}
    assert set(report['screw']) >= {
        'direction', 'point', 'moment', 'angle', 'translation', 'pitch'}
    assert set(report['axis_angle']) >= {'axis', 'angle', 'angle_deg'}


def test_describe_uses_the_settings_of_the_latest_input(make_rig):
    rig = make_rig(euler_sequence='zxz', angle_unit='deg')
    rig.roundtrip('euler', euler_stamped((30.0, 40.0, 50.0)))
    report = rig.report()
    R = euler_to_matrix(np.radians([30.0, 40.0, 50.0]), 'zxz')
    expected = transform_report(R, np.zeros(3), 'zxz', True)
    assert_report_close({k: report[k] for k in expected}, expected)
    assert report['euler']['unit'] == 'deg' and report['euler']['sequence'] == 'zxz'
    assert report['euler']['angles'] == pytest.approx([30.0, 40.0, 50.0], abs=1e-9)
    assert report['source'] == rig.topic('euler')


def test_describe_reports_gimbal_lock(rig):
    rig.roundtrip('euler', euler_stamped((0.3, math.pi / 2, 0.2)))
    report = rig.report()
    angles, degenerate = matrix_to_euler(euler_to_matrix((0.3, math.pi / 2, 0.2)))
    assert report['euler']['degenerate'] is True and bool(degenerate)
    assert report['euler']['angles'] == pytest.approx(angles.tolist(), rel=1e-11, abs=1e-12)
    assert report['euler']['angles'][2] == 0.0


# ~/screw_path


def path_arrays(path):
    """(positions (n, 3), quaternions (n, 4)) of a nav_msgs/Path."""
    return (np.array([xyz(p.pose.position) for p in path.poses]),
            np.array([quat(p.pose.orientation) for p in path.poses]))


def test_screw_path_default_steps(rig):
    start = pose_stamped((0, 0, 0, 1), (0, 0, 0), frame='map')
    start.header.stamp.sec = 7
    q1 = np.array([0.1, 0.7, 0.3, 0.5]) / math.sqrt(0.84)
    goal = pose_stamped(q1 * (1 + 5e-4), (2, -1, 3), frame='map')  # as given: not normalised
    path = rig.screw_path(start, goal, tolerance=0.0)
    assert len(path.poses) == 21
    assert path.header.frame_id == 'map' and path.header.stamp.sec == 7
    assert all(p.header.frame_id == 'map' for p in path.poses)
    assert path.poses[0] == start and path.poses[-1] == goal  # exactly as given
    positions, quats = path_arrays(path)
    R0, b0 = quaternion_to_matrix((0, 0, 0, 1)), np.zeros(3)
    R1, b1 = quaternion_to_matrix(q1), np.array([2.0, -1.0, 3.0])
    Rs, bs = screw_interpolate(R0, b0, R1, b1, np.linspace(0.0, 1.0, 21))
    np.testing.assert_allclose(positions[1:-1], bs[1:-1], rtol=0, atol=ATOL * 10)
    np.testing.assert_allclose(quaternion_to_matrix(quats[1:-1]), Rs[1:-1], rtol=0, atol=ATOL)
    np.testing.assert_allclose(np.linalg.norm(quats[1:-1], axis=1), 1.0, rtol=0, atol=ATOL)
    assert (np.einsum('ij,ij->i', quats[1:], quats[:-1]) > 0).all()  # no sign jumps


@pytest.mark.parametrize('tolerance', [0.05, 0.3, 2.0])
def test_screw_path_respects_tolerance(rig, tolerance):
    q0, q1 = random_quaternion(), random_quaternion()
    start = pose_stamped(q0, (1, 0, -1), frame='odom')
    goal = pose_stamped(q1, (0, 2, 1), frame='odom')
    path = rig.screw_path(start, goal, tolerance)
    positions, quats = path_arrays(path)
    quats /= np.linalg.norm(quats, axis=1)[:, None]
    R = quaternion_to_matrix(quats)
    step_angles = np.linalg.norm(matrix_to_rotvec(np.swapaxes(R[:-1], -1, -2) @ R[1:]), axis=1)
    step_lengths = np.linalg.norm(np.diff(positions, axis=0), axis=1)
    assert step_angles.max() <= tolerance * (1 + 1e-9)
    assert step_lengths.max() <= tolerance * (1 + 1e-9)
    # Not needlessly many: at most the bound of the helix the start frame's origin follows.
    R0, b0 = quaternion_to_matrix(q0), np.array([1.0, 0, -1])
    R1, b1 = quaternion_to_matrix(q1), np.array([0.0, 2, 1])
    rel = screw_from_transform(R0.T @ R1, R0.T @ (b1 - b0))
    arc = math.hypot(np.linalg.norm(rel.point) * rel.angle, rel.translation)
    n = len(path.poses) - 1
    assert n <= max(1, math.ceil(max(rel.angle, arc) / tolerance))
    Rs, bs = screw_interpolate(R0, b0, R1, b1, np.linspace(0.0, 1.0, n + 1))
    np.testing.assert_allclose(positions, bs, rtol=0, atol=10 * ATOL)
    np.testing.assert_allclose(R, Rs, rtol=0, atol=ATOL)


def test_screw_path_pure_translation_and_same_pose(rig):
    start = pose_stamped((0, 0, 0, 1), (0, 0, 0))
    goal = pose_stamped((0, 0, 0, 1), (1, 0, 0))
    path = rig.screw_path(start, goal, 0.25)
    positions, _ = path_arrays(path)
    np.testing.assert_allclose(positions[:, 0], [0, 0.25, 0.5, 0.75, 1.0], rtol=0, atol=ATOL)
    same = rig.screw_path(start, start, 0.1)
    assert same.poses == [start, start]
    assert len(rig.screw_path(start, start, -1.0).poses) == 21


SCREW_PATH_REFUSALS = {
    'frame_mismatch': (pose_stamped((0, 0, 0, 1), frame='map'),
                       pose_stamped((0, 0, 1, 0), frame='odom'), 0.0, 'frame_mismatch',
                       "start is in frame 'map', goal in 'odom'"),
    'zero_quaternion': (pose_stamped((0, 0, 0, 0)), pose_stamped((0, 0, 1, 0)), 0.0,
                        'zero_quaternion', 'start.pose.orientation is the zero quaternion'),
    'non_unit_goal': (pose_stamped((0, 0, 0, 1)), pose_stamped((0, 0, 2, 0)), 0.0,
                      'non_unit_quaternion', 'goal.pose.orientation has norm 2'),
    'inf_position': (pose_stamped((0, 0, 0, 1)), pose_stamped((0, 0, 1, 0), (0, math.inf, 0)),
                     0.0, 'non_finite', 'goal.pose.position.y is inf'),
    'nan_tolerance': (pose_stamped((0, 0, 0, 1)), pose_stamped((0, 0, 1, 0)), math.nan,
                      'bad_tolerance', 'tolerance is NaN'),
    'tiny_tolerance': (pose_stamped((0, 0, 0, 1)), pose_stamped((0, 0, 1, 0)), 1e-6,
                       'path_too_long', f'more than {MAX_PATH_STEPS}'),
}


@pytest.mark.parametrize('case', SCREW_PATH_REFUSALS)
def test_screw_path_refusals(rig, case):
    start, goal, tolerance, reason, why = SCREW_PATH_REFUSALS[case]
    path = rig.screw_path(start, goal, tolerance)
    assert path.poses == []
    rig.tester.spin_until(lambda: rig.node_logs(Log.ERROR), what='the error on /rosout')
    (error,) = rig.node_logs(Log.ERROR)
    assert why in error.msg
    # The node keeps serving; the refusal is counted.
    rig.roundtrip('pose', pose_stamped((0, 0, 0.6, 0.8)))
    refused = rig.report()['refused']
    assert refused['total'] == 1 and refused[reason] == 1


# The tables: a new output or parameter is one row


def test_a_new_parameter_is_one_row(ros_context, make_rig, namespace, monkeypatch):
    from rcl_interfaces.msg import ParameterDescriptor
    from rot_tools.ros.node.parameters import ParameterSpec
    row = ParameterSpec(
        2.0, ParameterDescriptor(type=ParameterType.PARAMETER_DOUBLE, description='a test'),
        lambda value: '' if value < 5.0 else f'test_limit {value} is not < 5')
    monkeypatch.setattr(rotation_node, 'PARAMETERS',
                        dict(rotation_node.PARAMETERS, test_limit=row))
    rig = make_rig()
    assert rig.node.get_parameter('test_limit').value == 2.0
    assert set_one(rig.node, 'test_limit', 4.5).successful
    result = set_one(rig.node, 'test_limit', 7.0)
    assert not result.successful and result.reason == 'test_limit 7.0 is not < 5'
    assert rig.node.get_parameter('test_limit').value == 4.5
    with pytest.raises(InvalidParameterValueException, match='test_limit 9.0 is not < 5'):
        RotationNode(context=ros_context, namespace=namespace,
                     parameter_overrides=[Parameter('test_limit', value=9.0)])


# Parameters


def test_parameter_descriptors(rig):
    node = rig.node
    expected = {'euler_sequence': (ParameterType.PARAMETER_STRING, 'ZYX'),
                'angle_unit': (ParameterType.PARAMETER_STRING, 'rad'),
                'quaternion_tolerance': (ParameterType.PARAMETER_DOUBLE, QUATERNION_TOLERANCE),
                'publish_markers': (ParameterType.PARAMETER_BOOL, True),
                'marker_scale': (ParameterType.PARAMETER_DOUBLE, 1.0)}
    for name, (kind, default) in expected.items():
        descriptor = node.describe_parameter(name)
        assert descriptor.type == kind and descriptor.description
        assert node.get_parameter(name).value == default
    for name, low in (('quaternion_tolerance', 0.0), ('marker_scale', 1e-6)):
        (fp_range,) = node.describe_parameter(name).floating_point_range
        assert (fp_range.from_value, fp_range.to_value) == (low, math.inf)
    assert 'zyz' in node.describe_parameter('euler_sequence').additional_constraints


def set_one(node, name, value):
    """node.set_parameters for one parameter; returns its SetParametersResult."""
    (result,) = node.set_parameters([Parameter(name, value=value)])
    return result


def test_euler_sequence_applies_from_the_next_message(rig):
    angles = (0.4, 0.3, 1.1)  # θ2 in range for Tait–Bryan and proper sequences
    before = rig.roundtrip('euler', euler_stamped(angles))
    check_outputs(before, before['screw'].header.stamp.sec, 'map',
                  euler_to_matrix(angles, 'ZYX'), np.zeros(3))
    for seq in ('xyz', 'YXY', 'zyz'):
        assert set_one(rig.node, 'euler_sequence', seq).successful
        out = rig.roundtrip('euler', euler_stamped(angles))
        R = euler_to_matrix(angles, seq)
        check_outputs(out, out['screw'].header.stamp.sec, 'map', R, np.zeros(3), seq=seq)
        np.testing.assert_allclose(xyz(out['euler_angles'].vector), angles, rtol=0, atol=ATOL)


def test_angle_unit_deg(rig):
    assert set_one(rig.node, 'angle_unit', 'deg').successful
    out = rig.roundtrip('euler', euler_stamped((30.0, -20.0, 10.0)))
    R = euler_to_matrix(np.radians([30.0, -20.0, 10.0]))
    check_outputs(out, out['screw'].header.stamp.sec, 'map', R, np.zeros(3), degrees=True)
    np.testing.assert_allclose(xyz(out['euler_angles'].vector), [30, -20, 10], atol=1e-10)
    # Only the Euler angles switch unit: the rotation vector stays in radians.
    out = rig.roundtrip('pose', pose_stamped((0, 0, 0.6, 0.8)))
    angle = 2 * math.atan2(0.6, 0.8)
    assert xyz(out['axis_angle'].vector)[2] == pytest.approx(angle, abs=ATOL)
    assert xyz(out['euler_angles'].vector)[0] == pytest.approx(math.degrees(angle), abs=1e-10)


def test_quaternion_tolerance(rig):
    q = np.array([0.0, 0.6, 0.0, 0.8]) * 1.01
    rig.send('pose', pose_stamped(q))
    rig.roundtrip('pose', pose_stamped((0, 0, 0.6, 0.8)))
    assert rig.report()['refused']['non_unit_quaternion'] == 1
    assert set_one(rig.node, 'quaternion_tolerance', 0.02).successful
    out = rig.roundtrip('pose', pose_stamped(q))
    check_outputs(out, out['screw'].header.stamp.sec, 'map', quaternion_to_matrix(q),
                  np.zeros(3))
    assert set_one(rig.node, 'quaternion_tolerance', 0.0).successful
    rig.roundtrip('pose', pose_stamped((0.0, 1.0, 0.0, 0.0)))  # |q| = 1 exactly
    rig.send('pose', pose_stamped(q))
    rig.roundtrip('pose', pose_stamped((0, 0, 0, 1)), marker=False)
    assert rig.report()['refused']['non_unit_quaternion'] == 2


def test_marker_scale(make_rig):
    rig = make_rig(marker_scale=0.25)
    q, p = POSE_CASES['general']
    out = rig.roundtrip('pose', pose_stamped(q, p))
    check_outputs(out, out['screw'].header.stamp.sec, 'map', quaternion_to_matrix(q), p,
                  scale=0.25)
    assert set_one(rig.node, 'marker_scale', 2.5).successful
    out = rig.roundtrip('pose', pose_stamped(q, p))
    check_outputs(out, out['screw'].header.stamp.sec, 'map', quaternion_to_matrix(q), p,
                  scale=2.5)


REFUSED_PARAMETERS = [  # (name, value, why)
    ('euler_sequence', 'ZZY', 'not a sequence'),
    ('euler_sequence', 'RPY', 'roll, pitch, yaw (about the fixed x, y, z axes) are the '
     "extrinsic sequence 'xyz': every report prints them as rpy, and rotation_node "
     'publishes them on ~/rpy'),
    ('euler_sequence', 'zYx', 'not a sequence'),
    ('euler_sequence', '', 'not a sequence'),
    ('euler_sequence', 3, 'Wrong parameter type'),
    ('angle_unit', 'grad', "not 'rad' or 'deg'"),
    ('angle_unit', True, 'Wrong parameter type'),
    ('quaternion_tolerance', -0.1, 'out of range'),
    ('quaternion_tolerance', math.nan, 'out of range'),
    ('quaternion_tolerance', math.inf, 'finite'),
    ('quaternion_tolerance', 'small', 'Wrong parameter type'),
    ('publish_markers', 'yes', 'Wrong parameter type'),
    ('publish_markers', 1, 'Wrong parameter type'),
    ('marker_scale', 0.0, 'out of range'),
    ('marker_scale', 5e-324, 'out of range'),
    ('marker_scale', 9.99e-7, 'out of range'),
    ('marker_scale', 0, 'out of range'),
    ('marker_scale', -2.0, 'out of range'),
    ('marker_scale', math.inf, 'finite'),
    ('marker_scale', [1.0, 2.0], 'Wrong parameter type'),
]


@pytest.mark.parametrize('name, value, why', REFUSED_PARAMETERS,
                         ids=[f'{n}={v!r}' for n, v, _ in REFUSED_PARAMETERS])
def test_invalid_parameter_is_refused(rig, name, value, why):
    before = rig.node.get_parameter(name).value
    result = set_one(rig.node, name, value)
    assert not result.successful
    assert why in result.reason
    assert rig.node.get_parameter(name).value == before
    # The old settings still apply.
    q, p = POSE_CASES['general']
    out = rig.roundtrip('pose', pose_stamped(q, p))
    check_outputs(out, out['screw'].header.stamp.sec, 'map', quaternion_to_matrix(q), p)


def test_parameters_through_the_parameter_service(rig):
    name = rig.node.get_fully_qualified_name()
    results = rig.tester.set_parameters(name, [
        Parameter('angle_unit', value='deg'),
        Parameter('marker_scale', value='long'),
        Parameter('euler_sequence', value='QQQ'),
        Parameter('marker_scale', value=3.0)])
    assert [r.successful for r in results] == [True, False, False, True]
    assert 'Wrong parameter type' in results[1].reason
    assert 'not a sequence' in results[2].reason
    assert rig.node.get_parameter('angle_unit').value == 'deg'
    assert rig.node.get_parameter('euler_sequence').value == 'ZYX'
    out = rig.roundtrip('euler', euler_stamped((90.0, 0.0, 0.0)))
    check_outputs(out, out['screw'].header.stamp.sec, 'map', euler_to_matrix((math.pi / 2, 0, 0)),
                  np.zeros(3), degrees=True, scale=3.0)


def test_parameters_it_does_not_own_are_accepted(rig):
    assert set_one(rig.node, 'use_sim_time', False).successful


@pytest.mark.parametrize('name, value', [('euler_sequence', 'abc'), ('angle_unit', 'turns'),
                                         ('marker_scale', 0.0), ('marker_scale', 5e-324),
                                         ('marker_scale', 0), ('quaternion_tolerance', -1)])
def test_invalid_override_at_start_up(ros_context, namespace, name, value):
    with pytest.raises(InvalidParameterValueException, match=name):
        RotationNode(context=ros_context, namespace=namespace,
                     parameter_overrides=[Parameter(name, value=value)])


def test_double_parameters_take_integer_values(make_rig):
    # A YAML file's `marker_scale: 3`, `-p marker_scale:=3` and `ros2 param set ... 3` are
    # integers to rclpy: the node takes them as doubles (test_node_e2e runs the file and -p).
    rig = make_rig(marker_scale=3, quaternion_tolerance=0)
    for name, value in (('marker_scale', 3.0), ('quaternion_tolerance', 0.0)):
        parameter = rig.node.get_parameter(name)
        assert (parameter.type_, parameter.value) == (Parameter.Type.DOUBLE, value)
        assert type(parameter.value) is float
    assert set_one(rig.node, 'marker_scale', 2).successful
    assert rig.node.get_parameter('marker_scale').value == 2.0
    results = rig.tester.set_parameters(rig.node.get_fully_qualified_name(), [
        Parameter('quaternion_tolerance', value=1), Parameter('marker_scale', value=4)])
    assert [r.successful for r in results] == [True, True]
    assert rig.node.get_parameter('quaternion_tolerance').get_parameter_value().double_value \
        == 1.0
    q, p = POSE_CASES['general']
    out = rig.roundtrip('pose', pose_stamped(q, p))
    check_outputs(out, out['screw'].header.stamp.sec, 'map', quaternion_to_matrix(q), p,
                  scale=4.0)
    # Only doubles: an integer is still not a string, nor a bool.
    assert not set_one(rig.node, 'euler_sequence', 3).successful
    assert not set_one(rig.node, 'publish_markers', 1).successful


@pytest.mark.parametrize('service', ['set_parameters', 'set_parameters_atomically'])
def test_a_parameter_without_a_name_is_refused(rig, service):
    from rcl_interfaces.srv import SetParameters, SetParametersAtomically
    srv_type = {'set_parameters': SetParameters,
                'set_parameters_atomically': SetParametersAtomically}[service]
    good = Parameter('angle_unit', value='deg').to_parameter_msg()
    bad = Parameter('', value=1.0).to_parameter_msg()
    why = 'a parameter name is empty'
    response = rig.call(srv_type, service, srv_type.Request(parameters=[bad, good]))
    if service == 'set_parameters':  # one by one: the good one is set
        assert [(r.successful, r.reason) for r in response.results] == [
            (False, why), (True, '')]
        assert rig.node.get_parameter('angle_unit').value == 'deg'
    else:  # all or nothing
        assert (response.result.successful, response.result.reason) == (False, why)
        assert rig.node.get_parameter('angle_unit').value == 'rad'
    assert '' not in rig.node.list_parameters([], 0).names
    (log,) = rig.node_logs(Log.ERROR)  # one line each time, no traceback
    assert log.msg == 'refused a malformed parameter request: a parameter name is empty'
    rig.roundtrip('pose', pose_stamped((0, 0, 0.6, 0.8)))  # and the node keeps serving


def test_a_megabyte_parameter_value_is_logged_and_answered_in_excerpts(rig):
    """Strings of 1 MB set by the service: the log line and refusals quote 40 characters."""
    huge = 'a' * 1_000_000
    names = ('tf_reference_frame', 'tf_body_frame', 'euler_sequence', 'angle_unit',
             'input_covariance')
    results = rig.tester.set_parameters(rig.node.get_fully_qualified_name(),
                                        [Parameter(name, value=huge) for name in names])
    assert [r.successful for r in results] == [True, True, False, False, False]
    excerpt = repr(huge)[:39] + '…'
    for name, result in zip(names[2:], results[2:]):
        assert result.reason.startswith(f'{name} {excerpt} is not '), result.reason[:100]
        assert len(result.reason) < 400
    following = f'following {excerpt} in {excerpt} on /tf'
    rig.tester.spin_until(lambda: any(log.msg == following for log in rig.node_logs()),
                          what='the log line of the frames followed')
    assert max(len(log.msg) for log in rig.node_logs()) < 1000
