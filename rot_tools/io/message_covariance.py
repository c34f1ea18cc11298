"""
A message's covariance as roll, pitch, yaw (rotation_node's ~/rpy_covariance, rot-tools bag).

ROS's conventions are read here. A covariance all of whose entries are zero is unknown
(sensor_msgs/Imu and geometry_msgs/PoseWithCovariance: "all zeros ... covariance unknown"):
reported as unknown, never as 0. An Imu whose orientation_covariance[0] is −1 has no
orientation at all and is refused before (rot_tools.io.boundary). The rotation block is read
as geometry_msgs/PoseWithCovariance documents it, rotations about the parent's fixed X, Y, Z
(``reading='rotvec'``: a small rotation vector in the parent frame), or as the covariance of
roll, pitch, yaw (``reading='rpy'``), as some drivers and filters write it. Roll, pitch, yaw
are the Euler angles of rot_tools.core.euler.RPY_SEQUENCE (REP 103: about the fixed x, y, z
axes), as rotation_node's ~/rpy.
"""

import numpy as np
from rot_tools.core.covariance import covariance_defects, rotvec_covariance_to_euler
from rot_tools.core.covariance import validate_covariance
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import RPY_SEQUENCE

READINGS = ('rotvec', 'rpy')
"""How a message's rotation covariance is read: a rotation vector about the parent's fixed
axes (ROS's PoseWithCovariance), or roll, pitch, yaw."""

OK, UNKNOWN, BAD, LOCK = 0, 1, 2, 3
"""Status codes of :func:`rpy_covariances`: converted; all zeros (unknown); not finite,
symmetric or PSD, or converted beyond float64; within GIMBAL_LOCK_TOL of pitch ±π/2 (no
roll/pitch/yaw covariance)."""


def square(cov):
    """Return cov (..., 9) or (..., 36), row-major, as (..., 3, 3) or (..., 6, 6) float64."""
    cov = np.asarray(cov, dtype=np.float64)
    n = 3 if cov.shape[-1] == 9 else 6
    return cov.reshape(cov.shape[:-1] + (n, n))


def rpy_covariances(R, cov, reading='rotvec'):
    """
    Return (C, status): each item's covariance of (roll, pitch, yaw), rad², and its status.

    R (N, 3, 3) rotations; cov (N, 9) (an Imu's orientation_covariance) or (N, 36) (a
    PoseWithCovariance's, x, y, z, rx, ry, rz), row-major. For ``reading='rotvec'``
    C = diag(I, E⁻¹)·Σ·diag(I, E⁻¹)ᵀ with E the Euler-rate matrix of RPY_SEQUENCE in the parent
    frame (rot_tools.core.covariance.rotvec_covariance_to_euler): a pose's position block
    kept, its cross terms carried through the same Jacobian; for 'rpy' C is Σ. C is
    (N, 3, 3) or (N, 6, 6), NaN where status (N,) is not OK (see the status codes).
    """
    if reading not in READINGS:
        raise RotationError(f'reading must be one of {READINGS}, got {reading!r}')
    C = square(cov)
    finite = np.isfinite(C).all(axis=(-2, -1))
    C = np.where(finite[..., None, None], C, 0.0)
    asymmetry, negativity, bound = covariance_defects(C)
    status = np.where(~finite | (asymmetry > bound) | (negativity > bound), BAD, OK)
    status = np.where(finite & ~C.any(axis=(-2, -1)), UNKNOWN, status).astype(np.int8)
    ok = status == OK
    out = np.full(C.shape, np.nan)
    if reading == 'rpy':  # its symmetric part (C + Cᵀ overflows near 1e308; 0.5·5e-324 is 0)
        Ct = np.swapaxes(C[ok], -1, -2)
        out[ok] = np.where(C[ok] == Ct, C[ok], 0.5 * C[ok] + 0.5 * Ct)
    else:  # linear in C: converted at the scale of 1, then each item's beyond float64 is BAD
        scale = np.abs(C[ok]).max(axis=(-2, -1))[:, None, None]  # > 0: all zeros is UNKNOWN
        unit, lock = rotvec_covariance_to_euler(np.asarray(R)[ok], C[ok] / scale, RPY_SEQUENCE,
                                                'parent')
        with np.errstate(over='ignore'):
            converted = unit * scale
        fits = np.isfinite(converted).all(axis=(-2, -1))
        out[ok] = np.where(fits[:, None, None], converted, np.nan)
        status[np.flatnonzero(ok)[lock]] = LOCK
        status[np.flatnonzero(ok)[~fits & ~lock]] = BAD
    return out, status


OVERFLOW = 'its covariance of roll, pitch, yaw overflows float64 (beyond ±1.8e308)'
"""Why a valid covariance is BAD: what rpy_covariances makes of it is too large."""


def fault(cov):
    """
    Say why one BAD covariance (9 or 36 numbers) is (its RotationError's text).

    A valid one is BAD when its roll, pitch, yaw covariance overflows float64 (OVERFLOW).
    """
    C = square(cov)
    try:
        validate_covariance(C, C.shape[-1], 'covariance')
    except RotationError as exc:
        return str(exc)
    return f'covariance: {OVERFLOW}'


NEAR_LOCK_SIGMAS = 3.0
"""A covariance of Euler angles is near gimbal lock when the lock lies within this many of the
middle angle's standard deviations: a first-order covariance assumes errors small against
the distance to the lock, and the other two angles' variances grow as 1/distance² there."""


def near_lock_note(distance, sigma, angle='pitch', lock='±90°'):
    """
    Return a note on a covariance of Euler angles near gimbal lock, or '' when it is not.

    ``distance``: the middle angle's from the lock (rad,
    rot_tools.core.covariance.gimbal_lock_distance); ``sigma``: its standard deviation (rad).
    Near is within NEAR_LOCK_SIGMAS standard deviations.
    """
    if not distance < NEAR_LOCK_SIGMAS * sigma:
        return ''
    return (f'{angle} is {distance:.2g} rad from gimbal lock ({angle} = {lock}), within '
            f'{NEAR_LOCK_SIGMAS:g} of its standard deviations ({sigma:.2g} rad): the other two '
            "angles' standard deviations grow as 1/distance there and, to first order, mean "
            'little')


def stddev_correlation(C):
    """
    Return (standard deviations (..., 3), correlation (..., 3, 3)) of C (..., 3, 3).

    σ_i = √C_ii; ρ_ij = C_ij/(σ_i·σ_j), with ρ_ii = 1 and ρ_ij = 0 where σ_i or σ_j is 0.
    """
    C = np.asarray(C, dtype=np.float64)
    s = np.sqrt(np.maximum(np.diagonal(C, axis1=-2, axis2=-1), 0.0))
    outer = s[..., :, None] * s[..., None, :]
    rho = np.where(outer > 0, C / np.where(outer > 0, outer, 1.0), 0.0)
    rho[..., np.arange(3), np.arange(3)] = 1.0
    return s, rho
