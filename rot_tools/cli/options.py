"""
What every rot-tools command shares: the program's name, its error line, the common options.

The common options (:func:`add_common`) are accepted before the command and among its words:
they are added to the main parser with their defaults and to each command's parser with
``argparse.SUPPRESS`` defaults, so that a value given before the command stays.
"""

import argparse
import math

from rot_tools.io import arguments
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.io.report import DEFAULT_PRECISION

PROG = 'rot-tools'

MATRIX_TOL = 1e-5
"""Default tolerance of a typed matrix (max|RᵀR − I|, |det R − 1|) or frame (|cos| between
two axes): six significant digits pass."""


def error(message):
    """Print ``rot-tools: error: message`` on one line and exit with status 2."""
    arguments.fail(PROG, message)


def _number(text, least):
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > least):
        raise ValueError(text)
    return value


def positive(text):
    """Read a finite number > 0 (seconds, frames, degrees)."""
    try:
        return _number(text, 0.0)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f'expected a number > 0, got {text.strip()!r}') from None


def offset(text):
    """Read 'auto' or a finite number of seconds."""
    if text.strip() == 'auto':
        return 'auto'
    try:
        return _number(text, -math.inf)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected 'auto' or seconds, got {text.strip()!r}") from None


def plot_file(text):
    """Read the name of a picture to write: .png or .svg."""
    if not text.lower().endswith(('.png', '.svg')):
        raise argparse.ArgumentTypeError(f'FILE must end in .png or .svg, got {text.strip()!r}')
    return text


def add_plot(parser, text, default=None):
    """Add --plot FILE: ``text`` says what is drawn; the file is .png or .svg (matplotlib)."""
    parser.add_argument('--plot', type=plot_file, default=default, metavar='FILE',
                        help=f'{text} in FILE (.png or .svg); needs matplotlib, the plot '
                        f"extra ({arguments.install_hint('plot')})")


def add_force(parser):
    """Add --force: write an output file over a recording (a bag) that is not an input."""
    parser.add_argument('--force', action='store_true',
                        help='write an output over a recording (a .bag, .db3 or .mcap file, a '
                        'rosbag2 directory or a file in one) that is not an input; without it, '
                        'refused')


def tolerance(text):
    """Read a tolerance: a finite number ≥ 0."""
    value = arguments.number(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f'must be >= 0, got {text.strip()!r}')
    return value


def add_common(parser, suppress, only=None):
    """
    Add the common options to parser (only those named in ``only`` when it is given).

    ``suppress``: a command's parser, whose options get SUPPRESS defaults and a group of
    their own ('common options').
    """
    def default(value):
        return argparse.SUPPRESS if suppress else value

    group = parser.add_argument_group('common options') if suppress else parser

    def wanted(option):
        return only is None or option in only

    if wanted('--deg'):
        arguments.add_deg(group, 'angles in degrees, in and out (axis-angle and screw angles are '
                          'printed in both units anyway)', default(False))
    if wanted('--seq'):
        group.add_argument('--seq', type=arguments.sequence, default=default(None),
                           metavar='SEQ', help='Euler sequence of the output, any of the 24 '
                           '(default: the input sequence for euler, else ZYX)')
    if wanted('--all-sequences'):
        group.add_argument('--all-sequences', action='store_true', default=default(False),
                           help='also print the Euler angles in all 24 sequences, each with '
                           'its gimbal-lock flag `degenerate`')
    if wanted('--json'):
        arguments.add_json(group, 'print JSON instead of YAML (an infinite pitch is the string '
                           '"inf")', default(False))
    if wanted('--precision'):
        arguments.add_precision(group, 'round numbers to N significant digits and N decimal '
                                f'places (default {DEFAULT_PRECISION}); -0.0 prints as 0.0',
                                default(DEFAULT_PRECISION))
    if wanted('--tol'):
        group.add_argument(
            '--tol', type=tolerance, default=default(None), metavar='TOL',
            help='how far a typed input may be from exact before it is refused; within it, '
            'it is made exact. A matrix (matrix, screw --rotation): max|RᵀR − I| and '
            f'|det R − 1| ≤ TOL, default {MATRIX_TOL:g} (six significant digits pass), then '
            'the nearest rotation. A frame (frame, screw --frame): |cos| between two axes ≤ '
            f'TOL, default {MATRIX_TOL:g}. A quaternion (quaternion, screw --quaternion): '
            f'||q| − 1| ≤ TOL, default {QUATERNION_TOLERANCE:g} (four digits pass), then '
            'normalised')
    if wanted('--wxyz'):
        arguments.add_wxyz(group, 'a typed quaternion is W X Y Z (w first) instead of the ROS '
                           'order X Y Z W', default(False))
    if wanted('--point'):
        group.add_argument('--point', type=arguments.number, nargs=3, default=default(None),
                           metavar=('X', 'Y', 'Z'), help='also print where the motion takes '
                           'the point p = (X, Y, Z), R·p + b, and its coordinates in the moved '
                           'frame, Rᵀ·(p − b)')
    if wanted('--plot'):
        add_plot(group, 'also draw the motion (both frames, the rotation or screw axis, the path '
                 'of the origin)', default(None))
    if wanted('--version'):
        arguments.add_version(group)
