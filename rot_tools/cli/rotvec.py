"""``rot-tools rotvec X Y Z``: a rotation from its rotation vector θ·l̂."""

import math

from rot_tools import rotvec_to_matrix
from rot_tools.cli import one_shot, typed_rotation
from rot_tools.io import arguments

NAME = 'rotvec'
SUMMARY = 'a rotation vector θ·l̂ (its norm is the angle)'
USAGE = 'rotvec X Y Z [options]'
TEXT = "With --deg the vector's norm is in degrees."
EXAMPLES = ('rot-tools rotvec 0 0 1.5707963267949\n'
            'rot-tools rotvec 0 90 0 --deg')


def add_words(parser):
    """Add the vector."""
    arguments.add_numbers(parser, 'vector', 'COMPONENT', 'X Y Z: θ·l̂ (rad, or deg with --deg)')


def rotation(args):
    """Return (R, None, None) of the typed vector (its norm is the angle hinted about)."""
    v = typed_rotation.count(args.vector, 3, 'rotvec X Y Z')
    return rotvec_to_matrix(typed_rotation.angles(args, v, size=math.hypot(*v))), None, None


def add_parser(subparsers):
    """Add ``rot-tools rotvec`` to argparse's subparsers action and return its parser."""
    return one_shot.add_parser(subparsers, NAME, SUMMARY, USAGE, TEXT, EXAMPLES, add_words)


def run(args):
    """Print the report of the typed rotation vector; return the exit status."""
    return one_shot.run(args, rotation)
