"""``rot-tools frame U V W``: a rotation from a frame's axes, the columns of R."""

from rot_tools.cli import one_shot, typed_rotation
from rot_tools.cli.options import MATRIX_TOL
from rot_tools.io import arguments

NAME = 'frame'
SUMMARY = "a frame's axes u, v, w written in the reference frame (Jia, Rotation in the Space, §4)"
USAGE = 'frame UX UY UZ VX VY VZ WX WY WZ [options]'
TEXT = ('R = (û v̂ ŵ): the axes are the columns of R, each normalised. They must be\n'
        f'orthogonal within --tol (|cos| between any two, default {MATRIX_TOL:g}) and\n'
        'right-handed ((û × v̂)·ŵ = +1); the frame is then made exactly orthonormal\n'
        '(nearest rotation). With --point P the report gives the coordinates Rᵀ·P of P in\n'
        'this frame.')
EXAMPLES = ('rot-tools frame 0 1 0  -1 0 0  0 0 1\n'
            'rot-tools frame 1 1 0  -1 1 0  0 0 1 --deg\n'
            'rot-tools frame 0 0 1  1 0 0  0 1 0 --point 1 2 3')


def add_words(parser):
    """Add the axes' components."""
    arguments.add_numbers(parser, 'axes', 'COMPONENT',
                          'UX UY UZ VX VY VZ WX WY WZ: the axes u, v, w (any length > 0)')


def rotation(args):
    """Return (R, None, None) of the typed axes."""
    return typed_rotation.frame(args, args.axes, 'frame U V W'), None, None


def add_parser(subparsers):
    """Add ``rot-tools frame`` to argparse's subparsers action and return its parser."""
    return one_shot.add_parser(subparsers, NAME, SUMMARY, USAGE, TEXT, EXAMPLES, add_words)


def run(args):
    """Print the report of the typed frame; return the exit status."""
    return one_shot.run(args, rotation)
