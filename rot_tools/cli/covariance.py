"""
``rot-tools covariance INPUT ARGS... --cov C11 .. C33 --from A --to B``: one covariance, re-read.

The rotation is typed as the one-shot commands take it; its error's covariance (9 numbers,
rad²) is converted between a rotation vector in the parent or body frame, roll-pitch-yaw
and any Euler sequence (rot_tools.core.covariance), and printed as YAML or JSON.
"""

import argparse
import math
import sys

import numpy as np
from rot_tools.cli import axis_angle, euler, frame, matrix, options, quaternion, rotvec
from rot_tools.cli import output_file, typed_rotation
from rot_tools.core.covariance import change_covariance_frame, euler_covariance_to_rotvec
from rot_tools.core.covariance import FRAMES, rotvec_covariance_to_euler, validate_covariance
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import EULER_SEQUENCES, GIMBAL_LOCK_TOL, matrix_to_euler, RPY_SEQUENCE
from rot_tools.io import arguments
from rot_tools.io.message_covariance import stddev_correlation
from rot_tools.io.report import DEFAULT_PRECISION, sequence_hint, to_json, to_yaml

ROTVEC, RPY = 'rotvec', 'rpy'
INPUTS = (euler, matrix, axis_angle, rotvec, quaternion, frame)
"""The rotation's input kinds: rot-tools' one-shot commands that give a rotation, each
module's words (add_words) and reading (rotation)."""
COMMON = ('--deg', '--json', '--precision', '--tol', '--wxyz', '--version')
"""rot-tools' common options that apply here (--deg: the angles typed in the rotation)."""

_REPRESENTATION_HELP = (
    'rotvec (a small rotation vector, in --frame), rpy (roll, pitch, yaw about the fixed '
    f'X, Y, Z: the sequence {RPY_SEQUENCE}) or an Euler sequence (XYZ ... ZYZ intrinsic, '
    'xyz ... zyz extrinsic)')
_TEXT = (
    'The covariance (9 numbers, row by row, rad²) of the small error of a rotation, read\n'
    "as --from and printed as --to: rotvec (a rotation vector about the parent's fixed\n"
    'X, Y, Z, as geometry_msgs/PoseWithCovariance documents it, or with --frame body\n'
    "about the body's own axes), rpy (roll, pitch, yaw: the extrinsic sequence "
    f'{RPY_SEQUENCE}) or\n'
    'any of the 24 Euler sequences. First order: Σ_θ = E⁻¹·Σ_δ·E⁻ᵀ with E the\n'
    "Euler-rate matrix at R's angles; sequence to sequence through the rotation vector.\n"
    'Prints covariance (rad²), stddev (rad), stddev_deg, correlation, degenerate.\n'
    'At gimbal lock the covariance of the angles does not exist: degenerate: true, the\n'
    'numbers null, a note on stderr. --deg applies to the angles of the rotation (stddev\n'
    'is printed in both units); --precision N keeps N significant digits of the largest\n'
    'entry of each matrix or list, so that a variance of 1e-7 rad² keeps its digits.')
_EXAMPLES = (
    'rot-tools covariance quaternion 0 0.5 0 0.866 --from rotvec --to rpy '
    '--cov 1e-4 0 0  0 1e-4 0  0 0 4e-4\n'
    'rot-tools covariance euler xyz 5 60 30 --deg --from rpy --to rotvec --frame body '
    '--cov 3e-4 0 0  0 7.6e-5 0  0 0 1.4e-3 --json\n'
    'rot-tools covariance rotvec 0 0 1 --from rotvec --to rotvec --frame parent --to-frame '
    'body --cov 1e-4 0 0  0 2e-4 0  0 0 3e-4')


def _representation(text):
    """Return rotvec, rpy or an Euler sequence (argparse type of --from and --to)."""
    if text in (ROTVEC, RPY) or text in EULER_SEQUENCES:
        return text
    raise argparse.ArgumentTypeError(
        f'expected {_REPRESENTATION_HELP}, got {text.strip()!r}{sequence_hint(text)}')


def _add_options(p, suppress):
    """
    Add --cov, --from, --to, --frame, --to-frame to p: defaults on the command, none on INPUTs.

    An INPUT's --cov takes every number that follows, so that a wrong count is counted in
    the error line (run).
    """
    def default(value):
        return argparse.SUPPRESS if suppress else value
    cov = {'nargs': '+', 'metavar': 'C'} if suppress else {}
    arguments.add_cov(p, 'the covariance, 9 numbers C11 C12 C13 C21 .. C33 row by row, rad²: '
                      'finite, symmetric, positive semi-definite', default=default(None), **cov)
    p.add_argument('--from', dest='source', type=_representation, default=default(None),
                   metavar='A', help=f'how the covariance is read: {_REPRESENTATION_HELP}')
    p.add_argument('--to', dest='target', type=_representation, default=default(None),
                   metavar='B', help='what to print it as (the same choices)')
    p.add_argument('--frame', choices=FRAMES, default=default('parent'),
                   help="the rotation vector's frame (default parent): R_true = exp([δ]×)·R "
                   "about the parent's fixed axes, or R·exp([δ]×) about the body's")
    p.add_argument('--to-frame', choices=FRAMES, default=default(None),
                   help="with --to rotvec: the output rotation vector's frame, when it is not "
                   '--frame (parent to body: Rᵀ·Σ·R)')


def _add_leading_options(p):
    """Add the options that may come before INPUT: theirs, and the common ones that apply."""
    _add_options(p, suppress=False)
    options.add_common(p, suppress=True, only=COMMON)


def add_parser(subparsers):
    """
    Add ``rot-tools covariance`` to argparse's subparsers action and return its parser.

    Its commands are the input kinds of the rotation (INPUTS), each with the words of its
    one-shot command.
    """
    p = subparsers.add_parser(
        'covariance', help="a rotation's covariance as another representation (rotvec, rpy, "
        'an Euler sequence)',
        usage='rot-tools covariance INPUT ARGS... --cov C11 .. C33 --from A --to B\n'
        '       [--frame parent|body] [--to-frame parent|body] [--json] [--deg] [--precision N]',
        description=f"A rotation's covariance as another representation.\n\n{_TEXT}",
        epilog=f'INPUT is one of {", ".join(kind.NAME for kind in INPUTS)},\nwith its words as '
        'for "rot-tools INPUT" ("rot-tools covariance INPUT --help").\n\nexamples:\n  '
        + _EXAMPLES.replace('\n', '\n  '))
    inputs = p.add_commands(_add_leading_options, dest='input', metavar='INPUT', required=True)
    for kind in INPUTS:
        words = kind.USAGE.splitlines()[0].split(' [options]')[0]
        q = inputs.add_parser(
            kind.NAME, help=kind.SUMMARY,
            usage=f'rot-tools covariance {words}\n       --cov C11 .. C33 --from A --to B '
            '[--frame parent|body] [options]',
            description=f'The covariance of a rotation given as {kind.SUMMARY}.\n\n{_TEXT}')
        q.set_defaults(rotation=kind.rotation)
        kind.add_words(q)
        _add_options(q, suppress=True)
        options.add_common(q, suppress=True, only=COMMON)
    return p


def _sequence(word):
    return RPY_SEQUENCE if word == RPY else word


def _frames(args):
    """Return (from_frame, to_frame): the rotation vectors' frames, None for Euler angles."""
    if args.to_frame is not None and args.target != ROTVEC:
        options.error('--to-frame applies to --to rotvec only (Euler angles have no frame)')
    source = args.frame if args.source == ROTVEC else None
    target = (args.to_frame or args.frame) if args.target == ROTVEC else None
    return source, target


def convert(R, C, source, target, source_frame='parent', target_frame='parent'):
    """
    Return (Σ as ``target``, the gimbal-locked sequence or None) of Σ = C read as ``source``.

    R (3, 3) the rotation, C (3, 3) a valid covariance in rad²; source and target are
    rotvec, rpy or a sequence; the frames apply to rotvec. At gimbal lock Σ is None.
    """
    if source == ROTVEC and target == ROTVEC:
        if source_frame == target_frame:
            return C, None
        return change_covariance_frame(C, R if source_frame == 'body' else R.T), None
    if source == ROTVEC:
        out, lock = rotvec_covariance_to_euler(R[None], C[None], _sequence(target), source_frame)
        return (None, _sequence(target)) if lock[0] else (out[0], None)
    seq = _sequence(source)
    angles, _ = matrix_to_euler(R, seq)
    frame = target_frame if target == ROTVEC else 'parent'
    out, lock = euler_covariance_to_rotvec(angles[None], C[None], seq, frame)
    if lock[0]:
        return None, seq
    if target == ROTVEC:
        return out[0], None
    return convert(R, out[0], ROTVEC, target, 'parent')


def _rounded(values, precision):
    """Round to ``precision`` significant digits of the largest |value| (a list of floats)."""
    values = np.asarray(values, dtype=np.float64)
    scale = float(np.abs(values).max())
    digits = precision - 1 - math.floor(math.log10(scale)) if 0 < scale < math.inf else 0
    return np.vectorize(lambda x: round(float(x), digits) + 0.0)(values).tolist()


def report(R, C, source, target, frames, precision=DEFAULT_PRECISION):
    """
    Return (the report's plain data, the locked sequence or None).

    The data: from, from_frame, to, to_frame (None for Euler angles), covariance (rad²),
    stddev (rad), stddev_deg, correlation and degenerate; each matrix or list rounded to
    ``precision`` significant digits of its largest entry. At gimbal lock of either
    sequence the covariance does not exist: degenerate True and the numbers None.
    """
    scale = float(np.abs(C).max()) or 1.0  # linear in C: converted as C / max|C|, so that
    out, locked = convert(R, C / scale, source, target, *(f or 'parent' for f in frames))
    out = None if out is None else out * scale  # entries near 1e308 do not overflow on the way
    data = {'from': source, 'from_frame': frames[0], 'to': target, 'to_frame': frames[1]}
    if locked is not None:
        data.update(covariance=None, stddev=None, stddev_deg=None, correlation=None)
    elif not np.isfinite(out).all():
        raise RotationError('--cov: the converted covariance overflows float64')
    else:
        stddev, correlation = stddev_correlation(out)
        data.update(covariance=_rounded(out, precision), stddev=_rounded(stddev, precision),
                    stddev_deg=_rounded(np.degrees(stddev), precision),
                    correlation=_rounded(correlation, precision))
    data['degenerate'] = locked is not None
    return data, locked


def _lock_note(seq):
    proper = seq[0].lower() == seq[2].lower()
    where = '0° or 180°' if proper else '±90°'
    return (f'the rotation is at gimbal lock of {seq!r} (θ2 = {where}, within '
            f'GIMBAL_LOCK_TOL = {GIMBAL_LOCK_TOL:g} rad): the covariance of its angles does '
            'not exist; covariance and stddev are null')


def run(args):
    """Run rot-tools covariance on the parsed ``args``; return the exit status (0)."""
    for option, given in (('--seq', args.seq), ('--all-sequences', args.all_sequences),
                          ('--point', args.point), ('--plot', args.plot)):
        if given:
            options.error(f'{option} does not apply to covariance')
    missing = [o for o, v in (('--cov', args.cov), ('--from', args.source),
                              ('--to', args.target)) if v is None]
    if missing:
        options.error(f'the following arguments are required: {", ".join(missing)}')
    if len(args.cov) != 9:
        options.error(f'--cov: expected 9 numbers (C11 C12 C13 C21 .. C33, row by row, rad²), '
                      f'got {len(args.cov)}')
    frames = _frames(args)
    R, _, _ = typed_rotation.read(args, args.rotation, f'covariance {args.input}')
    C = np.reshape(args.cov, (3, 3))
    with np.errstate(all='ignore'):  # entries near 1e308: converted as C / max|C| (report)
        try:
            validate_covariance(C, name='--cov')
            data, locked = report(R, C, args.source, args.target, frames, args.precision)
        except RotationError as exc:
            options.error(str(exc))
    text = to_json if args.json else to_yaml
    # flushed before the note or hint: in this order on a shared terminal or pipe
    output_file.to_stdout(lambda out: out.write(text(data, precision=None)))
    if locked is not None:
        sys.stderr.write(f'{options.PROG}: note: {_lock_note(locked)}\n')
    for hint in args.hints:
        sys.stderr.write(f'{options.PROG}: hint: {hint}\n')
    return 0
