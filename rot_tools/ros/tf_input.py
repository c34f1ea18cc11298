"""
/tf and /tf_static into a TransformTree, and the transform between two frames out.

The ROS side of rot_tools.core.transform_tree, shared by rotation_node (its parameters
``tf_reference_frame`` and ``tf_body_frame``) and ``rotation_client tf``. A
:class:`TfFollower` subscribes to /tf and /tf_static with tf2_ros's QoS (reliable, depth 100;
/tf volatile, /tf_static transient-local, so that a late joiner gets the static transforms),
passes every geometry_msgs/TransformStamped through the same inbound boundary as the node's
other inputs (rot_tools.io.boundary: NaN/Inf → ``non_finite``, a zero or non-unit quaternion
refused) into the tree, and after each message looks the pair up at the chain's latest common
time. When that time (or the chain itself) is new, it hands ``(header, R, b)`` on, with
``header.frame_id`` = the reference frame and the lookup's stamp: p_reference = R·p_body + b.

Refusals are handed on with a reason, for the node to count and warn about:
``tf_unknown_frame``, ``tf_not_connected``, ``tf_extrapolation`` (the lookup, after a message
arrived while it cannot be answered), ``tf_loop`` (a transform that would make a frame its
own ancestor), ``tf_bad_frame`` (an empty frame_id or child_frame_id), ``tf_too_many_frames``
(a new frame beyond MAX_FRAMES), and the boundary's
``non_finite``, ``zero_quaternion``, ``non_unit_quaternion``.

Stamps. The tree holds float seconds. A header stamp (sec, nanosec) is kept as seconds since
an epoch — the whole second of the first stamp heard (the wall clock's if that one is 0) —
so that every stamp within days of it keeps its nanoseconds through the float and back
(seconds since 1970 would lose up to a hundred).
"""

import time
from types import SimpleNamespace

from builtin_interfaces.msg import Time
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rot_tools.core.transform_tree import (
    TransformLookupError, TransformTree, TransformTreeError)
from rot_tools.io import boundary
from std_msgs.msg import Header

TF_TOPIC = '/tf'
TF_STATIC_TOPIC = '/tf_static'

TF_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                    durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)
"""tf2_ros's TransformListener QoS of /tf."""

TF_STATIC_QOS = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                           durability=DurabilityPolicy.TRANSIENT_LOCAL,
                           history=HistoryPolicy.KEEP_LAST)
"""tf2_ros's TransformListener QoS of /tf_static (transient local: latched)."""

TF_UNKNOWN_FRAME = 'tf_unknown_frame'
TF_NOT_CONNECTED = 'tf_not_connected'
TF_EXTRAPOLATION = 'tf_extrapolation'
TF_LOOP = 'tf_loop'
TF_BAD_FRAME = 'tf_bad_frame'
TF_TOO_MANY_FRAMES = 'tf_too_many_frames'
REFUSAL_REASONS = (TF_UNKNOWN_FRAME, TF_NOT_CONNECTED, TF_EXTRAPOLATION, TF_LOOP, TF_BAD_FRAME,
                   TF_TOO_MANY_FRAMES)
"""The reasons of this input, besides the boundary's (rot_tools.io.boundary.REFUSAL_REASONS)."""

_REASON = {'unknown_frame': TF_UNKNOWN_FRAME, 'not_connected': TF_NOT_CONNECTED,
           'extrapolation': TF_EXTRAPOLATION, 'loop': TF_LOOP, 'bad_frame': TF_BAD_FRAME,
           'too_many_frames': TF_TOO_MANY_FRAMES,
           # A transform past the boundary is finite and its R a rotation: these two are
           # only here so that every reason of the tree has a name.
           'non_finite': boundary.NON_FINITE, 'not_rotation': boundary.NON_UNIT_QUATERNION,
           'bad_value': boundary.NON_FINITE}

TYPE_NAME = 'tf2_msgs/msg/TFMessage'


def tf2_msgs_missing():
    """
    '' when tf2_msgs.msg.TFMessage imports, else one line saying how to get it.

    tf2_msgs is not on PyPI: ``make`` builds the project's own copy into .venv, and a ROS
    install brings the system's. Imported only when frames are followed, so that the rest
    of rotation_node runs without it.
    """
    try:
        from tf2_msgs.msg import TFMessage  # noqa: F401
    except ImportError as exc:
        return (f'tf2_msgs is not importable ({exc}): run make in the rot_tools checkout, '
                'which builds it into .venv, or source a ROS 2 Jazzy install')
    return ''


DEFAULT_QUATERNION_TOLERANCE = 1e-3
"""|‖q‖ − 1| accepted when no node parameter says otherwise (rotation_client tf)."""

CACHE_SECONDS = 10.0
MAX_SAMPLES = 10_000
MAX_FRAMES = 1_000
"""The follower's tree: 10 s of each edge (tf2's default), at most 10,000 samples an edge
(1 kHz) and 1,000 frames, so that a flood on /tf holds a few MB at most."""


class TfFollower:
    """
    A TransformTree fed from /tf and /tf_static; the pair (reference, body) looked up.

    node: the rclpy node to subscribe with. on_transform(header, R, b): called with each new
    lookup. on_refused(topic, reason, text): called with each refusal. The subscriptions
    exist only while both frames are set (:meth:`follow`).
    """

    def __init__(self, node, on_transform, on_refused, *,
                 quaternion_tolerance=DEFAULT_QUATERNION_TOLERANCE, max_frames=MAX_FRAMES):
        self.node = node
        self.tree = TransformTree(CACHE_SECONDS, max_samples=MAX_SAMPLES,
                                  max_frames=max_frames)
        self.reference = self.body = ''
        self.topic = node.resolve_topic_name(TF_TOPIC)
        self.static_topic = node.resolve_topic_name(TF_STATIC_TOPIC)
        self._settings = SimpleNamespace(quaternion_tolerance=quaternion_tolerance)
        self._on_transform = on_transform
        self._on_refused = on_refused
        self._subscriptions = ()
        self._published = None  # (chain, stamp) of the last lookup handed on
        self._epoch = None  # set by the first stamp (seconds)

    @property
    def following(self):
        """Tell whether both frames are set."""
        return bool(self.reference and self.body)

    def set_quaternion_tolerance(self, tolerance):
        self._settings = SimpleNamespace(quaternion_tolerance=tolerance)

    def follow(self, reference, body):
        """
        Follow body in reference from now on ('' for either: follow nothing).

        Subscribes on the first pair, unsubscribes when a frame is cleared (the tree is
        kept); the current tree is looked up at once. RuntimeError (one line) when tf2_msgs
        is not importable.
        """
        self.reference, self.body = reference, body
        self._published = None
        if self.following and not self._subscriptions:
            missing = tf2_msgs_missing()
            if missing:
                raise RuntimeError(missing)
            from tf2_msgs.msg import TFMessage
            self._subscriptions = (
                self.node.create_subscription(
                    TFMessage, TF_TOPIC, lambda msg: self._on_tf(msg, False), TF_QOS),
                self.node.create_subscription(
                    TFMessage, TF_STATIC_TOPIC, lambda msg: self._on_tf(msg, True),
                    TF_STATIC_QOS))
        elif not self.following and self._subscriptions:
            for subscription in self._subscriptions:
                self.node.destroy_subscription(subscription)
            self._subscriptions = ()
        if self.following and self.tree.frames:
            self.update()

    # -- stamps ----------------------------------------------------------------------

    def seconds(self, stamp):
        """Return a builtin_interfaces/Time as float seconds since the epoch."""
        if self._epoch is None:
            self._epoch = stamp.sec or int(time.time())
        return (stamp.sec - self._epoch) + stamp.nanosec * 1e-9

    def time_msg(self, seconds):
        """Float seconds since the epoch as a builtin_interfaces/Time (to the nanosecond)."""
        sec, nanosec = divmod(self._epoch * 1_000_000_000 + round(seconds * 1e9), 1_000_000_000)
        return Time(sec=sec, nanosec=nanosec)

    # -- messages ----------------------------------------------------------------------

    def _on_tf(self, msg, static):
        """Put every transform of a TFMessage into the tree; then look the pair up."""
        topic = self.static_topic if static else self.topic
        for transform in msg.transforms:
            self.add(transform, static, topic)
        self.update()

    def add(self, transform, static, topic):
        """One geometry_msgs/TransformStamped into the tree, or a refusal; True if stored."""
        try:
            header, R, b = boundary.transform_stamped_to_transform(transform, self._settings)
            self.tree.set_transform(header.frame_id, transform.child_frame_id, R, b,
                                    self.seconds(header.stamp), static=static)
        except boundary.RefusedInput as exc:
            self._on_refused(topic, exc.reason, f'{_edge_name(transform)}: {exc}')
            return False
        except TransformTreeError as exc:
            self._on_refused(topic, _REASON[exc.reason], str(exc))
            return False
        return True

    def lookup(self):
        """Return (header, R, b) of body in reference at the latest common time."""
        R, b, stamp = self.tree.lookup(self.reference, self.body)
        return Header(frame_id=self.reference, stamp=self.time_msg(stamp)), R, b

    def update(self):
        """Hand on the pair's transform if the chain has a new common time (or is new)."""
        if not self.following:
            return
        try:
            chain = tuple(self.tree.chain(self.reference, self.body))
            key = (chain, self.tree.latest_common_time(self.reference, self.body))
            if key == self._published:
                return
            header, R, b = self.lookup()
        except TransformLookupError as exc:
            self._on_refused(self.topic, _REASON[exc.reason], str(exc))
            return
        self._published = key
        self._on_transform(header, R, b)

    def why_not(self, seconds):
        """One line saying why the pair could not be looked up within ``seconds``."""
        topics = f'{self.topic} or {self.static_topic}'
        missing = [f for f in (self.reference, self.body) if f not in self.tree.frames]
        if missing:
            seen = ', '.join(self.tree.frames) or 'none'
            names = ' and '.join(repr(f) for f in missing)
            frames = 'frame' if len(missing) == 1 else 'frames'
            return (f'{frames} {names} did not appear on {topics} within {seconds:g} s '
                    f'(frames seen: {seen})')
        what = f'no transform of {self.body!r} in {self.reference!r} within {seconds:g} s'
        try:
            self.lookup()
        except TransformLookupError as exc:
            return f'{what}: {exc}'
        return what

    def describe(self):
        """{source, reference_frame, body_frame, chain} (chain: the frames, or why none)."""
        try:
            chain = self.tree.chain(self.reference, self.body)
        except TransformLookupError as exc:
            chain = f'none: {exc}'
        return {'source': self.topic, 'reference_frame': self.reference,
                'body_frame': self.body, 'chain': chain}


def _edge_name(transform):
    return f'transform {transform.header.frame_id!r} → {transform.child_frame_id!r}'
