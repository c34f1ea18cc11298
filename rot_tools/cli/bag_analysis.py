"""
The analysis of ``rot-tools bag``: the orientations recorded in a bag, topic by topic.

Each topic's messages pass rotation_node's boundary checks (refusals counted by reason), then
every representation comes from one batch decomposition (rot_tools.core.decomposition), and
the summary adds ranges, rates, positions and an Imu's agreement with its own gyro.
"""

import math
import sys
import time
from typing import NamedTuple

import numpy as np
from rot_tools.cli import bag_covariance
from rot_tools.cli.bag_output import in_unit, NS_PER_S
from rot_tools.core import transform_tree
from rot_tools.core.axis_angle import matrix_to_rotvec
from rot_tools.core.decomposition import decompose
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.core.fitting import mean_rotation
from rot_tools.core.imu import GYRO_TOL
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


GYRO_NOISE = math.radians(5)
"""RMS of |ω − ω_gyro| (rad/s) allowed to the noise of an Imu's gyro and of the rates
differentiated from its consecutive orientations, whatever it turns at."""


def gyro_threshold(gyro_rms):
    """
    Return the RMS of |ω − ω_gyro| (rad/s) beyond which an orientation disagrees with its gyro.

    GYRO_NOISE, plus GYRO_TOL (imu-check's tolerance on the gyro's scale) times the gyro's
    RMS rate ``gyro_rms`` (rad/s): what a scale off by that much adds at most.
    """
    return GYRO_NOISE + GYRO_TOL * gyro_rms


class GyroAgreement(NamedTuple):
    """An Imu's rates from its orientations against its gyro: RMS difference, threshold (rad/s)."""

    rms: float
    threshold: float


def gyro_agreement(omega, gyro):
    """
    Return the GyroAgreement of body rates ω (n, 3) (NaN on rows without one) and the gyro.

    ω_k is the rate of the step to message k (log(Rₖ₋₁ᵀRₖ)/Δt); gyro (n, 3) the messages'
    angular_velocity, taken at each step as the mean of its two ends. None without a step.
    """
    steps = np.isfinite(omega[1:, 0])
    if not steps.any():
        return None
    at_step = 0.5 * (gyro[:-1] + gyro[1:])[steps]
    diff = omega[1:][steps] - at_step
    rms = float(np.sqrt(np.mean(np.sum(diff * diff, axis=1))))
    rate = float(np.sqrt(np.mean(np.sum(at_step * at_step, axis=1))))
    return GyroAgreement(rms, gyro_threshold(rate))


def continuous(angles, wrap):
    """Return angles (n, 3) as they are when ``wrap``, else unwrapped along the stream."""
    return angles if wrap or not len(angles) else np.unwrap(angles, axis=0)


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
        self.has_position = chain is not None or c.position is not None
        self.position = c.position[ok] if c.position is not None else np.zeros((n, 3))
        self.seq = seq
        # The rotations only: the positions are not part of any column computed from it.
        d = decompose(self.R, np.zeros(3), seq or RPY_SEQUENCE, check=False)
        self.quaternion, self.rotvec, self.angle = d.quaternion, d.rotvec, d.angle
        self.rpy = continuous(d.rpy, wrap)
        self.seq_angles = continuous(d.euler, wrap) if seq else None
        self.omega = np.full((n, 3), np.nan)
        self.steps = np.zeros(0)
        if n > 1:
            D = np.einsum('nji,njk->nik', self.R[:-1], self.R[1:])
            step = matrix_to_rotvec(D, check=False)
            self.steps = np.linalg.norm(step, axis=1)
            dt = 1e-9 * np.diff(self.ns)
            good = dt > 0
            self.omega[1:][good] = step[good] / dt[good][:, None]
        self.gyro = None
        if c.angular_velocity is not None and n > 1:
            self.gyro = gyro_agreement(self.omega, c.angular_velocity[ok])
        self.reading = reading
        self.rpy_std, self.covariance_status = np.full((n, 3), np.nan), None
        if chain is None and c.covariance is not None:
            self.covariance = c.covariance[ok]
            self.rpy_std, self.covariance_status = bag_covariance.stddevs(
                self.R, self.covariance, reading)

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
        d = decompose(mean, np.zeros(3), check=False)
        out['mean_orientation'] = {
            'quaternion': dict(zip('xyzw', map(float, d.quaternion))),
            'rpy': dict(zip(('roll', 'pitch', 'yaw'), in_unit(d.rpy, degrees).tolist()))}
    if t.has_position:
        out.update(motion_summary(t.position, t.ns))
    if t.gyro is not None:
        out.update(gyro_summary(t.gyro, degrees))
    if t.covariance_status is not None:
        out.update(bag_covariance.summary(t.rpy_std, t.covariance_status, t.covariance,
                                          t.reading, degrees))
    return out


def motion_summary(position, ns):
    """
    Return the summary of a topic's positions (m): their ranges, and the largest speed.

    position (n, 3), n ≥ 1; ns (n,) header stamps. The speed of a step is |bₖ − bₖ₋₁| over
    its Δt (m/s), over the steps whose Δt > 0; ``max_speed_stamp`` is the stamp of its end.
    """
    out = {'position_range': {
        name: [float(position[:, k].min()), float(position[:, k].max())]
        for k, name in enumerate('xyz')}}
    dt = np.diff(ns) / NS_PER_S
    forward = np.flatnonzero(dt > 0)
    if len(forward):
        with np.errstate(over='ignore'):  # steps beyond float64: an infinite speed
            speed = np.linalg.norm(np.diff(position, axis=0)[forward], axis=1) / dt[forward]
        k = int(np.argmax(speed))
        out['max_speed'] = float(speed[k])
        out['max_speed_stamp'] = Exact(int(ns[forward[k] + 1]) / NS_PER_S)
    return out


def gyro_warning(gyro, degrees):
    """Return why an Imu's orientation disagrees with its gyro (GyroAgreement), or None."""
    if not gyro.rms > gyro.threshold:
        return None
    unit = 'deg/s' if degrees else 'rad/s'
    rms, threshold = in_unit([gyro.rms, gyro.threshold], degrees)
    return (f'the orientation disagrees with the gyro: the RMS difference of their rates, '
            f'{rms:.4g} {unit}, exceeds {threshold:.4g} {unit} (its quaternion may be written '
            'w-first or inverted, or the gyro be on other axes: rot-tools imu-check says which)')


def gyro_summary(gyro, degrees):
    """Return the summary of an Imu's GyroAgreement (and its warning when it disagrees)."""
    unit = 'deg' if degrees else 'rad'
    out = {'gyro_rms_difference': float(in_unit(gyro.rms, degrees)),
           'gyro_rms_difference_unit': f'{unit}/s',
           'gyro_rms_threshold': float(in_unit(gyro.threshold, degrees))}
    warning = gyro_warning(gyro, degrees)
    if warning is not None:
        out['gyro_warning'] = warning
    return out


def warnings(topics, degrees):
    """Return the one-line warnings of a bag's topics: ['TOPIC: why', ...]."""
    out = []
    for t in topics:
        warning = gyro_warning(t.gyro, degrees) if t.gyro is not None else None
        if warning is not None:
            out.append(f'{t.topic}: {warning}')
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
