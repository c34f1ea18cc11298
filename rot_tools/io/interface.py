"""
rotation_node's interface: every input and output by name, message type and help text.

The table people read: the node's ``--help``, ``rotation_client`` (a verb per input, named as
the input; ``echo`` and its answers by output name) and the docs list these rows. What the
node reads from each message and writes into each output is plain code in rotation_node.
Message types are names ('geometry_msgs/msg/PoseStamped'): this module imports no ROS.
"""

from typing import NamedTuple


class Topic(NamedTuple):
    """One input or output of the node: ``~/name``, its message type and its help."""

    name: str
    """The topic's name under the node (``~/name``), rotation_client's verb (an input) or
    the name it prints an answer under (an output)."""
    type_name: str
    help: str  # noqa: A003

    @property
    def topic(self):
        """Return '~/name'."""
        return '~/' + self.name


INPUTS = (
    Topic('pose', 'geometry_msgs/msg/PoseStamped',
          "a body's orientation and position in header.frame_id"),
    Topic('euler', 'geometry_msgs/msg/Vector3Stamped',
          'x, y, z = θ1, θ2, θ3 of euler_sequence, in angle_unit (b = 0)'),
    Topic('transform', 'geometry_msgs/msg/TransformStamped',
          'rotation and translation of child_frame_id in header.frame_id'),
    Topic('pose_with_covariance', 'geometry_msgs/msg/PoseWithCovarianceStamped',
          'pose.pose, and pose.covariance'),
    Topic('odometry', 'nav_msgs/msg/Odometry',
          'pose.pose: the body child_frame_id in header.frame_id, and pose.covariance (the '
          'twist is not used)'),
    Topic('imu', 'sensor_msgs/msg/Imu',
          'orientation (b = 0) and orientation_covariance; refused when '
          'orientation_covariance[0] is -1 (no estimate)'),
    Topic('orientation', 'geometry_msgs/msg/QuaternionStamped', 'quaternion (b = 0)'),
)
"""Every input of the node; each becomes one rigid motion (header, R, b)."""

OUTPUTS = (
    Topic('rotation_matrix', 'std_msgs/msg/Float64MultiArray',
          'R, 9 values row-major (the type has no header)'),
    Topic('quaternion', 'geometry_msgs/msg/QuaternionStamped',
          'R as (x, y, z, w), the canonical sign of matrix_to_quaternion'),
    Topic('axis_angle', 'geometry_msgs/msg/Vector3Stamped',
          'rotation vector θ·l̂ (rad; its norm is the angle)'),
    Topic('rodrigues', 'geometry_msgs/msg/Vector3Stamped',
          'Rodrigues (Gibbs) vector tan(θ/2)·l̂; none at θ = π, where it is infinite'),
    Topic('euler_angles', 'geometry_msgs/msg/Vector3Stamped',
          'θ1, θ2, θ3 of euler_sequence, in angle_unit'),
    Topic('rpy', 'geometry_msgs/msg/Vector3Stamped',
          'roll, pitch, yaw (REP 103: about the fixed x, y, z axes), in angle_unit'),
    Topic('screw', 'geometry_msgs/msg/TwistStamped',
          'exponential coordinates: angular = θ·l̂, linear = θ·v (screw_log)'),
    Topic('rpy_covariance', 'geometry_msgs/msg/PoseWithCovarianceStamped',
          'for an input with a known covariance (~/imu, ~/pose_with_covariance, ~/odometry): '
          'its pose, and the covariance of x, y, z, roll, pitch, yaw (rad², whatever '
          'angle_unit; read as input_covariance says), none at gimbal lock'),
    Topic('screw_axis', 'visualization_msgs/msg/Marker',
          'when publish_markers: the screw axis, an ARROW (DELETE for the identity)'),
    Topic('markers', 'visualization_msgs/msg/MarkerArray',
          "when publish_markers: the moved frame's axes, the screw axis, the helical path "
          'and a label'),
)
"""Every output of the node, in the order it publishes them."""


def input_named(name):
    """Return the input row ``name`` (KeyError if none)."""
    return {row.name: row for row in INPUTS}[name]


def output_named(name):
    """Return the output row ``name`` (KeyError if none)."""
    return {row.name: row for row in OUTPUTS}[name]
