"""
The analysis of ``rot-tools bag``: the orientations recorded in a bag, topic by topic.

A topic's messages are read into NumPy columns (rot_tools.io.bag_read), pass the same boundary
as rotation_node's inputs (rot_tools.io.boundary: same checks, same refusal reasons, counted
per topic), and are converted as batches by the vectorised engine: one call of each
conversion per topic, never one per message. Per accepted message, with R its rotation:

- the canonical quaternion (rot_tools.matrix_to_quaternion: w > 0);
- roll, pitch, yaw: REP-103's angles about the fixed X, Y, Z axes (the extrinsic sequence
  rot_tools.core.euler.RPY_SEQUENCE), and the angles of ``--seq SEQ`` when asked; each made
  continuous along the topic's stream with numpy.unwrap (so a heading goes on past ±180°
  instead of jumping), unless ``--wrap``;
- the rotation vector and angle of R (rot_tools.matrix_to_axis_angle);
- the body angular velocity from the previous accepted message of the topic:
  ω = log(Rₖ₋₁ᵀ·Rₖ)/Δt, Δt from the header stamps (none on the first row, nor where Δt ≤ 0).

Per topic the summary adds the messages' start, end and mean rate (header stamps of every
message read; start and end with every digit of their float64, whatever ``--precision``
rounds the other numbers to: rot_tools.io.report.Exact), the ranges of roll, pitch and yaw,
the total angle turned (the sum of the angles of the steps Rₖ₋₁ᵀ·Rₖ), the chordal mean
orientation (rot_tools.mean_rotation), and for an Imu the RMS of |ω − ω_gyro|, ω_gyro the
mean of the gyro's angular_velocity at the step's two ends: a check of the IMU's own
consistency.

For the types that carry their orientation's covariance (Imu, PoseWithCovarianceStamped,
Odometry), each message's standard deviations of roll, pitch and yaw, and per topic their
median and the counts of unknown and bad covariances (rot_tools.cli.bag_covariance; read as
``--input-covariance`` says, as rotation_node's parameter input_covariance).

Messages are taken in the order they were recorded; ``--start``/``--end`` select them by
record time, in seconds from the bag's start.

``--tf REFERENCE BODY``: the transforms of the bag's TFMessage topics pass the same boundary
(counted) and feed a rot_tools.TransformTree, which follows BODY in REFERENCE over the
recording (TransformTree.follow: the chain looked up as one batch at every stamp of its
dynamic edges); it is one more topic, ``tf:REFERENCE->BODY``.
"""

import math
import sys
import time
from typing import NamedTuple

import numpy as np
from rot_tools.cli import bag_covariance
from rot_tools.cli.bag_output import in_unit, NS_PER_S
from rot_tools.core import transform_tree
from rot_tools.core.axis_angle import matrix_to_axis_angle, matrix_to_rotvec
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import matrix_to_euler, RPY_SEQUENCE
from rot_tools.core.fitting import mean_rotation
from rot_tools.core.so3 import matrix_to_quaternion
from rot_tools.io import bag_read, boundary
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.io.report import Exact

TF_REASONS = (transform_tree.BAD_FRAME, transform_tree.LOOP, transform_tree.TOO_MANY_FRAMES)
"""Refusals of a TF transform besides the boundary's: the tree's, counted as rotation_node
counts them (an empty frame name, a loop, a tree full of frames), and the analysis goes on."""

_TF_CODE = {reason: len(boundary.REFUSAL_REASONS) + 1 + k for k, reason in enumerate(TF_REASONS)}


class TfChain(NamedTuple):
    """
    BODY followed in REFERENCE through the bag's TF (:func:`tf_topic`).

    R (n, 3, 3): the lookups' rotations; frames: the chain of frames (or the list of the
    chains, in time order, when a frame was re-parented); codes: every TF transform's reason
    code (boundary.ACCEPTED, a boundary refusal, or one of TF_REASONS after them);
    transforms: their Columns; texts: {transform index: why the tree refused it}.
    """

    R: np.ndarray
    frames: list
    codes: np.ndarray
    transforms: bag_read.Columns
    texts: dict


class TfTopic(NamedTuple):
    """The topic ``tf:REFERENCE->BODY``: its Columns (the lookups) and its TfChain."""

    columns: bag_read.Columns
    chain: TfChain


class Topic:
    """One topic's accepted messages and everything computed from them (radians)."""

    def __init__(self, columns, tolerance, seq=None, wrap=False, chain=None, reading='rotvec'):
        self.columns = c = columns
        self.topic, self.msgtype = c.topic, c.msgtype
        self.tolerance = tolerance
        self.chain = chain
        if chain is None:
            verdict = boundary.check_batch(c.orientation, tolerance, c.position, c.covariance0)
            self.codes = verdict.code
            self.ok = self.codes == boundary.ACCEPTED
            self.R = boundary.accepted_rotations(c.orientation, verdict.norm, self.codes)
        else:  # a TF chain: its lookups, all made; the transforms' refusals are chain.codes
            self.codes = chain.codes
            self.ok = np.ones(len(c), bool)
            self.R = chain.R
        ok, n = self.ok, len(self.R)
        self.ns, self.frame = stamp_ns(c.sec[ok], c.nanosec[ok]), c.frame[ok]
        self.position = c.position[ok] if c.position is not None else np.zeros((n, 3))
        self.quaternion = matrix_to_quaternion(self.R, check=False)
        self.rpy = self._angles(RPY_SEQUENCE, wrap)
        self.seq = seq
        self.seq_angles = self._angles(seq, wrap) if seq else None
        axis, self.angle = matrix_to_axis_angle(self.R, check=False)
        self.rotvec = axis * self.angle[:, None]
        self.omega = np.full((n, 3), np.nan)
        self.steps = np.zeros(0)
        if n > 1:
            D = np.einsum('nji,njk->nik', self.R[:-1], self.R[1:])
            step = matrix_to_rotvec(D, check=False)
            self.steps = np.linalg.norm(step, axis=1)
            dt = 1e-9 * np.diff(self.ns)
            good = dt > 0
            self.omega[1:][good] = step[good] / dt[good][:, None]
        self.gyro_rms = None
        if c.angular_velocity is not None and n > 1:
            gyro = c.angular_velocity[ok]
            diff = self.omega[1:] - 0.5 * (gyro[:-1] + gyro[1:])
            diff = diff[np.isfinite(self.omega[1:, 0])]
            if len(diff):
                self.gyro_rms = float(np.sqrt(np.mean(np.sum(diff * diff, axis=1))))
        self.reading = reading
        self.rpy_std, self.covariance_status = np.full((n, 3), np.nan), None
        if chain is None and c.covariance is not None:
            self.covariance = c.covariance[ok]
            self.rpy_std, self.covariance_status = bag_covariance.stddevs(
                self.R, self.covariance, reading)

    def _angles(self, seq, wrap):
        angles = matrix_to_euler(self.R, seq, check=False)[0]
        return angles if wrap or not len(angles) else np.unwrap(angles, axis=0)

    def refused(self):
        """{'total': n, reason: n, ...} over every reason of the boundary."""
        reasons = boundary.REFUSAL_REASONS + (TF_REASONS if self.chain is not None else ())
        counts = np.bincount(self.codes, minlength=len(reasons) + 1)
        return {'total': int(counts[1:].sum()),
                **{r: int(counts[k + 1]) for k, r in enumerate(reasons)}}

    def first_refusal(self):
        """Return the sentence of the first refused message (what and by how much), or None."""
        bad = np.flatnonzero(self.codes != boundary.ACCEPTED)
        if not len(bad):
            return None
        k, c = int(bad[0]), self.columns if self.chain is None else self.chain.transforms
        if self.chain is not None and k in self.chain.texts:
            return self.chain.texts[k]
        q = c.orientation[k]
        norm = boundary.check_batch(q[None], self.tolerance).norm
        position = c.position[k] if c.position is not None else None
        fields = (bag_read.TF_FIELDS if self.chain is not None
                  else bag_read.SUPPORTED[self.msgtype])
        return boundary.batch_refusal_text(fields, int(self.codes[k]), q, float(norm[0]),
                                           self.tolerance, position)


def stamp_ns(sec, nanosec):
    """Return header stamps as int64 nanoseconds, sec·10⁹ + nanosec: exact, negative ones too."""
    return np.asarray(sec, np.int64) * NS_PER_S + np.asarray(nanosec, np.int64)


def topic_summary(t, degrees):
    """Return the summary of one Topic as plain data (angles in degrees when ``degrees``)."""
    c = t.columns
    out = {'type': t.msgtype, 'frame_ids': list(c.frame_ids)}
    if c.child_frame_ids is not None:
        out['child_frame_ids'] = list(c.child_frame_ids)
    if t.chain is not None:
        out['chain'] = t.chain.frames
        out['transforms'] = len(t.codes)
        out['accepted'] = int((t.codes == boundary.ACCEPTED).sum())
        out['refused'] = t.refused()
        out['lookups'] = len(c)
    else:
        out['messages'] = len(c)
        out['accepted'] = int(t.ok.sum())
        out['refused'] = t.refused()
    refusal = t.first_refusal()
    if refusal is not None:
        out['first_refusal'] = refusal
    if len(c):
        ns = stamp_ns(c.sec, c.nanosec)
        first, last = int(ns.min()), int(ns.max())
        out['start'], out['end'] = Exact(first / NS_PER_S), Exact(last / NS_PER_S)
        out['duration'] = (last - first) / NS_PER_S
        out['rate'] = (len(c) - 1) / out['duration'] if last > first else None
    if not len(t.R):
        return out
    unit = 'deg' if degrees else 'rad'
    out['unit'] = unit
    out['rpy_range'] = {
        name: in_unit([float(t.rpy[:, k].min()), float(t.rpy[:, k].max())], degrees).tolist()
        for k, name in enumerate(('roll', 'pitch', 'yaw'))}
    out['total_angle'] = float(in_unit(t.steps.sum(), degrees))
    try:
        mean = mean_rotation(t.R, check=False)
    except RotationError as exc:
        out['mean_orientation'] = f'not unique: {exc}'
    else:
        q = matrix_to_quaternion(mean)
        rpy = in_unit(matrix_to_euler(mean, RPY_SEQUENCE)[0], degrees)
        out['mean_orientation'] = {
            'quaternion': dict(zip('xyzw', map(float, q))),
            'rpy': dict(zip(('roll', 'pitch', 'yaw'), map(float, rpy)))}
    if t.gyro_rms is not None:
        out['gyro_rms_difference'] = float(in_unit(t.gyro_rms, degrees))
        out['gyro_rms_difference_unit'] = f'{unit}/s'
    if t.covariance_status is not None:
        out.update(bag_covariance.summary(t.rpy_std, t.covariance_status, t.covariance,
                                          t.reading, degrees))
    return out


def failure(path, exc):
    """
    Return the one line that says why the bag at PATH failed, beginning with PATH.

    A BagError's text (what is wrong with the bag); any other exception is rot-tools' own
    fault on this bag, named by its type and text, so that one bag's failure is one line and
    never a traceback.
    """
    if isinstance(exc, bag_read.BagError):
        text = str(exc)
    else:
        said = ' '.join(str(exc).split())
        text = (f'unexpected {type(exc).__name__}{": " if said else ""}{said[:300]} (a fault '
                'of rot-tools on this bag: please report it)')
    return text if text.startswith(f'{path}:') else f'{path}: {text}'


def summary(path, storage, topics, degrees):
    """Return the whole summary: the bag, then each topic."""
    return {'bag': str(path), 'storage': storage,
            'topics': {t.topic: topic_summary(t, degrees) for t in topics}}


# ---------------------------------------------------------------------------------------
# Progress


class Progress:
    """A one-line progress bar on a terminal stream; nothing at all on anything else."""

    def __init__(self, total, stream=None):
        self.stream = sys.stderr if stream is None else stream
        isatty = getattr(self.stream, 'isatty', None)
        self.active = bool(total) and isatty is not None and isatty()
        self.total, self.last = total, 0.0

    def __call__(self, count):
        if not self.active:
            return
        now = time.monotonic()
        if now - self.last < 0.1 and count < self.total:
            return
        self.last = now
        share = min(1.0, count / self.total)
        bar = '#' * int(30 * share)
        self.stream.write(f'\rrot-tools bag: [{bar:<30}] {100 * share:3.0f}% '
                          f'{count}/{self.total} messages')
        self.stream.flush()

    def done(self):
        if self.active:
            self.stream.write('\r' + ' ' * 79 + '\r')
            self.stream.flush()


# ---------------------------------------------------------------------------------------
# Reading a bag


def _listed(names, most=20):
    """Return names joined by commas, the first ``most`` of them and how many more."""
    names = list(names)
    more = f' and {len(names) - most} more' if len(names) > most else ''
    return ', '.join(names[:most]) + more


def tf_frames_hint(reader, connections):
    """
    Return the words that tell how to read a bag's TF: --tf PARENT CHILD, and its frames.

    connections: its TFMessage connections. The frames are every transform's parent and child
    (sorted), the transforms each pair once, in the order first read.
    """
    static = [c for c in connections if c.topic.endswith('tf_static')]
    tf = bag_read.read_tf(reader, static, [c for c in connections if c not in static])
    c = tf.columns
    pairs = dict.fromkeys(zip(np.array(c.frame_ids, object)[c.frame].tolist(),
                              np.array(c.child_frame_ids, object)[c.child].tolist()))
    frames = sorted({frame for pair in pairs for frame in pair})
    if not frames:
        return 'its TF holds no transform'
    transforms = _listed((f'{parent} -> {child}' for parent, child in pairs), 10)
    return (f'its TF holds the frames {_listed(frames)} ({transforms}): give --tf PARENT '
            'CHILD to follow CHILD in PARENT')


def select_connections(reader, topics):
    """
    Return the connections to read: every one of a supported type, or the topics asked for.

    BagSkipped when the bag has none of the topics asked for, or (none asked for) no topic of
    a type read: then, when it holds TF, the words say to use --tf PARENT CHILD and name its
    frames. BagError for a topic asked for that is missing while others are there, or is of
    a type not read.
    """
    connections = reader.connections
    found = {}
    for conn in connections:
        found.setdefault(conn.topic, conn.msgtype)
    if topics:
        if not any(topic in found for topic in topics):
            asked = (f'no topic {topics[0]}' if len(topics) == 1 else
                     f'none of the topics asked for ({", ".join(topics)}) is')
            raise bag_read.BagSkipped(
                f'{asked} in the bag (its topics: {_listed(sorted(found)) or "none"})')
        for topic in topics:
            if topic not in found:
                raise bag_read.BagError(
                    f'no topic {topic} in the bag (its topics: '
                    f'{", ".join(sorted(found)) or "none"})')
            if found[topic] not in bag_read.SUPPORTED:
                raise bag_read.BagError(
                    f'topic {topic} is a {found[topic]}, not one of the types read: '
                    f'{", ".join(t.rsplit("/", 1)[1] for t in bag_read.SUPPORTED)}'
                    f' (TFMessage with --tf)')
        return [c for c in connections if c.topic in topics]
    chosen = [c for c in connections if c.msgtype in bag_read.SUPPORTED]
    if not chosen:
        listed = _listed(f'{t} ({m})' for t, m in sorted(found.items())) or 'no topic'
        tf = [c for c in connections if c.msgtype == bag_read.TF_TYPE]
        hint = f'; {tf_frames_hint(reader, tf)}' if tf else ''
        raise bag_read.BagSkipped(f'no topic of a type read here in the bag: {listed}{hint}')
    return chosen


def tf_topic(reader, reference, body, tolerance, lo, hi):
    """
    Return the TfTopic of BODY in REFERENCE from the bag's TFMessage topics.

    Every transform passes the boundary's checks (refusals counted, the rest goes on); the
    accepted ones, static ones whatever --start/--end say, feed a rot_tools.TransformTree
    that follows BODY in REFERENCE over the recording (TransformTree.follow), whose own
    refusals (an empty frame name, a loop) are counted too. Its stamps are seconds from the
    first transform's, so that stamps a nanosecond apart stay apart over a long bag.
    """
    connections = [c for c in reader.connections if c.msgtype == bag_read.TF_TYPE]
    if not connections:
        raise bag_read.BagSkipped('--tf: the bag has no tf2_msgs/msg/TFMessage topic')
    static = [c for c in connections if c.topic.endswith('tf_static')]
    dynamic = [c for c in connections if c not in static]
    tf = bag_read.read_tf(reader, static, dynamic, lo, hi)
    c = tf.columns
    verdict = boundary.check_batch(c.orientation, tolerance, c.position)
    codes = verdict.code
    ok = codes == boundary.ACCEPTED
    parents = np.array(c.frame_ids, object)[c.frame[ok]]
    children = np.array(c.child_frame_ids, object)[c.child[ok]]
    named = set(parents) | set(children)
    for frame in (reference, body):
        if frame not in named:
            known = ', '.join(sorted(named)) or 'none'
            raise bag_read.BagSkipped(
                f"--tf: frame {frame} never appears in the bag's TF (frames: {known})")
    ns = stamp_ns(c.sec[ok], c.nanosec[ok])
    origin = int(ns.min())
    transforms = transform_tree.Transforms(
        parents, children, boundary.accepted_rotations(c.orientation, verdict.norm, codes),
        c.position[ok], (ns - origin) / NS_PER_S, tf.static[ok])
    tree = transform_tree.TransformTree(math.inf, max_samples=max(2, len(ns)))
    try:
        followed = tree.follow(reference, body, transforms)
    except transform_tree.TransformLookupError as exc:
        raise bag_read.BagError(f'--tf {reference} {body}: {exc}') from None
    accepted = np.flatnonzero(ok)
    texts = {}
    for row, exc in sorted(followed.refused.items()):
        codes[accepted[row]] = _TF_CODE[exc.reason]
        texts[int(accepted[row])] = str(exc)
    # The lookups' stamps are stamps of the transforms: back to their exact nanoseconds.
    known = np.unique(ns)
    t = known[np.searchsorted((known - origin) / NS_PER_S, followed.stamp)]
    n = len(t)
    sec, nanosec = np.divmod(t, NS_PER_S)
    columns = bag_read.Columns(f'tf:{reference}->{body}', bag_read.TF_TYPE,
                               np.zeros(n, np.int64), sec, nanosec, [reference],
                               np.zeros(n, np.intp), [body], np.zeros(n, np.intp),
                               position=followed.b)
    chains = followed.chains
    return TfTopic(columns, TfChain(followed.R, chains[0] if len(chains) == 1 else chains,
                                    codes, c, texts))


NS_MAX = 2 ** 63 - 1
"""The latest record time a bag holds (int64 nanoseconds)."""


def record_bound(bag_start, seconds):
    """Return the record time ``seconds`` (≥ 0) after ``bag_start`` (ns), at most NS_MAX."""
    return min(bag_start + int(round(min(seconds * 1e9, 2.0 ** 63))), NS_MAX - 1)


class Analysis(NamedTuple):
    """A bag analysed: its storage ('rosbag1', 'rosbag2 sqlite3', ...) and its [Topic]."""

    storage: str
    topics: list


def analyse(path, topics=(), start=None, end=None, tolerance=QUATERNION_TOLERANCE, seq=None,
            wrap=False, progress_stream=None, tf=None, reading='rotvec'):
    """
    Return the Analysis of the bag at PATH; BagError for what cannot be read.

    BagSkipped (a BagError) for a bag with nothing of what was asked: no message, none of the
    topics asked for, no topic of a type read, no TF or not the frames of ``tf``.

    tf: (REFERENCE, BODY) adds the TF chain between them (then topics are read only when
    asked for by name). reading: how a recorded covariance's rotation block is read,
    'rotvec' or 'rpy' (rot_tools.io.message_covariance.READINGS).
    """
    with bag_read.open_bag(path) as reader:
        if not reader.connections or not sum(c.msgcount for c in reader.connections):
            raise bag_read.BagSkipped(f'{path}: the bag holds no messages')
        connections = select_connections(reader, topics) if topics or not tf else []
        bag_start = reader.start_time
        lo = None if start is None else record_bound(bag_start, start)
        hi = None if end is None else record_bound(bag_start, end) + 1
        progress = Progress(sum(c.msgcount for c in connections), progress_stream)
        try:
            columns = bag_read.read_topics(reader, connections, lo, hi,
                                           progress=progress) if connections else {}
        finally:
            progress.done()
        followed = tf_topic(reader, tf[0], tf[1], tolerance, lo, hi) if tf else None
        storage = bag_read.storage_name(reader)
    out = [Topic(columns[name], tolerance, seq, wrap, reading=reading)
           for name in sorted(columns)]
    if followed is not None:
        out.append(Topic(followed.columns, tolerance, seq, wrap, chain=followed.chain))
    return Analysis(storage, out)
