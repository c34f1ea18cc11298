"""
The results of check_imu: one NamedTuple per check, (status, message, its numbers), in ImuChecks.

A status is 'ok', 'fault' or 'unknown' (where the data cannot tell: its numbers are None then);
angles in radians, rates in rad/s, times in seconds, scales as plain factors. The tolerances
named here are rot_tools.core.imu's.
"""

from typing import Any, NamedTuple


class QuaternionCheck(NamedTuple):
    """
    reading: how the orientation's quaternion is read ('as recorded', 'w-first', 'inverted').

    Tried three ways (READINGS), a reading other than as recorded is a fault when the
    orientation, read so, agrees with both the gyro and the accelerometer where read as
    recorded it does not; the other checks then take the orientation so read. None where
    there is no orientation.
    """

    status: str
    message: str
    reading: Any


class StampsCheck(NamedTuple):
    """
    Stamps: increasing, no gap longer than GAP_PERIODS periods; their steps' jitter.

    period: the median step (s); gap: the longest step (s); backwards: steps ≤ 0 as given;
    spread: the steps' scatter (s, stamps.StampSteps); rate: 1/period (Hz); arrival_time:
    the steps fall into two groups (stamped on arrival suspected; not a fault).
    """

    status: str
    message: str
    period: Any
    gap: Any
    backwards: int
    spread: Any
    rate: Any
    arrival_time: bool


class AccelUnitsCheck(NamedTuple):
    """
    scale: the factor that makes |linear_acceleration| read 9.80665 m/s² in slow spells.

    9.80665 over the median |ā_k| in slow spells (imu_motion.slow_spells; ā_k the
    accelerometer averaged over the slow window); fault beyond ACCEL_TOL (g instead of m/s²,
    gravity removed).
    """

    status: str
    message: str
    scale: Any


class AngleCheck(NamedTuple):
    """
    angle (rad) between two directions that should agree.

    orientation_vs_accel: the orientation's up in the IMU frame, Rᵀ·ẑ, against the specific
    force in slow spells (their median angle: a tilt shows at every attitude); fault beyond
    ANGLE_TOL, beyond OPPOSITE a sign flipped or NED. accel_sign: the body's up that the
    reference gives through the mounting against the specific force; fault beyond OPPOSITE.
    world_up: the orientation's world z in the reference's world against ẑ; fault beyond
    OPPOSITE (NED). Between 90° and OPPOSITE neither is told: unknown.
    """

    status: str
    message: str
    angle: Any


class GyroUnitsCheck(NamedTuple):
    """
    scale: ω_orientation ≈ scale·M·(ω_measured − bias) (imu_motion.fit_gyro).

    Fault beyond GYRO_TOL (degrees/s), and where the orientation turns clearly but the gyro
    does not follow it (reads zeros, a constant, noise): scale None then.
    """

    status: str
    message: str
    scale: Any


class GyroAxesCheck(NamedTuple):
    """
    matrix: the signed permutation M (3 rows of 3 ints), None unless every row is fixed.

    Fault where M ≠ I on the axes the motion fixes. mirror: det M = −1 (one axis negated, a
    left-handed frame: no turn of the IMU gives it), None where M is not known; negate: the
    gyro axis ('x', 'y' or 'z') whose negation leaves a turn of the frame, the one closest to
    the identity, or None.
    """

    status: str
    message: str
    matrix: Any
    mirror: Any
    negate: Any


class GyroBiasCheck(NamedTuple):
    """bias: the gyro's reading at rest (3 floats, rad/s, its own axes); fault beyond BIAS_TOL."""

    status: str
    message: str
    bias: Any


class TimeOffsetCheck(NamedTuple):
    """
    seconds: how much the orientation lags the gyro (positive: the orientation is late).

    From the angular speeds (imu_motion.orientation_lag); fault beyond LAG_PERIODS periods.
    """

    status: str
    message: str
    seconds: Any


class MountingCheck(NamedTuple):
    """
    quaternion [x, y, z, w] of the IMU frame in the body frame; warning: '' or why not whole.

    From the relative rotations of the reference and of the orientation (imu_mounting), as a
    static transform base_link → imu_link gives it.
    """

    status: str
    message: str
    quaternion: Any
    warning: str


class ImuChecks(NamedTuple):
    """Every check of check_imu, each a NamedTuple (status, message, its numbers)."""

    quaternion: QuaternionCheck
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


def unknown(kind, message):
    """Return a check of the NamedTuple class kind, status 'unknown', its numbers None."""
    extra = {'warning': ''} if kind is MountingCheck else {}
    numbers = {f: None for f in kind._fields[2:] if f not in extra}
    return kind(status='unknown', message=message, **numbers, **extra)
