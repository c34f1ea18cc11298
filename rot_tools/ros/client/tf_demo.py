"""
A demo TF tree on /tf and /tf_static: ``rotation_client tf-demo``.

map → odom (static), odom → base_link (a robot driving a circle), base_link → camera
(static, tilted down), with tf2_ros's broadcasters' QoS.
"""

import math

from rot_tools.ros import tf_input

RATE = 20.0
"""Messages a second on /tf."""

RADIUS = 1.0
TURN_RATE = 0.5
"""The robot's circle: radius (m) and rate of turn (rad/s)."""


def _about(axis, angle):
    """Return the quaternion (x, y, z, w) of a turn by ``angle`` about axis 'x', 'y' or 'z'."""
    q = [0.0, 0.0, 0.0, math.cos(angle / 2.0)]
    q['xyz'.index(axis)] = math.sin(angle / 2.0)
    return tuple(q)


STATIC_EDGES = (
    ('map', 'odom', (2.0, 0.0, 0.0), _about('z', math.pi / 2.0)),
    ('base_link', 'camera', (0.2, 0.0, 0.5), _about('y', math.radians(15.0))),
)
"""(parent, child, translation, quaternion (x, y, z, w)) of the static edges."""


def base_link(t):
    """Return the moving edge odom → base_link at ``t`` s: (parent, child, b, q)."""
    yaw = TURN_RATE * t
    b = (RADIUS * math.sin(yaw), RADIUS * (1.0 - math.cos(yaw)), 0.0)
    return 'odom', 'base_link', b, _about('z', yaw)


def frames():
    """Return the tree's frames, root first: 'map -> odom -> base_link -> camera'."""
    return ' -> '.join(['map', 'odom', 'base_link', 'camera'])


def _transform(edge, stamp):
    from geometry_msgs.msg import TransformStamped
    parent, child, b, q = edge
    msg = TransformStamped()
    msg.header.frame_id, msg.header.stamp, msg.child_frame_id = parent, stamp, child
    t, r = msg.transform.translation, msg.transform.rotation
    t.x, t.y, t.z = b
    r.x, r.y, r.z, r.w = q
    return msg


class TfDemo:
    """Publishers of the demo tree on ``node``: the static edges at once, then tick()."""

    def __init__(self, node):
        from tf2_msgs.msg import TFMessage  # (tf_input.tf2_msgs_missing says when it is not)
        self.node = node
        self.tf = node.create_publisher(TFMessage, '/tf', tf_input.TF_QOS)
        self.tf_static = node.create_publisher(TFMessage, '/tf_static', tf_input.TF_STATIC_QOS)
        self.start = node.get_clock().now()
        stamp = self.start.to_msg()
        self.tf_static.publish(TFMessage(
            transforms=[_transform(edge, stamp) for edge in STATIC_EDGES]))
        self.timer = node.create_timer(1.0 / RATE, self.tick)

    def tick(self):
        """Publish the moving edge, stamped now."""
        from tf2_msgs.msg import TFMessage
        now = self.node.get_clock().now()
        t = (now - self.start).nanoseconds * 1e-9
        self.tf.publish(TFMessage(transforms=[_transform(base_link(t), now.to_msg())]))

    def close(self):
        self.node.destroy_timer(self.timer)
        self.node.destroy_publisher(self.tf)
        self.node.destroy_publisher(self.tf_static)
