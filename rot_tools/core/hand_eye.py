"""
Hand-eye calibration: the rigid transform between two joined bodies, from their motion.

Two bodies A and B are rigidly joined; each reports its pose in its own fixed world,
T_A(t) = (R_a, b_a) and T_B(t) = (R_b, b_b) (R maps the body's coordinates to its world's,
as everywhere in rot_tools). The constant transforms between them are

    T_A(t)·X = Z·T_B(t)

with **X** body B's pose in body A's frame and **Z** world B's pose in world A's frame. Eye in
hand: A the hand in the robot's base, B the camera in the marker's frame: X is the camera on
the hand, Z the marker in the base. The relative motions of two samples i, j,
A_ij = T_A(i)⁻¹·T_A(j) and B_ij = T_B(i)⁻¹·T_B(j), then satisfy A_ij·X = X·B_ij: one screw
seen from two frames (Chasles' theorem; Jia, Rotation in the Space, §5). Their rotation
angles and their translations along the screw axis are equal whatever X is: Chen's screw
congruence, which tells a bad sample before X is known.

hand_eye, step by step:

1. **Time.** An offset o is added to B's stamps: given, or found from the angular speeds,
   which do not depend on X (estimate_time_offset).
2. **Matching.** B along its constant-screw motion at A's stamps (interpolate_poses).
3. **Pairs** of matched samples whose motion in A turns by at least min_angle: all of them
   for up to ALL_PAIRS samples, else each sample with partners at PAIR_LAGS lags spread
   geometrically over the recording.
4. **Congruence** (screw_congruence). A sample is rejected when the median, over its pairs,
   of the difference in angle or in translation along the axis exceeds REJECT_LIMIT times
   the robust standard deviation (1.4826 × the median absolute deviation) of all pairs.
5. **X.** Its rotation from the rotation vectors α_ij = R_X·β_ij (Park and Martin,
   hand_eye_rotation); when A turns about one axis u only, the turn about u comes from the
   translations. Its translation from (R_Aij − I)·t_X = R_X·t_Bij − t_Aij (linear least
   squares). Then both by Gauss–Newton on every kept pair's residuals: the rotation
   log(R_Aij·R_X·R_Bijᵀ·R_Xᵀ) and that translation equation, each weighted by the inverse of
   its mean square. **Z** is the mean of T_A(k)·X·T_B(k)⁻¹ over the kept samples.
6. **What the motion cannot tell.** Translation along an axis about which A never turns
   cannot be seen ((R_Aij − I)·u = 0 for every pair): it is set to 0 and the axis listed in
   ``unobservable``.
7. **Uncertainty.** One standard deviation of each of X's parameters by the delete-a-group
   jackknife (up to JACKKNIFE_GROUPS groups of consecutive samples, each group's pairs
   removed in turn, one Gauss–Newton step from the solution): it holds for pairs that share
   samples and for noise that follows the stream.
"""

__all__ = ['hand_eye', 'HandEyeCalibration', 'screw_congruence', 'ScrewCongruence']

import math
from typing import NamedTuple

import numpy as np
from rot_tools.core._arrays import finite_array, require_tolerance
from rot_tools.core.axis_angle import axis_angle_to_matrix, matrix_to_rotvec
from rot_tools.core.errors import RotationError
from rot_tools.core.fitting import mean_rotation
from rot_tools.core.rigid import compose_transforms, invert_transform, Motion
from rot_tools.core.screw import screw_from_transform
from rot_tools.core.so3 import checked_rotation, skew
from rot_tools.core.stamps import checked_stamps, plain
from rot_tools.core.trajectory import (
    estimate_time_offset, EXCITED_RATIO, hand_eye_rotation, interpolate_poses)

DEFAULT_MIN_ANGLE = math.radians(5.0)
"""Turn (rad) a pair's motion must reach to be used: smaller turns leave the axis to noise."""

ALL_PAIRS = 200
"""Samples up to which every pair of them is formed."""

PAIR_LAGS = 24
"""Lags at which each sample of a longer recording gets a partner (spread geometrically)."""

MAX_PAIRS = 100_000
"""Pairs of a longer recording at most (about): enough for its noise, few enough for speed."""

REJECT_LIMIT = 5.0
"""Robust standard deviations of all pairs beyond which a sample's median difference rejects it."""

NEAR_HALF_TURN = math.radians(170.0)
"""Turn (rad) above which the screw axis' sign is set by noise: translations compared by size."""

JACKKNIFE_GROUPS = 25
"""Groups of consecutive samples of the jackknife (each sample its own group below this)."""

LEAST_SAMPLES = 3
"""Matched samples needed: two give one relative motion, which leaves a turn free."""

ITERATIONS = 20
"""Gauss–Newton steps at most; it stops once a step changes X by less than rounding."""

REACH = 1e150
"""Positions at most this far from the origin (m): beyond, squared residuals overflow float64."""


class ScrewCongruence(NamedTuple):
    """
    The screws of paired relative motions in A and in B (screw_congruence); (P,) each.

    pairs (P, 2): sample indices (i, j), i < j; angle_a, angle_b: θ ∈ [0, π] of A_ij and B_ij;
    translation_a, translation_b: their translations d along the screw axis (signed; by size
    above NEAR_HALF_TURN, where the axis' sign is set by noise).
    """

    pairs: np.ndarray
    angle_a: np.ndarray
    angle_b: np.ndarray
    translation_a: np.ndarray
    translation_b: np.ndarray


class Rejection(NamedTuple):
    """A rejected sample: its stamp (s, A's clock) and why, in words."""

    stamp: float
    reason: str


class Residual(NamedTuple):
    """RMS over the kept pairs of the rotation residual (rad) and the translation residual."""

    rotation: float
    translation: float


class Sigma(NamedTuple):
    """
    One standard deviation of each of X's rotation angles and translation components.

    rotation (3,) rad, about body A's x, y, z (the small turn δ with X_true = exp(δ)·X), and
    translation (3,) along them; inf where not observable.
    """

    rotation: np.ndarray
    translation: np.ndarray


class HandEyeCalibration(NamedTuple):
    """
    The result of hand_eye.

    X: Motion(R, b), body B's pose in body A's frame; Z: Motion(R, b), world B's pose in world
    A's frame (T_A·X = Z·T_B); offset: s added to B's stamps; correlation: of the angular
    speeds at that offset (NaN when it was given); samples: matched samples; pairs: pairs
    used; rejected: tuple of Rejection; residual: Residual; sigma: Sigma; unobservable (M, 3):
    unit axes of body A along which X's translation is not determined (set to 0).
    """

    X: Motion
    Z: Motion
    offset: float
    correlation: float
    samples: int
    pairs: int
    rejected: tuple
    residual: Residual
    sigma: Sigma
    unobservable: np.ndarray


# ---- pairs and their screws --------------------------------------------------------------


def _poses(R, b, name, count=None):
    """Return rotations (N, 3, 3) and positions (N, 3) checked, N = count when given."""
    R = checked_rotation(R, True)
    b = finite_array(b, (3,), f'{name}: positions')
    if R.ndim != 3 or b.shape != (len(R), 3):
        raise RotationError(f'{name}: rotations (N, 3, 3) and positions (N, 3) expected, got '
                            f'{R.shape} and {b.shape}')
    if count is not None and len(R) != count:
        raise RotationError(f'{name} has {len(R)} poses for {count} stamps')
    return R, b


def _require_reach(b, name):
    """Raise RotationError when a position of ``b`` lies beyond REACH of the origin."""
    far = float(np.max(np.abs(b), initial=0.0))
    if far > REACH:
        raise RotationError(f'{name}: positions reach {far:.3g}, beyond ±{REACH:.0e}, where '
                            "hand_eye's squared residuals would overflow float64")


def sample_pairs(count):
    """
    Index pairs (P, 2), i < j, of ``count`` samples: all pairs up to ALL_PAIRS samples.

    Beyond, pairs (i, i + L) at PAIR_LAGS lags L spread geometrically from 1 to count − 1
    (short and long intervals alike), at most about MAX_PAIRS of them: each lag takes every
    s-th start, the starts of successive lags shifted by one, so every sample has partners.
    """
    if count <= ALL_PAIRS:
        i, j = np.triu_indices(count, 1)
        return np.column_stack([i, j])
    lags = np.unique(np.rint(np.geomspace(1, count - 1, PAIR_LAGS)).astype(np.int64))
    stride = max(1, math.ceil(count * len(lags) / MAX_PAIRS))
    parts = []
    for n, lag in enumerate(lags):
        i = np.arange(n % stride, count - lag, stride)
        parts.append(np.column_stack([i, i + lag]))
    return np.concatenate(parts)


def _relative(R, b, pairs):
    """Relative motions T(i)⁻¹·T(j) of the pairs: Motion (P, 3, 3), (P, 3)."""
    i, j = pairs[:, 0], pairs[:, 1]
    return compose_transforms(*invert_transform(R[i], b[i], check=False), R[j], b[j],
                              check=False)


def _screw_numbers(motion):
    """Return angle θ and translation d along the axis of motions; |d| near a half turn."""
    screw = screw_from_transform(motion.R, motion.b, check=False)
    d = np.where(screw.angle > NEAR_HALF_TURN, np.abs(screw.translation), screw.translation)
    return screw.angle, d


def _pair_indices(pairs, count):
    """Return ``pairs`` as int64 (P, 2), whole numbers in [0, count); else raise RotationError."""
    given = finite_array(pairs, (), 'pairs')
    if given.ndim != 2 or given.shape[1] != 2:
        raise RotationError(f'pairs must have shape (P, 2), got {given.shape}')
    wrong = (given < 0) | (given >= count) | (given != np.floor(given))
    if wrong.any():
        first = tuple(int(i) for i in np.argwhere(wrong)[0])
        raise RotationError(f'pairs must be whole sample indices in [0, {count}), got '
                            f'{plain(given[first])} at index {first}')
    return given.astype(np.int64)


def screw_congruence(R_a, b_a, R_b, b_b, pairs=None):
    """
    Return the screws of the relative motions of matched samples, in A and in B.

    R_a, R_b (K, 3, 3), b_a, b_b (K, 3): the poses of A and B at the same K instants. pairs
    (P, 2) of sample indices, default sample_pairs(K). For a rigid joint A_ij·X = X·B_ij,
    so each pair's angles agree and its translations along the axis agree (Chen), whatever
    X is; a difference is noise, a bad sample or a joint that is not rigid. Returns
    ScrewCongruence.
    """
    R_a, b_a = _poses(R_a, b_a, 'A')
    R_b, b_b = _poses(R_b, b_b, 'B', len(R_a))
    pairs = sample_pairs(len(R_a)) if pairs is None else _pair_indices(pairs, len(R_a))
    angle_a, d_a = _screw_numbers(_relative(R_a, b_a, pairs))
    angle_b, d_b = _screw_numbers(_relative(R_b, b_b, pairs))
    return ScrewCongruence(pairs=pairs, angle_a=angle_a, angle_b=angle_b,
                           translation_a=d_a, translation_b=d_b)


# ---- rejection by congruence -------------------------------------------------------------


def _robust_scale(x, floor):
    """1.4826 × the median absolute deviation of x about its median, at least floor."""
    return max(1.4826 * float(np.median(np.abs(x - np.median(x)))), floor)


def _sample_medians(pairs, x, count):
    """Median of |x| over each sample's pairs (count,); NaN for a sample in no pair."""
    ends = np.concatenate([pairs[:, 0], pairs[:, 1]])
    values = np.abs(np.concatenate([x, x]))
    order = np.lexsort((values, ends))
    ends, values = ends[order], values[order]
    start = np.searchsorted(ends, np.arange(count))
    stop = np.searchsorted(ends, np.arange(count), side='right')
    out = np.full(count, np.nan)
    has = stop > start
    first, size = start[has], stop[has] - start[has]
    out[has] = (values[first + (size - 1) // 2] + values[first + size // 2]) / 2
    return out


def _reject(congruence, stamps, length):
    """
    Return a bool (K,) of the samples kept and the Rejection of each sample dropped.

    length: a length of the data's scale, for the translations' floor.
    """
    pairs = congruence.pairs
    count = len(stamps)
    checks = (
        (congruence.angle_b - congruence.angle_a, 1e-9, 'screw angles',
         lambda x: f'{math.degrees(x):.3g}°'),
        (congruence.translation_b - congruence.translation_a, 1e-9 * length,
         'translations along the screw axis', lambda x: f'{x:.3g}'))
    keep = np.ones(count, bool)
    reasons = {}
    for difference, floor, what, shown in checks:
        centre = float(np.median(difference))
        scale = _robust_scale(difference, floor)
        medians = _sample_medians(pairs, difference - centre, count)
        bad = medians > REJECT_LIMIT * scale
        for k in np.flatnonzero(bad & keep):
            n = int(np.sum(pairs == k))
            reasons[k] = (f'its motions differ in A and B by {shown(medians[k])} in their {what} '
                          f'(median over its {n} pairs; all pairs spread by {shown(scale)})')
        keep &= ~bad
    return keep, tuple(Rejection(float(stamps[k]), reasons[k]) for k in sorted(reasons))


# ---- the solution ------------------------------------------------------------------------


class _Pairs(NamedTuple):
    """Relative motions of the kept pairs in A (RA, tA) and B (RB, tB), and the pairs."""

    RA: np.ndarray
    tA: np.ndarray
    RB: np.ndarray
    tB: np.ndarray
    index: np.ndarray


def _residuals(p, R, t):
    """Rotation (P, 3) log(R_A·R·R_Bᵀ·Rᵀ) and translation (P, 3) (R_A − I)·t − R·t_B + t_A."""
    E = np.einsum('pij,pjk->pik', p.RA, R @ np.swapaxes(p.RB, 1, 2) @ R.T)
    rotation = matrix_to_rotvec(E, check=False)
    translation = (p.RA @ t) - t - p.tB @ R.T + p.tA
    return rotation, translation


def _jacobians(p, R, basis):
    """
    Jacobians (P, 6, n) of the residuals in the parameters (δ, t) of ``basis`` (6, n).

    In (δ, t): rotation [R_A − I, 0], translation [[R·t_B]×, R_A − I]; δ a small turn of X in
    A's frame (R ← exp(δ)·R).
    """
    M = p.RA - np.eye(3)
    rotation = np.einsum('pij,jk->pik', M, basis[:3])
    translation = (np.einsum('pij,jk->pik', skew(p.tB @ R.T), basis[:3])
                   + np.einsum('pij,jk->pik', M, basis[3:]))
    return np.concatenate([rotation, translation], axis=1)


def _observable(p):
    """
    Return (basis (3, 3 − M) of the observable translations, unobservable axes (M, 3)).

    The translation is seen through S = Σ (R_A − I)ᵀ(R_A − I); an eigen-direction whose
    √(λ/λ_max) is below EXCITED_RATIO is an axis that A (almost) never turns about.
    """
    M = p.RA - np.eye(3)
    lam, vec = np.linalg.eigh(np.einsum('pki,pkj->ij', M, M))
    seen = np.sqrt(np.maximum(lam, 0.0) / lam[-1]) >= EXCITED_RATIO
    axes = vec[:, ~seen].T
    axes *= np.sign(axes[np.arange(len(axes)), np.argmax(np.abs(axes), axis=1)])[:, None]
    return vec[:, seen], axes


def _basis(translation_basis):
    """Parameter basis (6, n): the three turns of X and its observable translations."""
    n = translation_basis.shape[1]
    B = np.zeros((6, 3 + n))
    B[:3, :3] = np.eye(3)
    B[3:, 3:] = translation_basis
    return B


def _turn_about_axis(p, R0, axis, basis):
    """
    Return (R, t) when A turns about ``axis`` only: R = Rot(axis, ψ)·R0, ψ from the translations.

    (R_A − I)·t − Rot(ψ)·v = −t_A, v = R0·t_B, is linear in t (in the observable ``basis``)
    and in (cos ψ, sin ψ): Rot(ψ)·v = cos ψ·v⊥ + sin ψ·u × v + (u·v)·u.
    """
    u = axis
    v = p.tB @ R0.T
    along = (v @ u)[:, None] * u
    columns = np.concatenate([(p.RA - np.eye(3)) @ basis,
                              -(v - along)[:, :, None], -np.cross(u, v)[:, :, None]], axis=2)
    rhs = along - p.tA
    solution = np.linalg.lstsq(columns.reshape(-1, columns.shape[2]), rhs.reshape(-1),
                               rcond=None)[0]
    c, s = solution[-2:]
    R = axis_angle_to_matrix(u, math.atan2(s, c)) @ R0
    return R, basis @ _translation(p, R, basis)


def _translation(p, R, basis):
    """Coordinates in ``basis`` of t minimising Σ|(R_A − I)·t − R·t_B + t_A|² (least squares)."""
    A = ((p.RA - np.eye(3)) @ basis).reshape(-1, basis.shape[1])
    rhs = (p.tB @ R.T - p.tA).reshape(-1)
    return np.linalg.lstsq(A, rhs, rcond=None)[0]


class _Fit(NamedTuple):
    R: np.ndarray
    t: np.ndarray
    weights: np.ndarray  # (6,): 1/mean square of the rotation and translation residuals
    basis: np.ndarray  # (6, n) of the parameters


def _weights(rotation, translation, floors):
    """Return W (6,): the inverse mean squares of the rotation and translation residuals."""
    w = [1.0 / max(float(np.mean(r * r)), f * f) for r, f in zip((rotation, translation), floors)]
    return np.repeat(w, 3)


def _normal_sums(p, fit, members=None):
    """
    Return Jᵀ·W·J (n, n) and Jᵀ·W·r (n,) summed over the pairs.

    With members (P, G) of 0 and 1, one sum per column instead: over the pairs of each
    group, (G, n, n) and (G, n).
    """
    rotation, translation = _residuals(p, fit.R, fit.t)
    r = np.concatenate([rotation, translation], axis=1)
    J = _jacobians(p, fit.R, fit.basis)
    WJ = fit.weights[None, :, None] * J
    if members is None:
        return np.einsum('pki,pkj->ij', WJ, J), np.einsum('pki,pk->i', WJ, r)
    n = J.shape[2]
    each = np.einsum('pki,pkj->pij', WJ, J).reshape(len(J), n * n)
    return (members.T @ each).reshape(-1, n, n), members.T @ np.einsum('pki,pk->pi', WJ, r)


def _step(fit, delta):
    """Move the fit by −delta (parameter basis): R ← exp(−δ)·R, t ← t − Δt."""
    d = fit.basis @ delta
    turn = -d[:3]
    angle = float(np.linalg.norm(turn))
    R = fit.R if angle == 0 else axis_angle_to_matrix(turn, angle) @ fit.R
    return fit._replace(R=R, t=fit.t - d[3:])


def _refine(p, R, t, basis, floors):
    """Gauss–Newton on the weighted residuals of all pairs, from (R, t); returns a _Fit."""
    fit = _Fit(R, t, _weights(*_residuals(p, R, t), floors), _basis(basis))
    for _ in range(ITERATIONS):
        H, g = _normal_sums(p, fit)
        _require_determined(H)
        delta = np.linalg.solve(H, g)
        fit = _step(fit, delta)
        fit = fit._replace(weights=_weights(*_residuals(p, fit.R, fit.t), floors))
        if np.max(np.abs(delta[:3])) < 1e-12 and np.max(np.abs(delta[3:]), initial=0.0) < (
                1e-12 * max(1.0, float(np.linalg.norm(fit.t)))):
            break
    return fit


def _require_determined(H):
    """
    Raise RotationError when the normal equations leave a turn of X free.

    The turns' information once the translations are fitted is the Schur complement
    S = H_δδ − H_δt·H_tt⁻¹·H_tδ; a turn whose eigenvalue of S is nothing beside the largest
    changes no residual.
    """
    S = H[:3, :3] - H[:3, 3:] @ np.linalg.solve(H[3:, 3:], H[3:, :3]) if len(H) > 3 else H
    lam, vec = np.linalg.eigh(S)
    if not lam[0] > 1e-12 * lam[-1]:
        raise RotationError(
            'the motion does not determine X: the turn about '
            f'{np.array2string(vec[:, 0], precision=3)} (in A) changes no residual (a turn '
            'about one axis, with no translation across it)')


def _jackknife(p, fit, groups):
    """
    Return the standard deviations (n,) of the parameters by the delete-a-group jackknife.

    groups (K,) the group of each sample; removing a group removes every pair that touches
    it, and the solution moves by one Gauss–Newton step on the rest: H₋g⁻¹·Σ_g Jᵀ·W·r.
    """
    count = int(groups.max()) + 1
    ends = groups[p.index]
    members = (ends[:, :1] == np.arange(count)) | (ends[:, 1:] == np.arange(count))
    H, g = _normal_sums(p, fit, np.column_stack([np.ones(len(ends)), members]))
    try:
        moves = np.linalg.solve(H[0] - H[1:], g[1:, :, None])[:, :, 0]
    except np.linalg.LinAlgError:
        return np.full(g.shape[1], np.inf)
    spread = (count - 1) / count * np.sum((moves - moves.mean(axis=0)) ** 2, axis=0)
    return np.sqrt(spread)


def _sigma(p, fit, groups, unobservable):
    """Sigma of X in A's axes from the jackknife, inf along the unobservable axes."""
    deviation = _jackknife(p, fit, groups)
    rotation = deviation[:3]
    n = fit.basis.shape[1] - 3
    translation = np.sqrt((fit.basis[3:, 3:] ** 2) @ (deviation[3:] ** 2)) if n else np.zeros(3)
    if len(unobservable):
        translation = np.where(np.abs(unobservable).max(axis=0) >= EXCITED_RATIO, np.inf,
                               translation)
    return Sigma(rotation=rotation, translation=translation)


def _groups(count):
    """Group (count,) of each of ``count`` samples: JACKKNIFE_GROUPS runs of consecutive ones."""
    g = min(count, JACKKNIFE_GROUPS)
    return np.arange(count) * g // count


# ---- the whole ---------------------------------------------------------------------------


def _matched(stamps_a, R_a, b_a, stamps_b, R_b, b_b, offset, max_gap):
    """Return A's samples with B interpolated at their stamps (B's stamps shifted by offset)."""
    with np.errstate(over='ignore'):
        at = stamps_a - offset  # B's clock
    lo, hi = max(at[0], stamps_b[0]), min(at[-1], stamps_b[-1])
    if not lo <= hi:
        raise RotationError(
            f'no overlap in time: A spans [{plain(stamps_a[0])}, {plain(stamps_a[-1])}] s, '
            f'B [{plain(stamps_b[0] + offset)}, {plain(stamps_b[-1] + offset)}] s '
            f'(offset {plain(offset)} s added)')
    pose = interpolate_poses(stamps_b, R_b, b_b, at, max_gap)
    covered = pose.covered
    if covered.sum() < LEAST_SAMPLES:
        raise RotationError(
            f'{int(covered.sum())} sample(s) of A have B within max_gap = {plain(max_gap)} s: '
            f'at least {LEAST_SAMPLES} needed')
    return stamps_a[covered], R_a[covered], b_a[covered], pose.R, pose.b


def _turning_pairs(R_a, min_angle):
    """Return the sample pairs whose motion in A turns by at least min_angle; error if none."""
    pairs = sample_pairs(len(R_a))
    angle = np.linalg.norm(matrix_to_rotvec(
        np.swapaxes(R_a[pairs[:, 0]], 1, 2) @ R_a[pairs[:, 1]], check=False), axis=1)
    if not (angle >= min_angle).any():
        raise RotationError(
            f'A never turns by min_angle = {math.degrees(min_angle):.3g}° between two samples '
            f'(at most {math.degrees(float(angle.max())):.3g}°): no turn, no hand-eye')
    return pairs[angle >= min_angle]


def _initial(p, basis, axes):
    """Return X's rotation and translation before refinement."""
    R = hand_eye_rotation(p.RA, p.RB).rotation
    if len(axes):
        return _turn_about_axis(p, R, axes[0], basis)
    return R, basis @ _translation(p, R, basis)


def _z(R_a, b_a, R_b, b_b, X):
    """Z = mean over samples of T_A·X·T_B⁻¹: the chordal mean rotation, the mean translation."""
    AX = compose_transforms(R_a, b_a, X.R, X.b, check=False)
    Zk = compose_transforms(*AX, *invert_transform(R_b, b_b, check=False), check=False)
    return Motion(R=mean_rotation(Zk.R, check=False), b=Zk.b.mean(axis=0))


def hand_eye(stamps_a, R_a, b_a, stamps_b, R_b, b_b, *, offset=0.0, max_offset=1.0,
             max_gap=0.1, min_angle=DEFAULT_MIN_ANGLE):
    """
    X and Z with T_A(t)·X = Z·T_B(t) from the poses of two joined bodies (module docstring).

    stamps_a (N,), R_a (N, 3, 3), b_a (N, 3): body A's poses in world A; stamps_b (M,),
    R_b, b_b: body B's in world B; stamps strictly increasing, seconds. offset: seconds added
    to B's stamps, or 'auto' (found within ±max_offset from the angular speeds); max_gap
    (s): B is interpolated at a stamp of A only where its neighbours lie within it;
    min_angle (rad): the least turn of a pair used. Returns HandEyeCalibration.
    RotationError for positions beyond ±REACH, no overlap in time, fewer than LEAST_SAMPLES
    matched samples (or kept), no pair that turns by min_angle, or motion that leaves X's
    rotation free.
    """
    stamps_a = checked_stamps(stamps_a, 'stamps_a', LEAST_SAMPLES)
    stamps_b = checked_stamps(stamps_b, 'stamps_b', 2)
    R_a, b_a = _poses(R_a, b_a, 'A', len(stamps_a))
    R_b, b_b = _poses(R_b, b_b, 'B', len(stamps_b))
    _require_reach(b_a, 'A')
    _require_reach(b_b, 'B')
    min_angle = require_tolerance(min_angle, 'min_angle')
    correlation = math.nan
    if isinstance(offset, str) and offset == 'auto':
        found = estimate_time_offset(stamps_b, R_b, stamps_a, R_a, max_offset)
        offset, correlation = found.offset, found.correlation
    offset = finite_array(offset, (), "offset (s, or 'auto')")
    if offset.ndim:
        raise RotationError(f'offset must be one number of seconds, got shape {offset.shape}')
    offset = float(offset)
    stamps, R_a, b_a, R_b, b_b = _matched(stamps_a, R_a, b_a, stamps_b, R_b, b_b, offset,
                                          max_gap)
    pairs = _turning_pairs(R_a, min_angle)
    length = max(float(np.sqrt(np.mean(b_a ** 2))), float(np.sqrt(np.mean(b_b ** 2))), 1e-6)
    keep, rejected = _reject(screw_congruence(R_a, b_a, R_b, b_b, pairs), stamps, length)
    if keep.sum() < LEAST_SAMPLES:
        raise RotationError(f'{int(keep.sum())} of {len(keep)} samples kept after '
                            f'{len(rejected)} disagreed: at least {LEAST_SAMPLES} needed')
    pairs = pairs[keep[pairs[:, 0]] & keep[pairs[:, 1]]]
    if not len(pairs):
        raise RotationError('no pair of the kept samples turns by min_angle = '
                            f'{math.degrees(min_angle):.3g}°')
    A, B = _relative(R_a, b_a, pairs), _relative(R_b, b_b, pairs)
    p = _Pairs(RA=A.R, tA=A.b, RB=B.R, tB=B.b, index=pairs)
    basis, unobservable = _observable(p)
    R, t = _initial(p, basis, unobservable)
    fit = _refine(p, R, t, basis, (1e-12, 1e-12 * length))
    X = Motion(R=fit.R, b=fit.t)
    rotation, translation = _residuals(p, fit.R, fit.t)
    residual = Residual(float(np.sqrt(np.mean(np.sum(rotation ** 2, 1)))),
                        float(np.sqrt(np.mean(np.sum(translation ** 2, 1)))))
    used = np.cumsum(keep) - 1
    groups = _groups(int(keep.sum()))[used]  # the kept samples' groups, by sample index
    return HandEyeCalibration(
        X=X, Z=_z(R_a[keep], b_a[keep], R_b[keep], b_b[keep], X), offset=offset,
        correlation=correlation, samples=len(stamps), pairs=len(pairs), rejected=rejected,
        residual=residual, sigma=_sigma(p, fit, groups, unobservable), unobservable=unobservable)
