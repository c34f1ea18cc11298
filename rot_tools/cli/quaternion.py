"""``rot-tools quaternion X Y Z W``: a rotation from a quaternion, in the ROS order."""

from rot_tools.cli import one_shot, typed_rotation
from rot_tools.io import arguments
from rot_tools.io.boundary import QUATERNION_TOLERANCE

NAME = 'quaternion'
SUMMARY = 'a quaternion, x y z w (the ROS message order)'
USAGE = 'quaternion X Y Z W [options]    (W X Y Z with --wxyz)'
TEXT = ('The order of geometry_msgs/Quaternion, as `ros2 topic echo` prints it;\n'
        '--wxyz reads w first (Eigen, transforms3d). |q| must be 1 within --tol\n'
        f'(default {QUATERNION_TOLERANCE:g}, so four significant digits suffice); q is then\n'
        'normalised. q and −q are the same rotation; the report prints the one with w > 0.')
EXAMPLES = ('rot-tools quaternion 0 0 0.7071 0.7071\n'
            'rot-tools quaternion 0.7071 0 0 0.7071 --wxyz --deg\n'
            'rot-tools quaternion 0.1 -0.2 0.3 0.927 --tol 1e-2 --json')


def add_words(parser):
    """Add the components."""
    arguments.add_numbers(parser, 'components', 'COMPONENT', 'X Y Z W (W X Y Z with --wxyz)')


def rotation(args):
    """Return (R, None, None) of the typed quaternion, normalised."""
    what = 'quaternion W X Y Z' if args.wxyz else 'quaternion X Y Z W'
    return typed_rotation.quaternion(args, args.components, what), None, None


def add_parser(subparsers):
    """Add ``rot-tools quaternion`` to argparse's subparsers action and return its parser."""
    return one_shot.add_parser(subparsers, NAME, SUMMARY, USAGE, TEXT, EXAMPLES, add_words)


def run(args):
    """Print the report of the typed quaternion; return the exit status."""
    return one_shot.run(args, rotation)
