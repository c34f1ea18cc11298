"""
rotation_node's job on ~/pose written the usual way: message objects, scipy per message.

What an engineer would write without rot_tools, the way ros2/demos write a node: it
subscribes ``~/pose`` (geometry_msgs/PoseStamped, with rotation_node's input QoS), refuses a
pose whose numbers are not finite or whose quaternion is off unit by more than the
tolerance, and for every other one builds scipy's ``Rotation`` and publishes fresh message
objects (reliable, depth 10) on rotation_node's topics:

- ``~/rotation_matrix`` (Float64MultiArray, row-major, rows/cols layout): ``as_matrix()``;
- ``~/quaternion`` (QuaternionStamped): ``as_quat(canonical=True)``;
- ``~/axis_angle`` (Vector3Stamped): ``as_rotvec()``;
- ``~/rodrigues`` (Vector3Stamped): tan(θ/2)·l̂ from the quaternion (x, y, z)/w, none at w = 0;
- ``~/euler_angles`` (Vector3Stamped): ``as_euler(euler_sequence)`` in ``angle_unit``;
- ``~/rpy`` (Vector3Stamped): roll, pitch, yaw, ``as_euler`` of REP 103's sequence;
- ``~/screw`` (TwistStamped): the exponential coordinates of (R, b), angular = θ·l̂ (the
  rotation vector), linear = V⁻¹·b with V⁻¹ = I − ½[ω]× + (1 − (θ/2)·cot(θ/2))/θ²·[ω]×²
  (the SE(3) logarithm of Lynch and Park's Modern Robotics).

Parameters ``euler_sequence`` (default ZYX) and ``angle_unit`` (rad | deg) are read once at
start. rclpy.init, rclpy.spin (a SingleThreadedExecutor) and the shutdown idiom of Jazzy:
SIGINT / SIGTERM end it. bench_node.py measures rotation_node against it.

Run: ``.venv/bin/python bench/usual_node.py [--ros-args -r __node:=NAME]`` (default name
``usual``).
"""

import math
import sys

from geometry_msgs.msg import PoseStamped, QuaternionStamped, TwistStamped, Vector3Stamped
import numpy as np
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.ros.node.rotation_node import INPUT_QOS  # the same QoS as the node's inputs
from scipy.spatial.transform import Rotation
from std_msgs.msg import Float64MultiArray, MultiArrayDimension


def screw_linear(rotvec, b):
    """Return θ·v, the linear part of the SE(3) logarithm of (R, b), R = exp([rotvec]×)."""
    theta = np.linalg.norm(rotvec)
    if theta < 1e-9:
        return b
    w_x_b = np.cross(rotvec, b)
    k = (1.0 - 0.5 * theta / math.tan(0.5 * theta)) / theta ** 2
    return b - 0.5 * w_x_b + k * np.cross(rotvec, w_x_b)


class UsualNode(Node):
    """Pose in, rotation_node's six per-input outputs out, computed with scipy."""

    def __init__(self, node_name='usual'):
        super().__init__(node_name)
        self.sequence = self.declare_parameter('euler_sequence', 'ZYX').value
        self.degrees = self.declare_parameter('angle_unit', 'rad').value == 'deg'
        qos = QoSProfile(depth=10)
        self.matrix_pub = self.create_publisher(Float64MultiArray, '~/rotation_matrix', qos)
        self.quaternion_pub = self.create_publisher(QuaternionStamped, '~/quaternion', qos)
        self.axis_angle_pub = self.create_publisher(Vector3Stamped, '~/axis_angle', qos)
        self.rodrigues_pub = self.create_publisher(Vector3Stamped, '~/rodrigues', qos)
        self.euler_pub = self.create_publisher(Vector3Stamped, '~/euler_angles', qos)
        self.rpy_pub = self.create_publisher(Vector3Stamped, '~/rpy', qos)
        self.screw_pub = self.create_publisher(TwistStamped, '~/screw', qos)
        self.pose_sub = self.create_subscription(PoseStamped, '~/pose', self.on_pose,
                                                 INPUT_QOS)

    def on_pose(self, msg):
        p, o = msg.pose.position, msg.pose.orientation
        q = np.array([o.x, o.y, o.z, o.w])
        b = np.array([p.x, p.y, p.z])
        if not (np.isfinite(q).all() and np.isfinite(b).all()):
            self.get_logger().warning('pose refused: not finite', throttle_duration_sec=1.0)
            return
        if abs(np.linalg.norm(q) - 1.0) > QUATERNION_TOLERANCE:
            self.get_logger().warning('pose refused: quaternion not unit',
                                      throttle_duration_sec=1.0)
            return
        rotation = Rotation.from_quat(q)
        rotvec = rotation.as_rotvec()
        header = msg.header

        matrix = Float64MultiArray(data=rotation.as_matrix().ravel().tolist())
        matrix.layout.dim = [MultiArrayDimension(label='rows', size=3, stride=9),
                             MultiArrayDimension(label='cols', size=3, stride=3)]
        self.matrix_pub.publish(matrix)

        quaternion = QuaternionStamped(header=header)
        x, y, z, w = rotation.as_quat(canonical=True).tolist()
        quaternion.quaternion.x, quaternion.quaternion.y = x, y
        quaternion.quaternion.z, quaternion.quaternion.w = z, w
        self.quaternion_pub.publish(quaternion)

        self.axis_angle_pub.publish(vector3_stamped(header, rotvec))
        if w != 0.0:
            self.rodrigues_pub.publish(vector3_stamped(header, (x / w, y / w, z / w)))
        self.euler_pub.publish(vector3_stamped(
            header, rotation.as_euler(self.sequence, degrees=self.degrees)))
        self.rpy_pub.publish(vector3_stamped(
            header, rotation.as_euler(RPY_SEQUENCE, degrees=self.degrees)))

        screw = TwistStamped(header=header)
        set_xyz(screw.twist.angular, rotvec)
        set_xyz(screw.twist.linear, screw_linear(rotvec, b))
        self.screw_pub.publish(screw)


def set_xyz(vector, values):
    vector.x, vector.y, vector.z = (float(v) for v in values)


def vector3_stamped(header, values):
    msg = Vector3Stamped(header=header)
    set_xyz(msg.vector, values)
    return msg


def main(args=None):
    rclpy.init(args=args)
    node = None
    try:
        node = UsualNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
