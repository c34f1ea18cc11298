"""``rot-tools matrix``: a rotation matrix (9 numbers) or a homogeneous 4×4 (16), row by row."""

import numpy as np
from rot_tools import homogeneous_to_transform
from rot_tools.cli import one_shot, typed_rotation
from rot_tools.cli.options import error, MATRIX_TOL
from rot_tools.core.errors import RotationError
from rot_tools.io import arguments

NAME = 'matrix'
SUMMARY = 'a rotation matrix (9 numbers) or a homogeneous 4×4 (16), row by row'
USAGE = ('matrix R11 R12 R13 R21 R22 R23 R31 R32 R33 [options]\n'
         '       rot-tools matrix R11 R12 R13 X  R21 R22 R23 Y  R31 R32 R33 Z  0 0 0 1 [options]')
TEXT = ('The rotation (R, or the block T[:3, :3] of the 4×4 T = [[R, b], [0, 0, 0, 1]])\n'
        'must be a rotation within --tol (max|RᵀR − I| and |det R − 1|, default\n'
        f'{MATRIX_TOL:g}); it is then replaced by the nearest rotation, so six significant\n'
        "digits suffice. A 4×4's last row must be 0 0 0 1 (to 1e-9); its last column is\n"
        'the translation b of p ↦ R·p + b, and the report adds the screw.')
EXAMPLES = ('rot-tools matrix 0 -1 0  1 0 0  0 0 1\n'
            'rot-tools matrix 0.866025 -0.5 0  0.5 0.866025 0  0 0 1 --deg\n'
            'rot-tools matrix 0 -1 0 1  1 0 0 0  0 0 1 0.5  0 0 0 1 --point 1 2 3')


def add_words(parser):
    """Add the entries."""
    arguments.add_numbers(parser, 'entries', 'ENTRY',
                          'the 9 entries of R, or the 16 of T, row by row')


def rotation(args):
    """Return (R, b, None): b None for 9 entries, T's last column for 16."""
    if len(args.entries) == 9:
        return typed_rotation.matrix(args, args.entries, 'matrix'), None, None
    if len(args.entries) != 16:
        error(f'matrix: expected 9 numbers (R) or 16 (a homogeneous 4×4 matrix), got '
              f'{len(args.entries)}')
    try:  # the last row is checked here (at 1e-9), the rotation block below (at --tol)
        R, b = homogeneous_to_transform(np.reshape(args.entries, (4, 4)), check=False)
    except RotationError as exc:
        error(f'matrix: {exc}')
    return typed_rotation.matrix(args, R.ravel(), 'matrix T[:3, :3]'), b, None


def add_parser(subparsers):
    """Add ``rot-tools matrix`` to argparse's subparsers action and return its parser."""
    return one_shot.add_parser(subparsers, NAME, SUMMARY, USAGE, TEXT, EXAMPLES, add_words)


def run(args):
    """Print the report of the typed matrix; return the exit status."""
    return one_shot.run(args, rotation)
