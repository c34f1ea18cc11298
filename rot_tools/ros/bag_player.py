"""
rotation_client play: a recording's messages published on their topics, as they were recorded.

For a user without rosbag2 (ros2 bag play), so that a recording can drive rotation_node. The bag
— a ROS 1 ``.bag``, a rosbag2 directory or a file of one — is read by rosbags' ``AnyReader``
(rot_tools.io.bag_read.open_bag): its topics are ``reader.connections``, its messages come from
``reader.messages(connections, start, stop)`` in the order recorded, each made an object by
``reader.deserialize``. Each object is then copied field by field into a message of the rclpy
class of its type (:func:`converter`: the fields that the class's
``get_fields_and_field_types()`` names, nested messages and sequences of them alike), so a ROS 1
message becomes its ROS 2 counterpart: a field the ROS 2 type lacks (a ROS 1 header's ``seq``)
is dropped, one the recording lacks keeps its default. Nothing is serialised by hand.

Each message is published when its recorded time (the time the recorder received it, as ros2
bag play uses it) comes, counted from the first message played, ``rate`` times faster when
``rate`` > 1; its header keeps its recorded stamp. The publishers are reliable, volatile, 100
deep — every subscription matches them, rotation_node's best-effort inputs included — except
``/tf_static`` and the topics recorded latched (ROS 1) or transient local (rosbag2), which are
transient local, as tf2_ros's static broadcaster, so a late subscriber still gets them. A topic
whose type has no Python message class here (a package not installed) is skipped and named.
Playing starts once some subscription has matched a publisher, within the client's timeout:
nothing listening is one line, exit status 1 (the topics are to be remapped onto the node's
inputs with ``--ros-args -r``).
"""

import re
import time
from typing import NamedTuple

import numpy as np
from rot_tools.ros.node.messages import type_name

MESSAGE_TYPE = r'([A-Za-z]\w*)/([A-Za-z]\w*)'
"""A message type inside a field type of get_fields_and_field_types(): 'geometry_msgs/Point'
in 'geometry_msgs/Point', 'sequence<geometry_msgs/Point>', 'geometry_msgs/Point[3]'."""

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
    skipped: list


# ---------------------------------------------------------------------------------------
# Message objects: rosbags' -> rclpy's


def _copy(value, default):
    """
    Return a plain field's value as the rclpy class takes it, from the kind of its default.

    A fixed-size numeric array is a NumPy array of the default's dtype; a numeric sequence
    an array.array of the default's typecode; bytes (octet) a list of one-byte bytes; a NumPy
    scalar its Python number.
    """
    if isinstance(default, np.ndarray):
        return np.asarray(value, dtype=default.dtype)
    if isinstance(value, np.ndarray):
        if isinstance(default, list):  # octets: rclpy keeps each as one byte
            return [bytes([v]) for v in value.tolist()]
        return type(default)(default.typecode, value.tolist())
    if isinstance(value, np.generic):
        return value.item()
    return value


def converter(cls, cache=None):
    """
    Return convert(obj): a message of rclpy class ``cls`` with the fields of ``obj``.

    ``obj`` is any object with the message's field names (rosbags' message objects). The
    plan — which fields are messages, sequences of messages, or plain values — is made once
    per class from ``cls.get_fields_and_field_types()``; ``cache`` ({class: convert}) shares
    the plans of the classes met along.
    """
    from rot_tools.ros.node.messages import message_class
    cache = {} if cache is None else cache
    if cls in cache:
        return cache[cls]
    plan = []

    def convert(obj):
        msg = cls()
        for name, kind, inner in plan:
            value = getattr(obj, name, None)
            if value is None:
                continue  # not in the recording's type: the default stays
            if kind == 'message':
                value = inner(value)
            elif kind == 'messages':
                value = [inner(item) for item in value]
            else:
                value = _copy(value, getattr(msg, name))
            setattr(msg, name, value)
        return msg
    cache[cls] = convert
    for name, field_type in cls.get_fields_and_field_types().items():
        found = re.search(MESSAGE_TYPE, field_type)
        if found is None:
            plan.append((name, 'value', None))
            continue
        inner = converter(message_class(f'{found[1]}/msg/{found[2]}'), cache)
        many = field_type.startswith('sequence<') or field_type.endswith(']')
        plan.append((name, 'messages' if many else 'message', inner))
    return convert


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
    from rot_tools.ros.node.messages import message_class
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

    def nobody_listens(self, timeout, node_name):
        """
        Return the line for topics no subscription matched within ``timeout`` seconds.

        It shows how to remap the topics of the node's input types onto the inputs of the
        node ``node_name`` (rot_tools.io.interface.INPUTS).
        """
        from rot_tools.io import interface
        names = [p.topic_name for p in self.publishers.values()]
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
                      0.0 if last is None else (last - origin) / 1e9, seconds, [])

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
    of the recording)``; then each topic skipped, with why.
    """
    total = sum(result.counts.values())
    topics_text = ', '.join(f'{topic} {n}' for topic, n in result.counts.items())
    line = (f'played {total} message{"" if total == 1 else "s"} of {bag} in '
            f'{result.seconds:.2f} s (rate {rate:g}): {topics_text or "none"} '
            f'({result.first:g} s to {result.last:g} s of the recording)')
    for s in result.skipped:
        line += f'; skipped {s.topic} ({s.msgtype}: {s.why})'
    return line
