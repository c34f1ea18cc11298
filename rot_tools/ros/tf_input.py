"""
/tf and /tf_static into a TransformTree, and the transform between two frames out.

Shared by rotation_node (parameters ``tf_reference_frame``, ``tf_body_frame``) and
``rotation_client tf``. A :class:`TfFollower` subscribes with tf2_ros's QoS, passes each
TransformStamped through the node's boundary checks into the tree, and hands
``(header, R, b)`` on (p_reference = R·p_body + b) when the pair's latest common time is new.
Refusals go to the node by reason (REFUSAL_REASONS and the boundary's). Time: a stamp more
than MAX_FUTURE_SECONDS ahead of the node's clock is refused; one more than CACHE_SECONDS
behind its edge's newest means time went back, and the edge starts again from it. Bounds:
MAX_TRANSFORMS_PER_MESSAGE, MAX_FRAME_NAME, MAX_FRAMES; unheard dynamic edges are forgotten
after CACHE_SECONDS. Stamps are kept as integer nanoseconds, so an output's stamp is an
input's exactly.
"""

import time
from typing import NamedTuple

from builtin_interfaces.msg import Time
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rot_tools.core.transform_tree import (
    MAX_FRAME_NAME, shown, SHOWN_NAME, TransformLookupError, TransformTree, TransformTreeError)
from rot_tools.io import boundary
from rot_tools.io.boundary import QUATERNION_TOLERANCE
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
TF_FUTURE_STAMP = 'tf_future_stamp'
TF_TIME_JUMP = 'tf_time_jump'
TF_TOO_MANY_TRANSFORMS = 'tf_too_many_transforms'
REFUSAL_REASONS = (TF_UNKNOWN_FRAME, TF_NOT_CONNECTED, TF_EXTRAPOLATION, TF_LOOP, TF_BAD_FRAME,
                   TF_TOO_MANY_FRAMES, TF_FUTURE_STAMP, TF_TIME_JUMP, TF_TOO_MANY_TRANSFORMS)
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


CACHE_SECONDS = 10.0
MAX_SAMPLES = 2_000
MAX_FRAMES = 1_000
"""The follower's tree: 10 s of each edge (tf2's default), at most 2,000 samples an edge (the
newest: 200 Hz for the whole 10 s; the latest common time needs only the newest few) and
1,000 frames."""

MAX_TRANSFORMS_PER_MESSAGE = 1_000
"""Transforms taken from one TFMessage at most (tf2's largest, robot_state_publisher's,
carry a few dozen); the rest are dropped, the message counted once."""

MAX_FUTURE_SECONDS = 60.0
"""How far after the node's clock a /tf stamp may be (clocks of two machines differ)."""

SHOWN_FRAMES = 20
"""Frames a message lists at most."""

FORGET_PERIOD = 1.0
"""Seconds between two looks for dynamic edges not heard for CACHE_SECONDS."""

_NS = 1_000_000_000


class Transform(NamedTuple):
    """One geometry_msgs/TransformStamped as the tree takes it."""

    sec: int
    nanosec: int
    frame_id: str
    child_frame_id: str
    values: tuple  # translation x, y, z, rotation x, y, z, w
    oversize: str = ''  # 'child_frame_id of N bytes' when a name is longer than allowed

    @classmethod
    def of(cls, msg):
        """Return the Transform of a geometry_msgs/TransformStamped message object."""
        t, q = msg.transform.translation, msg.transform.rotation
        long = [f'{what} of {len(name.encode()):,} bytes' for what, name in (
            ('frame_id', msg.header.frame_id), ('child_frame_id', msg.child_frame_id))
            if len(name.encode()) > MAX_FRAME_NAME]
        return cls(msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id,
                   msg.child_frame_id, (t.x, t.y, t.z, q.x, q.y, q.z, q.w), ', '.join(long))


class TfFollower:
    """
    A TransformTree fed from /tf and /tf_static; the pair (reference, body) looked up.

    node: the rclpy node to subscribe with. on_transform(header, R, b): called with each new
    lookup. on_refused(topic, reason, text): called with each refusal. The subscriptions
    exist only while both frames are set (:meth:`follow`).
    """

    def __init__(self, node, on_transform, on_refused, *,
                 quaternion_tolerance=QUATERNION_TOLERANCE, max_frames=MAX_FRAMES):
        self.node = node
        self.tree = TransformTree(CACHE_SECONDS, max_samples=MAX_SAMPLES,
                                  max_frames=max_frames)
        self.reference = self.body = ''
        self.topic = node.resolve_topic_name(TF_TOPIC)
        self.static_topic = node.resolve_topic_name(TF_STATIC_TOPIC)
        self._tolerance = quaternion_tolerance
        self._on_transform = on_transform
        self._on_refused = on_refused
        self._subscriptions = ()
        self._published = None  # (chain, stamp) of the last lookup handed on
        self._epoch = None  # ns: the whole second of the first stamp that is not 0
        self._newest = {}  # child: (seconds, ns) of its edge's newest sample
        self._heard = {}  # child of a dynamic edge: time.monotonic() of its latest sample
        self._swept = time.monotonic()
        self.messages = 0
        """TFMessages of /tf taken since the start (rot_tools.ros.node.diagnostics' rate)."""

    @property
    def following(self):
        """Tell whether both frames are set."""
        return bool(self.reference and self.body)

    def set_quaternion_tolerance(self, tolerance):
        self._tolerance = tolerance

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
                self.node.create_subscription(TFMessage, TF_TOPIC, self.on_tf, TF_QOS),
                self.node.create_subscription(TFMessage, TF_STATIC_TOPIC, self.on_tf_static,
                                              TF_STATIC_QOS))
        elif not self.following and self._subscriptions:
            for subscription in self._subscriptions:
                self.node.destroy_subscription(subscription)
            self._subscriptions = ()
        if self.following and self.tree.frames:
            self.update()

    # -- stamps ----------------------------------------------------------------------

    def seconds(self, ns):
        """Return a stamp in integer nanoseconds as the tree's float seconds."""
        if self._epoch is None and ns >= _NS:
            self._epoch = ns - ns % _NS
        return (ns - (self._epoch or 0)) / 1e9

    def stamp_ns(self, chain, seconds):
        """
        Return the nanoseconds of the tree's stamp ``seconds`` for the frames of ``chain``.

        That stamp is the newest of an edge of the chain (the latest common time): its
        nanoseconds as received. 0 for a root looked up in itself (tf2's time 0).
        """
        for frame in chain:
            newest = self._newest.get(frame)
            if newest is not None and newest[0] == seconds:
                return newest[1]
        return 0 if seconds == 0.0 else (self._epoch or 0) + round(seconds * 1e9)

    # -- messages ----------------------------------------------------------------------

    def on_tf(self, msg):
        """Take a tf2_msgs/TFMessage of /tf."""
        self.messages += 1
        self.on_message(msg, False)

    def on_tf_static(self, msg):
        """Take a tf2_msgs/TFMessage of /tf_static."""
        self.on_message(msg, True)

    def on_message(self, msg, static):
        """Put the transforms of a TFMessage into the tree; then look the pair up."""
        topic = self.static_topic if static else self.topic
        transforms = msg.transforms
        if len(transforms) > MAX_TRANSFORMS_PER_MESSAGE:
            self._on_refused(topic, TF_TOO_MANY_TRANSFORMS, (
                f'a TFMessage of {len(transforms):,} transforms: the first '
                f'{MAX_TRANSFORMS_PER_MESSAGE:,} taken, '
                f'{len(transforms) - MAX_TRANSFORMS_PER_MESSAGE:,} dropped (at most '
                f'MAX_TRANSFORMS_PER_MESSAGE = {MAX_TRANSFORMS_PER_MESSAGE:,} a message)'))
            transforms = transforms[:MAX_TRANSFORMS_PER_MESSAGE]
        self._forget_unheard()  # first: a new frame may need the place of a forgotten one
        now = 0 if static else self.node.get_clock().now().nanoseconds
        for transform in transforms:
            self.add(transform, static, topic, now)
        self.update()

    def add(self, transform, static, topic, now=0):
        """
        Put one transform into the tree, or refuse it; True if stored.

        transform: a Transform or a geometry_msgs/TransformStamped. now: the node's clock
        (ns) for the future-stamp check, 0 for none.
        """
        if not isinstance(transform, Transform):
            transform = Transform.of(transform)
        parent, child = transform.frame_id, transform.child_frame_id
        edge = f'transform {shown(parent)} → {shown(child)}'
        ns = transform.sec * _NS + transform.nanosec
        if transform.oversize:
            return self._refuse(topic, TF_BAD_FRAME, f'{edge}: {transform.oversize}, at most '
                                f'MAX_FRAME_NAME = {MAX_FRAME_NAME}')
        if now and ns > now + MAX_FUTURE_SECONDS * _NS:
            return self._refuse(topic, TF_FUTURE_STAMP, (
                f'{edge} stamped {(ns - now) / _NS:.9g} s after the clock of the node '
                f'(at most MAX_FUTURE_SECONDS = {MAX_FUTURE_SECONDS:g})'))
        try:
            R, b = boundary.rigid_motion(transform.values[:3], transform.values[3:],
                                         self._tolerance,
                                         ('transform.translation', 'transform.rotation'))
            t = self.seconds(ns)
            if not self.tree.set_transform(parent, child, R, b, t, static=static):
                # More than the cache older than the edge's newest: time went back.
                newest = self.tree.time_range(parent, child)[1]
                self.tree.forget(child)
                self.tree.set_transform(parent, child, R, b, t)
                self._on_refused(topic, TF_TIME_JUMP, (
                    f'{edge} stamped {newest - t:.9g} s before its newest sample, more than '
                    f'the {CACHE_SECONDS:g} s cache: time went back (a bag replayed in a '
                    'loop, a simulator restarted?); the samples of the edge were dropped'))
        except boundary.RefusedInput as exc:
            return self._refuse(topic, exc.reason, f'{edge}: {exc}')
        except TransformTreeError as exc:
            return self._refuse(topic, _REASON[exc.reason], str(exc))
        if static or self.tree.time_range(parent, child)[1] == t:
            self._newest[child] = (t, ns)
        if static:
            self._heard.pop(child, None)  # a static edge is never forgotten
        else:
            self._heard[child] = time.monotonic()
        return True

    def _refuse(self, topic, reason, text):
        self._on_refused(topic, reason, text)
        return False

    def _forget_unheard(self):
        """Forget the dynamic edges not heard for CACHE_SECONDS (at most once a FORGET_PERIOD)."""
        now = time.monotonic()
        if now - self._swept < FORGET_PERIOD:
            return
        self._swept = now
        for child, heard in list(self._heard.items()):
            if now - heard > CACHE_SECONDS:
                self.tree.forget(child)
                del self._heard[child]
                self._newest.pop(child, None)

    def lookup(self):
        """Return (header, R, b) of body in reference at the latest common time."""
        R, b, stamp = self.tree.lookup(self.reference, self.body)
        ns = self.stamp_ns(self.tree.chain(self.reference, self.body), stamp)
        return Header(frame_id=self.reference, stamp=Time(sec=ns // _NS, nanosec=ns % _NS)), R, b

    def update(self):
        """Hand on the pair's transform if the chain has a new common time (or is new)."""
        if not self.following:
            return
        try:
            chain = tuple(self.tree.chain(self.reference, self.body))
            key = (chain, self.stamp_ns(
                chain, self.tree.latest_common_time(self.reference, self.body)))
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
        frames = self.tree.frames
        missing = [f for f in (self.reference, self.body) if f not in frames]
        if missing:
            seen = ', '.join(f if len(f) <= SHOWN_NAME else f[:SHOWN_NAME - 1] + '…'
                             for f in frames[:SHOWN_FRAMES]) or 'none'
            if len(frames) > SHOWN_FRAMES:
                seen += f' and {len(frames) - SHOWN_FRAMES:,} more'
            names = ' and '.join(map(shown, missing))
            frames = 'frame' if len(missing) == 1 else 'frames'
            return (f'{frames} {names} did not appear on {topics} within {seconds:g} s '
                    f'(frames seen: {seen})')
        what = (f'no transform of {shown(self.body)} in {shown(self.reference)} within '
                f'{seconds:g} s')
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
