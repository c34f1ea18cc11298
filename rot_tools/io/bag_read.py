"""
Reading the orientation fields of recorded bags into NumPy columns, without ROS.

The bags are read by the ``rosbags`` library (the optional ``bag`` extra): rosbag2 (sqlite3
and MCAP) and ROS 1 bags. Its reader hands over each message's raw bytes; turning every one
into a Python message object (rosbags' deserialiser) costs far more than the rest of
``rot-tools bag``. The types read here have a fixed layout once their strings' lengths are
known: no sequences, only numbers, fixed arrays, nested messages and strings. So, as
rosbags' own generated deserialisers do, the layout is computed from the type's field
definitions (the bag's own, which rosbags parses) — alignment as CDR wants it for rosbag2,
none for ROS 1 — but for a whole chunk of messages at once: the messages of one topic with
the same byte length and the same string lengths are rows of one (n, length) byte array,
and each needed field is a column of it, read with NumPy (``ndarray.view``). A chunk whose
layout does not come out exactly (a big-endian CDR message, a length that does not add
up) goes through rosbags' deserialiser message by message instead, which also is the
reference the tests compare the fast path with.

:func:`open_bag` opens PATH (a ROS 1 ``.bag`` file, a rosbag2 directory, or a file inside
one) and :func:`read_topics` returns a :class:`Columns` per topic: record times, header
stamps (sec, nanosec), frame ids, and the fields its boundary check and conversions need.
Every failure of the bag itself — missing, empty, corrupt — is a :class:`BagError` with one
line of text.
"""

from contextlib import contextmanager
from itertools import islice
from operator import attrgetter
from pathlib import Path
import stat

import numpy as np
from rot_tools.io import interface

SUPPORTED = interface.recorded_inputs()
"""The message types read — rotation_node's inputs with an orientation — and where their
fields are: column (a role of rot_tools.io.interface.MEMBERS) → field path."""

COVARIANCE = {row.type_name: row.covariance for row in interface.INPUTS
              if row.covariance and row.type_name in SUPPORTED}
"""The types read that carry their orientation's covariance: type name → (path, size) of
the float64 array, read whole as the column ``covariance`` (N, size), row-major."""

TF_TYPE = 'tf2_msgs/msg/TFMessage'
"""Read only with --tf (the transforms of /tf and /tf_static feed a transform tree)."""

_HEADER = {'sec': 'header.stamp.sec', 'nanosec': 'header.stamp.nanosec',
           'frame_id': 'header.frame_id'}
_COLUMN_SHAPE = {role: parts for role, parts in interface.MEMBERS.items()
                 if parts is not None and len(parts) > 1}
"""The columns of several components, and the field members of each (x, y, z, w)."""


def wanted_fields(msgtype):
    """Return [(column, field path)] read from each message of msgtype, in no set order."""
    out = list({**_HEADER, **SUPPORTED[msgtype]}.items())
    if msgtype in COVARIANCE:
        out.append(('covariance', COVARIANCE[msgtype][0]))
    return out


CHUNK = 1 << 15
"""Messages read at a time; each topic's among them are parsed together, then dropped."""

_SIZES = {'bool': 1, 'byte': 1, 'char': 1, 'int8': 1, 'uint8': 1, 'int16': 2, 'uint16': 2,
          'int32': 4, 'uint32': 4, 'float32': 4, 'int64': 8, 'uint64': 8, 'float64': 8}
_KINDS = {'bool': 'u', 'byte': 'u', 'char': 'u', 'int8': 'i', 'uint8': 'u', 'int16': 'i',
          'uint16': 'u', 'int32': 'i', 'uint32': 'u', 'float32': 'f', 'int64': 'i',
          'uint64': 'u', 'float64': 'f'}


BAG_SUFFIXES = ('.bag', '.db3', '.mcap')
"""Files read as a bag outside a rosbag2 directory: ROS 1, and rosbag2's storage files."""


class BagError(Exception):
    """A bag that cannot be read as asked: one line of text for the user."""


def rosbags_missing():
    """Return the name of the missing module when rosbags cannot be imported, else None."""
    try:
        import rosbags.highlevel  # noqa: F401
    except ImportError as exc:
        return exc.name or 'rosbags'
    return None


# ---------------------------------------------------------------------------------------
# Opening a bag


def bag_paths(path):
    """
    Return the paths rosbags opens for PATH: [a .bag file] or [a rosbag2 directory].

    A file inside a rosbag2 directory stands for the directory. Anything else — missing, not
    a regular file nor a directory (a FIFO would block the reader for ever), empty, a file
    that is neither a ROS 1 bag nor in a rosbag2 directory — is a BagError, before opening.
    """
    path = Path(path)
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        raise BagError(f'{path}: no such file or directory') from None
    except OSError as exc:
        raise BagError(f'{path}: cannot be read: {exc.strerror or exc}') from None
    if not (stat.S_ISREG(mode) or stat.S_ISDIR(mode)):
        raise BagError(f'{path}: not a regular file or a directory')
    if stat.S_ISDIR(mode):
        if not (path / 'metadata.yaml').exists():
            raise BagError(f'{path}: a directory without metadata.yaml is not a rosbag2 bag')
        return [path]
    if path.suffix != '.bag' and (path.parent / 'metadata.yaml').exists():
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


@contextmanager
def open_bag(path):
    """Return a rosbags AnyReader on PATH, open; BagError for what cannot be read."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import get_typestore, Stores
    paths = bag_paths(path)
    try:
        reader = AnyReader(paths, default_typestore=get_typestore(Stores.ROS2_JAZZY))
        reader.open()
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
    suffixes = {p.suffix for path in reader.paths for p in Path(path).iterdir()}
    names = [name for suffix, name in (('.db3', 'sqlite3'), ('.mcap', 'mcap'))
             if suffix in suffixes]
    return ' '.join(['rosbag2'] + names)


# ---------------------------------------------------------------------------------------
# Layouts: the leaves of a message type, in serialisation order


class _Unsupported(Exception):
    """A type with a field of no fixed layout (a sequence): parsed by rosbags instead."""


def _leaves(typestore, typename, prefix=''):
    """[(path, kind, base, count)] of a type: kind 'prim' (count numbers) or 'string'."""
    out = []
    for name, (nodetype, desc) in typestore.fielddefs[typename][1]:
        path = prefix + name
        kind = getattr(nodetype, 'name', str(nodetype))
        if kind == 'NAME':
            out.extend(_leaves(typestore, desc, path + '.'))
        elif kind == 'BASE':
            base = desc[0]
            if base == 'string':
                out.append((path, 'string', base, 1))
            elif base in _SIZES:
                out.append((path, 'prim', base, 1))
            else:
                raise _Unsupported(f'{path}: {base}')
        elif kind == 'ARRAY':
            (sub_kind, sub_desc), count = desc
            if getattr(sub_kind, 'name', '') == 'BASE' and sub_desc[0] in _SIZES:
                out.append((path, 'prim', sub_desc[0], count))
            elif getattr(sub_kind, 'name', '') == 'NAME':
                for i in range(count):
                    out.extend(_leaves(typestore, sub_desc, f'{path}[{i}].'))
            else:
                raise _Unsupported(path)
        else:
            raise _Unsupported(path)
    return out


class _Layout:
    """How to read the needed leaves of one type from rows of raw bytes."""

    def __init__(self, typestore, typename, cdr):
        self.leaves = _leaves(typestore, typename)
        self.cdr = cdr
        by_path = {}  # field path -> the columns read from it
        for name, path in wanted_fields(typename):
            by_path.setdefault(path, []).append(name)
        self.wanted = {}  # leaf path -> [(column, component index or None)]
        for path, _, _, count in self.leaves:
            parent, _, last = path.rpartition('.')
            if path in by_path:
                if 'covariance' in by_path[path] and count != COVARIANCE[typename][1]:
                    raise _Unsupported(f'{path}: {count} numbers')
                self.wanted[path] = [(name, None) for name in by_path[path]]
            elif parent in by_path:
                self.wanted[path] = [(name, _COLUMN_SHAPE[name].index(last))
                                     for name in by_path[parent] if name in _COLUMN_SHAPE]
        found = {name for columns in self.wanted.values() for name, _ in columns}
        missing = {name for names in by_path.values() for name in names} - found
        if missing:
            raise _Unsupported(f'no field for {sorted(missing)}')

    def read(self, rows):
        """{column: array} of rows (n, length) uint8, or None where the layout fails."""
        n, length = rows.shape
        if self.cdr:
            if length < 4 or not ((rows[:, 0] == 0) & (rows[:, 1] == 1)).all():
                return None  # not little-endian CDR
            start = 4
        else:
            start = 0
        out = {}
        if not self._walk(rows, start, 0, out, np.arange(n)):
            return None
        return out

    def _walk(self, rows, pos, first, out, index):
        """Read leaves[first:] from byte pos on; split rows where a string length differs."""
        n, length = rows.shape
        origin = 4 if self.cdr else 0
        for k in range(first, len(self.leaves)):
            path, kind, base, count = self.leaves[k]
            if kind == 'string':
                if self.cdr:
                    pos += -(pos - origin) % 4
                if pos + 4 > length:
                    return False
                lens = rows[:, pos:pos + 4].copy().view('<u4')[:, 0]
                if (lens != lens[0]).any():  # a different layout for each length
                    for value in np.unique(lens):
                        part = lens == value
                        if not self._walk(rows[part], pos, k, out, index[part]):
                            return False
                    return True
                size = int(lens[0])
                end = pos + 4 + size
                if end > length:
                    return False
                for name, _ in self.wanted.get(path, ()):
                    text = rows[:, pos + 4:end]
                    if self.cdr and size:
                        text = text[:, :-1]  # the terminating NUL
                    _put_strings(out, name, text, index)
                pos = end
            else:
                size = _SIZES[base]
                if self.cdr:
                    pos += -(pos - origin) % size
                end = pos + size * count
                if end > length:
                    return False
                for name, part in self.wanted.get(path, ()):
                    dtype = np.dtype(f'<{_KINDS[base]}{size}')
                    if name == 'covariance':  # the whole array: (n, count)
                        values = np.ascontiguousarray(rows[:, pos:end]).view(dtype)
                    else:  # a number, or an array's first (covariance0)
                        values = np.ascontiguousarray(rows[:, pos:pos + size]).view(dtype)[:, 0]
                    out.setdefault(name, []).append((index, part, values))
                pos = end
        padding = length - pos
        return padding == 0 or (self.cdr and 0 <= padding < 4)


def _put_strings(out, name, text, index):
    """Store the strings of rows ``index`` (m, size bytes) into column ``name``."""
    if text.shape[1] == 0:
        uniques, inverse = [b''], np.zeros(len(index), np.intp)
    else:
        flat = np.ascontiguousarray(text).view(f'V{text.shape[1]}')[:, 0]
        values, inverse = np.unique(flat, return_inverse=True)
        uniques = [v.tobytes() for v in values]
    out.setdefault(name, []).append((index, None, (uniques, inverse.reshape(-1))))


# ---------------------------------------------------------------------------------------
# Columns of one topic


class Columns:
    """
    The fields of one topic's messages, one row per message, in the bag's order.

    record: (N,) int64 ns, when the message was recorded; sec, nanosec: (N,) int64, its
    header stamp; frame_ids: list of str, frame: (N,) index into it; child_frame_ids/child
    likewise for Odometry and TransformStamped (else None); orientation (N, 4) as
    (x, y, z, w); position (N, 3) or None; covariance0 (N,) (Imu's
    orientation_covariance[0]) or None; covariance (N, 9) or (N, 36), the orientation's
    covariance of the types of :data:`COVARIANCE`, row-major, or None; angular_velocity
    (N, 3) (Imu's gyro) or None.
    """

    def __init__(self, topic, msgtype):
        self.topic, self.msgtype = topic, msgtype
        self._parts = []

    def add(self, record, fields):
        self._parts.append((record, fields))

    def finish(self):
        """Concatenate the chunks read into the columns."""
        parts, self._parts = self._parts, None
        self.record = np.concatenate([p[0] for p in parts]) if parts else np.zeros(0, np.int64)
        names = {name for name, _ in wanted_fields(self.msgtype)}
        for name in sorted(names):
            if name in ('frame_id', 'child_frame_id'):
                strings, index = _join_strings([p[1][name] for p in parts])
                setattr(self, 'frame_ids' if name == 'frame_id' else 'child_frame_ids', strings)
                setattr(self, 'frame' if name == 'frame_id' else 'child', index)
            else:
                dtype = np.int64 if name in ('sec', 'nanosec') else np.float64
                width = (COVARIANCE[self.msgtype][1] if name == 'covariance'
                         else len(_COLUMN_SHAPE.get(name, ())))
                shape = (0, width) if width else (0,)
                arrays = [np.asarray(p[1][name], dtype) for p in parts]
                setattr(self, name, np.concatenate(arrays) if arrays else np.zeros(shape, dtype))
        for name in ('position', 'covariance0', 'covariance', 'angular_velocity'):
            if name not in names:
                setattr(self, name, None)
        if self.covariance is not None and self.covariance.shape[1:] != (
                COVARIANCE[self.msgtype][1],):
            self.covariance = None  # a bag's own definition of the type, with another size
        if 'child_frame_id' not in names:
            self.child_frame_ids = self.child = None
        return self

    def __len__(self):
        return len(self.record)

    def stamps(self):
        """Header stamps in seconds (float64)."""
        return self.sec + 1e-9 * self.nanosec


def _join_strings(parts):
    """
    Join several (strings, index) chunks into one.

    (strings, index) of several (strings, index) chunks (bytes from the fast path, str
    from rosbags' decoder: the same frame id is one string either way).
    """
    lookup, indices = {}, []
    for chunk_strings, chunk_index in parts:
        remap = np.array([lookup.setdefault(_text(s), len(lookup)) for s in chunk_strings],
                         np.intp)
        indices.append(remap[chunk_index] if len(chunk_index) else chunk_index)
    index = np.concatenate(indices) if indices else np.zeros(0, np.intp)
    return list(lookup), index


def _text(s):
    return s.decode('utf-8', 'replace') if isinstance(s, bytes) else s


def _assemble(pieces, n, msgtype):
    """{column: array (n, ...)} from the pieces of the layout walk (rows in any order)."""
    out = {}
    for name, items in pieces.items():
        if name in ('frame_id', 'child_frame_id'):
            lookup, index = {}, np.empty(n, np.intp)
            for rows, _, (uniques, inverse) in items:
                remap = np.array([lookup.setdefault(u, len(lookup)) for u in uniques], np.intp)
                index[rows] = remap[inverse]
            out[name] = (list(lookup), index)
            continue
        parts = _COLUMN_SHAPE.get(name)
        width = (len(parts),) if parts else items[0][2].shape[1:]  # (count,): covariance
        column = np.empty((n,) + width, np.float64 if name not in (
            'sec', 'nanosec') else np.int64)
        for rows, part, values in items:
            if part is None:
                column[rows] = values
            else:
                column[rows, part] = values
        out[name] = column
    return out


def _get(obj, path):
    for name in path.split('.'):
        obj = getattr(obj, name)
    return obj


def fields_of_objects(messages, msgtype):
    """Return the columns of deserialised message objects (the reference of the fast path)."""
    out = {}
    for name, path in wanted_fields(msgtype):
        parts = _COLUMN_SHAPE.get(name)
        values = [_get(m, path) for m in messages]
        if name in ('frame_id', 'child_frame_id'):
            lookup = {}
            index = np.array([lookup.setdefault(v, len(lookup)) for v in values], np.intp)
            out[name] = (list(lookup), index)
        elif parts:
            out[name] = np.array([[getattr(v, p) for p in parts] for v in values],
                                 np.float64).reshape(-1, len(parts))
        elif name == 'covariance0':
            out[name] = np.array([v[0] for v in values], np.float64)
        elif name == 'covariance':
            size = COVARIANCE[msgtype][1]
            out[name] = np.array([np.ravel(v) for v in values], np.float64).reshape(
                len(values), -1) if values else np.zeros((0, size))
        else:
            out[name] = np.array(values, np.int64)
    return out


class _TopicReader:
    """Parses one topic's raw messages, a chunk at a time, into Columns."""

    def __init__(self, reader, topic, msgtype, fast=True):
        self.reader, self.msgtype = reader, msgtype
        self.columns = Columns(topic, msgtype)
        self.count = 0
        self.layout = None
        if fast:
            try:
                self.layout = _Layout(reader.typestore, msgtype, cdr=reader.is2)
            except (_Unsupported, KeyError):
                self.layout = None

    def add(self, raw, times):
        fields = self._fast(raw) if self.layout is not None else None
        if fields is None:
            fields = fields_of_objects(self._deserialise(raw), self.msgtype)
        self.columns.add(np.asarray(times, np.int64), fields)
        self.count += len(raw)

    def _fast(self, raw):
        """Return the fields of raw messages by their layout, None if any group fails."""
        n = len(raw)
        lengths = np.fromiter(map(len, raw), np.int64, n)
        pieces = {}
        for length in np.unique(lengths):
            index = np.flatnonzero(lengths == length)
            if len(index) == n:
                data = b''.join(raw)
            else:
                data = b''.join([raw[i] for i in index])
            rows = np.frombuffer(data, np.uint8).reshape(len(index), int(length))
            out = self.layout.read(rows)
            if out is None:
                return None
            for name, items in out.items():
                pieces.setdefault(name, []).extend(
                    (index[rows_], part, values) for rows_, part, values in items)
        return _assemble(pieces, n, self.msgtype)

    def _deserialise(self, raw):
        out = []
        for k, data in enumerate(raw):
            try:
                out.append(self.reader.deserialize(data, self.msgtype))
            except Exception as exc:  # noqa: BLE001 - rosbags' serde errors vary
                raise BagError(f'{self.columns.topic}: message {self.count + k} cannot be '
                               f'decoded as {self.msgtype}: {_one_line(exc)}') from None
        return out


def _messages(reader, connections, start, stop):
    """Return rosbags' message generator; one bag's own reader when there is one."""
    if len(reader.readers) == 1:
        return reader.readers[0].messages(connections=connections, start=start, stop=stop)
    return reader.messages(connections=connections, start=start, stop=stop)


def read_topics(reader, connections, start=None, stop=None, fast=True, progress=None):
    """
    {topic: Columns} of the connections' messages between start and stop (ns, record time).

    ``fast=False`` decodes every message with rosbags (the reference). ``progress(n)`` is
    called now and then with the number of messages read so far.
    """
    readers, by_id = {}, {}
    for conn in connections:
        topic_reader = readers.get(conn.topic)
        if topic_reader is None:
            topic_reader = readers[conn.topic] = _TopicReader(reader, conn.topic, conn.msgtype,
                                                              fast)
        by_id[conn.id] = topic_reader
    count = 0
    try:
        messages = _messages(reader, connections, start, stop)
        while True:
            chunk = list(islice(messages, CHUNK))
            if not chunk:
                break
            conns, times, raws = zip(*chunk)
            ids = np.fromiter(map(attrgetter('id'), conns), np.int64, len(chunk))
            unique = np.unique(ids)
            if len(unique) == 1:
                by_id[int(unique[0])].add(raws, times)
            else:
                for conn_id in unique:
                    index = np.flatnonzero(ids == conn_id).tolist()
                    by_id[int(conn_id)].add([raws[i] for i in index], [times[i] for i in index])
            count += len(chunk)
            if progress is not None:
                progress(count)
    except BagError:
        raise
    except Exception as exc:  # noqa: BLE001 - a damaged bag fails inside rosbags' reader
        raise BagError(f'cannot read the bag: {_one_line(exc)}') from None
    return {topic: r.columns.finish() for topic, r in readers.items()}


def read_tf(reader, connections, start=None, stop=None):
    """
    Return the transforms of TFMessage connections as columns, in the order they were recorded.

    Returns a dict: static (N,) bool (from a /tf_static-like topic: its name ends in
    'static'), parent/child (N,) indices into frames (list), sec, nanosec (N,), position
    (N, 3), orientation (N, 4), topic (N,) index into topics (list).
    """
    frames, topics = {}, {}
    rows = []
    try:
        for conn, _, raw in reader.messages(connections=connections, start=start, stop=stop):
            msg = reader.deserialize(raw, conn.msgtype)
            t_index = topics.setdefault(conn.topic, len(topics))
            for tf in msg.transforms:
                t, q, stamp = tf.transform.translation, tf.transform.rotation, tf.header.stamp
                rows.append((t_index, frames.setdefault(tf.header.frame_id, len(frames)),
                             frames.setdefault(tf.child_frame_id, len(frames)),
                             stamp.sec, stamp.nanosec, t.x, t.y, t.z, q.x, q.y, q.z, q.w))
    except Exception as exc:  # noqa: BLE001 - a damaged bag fails inside rosbags
        raise BagError(f'cannot read the bag: {_one_line(exc)}') from None
    table = np.array(rows, np.float64).reshape(-1, 12)
    ints = table[:, :5].astype(np.int64)
    topic_names = list(topics)
    return {'topics': topic_names, 'topic': ints[:, 0], 'frames': list(frames),
            'parent': ints[:, 1], 'child': ints[:, 2], 'sec': ints[:, 3],
            'nanosec': ints[:, 4], 'position': table[:, 5:8], 'orientation': table[:, 8:12],
            'static': np.array([topic_names[i].endswith('static') for i in ints[:, 0]], bool)}


def join_tf(parts):
    """One read_tf result of several (frames and topics renumbered)."""
    frames, topics, out = {}, {}, []
    for part in parts:
        fmap = np.array([frames.setdefault(f, len(frames)) for f in part['frames']] or [0])
        tmap = np.array([topics.setdefault(t, len(topics)) for t in part['topics']] or [0])
        out.append({**part, 'parent': fmap[part['parent']], 'child': fmap[part['child']],
                    'topic': tmap[part['topic']]})
    joined = {'frames': list(frames), 'topics': list(topics)}
    for key in ('topic', 'parent', 'child', 'sec', 'nanosec', 'static'):
        joined[key] = np.concatenate([p[key] for p in out]) if out else np.zeros(0, np.int64)
    for key, width in (('position', 3), ('orientation', 4)):
        joined[key] = (np.concatenate([p[key] for p in out]) if out
                       else np.zeros((0, width)))
    return joined
