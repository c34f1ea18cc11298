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

import sys

from rot_tools.cli import (
    axis_angle, bag, compare, covariance, euler, frame, imu_check, matrix, options, quaternion,
    rotvec, screw)
from rot_tools.io import arguments

PROG = options.PROG

COMMANDS = (euler, matrix, axis_angle, rotvec, quaternion, frame, screw, bag, compare,
            covariance, imu_check)
"""The modules of rot-tools' commands, in the order --help lists them."""

ONE_SHOT = (euler, matrix, axis_angle, rotvec, quaternion, frame, screw)
"""The one-shot commands, whose first examples the main help shows."""


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
