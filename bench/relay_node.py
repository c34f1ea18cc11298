"""A bare rclpy relay: rotation_node's topics and QoS with constant content and no math.

It subscribes ``~/pose`` (geometry_msgs/PoseStamped, sensor-data QoS: best effort) and, for
every message, publishes the same five outputs as rotation_node (reliable, depth 10):
``~/rotation_matrix`` (Float64MultiArray), ``~/axis_angle`` and ``~/euler_angles``
(Vector3Stamped), ``~/screw`` (TwistStamped) and ``~/screw_axis`` (Marker). Their content is
built once at start-up; each callback only copies the input's header into the stamped ones.
So its throughput and latency are rclpy's own messaging limit on this machine, the baseline
bench_node.py measures rotation_node against.

With ``--full-interface`` it also creates rotation_node's other subscriptions (``~/euler``,
``~/transform``) and services (``~/describe``, ``~/screw_path``), idle: the same entities
for the executor to wait on, still no math.

Run: ``.venv/bin/python bench/relay_node.py [--full-interface] [--ros-args -r __node:=NAME]``
(default node name ``relay``); SIGINT / SIGTERM end it.
"""

import sys

from geometry_msgs.msg import Point, PoseStamped, TransformStamped, TwistStamped, Vector3
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.srv import GetPlan
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data, QoSProfile
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, MultiArrayLayout
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker


class RelayNode(Node):
    """Pose in, rotation_node's five outputs out, with precomputed content."""

    def __init__(self, node_name='relay', full_interface=False):
        super().__init__(node_name)
        if full_interface:
            # rotation_node's other entities, idle here: two more subscriptions and two
            # services. rclpy's wait-set executors pay per entity on every wake-up, so this
            # variant separates that cost from the math's.
            self._idle = [
                self.create_subscription(Vector3Stamped, '~/euler', lambda m: None,
                                         qos_profile_sensor_data),
                self.create_subscription(TransformStamped, '~/transform', lambda m: None,
                                         qos_profile_sensor_data),
                self.create_service(Trigger, '~/describe', lambda req, res: res),
                self.create_service(GetPlan, '~/screw_path', lambda req, res: res)]
        qos = QoSProfile(depth=10)
        self._matrix_pub = self.create_publisher(Float64MultiArray, '~/rotation_matrix', qos)
        self._axis_angle_pub = self.create_publisher(Vector3Stamped, '~/axis_angle', qos)
        self._euler_pub = self.create_publisher(Vector3Stamped, '~/euler_angles', qos)
        self._screw_pub = self.create_publisher(TwistStamped, '~/screw', qos)
        self._marker_pub = self.create_publisher(Marker, '~/screw_axis', qos)
        self._pose_sub = self.create_subscription(
            PoseStamped, '~/pose', self._on_pose, qos_profile_sensor_data)

        self._matrix = Float64MultiArray(
            layout=MultiArrayLayout(
                dim=[MultiArrayDimension(label='rows', size=3, stride=9),
                     MultiArrayDimension(label='cols', size=3, stride=3)],
                data_offset=0),
            data=[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
        self._axis_angle = Vector3Stamped(vector=Vector3(x=0.1, y=0.2, z=0.3))
        self._euler = Vector3Stamped(vector=Vector3(x=0.3, y=0.2, z=0.1))
        self._screw = TwistStamped()
        self._screw.twist.angular = Vector3(x=0.1, y=0.2, z=0.3)
        self._screw.twist.linear = Vector3(x=1.0, y=2.0, z=3.0)
        self._marker = Marker(ns='screw_axis', id=0, type=Marker.ARROW, action=Marker.ADD,
                              points=[Point(x=0.0, y=0.0, z=0.0), Point(x=0.0, y=0.0, z=1.0)],
                              scale=Vector3(x=0.05, y=0.1, z=0.2))
        self._marker.pose.orientation.w = 1.0
        self._marker.color.r, self._marker.color.g, self._marker.color.a = 1.0, 0.5, 1.0

    def _on_pose(self, msg):
        header = msg.header
        self._axis_angle.header = header
        self._euler.header = header
        self._screw.header = header
        self._marker.header = header
        self._matrix_pub.publish(self._matrix)
        self._axis_angle_pub.publish(self._axis_angle)
        self._euler_pub.publish(self._euler)
        self._screw_pub.publish(self._screw)
        self._marker_pub.publish(self._marker)


def main(args=None):
    """Spin until SIGINT / SIGTERM (exit 0), like rotation_node."""
    args = sys.argv if args is None else args
    full = '--full-interface' in args
    rclpy.init(args=[a for a in args if a != '--full-interface'])  # SIGINT/SIGTERM: shutdown
    node = None
    try:
        node = RelayNode(full_interface=full)
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
