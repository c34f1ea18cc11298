"""
Comparing, averaging, fitting and sampling rotations — quaternion-free.

The geodesic distance, the chordal mean, the fit of rotated vectors (Wahba's problem) and
Haar-uniform sampling; the mean and the fit are the nearest rotation to a matrix, by its SVD
(NumPy's batched linalg: any leading batch shape).
"""

__all__ = ['align_vectors', 'mean_rotation', 'random_rotations', 'rotation_distance', 'UNIQUE_TOL']

import math
import numbers
import os
from typing import NamedTuple

import numpy as np
from rot_tools.core._arrays import finite_array, refuse_overflow, require_finite
from rot_tools.core.axis_angle import axis_angle_to_matrix, skew_and_cos
from rot_tools.core.engine import norm, SCALAR
from rot_tools.core.errors import RotationError
from rot_tools.core.so3 import apply_to_named_rotations, checked_rotation

UNIQUE_TOL = 1e-9
"""Relative size σ2 + s·σ3 ≤ UNIQUE_TOL·σ1 below which a mean or a fit is not unique.

At that size rounding in S (or H) moves the answer by ~1e-7 rad; beyond it the answer is
determined by the data.
"""

ROUNDING_SIN = np.finfo(float).eps
"""|b × a| (⊥ b) of unit vectors at or below which _smallest_rotation takes a fixed axis ⊥ b:
the cross product is then rounding noise (opposite unit vectors give ≲ ε), and any axis
⊥ b misses a by at most ~2·|b × a|. Measured: R·b − a ≤ 1.1e-15 from θ = π − 1e-6 to π;
a threshold of 16ε gave up to 7e-15.
"""


def _distance_kernel(ops, m1, m2):
    # R1ᵀ·R2, entry (i, j) = Σ_k R1[k][i]·R2[k][j]
    m = [[m1[0][i] * m2[0][j] + m1[1][i] * m2[1][j] + m1[2][i] * m2[2][j] for j in range(3)]
         for i in range(3)]
    parts = skew_and_cos(m)
    return ops.atan2(norm(ops, parts.skew), parts.cos)


def rotation_distance(R1, R2, *, check=True):
    """
    Geodesic angle between rotations: the angle θ ∈ [0, π] of R1ᵀ·R2.

    R1, R2 (..., 3, 3), broadcasting → (...). θ = atan2(|w|, (tr R1ᵀR2 − 1)/2) with w the
    skew part of R1ᵀR2: accurate to rounding at 0 and π. Symmetric, and θ(R1, R2) =
    θ(Q·R1, Q·R2) for every rotation Q. check=False trusts R1, R2: for matrices that are
    not rotations the angle means nothing and may be NaN (rot_tools.core.so3).
    """
    return apply_to_named_rotations(_distance_kernel, [(R1, 'R1'), (R2, 'R2')], check, SCALAR)


def _weights(weights, count, name):
    """Weights (..., N) ≥ 0, not all 0, scaled to max 1 (Σ wᵢRᵢ then cannot overflow)."""
    if weights is None:
        return np.ones(count)
    w = finite_array(weights, (), 'weights')
    if w.ndim == 0 or w.shape[-1] != count:
        got = 'a scalar' if w.ndim == 0 else f'{w.shape[-1]} entries'
        raise RotationError(f'weights must have one entry per {name} ({count}), got {got}')
    negative = w < 0
    if negative.any():
        where = tuple(int(i) for i in np.argwhere(negative)[0])
        index = where[0] if len(where) == 1 else where
        raise RotationError(f'weights must be ≥ 0, got {w[where]:g} at index {index}')
    top = w.max(axis=-1, keepdims=True)
    if (top == 0).any():
        raise RotationError(f'weights are all 0: at least one {name} needs a positive weight')
    return w / top


class _Nearest(NamedTuple):
    """The rotation U·diag(1, 1, det UVᵀ)·Vᵀ of an SVD s = U·diag(sigma)·Vᵀ, and its parts."""

    rotation: np.ndarray
    sigma: np.ndarray
    u: np.ndarray  # its third column times det UVᵀ
    vt: np.ndarray
    rank_one: np.ndarray  # σ2 ≤ rank_one_below·σ1


def _nearest_rotations(s, what, matrix, rank_one_below=UNIQUE_TOL):
    """
    Return the _Nearest rotation maximising tr(Mᵀ·s) per item, and the rank-one flags.

    RotationError when the maximiser is not unique (σ2 + det·σ3 ≤ UNIQUE_TOL·σ1) for an item
    not flagged; items with σ2 ≤ rank_one_below·σ1 are only flagged (the caller decides).
    """
    u, sigma, vt = np.linalg.svd(s)
    sign = np.where(np.linalg.det(u) * np.linalg.det(vt) < 0, -1.0, 1.0)
    gap = sigma[..., 1] + sign * sigma[..., 2]
    rank_one = sigma[..., 1] <= rank_one_below * sigma[..., 0]
    ambiguous = (gap <= UNIQUE_TOL * sigma[..., 0]) & ~rank_one
    if ambiguous.any():
        index = tuple(int(i) for i in np.argwhere(ambiguous)[0])
        where = f' (item {index})' if index else ''
        raise RotationError(
            f'{what} is not unique: the singular values of {matrix} are '
            f'{np.array2string(sigma[index], precision=3)} with det {sign[index]:+.0f}, and '
            f'σ2 {"+" if sign[index] > 0 else "−"} σ3 = {gap[index]:.3g} ≤ '
            f'{UNIQUE_TOL:g}·σ1{where}')
    u = u * np.stack([np.ones_like(sign), np.ones_like(sign), sign], -1)[..., None, :]
    return _Nearest(rotation=u @ vt, sigma=sigma, u=u, vt=vt, rank_one=rank_one)


def mean_rotation(R, weights=None, *, check=True):
    """
    Chordal L2 mean of rotations: the rotation nearest to S = Σ wᵢRᵢ.

    It minimises Σ wᵢ‖M − Rᵢ‖² (Frobenius): M = U·diag(1, 1, det(U·Vᵀ))·Vᵀ from the SVD
    S = U·diag(σ)·Vᵀ.

    R (..., N, 3, 3) → (..., 3, 3); weights (N,) or (..., N), ≥ 0, not all 0 (default
    equal). RotationError when the mean is not unique (Σ wᵢRᵢ rank-deficient, e.g. two
    rotations π apart with equal weights), for negative or all-zero weights, and for a
    weights count other than N. check=False: the nearest rotation to Σ wᵢMᵢ of the matrices
    as given (scaled by their largest entry first, so any finite ones are fine; NaN/Inf
    refused).
    """
    R = checked_rotation(R, check)
    if R.ndim < 3 or not R.shape[-3]:
        raise RotationError(f'R must have shape (..., N, 3, 3) with N ≥ 1, got {R.shape}')
    if not check:  # matrices as given: no NaN/Inf or overflow into the SVD (it may loop on Inf)
        scale = np.abs(require_finite(R, 'R')).max(axis=(-3, -2, -1), keepdims=True)
        R = R / np.where(scale > 0, scale, 1.0)  # the nearest rotation is scale-free
    w = _weights(weights, R.shape[-3], 'rotation')
    try:
        total = np.einsum('...n,...nij->...ij', w, R)
    except ValueError:
        raise RotationError(f'weights {w.shape} and R {R.shape} do not broadcast') from None
    mean = _nearest_rotations(total, 'the mean rotation', 'Σ wᵢRᵢ')
    if mean.rank_one.any():
        index = tuple(int(i) for i in np.argwhere(mean.rank_one)[0])
        raise RotationError(
            'the mean rotation is not unique: Σ wᵢRᵢ is rank-deficient (singular values '
            f'{np.array2string(mean.sigma[index], precision=3)}; e.g. rotations π apart with '
            'equal weights)' + (f' (item {index})' if index else ''))
    return mean.rotation


def _vectors(x, name):
    x = finite_array(x, (3,), name)
    if x.ndim < 2:
        raise RotationError(f'{name} must have shape (..., N, 3), got {x.shape}')
    zero = ~np.any(x, axis=-1)
    if zero.any():
        index = tuple(int(i) for i in np.argwhere(zero)[0])
        raise RotationError(f'{name}[{", ".join(map(str, index))}] is the zero vector: it has '
                            'no direction to align')
    return x


def _unit_rows(x):
    """Rows of x scaled to unit length (rescaled first, so huge or tiny rows are fine)."""
    x = x / np.abs(x).max(axis=-1, keepdims=True)
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def _smallest_rotation(b, a):
    """
    Return the smallest rotation taking the unit vector b onto the unit vector a (..., 3).

    Axis b × a, angle atan2(|b × a|, b·a). Near the angle π, b × a is small and its
    rounding noise (~ε) is not ⊥ b; a half-turn about an axis tilted by τ off the plane ⊥ b
    misses a by ~2τ, so the axis is first projected onto that plane. Where what remains is
    at rounding level (opposite vectors to rounding, or equal ones), the axis is b × e_k,
    e_k the coordinate axis least aligned with b: ⊥ b, and the same for equal inputs.
    """
    axis = np.cross(b, a)
    axis = axis - np.sum(axis * b, axis=-1, keepdims=True) * b
    sin = np.linalg.norm(axis, axis=-1)
    angle = np.arctan2(sin, np.sum(b * a, axis=-1))
    least = np.eye(3)[np.argmin(np.abs(b), axis=-1)]
    axis = np.where((sin <= ROUNDING_SIN)[..., None], np.cross(b, least), axis)
    return axis_angle_to_matrix(axis, angle)


def _log_norms(x):
    """Return log |xᵢ| of non-zero rows, without |xᵢ|² underflowing (rows of 1e-300)."""
    big = np.abs(x).max(axis=-1)
    return np.log(big) + np.log(np.linalg.norm(x / big[..., None], axis=-1))


def _rmsd(a, b, R, w):
    """
    Return sqrt(Σ wᵢ‖aᵢ − R·bᵢ‖² / Σ wᵢ) per item.

    Computed on a and b scaled by a common factor so that nothing overflows; RotationError if
    the rmsd itself does.
    """
    big = np.maximum(np.abs(a).max(axis=(-2, -1)), np.abs(b).max(axis=(-2, -1)))[..., None, None]
    residual = a / big - np.einsum('...ij,...nj->...ni', R, b / big)
    mean = np.sum(w * np.sum(residual * residual, axis=-1), axis=-1) / np.sum(w, axis=-1)
    with np.errstate(over='ignore'):
        rmsd = big[..., 0, 0] * np.sqrt(mean)
    refuse_overflow(np.isfinite(rmsd), 'the rmsd of align_vectors')
    return rmsd


class _Fit(NamedTuple):
    """The best rotation about a dominant axis, and where it is the only best one."""

    rotation: np.ndarray
    unique: np.ndarray


def _fit_about_dominant(a, b, w, a_axis, b_axis):
    """
    Return the best rotation among those taking b_axis onto a_axis (unit vectors, (..., 3)).

    R0, the smallest rotation taking b_axis onto a_axis, then the turn φ about a_axis that
    best fits the pairs: with c = R0·b and the parts a⊥, c⊥ of a and c ⊥ a_axis, the cost
    Σ wᵢ‖aᵢ − Rot(a_axis, φ)·cᵢ‖² is least at φ = atan2(Σ wᵢ (c⊥ᵢ × a⊥ᵢ)·â, Σ wᵢ c⊥ᵢ·a⊥ᵢ)
    (the way scipy fits the other pairs about a primary one of infinite weight). Both sums
    come from the pairs themselves, not from H, so pairs that H's rounding would drop still
    count. Returns a _Fit: unique is False where pairs off a_axis exist but their pulls
    cancel (every φ fits as well); where every pair lies along the axis (H of rank one), φ is
    0: the smallest rotation.
    """
    r0 = _smallest_rotation(b_axis, a_axis)
    c = np.einsum('...ij,...nj->...ni', r0, b)
    n = a_axis[..., None, :]
    # unit directions, and each pair's size wᵢ|aᵢ||cᵢ| relative to the largest pair off the
    # axis, from logarithms: the products of 1e-150-long vectors would underflow
    a_u, c_u = _unit_rows(a), _unit_rows(c)
    a_perp = a_u - np.sum(a_u * n, axis=-1, keepdims=True) * n
    c_perp = c_u - np.sum(c_u * n, axis=-1, keepdims=True) * n
    a_off = np.linalg.norm(a_perp, axis=-1)
    c_off = np.linalg.norm(c_perp, axis=-1)
    # a pair along the axis to rounding pulls nowhere (its ⊥ parts are noise)
    off_axis = (a_off > ALONG_AXIS_SIN) & (c_off > ALONG_AXIS_SIN)
    with np.errstate(divide='ignore'):  # log 0 = −inf for a weight 0: a size 0
        log_size = np.log(w) + _log_norms(a) + _log_norms(c)
    log_size = np.where(off_axis, log_size, -np.inf)
    top = np.max(log_size, axis=-1, keepdims=True)
    size = np.exp(log_size - np.where(np.isfinite(top), top, 0.0))
    sin = np.sum(size * np.sum(np.cross(c_perp, a_perp) * n, axis=-1), axis=-1)
    cos = np.sum(size * np.sum(c_perp * a_perp, axis=-1), axis=-1)
    pull = np.sum(size * a_off * c_off, axis=-1)
    unique = ~off_axis.any(axis=-1) | (np.hypot(sin, cos) > UNIQUE_TOL * pull)
    phi = np.arctan2(sin, cos)
    return _Fit(rotation=axis_angle_to_matrix(a_axis, phi) @ r0, unique=unique)


DOMINANT = 1e-2
"""σ2 ≤ DOMINANT·σ1 of H: align_vectors fits about the dominant direction (_fit_about_dominant).

H's entries carry rounding of ~ε·σ1, so the turn that the SVD's second singular vectors
give is accurate to ~ε·σ1/σ2: 2e-7 rad for weights 1e9 : 1, nothing at all beyond 1e16.
The rotation maximising tr(Rᵀ·H) takes the first right singular vector onto the first left
one, and those are accurate to ~ε·σ1/(σ1 − σ2) ≤ 1.02ε here; the turn about them is then
fitted from the pairs directly.
"""

ALONG_AXIS_SIN = 64 * np.finfo(float).eps
"""|a⊥|/|a| at or below which a pair counts as lying along the dominant axis (rounding)."""


class Alignment(NamedTuple):
    """What align_vectors gives: the best rotation R (..., 3, 3) and its rmsd (...)."""

    R: np.ndarray
    rmsd: np.ndarray


def align_vectors(a, b, weights=None):
    """
    Return the Alignment: the R minimising Σ wᵢ‖aᵢ − R·bᵢ‖² (Wahba, Kabsch), and its rmsd.

    a, b (..., N, 3) → (R (..., 3, 3), rmsd (...)), rmsd = sqrt(Σ wᵢ‖aᵢ − R·bᵢ‖² / Σ wᵢ) in
    the units of a and b; weights (N,) or (..., N), ≥ 0, not all 0 (default equal). R comes
    from the SVD of H = Σ wᵢ·aᵢbᵢᵀ, as mean_rotation's; when one direction dominates H
    (σ2 ≤ DOMINANT·σ1: a weight or a length far above the rest), R takes its first right
    singular vector onto its first left one and the turn about that axis is fitted from the
    pairs directly, so the small pairs still count however large the ratio (1e9, 1e16, ...).
    A single pair, or pairs that are all parallel, give the smallest rotation taking b̂ onto
    â. RotationError for zero vectors, counts that differ, negative or all-zero weights, and a
    best rotation that is not unique.
    """
    a, b = _vectors(a, 'a'), _vectors(b, 'b')
    if not a.shape[-2]:
        raise RotationError('no vector pairs to align (N = 0)')
    if a.shape[-2] != b.shape[-2]:
        raise RotationError(f'a has {a.shape[-2]} vectors but b has {b.shape[-2]}: align '
                            'needs pairs')
    w = _weights(weights, a.shape[-2], 'vector pair')
    try:
        shape = np.broadcast_shapes(a.shape, b.shape, w.shape + (3,))
    except ValueError:
        raise RotationError(f'a {a.shape}, b {b.shape} and weights {w.shape} do not '
                            'broadcast') from None
    # scale a and b separately: H/(|a|max·|b|max) has the same SVD directions
    a_dir = a / np.abs(a).max(axis=(-2, -1), keepdims=True)
    b_dir = b / np.abs(b).max(axis=(-2, -1), keepdims=True)
    h = np.einsum('...n,...ni,...nj->...ij', w, a_dir, b_dir)
    scale = np.einsum('...n,...n,...n->...', w, np.linalg.norm(a_dir, axis=-1),
                      np.linalg.norm(b_dir, axis=-1))
    best = _nearest_rotations(h, 'the best rotation', 'H = Σ wᵢ·aᵢbᵢᵀ', DOMINANT)
    sigma, R, dominant = best.sigma, best.rotation, best.rank_one
    vanishing = sigma[..., 0] <= UNIQUE_TOL * scale
    if vanishing.any():
        index = tuple(int(i) for i in np.argwhere(vanishing)[0])
        raise RotationError(
            'the best rotation is not unique: H = Σ wᵢ·aᵢbᵢᵀ vanishes (|H| = '
            f'{sigma[index][0]:.3g} for Σ wᵢ|aᵢ||bᵢ| = {scale[index]:.3g}, with a and b '
            'scaled to max 1): every rotation fits as well'
            + (f' (item {index})' if index else ''))
    if dominant.any():
        fit = _fit_about_dominant(a_dir, b_dir, w, best.u[..., :, 0], best.vt[..., 0, :])
        unsure = dominant & ~fit.unique
        if unsure.any():
            index = tuple(int(i) for i in np.argwhere(unsure)[0])
            raise RotationError(
                'the best rotation is not unique: about the dominant direction of '
                'H = Σ wᵢ·aᵢbᵢᵀ (σ2 ≤ 0.01·σ1), the other pairs pull equally every way: '
                'every turn about it fits as well' + (f' (item {index})' if index else ''))
        R = np.where(dominant[..., None, None], fit.rotation, R)
    return Alignment(R=R, rmsd=_rmsd(a, b, R, np.broadcast_to(w, shape[:-1])))


def random_rotations(n=None, rng=None):
    """
    Haar-uniform random rotations: (3, 3) for n=None, else (n, 3, 3).

    rng: a numpy.random.Generator, or a seed for numpy.random.default_rng (None: fresh
    entropy). Columns u = g1/|g1|, v = the unit part of g2 ⊥ u, w = u × v for Gaussian
    g1, g2 — a distribution invariant under every rotation, hence Haar; the angle has density
    (1 − cos θ)/π, i.e. P(angle ≤ θ) = (θ − sin θ)/π.
    """
    if n is not None and (not isinstance(n, numbers.Integral) or isinstance(n, bool) or n < 0):
        raise RotationError(f'n must be None or an integer ≥ 0, got {n!r}')
    try:
        gen = np.random.default_rng(rng)
    except (TypeError, ValueError) as exc:
        raise RotationError(f'rng must be a numpy.random.Generator or a seed: {exc}') from None
    count = 1 if n is None else int(n)
    need = count * _BYTES_PER_SAMPLE
    if need > _physical_memory():
        raise RotationError(f'n = {_count(count)} rotations are too many to allocate: about '
                            f'{_bytes(need)} of float64, more than this machine’s memory')
    try:
        return _haar(gen, count, n is None)
    except (MemoryError, ValueError) as exc:  # NumPy: 'array is too big', 'Unable to allocate'
        raise RotationError(f'n = {_count(count)} rotations are too many to allocate: {exc}'
                            ) from None


_BYTES_PER_SAMPLE = 200
"""Peak memory of random_rotations per rotation, in bytes: the Gaussian pairs, u, v, the
result and the temporaries between them."""


def _count(n):
    """Write n as digits, or as 1.0e+400 when it has more than 20."""
    return str(n) if len(str(n)) <= 20 else _bytes(n)[:-len(' bytes')]


def _bytes(count):
    """Write a byte count, e.g. '9.2e+17 bytes' (any size: Python ints do not overflow)."""
    digits = str(count)
    return f'{digits[0]}.{digits[1:2] or "0"}e+{len(digits) - 1} bytes'


def _physical_memory():
    """Bytes of physical memory, or inf where the OS does not say."""
    try:
        return os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES')
    except (AttributeError, OSError, ValueError):
        return math.inf


def _haar(gen, count, single):
    g = gen.standard_normal((count, 2, 3))
    while True:  # a zero or parallel pair has probability 0; redraw it all the same
        u = g[:, 0] / np.linalg.norm(g[:, 0], axis=-1, keepdims=True)
        v = g[:, 1] - np.sum(g[:, 1] * u, axis=-1, keepdims=True) * u
        size = np.linalg.norm(v, axis=-1, keepdims=True)
        bad = (size[:, 0] <= 1e-6 * np.linalg.norm(g[:, 1], axis=-1)) | ~np.isfinite(u[:, 0])
        if not bad.any():
            break
        g[bad] = gen.standard_normal((int(bad.sum()), 2, 3))
    v = v - np.sum(v * u, axis=-1, keepdims=True) * u  # twice is enough: ⊥ u to rounding
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    out = np.stack([u, v, np.cross(u, v)], axis=-1)
    return out[0] if single else out
