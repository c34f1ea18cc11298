"""
A TF publisher for the tests, run as a separate process: a chain of four frames.

    odom ──(dynamic)── base_link ──(static)── camera ──(dynamic)── gimbal

The gimbal is stamped half a period before base_link, so a lookup interpolates; a second
tree (moon → rover) stands apart. Quaternions from scipy.

Usage: tf_publisher.py TF_TOPIC TF_STATIC_TOPIC [--rate HZ] [--lifetime S] [--bad] [--still]
--bad also publishes, once a second, a NaN, a loop and a stale edge; --still holds the motion.
"""

import argparse
import math

from geometry_msgs.msg import TransformStamped
import numpy as np
import rclpy
from rclpy.duration import Duration
from rclpy.executors import ExternalShutdownException
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from scipy.spatial.transform import Rotation
from tf2_msgs.msg import TFMessage

STATIC = ('base_link', 'camera',
          Rotation.from_euler('ZYX', [0.1, -0.3, 0.0]).as_matrix(), np.array([0.2, 0.0, 0.5]))


def base_link(t):
    """Return the edge odom → base_link at t (seconds): a turn about z with a wobble."""
    R = Rotation.from_euler('ZX', [0.5 * t, 0.2 * math.sin(t)]).as_matrix()
    return R, np.array([math.cos(t), math.sin(t), 0.1 * (t % 100.0)])


def gimbal(t):
    """Return the edge camera → gimbal at t: a nod about x, 5 cm off the camera's origin."""
    return Rotation.from_euler('X', 0.8 * math.sin(2.0 * t)).as_matrix(), np.array(
        [0.0, 0.05, 0.0])


def transform_msg(parent, child, R, b, stamp):
    msg = TransformStamped()
    msg.header.frame_id, msg.child_frame_id = parent, child
    msg.header.stamp = stamp
    t, q = msg.transform.translation, msg.transform.rotation
    t.x, t.y, t.z = map(float, b)
    q.x, q.y, q.z, q.w = map(float, Rotation.from_matrix(R).as_quat())
    return msg


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('tf_topic')
    parser.add_argument('tf_static_topic')
    parser.add_argument('--rate', type=float, default=20.0)
    parser.add_argument('--lifetime', type=float, default=60.0)
    parser.add_argument('--bad', action='store_true')
    parser.add_argument('--still', action='store_true',
                        help='the dynamic edges keep their values at t = 1 s (docs)')
    args, ros_args = parser.parse_known_args()
    rclpy.init(args=ros_args)
    node = rclpy.create_node('tf_publisher')
    tf_pub = node.create_publisher(TFMessage, args.tf_topic, QoSProfile(
        depth=100, reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST))
    static_pub = node.create_publisher(TFMessage, args.tf_static_topic, QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL, history=HistoryPolicy.KEEP_LAST))
    clock = node.get_clock()
    parent, child, R, b = STATIC
    static_pub.publish(TFMessage(transforms=[
        transform_msg(parent, child, R, b, clock.now().to_msg()),
        transform_msg('moon', 'rover', np.eye(3), [1.0, 0.0, 0.0], clock.now().to_msg())]))
    old = (clock.now() - Duration(seconds=20.0)).to_msg()  # before every other edge's cache
    start = clock.now()
    half = 0.5 / args.rate
    ticks = [0]

    def tick():
        now = clock.now()
        t = 1.0 if args.still else now.nanoseconds * 1e-9
        tf_pub.publish(TFMessage(transforms=[
            transform_msg('odom', 'base_link', *base_link(t), now.to_msg())]))
        earlier = now - Duration(seconds=half)
        t = 1.0 if args.still else earlier.nanoseconds * 1e-9
        tf_pub.publish(TFMessage(transforms=[transform_msg(
            'camera', 'gimbal', *gimbal(t), earlier.to_msg())]))
        ticks[0] += 1
        if args.bad and ticks[0] % int(args.rate) == 0:
            bad = transform_msg('odom', 'stray', np.eye(3), [math.nan, 0.0, 0.0], now.to_msg())
            loop = transform_msg('gimbal', 'odom', np.eye(3), [0.0, 0.0, 0.0], now.to_msg())
            # An edge whose only sample is 20 s old: beyond the 10 s that the others keep.
            stale = transform_msg('odom', 'old_marker', np.eye(3), [0.0, 0.0, 1.0], old)
            tf_pub.publish(TFMessage(transforms=[bad, loop, stale]))
        if (now - start).nanoseconds * 1e-9 > args.lifetime:
            raise SystemExit(0)

    node.create_timer(1.0 / args.rate, tick)
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException, SystemExit):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == '__main__':
    main()
