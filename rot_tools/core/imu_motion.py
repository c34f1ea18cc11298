"""
An IMU's motion: its slow spells, its orientation's lag, its gyro against its orientation.

Samples in time order (imu_samples.ImuSamples): stamps t_k, orientations R_k (the IMU frame in
the orientation's world) or none, gyro ω_k and accelerometer a_k on the IMU's axes.
"""

import math
from typing import Any, NamedTuple

import numpy as np
from rot_tools.core.axis_angle import axis_angle_kernel, rotvec_of
from rot_tools.core.engine import VECTOR
from rot_tools.core.errors import RotationError
from rot_tools.core.fitting import rotation_distance
from rot_tools.core.so3 import apply_to_named_rotations, rot_z
from rot_tools.core.trajectory import estimate_time_offset

RATE_GAP = 3
"""Steps longer than this many median periods give no rate (the turn may alias)."""

SLOW_RATE = 0.05
"""Angular speed (rad/s), averaged over SLOW_WINDOW, below which the body turns slowly."""

SLOW_WINDOW = 0.5
"""Seconds over which the angular speed of a slow spell is averaged."""

MAX_LAG = 1.0
"""The lag is searched within ±MAX_LAG (s) at most."""

LAG_SHARE = 0.1
"""The lag is searched within ±LAG_SHARE of the recording's span at most: a longer lag would
leave too little overlap to tell it."""

MIN_T = 10.0
"""|A_ij| / its standard error at least, for row i of the gyro fit to fix an axis."""

DOMINANCE = 3.0
"""|A_ij| at least this many times every other entry of its row, to fix an axis."""

SIZE_RANGE = (0.5, 2.0)
"""|A_ij| / scale within this range, to fix an axis (outside it the rates disagree)."""

MIN_RATES = 10
"""Rates (pairs of samples) at least, for the gyro fit."""

BIAS_SLACK = 0.002
"""Mean orientation rate (rad/s) about an axis the fit leaves unknown, at most, for a bias."""


def integrated_gyro(samples):
    """Return ∫ω dt from the first sample (N, 3), by trapezoids: the turn over small steps."""
    steps = 0.5 * (samples.gyro[:-1] + samples.gyro[1:]) * np.diff(samples.t)[:, None]
    return np.concatenate([np.zeros((1, 3)), np.cumsum(steps, axis=0)])


def _window(samples):
    """Return the samples per SLOW_WINDOW (≥ 1)."""
    return max(1, int(round(SLOW_WINDOW / samples.period)))


def steady_accel(samples):
    """
    Return the accelerometer averaged over SLOW_WINDOW around each sample (N, 3).

    In a slow spell the IMU turns by less than SLOW_RATE·SLOW_WINDOW over the window, so the
    average keeps the specific force's direction and drops the vibration (which would add
    its square to |a| and scatter the direction).
    """
    count = len(samples.t)
    w = min(_window(samples), count)
    total = np.concatenate([np.zeros((1, 3)), np.cumsum(samples.accel, axis=0)])
    mean = (total[w:] - total[:-w]) / w  # the windows starting at 0 … count − w
    out = np.empty((count, 3))
    start, end = w // 2, w // 2 + len(mean)
    out[start:end] = mean
    out[:start], out[end:] = mean[0], mean[-1]  # the ends: the first and last whole windows
    return out


def slow_spells(samples):
    """
    Return (N,) bool: the mean angular speed over SLOW_WINDOW around the sample < SLOW_RATE.

    The speed is the orientation's turn over the window, or without orientation the gyro's
    integrated rate (as it reads).
    """
    t, count, w = samples.t, len(samples.t), _window(samples)
    slow = np.zeros(count, dtype=bool)
    if count <= w:
        return slow
    span = t[w:] - t[:-w]
    if samples.R is not None:
        turn = rotation_distance(samples.R[:-w], samples.R[w:], check=False)
    else:
        total = integrated_gyro(samples)
        turn = np.linalg.norm(total[w:] - total[:-w], axis=1)
    slow[w // 2:w // 2 + count - w] = (turn < SLOW_RATE * span) & (
        span <= RATE_GAP * w * samples.period)
    return slow


class Lag(NamedTuple):
    """How late the orientation is (s), and the correlation of the two speeds there."""

    seconds: float
    correlation: float


LAG_SAMPLES = 1 << 15
"""Samples at most over which the lag is estimated (the lag is one number, and the
correlation's FFTs grow with the samples): of a longer recording, the stretch of this many
whose gyro speed varies most."""


def orientation_lag(samples):
    """
    Return the Lag of the orientation behind the gyro, from their angular speeds.

    The angular speeds of the gyro and of consecutive orientations do not depend on units,
    axes or frames: the shift that best correlates them (trajectory.estimate_time_offset, the
    gyro's speed given as the turn of a rotation about z, scaled to at most 1 rad per step)
    is how late the orientation is. It is searched within ±MAX_LAG and ±LAG_SHARE of the
    span, over LAG_SAMPLES at most (of a longer recording, the stretch whose gyro speed
    varies most). RotationError, in words, when the data cannot fix it.
    """
    t, R, speed = samples.t, samples.R, np.linalg.norm(samples.gyro, axis=1)
    if len(t) > LAG_SAMPLES:
        chunks = len(t) // LAG_SAMPLES
        spread = speed[:chunks * LAG_SAMPLES].reshape(chunks, LAG_SAMPLES).std(axis=1)
        stretch = slice(int(np.argmax(spread)) * LAG_SAMPLES, None)
        t, R, speed = (x[stretch][:LAG_SAMPLES] for x in (t, R, speed))
    reach = min(MAX_LAG, LAG_SHARE * float(t[-1] - t[0]))
    if reach < 2 * samples.period:
        raise RotationError(f'{len(t)} samples over {t[-1] - t[0]:.3g} s are too short to '
                            'search for a lag')
    if np.ptp(speed) == 0:
        raise RotationError(f'the gyro reads a constant speed ({speed[0]:.3g} rad/s): nothing '
                            'to align in time')
    if np.ptp(rotation_distance(R[:-1], R[1:], check=False) / np.diff(t)) == 0:
        raise RotationError('the orientation turns at a constant speed: nothing to align in '
                            'time')
    steps = 0.5 * (speed[:-1] + speed[1:]) * np.diff(t)
    turn = np.concatenate([[0.0], np.cumsum(steps / steps.max())])
    try:
        found = estimate_time_offset(t, R, t, rot_z(turn % (2 * math.pi)), reach)
    except RotationError:
        raise RotationError('the angular speeds of the gyro and the orientation fix no lag '
                            f'within ±{reach:.3g} s') from None
    return Lag(seconds=-found.offset, correlation=found.correlation)


def _relative_rotvec_kernel(ops, m1, m2):
    # R1ᵀ·R2, entry (i, j) = Σ_k R1[k][i]·R2[k][j]
    m = [[m1[0][i] * m2[0][j] + m1[1][i] * m2[1][j] + m1[2][i] * m2[2][j] for j in range(3)]
         for i in range(3)]
    return rotvec_of(axis_angle_kernel(ops, m))


def relative_rotvecs(R1, R2):
    """Return the rotation vectors of R1ᵀ·R2 (..., 3), for rotations as given (unchecked)."""
    return apply_to_named_rotations(_relative_rotvec_kernel, [(R1, 'R1'), (R2, 'R2')], False,
                                    VECTOR)


class Rates(NamedTuple):
    """The orientation's body rates (K, 3) and the gyro at the same instants (K, 3)."""

    orientation: np.ndarray
    gyro: np.ndarray


def body_rates(samples, lag):
    """
    Return the Rates: of consecutive orientations, and the gyro at their midpoints − lag.

    ω°_k = log(R_kᵀR_{k+1}) / Δt_k (rad/s), the gyro interpolated at (t_k + t_{k+1})/2 − lag;
    steps longer than RATE_GAP periods give none.
    """
    t, R = samples.t, samples.R
    dt = np.diff(t)
    at = t[:-1] + dt / 2 - lag
    use = (dt <= RATE_GAP * samples.period) & (at >= t[0]) & (at <= t[-1])
    orientation = (relative_rotvecs(R[:-1], R[1:]) / dt[:, None])[use]
    gyro = np.empty_like(orientation)
    for i in range(3):
        gyro[:, i] = np.interp(at[use], t, samples.gyro[:, i])
    return Rates(orientation=orientation, gyro=gyro)


class GyroFit(NamedTuple):
    """
    What the rates fix: ω° ≈ scale·M·(ω − bias/scale).

    scale: float or None; rows: {i: (j, ±1)}, M_ij for the axes i of the orientation fixed;
    bias: (3,) rad/s on the gyro's axes, or None; mean_rate: mean ω° (3,) rad/s; spread: the
    RMS of ω° about its mean (rad/s: how clearly the orientation's rate varies); residual:
    the RMS of what scale·M·(ω − bias/scale) leaves of ω° (rad/s; spread where no axis is
    fixed); explained: the share of ω°'s variance that any linear map of ω explains (0 … 1,
    None where ω° does not vary).
    """

    scale: Any
    rows: dict
    bias: Any
    mean_rate: np.ndarray
    spread: float
    residual: float
    explained: Any


def fit_gyro(rates):
    """
    Return the GyroFit of the least-squares fit ω° ≈ A·ω + c of the rates (Rates).

    A row i of A fixes an axis where its largest entry A_ij stands out: MIN_T standard
    errors, DOMINANCE times every other entry of the row, and within SIZE_RANGE of the scale;
    M_ij = sign A_ij. The scale is the least-squares s of ω° ≈ s·M·ω + c over the rows fixed;
    the bias, on the gyro's axes, s·mean(ω) − Mᵀ·mean(ω°) (from mean ω° = s·M·(mean ω − b)).
    An axis the motion does not excite stays unknown; its row of M is completed in order for
    the bias, which is then given only when the orientation's mean rate about it is at most
    BIAS_SLACK.
    """
    # centred sums from the raw ones, as products: NumPy reduces and subtracts tall (K, 3)
    # arrays slowly, and the means are not large against the spread here
    g, o, count = rates.gyro, rates.orientation, len(rates.gyro)
    if count < MIN_RATES:
        return GyroFit(scale=None, rows={}, bias=None, mean_rate=np.zeros(3), spread=0.0,
                       residual=0.0, explained=None)
    ones = np.full(count, 1.0 / count)
    mean_g, mean_o = ones @ g, ones @ o
    S = g.T @ g - count * np.outer(mean_g, mean_g)
    C = g.T @ o - count * np.outer(mean_g, mean_o)
    Y = np.maximum(np.diag(o.T @ o) - count * mean_o * mean_o, 0.0)
    inverse = np.linalg.pinv(S)
    A = (inverse @ C).T
    # Σ residual² per row, from the Gram matrix: Σ d_o² − Cᵀ·S⁻¹·C
    residual = np.maximum(Y - np.einsum('ji,jk,ki->i', C, inverse, C), 0.0)
    spread = math.sqrt(Y.sum() / count)
    explained = 1.0 - min(residual.sum() / Y.sum(), 1.0) if Y.sum() > 0 else None
    variance = residual / max(count - 4, 1)
    error = np.sqrt(variance[:, None] * np.maximum(np.diag(inverse), 0.0)[None, :])
    size = np.abs(A)
    column = np.argmax(size, axis=1)
    ordered = np.sort(size, axis=1)
    top, second = ordered[:, 2], ordered[:, 1]
    clear = ((top > 0) & (top >= MIN_T * error[np.arange(3), column])
             & (top >= DOMINANCE * second))
    rows = {i: (int(column[i]), 1 if A[i, column[i]] > 0 else -1) for i in range(3) if clear[i]}
    taken = [j for j, _ in rows.values()]
    rows = {i: js for i, js in rows.items() if taken.count(js[0]) == 1}
    none = GyroFit(scale=None, rows={}, bias=None, mean_rate=mean_o, spread=spread,
                   residual=spread, explained=explained)
    scale = 0.0
    for _ in range(2):  # once, then again without the rows whose size disagrees
        den = sum(S[j, j] for j, _ in rows.values())
        if not rows or den <= 0:
            return none
        scale = sum(s * C[j, i] for i, (j, s) in rows.items()) / den
        if scale <= 0:
            return none
        rows = {i: (j, s) for i, (j, s) in rows.items()
                if SIZE_RANGE[0] <= size[i, j] / scale <= SIZE_RANGE[1]}
    if not rows:
        return none
    free = iter(j for j in range(3) if j not in [j for j, _ in rows.values()])
    M = np.zeros((3, 3))
    for i in range(3):
        j, s = rows.get(i) or (next(free), 1)
        M[i, j] = s
    bias = None
    if all(abs(mean_o[i]) <= BIAS_SLACK for i in range(3) if i not in rows):
        bias = scale * mean_g - M.T @ mean_o
    left = (o - mean_o) - scale * (g - mean_g) @ M.T
    return GyroFit(scale=float(scale), rows=rows, bias=bias, mean_rate=mean_o, spread=spread,
                   residual=float(np.sqrt(np.einsum('ij,ij->', left, left) / count)),
                   explained=explained)
