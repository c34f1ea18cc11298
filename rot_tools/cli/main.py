"""
rot-tools: every representation of a rotation or rigid transform, on the command line.

No ROS needed: argparse over rot_tools and rot_tools.io.report. Each subcommand reads one kind
of input, turns it into (R, b) and prints ``transform_report`` (keys documented in
rot_tools.io.report) as YAML, or JSON with ``--json``::

    rot-tools euler ZYX 30 20 10 --deg
    rot-tools matrix 0 -1 0  1 0 0  0 0 1
    rot-tools axis-angle 0 0 1 90 --deg
    rot-tools rotvec 0 0 1.5707963267949
    rot-tools quaternion 0 0 0.7071 0.7071
    rot-tools frame 0 1 0  -1 0 0  0 0 1
    rot-tools matrix 0 -1 0 1  1 0 0 0  0 0 1 0.5  0 0 0 1
    rot-tools screw --euler ZYX 90 0 0 --translation 1 0 0.5 --deg --point 1 2 3
    rot-tools bag run.bag --csv run.csv --plot rpy.png   (rot_tools.cli.bag: the 'bag' extra)
    rot-tools compare est.tum gt.csv --align se3          (rot_tools.cli.compare)
    rot-tools covariance quaternion 0 0 0 1 --cov 1e-4 0 0 0 1e-4 0 0 0 1e-4 --from rotvec --to rpy

Every option is accepted before the command, after its arguments (``_add_common``) and
between them (``_CommandParser``).

Typed inputs are validated with a tolerance ``--tol``, then made exact before the math,
which checks at 1e-9. A matrix (9 numbers, or the rotation block of a homogeneous 4×4):
max|RᵀR − I| and |det R − 1| ≤ tol (default ``MATRIX_TOL`` = 1e-5, so six significant
digits are enough), then the nearest rotation (rot_tools.nearest_rotation). A frame: its
axes normalised, |cos| between any two ≤ tol (same default), then the nearest rotation. A
quaternion, (x, y, z, w) — the ROS order — or (w, x, y, z) with ``--wxyz``: ||q| − 1| ≤ tol
(default ``QUATERNION_TOL`` = 1e-3, the node's quaternion_tolerance, so four significant
digits are enough), then normalised. A homogeneous matrix's last row must be (0, 0, 0, 1)
to 1e-9 (rot_tools.homogeneous_to_transform; --tol does not apply).

Bad input — a wrong count, a non-number, NaN/Inf, a matrix that is not a rotation or is a
reflection, a homogeneous matrix whose last row is not 0 0 0 1, a zero, non-orthogonal or
left-handed frame, a zero quaternion or one too far from unit length, an unknown sequence,
a zero axis with a non-zero angle — prints exactly one line ``rot-tools: error: ...`` on
stderr and exits with status 2. An angle typed without ``--deg`` that is larger than 2π
only gets a one-line ``rot-tools: hint: ...`` on stderr (after the report; status 0).
"""

import argparse
import math
import sys

import numpy as np
from rot_tools import (
    axis_angle_to_matrix, EULER_SEQUENCES, euler_to_matrix, frame_to_matrix,
    homogeneous_to_transform, nearest_rotation, quaternion_to_matrix, rotvec_to_matrix,
    validate_rotation)
from rot_tools.cli import compare, covariance, output_file
from rot_tools.core.errors import RotationError
from rot_tools.io.arguments import negative_numbers_as_values, whole_number
from rot_tools.io.message_covariance import READINGS
from rot_tools.io.report import angle_hint, DEFAULT_PRECISION, sequence_hint, to_json, to_yaml
from rot_tools.io.report import transform_report

PROG = 'rot-tools'
MATRIX_TOL = 1e-5
"""Default tolerance of a typed matrix (max|RᵀR − I|, |det R − 1|) or frame (|cos| between
two axes): six significant digits pass."""
QUATERNION_TOL = 1e-3
"""Default tolerance on ||q| − 1| of a typed quaternion (four digits pass; as the node's)."""

_SEQUENCE_HELP = (
    'one of the 12 axis orders XYZ XZY YXZ YZX ZXY ZYX XYX XZX YXY YZY ZXZ ZYZ; '
    'upper case = intrinsic (body axes), lower case = extrinsic (fixed axes)')


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line (no usage block) and exit status 2."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault('formatter_class', argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message):
        """Print ``rot-tools: error: message`` on one line and exit 2."""
        self.exit(2, f'{PROG}: error: {" ".join(str(message).split())}\n')


class _CommandParser(_Parser):
    """
    Make a command's parser that takes options between its arguments.

    A command's parser: options may also come between its arguments (``euler ZYX --deg 30
    20 10``), which plain argparse refuses once a ``nargs='*'`` argument has matched nothing.
    """

    intermixed = True
    """False for a command with commands of its own (argparse cannot intermix those)."""
    _intermixing = False

    def parse_known_args(self, args=None, namespace=None):
        """parse_known_intermixed_args, which calls this method again for its two passes."""
        if self._intermixing or not self.intermixed:
            return super().parse_known_args(args, namespace)
        self._intermixing = True
        try:
            return self.parse_known_intermixed_args(args, namespace)
        finally:
            self._intermixing = False


class _Version(argparse.Action):
    """--version: the installed distribution's version (setup.py's), looked up when asked."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help=None):  # noqa: A002
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        from importlib.metadata import PackageNotFoundError, version  # ~40 ms: when asked
        try:
            text = f'{PROG} {version("rot_tools")}'
        except PackageNotFoundError:
            parser.error('--version: rot_tools is not installed (no distribution metadata)')
        print(text)
        parser.exit(0)


# ---------------------------------------------------------------------------------------
# Value types (argparse turns their ArgumentTypeError into 'argument X: message')


def _number(text):
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text.strip()!r}') from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'not a finite number: {text.strip()!r}')
    return value


def _sequence(text):
    if text not in EULER_SEQUENCES:
        raise argparse.ArgumentTypeError(
            f'unknown Euler sequence {text.strip()!r}: use {_SEQUENCE_HELP}{sequence_hint(text)}')
    return text


def _precision(text):
    try:
        value = int(text)
    except ValueError:
        value = 0
    if not 1 <= value <= 17:
        raise argparse.ArgumentTypeError(f'expected an integer 1..17, got {text.strip()!r}')
    return value


def _plot_file(text):
    if not text.lower().endswith(('.png', '.svg')):
        raise argparse.ArgumentTypeError(f'FILE must end in .png or .svg, got {text.strip()!r}')
    return text


def _seconds(text):
    value = _number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(
            f"must be >= 0 seconds from the bag's start, got {text.strip()!r}")
    return value


def _tolerance(text):
    value = _number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f'must be >= 0, got {text.strip()!r}')
    return value


# ---------------------------------------------------------------------------------------
# Inputs → (R, b, default output sequence)


def _count(parser, values, n, what):
    if len(values) != n:
        parser.error(f'{what}: expected {n} numbers, got {len(values)}')
    return np.array(values)


def _tol(args, default):
    return default if args.tol is None else args.tol


def _angle_in(args, values, size=None):
    """
    Angles in radians; a hint when radians typed without --deg look like degrees.

    ``size`` is the angle the hint is about (default the largest |value|; a rotation
    vector's is its norm). The hint is printed after the report (see main).
    """
    if args.deg:
        return np.radians(values)
    values = np.asarray(values, dtype=np.float64)
    hint = angle_hint(values if size is None else [size])
    if hint:
        args.hints.append(hint)
    return values


def _typed_matrix(parser, args, values, what):
    """Validate a typed 3x3 matrix at --tol, then project it onto the nearest rotation."""
    R = _count(parser, values, 9, what).reshape(3, 3)
    try:
        validate_rotation(R, tol=_tol(args, MATRIX_TOL))
    except RotationError as exc:
        hint = ' (the tolerance is --tol)' if _det_sign(R) > 0 else ''
        parser.error(f'{what}: {exc}{hint}')
    return nearest_rotation(R)


def _det_sign(R):
    """Sign of det R for any finite R: scaled first, so entries of 1e308 do not overflow."""
    scale = float(np.abs(R).max()) if np.isfinite(R).all() else 0.0
    if not scale > 0:
        return 0.0
    with np.errstate(all='ignore'):  # a singular R: LU divides by a zero pivot
        return float(np.sign(np.linalg.det(R / scale)))


def _typed_frame(parser, args, values, what):
    """R = (û v̂ ŵ) of typed axes U V W, |cos| between axes ≤ --tol, then made exact."""
    u, v, w = _count(parser, values, 9, what).reshape(3, 3)
    try:
        R = frame_to_matrix(u, v, w, tol=_tol(args, MATRIX_TOL))
    except RotationError as exc:
        hint = ' (the tolerance is --tol)' if 'not orthogonal' in str(exc) else ''
        parser.error(f'{what}: {exc}{hint}')
    return nearest_rotation(R)


def _typed_quaternion(parser, args, values, what):
    """R of a typed quaternion: x y z w (w x y z with --wxyz), ||q| − 1| ≤ --tol."""
    q = _count(parser, values, 4, what)
    if args.wxyz:
        q = np.roll(q, -1)  # (w, x, y, z) → (x, y, z, w)
    try:
        return quaternion_to_matrix(q, tol=_tol(args, QUATERNION_TOL))  # normalises q
    except RotationError as exc:
        hint = ' (the tolerance is --tol)' if 'unit length' in str(exc) else ''
        parser.error(f'{what}: {exc}{hint}')


def _from_euler(args, parser):
    angles = _count(parser, args.angles, 3, f'euler {args.sequence} angles')
    return euler_to_matrix(_angle_in(args, angles), args.sequence), None, args.sequence


def _from_matrix(args, parser):
    if len(args.entries) == 9:
        return _typed_matrix(parser, args, args.entries, 'matrix'), None, None
    if len(args.entries) != 16:
        parser.error(f'matrix: expected 9 numbers (R) or 16 (a homogeneous 4×4 matrix), got '
                     f'{len(args.entries)}')
    try:  # the last row is checked here (at 1e-9), the rotation block below (at --tol)
        R, b = homogeneous_to_transform(np.reshape(args.entries, (4, 4)), check=False)
    except RotationError as exc:
        parser.error(f'matrix: {exc}')
    return _typed_matrix(parser, args, R.ravel(), 'matrix T[:3, :3]'), b, None


def _from_frame(args, parser):
    return _typed_frame(parser, args, args.axes, 'frame U V W'), None, None


def _from_axis_angle(args, parser):
    v = _count(parser, args.values, 4, 'axis-angle X Y Z ANGLE')
    return axis_angle_to_matrix(v[:3], _angle_in(args, v[3])), None, None


def _from_rotvec(args, parser):
    v = _count(parser, args.vector, 3, 'rotvec X Y Z')
    return rotvec_to_matrix(_angle_in(args, v, size=math.hypot(*v))), None, None


def _from_quaternion(args, parser):
    what = 'quaternion W X Y Z' if args.wxyz else 'quaternion X Y Z W'
    return _typed_quaternion(parser, args, args.components, what), None, None


def _from_screw(args, parser):
    if args.rotation is not None:
        R = _typed_matrix(parser, args, args.rotation, 'argument --rotation')
    elif args.quaternion is not None:
        R = _typed_quaternion(parser, args, args.quaternion, 'argument --quaternion')
    elif args.frame is not None:
        R = _typed_frame(parser, args, args.frame, 'argument --frame')
    elif args.euler is not None:
        seq, *angles = args.euler
        try:
            seq, angles = _sequence(seq), [_number(a) for a in angles]
        except argparse.ArgumentTypeError as exc:
            parser.error(f'argument --euler: {exc}')
        R = euler_to_matrix(_angle_in(args, angles), seq)
    elif args.axis_angle is not None:
        v = np.array(args.axis_angle)
        try:
            R = axis_angle_to_matrix(v[:3], _angle_in(args, v[3]))
        except RotationError as exc:
            parser.error(f'argument --axis-angle: {exc}')
    elif args.rotvec is not None:
        v = np.array(args.rotvec)
        R = rotvec_to_matrix(_angle_in(args, v, size=math.hypot(*v)))
    else:
        R = np.eye(3)
    return R, np.array(args.translation), None


def _reads_quaternion(args):
    kind = getattr(args, 'input', args.command)  # covariance's input
    return kind == 'quaternion' or getattr(args, 'quaternion', None) is not None


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
        _from_matrix, 'a rotation matrix (9 numbers) or a homogeneous 4×4 (16), row by row',
        'matrix R11 R12 R13 R21 R22 R23 R31 R32 R33 [options]\n'
        '       rot-tools matrix R11 R12 R13 X  R21 R22 R23 Y  R31 R32 R33 Z  0 0 0 1 [options]',
        'The rotation (R, or the block T[:3, :3] of the 4×4 T = [[R, b], [0, 0, 0, 1]])\n'
        'must be a rotation within --tol (max|RᵀR − I| and |det R − 1|, default\n'
        f'{MATRIX_TOL:g}); it is then replaced by the nearest rotation, so six significant\n'
        "digits suffice. A 4×4's last row must be 0 0 0 1 (to 1e-9); its last column is\n"
        'the translation b of p ↦ R·p + b, and the report adds the screw.',
        'rot-tools matrix 0 -1 0  1 0 0  0 0 1\n'
        'rot-tools matrix 0.866025 -0.5 0  0.5 0.866025 0  0 0 1 --deg\n'
        'rot-tools matrix 0 -1 0 1  1 0 0 0  0 0 1 0.5  0 0 0 1 --point 1 2 3'),
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
    'quaternion': (
        _from_quaternion, 'a quaternion, x y z w (the ROS message order)',
        'quaternion X Y Z W [options]    (W X Y Z with --wxyz)',
        'The order of geometry_msgs/Quaternion, as `ros2 topic echo` prints it;\n'
        '--wxyz reads w first (Eigen, transforms3d). |q| must be 1 within --tol\n'
        f'(default {QUATERNION_TOL:g}, so four significant digits suffice); q is then\n'
        'normalised. q and −q are the same rotation; the report prints the one with w > 0.',
        'rot-tools quaternion 0 0 0.7071 0.7071\n'
        'rot-tools quaternion 0.7071 0 0 0.7071 --wxyz --deg\n'
        'rot-tools quaternion 0.1 -0.2 0.3 0.927 --tol 1e-2 --json'),
    'frame': (
        _from_frame,
        "a frame's axes u, v, w written in the reference frame (Jia, Rotation in the Space, §4)",
        'frame UX UY UZ VX VY VZ WX WY WZ [options]',
        'R = (û v̂ ŵ): the axes are the columns of R, each normalised. They must be\n'
        f'orthogonal within --tol (|cos| between any two, default {MATRIX_TOL:g}) and\n'
        'right-handed ((û × v̂)·ŵ = +1); the frame is then made exactly orthonormal\n'
        '(nearest rotation). With --point P the report gives the coordinates Rᵀ·P of P in\n'
        'this frame.',
        'rot-tools frame 0 1 0  -1 0 0  0 0 1\n'
        'rot-tools frame 1 1 0  -1 1 0  0 0 1 --deg\n'
        'rot-tools frame 0 0 1  1 0 0  0 1 0 --point 1 2 3'),
    'screw': (
        _from_screw, 'a rigid transform (R, b) and its screw (Chasles) decomposition',
        'screw [--rotation R11 .. R33 | --quaternion X Y Z W | --frame U V W |\n'
        '       --euler SEQ A1 A2 A3 | --axis-angle X Y Z ANGLE | --rotvec X Y Z]\n'
        '       --translation X Y Z [options]',
        'p ↦ R·p + b is a rotation by `angle` about the line through `point` along\n'
        '`direction`, then a translation `translation` along it; pitch = translation/angle\n'
        '(.inf in YAML and "inf" in JSON for a pure translation). The rotation defaults to\n'
        'the identity. A ROS pose is --quaternion (its orientation) --translation (its\n'
        'position).',
        'rot-tools screw --euler ZYX 90 0 0 --translation 1 0 0.5 --deg\n'
        'rot-tools screw --rotation 0 -1 0  1 0 0  0 0 1 --translation 0 0 1 --json\n'
        'rot-tools screw --quaternion 0 0 1 0 --translation 1 0 0.5\n'
        'rot-tools screw --translation 1 2 3'),
}


def _add_common(parser, suppress, only=None):
    """
    Options accepted before the command and after its arguments (one line each).

    They are added to the main parser (with their defaults) and to every command's parser
    (with SUPPRESS defaults, so a value given before the command is not overwritten); only
    those named in ``only`` when it is given.
    """
    def default(value):
        return argparse.SUPPRESS if suppress else value

    def add(option, **kwargs):
        if only is None or option in only:
            group.add_argument(option, **kwargs)
    group = parser.add_argument_group('common options') if suppress else parser
    add('--deg', action='store_true', default=default(False),
        help='angles in degrees, in and out (axis-angle and screw angles are '
        'printed in both units anyway)')
    add('--seq', type=_sequence, default=default(None), metavar='SEQ',
        help='Euler sequence of the output, any of the 24 (default: the input '
        'sequence for euler, else ZYX)')
    add('--all-sequences', action='store_true', default=default(False),
        help='also print the Euler angles in all 24 sequences, each with its '
        'gimbal-lock flag `degenerate`')
    add('--json', action='store_true', default=default(False),
        help='print JSON instead of YAML (an infinite pitch is the string "inf")')
    add('--precision', type=_precision, default=default(DEFAULT_PRECISION),
        metavar='N', help='round numbers to N significant digits and N decimal '
        f'places (default {DEFAULT_PRECISION}); -0.0 prints as 0.0')
    add('--tol', type=_tolerance, default=default(None), metavar='TOL',
        help='how far a typed input may be from exact before it is refused; '
        'within it, it is made exact. A matrix (matrix, screw --rotation): '
        f'max|RᵀR − I| and |det R − 1| ≤ TOL, default {MATRIX_TOL:g} (six '
        'significant digits pass), then the nearest rotation. A frame (frame, '
        'screw --frame): |cos| between two axes ≤ TOL, default '
        f'{MATRIX_TOL:g}. A quaternion (quaternion, screw --quaternion): '
        f'||q| − 1| ≤ TOL, default {QUATERNION_TOL:g} (four digits pass), then '
        'normalised')
    add('--wxyz', action='store_true', default=default(False),
        help='a typed quaternion is W X Y Z (w first) instead of the ROS order '
        'X Y Z W')
    add('--point', type=_number, nargs=3, default=default(None),
        metavar=('X', 'Y', 'Z'), help='also print where the motion takes the point '
        'p = (X, Y, Z), R·p + b, and its coordinates in the moved frame, '
        'Rᵀ·(p − b)')
    add('--plot', type=_plot_file, default=default(None), metavar='FILE',
        help='also draw the motion in FILE (.png or .svg): both frames, the '
        'rotation or screw axis, the path of the origin; needs matplotlib (pip '
        "install 'rot_tools[plot]')")
    add('--version', action=_Version, help='print the version and exit')


# The numbers each command takes as arguments: (dest, metavar, help).
_NUMBERS = {
    'euler': ('angles', 'ANGLE', 'the three angles A1 A2 A3 (rad, or deg with --deg)'),
    'matrix': ('entries', 'ENTRY', 'the 9 entries of R, or the 16 of T, row by row'),
    'axis-angle': ('values', 'NUMBER', 'X Y Z ANGLE: the axis (any length > 0) and the angle'),
    'rotvec': ('vector', 'COMPONENT', 'X Y Z: θ·l̂ (rad, or deg with --deg)'),
    'quaternion': ('components', 'COMPONENT', 'X Y Z W (W X Y Z with --wxyz)'),
    'frame': ('axes', 'COMPONENT',
              'UX UY UZ VX VY VZ WX WY WZ: the axes u, v, w (any length > 0)'),
}


_BAG_TEXT = (
    'Reads rosbag2 (sqlite3, MCAP) and ROS 1 bags without ROS (the rosbags library: pip\n'
    "install 'rot_tools[bag]'). Topics of type PoseStamped, PoseWithCovarianceStamped,\n"
    'Odometry, Imu, QuaternionStamped and TransformStamped are read (default: all of\n'
    "them). Each message passes the checks of rotation_node's inputs: a NaN/Inf, a zero or\n"
    'non-unit quaternion (|q| off 1 by more than --tol, default 0.001), an Imu without\n'
    'orientation is refused and counted by reason.\n\n'
    'Prints a summary per topic (YAML, or JSON with --json): type, frame ids, messages\n'
    'accepted and refused, start, end, rate, roll/pitch/yaw ranges, total angle turned,\n'
    'mean orientation, and for an Imu how far the angular velocity of its orientations is\n'
    'from its gyro (RMS). For Imu, PoseWithCovarianceStamped and Odometry, the median\n'
    'standard deviations of roll, pitch and yaw from their covariances, and how many were\n'
    "unknown or bad. roll, pitch, yaw are REP-103's (about the fixed X, Y, Z axes,\n"
    'the extrinsic sequence xyz) and continuous along each topic (no jump at ±180°)\n'
    'unless --wrap. With --csv, one row per accepted message; with --plot, roll, pitch\n'
    'and yaw against time, one panel per topic.')


def _add_bag(sub):
    """Return the bag command: its own options, and the common ones that apply to it."""
    p = sub.add_parser(
        'bag', help='the orientations recorded in a ROS bag: summary, CSV, plot',
        usage=f'{PROG} bag PATH... [--topic T]... [--tf REFERENCE BODY] [--seq SEQ] [--deg]\n'
        '       [--wrap] [--csv FILE|-] [--json] [--plot FILE] [--start S] [--end S]\n'
        '       [--input-covariance rotvec|rpy] [--jobs N] [--parquet DIR]\n'
        '       [--engine dask [--scheduler ADDRESS]]',
        description=f'The orientations recorded in a ROS bag.\n\n{_BAG_TEXT}',
        epilog='examples:\n  rot-tools bag run.bag\n'
        '  rot-tools bag run.bag --topic /imu/data --csv imu.csv --deg\n'
        '  rot-tools bag rosbag2_dir --plot rpy.png --start 10 --end 20\n'
        '  rot-tools bag recordings/ --jobs 4 --parquet table/')
    p.set_defaults(handler=None)
    p.add_argument('path', metavar='PATH', nargs='+',
                   help='a ROS 1 .bag file, a rosbag2 directory, or a file in one; any other '
                   'directory is searched for bags. Several bags: a summary per bag and '
                   'for the fleet, a bag that cannot be read listed as failed (exit '
                   'status 1), --csv one table with a bag column first')
    p.add_argument('--topic', action='append', metavar='T',
                   help='read this topic (repeat for more); default: every topic of a type '
                   'read')
    p.add_argument('--tf', nargs=2, metavar=('REFERENCE', 'BODY'),
                   help="the transform of BODY in REFERENCE from the bag's /tf and "
                   '/tf_static (tf2_msgs/TFMessage), through rot_tools.TransformTree, at every '
                   'stamp of the dynamic transforms between them (a topic named '
                   'tf:REFERENCE->BODY); other topics then only with --topic')
    p.add_argument('--wrap', action='store_true',
                   help='angles as computed, each in (−180°, 180°], instead of continuous')
    p.add_argument('--csv', metavar='FILE',
                   help='write one row per accepted message to FILE (- = standard output, '
                   'which then gets no summary): topic, stamp (s), frame_id, x, y, z, qx, qy, '
                   'qz, qw (w ≥ 0), roll, pitch, yaw, the --seq angles SEQ_1..3, rotation '
                   'vector rx, ry, rz, angle, body angular velocity wx, wy, wz from the '
                   'previous row of the topic (empty on its first row), standard deviations '
                   'roll_std, pitch_std, yaw_std from the covariance (empty where none is '
                   'known)')
    p.add_argument('--input-covariance', choices=READINGS, default='rotvec',
                   help="how a recorded covariance's rotation block is read, as "
                   "rotation_node's input_covariance: rotvec (default, ROS's "
                   "PoseWithCovariance: rotations about the parent's fixed X, Y, Z) or rpy "
                   '(already roll, pitch, yaw)')
    p.add_argument('--start', type=_seconds, metavar='S',
                   help="only messages recorded S seconds or more after the bag's start")
    p.add_argument('--end', type=_seconds, metavar='S',
                   help="only messages recorded at most S seconds after the bag's start")
    p.add_argument('--jobs', type=whole_number, metavar='N',
                   help='read the bags in N processes (default: one per CPU; 1: here, one '
                   'after the other); the output is the same whatever N is')
    p.add_argument('--parquet', metavar='DIR',
                   help='write one Parquet file per bag in DIR: the --csv columns plus bag, '
                   'stamp as int64 nanoseconds (needs pyarrow, the bag extra)')
    p.add_argument('--engine', choices=('processes', 'dask'), default='processes',
                   help='processes: --jobs N processes here (default); dask: each bag a '
                   'task on a Dask cluster (the fleet extra), a local one of N workers '
                   'unless --scheduler')
    p.add_argument('--scheduler', metavar='ADDRESS',
                   help='with --engine dask: the address of a running Dask scheduler '
                   '(tcp://HOST:8786), whose workers must see the bags and DIR')
    common = p.add_argument_group('common options')
    suppress = argparse.SUPPRESS
    common.add_argument('--deg', action='store_true', default=suppress,
                        help='every angle in degrees (angular velocities in deg/s)')
    common.add_argument('--seq', type=_sequence, default=suppress, metavar='SEQ',
                        help='also the Euler angles of SEQ (CSV columns SEQ_1..3), '
                        'continuous like roll, pitch, yaw')
    common.add_argument('--json', action='store_true', default=suppress,
                        help='print the summary as JSON instead of YAML')
    common.add_argument('--precision', type=_precision, default=suppress, metavar='N',
                        help='round numbers to N significant digits and N decimal places '
                        f'(default {DEFAULT_PRECISION}), in the summary and the CSV (whose '
                        'stamps are exact)')
    common.add_argument('--tol', type=_tolerance, default=suppress, metavar='TOL',
                        help='largest ||q| − 1| of a recorded quaternion (default 0.001, '
                        "rotation_node's quaternion_tolerance); within it q is normalised")
    common.add_argument('--plot', type=_plot_file, default=suppress, metavar='FILE',
                        help='draw roll, pitch, yaw against time, one panel per topic, in '
                        "FILE (.png or .svg); needs matplotlib (pip install 'rot_tools[plot]')")
    common.add_argument('--version', action=_Version, help='print the version and exit')


def build_parser():
    """Build the rot-tools ArgumentParser (one subparser per input kind)."""
    parser = _Parser(
        prog=PROG,
        description='Print every representation of a rotation or rigid transform: matrix,\n'
        'axis-angle (both solutions), rotation vector, Euler angles, quaternion, and for a\n'
        'transform its homogeneous matrix and screw; with --point, where a point goes.\n'
        'YAML by default, JSON with --json. Angles in radians unless --deg.\n'
        'Options may come before COMMAND, after its arguments or between them.',
        epilog='examples:\n  ' + '\n  '.join(
            spec[4].splitlines()[0] for spec in _COMMANDS.values())
        + '\n  rot-tools bag run.bag --csv run.csv'
        + '\n\n"rot-tools COMMAND --help" explains each command.')
    _add_common(parser, suppress=False)
    sub = parser.add_subparsers(dest='command', metavar='COMMAND', required=True,
                                parser_class=_CommandParser)
    for name, (handler, summary, usage, text, examples) in _COMMANDS.items():
        p = sub.add_parser(
            name, help=summary, usage=f'{PROG} {usage}',
            description=f'{summary[0].upper()}{summary[1:]}.\n\n{text}',
            epilog='examples:\n  ' + examples.replace('\n', '\n  '))
        _add_words(p, name)
        if name == 'screw':
            rotation = p.add_mutually_exclusive_group()
            rotation.add_argument('--rotation', type=_number, nargs=9,
                                  metavar=tuple(f'R{i}{j}' for i in '123' for j in '123'),
                                  help='the 9 entries of R, row by row')
            rotation.add_argument('--quaternion', type=_number, nargs=4,
                                  metavar=('X', 'Y', 'Z', 'W'),
                                  help='R from a quaternion (W X Y Z with --wxyz)')
            rotation.add_argument('--frame', type=_number, nargs=9,
                                  metavar=('UX', 'UY', 'UZ', 'VX', 'VY', 'VZ', 'WX', 'WY', 'WZ'),
                                  help="R from a frame's axes (its columns)")
            rotation.add_argument('--euler', nargs=4, metavar=('SEQ', 'A1', 'A2', 'A3'),
                                  help='R from Euler angles')
            rotation.add_argument('--axis-angle', type=_number, nargs=4,
                                  metavar=('X', 'Y', 'Z', 'ANGLE'), help='R from axis-angle')
            rotation.add_argument('--rotvec', type=_number, nargs=3, metavar=('X', 'Y', 'Z'),
                                  help='R from a rotation vector')
            p.add_argument('--translation', type=_number, nargs=3, required=True,
                           metavar=('X', 'Y', 'Z'), help='the translation b')
        _add_common(p, suppress=True)
    _add_bag(sub)
    compare.add_parser(sub, _plot_file, _precision, _Version)
    covariance.add_parser(sub, _COMMANDS, _add_words, _add_common, _number)
    return parser


def _add_words(p, name):
    """Add the words of input ``name`` to its parser p (SEQ, the numbers), and its handler."""
    p.set_defaults(handler=_COMMANDS[name][0])
    if name == 'euler':
        p.add_argument('sequence', type=_sequence, metavar='SEQ', help=_SEQUENCE_HELP)
    if name in _NUMBERS:
        dest, metavar, help_text = _NUMBERS[name]
        p.add_argument(dest, type=_number, nargs='*', metavar=metavar, help=help_text)


def _write_plot(parser, path, R, b, degrees):
    """Draw (R, b) into ``path`` with rot_tools.cli.plot, imported only now (matplotlib)."""
    def draw():
        from rot_tools.cli import plot
        plot.save(R, b, path, degrees)

    try:
        output_file.write_figure(draw, path, parser.error)
    except ValueError as exc:  # RotationError: a picture too large for float64
        parser.error(f'--plot: {exc}')


def _rotation(args, parser, command):
    """(R, b, input sequence) of the typed rotation; one ``rot-tools: error:`` line if bad."""
    if args.wxyz and not _reads_quaternion(args):
        parser.error('--wxyz: there is no quaternion to read (it applies to quaternion and '
                     'screw --quaternion)')
    try:
        return args.handler(args, parser)
    except ValueError as exc:  # RotationError is a ValueError
        parser.error(f'{command}: {exc}')


def _report(args, parser):
    """(R, b, report) of the parsed input; one ``rot-tools: error:`` line for bad input."""
    R, b, input_seq = _rotation(args, parser, args.command)
    try:
        return R, b, transform_report(R, b, seq=args.seq or input_seq or 'ZYX',
                                      degrees=args.deg, all_sequences=args.all_sequences,
                                      point=args.point)
    except ValueError as exc:  # RotationError is a ValueError
        parser.error(f'{args.command}: {exc}')


def _bag(args, parser):
    """rot-tools bag: rot_tools.cli.fleet, then bag (imported only now: the 'bag' extra)."""
    for option, given in (('--point', args.point), ('--wxyz', args.wxyz),
                          ('--all-sequences', args.all_sequences)):
        if given:
            parser.error(f'{option} does not apply to bag')
    from rot_tools.cli import fleet
    return fleet.command(args, parser.error)


def main(argv=None):
    """Run rot-tools on argv (default sys.argv[1:]); return the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(negative_numbers_as_values(
            sys.argv[1:] if argv is None else argv))
        if args.command == 'bag':
            return _bag(args, parser)
        if args.command == 'compare':
            return compare.run(args, parser.error)
        if args.command == 'covariance':
            return covariance.run(args, parser, _rotation)
        args.hints = []
        R, b, report = _report(args, parser)
        if args.plot:
            _write_plot(parser, args.plot, R, b, args.deg)
    except SystemExit as exc:  # argparse's --help (0) and errors (2)
        return exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2
    text = to_json if args.json else to_yaml
    sys.stdout.write(text(report, precision=args.precision))
    for hint in args.hints:
        sys.stderr.write(f'{PROG}: hint: {hint}\n')
    return 0


if __name__ == '__main__':
    sys.exit(main())
