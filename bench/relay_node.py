"""
A bare rclpy relay: rotation_node's topics and QoS with constant content and no math.

It subscribes ``~/pose`` (geometry_msgs/PoseStamped, rotation_node's INPUT_QOS) and, for
every message, publishes rotation_node's six message outputs (reliable, depth 10):
``~/rotation_matrix`` (Float64MultiArray), ``~/quaternion`` (QuaternionStamped),
``~/axis_angle``, ``~/euler_angles`` and ``~/rpy`` (Vector3Stamped) and ``~/screw``
(TwistStamped).
Their content is built once at start-up; each callback only copies the input's header into
the stamped ones. So its throughput and latency are rclpy's own messaging limit on this
machine, the baseline bench_node.py measures rotation_node against.

``--executor default`` spins it on rclpy's SingleThreadedExecutor (the executor
rotation_node runs on); ``--executor events`` on rclpy's EventsExecutor. Either way the
relay is started and stopped as rotation_node's console script runs the node: the node's
own loop (serve), and the same exit. ``--full-interface`` also creates rotation_node's
other input subscriptions and its two services, idle: the same entities for the executor
to watch, still no math.

Run: ``.venv/bin/python bench/relay_node.py [--executor default|events] [--full-interface]
[--ros-args -r __node:=NAME]`` (default node name ``relay``); SIGINT / SIGTERM end it.
"""

import argparse
import sys

from geometry_msgs.msg import PoseStamped, QuaternionStamped, TwistStamped, Vector3
from geometry_msgs.msg import Vector3Stamped
from nav_msgs.srv import GetPlan
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile
from rot_tools.ros import runtime
from rot_tools.ros.rotation_node import INPUT_QOS, INPUTS
from rot_tools.ros.runtime import serve
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, MultiArrayLayout
from std_srvs.srv import Trigger


class RelayNode(Node):
    """Pose in, rotation_node's six message outputs out, with precomputed content."""

    def __init__(self, node_name='relay', full_interface=False):
        super().__init__(node_name)
        if full_interface:
            # rotation_node's other entities, idle here. rclpy's executor pays per
            # entity on every wake-up, so this variant separates that cost from the math's.
            self._idle = [self.create_subscription(kind.msg_type, kind.topic, lambda m: None,
                                                   INPUT_QOS)
                          for kind in INPUTS if kind.topic != '~/pose']
            self._idle += [self.create_service(Trigger, '~/describe', lambda req, res: res),
                           self.create_service(GetPlan, '~/screw_path', lambda req, res: res)]
        qos = QoSProfile(depth=10)
        self._matrix_pub = self.create_publisher(Float64MultiArray, '~/rotation_matrix', qos)
        self._quaternion_pub = self.create_publisher(QuaternionStamped, '~/quaternion', qos)
        self._axis_angle_pub = self.create_publisher(Vector3Stamped, '~/axis_angle', qos)
        self._euler_pub = self.create_publisher(Vector3Stamped, '~/euler_angles', qos)
        self._rpy_pub = self.create_publisher(Vector3Stamped, '~/rpy', qos)
        self._screw_pub = self.create_publisher(TwistStamped, '~/screw', qos)
        self._pose_sub = self.create_subscription(
            PoseStamped, '~/pose', self._on_pose, INPUT_QOS)

        self._matrix = Float64MultiArray(
            layout=MultiArrayLayout(
                dim=[MultiArrayDimension(label='rows', size=3, stride=9),
                     MultiArrayDimension(label='cols', size=3, stride=3)],
                data_offset=0),
            data=[1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
        self._quaternion = QuaternionStamped()
        self._quaternion.quaternion.z, self._quaternion.quaternion.w = 0.6, 0.8
        self._axis_angle = Vector3Stamped(vector=Vector3(x=0.1, y=0.2, z=0.3))
        self._euler = Vector3Stamped(vector=Vector3(x=0.3, y=0.2, z=0.1))
        self._rpy = Vector3Stamped(vector=Vector3(x=0.1, y=0.2, z=0.3))
        self._screw = TwistStamped()
        self._screw.twist.angular = Vector3(x=0.1, y=0.2, z=0.3)
        self._screw.twist.linear = Vector3(x=1.0, y=2.0, z=3.0)

    def _on_pose(self, msg):
        header = msg.header
        self._quaternion.header = header
        self._axis_angle.header = header
        self._euler.header = header
        self._rpy.header = header
        self._screw.header = header
        self._matrix_pub.publish(self._matrix)
        self._quaternion_pub.publish(self._quaternion)
        self._axis_angle_pub.publish(self._axis_angle)
        self._euler_pub.publish(self._euler)
        self._rpy_pub.publish(self._rpy)
        self._screw_pub.publish(self._screw)


def main(argv=None):
    """Spin until SIGINT / SIGTERM (exit 0), with rotation_node's loop."""
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--executor', choices=EXECUTORS, default='default',
                        help="rclpy's SingleThreadedExecutor (rotation_node's) or its "
                        'EventsExecutor')
    parser.add_argument('--full-interface', action='store_true')
    args, ros_args = parser.parse_known_args(argv)
    rclpy.init(args=[sys.argv[0], *ros_args])  # SIGINT/SIGTERM: shutdown
    serve(lambda: RelayNode(full_interface=args.full_interface), EXECUTORS[args.executor])
    return 0


def _events_executor(context=None):
    from rclpy.experimental import EventsExecutor
    return EventsExecutor(context=context)


EXECUTORS = {'default': SingleThreadedExecutor, 'events': _events_executor}


if __name__ == '__main__':
    runtime.exit_now(main())  # the node's own exit (no interpreter teardown)
