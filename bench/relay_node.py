"""
A bare rclpy relay: rotation_node's per-input topics and QoS, constant content, no math.

The ceiling of rclpy's own messaging on this machine, the second baseline of bench_node.py.
It subscribes ``~/pose`` (geometry_msgs/PoseStamped, with rotation_node's input QoS) and,
for every message, publishes the six outputs usual_node.py and rotation_node publish
(reliable, depth 10): ``~/rotation_matrix`` (Float64MultiArray), ``~/quaternion``
(QuaternionStamped), ``~/axis_angle``, ``~/euler_angles`` and ``~/rpy`` (Vector3Stamped)
and ``~/screw`` (TwistStamped). The messages are made once at start-up; each callback only
puts the input's header into the stamped ones and publishes them. A plain message-object
node, as usual_node.py, started and ended the same way.

Run: ``.venv/bin/python bench/relay_node.py [--ros-args -r __node:=NAME]`` (default name
``relay``); SIGINT / SIGTERM end it.
"""

import sys

from geometry_msgs.msg import PoseStamped, QuaternionStamped, TwistStamped, Vector3
from geometry_msgs.msg import Vector3Stamped
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rot_tools.ros.node.rotation_node import INPUT_QOS  # the same QoS as the node's inputs
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, MultiArrayLayout


class RelayNode(Node):
    """Pose in, the six per-input outputs out, their content made once."""

    def __init__(self, node_name='relay'):
        super().__init__(node_name)
        qos = QoSProfile(depth=10)
        self.matrix_pub = self.create_publisher(Float64MultiArray, '~/rotation_matrix', qos)
        self.quaternion_pub = self.create_publisher(QuaternionStamped, '~/quaternion', qos)
        self.axis_angle_pub = self.create_publisher(Vector3Stamped, '~/axis_angle', qos)
        self.euler_pub = self.create_publisher(Vector3Stamped, '~/euler_angles', qos)
        self.rpy_pub = self.create_publisher(Vector3Stamped, '~/rpy', qos)
        self.screw_pub = self.create_publisher(TwistStamped, '~/screw', qos)
        self.pose_sub = self.create_subscription(PoseStamped, '~/pose', self.on_pose,
                                                 INPUT_QOS)

        self.matrix = Float64MultiArray(
            layout=MultiArrayLayout(
                dim=[MultiArrayDimension(label='rows', size=3, stride=9),
                     MultiArrayDimension(label='cols', size=3, stride=3)],
                data_offset=0),
            data=[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
        self.quaternion = QuaternionStamped()
        self.quaternion.quaternion.z, self.quaternion.quaternion.w = 0.6, 0.8
        self.axis_angle = Vector3Stamped(vector=Vector3(x=0.1, y=0.2, z=0.3))
        self.euler = Vector3Stamped(vector=Vector3(x=0.3, y=0.2, z=0.1))
        self.rpy = Vector3Stamped(vector=Vector3(x=0.1, y=0.2, z=0.3))
        self.screw = TwistStamped()
        self.screw.twist.angular = Vector3(x=0.1, y=0.2, z=0.3)
        self.screw.twist.linear = Vector3(x=1.0, y=2.0, z=3.0)

    def on_pose(self, msg):
        header = msg.header
        self.quaternion.header = header
        self.axis_angle.header = header
        self.euler.header = header
        self.rpy.header = header
        self.screw.header = header
        self.matrix_pub.publish(self.matrix)
        self.quaternion_pub.publish(self.quaternion)
        self.axis_angle_pub.publish(self.axis_angle)
        self.euler_pub.publish(self.euler)
        self.rpy_pub.publish(self.rpy)
        self.screw_pub.publish(self.screw)


def main(args=None):
    rclpy.init(args=args)
    node = None
    try:
        node = RelayNode()
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
