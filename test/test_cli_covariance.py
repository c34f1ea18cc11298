"""
rot-tools covariance as a user runs it, against scipy's Rotation by central differences.

Σ_out = J·Σ_in·Jᵀ with J from scipy (nothing of rot_tools), agreeing to 1e-7 of the largest entry.
"""

import json
import math

from conftest import REPO
from doc_blocks import assert_doc_output, console_steps, doc_block
import math_helpers as h
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_cli import ok, run

H = 1e-5
"""Central-difference step (rad)."""


ROTATIONS = Rotation.from_euler('xyz', [[0.3, -0.7, 2.1], [-2.5, 0.4, -0.9], [1.2, 1.1, 0.2]])
"""Rotations away from every lock used below (pitch 0.4–1.1 rad, ZYZ's θ2 well inside (0, π))."""


def _random_covariance(seed, scale=0.05):
    """Return a seeded positive definite 3×3, exactly symmetric in float64."""
    A = np.random.default_rng(seed).normal(size=(3, 3)) * scale
    C = A @ A.T + np.eye(3) * scale ** 2 / 10
    return (C + C.T) / 2


def _jacobian(f, x, wrap):
    """∂f/∂x at x (3,) by central differences, f: (3,) → (3,)."""
    columns = []
    for k in range(3):
        step = np.zeros(3)
        step[k] = H
        d = f(x + step) - f(x - step)
        columns.append((h.wrap(d) if wrap else d) / (2 * H))
    return np.stack(columns, axis=1)


def _rotation_of(r, word, frame):
    """Return x ↦ Rotation near r, for coordinates x of ``word`` (x = 0 or r's angles)."""
    if word == 'rotvec':
        if frame == 'parent':
            return lambda x: Rotation.from_rotvec(x) * r  # R_true = exp([δ]×)·R
        return lambda x: r * Rotation.from_rotvec(x)      # R_true = R·exp([δ]×)
    return lambda x: Rotation.from_euler('xyz' if word == 'rpy' else word, x)


def _coordinates_of(r, word, frame):
    """Return Rotation ↦ its coordinates as ``word`` (a rotation vector relative to r)."""
    if word == 'rotvec':
        if frame == 'parent':
            return lambda q: (q * r.inv()).as_rotvec()
        return lambda q: (r.inv() * q).as_rotvec()
    return lambda q: q.as_euler('xyz' if word == 'rpy' else word)


def reference(r, C, source, target, source_frame='parent', target_frame='parent'):
    """Σ of C read as ``source`` at r, as ``target``: J·C·Jᵀ by central differences."""
    x0 = np.zeros(3) if source == 'rotvec' else r.as_euler(
        'xyz' if source == 'rpy' else source)
    into = _rotation_of(r, source, source_frame)
    out = _coordinates_of(r, target, target_frame)
    J = _jacobian(lambda x: out(into(x)), x0, wrap=target != 'rotvec')
    return J @ C @ J.T


def _typed(values):
    return [repr(float(v)) for v in np.ravel(values)]


def _rotation_words(kind, r):
    """Return the words of rotation r as input ``kind`` (17 significant digits)."""
    if kind == 'quaternion':
        return ['quaternion', *_typed(r.as_quat())]
    if kind == 'matrix':
        return ['matrix', *_typed(r.as_matrix())]
    if kind == 'frame':
        return ['frame', *_typed(r.as_matrix().T)]  # the axes are R's columns
    if kind == 'rotvec':
        return ['rotvec', *_typed(r.as_rotvec())]
    if kind == 'axis-angle':
        v = r.as_rotvec()
        return ['axis-angle', *_typed(v / np.linalg.norm(v)), repr(float(np.linalg.norm(v)))]
    seq = kind.split()[1]
    return ['euler', seq, *_typed(np.degrees(r.as_euler(seq))), '--deg']


def converted(words, C, source, target, *options):
    """Run rot-tools covariance; return the parsed JSON report."""
    return ok('covariance', *words, '--cov', *_typed(C), '--from', source,
              '--to', target, *options, '--json', '--precision', '17')


def close_to(got, want):
    """Agreement to 1e-7 of the largest entry (cross terms may be 0)."""
    got = np.asarray(got, dtype=float)
    np.testing.assert_allclose(got, want, rtol=1e-7, atol=1e-7 * np.abs(want).max())


# Values: every kind of pair, every input kind, both frames

PAIRS = [  # (rotation input, rotation, from, to, --frame, --to-frame or None)
    ('quaternion', 0, 'rotvec', 'rpy', 'parent', None),
    ('matrix', 1, 'rotvec', 'ZYZ', 'body', None),
    ('rotvec', 2, 'rpy', 'rotvec', 'parent', None),
    ('euler XZY', 0, 'yxz', 'rotvec', 'body', None),
    ('axis-angle', 1, 'rpy', 'ZXZ', 'parent', None),
    ('frame', 2, 'ZYX', 'rpy', 'parent', None),
    ('euler xyz', 1, 'rpy', 'rpy', 'parent', None),
    ('quaternion', 2, 'rotvec', 'rotvec', 'parent', 'body'),
    ('matrix', 0, 'rotvec', 'rotvec', 'body', 'parent'),
    ('rotvec', 1, 'rotvec', 'rotvec', 'body', None),
]


@pytest.mark.parametrize('kind, index, source, target, frame, to_frame', PAIRS)
def test_values_against_central_differences(kind, index, source, target, frame,
                                            to_frame):
    r, C = ROTATIONS[index], _random_covariance(len(source) + 10 * index)
    options = ['--frame', frame] + (['--to-frame', to_frame] if to_frame else [])
    rep = converted(_rotation_words(kind, r), C, source, target, *options)
    want = reference(r, C, source, target, frame, to_frame or frame)
    close_to(rep['covariance'], want)
    sigma = np.sqrt(np.diag(want))
    close_to(rep['stddev'], sigma)
    close_to(rep['stddev_deg'], np.degrees(sigma))
    close_to(rep['correlation'], want / np.outer(sigma, sigma))
    assert rep['degenerate'] is False
    rotvec_frame = {'rotvec': frame}
    assert (rep['from'], rep['to']) == (source, target)
    assert rep['from_frame'] == rotvec_frame.get(source)
    assert rep['to_frame'] == ({'rotvec': to_frame or frame}).get(target)


def test_the_reference_sees_the_frame_and_the_reading():
    # the pairs above are not vacuous: the frames and the readings give different numbers
    r, C = ROTATIONS[0], _random_covariance(0)
    for a, b in ((reference(r, C, 'rotvec', 'rpy', 'parent'),
                  reference(r, C, 'rotvec', 'rpy', 'body')),
                 (reference(r, C, 'rotvec', 'rpy'), C),
                 (reference(r, C, 'rotvec', 'rotvec', 'parent', 'body'), C)):
        assert np.abs(a - b).max() > 0.1 * np.abs(C).max()


def test_json_and_yaml_carry_the_same_report_and_its_shape():
    words = ['euler', 'xyz', '5', '60', '30', '--deg', '--cov', '7.6e-5', '0', '0', '0',
             '7.6e-5', '0', '0', '0', '1.2e-3', '--from', 'rotvec', '--to', 'rpy']
    as_json = ok('covariance', *words, '--json')
    assert ok('covariance', *words) == as_json
    assert list(as_json) == ['from', 'from_frame', 'to', 'to_frame', 'covariance', 'stddev',
                             'stddev_deg', 'correlation', 'degenerate']
    assert np.shape(as_json['covariance']) == (3, 3) and len(as_json['stddev']) == 3
    # pitch 60°: roll's variance is that about X and Y over cos² 60° (doc/covariance.md)
    assert as_json['stddev'][0] == pytest.approx(2 * math.sqrt(7.6e-5), rel=1e-11)


def test_small_covariances_keep_their_digits():
    # rounding is to significant digits of the largest entry, not to decimal places
    rep = ok('covariance', 'quaternion', '0', '0', '0', '1', '--cov', '2.59777776e-07',
             '0', '0', '0', '2.59777776e-07', '0', '0', '0', '2.5e-05', '--from', 'rotvec',
             '--to', 'rpy', '--json')
    assert rep['covariance'][0][0] == 2.59777776e-07
    assert rep['stddev'][2] == 0.005


# Gimbal lock: degenerate, no numbers, a note, status 0


@pytest.mark.parametrize('words, source, target, seq', [
    (['euler', 'xyz', '10', '90', '30', '--deg'], 'rotvec', 'rpy', 'xyz'),
    (['euler', 'ZYZ', '0.3', '0', '0'], 'ZYZ', 'rotvec', 'ZYZ'),
    (['quaternion', '0', '0', '0', '1'], 'rpy', 'zxz', 'zxz'),  # identity: zxz's θ2 = 0
])
def test_gimbal_lock_is_degenerate_with_a_note(words, source, target, seq):
    args = ['covariance', *words, '--cov', '1e-4', '0', '0', '0', '1e-4', '0', '0', '0',
            '4e-4', '--from', source, '--to', target, '--json']
    proc = run(*args)
    assert proc.returncode == 0
    rep = json.loads(proc.stdout)
    assert rep['degenerate'] is True
    assert [rep[k] for k in ('covariance', 'stddev', 'stddev_deg', 'correlation')] == [None] * 4
    assert proc.stderr.startswith(f"rot-tools: note: the rotation is at gimbal lock of '{seq}'")
    assert proc.stderr.count('\n') == 1


# Refusals: one line, status 2

COV = ['--cov', '1', '0', '0', '0', '2', '0', '0', '0', '3']
FROM_TO = ['--from', 'rotvec', '--to', 'rpy']


def _cov(text):
    return ['--cov', *text.split()]


@pytest.mark.parametrize('args, message', [
    (_cov('1 0 0 0 1 0 0 0') + FROM_TO,
     '--cov: expected 9 numbers (C11 C12 C13 C21 .. C33, row by row, rad²), got 8'),
    (_cov('1 0 0 0 1 0 0 0 1 1') + FROM_TO,
     '--cov: expected 9 numbers (C11 C12 C13 C21 .. C33, row by row, rad²), got 10'),
    (_cov('1 0.1 0 0 1 0 0 0 1') + FROM_TO,
     '--cov is not symmetric: max|C − Cᵀ| = 0.1 > 1e-09·max|C| = 1e-09'),
    (_cov('1 2 0 2 1 0 0 0 1') + FROM_TO,
     '--cov is not positive semi-definite: its lowest eigenvalue is -1, below -1e-09·max|C| '
     '= -2e-09'),
    (_cov('1 0 0 0 1 0 0 0 nan') + FROM_TO, "argument --cov: not a finite number: 'nan'"),
    (_cov('1 0 0 0 -inf 0 0 0 1') + FROM_TO, "argument --cov: not a finite number: '-inf'"),
    (_cov('1 0 0 0 x 0 0 0 1') + FROM_TO, "argument --cov: not a number: 'x'"),
    (COV + ['--from', 'abc', '--to', 'rpy'], 'argument --from: expected rotvec (a small '
     'rotation vector, in --frame), rpy (roll, pitch, yaw about the fixed X, Y, Z: the '
     'sequence xyz) or an Euler sequence (XYZ ... ZYZ intrinsic, xyz ... zyz extrinsic), got '
     "'abc'"),
    (COV + ['--from', 'rotvec', '--to', 'RPY'], 'argument --to: expected rotvec'),
    (COV + ['--from', 'rotvec', '--to', 'ZyX'], 'argument --to: expected rotvec'),
    (COV + FROM_TO + ['--frame', 'world'], "argument --frame: invalid choice: 'world'"),
    (COV + FROM_TO + ['--to-frame', 'map'], "argument --to-frame: invalid choice: 'map'"),
    (COV + FROM_TO + ['--to-frame', 'body'],
     '--to-frame applies to --to rotvec only (Euler angles have no frame)'),
    (['--from', 'rotvec'], 'the following arguments are required: --cov, --to'),
    (COV + FROM_TO + ['--seq', 'xyz'], 'unrecognized arguments: --seq xyz'),
])
def test_bad_covariance_options(args, message):
    proc = run('covariance', 'euler', 'xyz', '0.1', '1.5', '0.2', *args)
    assert (proc.returncode, proc.stdout) == (2, ''), proc
    assert proc.stderr.startswith(f'rot-tools: error: {message}'), proc.stderr
    assert proc.stderr.count('\n') == 1, proc.stderr


@pytest.mark.parametrize('cov, message', [
    ('1.7976931348623157e308 -1e308 0 -1e308 5e-324 0 0 0 1',  # C + Cᵀ overflows
     '--cov is not positive semi-definite: its lowest eigenvalue is -4.4'),
    ('1.7976931348623157e308 0 0 0 1e308 0 0 0 1',  # E⁻¹ makes it larger
     '--cov: the converted covariance overflows float64'),
    ('1e308 0 1e308 0 1 0 1e308 0 1e308', None),  # eigvalsh does not converge on it as typed
])
def test_covariances_at_the_edge_of_float64(cov, message):
    proc = run('covariance', 'euler', 'xyz', '0.1', '0.2', '0.3', *_cov(cov), '--from',
               'rotvec', '--to', 'ZYX', '--json')
    if message is None:
        assert (proc.returncode, proc.stderr) == (0, ''), proc.stderr
        assert np.isfinite(json.loads(proc.stdout)['covariance']).all()
        return
    assert (proc.returncode, proc.stdout) == (2, ''), proc
    assert proc.stderr.startswith(f'rot-tools: error: {message}'), proc.stderr
    assert proc.stderr.count('\n') == 1, proc.stderr


@pytest.mark.parametrize('mixed', [
    '--deg covariance --from rpy --to rotvec euler xyz 5 60 30 --cov 3e-4 0 0 0 7.6e-5 0 0 0 '
    '1.4e-3',
    'covariance --from rpy euler xyz 5 --deg 60 30 --frame body --to rotvec --cov 3e-4 0 0 0 '
    '7.6e-5 0 0 0 1.4e-3',
    'covariance --cov 3e-4 0 0 0 7.6e-5 0 0 0 1.4e-3 --to rotvec euler --from rpy xyz 5 60 30',
])
def test_options_before_between_and_after_the_rotation(mixed):
    """Covariance's own options and the common ones go anywhere, as for the other commands."""
    canonical = ('covariance euler xyz 5 60 30 --deg --from rpy --to rotvec --frame body --cov '
                 '3e-4 0 0  0 7.6e-5 0  0 0 1.4e-3')
    mixed += '' if '--frame' in mixed else ' --frame body'
    mixed += '' if '--deg' in mixed else ' --deg'
    proc = run(*mixed.split())
    assert (proc.returncode, proc.stderr) == (0, ''), proc.stderr
    assert proc.stdout == run(*canonical.split()).stdout


@pytest.mark.parametrize('args, message', [
    ('covariance quaternion 0 0 0 0', 'quaternion X Y Z W: quaternion (x, y, z, w) must be '
     'non-zero'),
    ('covariance quaternion 0 0 1', 'quaternion X Y Z W: expected 4 numbers, got 3'),
    ('covariance axis-angle 0 0 0 1', 'covariance axis-angle: axis is zero but the angle is 1 '
     'rad'),
    ('covariance euler XYZW 1 2 3', "argument SEQ: unknown Euler sequence 'XYZW'"),
    ('covariance euler xyz 1 2 3 --wxyz', '--wxyz: there is no quaternion to read'),
    ('covariance screw --translation 0 0 0', "argument INPUT: invalid choice: 'screw'"),
    ('covariance', 'the following arguments are required: INPUT'),
    ('--point 1 2 3 covariance quaternion 0 0 0 1', '--point does not apply to covariance'),
    ('--seq xyz covariance quaternion 0 0 0 1', '--seq does not apply to covariance'),
    ('covariance euler xyz 0.1 1.5707 0.2', '--cov: the converted covariance overflows '
     'float64'),
])
def test_bad_rotation_or_misplaced_option(args, message):
    cov = '1e307 0 0 0 1e307 0 0 0 1e307' if 'overflows' in message else '1 0 0 0 2 0 0 0 3'
    tail = f' --cov {cov} --from rotvec --to rpy' if args != 'covariance' else ''
    proc = run(*(args + tail).split())
    assert (proc.returncode, proc.stdout) == (2, ''), proc
    assert proc.stderr.startswith(f'rot-tools: error: {message}'), proc.stderr
    assert proc.stderr.count('\n') == 1, proc.stderr


# Help


def test_help_lists_the_command_its_inputs_and_examples_that_run():
    assert '\n    covariance ' in run('--help').stdout
    proc = run('covariance', '--help')
    assert (proc.returncode, proc.stderr) == (0, '')
    assert proc.stdout.startswith('usage: rot-tools covariance INPUT ARGS... --cov C11 .. C33')
    for kind in ('euler', 'matrix', 'axis-angle', 'rotvec', 'quaternion', 'frame'):
        assert f'\n    {kind} ' in proc.stdout
    examples = proc.stdout.split('\nexamples:\n', 1)[1].splitlines()
    assert len(examples) == 3
    for line in examples:
        done = run(*line.split()[1:])
        assert (done.returncode, done.stderr) == (0, ''), line
    inner = run('covariance', 'quaternion', '--help').stdout
    assert inner.startswith('usage: rot-tools covariance quaternion X Y Z W\n')


# doc/covariance.md: the Jackal's IMU


def _most_pitched_imu_message():
    """Return (stamp s, orientation (x, y, z, w), covariance (9,)) of /imu/data's largest pitch."""
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    from rosbags.highlevel import AnyReader
    best = None
    with AnyReader([REPO.parent / 'shared' / 'data' / 'jackal_imu_odometry.bag']) as reader:
        connections = [c for c in reader.connections if c.topic == '/imu/data']
        for connection, _, raw in reader.messages(connections=connections):
            msg = reader.deserialize(raw, connection.msgtype)
            q = msg.orientation
            pitch = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_euler('xyz')[1]
            if best is None or abs(pitch) > best[0]:
                stamp = msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9
                best = (abs(pitch), stamp, [q.x, q.y, q.z, q.w],
                        list(msg.orientation_covariance))
    return best


def test_doc_jackal_imu_example():
    if not (REPO.parent / 'shared' / 'data' / 'jackal_imu_odometry.bag').exists():
        pytest.skip('the shared Jackal bag is not here')
    pitch, stamp, q, cov = _most_pitched_imu_message()
    assert (round(stamp, 2), round(math.degrees(pitch), 1)) == (75.78, 11.9)  # the prose's
    rotation = ' '.join(['quaternion', *_typed(q), '--cov', *_typed(cov)])
    shown = []
    for command, _ in console_steps(doc_block('covariance-jackal')):
        argv = command.split()
        assert ' '.join(argv[2:2 + len(rotation.split())]) == rotation  # the message's
        done = run(*argv[1:])
        assert (done.returncode, done.stderr) == (0, ''), done.stderr
        shown.append(f'$ {command}\n{done.stdout}')
    assert_doc_output('covariance-jackal', ''.join(shown))
