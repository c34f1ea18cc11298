"""
An IMU's samples and a reference orientation, checked and put in time order for check_imu.

Samples are sorted by stamp, each stamp kept once (the first); quaternions [x, y, z, w] become
rotation matrices; all of them zero means no orientation.
"""

from typing import Any, NamedTuple

import numpy as np
from rot_tools.core._arrays import finite_array
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import quaternion_to_matrix
from rot_tools.core.stamps import stamp_steps

MIN_SAMPLES = 10
"""Samples (distinct stamps) at least, of the IMU and of a reference."""


MAX_READING = 1e9
"""|angular_velocity| and |linear_acceleration| entries at most: beyond, no sensor's reading
(and sums of their squares would leave float64)."""


class ImuSamples(NamedTuple):
    """Samples in time order, each stamp once: t (N,), R (N, 3, 3) or None, gyro, accel (N, 3)."""

    t: np.ndarray
    R: Any
    gyro: np.ndarray
    accel: np.ndarray
    period: float


class ReferenceSamples(NamedTuple):
    """A reference in time order, each stamp once: t (M,), Q (M, 3, 3), its median period."""

    t: np.ndarray
    Q: np.ndarray
    period: float


def _vectors(x, name, count):
    """Return x (count, 3), finite, within MAX_READING."""
    x = finite_array(x, (3,), name)
    if x.shape != (count, 3):
        raise RotationError(f'{name} must have shape ({count}, 3), one per stamp, got '
                            f'{x.shape}')
    big = np.abs(x) > MAX_READING
    if big.any():
        k, i = (int(j) for j in np.argwhere(big)[0])
        raise RotationError(f'{name}[{k}] reads {float(x[k, i]):.3g}: beyond {MAX_READING:g}, '
                            f'no sensor reads that ({int(big.sum())} such entries)')
    return x


def _orientation(q, name, count, tol):
    """Return the rotations (count, 3, 3) of quaternions (count, 4), None when every q is 0."""
    q = finite_array(q, (4,), name)
    if q.shape != (count, 4):
        raise RotationError(f'{name} must have shape ({count}, 4), one per stamp, got '
                            f'{q.shape}')
    zero = ~q.any(axis=1)
    if zero.all():
        return None
    if zero.any():
        k = int(np.argmax(zero))
        raise RotationError(f'{name}[{k}] is (0, 0, 0, 0) but {int((~zero).sum())} of {count} '
                            'are not: give None for an IMU without orientation')
    try:
        return quaternion_to_matrix(q, tol=tol)
    except RotationError as exc:
        raise RotationError(f'{name}: {exc}') from None


def stamps_array(stamps, name):
    """Return stamps (N,) as float64, finite, N ≥ MIN_SAMPLES (in any order)."""
    t = finite_array(stamps, (), name)
    if t.ndim != 1:
        raise RotationError(f'{name} must have shape (N,), got {t.shape}')
    if len(t) < MIN_SAMPLES:
        raise RotationError(f'{name} has {len(t)} sample(s): at least {MIN_SAMPLES} needed')
    return t


def _period(t, name):
    """Return the median step of stamps t in order (s), or RotationError naming them."""
    try:
        return stamp_steps(t).period
    except RotationError as exc:
        raise RotationError(f'{name}: {exc}') from None


def _in_order(t, name):
    """Return the indices that put t in order, each stamp once (the first of equal ones)."""
    order = np.argsort(t, kind='stable')
    keep = np.concatenate([[True], t[order][1:] > t[order][:-1]])
    if keep.sum() < MIN_SAMPLES:
        raise RotationError(f'{name} has {int(keep.sum())} distinct stamp(s): at least '
                            f'{MIN_SAMPLES} needed')
    return order[keep]


def imu_samples(t, quaternions, angular_velocity, linear_acceleration, tol):
    """
    Return the ImuSamples of stamps t (from stamps_array) and the arrays of check_imu.

    RotationError for a shape, a NaN or Inf, a reading beyond MAX_READING, a zero or (tol a
    number) non-unit quaternion, fewer than MIN_SAMPLES distinct stamps, steps under a
    nanosecond at the median or beyond float64.
    """
    count = len(t)
    gyro = _vectors(angular_velocity, 'angular_velocity', count)
    accel = _vectors(linear_acceleration, 'linear_acceleration', count)
    R = None if quaternions is None else _orientation(quaternions, 'quaternions', count, tol)
    if not (t[1:] > t[:-1]).all():  # compared, not subtracted: a step may overflow
        keep = _in_order(t, 'stamps')
        t, gyro, accel, R = t[keep], gyro[keep], accel[keep], None if R is None else R[keep]
    return ImuSamples(t=t, R=R, gyro=gyro, accel=accel, period=_period(t, 'stamps'))


def reference_samples(reference, tol):
    """Return the ReferenceSamples of an ImuReference(stamps, quaternions), or RotationError."""
    try:
        stamps, quaternions = reference
    except (TypeError, ValueError):
        raise RotationError('reference must be ImuReference(stamps, quaternions), got '
                            f'{type(reference).__name__}') from None
    t = stamps_array(stamps, 'reference.stamps')
    Q = _orientation(quaternions, 'reference.quaternions', len(t), tol)
    if Q is None:
        raise RotationError('reference.quaternions are all (0, 0, 0, 0): no orientation')
    keep = _in_order(t, 'reference.stamps')
    t = t[keep]
    return ReferenceSamples(t=t, Q=Q[keep], period=_period(t, 'reference.stamps'))
