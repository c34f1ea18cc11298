"""
rot-tools: every representation of a rotation or rigid transform, on the command line.

No ROS needed: argparse over rot_tools and rot_tools.io.report::

    rot-tools euler ZYX 30 20 10 --deg
    rot-tools matrix 0 -1 0  1 0 0  0 0 1
    rot-tools axis-angle 0 0 1 90 --deg
    rot-tools rotvec 0 0 1.5707963267949
    rot-tools quaternion 0 0 0.7071 0.7071
    rot-tools frame 0 1 0  -1 0 0  0 0 1
    rot-tools matrix 0 -1 0 1  1 0 0 0  0 0 1 0.5  0 0 0 1
    rot-tools screw --euler ZYX 90 0 0 --translation 1 0 0.5 --deg --point 1 2 3
    rot-tools bag run.bag --csv run.csv --plot rpy.png   (the 'bag' extra)
    rot-tools compare est.tum gt.csv --align se3
    rot-tools covariance quaternion 0 0 0 1 --cov 1e-4 0 0 0 1e-4 0 0 0 1e-4 --from rotvec --to rpy

Each command is a module of rot_tools.cli (``axis-angle``: axis_angle) with
``add_parser(subparsers)``, which adds its parser to argparse's subparsers action and returns
it, and ``run(args)``, which runs it and returns the exit status. This module lists them
(COMMANDS), reads the command line and runs the command it names.

The one-shot commands (euler ... screw) print ``transform_report`` (keys documented in
rot_tools.io.report) as YAML, or JSON with ``--json`` (rot_tools.cli.one_shot), of an input
checked at ``--tol`` and made exact (rot_tools.cli.typed_rotation).

Every option is accepted before the command, after its arguments and between them
(rot_tools.io.arguments.Parser.parse_command_line).

Bad input — a wrong count, a non-number, NaN/Inf, a matrix that is not a rotation or is a
reflection, a homogeneous matrix whose last row is not 0 0 0 1, a zero, non-orthogonal or
left-handed frame, a zero quaternion or one too far from unit length, an unknown sequence,
a zero axis with a non-zero angle — prints exactly one line ``rot-tools: error: ...`` on
stderr and exits with status 2. An angle typed without ``--deg`` that is larger than 2π
only gets a one-line ``rot-tools: hint: ...`` on stderr (after the report; status 0).
"""

import argparse
import sys

from rot_tools.cli import (
    axis_angle, compare, covariance, euler, frame, matrix, options, quaternion, rotvec, screw)
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.io import arguments
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.io.message_covariance import READINGS
from rot_tools.io.report import DEFAULT_PRECISION

PROG = options.PROG

COMMANDS = (euler, matrix, axis_angle, rotvec, quaternion, frame, screw, compare, covariance)
"""The modules of rot-tools' commands, in the order --help lists them (bag's is added after
screw's)."""

ONE_SHOT = (euler, matrix, axis_angle, rotvec, quaternion, frame, screw)
"""The one-shot commands, whose first examples the main help shows."""


def _seconds(text):
    value = arguments.number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(
            f"must be >= 0 seconds from the bag's start, got {text.strip()!r}")
    return value


_BAG_TEXT = (
    'Reads rosbag2 (sqlite3, MCAP) and ROS 1 bags without ROS (the rosbags library: pip\n'
    "install 'rot_tools[bag]'). Topics of type PoseStamped, PoseWithCovarianceStamped,\n"
    'Odometry, Imu, QuaternionStamped and TransformStamped are read (default: all of\n'
    "them). Each message passes the checks of rotation_node's inputs: a NaN/Inf, a zero or\n"
    f'non-unit quaternion (|q| off 1 by more than --tol, default {QUATERNION_TOLERANCE:g}), an '
    'Imu without\n'
    'orientation is refused and counted by reason.\n\n'
    'Prints a summary per topic (YAML, or JSON with --json): type, frame ids, messages\n'
    'accepted and refused, start, end, rate, roll/pitch/yaw ranges, total angle turned,\n'
    'mean orientation, and for an Imu how far the angular velocity of its orientations is\n'
    'from its gyro (RMS). For Imu, PoseWithCovarianceStamped and Odometry, the median\n'
    'standard deviations of roll, pitch and yaw from their covariances, and how many were\n'
    "unknown or bad. roll, pitch, yaw are REP-103's (about the fixed X, Y, Z axes,\n"
    f'the extrinsic sequence {RPY_SEQUENCE}) and continuous along each topic (no jump at ±180°)\n'
    'unless --wrap. With --csv, one row per accepted message; with --plot, roll, pitch\n'
    'and yaw against time, one panel per topic.')


def _add_bag(sub):
    """Add the bag command: its own options, and the common ones that apply to it."""
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
    p.add_argument('--jobs', type=arguments.whole_number, metavar='N',
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
    common.add_argument('--seq', type=arguments.sequence, default=suppress, metavar='SEQ',
                        help='also the Euler angles of SEQ (CSV columns SEQ_1..3), '
                        'continuous like roll, pitch, yaw')
    common.add_argument('--json', action='store_true', default=suppress,
                        help='print the summary as JSON instead of YAML')
    common.add_argument('--precision', type=arguments.precision, default=suppress, metavar='N',
                        help='round numbers to N significant digits and N decimal places '
                        f'(default {DEFAULT_PRECISION}), in the summary and the CSV (whose '
                        'stamps are exact)')
    common.add_argument('--tol', type=options.tolerance, default=suppress, metavar='TOL',
                        help='largest ||q| − 1| of a recorded quaternion (default '
                        f'{QUATERNION_TOLERANCE:g}, '
                        "rotation_node's quaternion_tolerance); within it q is normalised")
    common.add_argument('--plot', type=options.plot_file, default=suppress, metavar='FILE',
                        help='draw roll, pitch, yaw against time, one panel per topic, in '
                        "FILE (.png or .svg); needs matplotlib (pip install 'rot_tools[plot]')")
    arguments.add_version(common)
    return p


def _bag(args):
    """rot-tools bag: rot_tools.cli.fleet, then bag (imported only now: the 'bag' extra)."""
    for option, given in (('--point', args.point), ('--wxyz', args.wxyz),
                          ('--all-sequences', args.all_sequences)):
        if given:
            options.error(f'{option} does not apply to bag')
    from rot_tools.cli import fleet
    return fleet.command(args, options.error)


def build_parser():
    """Build the rot-tools ArgumentParser: the common options, and a parser per command."""
    parser = arguments.Parser(
        prog=PROG,
        description='Print every representation of a rotation or rigid transform: matrix,\n'
        'axis-angle (both solutions), rotation vector, Euler angles, quaternion, and for a\n'
        'transform its homogeneous matrix and screw; with --point, where a point goes.\n'
        'YAML by default, JSON with --json. Angles in radians unless --deg.\n'
        'Options may come before COMMAND, after its arguments or between them.',
        epilog='examples:\n  ' + '\n  '.join(
            module.EXAMPLES.splitlines()[0] for module in ONE_SHOT)
        + '\n  rot-tools bag run.bag --csv run.csv'
        + '\n\n"rot-tools COMMAND --help" explains each command.')
    subparsers = parser.add_commands(lambda p: options.add_common(p, suppress=False),
                                     dest='command', metavar='COMMAND', required=True)
    for module in COMMANDS:
        module.add_parser(subparsers).set_defaults(run=module.run)
        if module is screw:
            _add_bag(subparsers).set_defaults(run=_bag)
    return parser


def parse_args(argv):
    """Return the parsed command line; exit 2 with one error line when it is bad."""
    return build_parser().parse_command_line(arguments.negative_numbers_as_values(argv))


def main(argv=None):
    """Run rot-tools on argv (default sys.argv[1:]); return the exit status."""
    try:
        args = parse_args(sys.argv[1:] if argv is None else argv)
        return args.run(args)
    except SystemExit as exc:  # argparse's --help (0), one-line errors (2)
        return exc.code if isinstance(exc.code, int) else 0 if exc.code is None else 2


if __name__ == '__main__':
    sys.exit(main())
