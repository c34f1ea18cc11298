"""
``rot-tools bag``: the orientations recorded in a bag, as a summary, a table and a plot.

A topic's messages are read into NumPy columns (rot_tools.io.bag_read), pass the same boundary
as rotation_node's inputs (rot_tools.io.boundary: same checks, same refusal reasons, counted
per topic), and are converted as batches by the vectorised engine: one call of each
conversion per topic, never one per message. Per accepted message, with R its rotation:

- the canonical quaternion (rot_tools.matrix_to_quaternion: w > 0);
- roll, pitch, yaw: REP-103's angles about the fixed X, Y, Z axes (the extrinsic sequence
  ``xyz``), and the angles of ``--seq SEQ`` when asked; each made continuous along the
  topic's stream with numpy.unwrap (so a heading goes on past ±180° instead of jumping),
  unless ``--wrap``;
- the rotation vector and angle of R (rot_tools.matrix_to_axis_angle);
- the body angular velocity from the previous accepted message of the topic:
  ω = log(Rₖ₋₁ᵀ·Rₖ)/Δt, Δt from the header stamps (none on the first row, nor where Δt ≤ 0).

Per topic the summary adds the messages' start, end and mean rate (header stamps of every
message read), the ranges of roll, pitch and yaw, the total angle turned (the sum of the
angles of the steps Rₖ₋₁ᵀ·Rₖ), the chordal mean orientation (rot_tools.mean_rotation), and
for an Imu the RMS of |ω − ω_gyro|, ω_gyro the mean of the gyro's angular_velocity at the
step's two ends: a check of the IMU's own consistency.

For the types that carry their orientation's covariance (Imu, PoseWithCovarianceStamped,
Odometry), each message's standard deviations of roll, pitch and yaw, and per topic their
median and the counts of unknown and bad covariances (rot_tools.cli.bag_covariance; read as
``--input-covariance`` says, as rotation_node's parameter input_covariance).

Messages are taken in the order they were recorded; ``--start``/``--end`` select them by
record time, in seconds from the bag's start.

``--tf REFERENCE BODY``: the transforms of the bag's TFMessage topics pass the same boundary
(counted), feed a rot_tools.TransformTree, and the chain between the two frames is looked up
as one batch at every stamp of its dynamic edges (:func:`tf_topic`); it is one more topic,
``tf:REFERENCE->BODY``.
"""

import math
import os
from pathlib import Path
import sys
import time
from types import SimpleNamespace

import numpy as np
from rot_tools.cli import bag_covariance, bag_parquet, output_file
from rot_tools.cli.bag_output import in_unit, MAX_PLOTTED_TOPICS, plot_note, write_csv, write_plot
from rot_tools.core import transform_tree
from rot_tools.core.axis_angle import matrix_to_axis_angle, matrix_to_rotvec
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import matrix_to_euler
from rot_tools.core.fitting import mean_rotation
from rot_tools.core.so3 import matrix_to_quaternion
from rot_tools.io import bag_read, boundary, csv_text, interface

RPY = 'xyz'
"""REP-103 roll, pitch, yaw: about the fixed X, Y, Z axes."""

DEFAULT_TOLERANCE = 1e-3
"""Largest |‖q‖ − 1| accepted (rotation_node's quaternion_tolerance default)."""


class Topic:
    """One topic's accepted messages and everything computed from them (radians)."""

    def __init__(self, columns, tolerance, seq=None, wrap=False, chain=None, reading='rotvec'):
        self.columns = c = columns
        self.topic, self.msgtype = c.topic, c.msgtype
        self.tolerance = tolerance
        self.chain = chain
        if chain is None:
            self.codes, norms = boundary.check_batch(c.orientation, tolerance, c.position,
                                                     c.covariance0)
            ok = self.codes == boundary.ACCEPTED
            self.R = boundary.accepted_rotations(c.orientation, norms, self.codes)
        else:  # a TF chain: its lookups, all made; the transforms' refusals are chain.codes
            self.codes = chain.codes
            ok = np.ones(len(c), bool)
            self.R = chain.R
        self.ok = ok
        n = len(self.R)
        self.ns, self.frame = stamp_ns(c.sec[ok], c.nanosec[ok]), c.frame[ok]
        self.position = c.position[ok] if c.position is not None else np.zeros((n, 3))
        self.quaternion = matrix_to_quaternion(self.R, check=False)
        self.rpy = self._angles(RPY, wrap)
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
        angles, _ = matrix_to_euler(self.R, seq, check=False)
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
        code = int(self.codes[k])
        _, norm = boundary.check_batch(q[None], self.tolerance)
        position = c.position[k] if c.position is not None else None
        fields = (interface.TF_FIELDS if self.chain is not None
                  else bag_read.SUPPORTED[self.msgtype])
        return boundary.batch_refusal_text(fields, code, q, float(norm[0]), self.tolerance,
                                           position)


def stamp_ns(sec, nanosec):
    """Return header stamps as int64 nanoseconds, sec·10⁹ + nanosec: exact, negative ones too."""
    return np.asarray(sec, np.int64) * csv_text.NS_PER_S + np.asarray(nanosec, np.int64)


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
        start, end = first / csv_text.NS_PER_S, last / csv_text.NS_PER_S
        out['start'], out['end'] = start, end
        out['duration'] = (last - first) / csv_text.NS_PER_S
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
        rpy = in_unit(matrix_to_euler(mean, RPY)[0], degrees)
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
# The command


def select_connections(reader, topics):
    """
    Return the connections to read: every one of a supported type, or the topics asked for.

    BagError for a topic not in the bag, of an unsupported type, or no topic to read.
    """
    connections = reader.connections
    found = {}
    for conn in connections:
        found.setdefault(conn.topic, conn.msgtype)
    if topics:
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
        listed = ', '.join(f'{t} ({m})' for t, m in sorted(found.items())) or 'no topic'
        raise bag_read.BagError(f'no topic of a type read here in the bag: {listed}')
    return chosen


TF_REASONS = (transform_tree.BAD_FRAME, transform_tree.LOOP, transform_tree.TOO_MANY_FRAMES)
"""Refusals of a TF transform besides the boundary's: the tree's, counted as rotation_node
counts them (an empty frame name, a loop, a tree full of frames), and the analysis goes on."""

_TF_CODE = {reason: len(boundary.REFUSAL_REASONS) + 1 + k for k, reason in enumerate(TF_REASONS)}


class _Chain:
    """
    The lookups of a TF chain, and what became of the transforms.

    R (n, 3, 3); frames, the chain (or the list of the chains, in time order, when a frame
    was re-parented); codes, every TF transform's reason code; texts {transform index: why
    the tree refused it}.
    """

    def __init__(self, R, frames, codes, transforms, texts):
        self.R, self.frames, self.codes, self.transforms = R, frames, codes, transforms
        self.texts = texts


class _Run:
    """Consecutive samples (by stamp) of one child under one parent: rows into the accepted."""

    def __init__(self, child, parent, static, rows, ns):
        self.child, self.parent, self.static = child, parent, static
        self.rows, self.ns = rows, ns


def _runs(parent, child, static, ns):
    """
    Return the runs of the accepted transforms ([_Run]).

    Per child, in stamp order, a new run wherever its parent (or static) changes; a dynamic
    run keeps the last recorded sample of each stamp.
    """
    runs = []
    order = np.lexsort((np.arange(len(ns)), ns, child))  # by child, stamp, record order
    key = np.stack([child[order], parent[order], static[order]], axis=1)
    cuts = np.flatnonzero((key[1:] != key[:-1]).any(axis=1)) + 1
    for rows in np.split(order, cuts):
        if not len(rows):
            continue
        stamps = ns[rows]
        if not static[rows[0]]:
            last = np.append(stamps[1:] != stamps[:-1], True)  # the last of equal stamps
            rows, stamps = rows[last], stamps[last]
        runs.append(_Run(int(child[rows[0]]), int(parent[rows[0]]), bool(static[rows[0]]),
                         rows, stamps))
    return runs


class _ChainLookups:
    """
    BODY in REFERENCE looked up over time while the tree's shape changes (re-parenting).

    The bag's time is cut where a frame takes a new parent; within each segment every
    child's run that holds there (the last that started at or before the segment's start)
    feeds a fresh TransformTree — only its samples in the segment and one on each side, so
    a segment costs what it holds — and the chain is looked up at every stamp of its dynamic
    edges in the segment at which all of them have data (one batch). Stamps go to the tree
    as seconds from the first stamp, ``(ns − ns₀)·10⁻⁹``: distinct to the nanosecond over
    a bag of weeks, where seconds since 1970 collapse stamps closer than ~0.2 µs.
    """

    def __init__(self, frames, R, b, ns, runs):
        self.frames, self.R, self.b, self.ns, self.runs = frames, R, b, ns, runs
        self.origin = int(ns.min()) if len(ns) else 0
        self.refused = {}  # accepted row -> (reason, text)

    def seconds(self, ns):
        return 1e-9 * (np.asarray(ns, np.int64) - self.origin)

    def segments(self):
        """[(lo, hi, [_Run])]: the runs that hold in [lo, hi) ns, segments in time order."""
        first_of = {}
        for run in self.runs:
            first_of.setdefault(run.child, run)
        switches = sorted({int(r.ns[0]) for r in self.runs if first_of[r.child] is not r})
        bounds = [-math.inf] + switches + [math.inf]
        out = []
        for lo, hi in zip(bounds[:-1], bounds[1:]):
            holding = {}
            for run in self.runs:  # runs of a child are in stamp order
                if run.child not in holding or run.ns[0] <= lo:
                    holding[run.child] = run
            out.append((lo, hi, sorted(holding.values(), key=lambda r: int(r.rows.min()))))
        return out

    def feed(self, tree, run, lo, hi):
        """Set run's samples in [lo, hi) (and one on each side) in tree; refusals noted."""
        names = self.frames[run.parent], self.frames[run.child]
        try:
            if run.static:
                last = run.rows[-1]
                tree.set_transform(*names, self.R[last], self.b[last],
                                   float(self.seconds(run.ns[-1])), static=True)
                return
            i0 = max(0, int(np.searchsorted(run.ns, lo, 'right')) - 1)
            i1 = min(len(run.ns), int(np.searchsorted(run.ns, hi, 'left')) + 1)
            rows = run.rows[i0:i1]
            tree.set_transform(*names, self.R[rows], self.b[rows], self.seconds(run.ns[i0:i1]))
        except transform_tree.TransformTreeError as exc:
            if exc.reason not in _TF_CODE:
                raise
            inside = (run.ns >= lo) & (run.ns < hi)
            for row in run.rows[inside].tolist():
                self.refused.setdefault(row, (exc.reason, str(exc)))

    def segment(self, tree, holding, reference, body, lo, hi):
        """(ns, R, b, chain) of the lookups in [lo, hi); TransformLookupError if none can be."""
        chain = tree.chain(reference, body)
        runs = {self.frames[r.child]: r for r in holding}
        times = [runs[f].ns for f in chain
                 if f in runs and not runs[f].static and tree.parent(f) in chain]
        if times:
            t = np.unique(np.concatenate(times))
            t = t[(t >= lo) & (t < hi)]
            first, last = tree.time_range(reference, body)
            seconds = self.seconds(t)
            t = t[(seconds >= first) & (seconds <= last)]
        else:  # static edges only: one lookup, at the newest of their stamps
            newest = max(int(runs[f].ns[-1]) for f in chain if f in runs
                         and tree.parent(f) in chain) if len(chain) > 1 else self.origin
            t = np.array([newest] if lo <= newest < hi or lo == -math.inf else [], np.int64)
        R, b, _ = tree.lookup(reference, body, self.seconds(t))
        return t, R.reshape(-1, 3, 3), b.reshape(-1, 3), chain

    def lookup(self, reference, body):
        """(ns, R, b, chains) of every lookup; BagError when there is none."""
        parts, chains, why = [], [], None
        for lo, hi, holding in self.segments():
            tree = transform_tree.TransformTree(cache_seconds=math.inf)
            for run in holding:
                self.feed(tree, run, lo, hi)
            try:
                t, R, b, chain = self.segment(tree, holding, reference, body, lo, hi)
            except transform_tree.TransformLookupError as exc:
                why = exc
                continue
            if len(t):
                parts.append((t, R, b))
                if chain not in chains:
                    chains.append(chain)
        if not parts:
            raise bag_read.BagError(f'--tf {reference} {body}: {why}' if why is not None else
                                    f'--tf: no time at which every edge of {reference} → '
                                    f'{body} has data')
        ns, R, b = (np.concatenate(x) for x in zip(*parts))
        return ns, R, b, chains


def tf_topic(reader, reference, body, tolerance, lo, hi):
    """
    (Columns, _Chain) of BODY in REFERENCE from the bag's TFMessage topics.

    Every transform passes the boundary's checks, then the tree's (an empty frame name, a
    loop): refusals are counted and the rest goes on. The accepted ones feed
    rot_tools.TransformTree (static ones whatever --start/--end say); a frame's samples
    under each of its parents are used while that parent holds (_ChainLookups).
    """
    connections = [c for c in reader.connections if c.msgtype == bag_read.TF_TYPE]
    if not connections:
        raise bag_read.BagError('--tf: the bag has no tf2_msgs/msg/TFMessage topic')
    static = [c for c in connections if c.topic.endswith('tf_static')]
    dynamic = [c for c in connections if c not in static]
    parts = [bag_read.read_tf(reader, static)] if static else []
    parts += [bag_read.read_tf(reader, dynamic, lo, hi)] if dynamic else []
    tf = bag_read.join_tf(parts)
    frames = tf['frames']
    codes, norms = boundary.check_batch(tf['orientation'], tolerance, tf['position'])
    empty = np.array([not f for f in frames] or [False])
    nameless = (codes == boundary.ACCEPTED) & (empty[tf['parent']] | empty[tf['child']])
    codes[nameless] = _TF_CODE[transform_tree.BAD_FRAME]
    texts = {int(k): 'an empty frame name: header.frame_id '
             f"{frames[tf['parent'][k]]!r}, child_frame_id {frames[tf['child'][k]]!r}"
             for k in np.flatnonzero(nameless)[:1]}
    ok = codes == boundary.ACCEPTED
    R = boundary.accepted_rotations(tf['orientation'], norms, codes)
    parent, child = tf['parent'][ok], tf['child'][ok]
    ns = stamp_ns(tf['sec'][ok], tf['nanosec'][ok])
    named = {frames[i] for i in np.concatenate([parent, child]).tolist()}
    for frame in (reference, body):
        if frame not in named:
            known = ', '.join(sorted(named)) or 'none'
            raise bag_read.BagError(
                f"--tf: frame {frame} never appears in the bag's TF (frames: {known})")
    lookups = _ChainLookups(frames, R, tf['position'][ok], ns,
                            _runs(parent, child, tf['static'][ok], ns))
    t, R_chain, b_chain, chains = lookups.lookup(reference, body)
    accepted = np.flatnonzero(ok)
    for row, (reason, text) in sorted(lookups.refused.items()):
        codes[accepted[row]] = _TF_CODE[reason]
        texts.setdefault(int(accepted[row]), text)
    columns = bag_read.Columns(f'tf:{reference}->{body}', bag_read.TF_TYPE)
    columns.record = np.zeros(len(t), np.int64)
    columns.sec, columns.nanosec = np.divmod(t, csv_text.NS_PER_S)
    columns.frame_ids, columns.frame = [reference], np.zeros(len(t), np.intp)
    columns.child_frame_ids, columns.child = [body], np.zeros(len(t), np.intp)
    columns.position = np.asarray(b_chain, np.float64).reshape(-1, 3)
    columns.orientation = None
    columns.covariance0 = columns.covariance = columns.angular_velocity = None
    transforms = SimpleNamespace(orientation=tf['orientation'], position=tf['position'])
    return columns, _Chain(R_chain, chains[0] if len(chains) == 1 else chains, codes,
                           transforms, texts)


NS_MAX = 2 ** 63 - 1
"""The latest record time a bag holds (int64 nanoseconds)."""


def record_bound(bag_start, seconds):
    """Return the record time ``seconds`` (≥ 0) after ``bag_start`` (ns), at most NS_MAX."""
    return min(bag_start + int(round(min(seconds * 1e9, 2.0 ** 63))), NS_MAX - 1)


def analyse(path, topics=(), start=None, end=None, tolerance=DEFAULT_TOLERANCE, seq=None,
            wrap=False, fast=True, progress_stream=None, tf=None, reading='rotvec'):
    """
    (storage name, [Topic]) of the bag at PATH; BagError for what cannot be read.

    tf: (REFERENCE, BODY) adds the TF chain between them (then topics are read only when
    asked for by name). reading: how a recorded covariance's rotation block is read,
    'rotvec' or 'rpy' (rot_tools.io.message_covariance.READINGS).
    """
    with bag_read.open_bag(path) as reader:
        if not reader.connections or not sum(c.msgcount for c in reader.connections):
            raise bag_read.BagError(f'{path}: the bag holds no messages')
        connections = select_connections(reader, topics) if topics or not tf else []
        bag_start = reader.start_time
        lo = None if start is None else record_bound(bag_start, start)
        hi = None if end is None else record_bound(bag_start, end) + 1
        progress = Progress(sum(c.msgcount for c in connections), progress_stream)
        try:
            columns = bag_read.read_topics(reader, connections, lo, hi, fast=fast,
                                           progress=progress) if connections else {}
        finally:
            progress.done()
        chain = tf_topic(reader, tf[0], tf[1], tolerance, lo, hi) if tf else None
        storage = bag_read.storage_name(reader)
    out = [Topic(columns[name], tolerance, seq, wrap, reading=reading)
           for name in sorted(columns)]
    if chain is not None:
        out.append(Topic(chain[0], tolerance, seq, wrap, chain=chain[1]))
    return storage, out


def refuse_overwriting(bag, outputs, error):
    """
    Call ``error`` if an output file is the bag: the same file, or a file in its directory.

    outputs: [(option, path or None)]; ``-`` is the standard output. The bag is what
    rot_tools.io.bag_read.bag_paths opens (a rosbag2 directory for a file inside one).
    """
    try:
        inputs = [Path(p).resolve() for p in bag_read.bag_paths(bag)] + [Path(bag).resolve()]
    except bag_read.BagError:
        return  # the analysis says what is wrong with it
    for option, path in outputs:
        if path is None or path == '-':
            continue
        target = Path(path).resolve()
        for source in inputs:
            if (target == source or (source.is_dir() and target.is_relative_to(source))
                    or (target.exists() and os.path.samefile(target, source))):
                error(f'{option} {path} would overwrite the bag being read ({bag}): refused')


def release_stdout():
    """Point the standard output at /dev/null: what could not be written is dropped."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)


def to_stdout(write, error):
    """
    Run ``write(sys.stdout)`` and flush it.

    A closed pipe ends quietly (status 0, as ``| head`` expects); a full disk or a closed
    standard output is one error line (status 2).
    """
    if sys.stdout is None:
        error('cannot write to the standard output: it is closed')
    try:
        write(sys.stdout)
        sys.stdout.flush()
    except BrokenPipeError:  # `rot-tools bag ... --csv - | head`: the reader is done
        release_stdout()
    except OSError as exc:
        release_stdout()
        error(f'cannot write to the standard output: {exc.strerror or exc}')


def run(args, error):
    """
    rot-tools bag on the one bag ``args.path``; ``error(text)`` prints one line and exits 2.

    rot_tools.cli.fleet.command reads the command line's paths and checks the options first,
    and hands one bag given alone to this function.
    """
    from rot_tools.io.report import to_json, to_yaml

    refuse_overwriting(args.path, [('--csv', args.csv), ('--plot', args.plot),
                                   ('--parquet', args.parquet)], error)
    try:
        storage, topics = analyse(args.path, args.topic or (), args.start, args.end,
                                  DEFAULT_TOLERANCE if args.tol is None else args.tol,
                                  args.seq, args.wrap, tf=args.tf,
                                  reading=args.input_covariance)
    except bag_read.BagError as exc:
        error(f'bag: {exc}')
    if args.plot:
        drawn = topics[:MAX_PLOTTED_TOPICS]
        output_file.write_figure(lambda: write_plot(args.plot, drawn, args.deg), args.plot,
                                 error)
        sys.stderr.write(plot_note(args.plot, drawn, topics[MAX_PLOTTED_TOPICS:]))
    if args.parquet is not None:
        bag_parquet.directory(args.parquet, error)
        target = os.path.join(args.parquet, bag_parquet.file_names([args.path])[0])
        try:
            bag_parquet.write(target, bag_parquet.table(topics, str(args.path), args.deg,
                                                        args.seq))
        except OSError as exc:
            error(f'--parquet: cannot write {target}: {exc.strerror or exc}')
    if args.csv == '-':
        to_stdout(lambda out: write_csv(out, topics, args.deg, args.precision), error)
        return 0
    if args.csv is not None:
        try:
            with output_file.complete_or_nothing(args.csv, 'w', encoding='utf-8',
                                                 newline='') as out:
                write_csv(out, topics, args.deg, args.precision)
        except OSError as exc:
            error(f'--csv: cannot write {args.csv}: {exc.strerror or exc}')
    text = to_json if args.json else to_yaml
    data = summary(args.path, storage, topics, args.deg)
    to_stdout(lambda out: out.write(text(data, precision=args.precision)), error)
    return 0
