"""check_imu on the real Jackal recording, one fault at a time, and on synthetic motion."""

import itertools
import math

import bag_helpers as bh
from hypothesis import given, settings, strategies as st
import numpy as np
import pytest
from rot_tools import check_imu, ImuReference
from rot_tools.core.errors import RotationError
from rot_tools.core.imu import faults, ImuChecks
from scipy.spatial.transform import Rotation, Slerp

G = 9.80665
IMU, ODOM = '/imu/data', '/jackal_velocity_controller/odom'
REFERENCE_CHECKS = ('accel_sign', 'world_up', 'mounting')

SWAP = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1]])
"""Gyro x and y swapped and z negated: ω_orientation = SWAP·ω_measured (SWAP is its inverse)."""

BIAS = np.array([0.02, -0.03, 0.015])
LAG = 0.1
ENU_TO_NED = Rotation.from_matrix([[0, 1, 0], [1, 0, 0], [0, 0, -1]])
FLU_TO_FRD = Rotation.from_euler('x', 180, degrees=True)
MOUNTINGS = {
    'x up': Rotation.from_euler('ZYX', [30, 90, 0], degrees=True),
    'upside down': Rotation.from_euler('xyz', [180, 0, 45], degrees=True),
    'tilted': Rotation.from_euler('xyz', [10, -20, 135], degrees=True),
}
"""IMU frames turned on the body (the IMU frame in base_link): mountings, no fault."""


@pytest.fixture(scope='module')
def jackal():
    """{'t', 'q', 'gyro', 'accel'} of /imu/data and the odometry's ImuReference."""
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    real = bh.decode()
    imu = {k: real[IMU][v] for k, v in (('t', 'stamp'), ('q', 'q'), ('gyro', 'gyro'),
                                        ('accel', 'accel'))}
    return imu, ImuReference(real[ODOM]['stamp'], real[ODOM]['q'])


def turned(imu, X):
    """Return the IMU turned by X on the body: orientation R·X, gyro and accelerometer Xᵀ·v."""
    return dict(imu, q=(Rotation.from_quat(imu['q']) * X).as_quat(),
                gyro=X.inv().apply(imu['gyro']), accel=X.inv().apply(imu['accel']))


def late(imu, seconds):
    """Return the IMU with its orientation slerped from the recording `seconds` earlier."""
    t = imu['t']
    slerp = Slerp(t, Rotation.from_quat(imu['q']))
    return dict(imu, q=slerp(np.clip(t - seconds, t[0], t[-1])).as_quat())


def ned(imu):
    """Return the whole IMU in NED: body frame FRD, world NED, gyro and specific force on FRD."""
    R = ENU_TO_NED * Rotation.from_quat(imu['q']) * FLU_TO_FRD
    return dict(imu, q=R.as_quat(), gyro=FLU_TO_FRD.inv().apply(imu['gyro']),
                accel=FLU_TO_FRD.inv().apply(imu['accel']))


CASES = {
    # name: (the faulty copy, faults without reference, faults with the odometry)
    'clean': (lambda imu: imu, (), ()),
    'accel in g': (lambda imu: dict(imu, accel=imu['accel'] / G),
                   ('accel_units',), ('accel_units',)),
    'accel sign flipped': (lambda imu: dict(imu, accel=-imu['accel']),
                           ('orientation_vs_accel',), ('orientation_vs_accel', 'accel_sign')),
    'gyro in deg/s': (lambda imu: dict(imu, gyro=np.degrees(imu['gyro'])),
                      ('gyro_units',), ('gyro_units',)),
    'gyro x, y swapped, z negated': (lambda imu: dict(imu, gyro=imu['gyro'] @ SWAP.T),
                                     ('gyro_axes',), ('gyro_axes',)),
    'gyro bias': (lambda imu: dict(imu, gyro=imu['gyro'] + BIAS), ('gyro_bias',), ('gyro_bias',)),
    'orientation late': (lambda imu: late(imu, LAG), ('time_offset',), ('time_offset',)),
    'NED': (ned, ('orientation_vs_accel',), ('orientation_vs_accel', 'world_up')),
    **{f'turned {name}': (lambda imu, X=X: turned(imu, X), (), ())
       for name, X in MOUNTINGS.items()},
}


def run(imu, reference=None):
    return check_imu(imu['t'], imu['q'], imu['gyro'], imu['accel'], reference)


def up_in_imu(quaternion):
    """Return the body's up in the IMU frame, of a mounting [x, y, z, w] (scipy)."""
    return Rotation.from_quat(quaternion).inv().apply([0.0, 0.0, 1.0])


def degrees_between(u, v):
    return math.degrees(math.atan2(np.linalg.norm(np.cross(u, v)), np.dot(u, v)))


@pytest.fixture(scope='module')
def results(jackal):
    """{(case, with reference): ImuChecks} for every case of CASES."""
    imu, odom = jackal
    return {(name, with_ref): run(make(imu), odom if with_ref else None)
            for name, (make, _, _) in CASES.items() for with_ref in (False, True)}


@pytest.mark.parametrize('with_ref', [False, True], ids=['alone', 'with odometry'])
@pytest.mark.parametrize('case', list(CASES))
def test_the_injected_fault_is_found_and_only_it(results, case, with_ref):
    checks = results[case, with_ref]
    assert faults(checks) == CASES[case][1 + with_ref], [c.message for c in checks]
    # the recording tells every check; only the reference's need the reference; where the
    # accelerometer disagrees with every reading of the quaternion, its reading is not told
    unknown = {name for name, c in zip(checks._fields, checks) if c.status == 'unknown'}
    untold = {'quaternion'} if case in ('accel sign flipped', 'NED') else set()
    assert unknown == untold | (set() if with_ref else set(REFERENCE_CHECKS))
    assert checks.quaternion.reading == 'as recorded'


@pytest.mark.parametrize('with_ref', [False, True], ids=['alone', 'with odometry'])
def test_the_numbers_of_each_fault(results, jackal, with_ref):
    period = float(np.median(np.diff(jackal[0]['t'])))
    clean = results['clean', with_ref]
    assert abs(clean.accel_units.scale - 1) < 0.03
    assert abs(clean.gyro_units.scale - 1) < 0.03
    assert clean.gyro_axes.matrix == ((1, 0, 0), (0, 1, 0), (0, 0, 1))
    assert np.linalg.norm(clean.gyro_bias.bias) < 0.003
    assert abs(clean.time_offset.seconds) <= period  # the filter's half sample
    assert clean.orientation_vs_accel.angle < math.radians(1)
    scale = results['accel in g', with_ref].accel_units.scale
    assert abs(scale / G - 1) < 0.03
    scale = results['gyro in deg/s', with_ref].gyro_units.scale
    assert abs(scale / math.radians(1) - 1) < 0.03
    assert np.array_equal(results['gyro x, y swapped, z negated', with_ref].gyro_axes.matrix,
                          SWAP)
    bias = np.array(results['gyro bias', with_ref].gyro_bias.bias)
    assert np.linalg.norm(bias - BIAS) < 0.003
    assert abs(results['orientation late', with_ref].time_offset.seconds - LAG) <= period
    for case in ('accel sign flipped', 'NED'):
        assert results[case, with_ref].orientation_vs_accel.angle > math.radians(175)


def test_the_reference_tells_a_flipped_accelerometer_from_ned(results):
    flipped, device = results['accel sign flipped', True], results['NED', True]
    # per sample, the odometry's planar up against the real one on the Jackal's ground: 6°
    assert flipped.accel_sign.angle > math.radians(170)
    assert flipped.world_up.angle < math.radians(10)
    assert device.accel_sign.angle < math.radians(10)
    assert device.world_up.angle > math.radians(170)


@pytest.mark.parametrize('name', list(MOUNTINGS))
def test_a_turned_imu_gives_its_mounting(results, name):
    X = MOUNTINGS[name]
    checks, clean = results[f'turned {name}', True], results['clean', True]
    up = up_in_imu(checks.mounting.quaternion)
    assert degrees_between(up, X.inv().apply([0, 0, 1])) < 3  # base_link's IMU: mounted level
    # the same mounting as the clean recording's, turned by X
    assert degrees_between(up, X.inv().apply(up_in_imu(clean.mounting.quaternion))) < 0.1
    assert 'not determined' in checks.mounting.warning  # the odometry turns about z only


def test_five_seconds_of_little_turn_leave_the_mounting_unknown(jackal):
    imu, odom = jackal
    window = {k: v[1000:1250] for k, v in imu.items()}  # the Jackal almost stands still
    checks = run(window, odom)
    assert faults(checks) == ()
    assert {checks.mounting.status, checks.accel_sign.status, checks.world_up.status} == {
        'unknown'}
    assert "the IMU's turns have no dominant axis" in checks.mounting.message


def test_a_ned_device_is_mounted_upside_down(results):
    mounting = results['NED', True].mounting
    assert degrees_between(up_in_imu(mounting.quaternion), [0, 0, -1]) < 3
    # of the turns about the up axis, the one that keeps x: FRD in FLU
    turn = Rotation.from_quat(mounting.quaternion).inv() * FLU_TO_FRD
    assert turn.magnitude() < math.radians(5)


@pytest.mark.parametrize('case', ['clean', 'gyro in deg/s', 'gyro x, y swapped, z negated',
                                  'accel sign flipped'])
def test_every_ten_seconds_say_the_same(jackal, results, case):
    """The node checks the last 10 s: every stretch of 10 s gives the whole recording's faults."""
    imu = CASES[case][0](jackal[0])
    for start in range(0, len(imu['t']) - 500, 250):
        stretch = {k: v[start:start + 500] for k, v in imu.items()}
        assert faults(run(stretch)) == faults(results[case, False]), start


def test_the_reference_is_only_one_more_input(results):
    """The checks that do not need the reference give the same answer with it."""
    for case in CASES:
        alone, both = results[case, False], results[case, True]
        assert alone[:8] == both[:8]


# ---- synthetic motion ----------------------------------------------------------------------

RATE, SECONDS, CYCLE, MOVING = 100.0, 40.0, 8.0, 6.0
"""Samples per second, the length, and each cycle's seconds of motion then of rest."""


def _rest_between(t):
    """Motion time: the clock of each cycle's first MOVING s, smoothly stopped, then held."""
    cycles, into = np.divmod(t, CYCLE)
    x = np.clip(into / MOVING, 0, 1)
    return (cycles + x ** 3 * (10 - 15 * x + 6 * x * x)) * MOVING


def body(t, axes=(1.0, 1.0, 1.0)):
    """Return the body's orientation at t: rotation vectors of sines on its axes (scipy)."""
    s = _rest_between(np.asarray(t, float))[:, None]
    rotvec = 1.2 * np.sin(2 * np.pi * np.array([0.31, 0.23, 0.17]) * s + [0.3, 1.1, 2.0])
    return Rotation.from_rotvec(np.array(axes) * rotvec)


def synthetic(M=np.eye(3), scale=1.0, bias=(0.0, 0.0, 0.0), lag=0.0, X=None,
              axes=(1.0, 1.0, 1.0), noise=0.0, seed=0):
    """Return an IMU mounted X on a body turning as body(t), its gyro ω/scale on Mᵀ's axes."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(SECONDS * RATE)) / RATE
    X = Rotation.identity() if X is None else X
    W = Rotation.from_euler('z', 0.7)
    h = 1e-5
    rate = X.inv().apply((body(t - h, axes).inv() * body(t + h, axes)).as_rotvec() / (2 * h))
    gyro = (rate @ np.asarray(M, float)) / scale + np.asarray(bias) / scale
    gyro += noise * rng.normal(size=gyro.shape)
    accel = (W * body(t, axes) * X).inv().apply([0.0, 0.0, G])
    accel += 10 * noise * rng.normal(size=accel.shape)
    imu = {'t': t, 'q': (W * body(t - lag, axes) * X).as_quat(), 'gyro': gyro, 'accel': accel}
    return imu, ImuReference(t, body(t, axes).as_quat())


SIGNED_PERMUTATIONS = [np.diag(signs)[list(order)]
                       for order in itertools.permutations(range(3))
                       for signs in itertools.product((1, -1), repeat=3)]
"""The 48 signed permutations, reflections among them."""


@settings(max_examples=12, deadline=None, derandomize=True, database=None)
@given(M=st.sampled_from(SIGNED_PERMUTATIONS),
       scale=st.sampled_from([1.0, math.radians(1), 0.5, 1.6]),
       bias=st.sampled_from([(0.0, 0.0, 0.0), (0.03, -0.02, 0.01), (-0.05, 0.0, 0.02)]),
       lag=st.sampled_from([0.0, 0.1, -0.06, 0.25]),
       mounting=st.integers(0, 2 ** 16))
def test_rich_motion_gives_exact_answers(M, scale, bias, lag, mounting):
    X = Rotation.random(random_state=mounting)
    imu, reference = synthetic(M=M, scale=scale, bias=bias, lag=lag, X=X)
    checks = run(imu, reference)
    swapped = not np.array_equal(M, np.eye(3))
    expected = (('gyro_units',) * (scale != 1) + ('gyro_axes',) * swapped
                + ('gyro_bias',) * any(bias) + ('time_offset',) * (lag != 0))
    assert faults(checks) == expected, [c.message for c in checks]
    assert 'unknown' not in [c.status for c in checks]
    assert np.array_equal(checks.gyro_axes.matrix, M)
    assert checks.gyro_axes.mirror == (np.linalg.det(M) < 0)
    if checks.gyro_axes.mirror:  # the one negation that leaves the rotation nearest I
        flips = {a: np.trace(M @ np.diag([-1 if b == a else 1 for b in 'xyz'])) for a in 'xyz'}
        assert flips[checks.gyro_axes.negate] == max(flips.values())
        assert 'a mirror' in checks.gyro_axes.message
    else:
        assert checks.gyro_axes.negate is None
    assert checks.gyro_units.scale == pytest.approx(scale, rel=1e-3)
    assert np.allclose(checks.gyro_bias.bias, bias, atol=1e-3)
    assert checks.time_offset.seconds == pytest.approx(lag, abs=0.1 / RATE)
    assert checks.accel_units.scale == pytest.approx(1, rel=1e-6)
    assert checks.mounting.warning == ''  # three axes turn: the whole mounting
    error = Rotation.from_quat(checks.mounting.quaternion).inv() * X
    assert error.magnitude() < math.radians(0.1)
    assert checks.accel_sign.angle < math.radians(0.1) and checks.world_up.angle < 1e-6


def test_rich_motion_faults_of_the_accelerometer_and_the_world():
    imu, reference = synthetic(X=Rotation.from_euler('y', 90, degrees=True))
    assert faults(run(dict(imu, accel=imu['accel'] / G), reference)) == ('accel_units',)
    gone = dict(imu, accel=imu['accel'] - Rotation.from_quat(imu['q']).inv().apply([0, 0, G]))
    checks = run(gone, reference)
    assert checks.accel_units.status == 'fault' and checks.accel_units.scale is None
    assert 'gravity is removed' in checks.accel_units.message
    # no gravity, no up: the directions are unknown
    assert checks.orientation_vs_accel.status == checks.accel_sign.status == 'unknown'
    assert faults(run(ned(imu), reference)) == ('orientation_vs_accel', 'world_up')
    assert faults(run(dict(imu, accel=-imu['accel']), reference)) == (
        'orientation_vs_accel', 'accel_sign')
    # the orientation's world tilted 8°: Rᵀ·ẑ 8° from the specific force at every attitude
    tilted = dict(imu, q=(Rotation.from_euler('x', 8, degrees=True)
                          * Rotation.from_quat(imu['q'])).as_quat())
    checks = run(tilted)
    assert 'orientation_vs_accel' in faults(checks)
    assert math.degrees(checks.orientation_vs_accel.angle) == pytest.approx(8, abs=0.1)


def test_yaw_alone_fixes_z_and_leaves_x_and_y_unknown():
    imu, reference = synthetic(axes=(0, 0, 1), noise=1e-3)
    checks = run(imu, reference)
    assert faults(checks) == ()
    assert checks.gyro_axes.status == 'unknown' and checks.gyro_axes.matrix is None
    assert 'does not fix x, y' in checks.gyro_axes.message
    # the orientation never turns about x or y: the bias is known all the same
    assert checks.gyro_bias.status == 'ok' and checks.gyro_units.status == 'ok'
    assert 'not determined' in checks.mounting.warning
    # a gyro z negated and an inverted quaternion read alike under yaw alone: not told
    negated = run(dict(imu, gyro=imu['gyro'] * [1, 1, -1]))
    assert faults(negated) == ()
    assert negated.quaternion.status == negated.gyro_axes.status == 'unknown'
    assert 'as recorded or inverted agree alike' in negated.gyro_axes.message


def test_without_orientation_the_orientation_checks_are_unknown():
    imu, reference = synthetic(X=Rotation.from_euler('x', 180, degrees=True))
    for q in (None, np.zeros((len(imu['t']), 4))):
        checks = run(dict(imu, q=q), reference)
        status = {name: c.status for name, c in zip(checks._fields, checks)}
        assert status == {'quaternion': 'unknown', 'stamps': 'ok', 'accel_units': 'ok',
                          'orientation_vs_accel': 'unknown',
                          'gyro_units': 'unknown', 'gyro_axes': 'unknown',
                          'gyro_bias': 'unknown', 'time_offset': 'unknown',
                          'accel_sign': 'ok', 'world_up': 'unknown', 'mounting': 'ok'}
        # the mounting from the gyro's turns, integrated to first order: the IMU upside down
        up = up_in_imu(checks.mounting.quaternion)
        assert degrees_between(up, [0, 0, -1]) < 1
    checks = run(dict(imu, q=None, accel=-imu['accel']), reference)
    assert faults(checks) == ('accel_sign',)


def test_a_body_that_never_rests_has_no_slow_spells():
    imu, _ = synthetic()
    t = imu['t']
    spin = Rotation.from_rotvec(np.outer(0.5 * t, [0.0, 0.6, 0.8]))
    checks = run(dict(imu, q=spin.as_quat(), gyro=np.tile([0.0, 0.3, 0.4], (len(t), 1)),
                      accel=spin.inv().apply([0, 0, G])))
    assert checks.accel_units.status == checks.orientation_vs_accel.status == 'unknown'
    assert 'turns slowly' in checks.accel_units.message
    # a constant rate has no feature to fit or to align in time: the gyro's scale and its
    # lag are unknown (its mean would need the bias)
    assert {checks.gyro_units.status, checks.time_offset.status} == {'unknown'}


def test_a_still_imu_leaves_the_gyro_unknown():
    t = np.arange(500) / 50.0
    rng = np.random.default_rng(3)
    checks = check_imu(t, np.tile([0.0, 0.0, 0.0, 1.0], (500, 1)),
                       1e-3 * rng.normal(size=(500, 3)), np.tile([0.0, 0.0, G], (500, 1)))
    assert faults(checks) == ()
    assert {checks.gyro_units.status, checks.gyro_axes.status, checks.time_offset.status} == {
        'unknown'}
    assert checks.accel_units.scale == pytest.approx(1)


def test_stamps_out_of_order_or_with_a_gap():
    imu, _ = synthetic()
    order = np.arange(len(imu['t']))
    order[[100, 101]] = order[[101, 100]]
    shuffled = {k: v[order] for k, v in imu.items()}
    checks = run(shuffled)
    assert faults(checks) == ('stamps',) and checks.stamps.backwards == 1
    in_order = run(imu)
    assert checks[2:] == in_order[2:] and checks[0] == in_order[0]  # the samples in order
    t = imu['t'].copy()
    t[2000:] += 0.5
    checks = run(dict(imu, t=t))
    assert faults(checks) == ('stamps',)
    assert checks.stamps.gap == pytest.approx(0.51) and checks.stamps.period == pytest.approx(0.01)
    assert '51 periods' in checks.stamps.message


def test_faults_and_the_order_of_the_checks():
    assert ImuChecks._fields == (
        'quaternion', 'stamps', 'accel_units', 'orientation_vs_accel', 'gyro_units',
        'gyro_axes', 'gyro_bias', 'time_offset', 'accel_sign', 'world_up', 'mounting')
    imu, _ = synthetic()
    checks = run(imu)
    for check in checks:
        assert check._fields[:2] == ('status', 'message')
        assert check.status in ('ok', 'fault', 'unknown') and check.message.endswith('.')
    assert faults(checks) == ()


# ---- bad input ---------------------------------------------------------------------------


@pytest.fixture(scope='module')
def small():
    imu, reference = synthetic()
    return {k: v[:200] for k, v in imu.items()}, reference


@pytest.mark.parametrize('change, message', [
    ({'t': np.arange(5.0)}, r'stamps has 5 sample\(s\): at least 10 needed'),
    ({'t': np.zeros(200)}, r'stamps has 1 distinct stamp\(s\): at least 10 needed'),
    ({'t': np.zeros((200, 1))}, r'stamps must have shape \(N,\), got \(200, 1\)'),
    ({'gyro': np.zeros((199, 3))}, r'angular_velocity must have shape \(200, 3\), one per '
                                   r'stamp, got \(199, 3\)'),
    ({'accel': np.zeros((200, 2))}, r'linear_acceleration must have shape \(\.\.\., 3\)'),
    ({'q': np.zeros((200, 3))}, r'quaternions must have shape \(\.\.\., 4\)'),
    ({'gyro': np.full((200, 3), np.nan)}, r'angular_velocity must be finite: 600 non-finite'),
    ({'t': np.r_[np.arange(199.0), np.inf]}, r'stamps must be finite: 1 non-finite'),
    ({'gyro': np.full((200, 3), 1e10)}, r'angular_velocity\[0\] reads 1e\+10: beyond 1e\+09, '
                                        r'no sensor reads that \(600 such entries\)'),
])
def test_bad_input_says_what_and_by_how_much(small, change, message):
    imu = dict(small[0], **change)
    with pytest.raises(RotationError, match=message):
        run(imu)


def test_bad_quaternions_and_references(small):
    imu, reference = small
    q = imu['q'].copy()
    q[7] = 0.0
    with pytest.raises(RotationError, match=r'quaternions\[7\] is \(0, 0, 0, 0\) but 199 of 200'):
        run(dict(imu, q=q))
    q = imu['q'] * 1.01
    assert faults(run(dict(imu, q=q))) == ()  # tol None: normalised
    with pytest.raises(RotationError, match=r'quaternions: quaternion \(x, y, z, w\) is not of '
                                            r'unit length: \|q\| = 1\.01, off 1 by 0\.01 > tol'):
        check_imu(imu['t'], q, imu['gyro'], imu['accel'], tol=1e-3)
    with pytest.raises(RotationError, match=r'reference must be ImuReference'):
        run(imu, reference=5)
    with pytest.raises(RotationError, match=r'reference\.quaternions must have shape \(4000, 4\)'):
        run(imu, ImuReference(reference.stamps, reference.quaternions[:-1]))
    with pytest.raises(RotationError, match=r'reference\.quaternions are all \(0, 0, 0, 0\)'):
        run(imu, ImuReference(reference.stamps, np.zeros_like(reference.quaternions)))
    far = ImuReference(reference.stamps + 1000, reference.quaternions)
    checks = run(imu, far)
    assert {checks.accel_sign.status, checks.world_up.status, checks.mounting.status} == {
        'unknown'}
    assert 'the reference covers 0 of' in checks.mounting.message
