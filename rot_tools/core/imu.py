"""
An IMU's conventions checked from its samples (REP-103, REP-145): check_imu, on arrays.

Sample k of a ``sensor_msgs/Imu`` stream: stamp t_k (s), orientation R_k (the IMU frame in the
orientation's world), gyro ω_k (rad/s) and accelerometer a_k (m/s²) on the IMU's axes. ROS
expects an ENU world (z up, REP-103), the gyro to be the body rate of R (R_kᵀ·Ṙ_k = [ω_k]×),
the accelerometer to read the specific force (+9.80665 m/s² along the IMU's up at rest,
REP-145), and all three at one instant. The checks (ImuChecks, in order):

- stamps: increasing, no gap longer than GAP_PERIODS sample periods.
- accel_units (scale = 9.80665 / median |ā_k| in slow spells, imu_motion.slow_spells; ā_k
  the accelerometer averaged over the slow window, imu_motion.steady_accel): fault beyond
  ACCEL_TOL (g instead of m/s², gravity removed).
- orientation_vs_accel (angle): the world z seen from the IMU, Rᵀ·ẑ, against the specific
  force's direction in slow spells: the median over those samples of the angle between
  R_kᵀ·ẑ and ā_k (a tilt shows at every attitude; a mean of vectors would let the attitudes
  cancel it). Fault beyond ANGLE_TOL; near 180° the accelerometer reads gravity, or the
  orientation's world is NED. Unknown where the accelerometer shows no gravity.
- gyro_units (scale), gyro_axes (matrix, a signed permutation M), gyro_bias (bias): the fit
  ω° ≈ scale·M·(ω − bias/scale) of the orientation's rates (imu_motion.fit_gyro). Faults:
  |scale − 1| > GYRO_TOL, M ≠ I on the axes the motion fixes, |bias| > BIAS_TOL rad/s.
- time_offset (seconds): how late the orientation is (imu_motion.orientation_lag); fault
  beyond LAG_PERIODS periods.
- With a reference (ImuReference: the body's orientation Q_k): mounting (quaternion, the
  IMU frame X in the body frame, imu_mounting); accel_sign (angle: the median over slow
  spells of the angle between the body's up in the IMU frame, Xᵀ·Q_kᵀ·ẑ, and ā_k; fault
  beyond 90°, the accelerometer's sign flipped); world_up (angle: the median over the
  mounting's poses of the angle between the orientation's world z in the reference's world,
  Q_k·X·R_kᵀ·ẑ, and ẑ; fault beyond 90°, NED).

Each check is ok, fault or unknown (where the data cannot tell: no orientation, no slow
spells, too little motion, no reference), with a one-sentence message and its numbers
(radians, rad/s, seconds, plain factors; None where unknown).
"""

import math
from typing import Any, NamedTuple

import numpy as np
from rot_tools.core.errors import RotationError
from rot_tools.core.imu_motion import (
    body_rates, fit_gyro, orientation_lag, RATE_GAP, SLOW_RATE, slow_spells, steady_accel)
from rot_tools.core.imu_mounting import HAND_EYE_STEP, imu_mounting, mounting_poses
from rot_tools.core.imu_samples import imu_samples, reference_samples, stamps_array
from rot_tools.core.so3 import matrix_to_quaternion
from rot_tools.core.trajectory import nearest_stamps

GRAVITY = 9.80665
"""Standard gravity (m/s²): what |linear_acceleration| reads at rest."""

GAP_PERIODS = 10
"""A step longer than this many median periods is a gap (stamps: fault)."""

MIN_SLOW = 1.0
"""Seconds of slow spells at least, for the accelerometer's checks."""

ACCEL_TOL = 0.05
"""|scale − 1| of the accelerometer beyond which it is a fault."""

ANGLE_TOL = math.radians(5)
"""Angle between Rᵀ·ẑ and the specific force beyond which it is a fault (rad)."""

GYRO_TOL = 0.1
"""|scale − 1| of the gyro beyond which it is a fault."""

BIAS_TOL = 0.01
"""Norm of the gyro bias beyond which it is a fault (rad/s)."""

LAG_PERIODS = 2
"""Orientation lag beyond this many sample periods is a fault."""

MIN_CORRELATION = 0.5
"""Correlation of the two angular speeds below which the lag is unknown."""

NO_GRAVITY = 0.5
"""Median |a| (in its units) in slow spells below which the accelerometer shows no gravity,
so no direction of up (a gravity-compensated output; in g it reads 1)."""

AXES = 'xyz'


# ---- the checks --------------------------------------------------------------------------


class ImuReference(NamedTuple):
    """The body's orientation in its world: stamps (M,) s, quaternions (M, 4) [x, y, z, w]."""

    stamps: Any
    quaternions: Any


class StampsCheck(NamedTuple):
    """Stamps: period (s, median step), gap (s, longest step), backwards (steps ≤ 0)."""

    status: str
    message: str
    period: Any
    gap: Any
    backwards: int


class AccelUnitsCheck(NamedTuple):
    """scale: the factor that makes |linear_acceleration| read 9.80665 m/s² in slow spells."""

    status: str
    message: str
    scale: Any


class AngleCheck(NamedTuple):
    """angle (rad) between two directions that should agree."""

    status: str
    message: str
    angle: Any


class GyroUnitsCheck(NamedTuple):
    """scale: ω_orientation ≈ scale·M·(ω_measured − bias)."""

    status: str
    message: str
    scale: Any


class GyroAxesCheck(NamedTuple):
    """matrix: the signed permutation M (3 rows of 3 ints), None unless every row is fixed."""

    status: str
    message: str
    matrix: Any


class GyroBiasCheck(NamedTuple):
    """bias: the gyro's reading at rest (3 floats, rad/s, on the gyro's own axes)."""

    status: str
    message: str
    bias: Any


class TimeOffsetCheck(NamedTuple):
    """seconds: how much the orientation lags the gyro (positive: the orientation is late)."""

    status: str
    message: str
    seconds: Any


class MountingCheck(NamedTuple):
    """quaternion [x, y, z, w] of the IMU frame in the body frame; warning: '' or why not whole."""

    status: str
    message: str
    quaternion: Any
    warning: str


class ImuChecks(NamedTuple):
    """Every check of check_imu, each a NamedTuple (status, message, its numbers)."""

    stamps: StampsCheck
    accel_units: AccelUnitsCheck
    orientation_vs_accel: AngleCheck
    gyro_units: GyroUnitsCheck
    gyro_axes: GyroAxesCheck
    gyro_bias: GyroBiasCheck
    time_offset: TimeOffsetCheck
    accel_sign: AngleCheck
    world_up: AngleCheck
    mounting: MountingCheck


def faults(checks):
    """Return the names of the checks of an ImuChecks whose status is 'fault', in order."""
    return tuple(name for name, check in zip(checks._fields, checks) if check.status == 'fault')


def _unknown(kind, message):
    """Return a check of the NamedTuple class kind, status 'unknown', its numbers None."""
    extra = {'warning': ''} if kind is MountingCheck else {}
    numbers = {f: None for f in kind._fields[2:] if f not in extra}
    return kind(status='unknown', message=message, **numbers, **extra)


def _status(fault):
    return 'fault' if fault else 'ok'


def _deg(angle):
    return f'{math.degrees(angle):.1f}°'


def _check_stamps(stamps, samples):
    """Return the StampsCheck: steps as given (backwards), and in order (period, gap)."""
    backwards = int((np.diff(stamps) <= 0).sum())
    period, gap = samples.period, float(np.diff(samples.t).max())
    rate = f'{len(stamps)} samples every {period:.6g} s ({1 / period:.4g} Hz)'
    faulty = []
    if backwards:
        faulty.append(f'{backwards} step(s) go back or repeat a stamp')
    if gap > GAP_PERIODS * period:
        faulty.append(f'the longest gap, {gap:.6g} s, is {gap / period:.3g} periods '
                      f'(> {GAP_PERIODS})')
    message = (f'{rate}: ' + ' and '.join(faulty) if faulty else
               f'{rate}, increasing, the longest step {gap:.6g} s.')
    return StampsCheck(status=_status(bool(faulty)), message=message.rstrip('.') + '.',
                       period=period, gap=gap, backwards=backwards)


# ---- the accelerometer -------------------------------------------------------------------


def _too_few_slow(samples, slow):
    """Return '' when the slow spells last MIN_SLOW at least, else why they are too few."""
    seconds = slow.sum() * samples.period
    if seconds >= MIN_SLOW:
        return ''
    source = 'orientation' if samples.R is not None else 'gyro'
    return (f'the body turns slowly (under {SLOW_RATE:g} rad/s by its {source}) for '
            f'{seconds:.3g} s: at least {MIN_SLOW:g} s needed')


def _no_gravity(force):
    """Return '' when the accelerometer shows gravity in slow spells, else why not."""
    size = float(np.median(np.linalg.norm(force, axis=1)))
    if size >= NO_GRAVITY:
        return ''
    return (f'the accelerometer reads {size:.3g} when the body turns slowly: no gravity, so no '
            'direction of up.')


def _accel_units(force):
    size = float(np.median(np.linalg.norm(force, axis=1)))
    scale = GRAVITY / size if size > 0 else None
    scale = scale if scale is not None and math.isfinite(scale) else None
    said = (f'|linear_acceleration| reads {size:.4g} when the body turns slowly'
            + (f' (scale {scale:.4g})' if scale is not None else ''))
    if scale is not None and abs(scale - 1) <= ACCEL_TOL:
        return AccelUnitsCheck(status='ok', scale=scale, message=f'{said}: m/s².')
    if scale is not None and abs(scale / GRAVITY - 1) <= ACCEL_TOL:
        why = 'it reads g, not m/s²'
    elif size < 0.2 * GRAVITY:
        why = ('gravity is removed, or there is no accelerometer (REP-145: it reads the '
               'specific force, +9.80665 m/s² up at rest)')
    else:
        why = f'off {GRAVITY} m/s² by {abs(size / GRAVITY - 1):.1%}'
    return AccelUnitsCheck(status='fault', scale=scale, message=f'{said}: {why}.')


def _median_angle(u, v):
    """Return the median over rows of the angle (rad) between u and v (K, 3)."""
    sin = np.linalg.norm(np.cross(u, v), axis=1)
    return float(np.median(np.arctan2(sin, np.sum(u * v, axis=1))))


def _orientation_vs_accel(R, force):
    angle = _median_angle(R[:, 2, :], force)  # Rᵀ·ẑ is R's last row
    said = f'Rᵀ·ẑ and the specific force are {_deg(angle)} apart when the body turns slowly'
    if angle <= ANGLE_TOL:
        return AngleCheck(status='ok', angle=angle, message=f'{said}.')
    if angle > math.pi / 2:
        why = ('the accelerometer reads gravity instead of the specific force (sign '
               "flipped), or the orientation's world is NED (z down)")
    else:
        why = f"the orientation's tilt disagrees with the accelerometer's (> {_deg(ANGLE_TOL)})"
    return AngleCheck(status='fault', angle=angle, message=f'{said}: {why}.')


# ---- the gyro against the orientation -----------------------------------------------------


def _time_offset(samples):
    """Return the TimeOffsetCheck, and the lag (s) for the gyro fit (0 where unknown)."""
    try:
        lag = orientation_lag(samples)
    except RotationError as exc:
        return _unknown(TimeOffsetCheck, f'the angular speeds do not fix the lag: {exc}.'), 0.0
    seconds, r = lag.seconds, lag.correlation
    if not r >= MIN_CORRELATION:
        return _unknown(TimeOffsetCheck, 'the angular speeds of the gyro and the orientation '
                        f'correlate at {r:.2f} at best (< {MIN_CORRELATION:g}): too little '
                        'motion to align them.'), 0.0
    periods = seconds / samples.period
    said = (f'the orientation lags the gyro by {seconds:.4g} s ({periods:+.2f} periods; the '
            f'angular speeds correlate at {r:.3f})')
    if abs(periods) <= LAG_PERIODS:
        return TimeOffsetCheck(status='ok', seconds=seconds, message=f'{said}.'), seconds
    late = 'late' if seconds > 0 else 'early'
    return TimeOffsetCheck(status='fault', seconds=seconds, message=(
        f'{said}: the orientation is {late} by more than {LAG_PERIODS} periods.')), seconds


def _axis_map(rows, axes):
    return ', '.join(f"{AXES[i]} is the gyro's {'+-'[rows[i][1] < 0]}{AXES[rows[i][0]]}"
                     for i in axes)


def _gyro_units(fit):
    said = f"the orientation's rates read {fit.scale:.4g} × the gyro's"
    if abs(fit.scale - 1) <= GYRO_TOL:
        return GyroUnitsCheck(status='ok', scale=fit.scale, message=f'{said}: rad/s.')
    why = ('it reads degrees/s, not rad/s' if abs(fit.scale * 180 / math.pi - 1) <= GYRO_TOL
           else f'off 1 by {abs(fit.scale - 1):.1%}')
    return GyroUnitsCheck(status='fault', scale=fit.scale, message=f'{said}: {why}.')


def _gyro_axes(fit):
    fixed = sorted(fit.rows)
    wrong = [i for i in fixed if fit.rows[i] != (i, 1)]
    left = ', '.join(AXES[i] for i in range(3) if i not in fit.rows)
    them = 'it' if len(fixed) == 2 else 'them'
    unfixed = (f'the motion does not fix {left} (too little turn about {them}, or rates that '
               'differ)')
    if len(fixed) == 3:
        matrix = tuple(tuple(s if k == j else 0 for k in range(3))
                       for j, s in (fit.rows[i] for i in range(3)))
        message = ("each gyro axis reads the orientation's rate about the same axis." if not
                   wrong else f'swapped or negated axes: {_axis_map(fit.rows, wrong)}.')
        return GyroAxesCheck(status=_status(bool(wrong)), matrix=matrix, message=message)
    if wrong:
        return GyroAxesCheck(status='fault', matrix=None, message=(
            f'swapped or negated axes: {_axis_map(fit.rows, wrong)}; {unfixed}.'))
    return GyroAxesCheck(status='unknown', matrix=None, message=(
        f"{', '.join(AXES[i] for i in fixed)} as the orientation's; {unfixed}."))


def _gyro_bias(fit):
    if fit.bias is None:
        left = ', '.join(AXES[i] for i in range(3) if i not in fit.rows)
        return _unknown(GyroBiasCheck, f'the orientation turns about {left}, which the '
                        'motion does not fix on the gyro, so the bias is not known.')
    norm = float(np.linalg.norm(fit.bias))
    said = (f'the gyro reads ({", ".join(f"{b:.4g}" for b in fit.bias)}) rad/s more than '
            f'the orientation turns (norm {norm:.4g} rad/s)')
    over = norm > BIAS_TOL
    return GyroBiasCheck(status=_status(over), bias=tuple(map(float, fit.bias)), message=(
        f'{said}: more than {BIAS_TOL:g} rad/s.' if over else f'{said}.'))


def _gyro_checks(samples):
    """Return the TimeOffsetCheck, GyroUnitsCheck, GyroAxesCheck and GyroBiasCheck."""
    if samples.R is None:
        why = 'no orientation to compare the gyro with.'
        return (_unknown(TimeOffsetCheck, why), _unknown(GyroUnitsCheck, why),
                _unknown(GyroAxesCheck, why), _unknown(GyroBiasCheck, why))
    offset, lag = _time_offset(samples)
    fit = fit_gyro(body_rates(samples, lag))
    if fit.scale is None:
        why = ("the orientation's rates fix no gyro axis (too little turn, or rates that do "
               'not match).')
        return (offset, _unknown(GyroUnitsCheck, why), _unknown(GyroAxesCheck, why),
                _unknown(GyroBiasCheck, why))
    return offset, _gyro_units(fit), _gyro_axes(fit), _gyro_bias(fit)


# ---- against a reference -------------------------------------------------------------------


def _mounting(samples, ref_t, ref_Q, ref_period, lag):
    """Return the MountingCheck, and the Mounting (None where unknown)."""
    count = len(mounting_poses(samples, ref_t))
    if count < 3:
        return _unknown(MountingCheck, f'the reference covers {count} of the IMU’s steps of '
                        f'{HAND_EYE_STEP:g} s: too few for a mounting.'), None
    try:
        found = imu_mounting(samples, ref_t, ref_Q, ref_period, lag)
    except RotationError as exc:
        return _unknown(MountingCheck, f'no mounting: {exc}.'), None
    quaternion = matrix_to_quaternion(found.X, check=False)
    angle = 2 * math.atan2(math.hypot(*quaternion[:3]), quaternion[3])
    up = ', '.join(f'{u:.3f}' for u in found.X[2])
    return MountingCheck(status='ok', quaternion=tuple(map(float, quaternion)), message=(
        f'the IMU frame is turned {_deg(angle)} in the body frame; the body’s up is ({up}) '
        'in the IMU frame.'), warning=found.warning), found


def _accel_sign(samples, slow, force, ref_t, ref_Q, ref_period, X):
    inside = np.flatnonzero(slow)
    near = nearest_stamps(ref_t, samples.t[inside], RATE_GAP * max(ref_period, samples.period))
    inside = inside[near.covered]
    why = _too_few_slow(samples, np.isin(np.arange(len(slow)), inside))
    if why:
        return _unknown(AngleCheck, f'{why} where the reference covers them.')
    # Xᵀ·Q_kᵀ·ẑ: the body's up in the IMU frame
    angle = _median_angle(ref_Q[near.index, 2, :] @ X, force[inside])
    said = (f'the specific force is {_deg(angle)} from the up that the reference gives through '
            'the mounting')
    if angle <= math.pi / 2:
        return AngleCheck(status='ok', angle=angle, message=f'{said}.')
    return AngleCheck(status='fault', angle=angle, message=(
        f'{said}: the accelerometer reads gravity, not the specific force (its sign is '
        'flipped).'))


def _world_up(found):
    covered = np.isfinite(found.Q[:, 0, 0])
    # Q_k·X·R_kᵀ·ẑ: the orientation's world z in the reference's world
    up = np.einsum('nij,jk,nk->ni', found.Q[covered], found.X, found.R[covered, 2, :])
    angle = _median_angle(up, np.array([[0.0, 0.0, 1.0]]))
    said = f"the orientation's world z is {_deg(angle)} from the reference's"
    if angle <= math.pi / 2:
        return AngleCheck(status='ok', angle=angle, message=f'{said}: up (ENU).')
    return AngleCheck(status='fault', angle=angle, message=(
        f'{said}: it points down, the orientation is NED (REP-103 wants ENU).'))


def _reference_checks(samples, slow, force, reference, tol, lag, flat):
    """Return the accel_sign, world_up and mounting checks (lag: the orientation's, s)."""
    if reference is None:
        why = 'no reference orientation to compare with.'
        return (_unknown(AngleCheck, why), _unknown(AngleCheck, why),
                _unknown(MountingCheck, why))
    ref_t, ref_Q, ref_period = reference_samples(reference, tol)
    mounting, found = _mounting(samples, ref_t, ref_Q, ref_period, lag)
    if found is None:
        why = 'no mounting, so no physical up in the IMU frame.'
        return _unknown(AngleCheck, why), _unknown(AngleCheck, why), mounting
    sign = (_unknown(AngleCheck, flat) if flat
            else _accel_sign(samples, slow, force, ref_t, ref_Q, ref_period, found.X))
    up = (_unknown(AngleCheck, 'no orientation.') if samples.R is None
          else _world_up(found))
    return sign, up, mounting


# ---- all together ------------------------------------------------------------------------


def check_imu(stamps, quaternions, angular_velocity, linear_acceleration, reference=None, *,
              tol=None):
    """
    Check an IMU's samples against ROS's conventions (REP-103, REP-145): return ImuChecks.

    stamps (N,) s, N ≥ 10, in any order (the stamps check says where they do not increase;
    the other checks take the samples in order, each stamp once); quaternions (N, 4)
    [x, y, z, w], or None for an IMU without orientation (all zeros count as None);
    angular_velocity (N, 3) rad/s; linear_acceleration (N, 3) m/s²; reference None or
    ImuReference(stamps (M,), quaternions (M, 4)), the orientation of the body that carries
    the IMU in its world (odometry, a pose, TF). tol: None takes any non-zero quaternion as
    its normalised self; a number refuses ||q| − 1| > tol. Each check is ok, fault or unknown
    (module docstring). RotationError (imu_samples) for a shape, NaN or Inf, a reading beyond
    1e9, a zero or non-unit quaternion, fewer than 10 distinct stamps.
    """
    given = stamps_array(stamps, 'stamps')
    samples = imu_samples(given, quaternions, angular_velocity, linear_acceleration, tol)
    slow, force = slow_spells(samples), steady_accel(samples)
    why = _too_few_slow(samples, slow)
    flat = '' if why else _no_gravity(force[slow])
    if why:
        units, tilt = _unknown(AccelUnitsCheck, f'{why}.'), _unknown(AngleCheck, f'{why}.')
    else:
        units = _accel_units(force[slow])
        tilt = (_unknown(AngleCheck, 'no orientation.') if samples.R is None
                else _unknown(AngleCheck, flat) if flat
                else _orientation_vs_accel(samples.R[slow], force[slow]))
    offset, gyro_units, gyro_axes, gyro_bias = _gyro_checks(samples)
    lag = offset.seconds if offset.status != 'unknown' else 0.0
    sign, up, mounting = _reference_checks(samples, slow, force, reference, tol, lag, flat)
    return ImuChecks(stamps=_check_stamps(given, samples), accel_units=units,
                     orientation_vs_accel=tilt, gyro_units=gyro_units, gyro_axes=gyro_axes,
                     gyro_bias=gyro_bias, time_offset=offset, accel_sign=sign, world_up=up,
                     mounting=mounting)
