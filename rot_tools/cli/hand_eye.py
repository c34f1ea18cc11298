"""
``rot-tools hand-eye A B``: the rigid transform between two joined bodies, from their motion.

A and B are each read as ``rot-tools compare`` reads a side (rot_tools.cli.compare.read_side:
a TUM file, an EuRoC CSV, a bag's pose topic or TF frame pair), each a body's pose in its own
world; ``--invert-a``/``--invert-b`` turn a stream that gives the world in the body (a marker
detector's marker in the camera) around. rot_tools.core.hand_eye.hand_eye then finds X (B's
body in A's) and Z (B's world in A's) with T_A(t)·X = Z·T_B(t). The report gives every
representation of X and Z (rot_tools.io.report.transform_report), the rejected samples by
stamp, the residuals, one standard deviation per angle and translation component, the axes
along which the motion cannot tell X's translation, and X's ``static_transform_publisher``
line; ``--yaml FILE`` writes X as the parameters of tf2_ros' static transform node.
"""

import argparse
import math

import numpy as np
from rot_tools.cli import options, output_file
from rot_tools.cli.compare import (
    CompareError, LOW_CORRELATION, read_side, say_warnings)
from rot_tools.core.errors import RotationError
from rot_tools.core.hand_eye import DEFAULT_MIN_ANGLE, hand_eye
from rot_tools.core.rigid import invert_transform
from rot_tools.core.so3 import matrix_to_quaternion
from rot_tools.io import arguments, bag_read
from rot_tools.io.report import Exact, to_json, to_yaml, transform_report
from rot_tools.io.trajectory_files import TrajectoryFileError

TEXT = (
    'A and B are each a bag (a pose topic with --a-topic/--b-topic, or the transform of\n'
    "CHILD in PARENT from the bag's TF with --a-tf/--b-tf), a TUM file (t x y z qx qy qz\n"
    'qw) or an EuRoC ground-truth CSV, each the pose of a body in its own fixed world;\n'
    '--invert-a/--invert-b when a stream gives the world in the body instead (a marker\n'
    'detector gives the marker in the camera). The bodies are rigidly joined: X is B in\n'
    "A's body frame and Z is B's world in A's world, T_A(t) X = Z T_B(t).\n\n"
    "B is interpolated at A's stamps (constant screw, neighbours within --max-gap); the\n"
    "offset is added to B's stamps (auto: from the angular speeds, within --max-offset).\n"
    'Pairs of samples that turn by --min-angle are compared by their screws (angle and\n'
    'translation along the axis, equal for a rigid joint whatever X is): a sample whose\n'
    'pairs disagree beyond the rest is rejected and named. X by least squares, with one\n'
    'standard deviation per angle and component; a translation along an axis that A never\n'
    'turns about cannot be seen: it is set to 0 and listed as unobservable.\n'
    'Angles in radians unless --deg; lengths in the unit of the input. Needs rosbags for\n'
    'bags (the bag extra).')


def add_parser(subparsers):
    """Add ``rot-tools hand-eye`` to argparse's subparsers action and return its parser."""
    p = subparsers.add_parser(
        'hand-eye', help='the transform between two joined bodies from their motion (AX = ZB)',
        usage='rot-tools hand-eye A B [--a-topic T | --a-tf PARENT CHILD]\n'
        '       [--b-topic T | --b-tf PARENT CHILD] [--invert-a] [--invert-b]\n'
        '       [--offset auto|SECONDS] [--max-offset S] [--max-gap S] [--min-angle DEG]\n'
        '       [--deg] [--json] [--yaml FILE]',
        description=f'Hand-eye calibration: X and Z with T_A(t) X = Z T_B(t).\n\n{TEXT}',
        epilog='examples:\n  rot-tools hand-eye hand.tum marker_in_camera.tum --invert-b\n'
        '  rot-tools hand-eye run_bag run_bag --a-tf base_link tool0 --b-tf camera marker '
        '--invert-b\n'
        '  rot-tools hand-eye odom.tum vo.tum --offset auto --deg --yaml camera_on_base.yaml')
    for side in ('a', 'b'):
        name = side.upper()
        p.add_argument(side, metavar=name, help='a bag, a TUM file or an EuRoC CSV')
        p.add_argument(f'--{side}-topic', metavar='T', help=f'the pose topic of {name} in its bag')
        p.add_argument(f'--{side}-tf', nargs=2, metavar=('PARENT', 'CHILD'),
                       help=f"{name} is the transform of CHILD in PARENT from its bag's TF")
        p.add_argument(f'--invert-{side}', action='store_true',
                       help=f'{name} gives the world in the body: invert each pose')
    p.add_argument('--offset', type=options.offset, default=0.0, metavar='auto|SECONDS',
                   help="seconds added to B's stamps (default 0), or auto: found from the "
                   'angular speeds')
    p.add_argument('--max-offset', type=options.positive, default=1.0, metavar='S',
                   help='search --offset auto within ±S seconds (default 1)')
    p.add_argument('--max-gap', type=options.positive, default=0.1, metavar='S',
                   help="largest time (s) from a stamp of A to B's stamps used (default 0.1)")
    p.add_argument('--min-angle', type=options.positive,
                   default=math.degrees(DEFAULT_MIN_ANGLE),
                   metavar='DEG', help='the least turn of a pair of samples used, in degrees '
                   f'(default {math.degrees(DEFAULT_MIN_ANGLE):g})')
    p.add_argument('--yaml', metavar='FILE',
                   help="write X as the parameters of tf2_ros' static transform node")
    common = p.add_argument_group('common options')
    suppress = argparse.SUPPRESS
    arguments.add_deg(common, 'angles in degrees', suppress)
    arguments.add_json(common, default=suppress)
    arguments.add_precision(common, 'round numbers to N significant digits and N decimal places',
                            suppress)
    arguments.add_version(common)
    return p


# ---- reading ------------------------------------------------------------------------------


def _body_frames(args):
    """Return the frame names of body A and body B: a TF pair's body, else 'body_a', 'body_b'."""
    names = []
    for side in ('a', 'b'):
        tf = getattr(args, f'{side}_tf')
        inverted = getattr(args, f'invert_{side}')
        names.append(f'body_{side}' if tf is None else tf[0] if inverted else tf[1])
    return names


def read(name, path, topic, tf, invert):
    """Poses of one side (name A or B), inverted when asked; CompareError without positions."""
    poses = read_side(name, path, topic, tf)
    if poses.b is None:
        raise CompareError(f'{name}: {poses.name} has orientations only: a hand-eye '
                           'calibration needs positions too (a pose topic or a TF frame pair)')
    if invert:
        R, b = invert_transform(poses.R, poses.b, check=False)
        poses = poses._replace(R=R, b=b)
    return poses


# ---- output -------------------------------------------------------------------------------


def static_transform(R, b, parent, child):
    """Return the ``ros2 run tf2_ros static_transform_publisher`` line of (R, b)."""
    x, y, z, w = (f'{v:.9g}' for v in np.round(matrix_to_quaternion(R, check=False), 9) + 0.0)
    tx, ty, tz = (f'{v:.9g}' for v in np.round(b, 9) + 0.0)
    return ('ros2 run tf2_ros static_transform_publisher '
            f'--x {tx} --y {ty} --z {tz} --qx {x} --qy {y} --qz {z} --qw {w} '
            f'--frame-id {parent} --child-frame-id {child}')


def _transform(motion, degrees):
    """Every representation of a Motion (transform_report), the quaternion as [x, y, z, w]."""
    report = transform_report(motion.R, motion.b, degrees=degrees)
    quaternion = report.pop('quaternion')
    return {'quaternion': [quaternion[k] for k in 'xyzw'],
            'translation': report.pop('translation'), 'matrix': report.pop('matrix'), **report}


def report(found, sides, args):
    """Return the report of a HandEyeCalibration as plain data (to_yaml / to_json)."""
    angle = np.degrees if args.deg else (lambda x: x)
    out = {side: {'source': str(source), 'read': poses.name, 'poses': len(poses.stamps),
                  'dropped_duplicates': poses.dropped_duplicates, 'reordered': poses.reordered}
           for side, source, poses in sides}
    out['offset'] = found.offset
    if args.offset == 'auto':
        out['offset_correlation'] = found.correlation
    out.update({
        'samples': found.samples, 'pairs': found.pairs,
        'rejected': [{'stamp': Exact(r.stamp), 'reason': r.reason} for r in found.rejected],
        'unit': 'deg' if args.deg else 'rad',
        'X': _transform(found.X, args.deg), 'Z': _transform(found.Z, args.deg),
        'residual': {'rotation': float(angle(found.residual.rotation)),
                     'translation': found.residual.translation},
        'sigma': {'rotation': angle(found.sigma.rotation).tolist(),
                  'translation': found.sigma.translation.tolist()},
        'unobservable': found.unobservable.tolist(),
        'static_transform_publisher': static_transform(*found.X, *_body_frames(args)),
    })
    return out


def parameters(found, args):
    """Return X as the parameters of tf2_ros' StaticTransformBroadcasterNode (a YAML file)."""
    parent, child = _body_frames(args)
    x, y, z, w = matrix_to_quaternion(found.X.R, check=False).tolist()
    tx, ty, tz = found.X.b.tolist()
    return {'/**': {'ros__parameters': {
        'frame_id': parent, 'child_frame_id': child,
        'translation': {'x': tx, 'y': ty, 'z': tz},
        'rotation': {'x': x, 'y': y, 'z': z, 'w': w}}}}


def write_parameters(path, found, args):
    """Write --yaml FILE, whole or not at all, with the line that uses it."""
    parent, child = _body_frames(args)
    head = (f"# X: {child}'s pose in {parent}'s frame, from rot-tools hand-eye.\n"
            "# The parameters of tf2_ros' StaticTransformBroadcasterNode (a composable node)\n"
            '# in a launch file; or on the command line:\n'
            f'# {static_transform(*found.X, parent, child)}\n')
    with output_file.complete_or_nothing(path, 'w', encoding='utf-8') as out:
        out.write(head + to_yaml(parameters(found, args), precision=None))


def warnings(found, args):
    """Return the one-line warnings of a calibration (without the ``warning:`` prefix)."""
    out = []
    if args.offset == 'auto' and not found.correlation >= LOW_CORRELATION:
        out.append(f'the angular speeds correlate poorly at the offset found (r = '
                   f'{found.correlation:.2f} < {LOW_CORRELATION:g}): the offset '
                   f'{found.offset:+.6g} s may be wrong; give --offset SECONDS')
    for axis in found.unobservable:
        shown = ', '.join(f'{v:.3g}' for v in axis + 0.0)
        out.append(f"X's translation along [{shown}] (in A) is unobservable: the motion turns "
                   'about that axis only; it is set to 0')
    return out


def run(args):
    """Run rot-tools hand-eye on the parsed ``args``; return the exit status (0)."""
    for option, given in (('--point', args.point), ('--wxyz', args.wxyz),
                          ('--all-sequences', args.all_sequences), ('--seq', args.seq),
                          ('--tol', args.tol), ('--plot', args.plot)):
        if given:
            options.error(f'{option} does not apply to hand-eye')
    output_file.check_outputs([('--yaml', args.yaml)], [args.a, args.b])
    try:
        a = read('A', args.a, args.a_topic, args.a_tf, args.invert_a)
        b = read('B', args.b, args.b_topic, args.b_tf, args.invert_b)
        found = hand_eye(a.stamps, a.R, a.b, b.stamps, b.R, b.b, offset=args.offset,
                         max_offset=args.max_offset, max_gap=args.max_gap,
                         min_angle=math.radians(args.min_angle))
    except (CompareError, TrajectoryFileError, bag_read.BagError, RotationError) as exc:
        options.error(f'hand-eye: {exc}')
    if args.yaml is not None:
        try:
            write_parameters(args.yaml, found, args)
        except OSError as exc:
            options.error(f'--yaml: cannot write {args.yaml}: {exc.strerror or exc}')
    data = report(found, (('a', args.a, a), ('b', args.b, b)), args)
    text = to_json if args.json else to_yaml
    output_file.to_stdout(lambda out: out.write(text(data, precision=args.precision)))
    say_warnings((('A', args.a, a), ('B', args.b, b)), warnings(found, args))
    return 0
