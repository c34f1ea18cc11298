"""``rot-tools axis-angle X Y Z ANGLE``: a rotation from its axis and angle (Rodrigues)."""

from rot_tools import axis_angle_to_matrix
from rot_tools.cli import one_shot, typed_rotation
from rot_tools.io import arguments

NAME = 'axis-angle'
SUMMARY = 'a rotation axis and angle (Rodrigues)'
USAGE = 'axis-angle X Y Z ANGLE [options]'
TEXT = 'The axis (X, Y, Z) is normalised; a zero axis needs a zero angle.'
EXAMPLES = ('rot-tools axis-angle 0 0 1 90 --deg\n'
            'rot-tools axis-angle 1 1 1 2.0943951 --json')


def add_words(parser):
    """Add the axis and the angle."""
    arguments.add_numbers(parser, 'values', 'NUMBER',
                          'X Y Z ANGLE: the axis (any length > 0) and the angle')


def rotation(args):
    """Return (R, None, None) of the typed axis and angle."""
    v = typed_rotation.count(args.values, 4, 'axis-angle X Y Z ANGLE')
    return axis_angle_to_matrix(v[:3], typed_rotation.angles(args, v[3])), None, None


def add_parser(subparsers):
    """Add ``rot-tools axis-angle`` to argparse's subparsers action and return its parser."""
    return one_shot.add_parser(subparsers, NAME, SUMMARY, USAGE, TEXT, EXAMPLES, add_words)


def run(args):
    """Print the report of the typed axis and angle; return the exit status."""
    return one_shot.run(args, rotation)
