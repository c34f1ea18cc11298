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

Messages are taken in the order they were recorded; ``--start``/``--end`` select them by
record time, in seconds from the bag's start.

``--tf REFERENCE BODY``: the transforms of the bag's TFMessage topics pass the same boundary
(counted), feed a rot_tools.TransformTree, and the chain between the two frames is looked up
as one batch at every stamp of its dynamic edges (:func:`tf_topic`); it is one more topic,
``tf:REFERENCE->BODY``.
"""

import csv
import io
import math
import os
import sys
import time
from types import SimpleNamespace

import numpy as np
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

    def __init__(self, columns, tolerance, seq=None, wrap=False, chain=None):
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
        self.sec, self.nanosec, self.frame = c.sec[ok], c.nanosec[ok], c.frame[ok]
        self.position = c.position[ok] if c.position is not None else np.zeros((n, 3))
        self.stamp = self.sec + 1e-9 * self.nanosec
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
            dt = (self.sec[1:] - self.sec[:-1]) + 1e-9 * (self.nanosec[1:] - self.nanosec[:-1])
            good = dt > 0
            self.omega[1:][good] = step[good] / dt[good][:, None]
        self.gyro_rms = None
        if c.angular_velocity is not None and n > 1:
            gyro = c.angular_velocity[ok]
            diff = self.omega[1:] - 0.5 * (gyro[:-1] + gyro[1:])
            diff = diff[np.isfinite(self.omega[1:, 0])]
            if len(diff):
                self.gyro_rms = float(np.sqrt(np.mean(np.sum(diff * diff, axis=1))))

    def _angles(self, seq, wrap):
        angles, _ = matrix_to_euler(self.R, seq, check=False)
        return angles if wrap or not len(angles) else np.unwrap(angles, axis=0)

    def refused(self):
        """{'total': n, reason: n, ...} over every reason of the boundary."""
        counts = np.bincount(self.codes, minlength=len(boundary.REFUSAL_REASONS) + 1)
        return {'total': int(counts[1:].sum()),
                **{r: int(counts[k + 1]) for k, r in enumerate(boundary.REFUSAL_REASONS)}}

    def first_refusal(self):
        """Return the sentence of the first refused message (what and by how much), or None."""
        bad = np.flatnonzero(self.codes != boundary.ACCEPTED)
        if not len(bad):
            return None
        k, c = int(bad[0]), self.columns if self.chain is None else self.chain.transforms
        q = c.orientation[k]
        code = int(self.codes[k])
        _, norm = boundary.check_batch(q[None], self.tolerance)
        position = c.position[k] if c.position is not None else None
        fields = (interface.TF_FIELDS if self.chain is not None
                  else bag_read.SUPPORTED[self.msgtype])
        return boundary.batch_refusal_text(fields, code, q, float(norm[0]), self.tolerance,
                                           position)


def _stamp_seconds(sec, nanosec):
    return float(sec) + 1e-9 * float(nanosec)


def _unit(values, degrees):
    return np.degrees(values) if degrees else np.asarray(values)


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
        first = int(np.argmin(c.sec * 1_000_000_000 + c.nanosec))
        last = int(np.argmax(c.sec * 1_000_000_000 + c.nanosec))
        start = _stamp_seconds(c.sec[first], c.nanosec[first])
        end = _stamp_seconds(c.sec[last], c.nanosec[last])
        out['start'], out['end'], out['duration'] = start, end, end - start
        out['rate'] = (len(c) - 1) / (end - start) if end > start else None
    if not len(t.R):
        return out
    unit = 'deg' if degrees else 'rad'
    out['unit'] = unit
    out['rpy_range'] = {name: _unit([float(t.rpy[:, k].min()), float(t.rpy[:, k].max())],
                                    degrees).tolist()
                        for k, name in enumerate(('roll', 'pitch', 'yaw'))}
    out['total_angle'] = float(_unit(t.steps.sum(), degrees))
    try:
        mean = mean_rotation(t.R, check=False)
    except RotationError as exc:
        out['mean_orientation'] = f'not unique: {exc}'
    else:
        q = matrix_to_quaternion(mean)
        rpy = _unit(matrix_to_euler(mean, RPY)[0], degrees)
        out['mean_orientation'] = {
            'quaternion': dict(zip('xyzw', map(float, q))),
            'rpy': dict(zip(('roll', 'pitch', 'yaw'), map(float, rpy)))}
    if t.gyro_rms is not None:
        out['gyro_rms_difference'] = float(_unit(t.gyro_rms, degrees))
        out['gyro_rms_difference_unit'] = f'{unit}/s'
    return out


def summary(path, storage, topics, degrees):
    """Return the whole summary: the bag, then each topic."""
    return {'bag': str(path), 'storage': storage,
            'topics': {t.topic: topic_summary(t, degrees) for t in topics}}


# ---------------------------------------------------------------------------------------
# CSV


def csv_header(seq):
    """Return the CSV's column names."""
    names = ['topic', 'stamp', 'frame_id', 'x', 'y', 'z', 'qx', 'qy', 'qz', 'qw',
             'roll', 'pitch', 'yaw']
    if seq:
        names += [f'{seq}_1', f'{seq}_2', f'{seq}_3']
    return names + ['rx', 'ry', 'rz', 'angle', 'wx', 'wy', 'wz']


def _csv_quote(text):
    """Write text as one CSV field (quoted only when it must be)."""
    out = io.StringIO()
    csv.writer(out, lineterminator='').writerow([text])
    return out.getvalue()


ROWS_PER_CHUNK = 1024
"""Rows made into text at a time (their arrays stay in the CPU's cache)."""


def _number_text(value, precision):
    """One number by the rule of rot_tools.io.csv_text, with Python's (correctly rounded) %f."""
    if value != value:
        return ''
    digits = len('%d' % abs(value)) if abs(value) >= 1 else 0
    text = '%.*f' % (max(0, precision - digits), value)
    if '.' in text:
        text = text.rstrip('0').rstrip('.')
    return '0' if text in ('-0', '') else text


def _binary_writer(out):
    """Return a function writing bytes to the text stream ``out`` (through its buffer if any)."""
    buffer = getattr(out, 'buffer', None)
    if buffer is None:
        return lambda data: out.write(data.decode('utf-8'))
    out.flush()
    return buffer.write


def write_csv(out, topics, degrees, precision):
    """
    Write the rows of every topic (topic by topic, in the bag's order) to ``out``.

    Numbers rounded to ``precision`` significant digits and ``precision`` decimal places (the
    rule of every number rot-tools prints), trailing zeros dropped, −0 as 0; the stamp
    exactly (sec.nanosec); ω empty on a topic's first row and where Δt ≤ 0. The text is
    made by rot_tools.io.csv_text for a chunk of rows at once (Python's formatting, one
    number at a time, where its arithmetic would not be exact: precision > 12, |x| ≥ 1e15).
    """
    seq = next((t.seq for t in topics if t.seq), None)
    out.write(','.join(csv_header(seq)) + '\n')
    write = _binary_writer(out)
    for t in topics:
        if not len(t.R):
            continue
        columns = [t.position, t.quaternion, _unit(t.rpy, degrees)]
        if t.seq_angles is not None:
            columns.append(_unit(t.seq_angles, degrees))
        columns += [_unit(t.rotvec, degrees), _unit(t.angle, degrees)[:, None],
                    _unit(t.omega, degrees)]
        values = np.hstack(columns)
        topic = _csv_quote(t.topic).encode()
        frames = [_csv_quote(f).encode() for f in t.columns.frame_ids]
        fast = csv_text.numbers_fit(values, precision)
        for start in range(0, len(values), ROWS_PER_CHUNK):
            part = slice(start, start + ROWS_PER_CHUNK)
            if fast:
                write(csv_text.rows(topic, t.sec[part], t.nanosec[part], frames,
                                    t.frame[part], values[part], precision))
                continue
            lines = [b'%s,%d.%09d,%s,%s\n' % (topic, sec, nsec, frames[f], ','.join(
                _number_text(v, precision) for v in row).encode())
                for sec, nsec, f, row in zip(t.sec[part].tolist(), t.nanosec[part].tolist(),
                                             t.frame[part].tolist(), values[part].tolist())]
            write(b''.join(lines))


# ---------------------------------------------------------------------------------------
# Plot


def write_plot(path, topics, degrees):
    """Roll, pitch and yaw (continuous) against time, one panel per topic (matplotlib)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    panels = max(1, len(topics))
    fig = Figure(figsize=(9.0, 2.6 * panels + 0.6), layout='constrained')
    FigureCanvasAgg(fig)
    axes = fig.subplots(panels, 1, sharex=True, squeeze=False)[:, 0]
    starts = [t.stamp.min() for t in topics if len(t.stamp)]
    t0 = min(starts) if starts else 0.0
    unit = 'deg' if degrees else 'rad'
    for ax, t in zip(axes, topics):
        ax.set_title(f'{t.topic} ({t.msgtype})', fontsize=10, loc='left')
        ax.set_ylabel(f'angle ({unit})')
        ax.grid(True, alpha=0.3)
        if not len(t.R):
            ax.text(0.5, 0.5, 'no accepted message', transform=ax.transAxes, ha='center')
            continue
        angles = _unit(t.rpy, degrees)
        for k, (name, color) in enumerate(zip(('roll', 'pitch', 'yaw'),
                                              ('tab:red', 'tab:green', 'tab:blue'))):
            ax.plot(t.stamp - t0, angles[:, k], color=color, lw=1.0, label=name,
                    gid=f'{t.topic}:{name}')
        ax.legend(loc='upper left', fontsize=8, ncols=3)
    axes[-1].set_xlabel(f'time (s) from header stamp {t0:.3f}')
    fig.suptitle('roll, pitch, yaw (REP-103, extrinsic xyz), continuous', fontsize=11)
    fig.savefig(path)


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


class _Chain:
    """The lookups of a TF chain: R (n, 3, 3), the frames, the TF transforms' reason codes."""

    def __init__(self, R, frames, codes, transforms):
        self.R, self.frames, self.codes, self.transforms = R, frames, codes, transforms


def tf_topic(reader, reference, body, tolerance, lo, hi):
    """
    (Columns, _Chain) of BODY in REFERENCE from the bag's TFMessage topics.

    Every transform passes the boundary's checks (refusals counted); the accepted ones feed a
    rot_tools.TransformTree (static ones whatever --start/--end say), which is looked up at
    every stamp of the chain's dynamic edges where all of them have data (one batch).
    """
    from rot_tools.core.errors import RotationError
    try:
        from rot_tools.core.transform_tree import TransformTree
    except ImportError:  # pragma: no cover - a checkout older than the TF tree
        raise bag_read.BagError('--tf needs rot_tools.TransformTree, not in this version'
                                ) from None

    connections = [c for c in reader.connections if c.msgtype == bag_read.TF_TYPE]
    if not connections:
        raise bag_read.BagError('--tf: the bag has no tf2_msgs/msg/TFMessage topic')
    static = [c for c in connections if c.topic.endswith('tf_static')]
    dynamic = [c for c in connections if c not in static]
    parts = [bag_read.read_tf(reader, static)] if static else []
    parts += [bag_read.read_tf(reader, dynamic, lo, hi)] if dynamic else []
    tf = bag_read.join_tf(parts)
    codes, norms = boundary.check_batch(tf['orientation'], tolerance, tf['position'])
    ok = codes == boundary.ACCEPTED
    R = boundary.accepted_rotations(tf['orientation'], norms, codes)
    b, parent, child = tf['position'][ok], tf['parent'][ok], tf['child'][ok]
    sec, nanosec, is_static = tf['sec'][ok], tf['nanosec'][ok], tf['static'][ok]
    stamps = sec + 1e-9 * nanosec
    exact = dict(zip(stamps.tolist(), zip(sec.tolist(), nanosec.tolist())))
    frames = tf['frames']
    tree = TransformTree(cache_seconds=math.inf)
    edge_stamps = {}
    keys = np.stack([parent, child, is_static], axis=1) if len(parent) else np.zeros((0, 3))
    order = np.unique(keys, axis=0, return_index=True)[1] if len(keys) else []
    try:
        for first in sorted(order):
            p, ch, st = keys[first]
            rows = np.flatnonzero((parent == p) & (child == ch) & (is_static == st))
            if st:
                last = rows[np.argmax(stamps[rows])]
                tree.set_transform(frames[p], frames[ch], R[last], b[last], stamps[last],
                                   static=True)
                continue
            rows = rows[np.argsort(stamps[rows], kind='stable')]
            t_rows, keep = np.unique(stamps[rows][::-1], return_index=True)
            rows = rows[::-1][keep]  # one sample per stamp: the last recorded
            tree.set_transform(frames[p], frames[ch], R[rows], b[rows], stamps[rows])
            edge_stamps[frames[ch]] = stamps[rows]
        for frame in (reference, body):
            if frame not in tree.frames:
                known = ', '.join(tree.frames) or 'none'
                raise bag_read.BagError(
                    f"--tf: frame {frame} never appears in the bag's TF (frames: {known})")
        chain = tree.chain(reference, body)
        times = [edge_stamps[f] for f in chain if f in edge_stamps
                 and tree.parent(f) in chain]
        first, last = tree.time_range(reference, body)
        if times:
            t = np.unique(np.concatenate(times))
            t = t[(t >= first) & (t <= last)]
        else:  # static edges only: one lookup
            t = np.array([tree.lookup(reference, body)[2]])
        if not len(t):
            raise bag_read.BagError(f'--tf: no time at which every edge of {reference} → '
                                    f'{body} has data')
        R_chain, b_chain, _ = tree.lookup(reference, body, t)
    except RotationError as exc:  # TransformTreeError / TransformLookupError: one line
        raise bag_read.BagError(f'--tf {reference} {body}: {exc}') from None
    columns = bag_read.Columns(f'tf:{reference}->{body}', bag_read.TF_TYPE)
    pairs = [exact.get(x, (int(math.floor(x)), int(round((x - math.floor(x)) * 1e9))))
             for x in t.tolist()]
    columns.record = np.zeros(len(t), np.int64)
    columns.sec = np.array([p[0] for p in pairs], np.int64)
    columns.nanosec = np.array([p[1] for p in pairs], np.int64)
    columns.frame_ids, columns.frame = [reference], np.zeros(len(t), np.intp)
    columns.child_frame_ids, columns.child = [body], np.zeros(len(t), np.intp)
    columns.position = np.asarray(b_chain, np.float64).reshape(-1, 3)
    columns.orientation = None
    columns.covariance0 = columns.angular_velocity = None
    transforms = SimpleNamespace(orientation=tf['orientation'], position=tf['position'])
    return columns, _Chain(np.asarray(R_chain).reshape(-1, 3, 3), chain, codes, transforms)


def analyse(path, topics=(), start=None, end=None, tolerance=DEFAULT_TOLERANCE, seq=None,
            wrap=False, fast=True, progress_stream=None, tf=None):
    """
    (storage name, [Topic]) of the bag at PATH; BagError for what cannot be read.

    tf: (REFERENCE, BODY) adds the TF chain between them (then topics are read only when
    asked for by name).
    """
    with bag_read.open_bag(path) as reader:
        if not reader.connections or not sum(c.msgcount for c in reader.connections):
            raise bag_read.BagError(f'{path}: the bag holds no messages')
        connections = select_connections(reader, topics) if topics or not tf else []
        bag_start = reader.start_time
        lo = None if start is None else bag_start + int(round(start * 1e9))
        hi = None if end is None else bag_start + int(round(end * 1e9)) + 1
        progress = Progress(sum(c.msgcount for c in connections), progress_stream)
        try:
            columns = bag_read.read_topics(reader, connections, lo, hi, fast=fast,
                                           progress=progress) if connections else {}
        finally:
            progress.done()
        chain = tf_topic(reader, tf[0], tf[1], tolerance, lo, hi) if tf else None
        storage = bag_read.storage_name(reader)
    out = [Topic(columns[name], tolerance, seq, wrap) for name in sorted(columns)]
    if chain is not None:
        out.append(Topic(chain[0], tolerance, seq, wrap, chain=chain[1]))
    return storage, out


def run(args, error):
    """rot-tools bag with parsed ``args``; ``error(text)`` prints one line and exits 2."""
    from rot_tools.io.report import to_json, to_yaml

    missing = bag_read.rosbags_missing()
    if missing:
        error(f"bag needs the rosbags library ({missing} is missing), the 'bag' extra: "
              "pip install 'rot_tools[bag]'")
    if args.start is not None and args.end is not None and args.end < args.start:
        error(f'--end {args.end:g} is before --start {args.start:g}')
    try:
        storage, topics = analyse(args.path, args.topic or (), args.start, args.end,
                                  DEFAULT_TOLERANCE if args.tol is None else args.tol,
                                  args.seq, args.wrap, tf=args.tf)
    except bag_read.BagError as exc:
        error(f'bag: {exc}')
    if args.plot:
        try:
            write_plot(args.plot, topics, args.deg)
        except ImportError as exc:
            if not (exc.name or '').startswith(('matplotlib', 'mpl_toolkits')):
                raise
            error("--plot needs matplotlib, the 'plot' extra: pip install 'rot_tools[plot]'")
        except OSError as exc:
            error(f'--plot: cannot write {args.plot}: {exc.strerror or exc}')
    if args.csv is not None:
        try:
            if args.csv == '-':
                try:
                    write_csv(sys.stdout, topics, args.deg, args.precision)
                    sys.stdout.flush()
                except BrokenPipeError:  # `rot-tools bag ... --csv - | head`: reader is done
                    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
                    return 0
            else:
                with open(args.csv, 'w', encoding='utf-8', newline='') as out:
                    write_csv(out, topics, args.deg, args.precision)
        except OSError as exc:
            error(f'--csv: cannot write {args.csv}: {exc.strerror or exc}')
    if args.csv != '-':
        data = summary(args.path, storage, topics, args.deg)
        text = to_json if args.json else to_yaml
        sys.stdout.write(text(data, precision=args.precision))
    return 0
