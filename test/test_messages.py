"""rotation_node's reading of each input message, and its messages module (no DDS traffic)."""

import math

from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, Quaternion
from geometry_msgs.msg import QuaternionStamped, TransformStamped, Vector3Stamped
from math_helpers import unit
from nav_msgs.msg import Odometry
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rot_tools import (
    euler_to_matrix, is_rotation, quaternion_to_matrix, rot_x, rot_z, rotvec_to_matrix)
from rot_tools.io import boundary
from rot_tools.io.boundary import QUATERNION_TOLERANCE as TOL
from rot_tools.io.boundary import RefusedInput
from rot_tools.ros.node import messages
from rot_tools.ros.node.parameters import read_settings
from rot_tools.ros.node.rotation_node import RotationNode
from sensor_msgs.msg import Imu
from std_msgs.msg import Header
from visualization_msgs.msg import Marker

ATOL = 1e-12
RNG = np.random.default_rng(7)


CALLBACKS = {PoseStamped: 'on_pose', Vector3Stamped: 'on_euler', TransformStamped: 'on_transform',
             PoseWithCovarianceStamped: 'on_pose_with_covariance', Odometry: 'on_odometry',
             Imu: 'on_imu', QuaternionStamped: 'on_orientation'}
"""The node's callback of each input type."""


@pytest.fixture(scope='module')
def node(ros_context):
    """Return a RotationNode whose callbacks hand (header, R, b) or the refusal back."""
    node = RotationNode('messages_check', context=ros_context, namespace='/messages')

    def accepted(source, header, R, b, settings):
        node.taken = (header, R, np.asarray(b, dtype=float))

    def refused(topic, reason, text, header=None):
        raise RefusedInput(reason, text)

    node.publish_outputs, node._refuse = accepted, refused
    yield node
    node.destroy_node()


@pytest.fixture
def take(node):
    """Return a function of (msg, **settings) giving (header, R, b) as the node takes msg."""
    def take(msg, **settings):
        node._settings = read_settings(node)._replace(**settings)
        msg = deserialize_message(serialize_message(msg), type(msg))
        node.taken = None
        getattr(node, CALLBACKS[type(msg)])(msg)
        return node.taken
    return take


def same_header(read, msg):
    return (read.stamp.sec, read.stamp.nanosec, read.frame_id) == (
        msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id)


def quaternion_fields(q):
    return tuple(float(c) for c in q)


def quaternion(q):
    return Quaternion(x=float(q[0]), y=float(q[1]), z=float(q[2]), w=float(q[3]))


# Inbound


@pytest.mark.parametrize('q', [(0, 0, 0, 1), (1, 0, 0, 0), (0.5, 0.5, 0.5, 0.5),
                               tuple(unit(RNG.normal(size=4)))])
def test_unit_quaternion(q):
    R = boundary.quaternion_to_rotation(*quaternion_fields(q), TOL)
    np.testing.assert_allclose(R, quaternion_to_matrix(q), rtol=0, atol=ATOL)


def test_quaternion_order_is_x_y_z_w():
    half = math.sqrt(0.5)  # 90° about z: (x, y, z, w) = (0, 0, sin 45°, cos 45°)
    R = boundary.quaternion_to_rotation(*quaternion_fields((0, 0, half, half)), TOL)
    np.testing.assert_allclose(R, rot_z(math.pi / 2), rtol=0, atol=ATOL)


def test_quaternion_within_tolerance_is_normalised():
    q = unit((0.3, -0.2, 0.9, 0.1)) * (1 - 0.99e-3)
    R = boundary.quaternion_to_rotation(*quaternion_fields(q), TOL)
    assert is_rotation(R, tol=1e-15)
    np.testing.assert_allclose(R, quaternion_to_matrix(unit(q)), rtol=0, atol=ATOL)


@pytest.mark.parametrize('q, tol, reason, match', [
    ((0, 0, 0, 0), TOL, 'zero_quaternion', 'orientation is the zero quaternion'),
    ((0, 0, 0, 0), 10.0, 'zero_quaternion', 'zero quaternion'),
    ((0, 0, 0, 2), TOL, 'non_unit_quaternion', r'norm 2, off 1 by 1 > quaternion_tolerance'),
    ((0, 0, 0, 1.0011), TOL, 'non_unit_quaternion', 'off 1 by 0.0011'),
    ((0, 0.5, 0, 0), 0.4, 'non_unit_quaternion', 'norm 0.5'),
    ((1e300, -1e300, 1e300, 1e300), TOL, 'non_unit_quaternion', r'norm 2e\+300'),
    ((math.nan, 0, 0, 1), TOL, 'non_finite', r'orientation\.x is nan'),
    ((0, 0, 0, math.inf), TOL, 'non_finite', r'orientation\.w is inf'),
    ((0, -math.inf, 0, 1), 1e3, 'non_finite', r'orientation\.y is -inf'),
])
def test_bad_quaternion_is_refused(q, tol, reason, match):
    with pytest.raises(RefusedInput, match=match) as info:
        boundary.quaternion_to_rotation(*quaternion_fields(q), tol)
    assert info.value.reason == reason
    assert reason in boundary.REFUSAL_REASONS


def test_zero_tolerance_accepts_an_exactly_unit_quaternion():
    R = boundary.quaternion_to_rotation(*quaternion_fields((0, 1, 0, 0)), 0.0)
    np.testing.assert_allclose(R, np.diag([-1.0, 1.0, -1.0]), rtol=0, atol=0)


def test_pose_stamped(take):
    msg = PoseStamped()
    msg.header.frame_id = 'map'
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = 1.0, -2.0, 3.5
    msg.pose.orientation = quaternion(unit((1, 2, 3, 4)))
    header, R, b = take(msg)
    assert same_header(header, msg)
    np.testing.assert_allclose(R, quaternion_to_matrix((1, 2, 3, 4)), rtol=0, atol=ATOL)
    assert b.tolist() == [1.0, -2.0, 3.5]


def test_transform_stamped(take):
    msg = TransformStamped()
    msg.header.frame_id = 'world'
    msg.transform.translation.x = 4.0
    msg.transform.rotation = quaternion((1, 0, 0, 0))
    header, R, b = take(msg)
    assert same_header(header, msg)
    np.testing.assert_allclose(R, rot_x(math.pi), rtol=0, atol=ATOL)
    assert b.tolist() == [4.0, 0.0, 0.0]


@pytest.mark.parametrize('seq', ['ZYX', 'xyz', 'ZXZ', 'yxy'])
@pytest.mark.parametrize('degrees', [False, True])
def test_euler_stamped(seq, degrees, take):
    angles = np.array([0.7, 0.4, -1.3])
    msg = Vector3Stamped()
    given = np.degrees(angles) if degrees else angles
    msg.vector.x, msg.vector.y, msg.vector.z = map(float, given)
    header, R, b = take(msg, euler_sequence=seq, degrees=degrees)
    assert same_header(header, msg)
    np.testing.assert_allclose(R, euler_to_matrix(angles, seq), rtol=0, atol=ATOL)
    assert b.tolist() == [0.0, 0.0, 0.0]


def test_pose_with_covariance_stamped_ignores_the_covariance(take):
    msg = PoseWithCovarianceStamped()
    msg.header.frame_id = 'map'
    msg.pose.pose.position.y = -1.5
    msg.pose.pose.orientation = quaternion((0, 1, 0, 0))
    msg.pose.covariance = [math.nan] * 36
    header, R, b = take(msg)
    assert same_header(header, msg)
    np.testing.assert_allclose(R, np.diag([-1.0, 1.0, -1.0]), rtol=0, atol=0)
    assert b.tolist() == [0.0, -1.5, 0.0]
    msg.pose.pose.orientation.w = 2.0
    with pytest.raises(RefusedInput, match=r'pose\.pose\.orientation has norm 2\.23606') as info:
        take(msg)
    assert info.value.reason == 'non_unit_quaternion'


def test_odometry_is_its_pose_and_ignores_the_twist(take):
    msg = Odometry()
    msg.header.frame_id, msg.child_frame_id = 'odom', 'base_link'
    msg.pose.pose.position.x = 3.0
    msg.pose.pose.orientation = quaternion((0, 0, math.sin(0.25), math.cos(0.25)))
    msg.twist.twist.angular.z = math.nan
    header, R, b = take(msg)
    assert same_header(header, msg)
    np.testing.assert_allclose(R, rot_z(0.5), rtol=0, atol=ATOL)
    assert b.tolist() == [3.0, 0.0, 0.0]
    msg.pose.pose.position.z = math.inf
    with pytest.raises(RefusedInput, match=r'pose\.pose\.position\.z is inf'):
        take(msg)


def test_imu_orientation(take):
    msg = Imu()
    msg.orientation = quaternion((math.sin(0.5), 0, 0, math.cos(0.5)))
    msg.linear_acceleration.x = math.inf  # not used
    header, R, b = take(msg)
    assert same_header(header, msg)
    np.testing.assert_allclose(R, rot_x(1.0), rtol=0, atol=ATOL)
    assert b.tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize('q', [(0, 0, 0, 0), (0, 0, 0, 1), (math.nan, 0, 0, 0)])
def test_imu_without_orientation_is_refused(q, take):
    msg = Imu()
    msg.orientation = quaternion(q)
    msg.orientation_covariance[0] = -1.0
    with pytest.raises(RefusedInput, match=r'orientation_covariance\[0\] is -1') as info:
        take(msg)
    assert info.value.reason == 'no_orientation'
    assert 'no_orientation' in boundary.REFUSAL_REASONS


def test_imu_with_a_covariance_is_used(take):
    msg = Imu()
    msg.orientation = quaternion((0, 0, 0, 1))
    msg.orientation_covariance = [0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01]
    np.testing.assert_array_equal(take(msg)[1], np.eye(3))
    msg.orientation.w = 0.0
    with pytest.raises(RefusedInput, match='orientation is the zero quaternion'):
        take(msg)


def test_quaternion_stamped(take):
    msg = QuaternionStamped()
    msg.quaternion = quaternion(np.array([0.0, 0.0, 1.0, 1.0]) * math.sqrt(0.5) * (1 + 5e-4))
    header, R, b = take(msg)
    assert same_header(header, msg)
    np.testing.assert_allclose(R, rot_z(math.pi / 2), rtol=0, atol=ATOL)
    assert b.tolist() == [0.0, 0.0, 0.0]
    with pytest.raises(RefusedInput, match='quaternion has norm') as info:
        take(msg, quaternion_tolerance=1e-4)
    assert info.value.reason == 'non_unit_quaternion'


# Outbound


def test_screw_axis_marker():
    header = Header(frame_id='map')
    m = messages.screw_axis_marker(header, np.array([1.0, 2.0, 0.0]),
                                   np.array([0.0, 0.6, 0.8]), 2.0)
    m = deserialize_message(serialize_message(m), Marker)
    assert m.header == header
    assert (m.type, m.action, m.id) == (Marker.ARROW, Marker.ADD, 0)
    assert [(p.x, p.y, p.z) for p in m.points] == [(1.0, 2.0, 0.0), (1.0, 3.2, 1.6)]
    o = m.pose.orientation
    assert (o.x, o.y, o.z, o.w) == (0.0, 0.0, 0.0, 1.0)
    assert (m.scale.x, m.scale.y, m.scale.z) == (0.1, 0.2, 0.4) and m.color.a == 1.0


def test_matrices_to_quaternions_round_trip_and_continuity():
    # A full turn about one axis in small steps passes θ = π, where the axis-angle sign of
    # the half-angle formula flips; the quaternions must stay continuous.
    axis = unit((1.0, -2.0, 0.5))
    angles = np.linspace(0.0, 2 * math.pi, 73)
    R = rotvec_to_matrix(axis * angles[:, None])
    q = messages.matrices_to_quaternions(R)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, rtol=0, atol=ATOL)
    np.testing.assert_allclose(quaternion_to_matrix(q), R, rtol=0, atol=ATOL)
    assert (np.einsum('ij,ij->i', q[1:], q[:-1]) > 0).all()
    # Signed to follow the given first quaternion.
    q = messages.matrices_to_quaternions(R[:3], first=np.array([0.0, 0.0, 0.0, -1.0]))
    assert q[0][3] < 0


def test_random_rotations_to_quaternions():
    q = RNG.normal(size=(1000, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    R = quaternion_to_matrix(q)
    np.testing.assert_allclose(quaternion_to_matrix(messages.matrices_to_quaternions(R)), R,
                               rtol=0, atol=ATOL)


def test_path_msg_keeps_start_and_goal_as_given():
    header = Header(frame_id='map')
    start, goal = PoseStamped(header=header), PoseStamped(header=header)
    goal.pose.orientation = quaternion((0, 0, 1.0005, 0))
    R = rotvec_to_matrix(np.array([[0, 0, 0], [0, 0, math.pi / 2], [0, 0, math.pi]]))
    b = np.array([[0, 0, 0], [0.5, 0, 0], [1, 0, 0]], dtype=float)
    path = messages.path_msg(header, start, goal, R, b)
    assert path.header is header
    assert path.poses[0] is start and path.poses[-1] is goal
    middle = path.poses[1].pose
    assert (middle.position.x, middle.position.y, middle.position.z) == (0.5, 0.0, 0.0)
    o = middle.orientation
    np.testing.assert_allclose([o.x, o.y, o.z, o.w], [0, 0, math.sqrt(0.5), math.sqrt(0.5)],
                               rtol=0, atol=ATOL)
    assert messages.path_msg(header, start, goal, R[[0, 2]], b[[0, 2]]).poses == [start, goal]
