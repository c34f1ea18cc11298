"""
``rot-tools bag``: each recorded covariance as standard deviations of roll, pitch and yaw.

For the types that carry their orientation's covariance (rot_tools.io.bag_read.COVARIANCE:
an Imu's orientation_covariance, the pose.covariance of PoseWithCovarianceStamped and
Odometry), each accepted message's covariance is read as rotation_node reads it
(rot_tools.io.message_covariance): all zeros is unknown; not finite, not symmetric or not
positive semi-definite is bad (the message is still used: only its covariance is not); with
``--input-covariance rotvec`` (the default, ROS's PoseWithCovariance) the rotation block is
the covariance of a small rotation about the parent's fixed X, Y, Z, carried to roll, pitch,
yaw by the inverse of the Euler-rate matrix — which does not exist at gimbal lock (pitch
±90°); with ``rpy`` it already is the covariance of roll, pitch, yaw. The columns
``roll_std, pitch_std, yaw_std`` are the square roots of its diagonal, NaN (an empty cell)
where there is none.

Drivers write the same covariance in message after message. A run of identical covariances
is checked once and converted as one batch against the run's rotations
(rot_tools.core.covariance.rotvec_covariance_to_euler takes one covariance for many
rotations); a topic whose covariance changes more than GROUPS times goes through
message_covariance.rpy_covariances, every message checked and converted in one batch. Both
give the same numbers (test_bag_covariance.py).
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


def stddevs(R, cov, reading='rotvec'):
    """
    Return Stddevs (σ (N, 3) of roll, pitch, yaw in rad, status (N,) int8) of N messages.

    R (N, 3, 3) their rotations; cov (N, 9) or (N, 36) their covariances, row-major
    (rot_tools.io.message_covariance.rpy_covariances: the same status codes and numbers);
    σ is NaN where the status is not OK.
    """
    R = np.asarray(R, dtype=np.float64).reshape(-1, 3, 3)
    cov = np.ascontiguousarray(cov, dtype=np.float64)
    n = len(cov)
    if not n:
        return Stddevs(np.zeros((0, 3)), np.zeros(0, np.int8))
    bits = cov.view(np.int64)  # bit for bit: a run of NaN is one run too
    starts = np.flatnonzero(np.append(True, (bits[1:] != bits[:-1]).any(axis=1)))
    if len(starts) > GROUPS:
        C, status = message_covariance.rpy_covariances(R, cov, reading)
        return Stddevs(_sigma(C), status)
    sigma, status = np.full((n, 3), np.nan), np.empty(n, np.int8)
    # each run's covariance alone: reading 'rpy' converts nothing, it only checks
    _, checked = message_covariance.rpy_covariances(
        np.broadcast_to(np.eye(3), (len(starts), 3, 3)), cov[starts], 'rpy')
    for start, end, code in zip(starts, np.append(starts[1:], n), checked):
        status[start:end] = code
        if code != OK:
            continue
        C = message_covariance.square(cov[start])
        if reading == 'rpy':
            sigma[start:end] = _sigma(C)
            continue
        converted = _euler_block(R[start:end], C)
        sigma[start:end] = _sigma(converted.cov)
        status[start:end][converted.degenerate] = LOCK
    return Stddevs(sigma, status)


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
