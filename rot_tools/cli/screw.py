"""``rot-tools screw``: a rigid transform (R, b) and its screw (Chasles) decomposition."""

import argparse
import math

import numpy as np
from rot_tools import axis_angle_to_matrix, euler_to_matrix, rotvec_to_matrix
from rot_tools.cli import one_shot, typed_rotation
from rot_tools.cli.options import error
from rot_tools.core.errors import RotationError
from rot_tools.io import arguments

NAME = 'screw'
SUMMARY = 'a rigid transform (R, b) and its screw (Chasles) decomposition'
USAGE = ('screw [--rotation R11 .. R33 | --quaternion X Y Z W | --frame U V W |\n'
         '       --euler SEQ A1 A2 A3 | --axis-angle X Y Z ANGLE | --rotvec X Y Z]\n'
         '       --translation X Y Z [options]')
TEXT = ('p ↦ R·p + b is a rotation by `angle` about the line through `point` along\n'
        '`direction`, then a translation `translation` along it; pitch = translation/angle\n'
        '(.inf in YAML and "inf" in JSON for a pure translation). The rotation defaults to\n'
        'the identity. A ROS pose is --quaternion (its orientation) --translation (its\n'
        'position).')
EXAMPLES = ('rot-tools screw --euler ZYX 90 0 0 --translation 1 0 0.5 --deg\n'
            'rot-tools screw --rotation 0 -1 0  1 0 0  0 0 1 --translation 0 0 1 --json\n'
            'rot-tools screw --quaternion 0 0 1 0 --translation 1 0 0.5\n'
            'rot-tools screw --translation 1 2 3')


def add_options(parser):
    """Add the rotation, in one of six forms, and the translation."""
    number = arguments.number
    rotation = parser.add_mutually_exclusive_group()
    rotation.add_argument('--rotation', type=number, nargs=9,
                          metavar=tuple(f'R{i}{j}' for i in '123' for j in '123'),
                          help='the 9 entries of R, row by row')
    rotation.add_argument('--quaternion', type=number, nargs=4, metavar=('X', 'Y', 'Z', 'W'),
                          help='R from a quaternion (W X Y Z with --wxyz)')
    rotation.add_argument('--frame', type=number, nargs=9,
                          metavar=('UX', 'UY', 'UZ', 'VX', 'VY', 'VZ', 'WX', 'WY', 'WZ'),
                          help="R from a frame's axes (its columns)")
    rotation.add_argument('--euler', nargs=4, metavar=('SEQ', 'A1', 'A2', 'A3'),
                          help='R from Euler angles')
    rotation.add_argument('--axis-angle', type=number, nargs=4,
                          metavar=('X', 'Y', 'Z', 'ANGLE'), help='R from axis-angle')
    rotation.add_argument('--rotvec', type=number, nargs=3, metavar=('X', 'Y', 'Z'),
                          help='R from a rotation vector')
    parser.add_argument('--translation', type=number, nargs=3, required=True,
                        metavar=('X', 'Y', 'Z'), help='the translation b')


def _euler(args):
    """R of --euler SEQ A1 A2 A3 (its words read here: argparse types one word list)."""
    seq, *angles = args.euler
    try:
        seq, angles = arguments.sequence(seq), [arguments.number(a) for a in angles]
    except argparse.ArgumentTypeError as exc:
        error(f'argument --euler: {exc}')
    return euler_to_matrix(typed_rotation.angles(args, angles), seq)


def _axis_angle(args):
    v = np.array(args.axis_angle)
    try:
        return axis_angle_to_matrix(v[:3], typed_rotation.angles(args, v[3]))
    except RotationError as exc:
        error(f'argument --axis-angle: {exc}')


def rotation(args):
    """Return (R, b, None): R from the form given (the identity if none), b --translation."""
    if args.rotation is not None:
        R = typed_rotation.matrix(args, args.rotation, 'argument --rotation')
    elif args.quaternion is not None:
        R = typed_rotation.quaternion(args, args.quaternion, 'argument --quaternion')
    elif args.frame is not None:
        R = typed_rotation.frame(args, args.frame, 'argument --frame')
    elif args.euler is not None:
        R = _euler(args)
    elif args.axis_angle is not None:
        R = _axis_angle(args)
    elif args.rotvec is not None:
        v = np.array(args.rotvec)
        R = rotvec_to_matrix(typed_rotation.angles(args, v, size=math.hypot(*v)))
    else:
        R = np.eye(3)
    return R, np.array(args.translation), None


def add_parser(subparsers):
    """Add ``rot-tools screw`` to argparse's subparsers action and return its parser."""
    return one_shot.add_parser(subparsers, NAME, SUMMARY, USAGE, TEXT, EXAMPLES, add_options)


def run(args):
    """Print the report of the typed rigid transform; return the exit status."""
    return one_shot.run(args, rotation)
