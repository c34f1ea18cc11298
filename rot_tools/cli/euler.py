"""``rot-tools euler SEQ A1 A2 A3``: a rotation from Euler angles of a sequence."""

from rot_tools import euler_to_matrix
from rot_tools.cli import one_shot, typed_rotation
from rot_tools.io import arguments

NAME = 'euler'
SUMMARY = 'Euler angles of a sequence'
USAGE = 'euler SEQ A1 A2 A3 [options]'
TEXT = ('R = Rot_a1(A1)·Rot_a2(A2)·Rot_a3(A3) for an upper-case (intrinsic) SEQ,\n'
        'Rot_a3(A3)·Rot_a2(A2)·Rot_a1(A1) for a lower-case (extrinsic) one.\n'
        'The output sequence is SEQ unless --seq says otherwise.')
EXAMPLES = ('rot-tools euler ZYX 30 20 10 --deg\n'
            'rot-tools euler zyx -30 20 10 --deg --seq XYZ --json\n'
            'rot-tools euler ZYX 0 90 0 --deg --all-sequences')


def add_words(parser):
    """Add SEQ and the angles."""
    arguments.add_sequence(parser)
    arguments.add_numbers(parser, 'angles', 'ANGLE',
                          'the three angles A1 A2 A3 (rad, or deg with --deg)')


def rotation(args):
    """Return (R, None, SEQ) of the typed angles."""
    angles = typed_rotation.count(args.angles, 3, f'euler {args.sequence} angles')
    return (euler_to_matrix(typed_rotation.angles(args, angles), args.sequence), None,
            args.sequence)


def add_parser(subparsers):
    """Add ``rot-tools euler`` to argparse's subparsers action and return its parser."""
    return one_shot.add_parser(subparsers, NAME, SUMMARY, USAGE, TEXT, EXAMPLES, add_words)


def run(args):
    """Print the report of the typed Euler angles; return the exit status."""
    return one_shot.run(args, rotation)
