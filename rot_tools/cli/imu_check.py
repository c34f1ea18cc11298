"""
``rot-tools imu-check BAG``: an IMU's conventions checked from a recording.

Reads one sensor_msgs/Imu topic (and, when asked, a reference orientation of the same body
from the bag or from another recording of the run), runs rot_tools.core.imu.check_imu on it
and prints the checks as a table or JSON, with each fault's fix in the user's terms.
doc/imu.md says what each check means.
"""

import argparse
import math
import sys

import numpy as np
from rot_tools.cli import imu_recording, options, output_file
from rot_tools.core.errors import RotationError
from rot_tools.core.imu import (
    ACCEL_TOL, check_imu, faults, GRAVITY, GYRO_TOL, ImuReference)
from rot_tools.io import arguments, bag_read
from rot_tools.io.report import DEFAULT_PRECISION, to_json

BODY_FRAME = 'base_link'
"""The body's frame in a static transform line when the reference does not name it (REP 105's
name for the robot's body)."""

IMU_FRAME = 'imu_link'
"""The IMU's frame in a static transform line when its messages are stamped with the body's
frame (REP 145's default frame_id)."""

NED_FRAME = 'imu_link_ned'
"""The same for a NED device (REP 145's default frame_id of an IMU with a NED world)."""

FRD = (1.0, 0.0, 0.0, 0.0)
"""A forward-right-down sensor frame in a forward-left-up body: π about x, [x, y, z, w]."""

JSON_DIGITS = 6
"""Significant digits of the numbers of ``--json`` (estimates from noisy data)."""

TABLE_DIGITS = 4
"""Significant digits of the numbers of the table."""

MOUNTING_SHOWN = math.radians(10)
"""A mounting turned further than this from the identity gets its static transform line
under the table: the turns that matter are by tens of degrees (an IMU on its side, upside
down, facing back); a few degrees are a plate's tilt, or the estimate's error over a short
recording."""

GRAVITY_REMOVED = 10
"""An accelerometer scale above this (|a| under a tenth of gravity when the body turns
slowly) reads with gravity removed."""

STEPS = ('period', 'gap', 'spread')
"""The numbers that are steps of stamps (s): to the nanosecond, as the stamps are."""

ANGLES = {'angle': ('rad', 'deg'), 'bias': ('rad/s', 'deg/s')}
"""The numbers of a check that are angles or rates: their unit without and with --deg."""

FLAGS = {'mirror': 'mirror', 'negate': 'negate {}',
         'arrival_time': 'arrival-time stamping suspected'}
"""The table's words for a check's flag or axis when it is set (nothing when it is not)."""

UNITS = {'period': 's', 'gap': 's', 'spread': 's', 'rate': 'Hz'}
"""The other numbers with a unit in the table (scales, matrices and quaternions have none;
time_offset's seconds are shown without their name)."""


# ---------------------------------------------------------------------------------------
# The checks, as data


def check(recording):
    """
    Return rot_tools.core.imu.check_imu's ImuChecks of a Recording.

    Its quaternions are unit ones already (the boundary's tolerance, then normalised).
    """
    imu, ref = recording.imu, recording.reference
    reference = None if ref is None else ImuReference(ref.stamps, ref.quaternions)
    return check_imu(imu.stamps, imu.quaternions, imu.angular_velocity,
                     imu.linear_acceleration, reference=reference)


def _plain(value):
    """Return a check's number as plain data: float, int, nested lists, or None."""
    if value is None or isinstance(value, (str, bool)):
        return value
    array = np.asarray(value)
    if array.dtype.kind in 'iub':
        return array.tolist()
    if array.ndim == 2 and np.all(array == np.round(array)):  # a signed permutation
        return array.astype(int).tolist()
    return array.astype(float).tolist()


def numbers(result, degrees=False):
    """
    Return {name: value}: the numbers of one check, its fields after status and message.

    Angles and rates (:data:`ANGLES`) in degrees when ``degrees``.
    """
    out = {}
    for name, value in result._asdict().items():
        if name in ('status', 'message'):
            continue
        value = _plain(value)
        if name in STEPS and value is not None:
            value = round(value, 9)
        if degrees and name in ANGLES and value is not None:
            value = np.degrees(value).tolist()
        out[name] = value
    return out


def document(recording, checks, degrees=False):
    """Return the ``--json`` document: imu, checks, faults, fix."""
    imu = recording.imu
    return {
        'imu': {'topic': imu.topic, 'frame': imu.frame, 'messages': imu.messages,
                'rate': checks.stamps.rate},
        'checks': {name: {'status': result.status, 'message': result.message,
                          **numbers(result, degrees)}
                   for name, result in checks._asdict().items()},
        'faults': len(faults(checks)),
        'fix': fixes(recording, checks, degrees)}


# ---------------------------------------------------------------------------------------
# What to change


def _g(x, digits=TABLE_DIGITS):
    """Return a number as short text: 4 significant digits, no -0."""
    return f'{float(x) + 0.0:.{digits}g}'


def axis_map(matrix):
    """
    Return the axis map of a signed permutation M (ω_true = M·ω_read) as text.

    'x = +y, y = +x, z = -z': what each axis should read, from what is read now.
    """
    M = np.asarray(matrix)
    parts = []
    for i, axis in enumerate('xyz'):
        j = int(np.argmax(np.abs(M[i])))
        parts.append(f'{axis} = {"+" if M[i, j] > 0 else "-"}{"xyz"[j]}')
    return ', '.join(parts)


def static_transform(q, parent, child):
    """Return the ``ros2 run tf2_ros static_transform_publisher`` line of rotation q."""
    q = np.asarray(q, float)
    q = np.round(q / np.linalg.norm(q), 6) + 0.0
    if q[np.flatnonzero(q)[-1]] < 0:  # w > 0, or the last non-zero of x, y, z when w is 0
        q = -q + 0.0
    x, y, z, w = (f'{v:.6g}' for v in q)
    return ('ros2 run tf2_ros static_transform_publisher --x 0 --y 0 --z 0 '
            f'--qx {x} --qy {y} --qz {z} --qw {w} --frame-id {parent} --child-frame-id {child}')


def _frames(recording, child=IMU_FRAME):
    """
    Return (body, IMU frame, note) of a static transform line.

    The IMU frame is the IMU's frame_id; when its messages are stamped with the body's own
    frame, ``child`` and a note that says to stamp them so.
    """
    ref = recording.reference
    body = ref.body if ref is not None and ref.body else BODY_FRAME
    frame = recording.imu.frame
    if frame and frame != body:
        return body, frame, ''
    return body, child, (f" (and set the IMU's frame_id to {child}: its messages are "
                         f'stamped {frame or "with no frame"}, the body\'s frame)')


def _angle_between(q, p):
    """Return the angle (rad) of the rotation between unit quaternions q and p."""
    dot = abs(float(np.dot(np.asarray(q, float), p)))
    return 2 * math.acos(min(1.0, dot))


def fixes(recording, checks, degrees=False):
    """Return the lines that say what to change for each fault, and for a turned mounting."""
    imu = recording.imu
    at_fault = set(faults(checks))
    rate_unit = ANGLES['bias'][degrees]
    lines = []
    for name in checks._fields:
        result = getattr(checks, name)
        if name == 'mounting':
            lines += _mounting_lines(recording, result, at_fault)
            continue
        if name not in at_fault:
            continue
        if name == 'stamps':
            lines.append(f"stamps: {imu.topic}'s header stamps should be the time of each "
                         "measurement, increasing at the sensor's rate: check the driver's "
                         'clock and the recorder (REP 145: "The timestamp for these messages '
                         'should reflect the best estimate of when the observation was '
                         'made.")')
        elif name == 'accel_units':
            lines.append(_accel_units_line(getattr(result, 'scale', None)))
        elif name == 'orientation_vs_accel':
            if at_fault & {'accel_sign', 'world_up'}:
                continue  # the reference's checks say which of the two it is
            lines.append(_tilt_line(getattr(result, 'angle', None), degrees))
        elif name == 'gyro_units':
            lines.append(_gyro_units_line(getattr(result, 'scale', None)))
        elif name == 'quaternion':
            lines.append(QUATERNION_FIXES.get(result.reading, f'quaternion: {result.message}'))
        elif name == 'gyro_axes':
            lines.append(_gyro_axes_line(result))
        elif name == 'gyro_bias':
            bias = getattr(result, 'bias', None)
            lines.append('gyro_bias: calibrate the gyro at rest' + (
                '' if bias is None else ', or subtract ('
                + ', '.join(_g(b) for b in numbers(result, degrees)['bias'])
                + f') {rate_unit} from angular_velocity'))
        elif name == 'time_offset':
            lines.append(_time_offset_line(getattr(result, 'seconds', None)))
        elif name == 'accel_sign':
            lines.append('accel_sign: negate linear_acceleration: it reads gravity (pointing '
                         'down) where REP 145 wants the specific force, +9.81 m/s² along the '
                         'axis that points up at rest')
        elif name == 'world_up':
            body, child, note = _frames(recording, NED_FRAME)
            lines.append("world_up: the orientation's world is NED (z down) where REP 103 "
                         'wants ENU: switch the driver to ENU if it can; else turn each '
                         "orientation's world, q_ENU = (0.707107, 0.707107, 0, 0) ⊗ q_NED "
                         "[x, y, z, w], and place the device's sensor frame on the body. A "
                         "NED device's sensor frame is FRD (x forward, y right, z down): "
                         f'mounted level and facing forward, it is {body} turned π about x: '
                         f'{static_transform(FRD, body, child)}{note}')
        else:
            lines.append(f'{name}: {result.message}')
    return lines


QUATERNION_FIXES = {
    'w-first': 'quaternion: the orientation is written w-first: its fields x, y, z, w hold the '
    "quaternion's w, x, y, z (Eigen's coeffs() are x, y, z, w; its constructor takes w, x, y, "
    'z). In the driver fill orientation.x = q.x(), orientation.y = q.y(), orientation.z = '
    'q.z(), orientation.w = q.w(); a recording reads right as x = orientation.y, y = '
    'orientation.z, z = orientation.w, w = orientation.x',
    'inverted': 'quaternion: the orientation is inverted: it gives the world in the IMU frame '
    'where REP 145 wants the IMU frame in the world. In the driver publish its conjugate '
    '(Eigen: q.conjugate()); a recording reads right as x = -orientation.x, y = '
    '-orientation.y, z = -orientation.z, w = orientation.w'}
"""The fix of a quaternion check at fault, by its reading."""


def _gyro_axes_line(result):
    said = "gyro_axes: angular_velocity is not about the orientation's axes"
    if result.matrix is None:
        return said
    publish = f'publish {axis_map(result.matrix)} of what it reads now'
    if not result.mirror:
        return f'{said}: {publish}'
    return (f"gyro_axes: the gyro's axes are a mirror of the orientation's (a left-handed "
            f"frame: no turn of the IMU gives it): negate the gyro's {result.negate} axis; in "
            f'all, {publish}')


def _tilt_line(angle, degrees):
    if angle is not None and angle > math.pi / 2:
        return ('orientation_vs_accel: the orientation puts up where the accelerometer reads '
                'down: either the accelerometer reads gravity instead of the specific force '
                '(negate linear_acceleration) or the orientation is NED (its world z down); '
                'a reference (--ref-topic or --ref-tf) tells which (accel_sign, world_up)')
    apart = '' if angle is None else (
        f' ({_fixed(np.degrees(angle) if degrees else angle, 2 if degrees else 4)} '
        f'{ANGLES["angle"][degrees]} apart)')
    return (f'orientation_vs_accel: the orientation and the accelerometer disagree on up{apart}: '
            'publish both in the one sensor frame (REP 145: "All data from a sensor should '
            'be published with respect to a single consistent sensor frame.")')


def _accel_units_line(scale):
    if scale is None:
        return ('accel_units: linear_acceleration does not read gravity at rest: REP 145 '
                'wants the specific force in m/s², gravity included (a gravity-compensated '
                'output belongs in imu_compensated/)')
    if abs(scale / GRAVITY - 1) <= ACCEL_TOL:
        return (f'accel_units: linear_acceleration reads in g: multiply it by {_g(GRAVITY, 6)} '
                f'(scale {_g(scale)}) to publish m/s²')
    if scale > GRAVITY_REMOVED:
        return ('accel_units: linear_acceleration reads about 0 at rest (gravity removed?): '
                'REP 145 wants the specific force in m/s², gravity included (a '
                'gravity-compensated output belongs in imu_compensated/)')
    return f'accel_units: multiply linear_acceleration by {_g(scale)} to publish m/s²'


def _gyro_units_line(scale):
    if scale is None:
        return 'gyro_units: angular_velocity is not in rad/s'
    if abs(scale / math.radians(1) - 1) <= GYRO_TOL:
        return (f'gyro_units: angular_velocity reads in deg/s: multiply it by π/180 = '
                f'{_g(math.radians(1), 6)} (scale {_g(scale)}) to publish rad/s')
    return f'gyro_units: multiply angular_velocity by {_g(scale)} to publish rad/s'


def _time_offset_line(seconds):
    if seconds is None:
        return 'time_offset: the orientation and the gyro are not stamped alike'
    late = 'late' if seconds > 0 else 'early'
    return (f'time_offset: the orientation is {_g(abs(seconds))} s {late} against the gyro '
            "(a filter's delay, or stamps of publication): stamp each message with the time "
            f'of its measurement, or shift the orientation {_g(abs(seconds))} s '
            f'{"earlier" if seconds > 0 else "later"}')


def _mounting_lines(recording, result, at_fault):
    """Return the line of a mounting turned from the identity (or, NED, from FRD), if any."""
    q = getattr(result, 'quaternion', None)
    if q is None or result.status == 'unknown':
        return []
    ned = 'world_up' in at_fault
    if _angle_between(q, FRD if ned else (0, 0, 0, 1)) <= MOUNTING_SHOWN:
        return []
    body, child, note = _frames(recording, NED_FRAME if ned else IMU_FRAME)
    turn = math.degrees(_angle_between(q, (0, 0, 0, 1)))
    warning = getattr(result, 'warning', None)
    return [f'mounting: the IMU is turned {turn:.1f}° on the body (a mounting, not a fault): '
            f'its static transform {body} → {child}{note}: '
            f'{static_transform(q, body, child)}'
            + (" (the motion turned about one axis only: see the mounting's warning)"
               if warning else '')]


# ---------------------------------------------------------------------------------------
# The table


def _fixed(values, decimals):
    """Numbers with a fixed number of decimals, no -0: '(0.0193, -0.0070, 0.0000)'."""
    texts = [f'{round(float(v), decimals) + 0.0:.{decimals}f}' for v in np.ravel(values)]
    return texts[0] if np.ndim(values) == 0 else '(' + ', '.join(texts) + ')'


def number_text(name, value, degrees=False):
    """Return one number of a check as the table shows it, with its unit."""
    if name in FLAGS:  # shown by its words when set, else not at all
        return FLAGS[name].format(value) if value else ''
    if value is None:
        return '-'
    if name == 'matrix':
        M = np.asarray(value)
        return 'identity' if np.array_equal(M, np.eye(3)) else axis_map(M)
    if name in ANGLES:
        return f'{_fixed(value, 2 if degrees else 4)} {ANGLES[name][degrees]}'
    if name == 'quaternion':
        return f'q {_fixed(value, 4)}'
    if name == 'seconds':
        return f'{_g(value)} s'
    if isinstance(value, str):
        return value
    unit = UNITS.get(name, '')
    return f'{name} {_g(value)}' + (f' {unit}' if unit else '')


def table(data, recording, degrees=False):
    """Return the text of the table: the IMU, a row per check, then the fixes."""
    imu, ref = data['imu'], recording.reference
    rate = 'no rate' if imu['rate'] is None else f'{_g(imu["rate"])} Hz'
    lines = [f'imu: {imu["topic"]} (frame {imu["frame"] or "none"}), {imu["messages"]} '
             f'messages, {rate}']
    if ref is not None:
        body = f', {ref.body} in {ref.parent}' if ref.body and ref.parent else ''
        lines.append(f'reference: {ref.name} ({ref.msgtype.rsplit("/", 1)[1]}{body})')
    rows = [('check', 'status', 'numbers', 'message')]
    notes = []
    for name, result in data['checks'].items():
        texts = [number_text(k, v, degrees) for k, v in result.items()
                 if k not in ('status', 'message', 'warning')]
        texts = [text for text in texts if text]
        text = '-' if set(texts) <= {'-'} else ', '.join(texts)
        rows.append((name, result['status'], text, result['message']))
        if result.get('warning'):
            notes.append(f'{name}: {result["warning"]}')
    widths = [max(len(row[k]) for row in rows) for k in range(3)]
    lines.append('')
    lines += [f'{row[0]:<{widths[0]}}  {row[1]:<{widths[1]}}  {row[2]:<{widths[2]}}  '
              f'{row[3]}'.rstrip() for row in rows]
    lines.append('')
    faults = data['faults']
    lines.append('no fault' if not faults else f'{faults} fault{"s" * (faults > 1)}')
    lines += [f'  {line}' for line in data['fix']]
    lines += [f'note: {note}' for note in notes + [recording.hint] if note]
    return '\n'.join(lines) + '\n'


# ---------------------------------------------------------------------------------------
# The command


TEXT = (
    'Reads one sensor_msgs/Imu topic of a bag (the only one, or --imu-topic) and checks it\n'
    'against REP 103 and REP 145: quaternion (as recorded, written w-first or inverted),\n'
    'stamps, accel_units, orientation_vs_accel, gyro_units, gyro_axes, gyro_bias,\n'
    'time_offset; with a reference orientation of the same body (--ref-topic: odometry or a\n'
    'pose; --ref-tf PARENT CHILD: a TF frame pair; from another recording of the run with\n'
    '--ref-bag) also accel_sign, world_up (NED) and mounting. Each check is ok, fault or\n'
    'unknown, with its numbers (angles in radians and rates in rad/s unless --deg; scales are\n'
    'plain factors). Prints a table and, under it, what to change for each fault; --json\n'
    'prints {imu, checks, faults, fix}. An IMU without orientation\n'
    '(orientation_covariance[0] = -1 or zero quaternions) leaves the orientation checks\n'
    'unknown. Exit status 0: no fault, 1: faults, 2: bad input. Needs rosbags (the bag\n'
    'extra). doc/imu.md explains each check.')
"""What ``rot-tools imu-check --help`` says of the command."""


def add_parser(subparsers):
    """Add ``rot-tools imu-check`` to argparse's subparsers action and return its parser."""
    p = subparsers.add_parser(
        'imu-check', help="an IMU's conventions checked from a recording (REP 103, REP 145)",
        usage=f'{options.PROG} imu-check BAG [--imu-topic T] [--ref-topic T | --ref-tf PARENT '
        'CHILD]\n       [--ref-bag BAG] [--start S] [--end S] [--deg] [--json]',
        description=f"An IMU's conventions checked from a recording.\n\n{TEXT}",
        epilog='examples:\n  rot-tools imu-check run.bag\n'
        '  rot-tools imu-check run.bag --imu-topic /imu/data --ref-topic /odom\n'
        '  rot-tools imu-check imu.bag --ref-bag odom.bag --ref-topic /odom\n'
        '  rot-tools imu-check rosbag2_dir --ref-tf odom base_link --deg --json')
    p.add_argument('path', metavar='BAG',
                   help='a ROS 1 .bag file, a rosbag2 directory, or a file in one')
    p.add_argument('--imu-topic', metavar='T',
                   help="the sensor_msgs/Imu topic to check (default: the bag's only one)")
    p.add_argument('--ref-topic', metavar='T',
                   help="the body's orientation from this topic (Odometry, PoseStamped, "
                   'PoseWithCovarianceStamped, TransformStamped, QuaternionStamped)')
    p.add_argument('--ref-tf', nargs=2, metavar=('PARENT', 'CHILD'),
                   help="the body's orientation: CHILD (the body frame, e.g. base_link) in "
                   "PARENT (e.g. odom) from the bag's /tf and /tf_static")
    p.add_argument('--ref-bag', metavar='BAG',
                   help='take the reference (--ref-topic or --ref-tf) from this bag, another '
                   'recording of the same run, instead of BAG')
    arguments.add_bag_window(p)
    common = p.add_argument_group('common options')
    suppress = argparse.SUPPRESS
    arguments.add_deg(common, 'angles in degrees and rates in deg/s', suppress)
    arguments.add_json(common, 'print {imu, checks, faults, fix} as JSON instead of the table',
                       suppress)
    arguments.add_version(common)
    return p


def run(args):
    """
    Run ``rot-tools imu-check`` on the parsed ``args``; return the exit status.

    0 when no check is at fault, 1 when one is; one error line and status 2
    (options.error) for bad input: an option that does not apply, a bag that cannot be
    read, no Imu topic or two without --imu-topic, nothing left to check, a reference that
    is not there or does not meet the IMU in time. Messages left out are warned of first.
    """
    error = options.error
    for option, given in (('--seq', args.seq), ('--all-sequences', args.all_sequences),
                          ('--wxyz', args.wxyz), ('--point', args.point),
                          ('--plot', args.plot), ('--tol', args.tol),
                          ('--precision', args.precision != DEFAULT_PRECISION)):
        if given:
            error(f'{option} does not apply to imu-check')
    if args.ref_topic is not None and args.ref_tf is not None:
        error('--ref-topic and --ref-tf: give one reference, not both')
    if args.ref_bag is not None and args.ref_topic is None and args.ref_tf is None:
        error('--ref-bag: say which reference to take from it (--ref-topic T or --ref-tf '
              'PARENT CHILD)')
    missing = bag_read.rosbags_missing()
    if missing:
        error(f"imu-check needs the rosbags library ({missing} is missing), the 'bag' extra: "
              f"{arguments.install_hint('bag')}")
    if args.start is not None and args.end is not None and args.end < args.start:
        error(f'--end {args.end:g} is before --start {args.start:g}')
    try:
        recording = imu_recording.read(
            args.path, args.imu_topic, args.ref_topic, args.ref_tf, args.start, args.end,
            args.ref_bag, warn=lambda text: sys.stderr.write(f'warning: {text}\n'))
    except bag_read.BagError as exc:
        error(f'imu-check: {exc}')
    try:
        checks = check(recording)
    except RotationError as exc:  # too few samples for the checks
        error(f'imu-check: {recording.imu.topic}: {exc}')
    data = document(recording, checks, args.deg)
    text = to_json(data, JSON_DIGITS) if args.json else table(data, recording, args.deg)
    output_file.to_stdout(lambda out: out.write(text))
    return 1 if data['faults'] else 0
