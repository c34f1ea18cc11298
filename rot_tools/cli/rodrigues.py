"""``rot-tools rodrigues G1 G2 G3``: a rotation from its Rodrigues (Gibbs) vector tan(θ/2)·l̂."""

from rot_tools import rodrigues_to_matrix
from rot_tools.cli import one_shot, typed_rotation
from rot_tools.io import arguments

NAME = 'rodrigues'
SUMMARY = 'a Rodrigues (Gibbs) vector tan(θ/2)·l̂'
USAGE = 'rodrigues G1 G2 G3 [options]'
TEXT = ('g = tan(θ/2)·l̂: its direction is the axis, its norm tan(θ/2) (1 for a quarter turn).\n'
        'A half turn (θ = π) has none: its g is infinite.')
EXAMPLES = ('rot-tools rodrigues 0 0 1\n'
            'rot-tools rodrigues 0.2 -0.1 0.3 --deg')


def add_words(parser):
    """Add the vector."""
    arguments.add_numbers(parser, 'vector', 'COMPONENT', 'G1 G2 G3: tan(θ/2)·l̂')


def rotation(args):
    """Return (R, None, None) of the typed Rodrigues vector."""
    g = typed_rotation.count(args.vector, 3, 'rodrigues G1 G2 G3')
    return rodrigues_to_matrix(g), None, None


def add_parser(subparsers):
    """Add ``rot-tools rodrigues`` to argparse's subparsers action and return its parser."""
    return one_shot.add_parser(subparsers, NAME, SUMMARY, USAGE, TEXT, EXAMPLES, add_words)


def run(args):
    """Print the report of the typed Rodrigues vector; return the exit status."""
    return one_shot.run(args, rotation)
