"""
An IMU's conventions checked from its samples (REP-103, REP-145): check_imu, on arrays.

Sample k: stamp t_k (s), orientation R_k (the IMU frame in the orientation's world), gyro ω_k
(rad/s) and accelerometer a_k (m/s²) on the IMU's axes. ROS expects an ENU world (z up), the
gyro to be the body rate of R, the accelerometer to read the specific force (+9.80665 m/s² up
at rest), all three at one instant. Each check of ImuChecks is ok, fault, or unknown where the
data cannot tell.
"""

__all__ = ['check_imu', 'ImuChecks', 'ImuReference']

import math
from typing import Any, NamedTuple

import numpy as np
from rot_tools.core.errors import RotationError
from rot_tools.core.imu_checks import (
    AccelUnitsCheck, AngleCheck, GyroAxesCheck, GyroBiasCheck, GyroUnitsCheck, ImuChecks,
    MountingCheck, QuaternionCheck, StampsCheck, TimeOffsetCheck, unknown)
from rot_tools.core.imu_motion import (
    body_rates, fit_gyro, orientation_lag, RATE_GAP, SLOW_RATE, slow_spells, steady_accel)
from rot_tools.core.imu_mounting import HAND_EYE_STEP, imu_mounting, mounting_poses
from rot_tools.core.imu_samples import imu_samples, reference_samples, stamps_array
from rot_tools.core.so3 import matrix_to_quaternion
from rot_tools.core.stamps import stamp_steps
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
"""Angle between the orientation's up and the specific force beyond which it is a fault."""

OPPOSITE = math.radians(150)
"""An angle between two up directions beyond which they are opposite (a sign flipped, NED)."""

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

TURNS = 0.05
"""RMS (rad/s) of the orientation's rates about their mean at least, for the orientation to
turn clearly: a gyro must then follow it."""

FOLLOWS = 0.25
"""Share of the orientation's rate variance that the gyro explains at least (by any linear
map, whatever its units, axes and bias), for the gyro to follow the orientation."""

READING_SLACK = 1.5
"""A reading of the quaternion agrees with the gyro when what the gyro leaves of its rates is
at most this many times what the best reading leaves."""

AXES = 'xyz'

READINGS = ('as recorded', 'w-first', 'inverted')
"""How a quaternion's fields x, y, z, w may be read (read_quaternions)."""


def read_quaternions(quaternions, reading):
    """
    Return quaternions (N, 4) [x, y, z, w] as `reading` (one of READINGS) takes them.

    'as recorded': as given; 'w-first': the fields x, y, z, w hold w, x, y, z (Eigen's
    coeffs() against its constructor), so (x, y, z, w) = (y, z, w, x) of the fields;
    'inverted': the conjugate (x, y, z, w) → (−x, −y, −z, w), the world in the IMU frame.
    """
    q = np.asarray(quaternions, dtype=np.float64)
    if reading == 'as recorded':
        return q
    if reading == 'w-first':
        return q[..., [1, 2, 3, 0]]
    if reading == 'inverted':
        return q * [-1.0, -1.0, -1.0, 1.0]
    raise RotationError(f'reading must be one of {", ".join(READINGS)}, got {reading!r}')


# ---- the reference, the faults, the stamps ----------------------------------------------


class ImuReference(NamedTuple):
    """The body's orientation in its world: stamps (M,) s, quaternions (M, 4) [x, y, z, w]."""

    stamps: Any
    quaternions: Any


def faults(checks):
    """Return the names of the checks of an ImuChecks whose status is 'fault', in order."""
    return tuple(name for name, check in zip(checks._fields, checks) if check.status == 'fault')


def _status(fault):
    return 'fault' if fault else 'ok'


def _deg(angle):
    return f'{math.degrees(angle):.1f}°'


def _seconds(x):
    """Write a duration in ms under a second, else in s."""
    return f'{x * 1e3:.3g} ms' if abs(x) < 1 else f'{x:.4g} s'


def _check_stamps(stamps, samples):
    """Return the StampsCheck: steps as given (backwards), and in order (period, gap, jitter)."""
    backwards = int((stamps[1:] <= stamps[:-1]).sum())  # compared: a step may overflow
    steps = stamp_steps(samples.t)
    period, gap = steps.period, float(np.diff(samples.t).max())
    spread = ('equal steps' if steps.spread == 0
              else f'the steps spread {_seconds(steps.spread)}')
    rate = f'{len(stamps)} samples every {_seconds(period)} ({steps.rate:.4g} Hz, {spread})'
    faulty = []
    if backwards > (len(stamps) - 1) / 2:
        faulty.append(f'{backwards} of {len(stamps) - 1} steps go back or repeat a stamp: the '
                      "samples' order is not known")
    elif backwards:
        faulty.append(f'{backwards} step(s) go back or repeat a stamp')
    if gap > GAP_PERIODS * period:
        faulty.append(f'the longest gap, {gap:.6g} s, is {gap / period:.3g} periods '
                      f'(> {GAP_PERIODS})')
    message = (f'{rate}: ' + ' and '.join(faulty) if faulty else
               f'{rate}, increasing, the longest step {_seconds(gap)}')
    if steps.arrival_time:
        low, high = steps.modes
        message += (f'; the steps fall into two groups, {_seconds(low)} and {_seconds(high)}: '
                    'stamped as messages arrive rather than by the sensor, it seems')
    return StampsCheck(status=_status(bool(faulty)), message=message + '.', period=period,
                       gap=gap, backwards=backwards, spread=steps.spread, rate=steps.rate,
                       arrival_time=steps.arrival_time)


def _order_unknown(stamps):
    """Return '' when most steps of the stamps as given go forward, else why not."""
    backwards = int((stamps[1:] <= stamps[:-1]).sum())  # compared: a step may overflow
    if backwards <= (len(stamps) - 1) / 2:
        return ''
    return ("the stamps mostly go back, so the samples' order, which this check needs, is "
            'not known.')


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


def _tilt_angle(samples, slow, force):
    """Return the median angle (rad) of Rᵀ·ẑ (R's last row) and the specific force, slow."""
    return _median_angle(samples.R[slow][:, 2, :], force[slow])


def _orientation_vs_accel(angle):
    said = (f"the orientation's up and the accelerometer's are {_deg(angle)} apart when the "
            'body turns slowly')
    if angle <= ANGLE_TOL:
        return AngleCheck(status='ok', angle=angle, message=f'{said}.')
    if angle >= OPPOSITE:
        why = ('the accelerometer reads gravity instead of the specific force (sign '
               "flipped), or the orientation's world is NED (z down)")
    else:
        why = f"the orientation's tilt disagrees with the accelerometer's (> {_deg(ANGLE_TOL)})"
    return AngleCheck(status='fault', angle=angle, message=f'{said}: {why}.')


# ---- the gyro against the orientation -----------------------------------------------------


def _lag(samples):
    """Return the orientation's Lag (imu_motion) and why it is unknown ('' when known)."""
    try:
        lag = orientation_lag(samples)
    except RotationError as exc:
        return None, f'{exc}.'
    if not lag.correlation >= MIN_CORRELATION:
        return None, ('the angular speeds of the gyro and the orientation correlate at '
                      f'{lag.correlation:.2f} at best (< {MIN_CORRELATION:g}): too little '
                      'motion to align them.')
    return lag, ''


def _time_offset(samples, lag, why):
    """Return the TimeOffsetCheck of a lag (imu_motion.Lag) or why it is unknown."""
    if why:
        return unknown(TimeOffsetCheck, why)
    seconds, r = lag.seconds, lag.correlation
    periods = seconds / samples.period
    said = (f'the orientation lags the gyro by {_seconds(seconds)} ({periods:+.2f} periods; '
            f'the angular speeds correlate at {r:.3f})')
    if abs(periods) <= LAG_PERIODS:
        return TimeOffsetCheck(status='ok', seconds=seconds, message=f'{said}.')
    late = 'late' if seconds > 0 else 'early'
    return TimeOffsetCheck(status='fault', seconds=seconds, message=(
        f'{said}: the orientation is {late} by more than {LAG_PERIODS} periods.'))


def _gyro_fit(samples):
    """Return the Lag, why it is unknown, and the GyroFit of the rates (taken 0 s apart then)."""
    lag, why = _lag(samples)
    return lag, why, fit_gyro(body_rates(samples, 0.0 if why else lag.seconds))


def _dead(fit):
    """Return whether the orientation turns clearly and the gyro does not follow it at all."""
    return bool(fit.scale is None and fit.explained is not None and fit.spread >= TURNS
                and fit.explained < FOLLOWS)


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


def _negate(matrix):
    """Return the gyro axis whose negation turns a mirror M into the rotation nearest I."""
    M = np.array(matrix, dtype=float)
    return max(AXES, key=lambda a: np.trace(M * np.where(np.arange(3) == AXES.index(a), -1, 1)))


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
        mirror = bool(round(np.linalg.det(matrix)) < 0)
        negate = _negate(matrix) if mirror else None
        if not wrong:
            message = "each gyro axis reads the orientation's rate about the same axis."
        elif mirror:
            turned = {i: (j, -s if AXES[j] == negate else s) for i, (j, s) in fit.rows.items()}
            rest = [i for i in range(3) if turned[i] != (i, 1)]
            message = (f'a mirror: {_axis_map(fit.rows, wrong)}, a left-handed frame that no '
                       f"turn of the IMU gives: the gyro's {negate} is negated" + (
                           f'; with it negated, {_axis_map(turned, rest)} (a turn of the '
                           'frame).' if rest else '.'))
        else:
            message = (f'swapped or negated axes (a turn of the frame): '
                       f'{_axis_map(fit.rows, wrong)}.')
        return GyroAxesCheck(status=_status(bool(wrong)), matrix=matrix, mirror=mirror,
                             negate=negate, message=message)
    if wrong:
        return GyroAxesCheck(status='fault', matrix=None, mirror=None, negate=None, message=(
            f'swapped or negated axes: {_axis_map(fit.rows, wrong)}; {unfixed}.'))
    return GyroAxesCheck(status='unknown', matrix=None, mirror=None, negate=None, message=(
        f"{', '.join(AXES[i] for i in fixed)} as the orientation's; {unfixed}."))


def _gyro_bias(fit):
    if fit.bias is None:
        left = ', '.join(AXES[i] for i in range(3) if i not in fit.rows)
        return unknown(GyroBiasCheck, f'the orientation turns about {left}, which the '
                       'motion does not fix on the gyro, so the bias is not known.')
    norm = float(np.linalg.norm(fit.bias))
    said = (f'the gyro reads ({", ".join(f"{b:.2g}" for b in fit.bias)}) rad/s more than '
            f'the orientation turns (norm {norm:.2g} rad/s)')
    over = norm > BIAS_TOL
    return GyroBiasCheck(status=_status(over), bias=tuple(map(float, fit.bias)), message=(
        f'{said}: more than {BIAS_TOL:g} rad/s.' if over else f'{said}.'))


def _gyro_checks(samples, doubt):
    """
    Return the TimeOffsetCheck, GyroUnitsCheck, GyroAxesCheck and GyroBiasCheck.

    doubt: why the order or the orientation's reading is not known, or ''.
    """
    why = ('no orientation to compare the gyro with.' if samples.R is None else doubt)
    if why:
        return (unknown(TimeOffsetCheck, why), unknown(GyroUnitsCheck, why),
                unknown(GyroAxesCheck, why), unknown(GyroBiasCheck, why))
    lag, lag_unknown, fit = _gyro_fit(samples)
    if _dead(fit):
        why = 'the gyro does not follow the orientation, so this is not known.'
        dead = GyroUnitsCheck(status='fault', scale=None, message=(
            f'the orientation turns clearly (its rates vary by {fit.spread:.2g} rad/s RMS) '
            'but the gyro does not follow it: any map of its readings explains '
            f'{fit.explained:.0%} of those rates (a dead, constant, noisy or shuffled gyro).'))
        return (unknown(TimeOffsetCheck, why), dead, unknown(GyroAxesCheck, why),
                unknown(GyroBiasCheck, why))
    offset = _time_offset(samples, lag, lag_unknown)
    if fit.scale is None:
        why = ("the orientation's rates fix no gyro axis (too little turn, or rates that do "
               'not match).')
        return (offset, unknown(GyroUnitsCheck, why), unknown(GyroAxesCheck, why),
                unknown(GyroBiasCheck, why))
    return offset, _gyro_units(fit), _gyro_axes(fit), _gyro_bias(fit)


# ---- the quaternion's reading --------------------------------------------------------------


class _Reading(NamedTuple):
    """
    One reading's agreement with the sensors, each None where they cannot tell.

    angle (rad) from the accelerometer; residual: what the gyro leaves of the orientation's
    rates (rad/s RMS), whatever its units, axes and bias; plain: the gyro's axes are the
    orientation's on every axis the motion fixes.
    """

    angle: Any
    residual: Any
    plain: Any


def _reading(samples):
    """Return the _Reading of samples whose orientation is read one way."""
    slow, force = slow_spells(samples), steady_accel(samples)
    angle = None
    if not _too_few_slow(samples, slow) and not _no_gravity(force[slow]):
        angle = _tilt_angle(samples, slow, force)
    fit = _gyro_fit(samples)[2]
    if fit.scale is None:
        return _Reading(angle=angle, residual=None, plain=None)
    plain = bool(fit.rows) and all(fit.rows[i] == (i, 1) for i in fit.rows)
    return _Reading(angle=angle, residual=fit.residual, plain=plain)


def _said(found):
    """Write one reading's agreement (a _Reading) in words."""
    accel = ('the accelerometer cannot tell' if found.angle is None
             else f'{_deg(found.angle)} from the accelerometer')
    gyro = ('the gyro cannot tell' if found.residual is None
            else f'the gyro differs by {found.residual:.2g} rad/s RMS')
    return f'{accel}, {gyro}'


def _choose_reading(found):
    """
    Return the QuaternionCheck of the readings' agreement {reading: _Reading}, and a doubt.

    The doubt: why the checks that take the orientation are unknown ('' when they are not).

    A reading agrees with the accelerometer within ANGLE_TOL and with the gyro within
    READING_SLACK of the best reading's residual. Of the readings that agree with both, the
    one that needs the fewest faults (a reading other than as recorded, gyro axes other than
    the orientation's) is chosen; a tie leaves the reading unknown. Where no reading agrees
    with both, it is as recorded, unknown, and in doubt when the gyro follows another
    reading better.
    """
    residuals = [f.residual for f in found.values() if f.residual is not None]
    best = min(residuals) if residuals else None

    def gyro_agrees(f):
        return f.residual is not None and f.residual <= READING_SLACK * best

    def faults_needed(name):
        return (name != 'as recorded') + (not found[name].plain)

    said = '; '.join(f'{n}: {_said(f)}' for n, f in found.items())
    both = [n for n, f in found.items()
            if f.angle is not None and f.angle <= ANGLE_TOL and gyro_agrees(f)]
    least = min(map(faults_needed, both), default=None)
    chosen = [n for n in both if faults_needed(n) == least]
    recorded = found['as recorded']
    if len(chosen) == 1 and chosen[0] == 'as recorded':
        return QuaternionCheck(status='ok', reading='as recorded', message=(
            'as recorded: the orientation agrees with the accelerometer '
            f'({_deg(recorded.angle)}) and the gyro follows it ({recorded.residual:.2g} rad/s '
            'RMS).')), ''
    if len(chosen) == 1:
        name = chosen[0]
        what = ('written w-first: its fields x, y, z, w hold w, x, y, z' if name == 'w-first'
                else 'inverted: it gives the world in the IMU frame, not the IMU frame in the '
                'world')
        return QuaternionCheck(status='fault', reading=name, message=(
            f'{what}; read so, the orientation agrees with the accelerometer '
            f'({_deg(found[name].angle)}) and the gyro follows it ({found[name].residual:.2g} '
            f'rad/s RMS); read as recorded, {_said(recorded)}; the other checks take it so '
            'read.')), ''
    if chosen:
        why = f'{" and ".join(chosen)} agree with both the gyro and the accelerometer alike'
    elif recorded.angle is None or best is None:
        why = f'the {"accelerometer" if recorded.angle is None else "gyro"} cannot tell'
    else:
        why = 'no reading makes it agree with both the gyro and the accelerometer'
    check = QuaternionCheck(status='unknown', reading='as recorded', message=(
        f'read as recorded; {why} ({said}).'))
    rivals = [n for n in READINGS[1:] if gyro_agrees(found[n]) and (
        not gyro_agrees(recorded) or found[n].plain and not recorded.plain)]
    if len(chosen) > 1:
        return check, (f"the quaternion's reading is not known ({' or '.join(chosen)} agree "
                       'alike), so neither is this.')
    if not chosen and rivals:
        return check, ("the quaternion's reading is not known, and the gyro follows it better "
                       f"read {' or '.join(rivals)}, so neither is this.")
    return check, ''


def _quaternion(stamps, quaternions, arrays, samples, unordered):
    """
    Return the QuaternionCheck, the samples with the orientation read as it says, a doubt.

    The doubt: why the checks that take the orientation are unknown ('' when they are not).
    """
    if samples.R is None:
        return unknown(QuaternionCheck, 'no orientation.'), samples, ''
    if unordered:
        return QuaternionCheck(status='unknown', reading='as recorded', message=(
            f'read as recorded; {unordered}')), samples, unordered
    read = {name: samples if name == 'as recorded' else
            imu_samples(stamps, read_quaternions(quaternions, name), *arrays)
            for name in READINGS}
    check, doubt = _choose_reading({name: _reading(s) for name, s in read.items()})
    return check, read[check.reading], doubt


# ---- against a reference -------------------------------------------------------------------


def _mounting(samples, ref_t, ref_Q, ref_period, lag):
    """Return the MountingCheck, and the Mounting (None where unknown)."""
    count = len(mounting_poses(samples, ref_t))
    if count < 3:
        return unknown(MountingCheck, f'the reference covers {count} of the IMU’s steps of '
                       f'{HAND_EYE_STEP:g} s: too few for a mounting.'), None
    try:
        found = imu_mounting(samples, ref_t, ref_Q, ref_period, lag)
    except RotationError as exc:
        return unknown(MountingCheck, f'no mounting: {exc}.'), None
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
        return unknown(AngleCheck, f'{why} where the reference covers them.')
    # Xᵀ·Q_kᵀ·ẑ: the body's up in the IMU frame
    angle = _median_angle(ref_Q[near.index, 2, :] @ X, force[inside])
    said = (f'the specific force is {_deg(angle)} from the up that the reference gives through '
            'the mounting')
    if angle <= math.pi / 2:
        return AngleCheck(status='ok', angle=angle, message=f'{said}.')
    if angle < OPPOSITE:
        return AngleCheck(status='unknown', angle=angle, message=(
            f'{said}: neither along it nor opposite.'))
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
    if angle < OPPOSITE:
        return AngleCheck(status='unknown', angle=angle, message=(
            f'{said}: neither up nor down.'))
    return AngleCheck(status='fault', angle=angle, message=(
        f'{said}: it points down, the orientation is NED (REP-103 wants ENU).'))


def _reference_checks(samples, slow, force, reference, tol, lag, flat, doubt):
    """Return the accel_sign, world_up and mounting checks (lag: the orientation's, s)."""
    why = 'no reference orientation to compare with.' if reference is None else doubt
    if why:
        return (unknown(AngleCheck, why), unknown(AngleCheck, why),
                unknown(MountingCheck, why))
    ref_t, ref_Q, ref_period = reference_samples(reference, tol)
    mounting, found = _mounting(samples, ref_t, ref_Q, ref_period, lag)
    if found is None:
        why = 'no mounting, so no physical up in the IMU frame.'
        return unknown(AngleCheck, why), unknown(AngleCheck, why), mounting
    sign = (unknown(AngleCheck, flat) if flat
            else _accel_sign(samples, slow, force, ref_t, ref_Q, ref_period, found.X))
    up = (unknown(AngleCheck, 'no orientation.') if samples.R is None
          else _world_up(found))
    return sign, up, mounting


# ---- all together ------------------------------------------------------------------------


def check_imu(stamps, quaternions, angular_velocity, linear_acceleration, reference=None, *,
              tol=None):
    """
    Check an IMU's samples against ROS's conventions (REP-103, REP-145): return ImuChecks.

    stamps (N,) s, N ≥ 10, in any order (the stamps check says where they do not increase;
    the other checks take the samples in order, each stamp once, and those that need the
    order are unknown when most steps go back); quaternions (N, 4) [x, y, z, w], or None for
    an IMU without orientation (all zeros count as None); angular_velocity (N, 3) rad/s;
    linear_acceleration (N, 3) m/s²; reference None or ImuReference(stamps (M,),
    quaternions (M, 4)), the orientation of the body that carries the IMU in its world
    (odometry, a pose, TF). tol: None takes any non-zero quaternion as its normalised self;
    a number refuses ||q| − 1| > tol. The quaternion is tried three ways first
    (QuaternionCheck); the other checks take it as that check reads it. RotationError
    (imu_samples) for a shape, NaN or Inf, a reading beyond 1e9, a zero or non-unit
    quaternion, fewer than 10 distinct stamps, steps under a nanosecond.
    """
    given = stamps_array(stamps, 'stamps')
    arrays = (angular_velocity, linear_acceleration, tol)
    samples = imu_samples(given, quaternions, *arrays)
    quaternion, samples, doubt = _quaternion(given, quaternions, arrays, samples,
                                             _order_unknown(given))
    slow, force = slow_spells(samples), steady_accel(samples)
    why = _too_few_slow(samples, slow)
    flat = '' if why else _no_gravity(force[slow])
    if why:
        units, tilt = unknown(AccelUnitsCheck, f'{why}.'), unknown(AngleCheck, f'{why}.')
    else:
        units = _accel_units(force[slow])
        tilt = (unknown(AngleCheck, 'no orientation.') if samples.R is None
                else unknown(AngleCheck, flat or doubt) if flat or doubt
                else _orientation_vs_accel(_tilt_angle(samples, slow, force)))
    offset, gyro_units, gyro_axes, gyro_bias = _gyro_checks(samples, doubt)
    lag = offset.seconds if offset.status != 'unknown' else 0.0
    sign, up, mounting = _reference_checks(samples, slow, force, reference, tol, lag, flat,
                                           doubt)
    return ImuChecks(quaternion=quaternion, stamps=_check_stamps(given, samples),
                     accel_units=units, orientation_vs_accel=tilt, gyro_units=gyro_units,
                     gyro_axes=gyro_axes, gyro_bias=gyro_bias, time_offset=offset,
                     accel_sign=sign, world_up=up, mounting=mounting)
