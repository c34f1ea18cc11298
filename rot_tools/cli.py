"""rot-tools: every representation of a rotation or rigid transform, on the command line.

No ROS needed: argparse over rot_tools and rot_tools.report. Each subcommand reads one kind
of input, turns it into (R, b) and prints ``transform_report`` (keys documented in
rot_tools.report) as YAML, or JSON with ``--json``::

    rot-tools euler ZYX 30 20 10 --deg
    rot-tools matrix 0 -1 0  1 0 0  0 0 1
    rot-tools axis-angle 0 0 1 90 --deg
    rot-tools rotvec 0 0 1.5707963267949
    rot-tools screw --euler ZYX 90 0 0 --translation 1 0 0.5 --deg

Typed matrices are validated with a tolerance (``--tol``, default 1e-5, on max|RᵀR − I|
and |det R − 1|) so that six significant digits are enough, then replaced by the nearest
rotation (rot_tools.nearest_rotation) before the math, which checks at 1e-9.

Bad input — a wrong count, a non-number, NaN/Inf, a matrix that is not a rotation or is a
reflection, an unknown sequence, a zero axis with a non-zero angle — prints exactly one
line ``rot-tools: error: ...`` on stderr and exits with status 2.
"""

import argparse
import math
import re
import sys

import numpy as np

from rot_tools import (
    axis_angle_to_matrix, EULER_SEQUENCES, euler_to_matrix, nearest_rotation,
    rotvec_to_matrix, validate_rotation)
from rot_tools.errors import RotationError
from rot_tools.report import DEFAULT_PRECISION, to_json, to_yaml, transform_report

PROG = 'rot-tools'
DEFAULT_TOL = 1e-5
"""Default tolerance on max|RᵀR − I| and |det R − 1| of a typed matrix (six digits pass)."""

# argparse (3.11) reads '-30' and '-.5' as values but '-1e-3' or '-inf' as an unknown
# option. Its (private, long-standing) _negative_number_matcher is set to this pattern, so
# every negative number (and -inf/-nan, refused later with a clear message) is a value.
# None of our options looks like a number, so nothing is shadowed; a test pins it.
_NEGATIVE_NUMBER = re.compile(
    r'^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$', re.IGNORECASE)

_SEQUENCE_HELP = (
    'one of the 12 axis orders XYZ XZY YXZ YZX ZXY ZYX XYX XZX YXY YZY ZXZ ZYZ; '
    'upper case = intrinsic (body axes), lower case = extrinsic (fixed axes)')


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line (no usage block) and exit status 2."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault('formatter_class', argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER

    def error(self, message):
        """Print ``rot-tools: error: message`` on one line and exit 2."""
        self.exit(2, f'{PROG}: error: {" ".join(str(message).split())}\n')


# ---------------------------------------------------------------------------------------
# Value types (argparse turns their ArgumentTypeError into 'argument X: message')


def _number(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text!r}') from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'not a finite number: {text!r}')
    return value


def _sequence(text):
    if text not in EULER_SEQUENCES:
        raise argparse.ArgumentTypeError(
            f'unknown Euler sequence {text!r}: use {_SEQUENCE_HELP}')
    return text


def _precision(text):
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= 17:
        raise argparse.ArgumentTypeError(f'expected an integer 1..17, got {text!r}')
    return value


def _plot_file(text):
    if not text.lower().endswith(('.png', '.svg')):
        raise argparse.ArgumentTypeError(f'FILE must end in .png or .svg, got {text!r}')
    return text


def _tolerance(text):
    value = _number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f'must be >= 0, got {text!r}')
    return value


# ---------------------------------------------------------------------------------------
# Inputs → (R, b, default output sequence)


def _count(parser, values, n, what):
    if len(values) != n:
        parser.error(f'{what}: expected {n} numbers, got {len(values)}')
    return np.array(values)


def _angle_in(values, deg):
    return np.radians(values) if deg else np.asarray(values, dtype=np.float64)


def _typed_matrix(parser, values, tol, what):
    """Validate a typed 3x3 matrix at tol, then project it onto the nearest rotation."""
    R = _count(parser, values, 9, what).reshape(3, 3)
    try:
        validate_rotation(R, tol=tol)
    except RotationError as exc:
        hint = ' (the tolerance is --tol)' if np.linalg.det(R) > 0 else ''
        parser.error(f'{what}: {exc}{hint}')
    return nearest_rotation(R)


def _from_euler(args, parser):
    angles = _count(parser, args.angles, 3, f'euler {args.sequence} angles')
    return euler_to_matrix(_angle_in(angles, args.deg), args.sequence), None, args.sequence


def _from_matrix(args, parser):
    return _typed_matrix(parser, args.entries, args.tol, 'matrix'), None, None


def _from_axis_angle(args, parser):
    v = _count(parser, args.values, 4, 'axis-angle X Y Z ANGLE')
    return axis_angle_to_matrix(v[:3], _angle_in(v[3], args.deg)), None, None


def _from_rotvec(args, parser):
    v = _count(parser, args.vector, 3, 'rotvec X Y Z')
    return rotvec_to_matrix(_angle_in(v, args.deg)), None, None


def _from_screw(args, parser):
    if args.rotation is not None:
        R = _typed_matrix(parser, args.rotation, args.tol, 'argument --rotation')
    elif args.euler is not None:
        seq, *angles = args.euler
        try:
            seq, angles = _sequence(seq), [_number(a) for a in angles]
        except argparse.ArgumentTypeError as exc:
            parser.error(f'argument --euler: {exc}')
        R = euler_to_matrix(_angle_in(angles, args.deg), seq)
    elif args.axis_angle is not None:
        v = np.array(args.axis_angle)
        try:
            R = axis_angle_to_matrix(v[:3], _angle_in(v[3], args.deg))
        except RotationError as exc:
            parser.error(f'argument --axis-angle: {exc}')
    elif args.rotvec is not None:
        R = rotvec_to_matrix(_angle_in(args.rotvec, args.deg))
    else:
        R = np.eye(3)
    return R, np.array(args.translation), None


# ---------------------------------------------------------------------------------------
# The parser

_COMMANDS = {
    'euler': (
        _from_euler, 'Euler angles of a sequence',
        'euler SEQ A1 A2 A3 [options]',
        'R = Rot_a1(A1)·Rot_a2(A2)·Rot_a3(A3) for an upper-case (intrinsic) SEQ,\n'
        'Rot_a3(A3)·Rot_a2(A2)·Rot_a1(A1) for a lower-case (extrinsic) one.\n'
        'The output sequence is SEQ unless --seq says otherwise.',
        'rot-tools euler ZYX 30 20 10 --deg\n'
        'rot-tools euler zyx -30 20 10 --deg --seq XYZ --json\n'
        'rot-tools euler ZYX 0 90 0 --deg --all-sequences'),
    'matrix': (
        _from_matrix, 'a rotation matrix, 9 numbers row by row',
        'matrix R11 R12 R13 R21 R22 R23 R31 R32 R33 [options]',
        'The matrix must be a rotation within --tol (max|RᵀR − I| and |det R − 1|);\n'
        'it is then replaced by the nearest rotation, so six significant digits suffice.',
        'rot-tools matrix 0 -1 0  1 0 0  0 0 1\n'
        'rot-tools matrix 0.866025 -0.5 0  0.5 0.866025 0  0 0 1 --deg'),
    'axis-angle': (
        _from_axis_angle, 'a rotation axis and angle (Rodrigues)',
        'axis-angle X Y Z ANGLE [options]',
        'The axis (X, Y, Z) is normalised; a zero axis needs a zero angle.',
        'rot-tools axis-angle 0 0 1 90 --deg\n'
        'rot-tools axis-angle 1 1 1 2.0943951 --json'),
    'rotvec': (
        _from_rotvec, 'a rotation vector θ·l̂ (its norm is the angle)',
        'rotvec X Y Z [options]',
        "With --deg the vector's norm is in degrees.",
        'rot-tools rotvec 0 0 1.5707963267949\n'
        'rot-tools rotvec 0 90 0 --deg'),
    'screw': (
        _from_screw, 'a rigid transform (R, b) and its screw (Chasles) decomposition',
        'screw [--rotation R11 .. R33 | --euler SEQ A1 A2 A3 | --axis-angle X Y Z ANGLE |\n'
        '       --rotvec X Y Z] --translation X Y Z [options]',
        'p ↦ R·p + b is a rotation by `angle` about the line through `point` along\n'
        '`direction`, then a translation `translation` along it; pitch = translation/angle\n'
        '(.inf in YAML and "inf" in JSON for a pure translation). The rotation defaults to\n'
        'the identity.',
        'rot-tools screw --euler ZYX 90 0 0 --translation 1 0 0.5 --deg\n'
        'rot-tools screw --rotation 0 -1 0  1 0 0  0 0 1 --translation 0 0 1 --json\n'
        'rot-tools screw --translation 1 2 3'),
}


def _add_common(parser, suppress):
    """Output options, accepted before the subcommand and after its arguments."""
    def default(value):
        return argparse.SUPPRESS if suppress else value
    out = parser.add_argument_group('output') if suppress else parser
    out.add_argument('--deg', action='store_true', default=default(False),
                     help='angles in degrees, in and out (axis-angle and screw angles are '
                     'printed in both units anyway)')
    out.add_argument('--seq', type=_sequence, default=default(None), metavar='SEQ',
                     help='Euler sequence of the output, any of the 24 (default: the input '
                     'sequence for euler, else ZYX)')
    out.add_argument('--all-sequences', action='store_true', default=default(False),
                     help='also print the Euler angles in all 24 sequences, each with its '
                     'gimbal-lock flag `degenerate`')
    out.add_argument('--json', action='store_true', default=default(False),
                     help='print JSON instead of YAML (an infinite pitch is the string "inf")')
    out.add_argument('--precision', type=_precision, default=default(DEFAULT_PRECISION),
                     metavar='N', help='round numbers to N significant digits and N decimal '
                     f'places (default {DEFAULT_PRECISION}); -0.0 prints as 0.0')
    out.add_argument('--plot', type=_plot_file, default=default(None), metavar='FILE',
                     help='also draw the motion in FILE (.png or .svg): both frames, the '
                     "rotation or screw axis, the path of the origin; needs matplotlib (pip "
                     "install 'rot_tools[plot]')")


def _add_tol(parser):
    parser.add_argument(
        '--tol', type=_tolerance, default=DEFAULT_TOL, metavar='TOL',
        help='a typed matrix may deviate from a rotation by this much in max|RᵀR − I| and '
        f'|det R − 1| (default {DEFAULT_TOL:g}); it is then projected onto the nearest one')


def build_parser():
    """Build the rot-tools ArgumentParser (one subparser per input kind)."""
    parser = _Parser(
        prog=PROG,
        description='Print every representation of a rotation or rigid transform: matrix,\n'
        'axis-angle (both solutions), rotation vector, Euler angles, and for a transform\n'
        'its screw. YAML by default, JSON with --json. Angles in radians unless --deg.\n'
        'Output options may come before COMMAND or after its arguments.',
        epilog='examples:\n  ' + '\n  '.join(
            spec[4].splitlines()[0] for spec in _COMMANDS.values())
        + '\n\n"rot-tools COMMAND --help" explains each command.')
    _add_common(parser, suppress=False)
    sub = parser.add_subparsers(dest='command', metavar='COMMAND', required=True,
                                parser_class=_Parser)
    for name, (handler, summary, usage, text, examples) in _COMMANDS.items():
        p = sub.add_parser(
            name, help=summary, usage=f'{PROG} {usage}',
            description=f'{summary[0].upper()}{summary[1:]}.\n\n{text}',
            epilog='examples:\n  ' + examples.replace('\n', '\n  '))
        p.set_defaults(handler=handler)
        if name == 'euler':
            p.add_argument('sequence', type=_sequence, metavar='SEQ', help=_SEQUENCE_HELP)
            p.add_argument('angles', type=_number, nargs='*', metavar='ANGLE',
                           help='the three angles A1 A2 A3 (rad, or deg with --deg)')
        elif name == 'matrix':
            p.add_argument('entries', type=_number, nargs='*', metavar='ENTRY',
                           help='the 9 entries R11 R12 R13 R21 R22 R23 R31 R32 R33')
            _add_tol(p)
        elif name == 'axis-angle':
            p.add_argument('values', type=_number, nargs='*', metavar='NUMBER',
                           help='X Y Z ANGLE: the axis (any length > 0) and the angle')
        elif name == 'rotvec':
            p.add_argument('vector', type=_number, nargs='*', metavar='COMPONENT',
                           help='X Y Z: θ·l̂ (rad, or deg with --deg)')
        else:
            rotation = p.add_mutually_exclusive_group()
            rotation.add_argument('--rotation', type=_number, nargs=9,
                                  metavar=tuple(f'R{i}{j}' for i in '123' for j in '123'),
                                  help='the 9 entries of R, row by row')
            rotation.add_argument('--euler', nargs=4, metavar=('SEQ', 'A1', 'A2', 'A3'),
                                  help='R from Euler angles')
            rotation.add_argument('--axis-angle', type=_number, nargs=4,
                                  metavar=('X', 'Y', 'Z', 'ANGLE'), help='R from axis-angle')
            rotation.add_argument('--rotvec', type=_number, nargs=3, metavar=('X', 'Y', 'Z'),
                                  help='R from a rotation vector')
            p.add_argument('--translation', type=_number, nargs=3, required=True,
                           metavar=('X', 'Y', 'Z'), help='the translation b')
            _add_tol(p)
        _add_common(p, suppress=True)
    return parser


def _write_plot(parser, path, R, b, degrees):
    """Draw (R, b) into ``path`` with rot_tools.plot, imported only now (matplotlib)."""
    try:
        from rot_tools import plot
    except ImportError as exc:
        if not (exc.name or '').startswith(('matplotlib', 'mpl_toolkits')):
            raise
        parser.error("--plot needs matplotlib, the 'plot' extra: "
                     "pip install 'rot_tools[plot]'")
    try:
        plot.save(R, b, path, degrees)
    except OSError as exc:
        parser.error(f'--plot: cannot write {path}: {exc.strerror or exc}')


def main(argv=None):
    """Run rot-tools on argv (default sys.argv[1:]); return the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        try:
            R, b, input_seq = args.handler(args, parser)
            report = transform_report(R, b, seq=args.seq or input_seq or 'ZYX',
                                      degrees=args.deg, all_sequences=args.all_sequences)
        except ValueError as exc:  # RotationError is a ValueError
            parser.error(f'{args.command}: {exc}')
        if args.plot:
            _write_plot(parser, args.plot, R, b, args.deg)
    except SystemExit as exc:  # argparse's --help (0) and errors (2)
        return exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
    text = to_json if args.json else to_yaml
    sys.stdout.write(text(report, precision=args.precision))
    return 0


if __name__ == '__main__':
    sys.exit(main())
