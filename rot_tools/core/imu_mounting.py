"""
An IMU's mounting on a body: the IMU frame in the body frame, from the two orientations.

The body's orientation Q_k (a reference: odometry, a pose, TF) and the IMU's R_k turn together:
Q_k·X = W·R_k for the mounting X (as a static transform base_link → imu_link gives it), so
their relative rotations over the same steps satisfy A·X = X·B: hand-eye calibration.
"""

import math
from typing import Any, NamedTuple

import numpy as np
from rot_tools.core.axis_angle import axis_angle_to_matrix, matrix_to_rotvec, rotvec_to_matrix
from rot_tools.core.errors import RotationError
from rot_tools.core.fitting import align_vectors
from rot_tools.core.imu_motion import integrated_gyro, RATE_GAP
from rot_tools.core.so3 import skew
from rot_tools.core.trajectory import hand_eye_rotation, interpolate_poses

HAND_EYE_STEP = 0.5
"""Seconds between the poses whose relative rotations give the mounting."""

KEEP_AXES = np.diag([1.0, 0.5, 0.25])
"""Weights of tr(KEEP_AXES·X) that one_axis_mounting maximises: x first, then y, then z."""


AXIS_DOMINANCE = 4.0
"""σ1/σ2 of the IMU's turns at least, for their first principal axis to be the one the body
turns about when the reference turns about one axis only."""

MIN_STEPS = 5
"""Steps HAND_EYE_STEP apart at least, with both poses known, for a mounting."""

MIN_TURN = 0.5
"""σ1 of the IMU's turns (rad) at least, for their main axis to stand above noise."""

MIN_AGREEMENT = 0.5
"""|cosine| of the body's and the IMU's turns about their main axes at least, for the IMU's
axis to be signed by the body's."""

ROUND_OFF = 1e-9
"""σ2/σ1 of the body's turns below which it turned about one axis only (said in words)."""


def one_axis_mounting(alpha, beta):
    """
    Return the mounting X of an IMU on a body that turns about one axis only.

    alpha, beta (K, 3): the body's turns (about one axis n, their first singular vector) and
    the IMU's over the same steps. The IMU axis m that turns with n is the first principal
    axis of the IMU's turns, signed to turn as n does (Σ (α_k·n)(β_k·m) > 0): it needs the
    reference's turns to be right in sense only, not in size (wheel odometry's are not), and
    it takes the IMU's turns that the reference does not show (a planar odometry on uneven
    ground) as noise about it. RotationError when those are not much smaller (σ1/σ2 of the
    IMU's turns below AXIS_DOMINANCE), when the IMU hardly turns (σ1 under MIN_TURN rad), or
    when its turns about m do not follow the body's about n (|cosine| under MIN_AGREEMENT).
    Of the mountings that map m onto n (X₀, the smallest
    turn, then Rot(n, ψ)·X₀), the one that best keeps the body's x, then y: tr(Rot(n, ψ)·P)
    greatest for P = X₀·KEEP_AXES, at ψ = atan2(tr([n]×·P), tr P − nᵀ·P·n).
    """
    n = np.linalg.svd(alpha, full_matrices=False)[2][0]
    _, sigma, vt = np.linalg.svd(beta, full_matrices=False)
    if sigma[1] * AXIS_DOMINANCE > sigma[0]:
        raise RotationError(
            "the reference turns about one axis, but the IMU's turns have no dominant axis "
            f'(σ2/σ1 = {sigma[1] / sigma[0]:.2g} > {1 / AXIS_DOMINANCE:g}): too little turn')
    if sigma[0] < MIN_TURN:
        raise RotationError(f'the IMU turns by {sigma[0]:.2g} rad over those steps (under '
                            f'{MIN_TURN:g}): too little turn to fix its axis')
    along, about = alpha @ n, beta @ vt[0]
    cosine = float(along @ about / (np.linalg.norm(along) * np.linalg.norm(about)))
    if abs(cosine) < MIN_AGREEMENT:
        raise RotationError("the IMU's turns about its main axis do not follow the body's "
                            f'(cosine {cosine:.2f}, under {MIN_AGREEMENT:g})')
    m = vt[0] if cosine >= 0 else -vt[0]
    X0 = align_vectors(n[None], m[None]).R
    P = X0 @ KEEP_AXES
    psi = math.atan2(float(np.trace(skew(n) @ P)), float(np.trace(P) - n @ P @ n))
    return axis_angle_to_matrix(n, psi) @ X0


class Mounting(NamedTuple):
    """
    The mounting X (3, 3), why only an axis of it may be fixed, and the poses it came from.

    warning: '' or the one-axis warning; Q, R (K, 3, 3): the reference and the IMU's
    orientation (None without one) at the same instants HAND_EYE_STEP apart, NaN where the
    reference does not cover them.
    """

    X: np.ndarray
    warning: str
    Q: np.ndarray
    R: Any


def mounting_poses(samples, ref_t):
    """Return the IMU sample indices HAND_EYE_STEP apart within the reference's span."""
    step = max(1, int(round(HAND_EYE_STEP / samples.period)))
    inside = (samples.t >= ref_t[0]) & (samples.t <= ref_t[-1])
    return np.flatnonzero(inside)[::step]


def imu_mounting(samples, ref_t, ref_Q, ref_period, lag=0.0):
    """
    Return the Mounting of the IMU (ImuSamples) on the body (ref_t (M,), ref_Q (M, 3, 3)).

    The reference at the IMU's stamps HAND_EYE_STEP apart (interpolate_poses: slerp, within
    RATE_GAP periods) and the IMU's orientation lag (s) after them (the nearest sample: it
    describes the instant of the stamp lag earlier), relative rotations of consecutive ones
    without a gap, then hand_eye_rotation (one_axis_mounting where the reference turns about
    one axis only). RotationError for fewer than MIN_STEPS steps, and as those raise it
    (fewer than two steps that turn, no dominant axis of the IMU's turns).
    """
    t = samples.t
    poses = mounting_poses(samples, ref_t)
    got = interpolate_poses(ref_t, ref_Q, None, t[poses],
                            max_gap=RATE_GAP * max(ref_period, samples.period))
    late = poses + int(round(lag / samples.period))
    covered = got.covered & (late >= 0) & (late < len(t))
    Q = np.full((len(poses), 3, 3), np.nan)
    Q[got.covered] = got.R
    Q[~covered] = np.nan
    step = max(HAND_EYE_STEP / samples.period, 1.0)
    pair = (covered[:-1] & covered[1:]
            & (np.diff(t[poses]) <= RATE_GAP * step * samples.period))
    A = np.swapaxes(Q[:-1][pair], -1, -2) @ Q[1:][pair]
    R = None
    if samples.R is not None:
        R = np.full((len(poses), 3, 3), np.nan)
        R[covered] = samples.R[late[covered]]
        B = np.swapaxes(R[:-1][pair], -1, -2) @ R[1:][pair]
    else:
        total = integrated_gyro(samples)
        B = rotvec_to_matrix(total[poses[1:][pair]] - total[poses[:-1][pair]])
    if len(A) < MIN_STEPS:
        raise RotationError(f'{len(A)} steps of {HAND_EYE_STEP:g} s where the reference covers '
                            f'the IMU: at least {MIN_STEPS} needed')
    found = hand_eye_rotation(A, B)
    X, warning = found.rotation, ''
    if found.axes < 2:
        X = one_axis_mounting(matrix_to_rotvec(A, check=False), matrix_to_rotvec(B, check=False))
        ratio = found.singular_values[1] / found.singular_values[0]
        how = ('only' if ratio < ROUND_OFF else f'mainly (σ2/σ1 = {ratio:.2g})')
        warning = (f'the body turned about one axis {how}: the turn of the mounting about it is '
                   "not determined; of the turns about it, the one that best keeps the IMU's "
                   "x (then y) along the body's is given")
    return Mounting(X=X, warning=warning, Q=Q, R=R)
