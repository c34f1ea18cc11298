"""
``rot-tools compare EST REF``: an orientation stream against ground truth, and its mounting.

Each side (a bag's topic or TF frame pair, a TUM or EuRoC file) is read into stamps,
rotations and positions; then, with rot_tools.core.trajectory: the time offset, the matching,
the mounting, the alignment of the reference frames, and the errors (APE, RPE, roll, pitch,
yaw of E = R_refᵀ·W·R_est).
"""

import argparse
import math
import os
from pathlib import Path
import sys
from typing import NamedTuple

import numpy as np
from rot_tools.cli import options, output_file
from rot_tools.core import trajectory
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import matrix_to_quaternion
from rot_tools.core.stamps import delta_pairs, order_stamps, plain
from rot_tools.io import arguments, bag_read
from rot_tools.io.report import round_number, to_json, to_yaml
from rot_tools.io.trajectory_files import Poses, read_text, TrajectoryFileError

DEFAULT_GAP = {'interpolate': 0.1, 'nearest': 0.01}
"""--max-gap (s) by --match: evo's 0.01 s for nearest."""

LOW_CORRELATION = 0.9
"""Correlation of the angular speeds below which an automatic offset gets a warning: the same
motion measured well by both streams correlates near 1, while unrelated streams searched over
a wide --max-offset can reach far above one half."""

LEAST_PAIRS = 3
"""Matched pairs needed (three positions fix an se3 alignment)."""

TEXT = (
    'EST and REF are each a bag (a topic with --est-topic/--ref-topic, or the transform of\n'
    "BODY in REFERENCE from the bag's TF with --est-tf/--ref-tf; a bag with one topic of a\n"
    "type 'rot-tools bag' reads needs neither), a TUM file (t x y z qx qy qz qw) or an\n"
    'EuRoC ground-truth CSV (ns, x, y, z, qw, qx, qy, qz, ...). Stamps are taken as\n'
    'they come: sorted, the first of equal ones kept, with a warning (--strict-stamps\n'
    'refuses them instead).\n\n'
    "The offset is added to EST's stamps; REF is then interpolated at each EST stamp\n"
    '(along the constant screw between its neighbours, each within --max-gap, default\n'
    '0.1 s) or, with --match nearest, its nearest stamp is taken (within --max-gap,\n'
    'default 0.01 s, as evo). --mounting estimates the rotation X between the two body\n'
    'frames (A_k X = X B_k over --delta) and compares EST turned by X. The alignment W\n'
    '(R_ref = W R_est) is then fitted, and the error E = R_refᵀ W R_est reported: APE and\n'
    "RPE angle statistics (rmse, mean, median, std, min, max; RPE as evo's, over --delta\n"
    "between non-overlapping pairs) and of E's roll, pitch, yaw (REP-103, each wrapped\n"
    'to (-180°, 180°]).\n'
    'Angles in radians unless --deg. Needs rosbags for bags (the bag extra).')


class CompareError(Exception):
    """Input that compare cannot use (one line for the user)."""


def add_parser(subparsers):
    """Add ``rot-tools compare`` to argparse's subparsers action and return its parser."""
    p = subparsers.add_parser(
        'compare', help='an orientation against ground truth: errors, offset, mounting',
        usage='rot-tools compare EST REF [--est-topic T] [--ref-topic T] [--est-tf A B]\n'
        '       [--ref-tf A B] [--match interpolate|nearest] [--max-gap S]\n'
        '       [--align none|rotation|yaw|se3|posyaw] [--offset auto|SECONDS]\n'
        '       [--max-offset S] [--mounting] [--delta D] [--delta-unit f|s]\n'
        '       [--strict-stamps] [--deg] [--json] [--csv FILE|-] [--plot FILE]',
        description=f'An orientation against ground truth.\n\n{TEXT}',
        epilog='examples:\n  rot-tools compare est.tum gt.csv --align se3 --deg\n'
        '  rot-tools compare run.bag gt.tum --est-topic /imu/data --offset auto --mounting\n'
        '  rot-tools compare est.tum ref.tum --match nearest --align se3 --deg --json')
    for side, name in (('est', 'EST'), ('ref', 'REF')):
        p.add_argument(side, metavar=name, help='a bag, a TUM file or an EuRoC CSV')
        p.add_argument(f'--{side}-topic', metavar='T', help=f'the topic of {name} in its bag')
        p.add_argument(f'--{side}-tf', nargs=2, metavar=('A', 'B'),
                       help=f"{name} is the transform of frame B in frame A from its bag's TF")
    p.add_argument('--match', choices=('interpolate', 'nearest'), default='interpolate',
                   help='REF interpolated at EST stamps (default), or its nearest stamp')
    p.add_argument('--max-gap', type=options.positive, metavar='S',
                   help='largest time (s) from an EST stamp to the REF stamps used (default '
                   '0.1, or 0.01 with --match nearest)')
    p.add_argument('--align', choices=trajectory.ALIGNMENTS, default='none',
                   help='fit the rotation between the reference frames: none (default), '
                   'rotation (least squares on SO(3)), yaw (about z), se3 (Umeyama on the '
                   'positions, as evo), posyaw (a yaw and a shift that align the positions, '
                   'as rpg_trajectory_evaluation aligns visual-inertial odometry)')
    p.add_argument('--offset', type=options.offset, default=0.0, metavar='auto|SECONDS',
                   help="seconds added to EST's stamps (default 0), or auto: estimated from "
                   'the angular speeds')
    p.add_argument('--max-offset', type=options.positive, default=1.0, metavar='S',
                   help='search --offset auto within ±S seconds (default 1)')
    p.add_argument('--mounting', action='store_true',
                   help='estimate the rotation X between the two body frames (hand-eye, '
                   'A X = X B), and compare EST turned by it')
    p.add_argument('--delta', type=options.positive, default=1, metavar='D',
                   help='the interval of relative rotations (RPE, mounting): D frames '
                   '(default 1) or seconds')
    p.add_argument('--delta-unit', choices=('f', 's'), default='f',
                   help='--delta in frames (f, default) or seconds (s)')
    p.add_argument('--strict-stamps', action='store_true',
                   help='refuse a trajectory whose stamps repeat or go back (by default they '
                   'are sorted and the first of equal stamps kept, with a warning)')
    p.add_argument('--csv', metavar='FILE',
                   help='write one row per match: stamp (s), angle, roll, pitch, yaw of E '
                   '(- = standard output, which then gets no report)')
    options.add_force(p)
    common = p.add_argument_group('common options')
    suppress = argparse.SUPPRESS
    arguments.add_deg(common, 'angles in degrees', suppress)
    arguments.add_json(common, default=suppress)
    arguments.add_precision(common, 'round numbers to N significant digits and N decimal places',
                            suppress)
    options.add_plot(common, 'draw the error angle and its roll, pitch, yaw against time',
                     suppress)
    arguments.add_version(common)
    return p


# ---- reading ------------------------------------------------------------------------------


def _is_bag(path):
    return bag_read.is_bag(path) or Path(path).is_dir()


def _ns_text(ns):
    """Write integer nanoseconds as exact seconds: 1311868229576000000 → 1311868229.576."""
    whole, fraction = divmod(abs(int(ns)), 10 ** 9)
    text = f'{whole}.{fraction:09d}'.rstrip('0')
    return ('-' if ns < 0 else '') + (text + '0' if text.endswith('.') else text)


def read_side(name, path, topic, tf, strict=False):
    """
    Poses of one side (name EST or REF): a bag's topic or TF chain, or a text file.

    Stamps as they come (order_stamps): sorted, the first of equal ones kept; with strict, the
    first that repeats or goes back is refused (CompareError, TrajectoryFileError).
    """
    if topic is None and tf is None and not _is_bag(path):
        return read_text(path, strict)
    if topic is not None and tf is not None:
        raise CompareError(f'{name}: give a topic or a TF frame pair, not both')
    missing = bag_read.rosbags_missing()
    if missing:
        raise CompareError(f'{name}: reading a bag needs the rosbags library ({missing} is '
                           f"missing), the 'bag' extra: {arguments.install_hint('bag')}")
    from rot_tools.cli import bag_analysis
    if tf is not None:
        _, topics = bag_analysis.analyse(path, tf=tuple(tf))
    else:
        _, topics = bag_analysis.analyse(path, () if topic is None else (topic,))
        if len(topics) > 1:
            listed = ', '.join(t.topic for t in topics)
            raise CompareError(f'{name}: the bag {path} has {len(topics)} topics ({listed}): '
                               f'choose one with --{name.lower()}-topic')
    t = topics[-1]
    if not len(t.ns):
        refused = t.refused()['total']
        why = t.first_refusal()
        raise CompareError(f'{name}: {t.topic}: no message to compare' + (
            f': all {refused} refused, the first because {why}' if refused else ''))
    back = t.ns[1:] <= t.ns[:-1]
    if strict and back.any():
        k = int(np.argmax(back)) + 1
        problem = (f'duplicate stamp {_ns_text(t.ns[k])}' if t.ns[k] == t.ns[k - 1] else
                   f'stamp {_ns_text(t.ns[k])} goes back from {_ns_text(t.ns[k - 1])}')
        raise CompareError(f'{name}: {t.topic}: {problem} (messages {k} and {k + 1} as '
                           'recorded)')
    order = order_stamps(t.ns)
    keep = order.index
    positions = t.chain is not None or t.columns.position is not None
    whole, fraction = np.divmod(t.ns[keep], 10 ** 9)  # ns / 1e9 would round twice
    return Poses(whole + fraction / 1e9, t.R[keep], t.position[keep] if positions else None,
                 t.topic, order.dropped_duplicates, order.reordered)


def stamp_warning(name, source, poses):
    """Return the warning of a side whose stamps were put in order, or None."""
    parts = []
    if poses.dropped_duplicates:
        n = poses.dropped_duplicates
        parts.append(f'{n} repeated stamp{"s" if n > 1 else ""} dropped (the first of each '
                     'kept)')
    if poses.reordered:
        n = poses.reordered
        parts.append(f'{n} stamp{"s" if n > 1 else ""} out of order sorted')
    return f'{name} ({source}): {", ".join(parts)}' if parts else None


def say_warnings(sides, lines):
    """
    Write a ``warning:`` line on stderr for each of ``sides`` put in order, then ``lines``.

    ``sides``: (name, source, poses) of each trajectory read (read_side).
    """
    ordered = [stamp_warning(name, source, poses) for name, source, poses in sides]
    for line in [line for line in ordered if line] + lines:
        sys.stderr.write(f'warning: {line}\n')


# ---- the comparison -----------------------------------------------------------------------


class Matched(NamedTuple):
    """Matched pairs: stamps (K,) in REF's clock, REF's and EST's rotations and positions."""

    stamps: np.ndarray
    R_ref: np.ndarray
    R_est: np.ndarray
    b_ref: np.ndarray
    b_est: np.ndarray


def _rows(b, rows):
    return None if b is None else b[rows]


def match(est, ref, offset, how, max_gap):
    """Pairs of EST (stamps shifted by offset) and REF: interpolated or nearest (Matched)."""
    with np.errstate(over='ignore'):
        t_est = est.stamps + offset
    lo, hi = max(t_est[0], ref.stamps[0]), min(t_est[-1], ref.stamps[-1])
    if not lo <= hi + max_gap:  # (an infinite t_est too)
        raise CompareError(
            f'no overlap in time: EST spans [{plain(t_est[0])}, {plain(t_est[-1])}] s (offset '
            f'{plain(offset)} s added), REF [{plain(ref.stamps[0])}, {plain(ref.stamps[-1])}] s')
    same = t_est[1:] <= t_est[:-1]
    if same.any():
        k = int(np.argmax(same))
        raise CompareError(
            f"the offset {plain(offset)} s swallows the steps of EST's stamps: "
            f'{plain(est.stamps[k])} and {plain(est.stamps[k + 1])} s both become '
            f'{plain(t_est[k])} s')
    if how == 'interpolate':
        if len(ref.stamps) < 2:
            raise CompareError('REF has 1 pose: at least 2 are needed to interpolate')
        R, b, covered = trajectory.interpolate_poses(ref.stamps, ref.R, ref.b, t_est, max_gap)
        pairs = Matched(t_est[covered], R, est.R[covered], b, _rows(est.b, covered))
    elif len(est.stamps) <= len(ref.stamps):  # evo walks the stream with fewer poses
        index, covered = trajectory.nearest_stamps(ref.stamps, t_est, max_gap)
        pairs = Matched(t_est[covered], ref.R[index], est.R[covered], _rows(ref.b, index),
                        _rows(est.b, covered))
    else:
        index, covered = trajectory.nearest_stamps(t_est, ref.stamps, max_gap)
        pairs = Matched(ref.stamps[covered], ref.R[covered], est.R[index],
                        _rows(ref.b, covered), _rows(est.b, index))
    if len(pairs.stamps) < LEAST_PAIRS:
        raise CompareError(
            f'{len(pairs.stamps)} matched pair(s) within --max-gap {plain(max_gap)} s: at least '
            f'{LEAST_PAIRS} needed (EST: {len(est.stamps)} poses, REF: {len(ref.stamps)})')
    return pairs


def overlapping_pairs(stamps, delta, unit):
    """
    Index pairs (k, j), one per start k: j = k + Δ frames, or the first t_j ≥ t_k + Δ s.

    ≥ within rounding of the stamps, as delta_pairs decides (overlapping=True). The mounting
    averages over all of them (each pose starts one); RotationError if fewer than 2 fit.
    """
    pairs = delta_pairs(len(stamps), delta, unit, stamps, overlapping=True)
    if len(pairs) < 2:
        raise RotationError(f'--delta {plain(delta)} {unit} leaves {len(pairs)} '
                            f'relative rotation(s) among {len(stamps)} pairs: at least 2 '
                            'needed for a mounting')
    return pairs[:, 0], pairs[:, 1]


def mounting(pairs, delta, unit):
    """Return the mounting of the matched pairs over Δ (trajectory.hand_eye_rotation)."""
    k, j = overlapping_pairs(pairs.stamps, delta, unit)
    A = np.swapaxes(pairs.R_ref[k], 1, 2) @ pairs.R_ref[j]
    B = np.swapaxes(pairs.R_est[k], 1, 2) @ pairs.R_est[j]
    return trajectory.hand_eye_rotation(A, B)


class Result(NamedTuple):
    """What compare found: the report's pieces (radians) and the errors per pair."""

    pairs: Matched
    offset: trajectory.TimeOffset
    alignment: trajectory.FrameAlignment
    mount: trajectory.HandEye
    errors: trajectory.RotationErrors


def compare(est, ref, args):
    """Run the comparison of Poses est and ref with the parsed options (Result)."""
    if args.offset == 'auto':
        found = trajectory.estimate_time_offset(est.stamps, est.R, ref.stamps, ref.R,
                                                args.max_offset)
    else:
        found = trajectory.TimeOffset(args.offset, math.nan)
    gap = DEFAULT_GAP[args.match] if args.max_gap is None else args.max_gap
    pairs = match(est, ref, found.offset, args.match, gap)
    mount = mounting(pairs, args.delta, args.delta_unit) if args.mounting else None
    R_est = pairs.R_est if mount is None else pairs.R_est @ mount.rotation.T
    if args.align in ('se3', 'posyaw') and (pairs.b_ref is None or pairs.b_est is None):
        side = 'REF' if pairs.b_ref is None else 'EST'
        raise CompareError(f'--align {args.align} fits positions, and {side} has none (an '
                           'Imu): use --align rotation or yaw')
    alignment = trajectory.align_rotations(pairs.R_ref, R_est, args.align, b_ref=pairs.b_ref,
                                           b_est=pairs.b_est)
    errors = trajectory.rotation_errors(pairs.R_ref, alignment.W @ R_est, args.delta,
                                        args.delta_unit, pairs.stamps)
    return Result(pairs, found, alignment, mount, errors)


# ---- output -------------------------------------------------------------------------------


def _unit(x, degrees):
    return np.degrees(x) if degrees else x


def _statistics(stats, degrees):
    return {key: float(_unit(value, degrees)) for key, value in stats.items()}


def _quaternion(R):
    return [float(x) for x in matrix_to_quaternion(R, check=False)]


def _listed(M):
    """Return a matrix as a list of its rows (a vector as a list), plain floats."""
    return np.asarray(M, dtype=float).tolist()


def report(result, est, ref, args):
    """Return the report as plain data (to_yaml / to_json)."""
    degrees = args.deg
    e = result.errors
    out = {side: {'source': str(source), 'read': poses.name, 'poses': len(poses.stamps),
                  'dropped_duplicates': poses.dropped_duplicates, 'reordered': poses.reordered}
           for side, source, poses in (('est', args.est, est), ('ref', args.ref, ref))}
    out.update({
        'match': args.match, 'pairs': len(result.pairs.stamps), 'offset': result.offset.offset})
    if args.offset == 'auto':
        out['offset_correlation'] = result.offset.correlation
        warning = offset_warning(result.offset)
        if warning:
            out['offset_warning'] = warning
    out['alignment'] = args.align
    out['alignment_quaternion'] = _quaternion(result.alignment.W)
    out['alignment_matrix'] = _listed(result.alignment.W)
    out['alignment_translation'] = _listed(result.alignment.t)
    out['unit'] = 'deg' if degrees else 'rad'
    out['ape'] = _statistics(e.ape, degrees)
    out['rpe'] = _statistics(e.rpe, degrees)
    out['rpe_pairs'] = len(e.pairs)
    rpy = [_statistics(stats, degrees) for stats in e.rpy_statistics]  # wrapped to ±π
    out['rpy'] = {key: [axis[key] for axis in rpy] for key in rpy[0]}  # [roll, pitch, yaw]
    if result.mount is not None:
        m = result.mount
        out['mounting'] = {'quaternion': _quaternion(m.rotation), 'matrix': _listed(m.rotation),
                           'residual': float(_unit(m.residual, degrees)),
                           'axes': m.axes}
        if m.warning:
            out['mounting']['warning'] = m.warning
    return out


def offset_warning(found):
    """Return why an automatic offset (trajectory.TimeOffset) may be wrong, or None."""
    if found.correlation >= LOW_CORRELATION:
        return None
    return (f'the angular speeds correlate weakly at the offset found (r = '
            f'{found.correlation:.2f} < {LOW_CORRELATION:g}): the offset {found.offset:+.6g} s '
            'may be wrong, or the streams not of one motion; give --offset SECONDS')


def warnings(result, args):
    """Return the one-line warnings of a result (without the ``warning:`` prefix)."""
    out = []
    offset = offset_warning(result.offset) if args.offset == 'auto' else None
    if offset:
        out.append(offset)
    if result.mount is not None and result.mount.warning:
        out.append(f'mounting: {result.mount.warning}')
    return out


def write_csv(out, result, degrees, precision):
    """
    Write one row per pair to the text stream ``out``: stamp (exact), angle, roll, pitch, yaw.

    roll, pitch, yaw wrapped to (−π, π], as their statistics are.
    """
    e = result.errors
    table = _unit(np.column_stack([e.angle, trajectory.wrap_angles(e.rpy)]), degrees)
    out.write('stamp,angle,roll,pitch,yaw\n')
    for stamp, row in zip(result.pairs.stamps.tolist(), table.tolist()):
        cells = [repr(stamp)] + [repr(round_number(x, precision)) for x in row]
        out.write(','.join(cells) + '\n')


ALIGNMENT_TITLES = {
    'none': 'no alignment (W = I)', 'rotation': 'rotation alignment (least squares on SO(3))',
    'yaw': 'yaw alignment (about z)', 'se3': 'se3 alignment (Umeyama on the positions)',
    'posyaw': 'posyaw alignment (a yaw and a shift of the positions)'}
"""What the plot's title says of each --align."""


def figure(result, args):
    """
    Return the matplotlib Figure of the error angle, then its roll, pitch, yaw, against time.

    roll, pitch, yaw drawn continuous (unwrapped: a drift through ±180° stays a line); the
    title names the alignment, and the mounting when EST was turned by it.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    e, stamps, degrees = result.errors, result.pairs.stamps, args.deg
    time = stamps - stamps[0]
    unit = 'deg' if degrees else 'rad'
    fig = Figure(figsize=(9.0, 6.0), layout='constrained')
    FigureCanvasAgg(fig)
    total, parts = fig.subplots(2, 1, sharex=True)
    total.plot(time, _unit(e.angle, degrees), color='black', lw=1.0, label='angle')
    for k, (name, color) in enumerate(zip(('roll', 'pitch', 'yaw'),
                                          ('tab:red', 'tab:green', 'tab:blue'))):
        parts.plot(time, _unit(e.rpy[:, k], degrees), color=color, lw=1.0,
                   label=f'{name} (continuous)')
    for ax in (total, parts):
        ax.set_ylabel(f'error ({unit})')
        ax.grid(True, alpha=0.3)
        ax.legend(loc='upper left', fontsize=8, ncols=3)
    parts.set_xlabel(f'time (s) from {plain(stamps[0])} s')
    turned = ', EST turned by the mounting X' if result.mount is not None else ''
    fig.suptitle('rotation error E = R_refᵀ·W·R_est: angle, and roll, pitch, yaw (REP-103)\n'
                 f'{ALIGNMENT_TITLES[args.align]}{turned}', fontsize=11)
    return fig


def write_plot(path, result, args):
    """Write figure(result, args) to ``path`` (.png or .svg), whole or not at all."""
    fig = figure(result, args)
    with output_file.complete_or_nothing(path, 'wb') as out:
        fig.savefig(out, format=os.path.splitext(str(path))[1][1:].lower())


def run(args):
    """Run rot-tools compare on the parsed ``args``; return the exit status (0)."""
    for option, given in (('--point', args.point), ('--wxyz', args.wxyz),
                          ('--all-sequences', args.all_sequences), ('--seq', args.seq),
                          ('--tol', args.tol)):
        if given:
            options.error(f'{option} does not apply to compare')
    output_file.check_outputs([('--csv', args.csv), ('--plot', args.plot)],
                              [args.est, args.ref], force=args.force)
    try:
        est = read_side('EST', args.est, args.est_topic, args.est_tf, args.strict_stamps)
        ref = read_side('REF', args.ref, args.ref_topic, args.ref_tf, args.strict_stamps)
        result = compare(est, ref, args)
    except (CompareError, TrajectoryFileError, bag_read.BagError, RotationError) as exc:
        options.error(f'compare: {exc}')
    if args.plot:
        output_file.write_figure(lambda: write_plot(args.plot, result, args), args.plot,
                                 options.error)
    if args.csv is not None:
        output_file.write_table(lambda out: write_csv(out, result, args.deg, args.precision),
                                args.csv, options.error)
    if args.csv != '-':
        data = report(result, est, ref, args)
        text = to_json if args.json else to_yaml
        output_file.to_stdout(lambda out: out.write(text(data, precision=args.precision)))
    say_warnings((('EST', args.est, est), ('REF', args.ref, ref)), warnings(result, args))
    return 0
