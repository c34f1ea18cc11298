"""
An orientation stream against ground truth: matching, time offset, alignment, mounting, errors.

Two streams of poses (stamps (N,), R (N, 3, 3), positions (N, 3) where they exist): the
estimate and the reference, R mapping the body's coordinates to its reference frame's.
Their stamps are checked and paired by rot_tools.core.stamps.
"""

__all__ = ['align_rotations', 'ALIGNMENTS', 'angular_speeds', 'delta_pairs', 'error_statistics',
           'estimate_time_offset', 'hand_eye_rotation', 'HandEye', 'interpolate_poses',
           'nearest_stamps', 'rotation_errors', 'RotationErrors', 'TimeOffset']

import math
from typing import NamedTuple

import numpy as np
from rot_tools.core._arrays import finite_array, require_tolerance
from rot_tools.core.axis_angle import matrix_to_rotvec
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import matrix_to_euler, RPY_SEQUENCE
from rot_tools.core.fitting import align_vectors, mean_rotation, rotation_distance
from rot_tools.core.screw import screw_interpolate
from rot_tools.core.so3 import checked_rotation, rot_z
from rot_tools.core.stamps import checked_stamps, delta_pairs, plain

EXCITED_RATIO = 0.05
"""σ_i/σ_1 of the stacked rotation vectors α_k at or above which axis i counts as excited.

Below it the turn about the poorly excited axis is set by noise, not by the motion.
"""

MAX_GRID = 1 << 20
"""Samples of the common grid of estimate_time_offset at most; a longer overlap coarsens it."""


# ---- checks (the stamps': rot_tools.core.stamps) -----------------------------------------


def _rotations(R, name, count=None):
    """Rotations (N, 3, 3) validated, N = count when given."""
    R = checked_rotation(R, True)
    if R.ndim != 3:
        raise RotationError(f'{name} must have shape (N, 3, 3), got {R.shape}')
    if count is not None and len(R) != count:
        raise RotationError(f'{name} has {len(R)} rotations for {count} stamps')
    return R


def _positions(b, name, count):
    """Positions (N, 3), finite."""
    b = finite_array(b, (3,), name)
    if b.shape != (count, 3):
        raise RotationError(f'{name} must have shape ({count}, 3), one per stamp, got {b.shape}')
    return b


def _times(at, name):
    at = finite_array(at, (), name)
    if at.ndim != 1:
        raise RotationError(f'{name} must have shape (M,), got {at.shape}')
    return at


class _Pairs(NamedTuple):
    R_ref: np.ndarray
    R_est: np.ndarray


def _pair_count(R_ref, R_est, least):
    """Return both batches of rotations as _Pairs, equal in count and ≥ least."""
    R_ref, R_est = _rotations(R_ref, 'R_ref'), _rotations(R_est, 'R_est')
    if len(R_ref) != len(R_est):
        raise RotationError(f'R_ref has {len(R_ref)} rotations but R_est has {len(R_est)}: '
                            'pairs are needed')
    if len(R_ref) < least:
        raise RotationError(f'{len(R_ref)} pair(s) of rotations: at least {least} needed')
    return _Pairs(R_ref=R_ref, R_est=R_est)


# ---- matching ----------------------------------------------------------------------------


class Interpolated(NamedTuple):
    """Poses at the covered times: R (K, 3, 3), b (K, 3) or None, covered (M,) bool."""

    R: np.ndarray
    b: np.ndarray
    covered: np.ndarray


def interpolate_poses(stamps, R, b, at, max_gap=0.1):
    """
    REF poses at the times ``at``, along the constant-screw motion between their neighbours.

    stamps (N,) strictly increasing, N ≥ 2; R (N, 3, 3); b (N, 3) or None (rotations only);
    at (M,) any order. For t_k ≤ a ≤ t_{k+1}: T(a) = T_k·exp(s·log(T_k⁻¹T_{k+1})),
    s = (a − t_k)/(t_{k+1} − t_k) (screw_interpolate; with b = 0 this is the slerp of R).
    ``a`` is covered where both neighbours lie within max_gap (s) of it, or a stamp equals it.
    Returns Interpolated(R (K, 3, 3), b (K, 3) or None, covered (M,) bool) with K =
    covered.sum(): the poses at at[covered], in order.
    """
    t = checked_stamps(stamps, 'stamps', 2)
    R = _rotations(R, 'R', len(t))
    positions = np.zeros((len(t), 3)) if b is None else _positions(b, 'b', len(t))
    at = _times(at, 'at')
    gap = require_tolerance(max_gap, 'max_gap')
    k = np.clip(np.searchsorted(t, at, side='right') - 1, 0, len(t) - 2)
    before, after = at - t[k], t[k + 1] - at
    exact = (before == 0) | (after == 0)
    covered = exact | ((before >= 0) & (after >= 0) & (before <= gap) & (after <= gap))
    k, before = k[covered], before[covered]
    s = before / (t[k + 1] - t[k])
    pose = screw_interpolate(R[k], positions[k], R[k + 1], positions[k + 1], s, check=False)
    return Interpolated(R=pose.R, b=None if b is None else pose.b, covered=covered)


class NearestStamps(NamedTuple):
    """Indices (K,) into the stamps, and which times were covered (M,) bool."""

    index: np.ndarray
    covered: np.ndarray


def nearest_stamps(stamps, at, max_gap=0.01):
    """
    Index of the nearest stamp to each time ``at``, within max_gap (s), as evo pairs poses.

    stamps (N,) strictly increasing; at (M,). A tie goes to the earlier stamp. Returns
    NearestStamps(index (K,) into stamps, covered (M,) bool), K = covered.sum(). evo walks the
    stream with fewer poses and looks each of its stamps up in the other: to reproduce its pairs,
    pass the shorter stream as ``at``.
    """
    t = checked_stamps(stamps, 'stamps', 1)
    at = _times(at, 'at')
    gap = require_tolerance(max_gap, 'max_gap')
    upper = np.searchsorted(t, at, side='right')
    lower = np.maximum(upper - 1, 0)
    upper = np.minimum(upper, len(t) - 1)
    d_lower, d_upper = np.abs(at - t[lower]), np.abs(t[upper] - at)
    index = np.where(d_upper < d_lower, upper, lower)
    covered = np.minimum(d_lower, d_upper) <= gap
    return NearestStamps(index=index[covered], covered=covered)


# ---- time offset -------------------------------------------------------------------------


class Speeds(NamedTuple):
    """Angular speeds (rad/s) between consecutive poses, at the midpoints of their stamps."""

    t: np.ndarray
    speed: np.ndarray


def angular_speeds(stamps, R, name='R'):
    """
    Angular speed |ω| (rad/s) between consecutive poses, at the midpoints of their stamps.

    |ω_k| = θ(R_kᵀR_{k+1}) / (t_{k+1} − t_k), θ the geodesic angle (a turn of more than π
    between two samples aliases). stamps (N,) strictly increasing, N ≥ 2; returns
    Speeds(t: midpoints (N − 1,), speed (N − 1,)).
    """
    t = checked_stamps(stamps, f'stamps of {name}', 2)
    R = _rotations(R, name, len(t))
    steps = np.diff(t)
    with np.errstate(over='ignore'):
        speed = rotation_distance(R[:-1], R[1:], check=False) / steps
    if not np.isfinite(speed).all():
        k = int(np.argmax(~np.isfinite(speed)))
        raise RotationError(f'{name} turns faster than float64 holds: '
                            f'{plain(rotation_distance(R[k], R[k + 1], check=False))} rad in '
                            f'{plain(steps[k])} s at stamp {plain(t[k])}')
    return Speeds(t=t[:-1] / 2 + t[1:] / 2, speed=speed)  # (t_k + t_k+1)/2 would overflow


def _on_grid(grid, t, v):
    """v(t) linearly interpolated at grid, NaN outside [t_0, t_end]."""
    out = np.interp(grid, t, v)
    out[(grid < t[0]) | (grid > t[-1])] = np.nan
    return out


def _sliding_sums(a, b, lags):
    """
    Return Σ_g a[g]·b[g + k] for k = 0 … 2·lags, by FFT (len(b) = len(a) + 2·lags).

    The FFTs are taken at the power of two ≥ len(b) (a length with a large prime factor is
    many times slower): g + k ≤ len(b) − 1 never wraps, so the zeros added change nothing.
    """
    size = 1 << (len(b) - 1).bit_length()
    sums = np.fft.irfft(np.conj(np.fft.rfft(a, size)) * np.fft.rfft(b, size), size)
    return sums[:2 * lags + 1]


class _Correlations(NamedTuple):
    r: np.ndarray
    count: np.ndarray


def _correlations(ref, est, lags):
    """
    Pearson correlation of ref[g] and est[g + lags − j] over their common samples, per lag j.

    ref (n,), est (n + 2·lags,), NaN where a stream has no sample. Returns _Correlations for
    j = −lags … lags; r is NaN where fewer than half the largest count overlap.
    """
    m_r, m_e = np.isfinite(ref), np.isfinite(est)
    x, y = np.where(m_r, ref, 0.0), np.where(m_e, est, 0.0)
    x = np.where(m_r, x - x[m_r].mean(), 0.0)  # centred: the sums below keep their digits
    y = np.where(m_e, y - y[m_e].mean(), 0.0)
    w_r, w_e = m_r.astype(float), m_e.astype(float)
    count = np.rint(_sliding_sums(w_r, w_e, lags))
    sx, sy = _sliding_sums(x, w_e, lags), _sliding_sums(w_r, y, lags)
    sxx, syy = _sliding_sums(x * x, w_e, lags), _sliding_sums(w_r, y * y, lags)
    sxy = _sliding_sums(x, y, lags)
    enough = count >= max(3.0, count.max() / 2)
    n = np.where(enough, count, 1.0)
    with np.errstate(divide='ignore', invalid='ignore'):
        r = (sxy - sx * sy / n) / np.sqrt((sxx - sx * sx / n) * (syy - sy * sy / n))
    r = np.where(enough & np.isfinite(r), r, np.nan)
    return _Correlations(r=r[::-1], count=count[::-1])  # k = lags − j: reversed, index j + lags


class TimeOffset(NamedTuple):
    """The offset (s) to add to EST's stamps, and the correlation of the speeds there."""

    offset: float
    correlation: float


def estimate_time_offset(stamps_est, R_est, stamps_ref, R_ref, max_offset=1.0):
    """
    Time offset between two orientation streams, from their angular speeds.

    Both speeds (angular_speeds) are put on one grid of step h = the shorter of the streams'
    median sample periods (coarser when the overlap or the search would exceed MAX_GRID
    samples), and the Pearson correlation r(o) of |ω_ref|(t) with |ω_est|(t − o) is taken for
    o = c + j·h over the offsets within ±max_offset (s) at which the streams overlap at all
    (c the middle of them: max_offset never sizes the search beyond the streams' own span);
    the best j is refined below one sample by the parabola through r at j − 1, j, j + 1:
    o = c + (j + ½(r₋ − r₊)/(r₋ − 2r₀ + r₊))·h. Returns TimeOffset(offset, correlation):
    offset is the value to add to EST's stamps before matching (evo's --t_offset),
    correlation r at the best sample, in [−1, 1]. RotationError when the streams do not
    overlap within max_offset, a stream never turns, or the best offset is at ±max_offset
    (the true one may lie beyond).
    """
    est = angular_speeds(stamps_est, R_est, 'R_est')
    ref = angular_speeds(stamps_ref, R_ref, 'R_ref')
    te, we, tr, wr = est.t, est.speed, ref.t, ref.speed
    reach = require_tolerance(max_offset, 'max_offset')
    for name, speed in (('R_est', we), ('R_ref', wr)):
        if np.ptp(speed) == 0:
            raise RotationError(f'{name} turns at a constant speed ({speed[0]:.3g} rad/s): '
                                'no feature to align in time')
    h = min(np.median(np.diff(te)), np.median(np.diff(tr)))
    low, high = max(-reach, tr[0] - te[-1]), min(reach, tr[-1] - te[0])  # EST + o meets REF
    if high - low < 2 * h:
        raise RotationError(
            f'the streams do not overlap within max_offset = {plain(reach)} s: R_ref spans '
            f'[{plain(tr[0])}, {plain(tr[-1])}] s, R_est [{plain(te[0])}, {plain(te[-1])}] s')
    centre, half = (low + high) / 2, (high - low) / 2
    te = te + centre  # the search is then ±half about 0
    lo, hi = max(tr[0], te[0] - half), min(tr[-1], te[-1] + half)
    h = max(h, (hi - lo) / MAX_GRID, half / MAX_GRID)
    lags, n = math.ceil(half / h - 1e-9), int((hi - lo) / h) + 1  # (0.2/0.01 = 20.000…04)
    grid = lo + h * np.arange(-lags, n + lags)
    r = _correlations(_on_grid(grid[lags:lags + n], tr, wr), _on_grid(grid, te, we), lags).r
    if not np.isfinite(r).any():
        raise RotationError('the angular speeds do not correlate at any offset within '
                            f'±{plain(reach)} s (too little overlap, or a speed constant there)')
    best = int(np.nanargmax(r))
    if best in (0, 2 * lags):
        edge = centre + (best - lags) * h
        limit = 'max_offset' if abs(abs(edge) - reach) <= h else 'the overlap of the streams'
        raise RotationError(f'the best offset lies at the edge, {edge:+.6g} s: the true one '
                            f'may lie beyond {limit}' + (
                                f' = {plain(reach)} s' if limit == 'max_offset' else ''))
    r_minus, r_0, r_plus = r[best - 1], r[best], r[best + 1]
    curve = r_minus - 2 * r_0 + r_plus
    step = 0.5 * (r_minus - r_plus) / curve if curve < 0 else 0.0  # NaN compares False: 0
    return TimeOffset(offset=float(centre + (best - lags + step) * h), correlation=float(r_0))


# ---- alignment ---------------------------------------------------------------------------


ALIGNMENTS = ('none', 'rotation', 'yaw', 'se3', 'posyaw')
"""The methods of align_rotations."""


class FrameAlignment(NamedTuple):
    """The constant motion (W (3, 3), t (3,)) between two streams' reference frames."""

    W: np.ndarray
    t: np.ndarray


def align_rotations(R_ref, R_est, method='rotation', *, b_ref=None, b_est=None):
    """
    Constant motion (W, t) between the reference frames of two paired streams.

    R_ref, R_est (N, 3, 3) paired; W·R_est is then compared with R_ref, and W·b_est + t with
    b_ref. method:

    - 'none': W = I, t = 0.
    - 'rotation': W minimises Σ‖R_ref,k − W·R_est,k‖² (chordal L2): the rotation nearest to
      S = Σ R_ref,k·R_est,kᵀ (mean_rotation of R_ref,k·R_est,kᵀ); t = 0.
    - 'yaw': the same over W = Rot_z(ψ) only: ψ = atan2(S₁₀ − S₀₁, S₀₀ + S₁₁); t = 0.
    - 'se3': Umeyama without scale on the positions, as evo's --align: W minimises
      Σ‖(b_ref,k − b̄_ref) − W·(b_est,k − b̄_est)‖² (align_vectors), t = b̄_ref − W·b̄_est.
      Needs b_ref, b_est (N, 3), N ≥ 3.
    - 'posyaw': the same over W = Rot_z(ψ) only, 4 degrees of freedom (ψ and t), as
      rpg_trajectory_evaluation aligns visual-inertial odometry, whose gravity direction is
      observable (Zhang and Scaramuzza, IROS 2018): with d = b − b̄,
      ψ = atan2(Σ(y_ref·x_est − x_ref·y_est), Σ(x_ref·x_est + y_ref·y_est)) of the d's,
      t = b̄_ref − W·b̄_est. Needs b_ref, b_est (N, 3), N ≥ 2, moving across z.

    Returns FrameAlignment(W (3, 3), t (3,)). RotationError for an unknown method, unpaired
    input and a W that is not unique.
    """
    if method not in ALIGNMENTS:
        raise RotationError(f'method must be one of {", ".join(ALIGNMENTS)}, got {method!r}')
    pairs = _pair_count(R_ref, R_est, 1)
    R_ref, R_est = pairs.R_ref, pairs.R_est
    zero = np.zeros(3)
    if method == 'none':
        return FrameAlignment(W=np.eye(3), t=zero)
    if method == 'se3':
        return _umeyama(b_ref, b_est, len(R_ref))
    if method == 'posyaw':
        return _position_yaw(b_ref, b_est, len(R_ref))
    if method == 'rotation':
        return FrameAlignment(W=mean_rotation(R_ref @ np.swapaxes(R_est, -1, -2)), t=zero)
    S = np.einsum('nij,nkj->ik', R_ref, R_est)
    cos, sin = S[0, 0] + S[1, 1], S[1, 0] - S[0, 1]
    if math.hypot(cos, sin) <= 1e-9 * len(R_ref):
        raise RotationError('the yaw alignment is not unique: every turn about z fits as well '
                            f'(S₀₀ + S₁₁ = {cos:.3g}, S₁₀ − S₀₁ = {sin:.3g})')
    return FrameAlignment(W=rot_z(math.atan2(sin, cos)), t=zero)


class _Centred(NamedTuple):
    mean: np.ndarray
    d: np.ndarray


def _centred(b, name):
    """
    Return the mean of positions b (K, 3) and b − mean scaled by a power of two (_Centred).

    Near float64's range the mean and the differences would overflow: b is scaled by 2^−e
    (e: max|b|'s exponent) first, exactly; the fits below do not depend on the scale of d.
    """
    e = math.frexp(float(np.max(np.abs(b))))[1] if b.size else 0
    scaled = np.ldexp(b, -e)
    mean = scaled.mean(axis=0)
    with np.errstate(over='ignore'):
        back = np.ldexp(mean, e)
    if not np.isfinite(back).all():
        raise RotationError(f'{name}: positions of ±{np.max(np.abs(b)):.3g} leave float64 in '
                            'the fit')
    return _Centred(mean=back, d=scaled - mean)


def _translation(W, mean_ref, mean_est):
    """Return the translation b̄_ref − W·b̄_est, refused where it leaves float64."""
    with np.errstate(over='ignore', invalid='ignore'):
        t = mean_ref - W @ mean_est
    if not np.isfinite(t).all():
        top = max(np.max(np.abs(mean_ref)), np.max(np.abs(mean_est)))
        raise RotationError(f'b_ref, b_est: positions of ±{top:.3g} leave float64 in the fit')
    return t


def _centred_positions(method, b_ref, b_est, count, least):
    """Check and centre the positions a fit by ``method`` needs (at least ``least``)."""
    if b_ref is None or b_est is None:
        raise RotationError(f"method '{method}' fits positions: give b_ref and b_est")
    if count < least:
        raise RotationError(f"method '{method}' needs at least {least} positions, got {count}")
    b_ref, b_est = _positions(b_ref, 'b_ref', count), _positions(b_est, 'b_est', count)
    return _centred(b_ref, 'b_ref'), _centred(b_est, 'b_est')


def _umeyama(b_ref, b_est, count):
    (mean_ref, d_ref), (mean_est, d_est) = _centred_positions('se3', b_ref, b_est, count, 3)
    if not d_ref.any() or not d_est.any():
        raise RotationError("method 'se3' needs positions that move: "
                            f"{'b_ref' if not d_ref.any() else 'b_est'} stands still")
    keep = d_ref.any(axis=1) & d_est.any(axis=1)  # a pair at a centroid pulls nowhere
    W = align_vectors(d_ref[keep], d_est[keep]).R
    return FrameAlignment(W=W, t=_translation(W, mean_ref, mean_est))


def _position_yaw(b_ref, b_est, count):
    """Fit the yaw and translation that best align the positions (align_rotations' 'posyaw')."""
    (mean_ref, d_ref), (mean_est, d_est) = _centred_positions('posyaw', b_ref, b_est, count, 2)
    cos = float(np.sum(d_ref[:, 0] * d_est[:, 0] + d_ref[:, 1] * d_est[:, 1]))
    sin = float(np.sum(d_ref[:, 1] * d_est[:, 0] - d_ref[:, 0] * d_est[:, 1]))
    spread = [float(np.linalg.norm(d[:, :2])) for d in (d_ref, d_est)]
    if math.hypot(cos, sin) <= 1e-12 * spread[0] * spread[1] or not all(spread):
        still = 'b_ref' if spread[0] <= spread[1] else 'b_est'
        raise RotationError("method 'posyaw' needs positions that move in x and y: "
                            f'{still} moves along z only, or the two do not correlate in x, y '
                            f'(Σ x·x + y·y = {cos:.3g}, Σ y·x − x·y = {sin:.3g})')
    W = rot_z(math.atan2(sin, cos))
    return FrameAlignment(W=W, t=_translation(W, mean_ref, mean_est))


# ---- mounting ----------------------------------------------------------------------------


class HandEye(NamedTuple):
    """
    The mounting rotation X with A_k·X = X·B_k, and how well the motion determines it.

    rotation: X (3, 3); residual: RMS over k of the angle of (A_k·X)ᵀ·X·B_k (rad);
    singular_values: σ1 ≥ σ2 ≥ σ3 of the stacked α_k / √K (rad), the RMS turn per principal
    axis; axes: how many σ_i ≥ EXCITED_RATIO·σ1; warning: '' or why X is not trustworthy.
    """

    rotation: np.ndarray
    residual: float
    singular_values: np.ndarray
    axes: int
    warning: str


def hand_eye_rotation(A, B):
    """
    Rotation part of hand-eye calibration: X with A_k·X = X·B_k for every k.

    A (K, 3, 3) relative rotations of the reference (Q_iᵀQ_j), B (K, 3, 3) those of the
    estimate (P_iᵀP_j) over the same intervals. A_k = X·B_k·Xᵀ, so the rotation vectors
    α_k = log A_k and β_k = log B_k satisfy α_k = X·β_k (Park and Martin); X minimises
    Σ‖α_k − X·β_k‖² (align_vectors: their X = (MᵀM)^(−1/2)·Mᵀ with M = Σ β_k·α_kᵀ, kept a
    rotation). Pairs in which either turn is 0 carry no information and are dropped. With
    fewer than two excited axes (HandEye.axes < 2) the turn about the one excited axis is
    set by noise, and HandEye.warning says so. RotationError for fewer than 2 pairs that turn.
    """
    pairs = _pair_count(A, B, 2)
    A, B = pairs.R_ref, pairs.R_est
    alpha, beta = matrix_to_rotvec(A, check=False), matrix_to_rotvec(B, check=False)
    turns = alpha.any(axis=1) & beta.any(axis=1)
    if turns.sum() < 2:
        raise RotationError(f'{int(turns.sum())} of {len(A)} relative rotations turn (in A '
                            'and B both): the motion never turns enough for a mounting')
    sigma = np.linalg.svd(alpha[turns], compute_uv=False) / math.sqrt(int(turns.sum()))
    axes = int(np.sum(sigma >= EXCITED_RATIO * sigma[0]))
    X = align_vectors(alpha[turns], beta[turns]).R
    residual = rotation_distance(A @ X, X @ B, check=False)
    warning = ''
    if axes < 2:
        ratio = sigma[1] / sigma[0]
        # A ratio at round-off level means one axis exactly: said in words, as its digits
        # depend on the platform's rounding and mean nothing.
        how = ('the motion turned about one axis only' if ratio < 1e-9 else
               f'the motion excited {axes} rotation axis (σ2/σ1 = {ratio:.2g} < '
               f'{EXCITED_RATIO:g})')
        warning = f'{how}: the turn of the mounting about it is not determined'
    return HandEye(rotation=X, residual=float(np.sqrt(np.mean(residual ** 2))),
                   singular_values=sigma, axes=axes, warning=warning)


# ---- errors ------------------------------------------------------------------------------


def error_statistics(x):
    """
    Return rmse √mean(x²), mean, median, std (population, as evo), min, max of x (K,), K ≥ 1.

    x finite; huge values (beyond 1e150) are scaled by a power of two first, so that x² and
    the sums do not overflow (exactly, bit for bit, where nothing would have overflowed).
    RotationError for x empty, not (K,), not finite, not real numbers.
    """
    x = finite_array(x, (), 'x')
    if x.ndim != 1:
        raise RotationError(f'x must have shape (K,), got {x.shape}')
    if not len(x):
        raise RotationError('x has no value: statistics need at least one')
    power = 0
    top = float(np.max(np.abs(x)))
    if top > 1e150:
        power = math.frexp(top)[1]
        x = np.ldexp(x, -power)
    stats = {'rmse': np.sqrt(np.mean(x * x)), 'mean': np.mean(x), 'median': np.median(x),
             'std': np.std(x), 'min': np.min(x), 'max': np.max(x)}
    return {key: math.ldexp(float(value), power) for key, value in stats.items()}


class RotationErrors(NamedTuple):
    """
    Absolute and relative rotation errors of paired streams (rotation_errors).

    angle (N,): θ(E_k) ∈ [0, π] of E_k = R_ref,kᵀ·R_est,k; rpy (N, 3): E_k's roll, pitch,
    yaw (RPY_SEQUENCE, each unwrapped along the stream, to be drawn: a yaw error that drifts
    through ±π goes on growing); ape: error_statistics(angle); pairs (K, 2): delta_pairs;
    rpe_angle (K,): the angle of (Q_iᵀQ_j)ᵀ(P_iᵀP_j); rpe: error_statistics(rpe_angle);
    rpy_statistics: (roll, pitch, yaw), each error_statistics of that angle of E_k wrapped to
    (−π, π] (wrap_angles: E's own angles, not the unwrapped drift). Radians.
    """

    angle: np.ndarray
    rpy: np.ndarray
    ape: dict
    pairs: np.ndarray
    rpe_angle: np.ndarray
    rpe: dict
    rpy_statistics: tuple


def wrap_angles(x):
    """
    Return angles x (any shape, radians) wrapped to (−π, π]: x − 2πk for the k that fits.

    Angles already in (−π, π] come back bit for bit; −π becomes π.
    """
    x = np.array(x, dtype=float)
    outside = (x <= -np.pi) | (x > np.pi)
    y = np.remainder(x[outside] + np.pi, 2 * np.pi) - np.pi  # in [−π, π)
    x[outside] = np.where(y == -np.pi, np.pi, y)
    return x


def rotation_errors(R_ref, R_est, delta=1, unit='f', stamps=None):
    """
    Rotation errors of an estimate P against a reference Q, paired pose by pose, as evo's.

    R_ref, R_est (N, 3, 3), N ≥ 2. Absolute: E_k = Q_kᵀ·P_k, its geodesic angle (accurate at 0
    and π; evo's APE with --pose_relation angle_deg, in radians) and roll/pitch/yaw.
    Relative (evo's RPE, --pose_relation angle_deg): for the pairs (i, j) of delta_pairs(N,
    delta, unit, stamps) — by default (1 frame) every consecutive pair (k, k + 1) — the angle
    of (Q_iᵀQ_j)ᵀ·(P_iᵀP_j). Returns RotationErrors.
    """
    both = _pair_count(R_ref, R_est, 2)
    R_ref, R_est = both.R_ref, both.R_est
    pairs = delta_pairs(len(R_ref), delta, unit, stamps)
    E = np.swapaxes(R_ref, -1, -2) @ R_est
    angle = rotation_distance(R_ref, R_est, check=False)
    rpy = np.unwrap(matrix_to_euler(E, RPY_SEQUENCE, check=False).angles, axis=0)
    i, j = pairs[:, 0], pairs[:, 1]
    rel_ref = np.swapaxes(R_ref[i], -1, -2) @ R_ref[j]
    rel_est = np.swapaxes(R_est[i], -1, -2) @ R_est[j]
    rpe_angle = rotation_distance(rel_ref, rel_est, check=False)
    wrapped = wrap_angles(rpy)
    return RotationErrors(angle=angle, rpy=rpy, ape=error_statistics(angle), pairs=pairs,
                          rpe_angle=rpe_angle, rpe=error_statistics(rpe_angle),
                          rpy_statistics=tuple(error_statistics(wrapped[:, k])
                                               for k in range(3)))
