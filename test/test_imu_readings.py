"""check_imu blames the right culprit, and says unknown where the data cannot tell."""

import math

import numpy as np
import pytest
from rot_tools import check_imu
from rot_tools.core.errors import RotationError
from rot_tools.core.imu import faults, read_quaternions
from rot_tools.core.stamps import delta_pairs, stamp_steps
from scipy.spatial.transform import Rotation
from test_imu import jackal, run, synthetic  # noqa: F401 (jackal: the module's fixture)

ORDERED = ('quaternion', 'gyro_units', 'gyro_axes', 'gyro_bias', 'time_offset')
"""The checks that need the samples' order."""


def w_first(imu):
    """Return the IMU with its quaternion written w-first: fields x, y, z, w hold w, x, y, z."""
    return dict(imu, q=np.roll(imu['q'], 1, axis=1))


def inverted(imu):
    """Return the IMU with the world in the IMU frame: the inverse rotation (scipy)."""
    return dict(imu, q=Rotation.from_quat(imu['q']).inv().as_quat())


def mirrored(imu):
    """Return the IMU with its gyro's z negated: a left-handed gyro."""
    return dict(imu, gyro=imu['gyro'] * [1, 1, -1])


FAULTS = {'w-first': (w_first, ('quaternion',)), 'inverted': (inverted, ('quaternion',)),
          'mirror': (mirrored, ('gyro_axes',)), 'clean': (lambda imu: imu, ())}


@pytest.fixture(scope='module')
def heeled():
    """Return a body heeled 15° that turns about three axes, its gyro noisy (test_imu)."""
    return synthetic(X=Rotation.from_euler('x', 15, degrees=True), noise=2e-3)


@pytest.mark.parametrize('with_ref', [False, True], ids=['alone', 'with odometry'])
@pytest.mark.parametrize('case', list(FAULTS))
def test_the_jackal_with_one_fault_blames_it_alone(jackal, case, with_ref):  # noqa: F811
    imu, odom = jackal
    make, expected = FAULTS[case]
    checks = run(make(imu), odom if with_ref else None)
    assert faults(checks) == expected, [c.message for c in checks]
    reading = case if case in ('w-first', 'inverted') else 'as recorded'
    assert checks.quaternion.reading == reading
    # the other checks take the orientation as read: the accelerometer and gyro agree with it
    assert checks.orientation_vs_accel.angle < math.radians(1)
    assert abs(checks.gyro_units.scale - 1) < 0.03


@pytest.mark.parametrize('case', list(FAULTS))
def test_a_heeled_body_turning_about_three_axes_blames_the_fault_alone(heeled, case):
    imu, reference = heeled
    make, expected = FAULTS[case]
    for checks in (run(make(imu)), run(make(imu), reference)):
        assert faults(checks) == expected, [c.message for c in checks]
        assert checks.quaternion.status == ('fault' if expected == ('quaternion',) else 'ok')


def test_the_quaternion_fault_says_how_it_was_written(jackal):  # noqa: F811
    imu, _ = jackal
    message = run(w_first(imu)).quaternion.message
    assert message.startswith('written w-first: its fields x, y, z, w hold w, x, y, z; read so')
    message = run(inverted(imu)).quaternion.message
    assert message.startswith('inverted: it gives the world in the IMU frame')


def test_a_mirror_is_named_with_the_axis_to_negate(jackal):  # noqa: F811
    imu, _ = jackal
    axes = run(mirrored(imu)).gyro_axes
    assert (axes.mirror, axes.negate) == (True, 'z')
    assert axes.matrix == ((1, 0, 0), (0, 1, 0), (0, 0, -1))
    assert axes.message.startswith("a mirror: z is the gyro's -z, a left-handed frame")
    # swapped x and y: negating x or y leaves a quarter turn about z; x is named first
    swapped = run(dict(imu, gyro=imu['gyro'][:, [1, 0, 2]])).gyro_axes
    assert (swapped.mirror, swapped.negate) == (True, 'x')
    assert "with it negated, x is the gyro's +y, y is the gyro's -x" in swapped.message
    turned = run(dict(imu, gyro=imu['gyro'] * [-1, -1, 1])).gyro_axes
    assert (turned.status, turned.mirror, turned.negate) == ('fault', False, None)
    assert turned.message.startswith('swapped or negated axes (a turn of the frame)')


GYROS = {
    'zeros': lambda gyro, rng: np.zeros_like(gyro),
    'a constant': lambda gyro, rng: np.full_like(gyro, 0.5),
    'absurd': lambda gyro, rng: np.full_like(gyro, 1e9),
    'noise': lambda gyro, rng: rng.normal(0, 0.1, gyro.shape),
    'shuffled': lambda gyro, rng: gyro[rng.permutation(len(gyro))],
}


@pytest.mark.parametrize('gyro', list(GYROS))
def test_a_gyro_that_does_not_follow_a_turning_orientation_is_a_fault(jackal, gyro):  # noqa: F811
    imu, _ = jackal
    checks = run(dict(imu, gyro=GYROS[gyro](imu['gyro'], np.random.default_rng(5))))
    assert faults(checks) == ('gyro_units',)
    assert checks.gyro_units.scale is None
    assert 'but the gyro does not follow it' in checks.gyro_units.message
    assert {checks.gyro_axes.status, checks.gyro_bias.status, checks.time_offset.status} == {
        'unknown'}


def test_stamps_going_back_are_the_only_fault(jackal):  # noqa: F811
    imu, odom = jackal
    for reference in (None, odom):
        checks = run(dict(imu, t=imu['t'][::-1]), reference)
        assert faults(checks) == ('stamps',)
        assert checks.stamps.backwards == len(imu['t']) - 1
        assert "the samples' order is not known" in checks.stamps.message
        for name in ORDERED:
            assert getattr(checks, name).status == 'unknown', name


def test_windows_of_a_clean_recording_have_no_fault(jackal):  # noqa: F811
    """100 windows of 2 to 10 s, every other one with the odometry: no fault."""
    imu, odom = jackal
    rng = np.random.default_rng(11)
    t = imu['t'] - imu['t'][0]
    for k in range(100):
        length = rng.uniform(2, 10)
        start = rng.uniform(0, t[-1] - length)
        inside = (t >= start) & (t < start + length)
        checks = run({key: v[inside] for key, v in imu.items()}, odom if k % 2 else None)
        assert faults(checks) == (), (start, length, [c.message for c in checks])


def test_the_lag_is_searched_within_what_the_data_can_fix(jackal):  # noqa: F811
    imu, _ = jackal
    first = run({k: v[:51] for k, v in imu.items()}).time_offset  # 1 s
    assert first.status != 'fault'
    assert first.seconds is None or abs(first.seconds) <= 0.1
    ten = run({k: v[:10] for k, v in imu.items()}).time_offset
    assert ten.status == 'unknown' and 'too short to search for a lag' in ten.message


def test_two_seconds_of_wheel_slip_leave_the_up_unknown(jackal):  # noqa: F811
    """28 to 30 s: the odometry turns, the IMU hardly: no mounting, so no up."""
    imu, odom = jackal
    t = imu['t'] - imu['t'][0]
    inside = (t >= 28) & (t <= 30)
    checks = run({k: v[inside] for k, v in imu.items()}, odom)
    assert faults(checks) == ()
    assert {checks.mounting.status, checks.accel_sign.status, checks.world_up.status} == {
        'unknown'}


def test_a_round_off_figure_is_said_in_words(jackal):  # noqa: F811
    imu, odom = jackal
    warning = run(imu, odom).mounting.warning
    assert warning.startswith('the body turned about one axis only: the turn of the mounting')
    assert 'σ' not in warning


def test_no_message_names_an_internal_variable(jackal):  # noqa: F811
    imu, _ = jackal
    for gyro in ('zeros', 'a constant'):
        checks = run(dict(imu, gyro=GYROS[gyro](imu['gyro'], None)))
        for check in checks:
            assert not any(name in check.message for name in ('R_ref', 'R_est', 'Rᵀ')), check


# ---- the stamps' jitter ----------------------------------------------------------------------


def test_bimodal_steps_suggest_arrival_time_stamps():
    rng = np.random.default_rng(2)
    steps = np.where(rng.random(999) < 0.5, 0.0095, 0.0106) + rng.normal(0, 5e-5, 999)
    found = stamp_steps(1.7e9 + np.concatenate([[0.0], np.cumsum(steps)]))
    assert found.arrival_time
    assert found.modes == pytest.approx((0.0095, 0.0106), abs=1e-4)
    assert found.rate == pytest.approx(1 / found.period)
    steady = stamp_steps(1.7e9 + np.cumsum(0.01 + rng.normal(0, 5e-5, 1000)))
    assert not steady.arrival_time and steady.modes is None
    assert steady.period == pytest.approx(0.01, abs=1e-5)
    assert steady.spread == pytest.approx(5e-5, rel=0.2)


def test_the_stamps_check_reports_the_jitter(heeled):
    imu, _ = heeled
    t = imu['t'] + np.tile([0.0, 0.0006], len(imu['t']) // 2)  # steps of 9.4 and 10.6 ms
    stamps = run(dict(imu, t=t)).stamps
    assert stamps.status == 'ok' and stamps.arrival_time
    assert stamps.rate == pytest.approx(1 / stamps.period)
    assert stamps.spread == pytest.approx(0.0006, rel=0.01)  # ±0.6 ms about their mean
    assert 'stamped as messages arrive rather than by the sensor' in stamps.message
    regular = run(imu).stamps
    assert not regular.arrival_time and 'equal steps' in regular.message


# ---- numbers beyond float64 ----------------------------------------------------------------


def test_counts_and_deltas_beyond_float64_raise_rotation_error():
    with pytest.raises(RotationError, match=r'count must be at most 268435456 poses, got '
                                            r'1\.000e\+400'):
        delta_pairs(10 ** 400)
    with pytest.raises(RotationError, match=r'delta = 1\.000e\+400 frames leaves no pair '
                                            r'among 10 poses'):
        delta_pairs(10, 10 ** 400)
    with pytest.raises(RotationError, match=r'delta = 1\.000e\+400 s leaves no pair'):
        delta_pairs(10, 10 ** 400, 's', np.arange(10.0))


def test_stamps_closer_than_a_nanosecond_raise_rotation_error(heeled):
    imu, _ = heeled
    tiny = np.arange(len(imu['t'])) * 5e-324
    with pytest.raises(RotationError, match=r'stamps: the median step is 4\.94e-324 s: under '
                                            r'1e-09 s, the resolution of ROS stamps'):
        check_imu(tiny, imu['q'], imu['gyro'], imu['accel'])
    huge = np.r_[-1e308, 1e308 * (1 + 1e-15 * np.arange(len(imu['t']) - 1))]
    with pytest.raises(RotationError, match=r'stamps: the steps between the stamps overflow '
                                            r'float64'):
        check_imu(huge, imu['q'], imu['gyro'], imu['accel'])


def test_the_three_readings_of_a_quaternion():
    q = np.array([[0.1, 0.2, 0.3, 0.9]])
    assert np.array_equal(read_quaternions(q, 'as recorded'), q)
    assert np.array_equal(read_quaternions(q, 'w-first'), [[0.2, 0.3, 0.9, 0.1]])
    assert np.array_equal(read_quaternions(q, 'inverted'), [[-0.1, -0.2, -0.3, 0.9]])
    with pytest.raises(RotationError, match='reading must be one of as recorded, w-first, '
                                            "inverted, got 'x-first'"):
        read_quaternions(q, 'x-first')
