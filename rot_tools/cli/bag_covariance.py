"""
``rot-tools bag``: each recorded covariance as standard deviations of roll, pitch and yaw.

Each accepted message's orientation covariance (an Imu's, a PoseWithCovarianceStamped's, an
Odometry's) is read as rotation_node reads it (rot_tools.io.message_covariance) and carried
to roll, pitch and yaw; runs of identical covariances are converted once, as one batch.
"""

from typing import NamedTuple

import numpy as np
from rot_tools.core.covariance import rotvec_covariance_to_euler
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.io import message_covariance
from rot_tools.io.message_covariance import BAD, LOCK, OK, UNKNOWN

GROUPS = 64
"""Most runs of identical covariances converted run by run (more: all in one batch)."""

COUNTS = (('good', OK), ('unknown', UNKNOWN), ('bad', BAD), ('gimbal_lock', LOCK))
"""The summary's counts of covariances, by status (rot_tools.io.message_covariance)."""

RPY_NAMES = ('roll', 'pitch', 'yaw')


def _sigma(C):
    """Return the standard deviations (..., 3) of the roll/pitch/yaw block: C's last 3×3."""
    return message_covariance.stddev_correlation(C[..., -3:, -3:])[0]


def _euler_block(R, C):
    """
    Return the ConvertedCovariance of one good covariance C at rotations R (n, 3, 3).

    cov: Σ of roll, pitch, yaw (n, 3, 3); degenerate (n,): at gimbal lock.

    Only the rotation block is converted (the diagonal needs nothing else); a block that fails
    the check on its own — its tolerance is relative to its own largest entry, the whole
    matrix's may be far larger (position variances of 10⁶ m²) — goes with the whole matrix,
    as message_covariance converts it.
    """
    try:
        return rotvec_covariance_to_euler(R, C[-3:, -3:], RPY_SEQUENCE, 'parent')
    except RotationError:
        whole = rotvec_covariance_to_euler(R, C, RPY_SEQUENCE, 'parent')
        return whole._replace(cov=whole.cov[:, -3:, -3:])


class Stddevs(NamedTuple):
    """The standard deviations of N messages' roll, pitch, yaw, and their covariances' status."""

    sigma: np.ndarray
    """(N, 3), rad; NaN where the status is not OK."""
    status: np.ndarray
    """(N,) int8: rot_tools.io.message_covariance's OK, UNKNOWN, BAD or LOCK."""


def _unit(cov):
    """
    Return (cov / s, s) per message, s = max|C| (1 where C is all zeros or not finite).

    A covariance is linear in C, a standard deviation goes as √C: each is converted at the
    scale of 1 and σ is σ(C / s)·√s, so that entries near float64's largest (1e308) or
    smallest (5e-324) neither overflow nor lose their digits on the way. The check of C
    (symmetric, PSD) is relative to s: the same on C / s.
    """
    with np.errstate(invalid='ignore'):
        scale = np.abs(cov).max(axis=1)
    scale = np.where(np.isfinite(scale) & (scale > 0), scale, 1.0)
    return cov / scale[:, None], scale


def _at_scale(C, scale, status):
    """
    Return Stddevs of covariances of roll, pitch, yaw C (n, k, k) converted at the scale of 1.

    σ = σ(C)·√scale (n,); where status is OK but the covariance C·scale is beyond float64
    (its diagonal: no other entry of a covariance is larger), the status becomes BAD, as
    rot_tools.io.message_covariance says of it, and σ NaN.
    """
    with np.errstate(over='ignore', invalid='ignore'):
        fits = np.isfinite(np.diagonal(C, axis1=-2, axis2=-1) * scale[:, None]).all(axis=1)
    status = np.where((status == OK) & ~fits, BAD, status).astype(np.int8)
    sigma = _sigma(C) * np.sqrt(scale)[:, None]
    return Stddevs(np.where((status == OK)[:, None], sigma, np.nan), status)


def stddevs(R, cov, reading='rotvec'):
    """
    Return Stddevs (σ (N, 3) of roll, pitch, yaw in rad, status (N,) int8) of N messages.

    R (N, 3, 3) their rotations; cov (N, 9) or (N, 36) their covariances, row-major
    (rot_tools.io.message_covariance.rpy_covariances: the same status codes, a covariance of
    roll, pitch, yaw beyond float64 BAD; each converted at the scale of 1, :func:`_unit`);
    σ is NaN where the status is not OK.
    """
    R = np.asarray(R, dtype=np.float64).reshape(-1, 3, 3)
    cov = np.ascontiguousarray(cov, dtype=np.float64)
    n = len(cov)
    if not n:
        return Stddevs(np.zeros((0, 3)), np.zeros(0, np.int8))
    unit, scale = _unit(cov)
    bits = cov.view(np.int64)  # bit for bit: a run of NaN is one run too
    starts = np.flatnonzero(np.append(True, (bits[1:] != bits[:-1]).any(axis=1)))
    if len(starts) > GROUPS:
        C, status = message_covariance.rpy_covariances(R, unit, reading)
        return _at_scale(C[..., -3:, -3:], scale, status)
    C, status = np.full((n, 3, 3), np.nan), np.empty(n, np.int8)
    # each run's covariance alone: reading 'rpy' converts nothing, it only checks
    _, checked = message_covariance.rpy_covariances(
        np.broadcast_to(np.eye(3), (len(starts), 3, 3)), unit[starts], 'rpy')
    for start, end, code in zip(starts, np.append(starts[1:], n), checked):
        status[start:end] = code
        if code != OK:
            continue
        block = message_covariance.square(unit[start])
        if reading == 'rpy':
            C[start:end] = block[-3:, -3:]
            continue
        converted = _euler_block(R[start:end], block)
        C[start:end] = converted.cov[:, -3:, -3:]
        status[start:end][converted.degenerate] = LOCK
    return _at_scale(C, scale, status)


def summary(sigma, status, cov, reading, degrees):
    """
    Return a topic's summary of its covariances: counts, median σ, the first bad one's fault.

    ``covariances``: how they were read and how many were good, unknown (all zeros), bad (not
    a covariance: the first one's defect is ``first_bad_covariance``) or at gimbal lock;
    ``rpy_stddev_median``: the median σ of roll, pitch, yaw over the good ones (degrees when
    ``degrees``), or ``unknown`` when none is.
    """
    counts = np.bincount(status, minlength=len(COUNTS))
    out = {'covariances': {'reading': reading,
                           **{name: int(counts[code]) for name, code in COUNTS}}}
    good = sigma[status == OK]
    if len(good):
        median = np.median(np.degrees(good) if degrees else good, axis=0)
        out['rpy_stddev_median'] = dict(zip(RPY_NAMES, map(float, median)))
    else:
        out['rpy_stddev_median'] = 'unknown'
    bad = np.flatnonzero(status == BAD)
    if len(bad):
        out['first_bad_covariance'] = message_covariance.fault(cov[bad[0]])
    return out
