"""
An IMU's recording read from bags for ``rot-tools imu-check``: the Imu topic and a reference.

The Imu topic's stamps and fields as the arrays check_imu takes, the messages it cannot use
left out and counted by reason; the reference orientation of the body from a topic or the
TF tree, of the same bag or of another recording of the run, refused when its time does not
meet the IMU's.
"""

from typing import NamedTuple

import numpy as np
from rot_tools.cli import bag_analysis
from rot_tools.cli.bag_analysis import stamp_ns
from rot_tools.cli.bag_output import NS_PER_S
from rot_tools.core.imu_samples import MAX_READING, MIN_SAMPLES
from rot_tools.core.so3 import matrix_to_quaternion
from rot_tools.core.stamps import plain
from rot_tools.io import bag_read, boundary
from rot_tools.io.boundary import QUATERNION_TOLERANCE

IMU_TYPE = 'sensor_msgs/msg/Imu'
"""The type of the topic checked."""

ACCELERATION = {IMU_TYPE: {'linear_acceleration': 'linear_acceleration'}}
"""The Imu field read besides those rot-tools bag reads (bag_read.read_topics' vectors)."""

REFERENCE_TYPES = tuple(t for t in bag_read.SUPPORTED if t != IMU_TYPE)
"""The types a reference topic may have: those of rot-tools bag with an orientation, but an
Imu (whose orientation is its own sensor frame's, not the body's)."""


class Stream(NamedTuple):
    """
    A stream of orientations read from the bag, stamps in seconds from the IMU's first.

    name: the topic, or ``tf:PARENT->CHILD``; msgtype; body: the frame the orientation is of
    (an Odometry's child frame, --ref-tf's CHILD; None when the message does not name it);
    parent: the frame it is in; stamps (n,); quaternions (n, 4) [x, y, z, w].
    """

    name: str
    msgtype: str
    body: object
    parent: object
    stamps: np.ndarray
    quaternions: np.ndarray


class Imu(NamedTuple):
    """
    The IMU topic read, and the arrays check_imu takes.

    topic, frame (its most frequent frame_id), messages (how many were read), left_out
    ({why: how many} of the messages left out, as _left_out counts them); stamps (N,) s,
    quaternions (N, 4) or None, angular_velocity and linear_acceleration (N, 3), as recorded.
    """

    topic: str
    frame: str
    messages: int
    left_out: dict
    stamps: np.ndarray
    quaternions: object
    angular_velocity: np.ndarray
    linear_acceleration: np.ndarray


class Recording(NamedTuple):
    """
    What imu-check reads from a bag.

    imu: the Imu; reference: the reference Stream or None; hint: a sentence naming the
    bag's topics that could serve as reference, or None.
    """

    imu: Imu
    reference: object
    hint: object


def _topics(reader):
    """Return {topic: type} of the bag, in the order of its connections."""
    found = {}
    for conn in reader.connections:
        found.setdefault(conn.topic, conn.msgtype)
    return found


def _listed(found):
    return ', '.join(f'{t} ({m})' for t, m in sorted(found.items())) or 'none'


def imu_topic(found, asked=None):
    """
    Return the Imu topic to check: ``asked``, or the bag's only one; BagError if none fits.

    found: {topic: type} of the bag.
    """
    if asked is not None:
        if asked not in found:
            raise bag_read.BagError(f'--imu-topic: no topic {asked} in the bag (its topics: '
                                    f'{_listed(found)})')
        if found[asked] != IMU_TYPE:
            raise bag_read.BagError(f'--imu-topic: {asked} is a {found[asked]}, not a '
                                    f'{IMU_TYPE}')
        return asked
    imus = sorted(t for t, m in found.items() if m == IMU_TYPE)
    if not imus:
        raise bag_read.BagError(f'no {IMU_TYPE} topic in the bag (its topics: '
                                f'{_listed(found)})')
    if len(imus) > 1:
        raise bag_read.BagError(f'{len(imus)} {IMU_TYPE} topics ({", ".join(imus)}): choose '
                                'one with --imu-topic')
    return imus[0]


def _reference_topic(found, asked, imu):
    if asked not in found:
        raise bag_read.BagError(f'--ref-topic: no topic {asked} in the bag (its topics: '
                                f'{_listed(found)})')
    if asked == imu or found[asked] not in REFERENCE_TYPES:
        kinds = ', '.join(t.rsplit('/', 1)[1] for t in REFERENCE_TYPES)
        raise bag_read.BagError(f'--ref-topic: {asked} is a {found[asked]}, not a reference '
                                f'orientation of the body ({kinds}; or --ref-tf PARENT '
                                'CHILD)')
    return asked


def reference_hint(found, imu):
    """Return a sentence naming the topics that could be the reference, or None."""
    topics = sorted(t for t, m in found.items() if m in REFERENCE_TYPES and t != imu)
    tf = any(m == bag_read.TF_TYPE for m in found.values())
    if not topics and not tf:
        return None
    ways = [f'--ref-topic {t}' for t in topics] + (['--ref-tf PARENT CHILD'] if tf else [])
    return ('accel_sign, world_up and mounting need a reference orientation of the body: '
            f'{" or ".join(ways)}')


def _majority(columns):
    """Return the frame_id most of a topic's messages carry ('' when it has none)."""
    if not len(columns):
        return ''
    counts = np.bincount(columns.frame, minlength=len(columns.frame_ids))
    return columns.frame_ids[int(np.argmax(counts))]


def _has_orientation(columns):
    """Tell which messages carry an orientation: covariance[0] ≠ −1 and a quaternion ≠ 0."""
    q = columns.orientation
    return (columns.covariance0 != -1) & np.any(q != 0, axis=1)


NON_FINITE_VECTOR = 'a NaN or Inf in angular_velocity or linear_acceleration'
BEYOND_READING = (f'a reading beyond {MAX_READING:g} in angular_velocity or '
                  'linear_acceleration (no sensor reads that)')
REFUSED = {
    boundary.NO_ORIENTATION: 'no orientation (orientation_covariance[0] = -1) among messages '
    'with one',
    boundary.NON_FINITE: 'a NaN or Inf in the orientation',
    boundary.ZERO_QUATERNION: 'a zero quaternion among messages with an orientation',
    boundary.NON_UNIT_QUATERNION: 'a quaternion whose norm is off 1 by more than '
    f'{QUATERNION_TOLERANCE:g}'}
"""Why an Imu message is left out: first its vectors, then the boundary's refusals of its
orientation (when some messages give one)."""


def _left_out(columns):
    """
    Return (keep (N,) bool, {why: count}) of an Imu topic's messages.

    Each message left out is counted once, under its first reason.
    """
    c = columns
    vectors = np.concatenate([c.angular_velocity, c.linear_acceleration], axis=1)
    finite = np.isfinite(vectors).all(axis=1)
    reasons = [(NON_FINITE_VECTOR, ~finite),
               (BEYOND_READING, finite & (np.abs(vectors) > MAX_READING).any(axis=1))]
    if _has_orientation(c).any():
        code = boundary.check_batch(c.orientation, QUATERNION_TOLERANCE, None,
                                    c.covariance0).code
        reasons += [(text, code == boundary.CODE[reason]) for reason, text in REFUSED.items()]
    keep = np.ones(len(c), bool)
    counts = {}
    for why, bad in reasons:
        count = int((bad & keep).sum())
        if count:
            counts[why] = count
        keep &= ~bad
    return keep, counts


def left_out_text(imu):
    """Return '3 of 3061 messages left out: 2 with ..., 1 with ...' of an Imu."""
    total = sum(imu.left_out.values())
    why = ', '.join(f'{count} with {text}' for text, count in imu.left_out.items())
    counted = 'all' if total == imu.messages else f'{total} of'
    return f'{counted} {imu.messages} messages left out: {why}'


def imu_stream(columns, origin):
    """
    Return the Imu of an Imu topic's Columns, stamps in seconds from ``origin`` (ns).

    With no orientation in any message (sensor_msgs/Imu's covariance[0] = −1, or zero
    quaternions) the quaternions are None. Messages the checks cannot use are left out and
    counted (_left_out): a NaN, an Inf or a reading beyond MAX_READING, and, when some
    messages give an orientation, one the boundary refuses (rotation_node's checks).
    """
    c = columns
    keep, counts = _left_out(c)
    quaternions = None
    if _has_orientation(c).any():
        q = c.orientation[keep]
        quaternions = q / np.linalg.norm(q, axis=1, keepdims=True)
    return Imu(c.topic, _majority(c), len(c), counts,
               (stamp_ns(c.sec, c.nanosec)[keep] - origin) / NS_PER_S, quaternions,
               c.angular_velocity[keep], c.linear_acceleration[keep])


def topic_stream(columns, origin):
    """Return the Stream of a reference topic's Columns (refused orientations left out)."""
    c = columns
    verdict = boundary.check_batch(c.orientation, QUATERNION_TOLERANCE, c.position,
                                   c.covariance0)
    ok = verdict.code == boundary.ACCEPTED
    body = c.child_frame_ids[int(c.child[ok][0])] if c.child is not None and ok.any() else None
    parent = c.frame_ids[int(c.frame[ok][0])] if ok.any() else None
    return Stream(c.topic, c.msgtype, body, parent,
                  (stamp_ns(c.sec, c.nanosec)[ok] - origin) / NS_PER_S,
                  c.orientation[ok] / verdict.norm[ok, None])


def tf_stream(followed, parent, child, origin):
    """Return the Stream of CHILD in PARENT followed through the bag's TF (a TfTopic)."""
    c = followed.columns
    return Stream(c.topic, bag_read.TF_TYPE, child, parent,
                  (stamp_ns(c.sec, c.nanosec) - origin) / NS_PER_S,
                  matrix_to_quaternion(followed.chain.R, check=False))


def _tf_reference(reader, frames, lo, hi, origin):
    """Return the Stream of --ref-tf PARENT CHILD from a bag's TF."""
    parent, child = frames
    try:
        followed = bag_analysis.tf_topic(reader, parent, child, QUATERNION_TOLERANCE, lo, hi)
    except bag_read.BagError as exc:  # its messages name rot-tools bag's --tf
        text = str(exc)
        raise bag_read.BagError(
            '--ref-tf' + text[len('--tf'):] if text.startswith('--tf') else text) from None
    return tf_stream(followed, parent, child, origin)


def _seconds(ns):
    """Return a time in ns as seconds in a plain decimal."""
    return plain(int(ns) / NS_PER_S)


def _span_text(span):
    return f'{_seconds(span[0])}–{_seconds(span[1])} s'


def _apart(a, b):
    """Return how far apart two spans (ns) are, as text in s, min or h."""
    gap = max(a[0] - b[1], b[0] - a[1]) / NS_PER_S
    if gap >= 3600:
        return f'{gap / 3600:.1f} h'
    return f'{gap / 60:.1f} min' if gap >= 60 else f'{gap:.3g} s'


def require_overlap(a, span_a, b, span_b, what):
    """
    Raise BagError when two spans (first, last) in ns do not overlap.

    a, b: what they are the spans of; what: 'recorded' or 'stamped'.
    """
    if span_a[0] <= span_b[1] and span_b[0] <= span_a[1]:
        return
    raise bag_read.BagError(
        f'{a} ({what} {_span_text(span_a)}) and {b} ({what} {_span_text(span_b)}) do not '
        f'overlap in time: {_apart(span_a, span_b)} apart')


def _stamp_span(stamps, origin):
    """Return (first, last) in ns of stamps in seconds from ``origin`` (ns)."""
    return (origin + int(round(float(np.min(stamps)) * NS_PER_S)),
            origin + int(round(float(np.max(stamps)) * NS_PER_S)))


def _record_span(reader):
    """Return (first, last) record time of an open bag, ns."""
    return reader.start_time, reader.end_time - 1  # rosbags' end_time is the last one + 1


def read_reference(path, ref_topic, ref_tf, lo, hi, origin, imu_bag):
    """
    Return the reference Stream from another recording of the run (--ref-bag PATH).

    lo, hi: the IMU bag's window (record time, ns, or None); origin: the IMU's first stamp
    (ns); imu_bag: (path, record span) of the IMU's bag, which this one must overlap.
    """
    with bag_read.open_bag(path) as reader:
        require_overlap(imu_bag[0], imu_bag[1], f'--ref-bag {path}', _record_span(reader),
                        'recorded')
        try:
            if ref_tf is not None:
                return _tf_reference(reader, ref_tf, lo, hi, origin)
            topic = _reference_topic(_topics(reader), ref_topic, None)
            connections = [c for c in reader.connections if c.topic == topic]
            return topic_stream(bag_read.read_topics(reader, connections, lo, hi)[topic],
                                origin)
        except bag_read.BagError as exc:
            raise bag_read.BagError(f'--ref-bag {path}: {exc}') from None


def _usable(reference, window):
    """Raise BagError unless the reference has MIN_SAMPLES distinct stamps at least."""
    count = len(reference.stamps)
    if not count:
        raise bag_read.BagError(f'{reference.name}: no usable orientation{window}')
    distinct = len(np.unique(reference.stamps))
    if distinct < MIN_SAMPLES:
        raise bag_read.BagError(
            f'{reference.name}: the reference has {distinct} distinct stamp(s) among its '
            f'{count} usable orientations{window}: at least {MIN_SAMPLES} needed')


def read(path, imu=None, ref_topic=None, ref_tf=None, start=None, end=None, ref_bag=None,
         warn=None):
    """
    Return the Recording of the bag at PATH; BagError (one line) for what cannot be read.

    imu: the Imu topic (default: the bag's only one); ref_topic or ref_tf (PARENT, CHILD):
    the reference, from the bag ref_bag when given (another recording of the same run), else
    from PATH; start, end: seconds from the bag's start (record time), as rot-tools bag's
    --start and --end (for ref_bag too, at the same record times). warn(text) is called with
    left_out_text once the IMU is read, when messages were left out (before any error about
    the reference).
    """
    window = '' if start is None and end is None else ' between --start and --end'
    with bag_read.open_bag(path) as reader:
        found = _topics(reader)
        topic = imu_topic(found, imu)
        names = [topic]
        if ref_topic is not None and ref_bag is None:
            names.append(_reference_topic(found, ref_topic, topic))
        lo = None if start is None else bag_analysis.record_bound(reader.start_time, start)
        hi = None if end is None else bag_analysis.record_bound(reader.start_time, end) + 1
        connections = [c for c in reader.connections if c.topic in names]
        columns = bag_read.read_topics(reader, connections, lo, hi, vectors=ACCELERATION)
        if not len(columns[topic]):
            raise bag_read.BagError(f'{topic}: no message{window}')
        origin = int(stamp_ns(columns[topic].sec[:1], columns[topic].nanosec[:1])[0])
        imu_data = imu_stream(columns[topic], origin)
        if not len(imu_data.stamps):
            raise bag_read.BagError(f'{topic}: {left_out_text(imu_data)}{window}: '
                                    'nothing to check')
        if imu_data.left_out and warn is not None:
            warn(f'{topic}: {left_out_text(imu_data)}')
        reference = None
        if ref_bag is None and ref_topic is not None:
            reference = topic_stream(columns[ref_topic], origin)
        elif ref_bag is None and ref_tf is not None:
            reference = _tf_reference(reader, ref_tf, lo, hi, origin)
        hint = None if ref_topic or ref_tf else reference_hint(found, topic)
        imu_bag = (path, _record_span(reader))
    if ref_bag is not None:
        reference = read_reference(ref_bag, ref_topic, ref_tf, lo, hi, origin, imu_bag)
    if reference is not None:
        _usable(reference, window)
        require_overlap(topic, _stamp_span(imu_data.stamps, origin), reference.name,
                        _stamp_span(reference.stamps, origin), 'stamped')
    return Recording(imu_data, reference, hint)
