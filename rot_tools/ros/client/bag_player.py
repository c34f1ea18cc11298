"""
rotation_client play: a recording's messages published on their topics, as recorded.

The bag is read by rosbags' ``AnyReader`` (rot_tools.io.bag_read.open_bag); each message,
ROS 1 or ROS 2, is copied field by field into the rclpy message of its type (:func:`converter`)
and published when its recorded time comes, ``rate`` times faster.
"""

import array
import os
import time
from typing import NamedTuple

import numpy as np
from rot_tools.ros.message_types import type_name

DEPTH = 100
"""The publishers' history depth."""

SETTLE = 0.5
"""Seconds to wait for the other topics' subscriptions once one has matched."""

FLUSH = 0.5
"""Seconds to wait at most, after the last message, for the subscriptions to acknowledge."""


class Skipped(NamedTuple):
    """A topic of the bag not played, and why."""

    topic: str
    msgtype: str
    why: str


class Played(NamedTuple):
    """What a play did: messages by topic, the part of the recording, the seconds it took."""

    counts: dict
    """{topic: messages published}, in the order of the bag's topics."""
    first: float
    """The recorded time of the first message played, seconds after the bag's start."""
    last: float
    """The recorded time of the last message played, seconds after the bag's start."""
    seconds: float
    """The seconds the play took, from the first message to the last."""


# ---------------------------------------------------------------------------------------
# Message objects: rosbags' -> rclpy's


def _octets(value):
    """Return bytes (ROS 1 byte: int8; octet: uint8) as rclpy keeps them: one bytes each."""
    data = np.asarray(value).astype(np.uint8).tobytes()
    return [data[k:k + 1] for k in range(len(data))]


def _numbers(default):
    """Return how a numeric array or sequence is taken, from the rclpy default's kind."""
    if isinstance(default, np.ndarray):  # a fixed-size array
        return lambda value: np.asarray(value, dtype=default.dtype)
    code = default.typecode  # a sequence: an array.array
    return lambda value: array.array(code, np.asarray(value, dtype=code).tobytes())


def _scalar(value):
    return value.item() if isinstance(value, np.generic) else value


def _field(slot, default, cache):
    """Return convert(value) of one field, from its rosidl type ``slot`` (SLOT_TYPES)."""
    from rosidl_parser.definition import AbstractNestedType, NamespacedType, OCTET_TYPE
    from rot_tools.ros.message_types import message_class
    if isinstance(slot, NamespacedType):
        return converter(message_class('/'.join([*slot.namespaces, slot.name])), cache)
    if isinstance(slot, AbstractNestedType):
        item = slot.value_type
        if isinstance(item, NamespacedType):
            inner = _field(item, None, cache)
            return lambda value: [inner(v) for v in value]
        if getattr(item, 'typename', None) == OCTET_TYPE:
            return _octets
        if isinstance(default, (np.ndarray, array.array)):
            return _numbers(default)
        return lambda value: [_scalar(v) for v in value]  # strings, booleans
    if getattr(slot, 'typename', None) == OCTET_TYPE:
        return lambda value: bytes([int(value) & 0xFF])
    return _scalar


def converter(cls, cache=None):
    """
    Return convert(obj): a message of rclpy class ``cls`` holding the fields of ``obj``.

    ``obj`` is a rosbags message object (ROS 1 or ROS 2). Each field of ``cls`` is taken
    from obj's field of that name as ``cls.SLOT_TYPES`` says: a message in turn, bytes as
    bytes, numbers as the array kind rclpy keeps; a field obj lacks keeps its default (a
    ROS 1 header's ``seq`` has no place and is dropped). ``cache`` ({class: convert})
    shares the converters of the classes met along.
    """
    cache = {} if cache is None else cache
    if cls not in cache:
        fields = []

        def convert(obj):
            msg = cls()
            for name, take in fields:
                value = getattr(obj, name, None)
                if value is not None:
                    setattr(msg, name, take(value))
            return msg
        default = cls()
        for name, slot in zip(cls.get_fields_and_field_types(), cls.SLOT_TYPES):
            fields.append((name, _field(slot, getattr(default, name), cache)))
        cache[cls] = convert
    return cache[cls]


# ---------------------------------------------------------------------------------------
# Topics and publishers


def _latched(connection):
    """Whether a topic was recorded latched (ROS 1) or transient local (rosbag2)."""
    from rosbags.interfaces import QosDurability
    if getattr(connection.ext, 'latching', None):
        return True
    profiles = getattr(connection.ext, 'offered_qos_profiles', None) or ()
    return any(getattr(q, 'durability', None) == QosDurability.TRANSIENT_LOCAL
               for q in profiles)


def qos(connections):
    """Return the QoS of a topic's publisher, from its connections in the bag."""
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    latched = connections[0].topic == '/tf_static' or any(map(_latched, connections))
    return QoSProfile(depth=DEPTH, reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL if latched
                      else DurabilityPolicy.VOLATILE)


def topics(reader, wanted=None):
    """
    Return ({topic: (rclpy class, its connections)}, [Skipped]) of a bag's topics to play.

    ``wanted``: the topics asked for (all when None); a topic the bag lacks is a KeyError
    naming it. A topic whose type has no rclpy message class here is Skipped.
    """
    from rot_tools.ros.message_types import message_class
    by_topic = {}
    for c in reader.connections:
        by_topic.setdefault(c.topic, []).append(c)
    for topic in wanted or ():
        if topic not in by_topic:
            raise KeyError(topic)
    played, skipped = {}, []
    for topic, connections in by_topic.items():
        if wanted and topic not in wanted:
            continue
        msgtype = connections[0].msgtype
        try:
            played[topic] = (message_class(msgtype), connections)
        except (ImportError, AttributeError, ValueError):
            skipped.append(Skipped(topic, msgtype, 'no Python message class for its type here'))
    return played, skipped


# ---------------------------------------------------------------------------------------
# Playing


def _deserialize(reader, raw, connection, stamp):
    """Return rosbags' message object of ``raw``; BagError naming it if it does not decode."""
    from rot_tools.io.bag_read import BagError
    try:
        return reader.deserialize(raw, connection.msgtype)
    except Exception as exc:  # noqa: BLE001 - rosbags' serde errors vary
        text = ' '.join(str(exc).split())[:200] or type(exc).__name__
        seconds = (stamp - reader.start_time) / 1e9
        raise BagError(f'{connection.topic}: the message recorded {seconds:g} s after the '
                       f'start cannot be decoded as {connection.msgtype}: {text}') from None


class Player:
    """
    The publishers of a bag's topics (:func:`topics`' ``played``), and their play.

    ``publisher(msg_type, topic, qos)`` returns a publisher of a node (rclpy's
    create_publisher, or a Client's that keeps them); ``spin_until(done, seconds)`` spins the
    node's executor while waiting (so that Ctrl-C ends any wait at once) and returns done().
    """

    def __init__(self, publisher, spin_until, played):
        self.spin_until = spin_until
        self.publishers, self.convert = {}, {}
        cache = {}
        for topic, (cls, connections) in played.items():
            self.publishers[topic] = publisher(cls, topic, qos(connections))
            self.convert[topic] = converter(cls, cache)
        self.connections = [c for _, cs in played.values() for c in cs]

    def wait_for_subscribers(self, timeout):
        """
        Wait until a subscription has matched a publisher, then the others a moment more.

        Return the topics (as published, remapped) with no subscription then: all of them if
        none matched within ``timeout`` seconds.
        """
        def unmatched():
            return [p.topic_name for p in self.publishers.values()
                    if p.get_subscription_count() == 0]
        if self.spin_until(lambda: len(unmatched()) < len(self.publishers), timeout):
            self.spin_until(lambda: not unmatched(), SETTLE)
        return unmatched()

    def plan(self, skipped):
        """Return the lines that say what is played: each topic, its type, where it goes."""
        lines = []
        for topic, publisher in self.publishers.items():
            to = '' if publisher.topic_name == topic else f' on {publisher.topic_name}'
            lines.append(f'playing {topic} ({type_name(publisher.msg_type)}){to}')
        return lines + [f'not playing {s.topic} ({s.msgtype}): {s.why}' for s in skipped]

    def nobody_listens(self, timeout, node_name, node_running):
        """
        Return the line for topics no subscription matched within ``timeout`` seconds.

        The node ``node_name`` not running is said so; else the line shows how to remap the
        topics of the node's input types onto its inputs (rot_tools.io.interface.INPUTS).
        """
        from rot_tools.io import interface
        names = [p.topic_name for p in self.publishers.values()]
        if not node_running:
            domain = os.environ.get('ROS_DOMAIN_ID') or '0'
            return (f'no subscription on {", ".join(names)} within {timeout:g} s, and node '
                    f'{node_name} is not running (not found with ROS_DOMAIN_ID {domain})')
        inputs = {row.type_name: row.name for row in interface.INPUTS}
        remaps = [f'-r {p.topic_name}:={node_name}/{inputs[type_name(p.msg_type)]}'
                  for p in self.publishers.values() if type_name(p.msg_type) in inputs]
        how = (f" (--ros-args {' '.join(remaps)})" if remaps else '')
        return (f'no subscription on {", ".join(names)} within {timeout:g} s: remap the '
                f"topics onto the node's inputs{how}")

    def play(self, reader, rate, start=None, stop=None):
        """
        Publish the messages recorded between ``start`` and ``stop`` (ns) at their times.

        Each is read, made an object (the reader's ``deserialize``) and converted, then
        published when its recorded time comes: (recorded − first recorded) / ``rate``
        seconds after the first was published. Return :class:`Played`.
        """
        counts = dict.fromkeys(self.publishers, 0)
        first = last = begin = None
        messages = reader.messages(connections=self.connections, start=start, stop=stop)
        for connection, stamp, raw in messages:
            msg = self.convert[connection.topic](_deserialize(reader, raw, connection, stamp))
            if begin is None:
                first, begin = stamp, time.monotonic()
            due = begin + (stamp - first) / (1e9 * rate)
            if time.monotonic() < due:
                self.spin_until(lambda: time.monotonic() >= due, due - time.monotonic())
            self.publishers[connection.topic].publish(msg)
            counts[connection.topic] += 1
            last = stamp
        seconds = 0.0 if begin is None else time.monotonic() - begin
        self.flush()
        origin = reader.start_time
        return Played(counts, 0.0 if first is None else (first - origin) / 1e9,
                      0.0 if last is None else (last - origin) / 1e9, seconds)

    def flush(self):
        """Wait, FLUSH seconds at most in all, for the subscriptions to acknowledge the last."""
        from rclpy.duration import Duration
        end = time.monotonic() + FLUSH
        for publisher in self.publishers.values():
            left = Duration(nanoseconds=int((end - time.monotonic()) * 1e9))
            if left.nanoseconds <= 0 or not publisher.wait_for_all_acked(left):
                return


def summary(bag, result, rate):
    """
    Return the summary line of a play.

    ``played 200 messages of BAG in 0.51 s (rate 2): /imu/data 100, /odom 100 (10 s to 10.99 s
    of the recording)``.
    """
    total = sum(result.counts.values())
    topics_text = ', '.join(f'{topic} {n}' for topic, n in result.counts.items())
    return (f'played {total} message{"" if total == 1 else "s"} of {bag} in '
            f'{result.seconds:.2f} s (rate {rate:g}): {topics_text or "none"} '
            f'({result.first:g} s to {result.last:g} s of the recording)')
