"""
Reading the orientation fields of recorded bags into NumPy columns, without ROS.

rosbags (the ``bag`` extra) opens ROS 1 and rosbag2 (sqlite3, MCAP) bags and decodes their
messages; each topic keeps only the fields its checks and conversions need (SUPPORTED), as
columns. Every failure of a bag is a BagError of one line that names the bag; a bag that
holds nothing of what was asked, a BagSkipped.
"""

from contextlib import contextmanager
from operator import attrgetter, itemgetter
import os
from pathlib import Path
import stat
from typing import NamedTuple

import numpy as np

MEMBERS = {
    'child_frame_id': None,
    'position': ('x', 'y', 'z'),
    'orientation': ('x', 'y', 'z', 'w'),
    'covariance0': ('[0]',),
    'angular_velocity': ('x', 'y', 'z'),
}
"""The columns read, and the float64 members of each field (None: a string)."""

_POSE = {'position': 'pose.position', 'orientation': 'pose.orientation'}
_POSE_POSE = {'position': 'pose.pose.position', 'orientation': 'pose.pose.orientation'}
TF_FIELDS = {'child_frame_id': 'child_frame_id', 'position': 'transform.translation',
             'orientation': 'transform.rotation'}
"""The fields of a geometry_msgs/TransformStamped (and of each transform of a TFMessage)."""

SUPPORTED = {
    'geometry_msgs/msg/PoseStamped': _POSE,
    'geometry_msgs/msg/TransformStamped': TF_FIELDS,
    'geometry_msgs/msg/PoseWithCovarianceStamped': _POSE_POSE,
    'nav_msgs/msg/Odometry': {'child_frame_id': 'child_frame_id', **_POSE_POSE},
    'sensor_msgs/msg/Imu': {'orientation': 'orientation',
                            'covariance0': 'orientation_covariance',
                            'angular_velocity': 'angular_velocity'},
    'geometry_msgs/msg/QuaternionStamped': {'orientation': 'quaternion'},
}
"""The message types read — rotation_node's inputs with an orientation — and where their
fields are: column (a key of :data:`MEMBERS`) → field path."""

COVARIANCE = {'geometry_msgs/msg/PoseWithCovarianceStamped': ('pose.covariance', 36),
              'nav_msgs/msg/Odometry': ('pose.covariance', 36),
              'sensor_msgs/msg/Imu': ('orientation_covariance', 9)}
"""The types read that carry their orientation's covariance: type name → (path, size) of
the float64 array, read whole as the column ``covariance`` (N, size), row-major."""

TF_TYPE = 'tf2_msgs/msg/TFMessage'
"""Read only with --tf (the transforms of /tf and /tf_static feed a transform tree)."""

HEADER = {'stamp': 'header.stamp', 'frame_id': 'header.frame_id'}
"""The header's fields read from every message (and every transform of a TFMessage)."""

STAMP_MEMBERS = ('sec', 'nanosec')
"""The members of a header stamp (builtin_interfaces/Time), read as int64."""

CHUNK = 64
"""Messages of one topic held as objects at a time, before their fields become columns: few,
so that they are gone before Python's garbage collector would walk them again and again."""

VECTOR3 = ('x', 'y', 'z')
"""The members of a Vector3 field read on request (read_topics' ``vectors``)."""

BAG_SUFFIXES = ('.bag', '.db3', '.mcap')
"""Files read as a bag outside a rosbag2 directory: ROS 1, and rosbag2's storage files."""


class BagError(Exception):
    """A bag that cannot be read as asked: one line of text for the user."""


class BagSkipped(BagError):
    """
    A bag that can be read but holds nothing of what was asked.

    None of the topics asked for, no topic of a type read, no TF for --tf or not the frames
    asked for, no message at all. Alone, it is an error like any BagError; in a fleet, the
    bag is ``skipped``, not ``failed``.
    """


def rosbags_missing():
    """Return the name of the missing module when rosbags cannot be imported, else None."""
    try:
        import rosbags.highlevel  # noqa: F401
    except ImportError as exc:
        return exc.name or 'rosbags'
    return None


# ---------------------------------------------------------------------------------------
# Opening a bag


def is_bag(path):
    """
    Tell whether PATH names a bag by its kind and name alone, opening nothing.

    A directory holding metadata.yaml (a rosbag2 bag), or a file whose name ends in .bag (ROS
    1), .db3 or .mcap (a rosbag2 storage file, in its bag's directory or alone). Whether it
    really is one, reading it says (:func:`open_bag`).
    """
    path = Path(path)
    if path.is_dir():
        return (path / 'metadata.yaml').exists()
    return path.suffix in BAG_SUFFIXES


def _mode(path):
    try:
        return path.stat().st_mode
    except FileNotFoundError:
        raise BagError(f'{path}: no such file or directory') from None
    except OSError as exc:
        raise BagError(f'{path}: cannot be read: {exc.strerror or exc}') from None


def _regular_files_only(directory):
    """
    Raise BagError if an entry of a rosbag2 directory is neither a regular file nor a directory.

    rosbags opens metadata.yaml and the storage files it names: a FIFO among them would block
    the reader for ever, a device would be read as a bag. Nothing is opened here (stat only).
    """
    try:
        entries = sorted(os.scandir(directory), key=lambda entry: entry.name)
    except OSError as exc:
        raise BagError(f'{directory}: cannot be read: {exc.strerror or exc}') from None
    for entry in entries:
        try:
            mode = entry.stat().st_mode
        except OSError:
            continue  # a dangling link: the reader says what it misses
        if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
            raise BagError(f'{directory}: its {entry.name} is not a regular file (a FIFO, '
                           'socket or device): refused')


def bag_paths(path):
    """
    Return the paths rosbags opens for PATH, checked without opening anything.

    [a .bag file], [a rosbag2 directory] or [a rosbag2 storage file alone]. A file inside a
    rosbag2 directory stands for the directory. Anything else — missing, not a regular file
    nor a directory, a rosbag2 directory holding one that is not (a FIFO would block the
    reader for ever), empty, a file that is not named as a bag — is a BagError, before
    opening.
    """
    path = Path(path)
    mode = _mode(path)
    if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
        raise BagError(f'{path}: not a regular file or a directory')
    if stat.S_ISDIR(mode):
        if not (path / 'metadata.yaml').exists():
            raise BagError(f'{path}: a directory without metadata.yaml is not a rosbag2 bag')
        _regular_files_only(path)
        return [path]
    if path.suffix != '.bag' and (path.parent / 'metadata.yaml').exists():
        _regular_files_only(path.parent)
        return [path.parent]  # a rosbag2 storage file: its directory is the bag
    if path.stat().st_size == 0:
        raise BagError(f'{path}: the file is empty')
    if path.suffix not in BAG_SUFFIXES:
        raise BagError(f'{path}: not a bag (a ROS 1 bag ends in .bag, a rosbag2 storage file '
                       'in .db3 or .mcap; a rosbag2 bag is a directory with metadata.yaml)')
    return [path]


def _one_line(exc):
    text = ' '.join(str(exc).split()) or type(exc).__name__
    return text if len(text) < 300 else text[:297] + '...'


def _opened(paths, typestore=None):
    from rosbags.highlevel import AnyReader
    reader = AnyReader(paths, default_typestore=typestore)
    reader.open()
    return reader


@contextmanager
def open_bag(path):
    """
    Return a rosbags AnyReader on PATH, open; BagError for what cannot be read.

    The bag's messages are read by its own type definitions (every ROS 1 bag, and rosbag2
    bags of recent recorders, carry them). Only one that AnyReader cannot open without is
    opened again with ROS 2 Jazzy's (a typesys store, built then: it takes longer than
    reading a small bag).
    """
    from rosbags.highlevel import AnyReaderError
    from rosbags.typesys import get_typestore, Stores
    paths = bag_paths(path)
    try:
        try:
            reader = _opened(paths)
        except AnyReaderError as exc:
            first = exc
            try:
                reader = _opened(paths, get_typestore(Stores.ROS2_JAZZY))
            except Exception:  # noqa: BLE001 - the first error says what is wrong
                raise first from None
    except Exception as exc:  # noqa: BLE001 - rosbags' errors vary by format and damage
        raise BagError(f'{path}: cannot read the bag: {_one_line(exc)}') from None
    try:
        yield reader
    finally:
        try:
            reader.close()
        except Exception:  # noqa: BLE001,S110 - closing a damaged bag may fail again
            pass


def storage_name(reader):
    """'rosbag1', 'rosbag2 sqlite3' or 'rosbag2 mcap'."""
    if not reader.is2:
        return 'rosbag1'
    paths = [Path(path) for path in reader.paths]
    suffixes = {p.suffix for path in paths
                for p in (path.iterdir() if path.is_dir() else [path])}
    names = [name for suffix, name in (('.db3', 'sqlite3'), ('.mcap', 'mcap'))
             if suffix in suffixes]
    return ' '.join(['rosbag2'] + names)


# ---------------------------------------------------------------------------------------
# Fields of message objects, as columns


def _members_getter(names):
    """Return get(value): the tuple of a field's members ('x', 'y'; or '[0]': one number)."""
    if names[0].startswith('['):
        return itemgetter(*(int(n.strip('[]')) for n in names))
    return attrgetter(*names)


def _field_getter(path):
    """Return get(msg): the field at ``path`` ('pose.position'; the last may be indexed)."""
    name, indexed, index = path.partition('[')
    get = attrgetter(name)
    if not indexed:
        return get
    k = int(index.rstrip(']'))
    return lambda msg: get(msg)[k]


class _Getter(NamedTuple):
    """How one column is read: the field at its path, then its members (None: a string)."""

    column: str
    field: object
    members: object
    dtype: type


class _Fields:
    """
    The columns read from the messages of one type, and how each is read.

    fields: {column: path}, the header's (:data:`HEADER`) added; covariance: (path, size) of
    an array read whole, or None; vectors: {column: path} of Vector3 fields read besides. A
    column is the stamp (sec, nanosec: int64), a string (a frame id), the numbers of a role's
    members (MEMBERS: float64) or of a Vector3 (:data:`VECTOR3`), or
    a whole float64 array (``covariance``).
    """

    def __init__(self, fields, covariance=None, vectors=None):
        self.getters = []
        self.vectors = dict(vectors or {})
        for column, path in {**HEADER, **fields, **self.vectors}.items():
            members = (STAMP_MEMBERS if column == 'stamp' else VECTOR3
                       if column in self.vectors else MEMBERS.get(column))
            self.getters.append(_Getter(column, _field_getter(path),
                                        members and _members_getter(members),
                                        np.int64 if column == 'stamp' else np.float64))
        if covariance:
            self.getters.append(_Getter('covariance', _field_getter(covariance[0]), None,
                                        np.float64))
        self.size = covariance[1] if covariance else None
        self.names = {getter.column for getter in self.getters}

    def columns(self, messages):
        """Return {column: values} of a list of message objects (numbers as NumPy arrays)."""
        out = {}
        for getter in self.getters:
            values = list(map(getter.field, messages))
            if getter.column == 'covariance':  # a whole array
                values = np.array(values, getter.dtype).reshape(len(values), -1)
            elif getter.members is not None:
                values = np.array(list(map(getter.members, values)), getter.dtype)
            out[getter.column] = values  # strings: a list
        return out


class Columns:
    """
    The fields of one topic's messages, one row per message, in the bag's order.

    record: (N,) int64, when the message was recorded (ns); sec, nanosec: (N,) int64, its
    header stamp; frame_ids: list of str, frame: (N,) index into it; child_frame_ids/child
    likewise for Odometry and TransformStamped (else None); orientation (N, 4) as
    (x, y, z, w); position (N, 3) or None; covariance0 (N,) (Imu's
    orientation_covariance[0]) or None; covariance (N, 9) or (N, 36), the orientation's
    covariance of the types of :data:`COVARIANCE`, row-major, or None; angular_velocity
    (N, 3) (Imu's gyro) or None; and an (N, 3) attribute per Vector3 field that
    :func:`read_topics` was asked for (``vectors``).
    """

    def __init__(self, topic, msgtype, record, sec, nanosec, frame_ids, frame,
                 child_frame_ids=None, child=None, orientation=None, position=None,
                 covariance0=None, covariance=None, angular_velocity=None):
        self.topic, self.msgtype, self.record = topic, msgtype, record
        self.sec, self.nanosec, self.frame_ids, self.frame = sec, nanosec, frame_ids, frame
        self.child_frame_ids, self.child = child_frame_ids, child
        self.orientation, self.position = orientation, position
        self.covariance0, self.covariance = covariance0, covariance
        self.angular_velocity = angular_velocity

    def __len__(self):
        return len(self.record)

    def stamps(self):
        """Header stamps in seconds (float64)."""
        return self.sec + 1e-9 * self.nanosec


class Chunk(NamedTuple):
    """Some messages of one topic, read: their record times (n,), {column: values}."""

    record: np.ndarray
    columns: dict


def _columns(topic, msgtype, chunks, fields):
    """Return the Columns of a topic's chunks [Chunk] of ``fields``, joined."""
    stamp = _join('stamp', chunks, fields)
    frames = _index([chunk.columns['frame_id'] for chunk in chunks])
    out = Columns(topic, msgtype, np.concatenate([chunk.record for chunk in chunks]
                                                 or [np.zeros(0, np.int64)]),
                  stamp[:, 0], stamp[:, 1], frames.values, frames.index)
    if 'child_frame_id' in fields.names:
        children = _index([chunk.columns['child_frame_id'] for chunk in chunks])
        out.child_frame_ids, out.child = children.values, children.index
    for name in ('orientation', 'position', 'covariance0', 'angular_velocity', 'covariance',
                 *fields.vectors):
        if name in fields.names:
            setattr(out, name, _join(name, chunks, fields))
    if out.covariance is not None and out.covariance.shape[1] != fields.size:
        out.covariance = None  # a bag's own definition of the type, with another size
    return out


class Strings(NamedTuple):
    """A column of strings: each distinct one listed once, and each row's index into them."""

    values: list
    index: np.ndarray


def _index(chunks):
    """Return the Strings of the strings of several chunks (lists), one row per string."""
    lookup = {}
    index = [lookup.setdefault(s, len(lookup)) for chunk in chunks for s in chunk]
    return Strings(list(lookup), np.array(index, np.intp))


def _join(name, chunks, fields):
    """Return column ``name`` of every chunk, joined."""
    width = len(STAMP_MEMBERS if name == 'stamp' else VECTOR3 if name in fields.vectors
                else MEMBERS.get(name) or ()) or fields.size
    empty = np.zeros((0, width) if width > 1 else (0,), np.int64 if name == 'stamp' else None)
    return np.concatenate([chunk.columns[name] for chunk in chunks] or [empty])


class _Topic:
    """One topic being read: its messages of the current chunk, and the chunks' columns."""

    def __init__(self, topic, msgtype, fields):
        self.topic, self.msgtype, self.fields = topic, msgtype, fields
        self.records, self.messages, self.chunks = [], [], []
        self.count = 0

    def index(self):
        """Return the index among the topic's messages of the next one added."""
        return self.count + len(self.messages)

    def add(self, record, message):
        self.records.append(record)
        self.messages.append(message)
        if len(self.messages) >= CHUNK:
            self.flush()

    def flush(self):
        if self.messages:
            self.chunks.append(Chunk(np.array(self.records, np.int64),
                                     self.fields.columns(self.messages)))
            self.count += len(self.messages)
        self.records, self.messages = [], []

    def finish(self):
        self.flush()
        return _columns(self.topic, self.msgtype, self.chunks, self.fields)


def fields_of(msgtype, vectors=None):
    """
    Return the _Fields read from messages of ``msgtype`` (one of SUPPORTED).

    vectors: {column: path} of Vector3 fields read besides (read_topics' ``vectors``).
    """
    return _Fields(SUPPORTED[msgtype], COVARIANCE.get(msgtype), vectors)


def bag_name(reader):
    """Return the path of the bag an open reader reads (a rosbag2 bag: its directory)."""
    return ', '.join(str(path) for path in reader.paths)


def _decode(reader, raw, conn, index):
    """
    Return the message object of ``raw``; BagError naming the bag and the message if not.

    index(): the message's index among its topic's (asked only then).
    """
    try:
        return reader.deserialize(raw, conn.msgtype)
    except Exception as exc:  # noqa: BLE001 - rosbags' serde errors vary
        raise BagError(f'{bag_name(reader)}: {conn.topic}: message {index()} cannot be decoded '
                       f'as {conn.msgtype}: {_one_line(exc)}') from None


def read_topics(reader, connections, start=None, stop=None, progress=None, vectors=None):
    """
    {topic: Columns} of the connections' messages between start and stop (ns, record time).

    ``progress(n)`` is called now and then with the number of messages read so far.
    ``vectors``: {type name: {column: path}}, Vector3 fields read besides a type's own, each
    an attribute ``column`` (N, 3) of its topics' Columns (an Imu's linear_acceleration for
    ``rot-tools imu-check``).
    """
    topics, by_id = {}, {}
    for conn in connections:
        if conn.topic not in topics:
            topics[conn.topic] = _Topic(conn.topic, conn.msgtype, fields_of(
                conn.msgtype, (vectors or {}).get(conn.msgtype)))
        by_id[conn.id] = topics[conn.topic]
    count = 0
    try:
        for conn, record, raw in reader.messages(connections=connections, start=start,
                                                 stop=stop):
            topic = by_id[conn.id]
            topic.add(record, _decode(reader, raw, conn, topic.index))
            count += 1
            if progress is not None and not count % CHUNK:
                progress(count)
    except BagError:
        raise
    except Exception as exc:  # noqa: BLE001 - a damaged bag fails inside rosbags' reader
        raise BagError(f'{bag_name(reader)}: cannot read the bag: {_one_line(exc)}') from None
    if progress is not None:
        progress(count)
    if start is None and stop is None:
        _check_complete(reader, connections, topics)
    return {name: topic.finish() for name, topic in topics.items()}


def _check_complete(reader, connections, topics):
    """
    Raise BagError if a topic read whole gave fewer messages than the bag's index lists.

    A damaged chunk of an MCAP file can be skipped by the reader without an error: the count
    the bag's index (or metadata.yaml) holds is the only sign of it.
    """
    for name, topic in topics.items():
        listed = sum(conn.msgcount for conn in connections if conn.topic == name)
        if topic.index() < listed:
            raise BagError(f'{bag_name(reader)}: {name}: {topic.index()} of the {listed} '
                           'messages its index lists could be read: the bag is damaged')


# ---------------------------------------------------------------------------------------
# TF


class TfColumns(NamedTuple):
    """
    The transforms of a bag's TFMessage topics, in the order they were read (read_tf).

    columns: Columns of the transforms (as TransformStamped: header, child frame,
    position, orientation), one row each; static (N,) bool: from a /tf_static-like topic
    (its name ends in 'static').
    """

    columns: Columns
    static: np.ndarray


def read_tf(reader, static, dynamic, start=None, stop=None):
    """
    Return TfColumns of the transforms of TFMessage connections.

    ``static`` connections are read whole, ``dynamic`` ones between start and stop (ns,
    record time), static ones first.
    """
    topic = _Topic('tf', TF_TYPE, _Fields(TF_FIELDS))
    kinds, count = [], 0
    try:
        for connections, lo, hi in ((static, None, None), (dynamic, start, stop)):
            if not connections:
                continue
            for conn, record, raw in reader.messages(connections=connections, start=lo,
                                                     stop=hi):
                transforms = _decode(reader, raw, conn, lambda: count).transforms
                count += 1
                kinds += [connections is static] * len(transforms)
                for transform in transforms:
                    topic.add(record, transform)
    except BagError:
        raise
    except Exception as exc:  # noqa: BLE001 - a damaged bag fails inside rosbags
        raise BagError(f'{bag_name(reader)}: cannot read the bag: {_one_line(exc)}') from None
    return TfColumns(topic.finish(), np.array(kinds, bool))
