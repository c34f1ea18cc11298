"""Comparing, averaging, fitting and sampling rotations, against scipy and closed forms."""

import re

import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    align_vectors, euler_to_matrix, is_rotation, matrix_to_axis_angle, mean_rotation,
    random_rotations, rotation_distance, RotationError, UNIQUE_TOL)
from scipy import optimize, stats
from scipy.spatial.transform import Rotation

N = 10_000
PI = h.PI
EPS = np.finfo(float).eps


def rodrigues(axis, angle):
    axis = np.asarray(axis, dtype=float)
    return h.notes_rodrigues_eq7(axis / np.linalg.norm(axis, axis=-1, keepdims=True), angle)


# ---- rotation_distance ---------------------------------------------------------------------


def test_distance_matches_scipy():
    r1, r2 = h.scipy_rotations(N, 1), h.scipy_rotations(N, 2)
    got = rotation_distance(r1, r2)
    assert got.shape == (N,)
    ref = (Rotation.from_matrix(r1).inv() * Rotation.from_matrix(r2)).magnitude()
    assert h.max_abs(got - ref) <= 1e-14
    assert np.all((got >= 0) & (got <= PI))


@pytest.mark.parametrize('angle', [0.0, 1e-300, 1e-15, 1e-12, 1e-8, 1e-4, 1.0, 3.0,
                                   PI - 1e-4, PI - 1e-8, PI - 1e-9, PI - 1e-12, PI])
def test_distance_is_accurate_to_rounding_at_0_and_pi(angle):
    # R2 = R1·Rot_l̂(θ): the distance is θ, to a few ulps of 1 (the rounding of R1·Rot).
    rng = np.random.default_rng(100)
    r1 = h.scipy_rotations(200, 3)
    axis = h.random_unit_vectors(rng, 200)
    r2 = r1 @ h.notes_rodrigues_eq7(axis, np.full(200, angle))
    got = rotation_distance(r1, r2)
    assert h.max_abs(got - angle) <= 8 * EPS
    # acos((tr R1ᵀR2 − 1)/2) loses half the digits here; the atan2 form does not
    if 0 < angle <= 1e-8 or PI - 1e-8 <= angle < PI:
        cos = (np.einsum('nij,nij->n', r1, r2) - 1) / 2
        assert h.max_abs(np.arccos(np.clip(cos, -1, 1)) - angle) > 100 * 8 * EPS


def test_distance_of_equal_rotations_is_exactly_zero():
    r = h.scipy_rotations(1000, 4)
    assert np.array_equal(rotation_distance(r, r), np.zeros(1000))


def test_distance_symmetry_and_invariance():
    r1, r2, q = h.scipy_rotations(1000, 5), h.scipy_rotations(1000, 6), h.scipy_rotations(1000, 7)
    d = rotation_distance(r1, r2)
    assert h.max_abs(rotation_distance(r2, r1) - d) <= 4 * EPS
    assert h.max_abs(rotation_distance(q @ r1, q @ r2) - d) <= 16 * EPS
    # not right-invariant in general, but the distance of R·Q and R is |angle of Q|
    _, angle = matrix_to_axis_angle(q)
    assert h.max_abs(rotation_distance(r1 @ q, r1) - angle) <= 16 * EPS


def test_distance_broadcasting_and_single_items():
    r = h.scipy_rotations(12, 8).reshape(3, 4, 3, 3)
    got = rotation_distance(r, r[0, 0])
    assert got.shape == (3, 4) and got[0, 0] == 0.0
    assert np.ndim(rotation_distance(r[1, 2], r[2, 1])) == 0
    for i in range(3):
        for j in range(4):
            assert abs(rotation_distance(r[i, j], r[0, 0]) - got[i, j]) <= 2 * EPS


def test_distance_validates_both_rotations():
    bad = np.eye(3)
    bad[0, 1] = 1e-6
    with pytest.raises(RotationError, match=r'R1 is not orthogonal'):
        rotation_distance(bad, np.eye(3))
    with pytest.raises(RotationError, match=r'R2 is a reflection'):
        rotation_distance(np.eye(3), np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(RotationError, match=r'R2 must have shape'):
        rotation_distance(np.eye(3), np.eye(2))


def test_distance_check_false_uses_the_matrices_as_given():
    # without the check, θ = atan2(|skew(M)|, (tr M − 1)/2) of M = R1ᵀR2 as given
    m1 = h.ref_elementary('z', 0.3) * 1.001
    m2 = h.ref_elementary('z', 1.0)
    m = m1.T @ m2
    w = 0.5 * np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])
    ref = np.arctan2(np.linalg.norm(w), (np.trace(m) - 1) / 2)
    assert abs(rotation_distance(m1, m2, check=False) - ref) <= 4 * EPS
    assert abs(ref - 0.7) > 1e-4


# ---- mean_rotation -------------------------------------------------------------------------


def clusters(n_sets, size, spread, seed):
    """n_sets clusters of `size` rotations spread around a random centre."""
    rng = np.random.default_rng(seed)
    centre = h.scipy_rotations(n_sets, seed)
    axis = h.random_unit_vectors(rng, n_sets * size).reshape(n_sets, size, 3)
    angle = rng.uniform(0, spread, (n_sets, size))
    return centre[:, None] @ h.notes_rodrigues_eq7(axis, angle)


@pytest.mark.parametrize('spread', [0.1, 1.0, 2.5])
def test_mean_matches_scipy(spread):
    r = clusters(300, 7, spread, 9)
    rng = np.random.default_rng(10)
    weights = rng.uniform(0, 2, 7)
    for w in (None, weights):
        got = mean_rotation(r, w)
        assert got.shape == (300, 3, 3)
        ref = np.array([Rotation.from_matrix(x).mean(weights=w).as_matrix() for x in r])
        assert h.max_abs(got - ref) <= 1e-13
        assert np.all(is_rotation(got, tol=1e-14))


def test_mean_maximises_the_trace_against_random_rotations():
    # The chordal mean M maximises tr(Mᵀ·Σ wᵢRᵢ): no other rotation does better.
    r = clusters(50, 5, 2.0, 11)
    w = np.array([1.0, 0.5, 2.0, 0.0, 1.0])
    s = np.einsum('n,knij->kij', w, r)
    best = np.einsum('kij,kij->k', mean_rotation(r, w), s)
    others = h.scipy_rotations(2000, 12)
    assert np.all(best[:, None] >= np.einsum('qij,kij->kq', others, s) - 1e-12)


def test_mean_of_rotations_about_one_axis_is_the_circular_mean():
    # Σ wᵢ Rot_z(θᵢ) = [[C, −S, 0], [S, C, 0], [0, 0, Σw]]: the nearest rotation is
    # Rot_z(atan2(S, C)) with S = Σ wᵢ sin θᵢ, C = Σ wᵢ cos θᵢ.
    rng = np.random.default_rng(13)
    for _ in range(200):
        theta = rng.uniform(-PI, PI, 5)
        w = rng.uniform(0, 1, 5)
        got = mean_rotation(h.ref_elementary('z', theta), w)
        ref = h.ref_elementary('z', np.arctan2(w @ np.sin(theta), w @ np.cos(theta)))
        assert h.max_abs(got - ref) <= 1e-14


def test_mean_closed_forms():
    a = 0.4
    r = h.ref_elementary('x', np.array([a, -a]))
    assert h.max_abs(mean_rotation(r) - np.eye(3)) <= 2 * EPS
    one = h.scipy_rotations(1, 14)
    assert h.max_abs(mean_rotation(one) - one[0]) <= 4 * EPS
    # nearly π apart is still unique: the geodesic midpoint
    r = h.ref_elementary('y', np.array([0.0, PI - 1e-6]))
    assert h.max_abs(mean_rotation(r) - h.ref_elementary('y', (PI - 1e-6) / 2)) <= 1e-9


def test_mean_invariances_and_weights():
    r = clusters(1, 6, 1.5, 15)[0]
    q = h.scipy_rotations(1, 16)[0]
    m = mean_rotation(r)
    assert h.max_abs(mean_rotation(q @ r) - q @ m) <= 1e-14
    assert h.max_abs(mean_rotation(r @ q) - m @ q) <= 1e-14
    w = np.array([1.0, 2.0, 0.0, 3.0, 0.5, 1.0])
    assert h.max_abs(mean_rotation(r, 1e-200 * w) - mean_rotation(r, w)) <= 1e-15 * 4
    assert h.max_abs(mean_rotation(r, 1e300 * w) - mean_rotation(r, w)) <= 1e-15 * 4
    # a zero weight drops the rotation
    assert h.max_abs(mean_rotation(r, w) - mean_rotation(np.delete(r, 2, 0), np.delete(w, 2))
                     ) <= 1e-14


def test_mean_batch_shapes_and_per_set_weights():
    r = clusters(6, 4, 1.0, 17).reshape(2, 3, 4, 3, 3)
    w = np.random.default_rng(18).uniform(0.1, 1, (2, 3, 4))
    got = mean_rotation(r, w)
    assert got.shape == (2, 3, 3, 3)
    for i in range(2):
        for j in range(3):
            assert h.max_abs(got[i, j] - mean_rotation(r[i, j], w[i, j])) <= 4 * EPS
    assert mean_rotation(r, w[0, 0]).shape == (2, 3, 3, 3)


def test_mean_of_rotations_pi_apart_with_equal_weights_is_refused():
    for r in (np.stack([np.eye(3), h.ref_elementary('z', PI)]),
              np.stack([h.ref_elementary('x', 0.3), h.ref_elementary('x', 0.3 + PI)]),
              rodrigues([[1, 2, 3]] * 2, [0.0, PI])):
        with pytest.raises(RotationError, match=r'mean rotation is not unique: Σ wᵢRᵢ is '
                                                r'rank-deficient .*π apart'):
            mean_rotation(r)
    # with unequal weights the heavier one wins
    r = np.stack([np.eye(3), h.ref_elementary('z', PI)])
    assert h.max_abs(mean_rotation(r, [1.0, 2.0]) - r[1]) <= 4 * EPS


def test_mean_of_a_symmetric_set_is_refused():
    # The four half-turn group {I, Rx(π), Ry(π), Rz(π)} with equal weights sums to 0.
    r = np.stack([np.diag(d) for d in ([1., 1, 1], [1., -1, -1], [-1., 1, -1], [-1., -1, 1])])
    with pytest.raises(RotationError, match=r'not unique.*singular values \[0\. 0\. 0\.\]'):
        mean_rotation(r)
    # weights 3, 3, 2, 1 sum to diag(3, 1, −1): det < 0 and σ2 = σ3, a circle of means
    with pytest.raises(RotationError, match=r'not unique: the singular values of Σ wᵢRᵢ are '
                                            r'\[1\. +0\.333 +0\.333\] with det -1, and '
                                            r'σ2 − σ3 = 0'):
        mean_rotation(r, [3.0, 3.0, 2.0, 1.0])


MEAN_REFUSALS = {
    'negative weight': (1, [1.0, -0.5, 1.0], re.escape('weights must be ≥ 0, got -0.5')),
    'tiny negative weight': (1, [-1e-300, 1.0, 1.0],
                             re.escape('weights must be ≥ 0, got -1e-300')),
    'zero weights': (1, [0.0, 0.0, 0.0], r'weights are all 0'),
    'zero weights of one set': (2, [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0]], r'weights are all 0'),
    'two weights': (1, [1.0, 1.0], r'weights must have one entry per rotation \(3\)'),
    'four weights': (1, [1.0] * 4, r'weights must have one entry per rotation \(3\)'),
    'one weight': (1, 1.0, r'weights must have one entry per rotation \(3\)'),
}
"""mean_rotation of n_sets sets of three rotations with weights that are refused, and why."""


@pytest.mark.parametrize('case', MEAN_REFUSALS)
def test_mean_refuses_bad_weights(case):
    n_sets, weights, message = MEAN_REFUSALS[case]
    r = clusters(n_sets, 3, 1.0, 20)
    with pytest.raises(RotationError, match=message):
        mean_rotation(r[0] if n_sets == 1 else r, weights)


def test_mean_needs_a_set_of_rotations():
    with pytest.raises(RotationError, match=r'\(\.\.\., N, 3, 3\) with N ≥ 1, got \(3, 3\)'):
        mean_rotation(np.eye(3))
    with pytest.raises(RotationError, match=r'N ≥ 1, got \(0, 3, 3\)'):
        mean_rotation(np.zeros((0, 3, 3)))


def test_mean_validates_rotations_and_weights():
    r = clusters(1, 3, 1.0, 22)[0]
    r[1, 0, 0] += 1e-6
    with pytest.raises(RotationError, match=r'R is not orthogonal.*item \(1,\)'):
        mean_rotation(r)
    with pytest.raises(RotationError, match=r'weights must be finite'):
        mean_rotation(clusters(1, 3, 1.0, 22)[0], [1.0, np.nan, 1.0])


def test_mean_check_false_projects_the_weighted_sum():
    # check=False: the nearest rotation to Σ wᵢ·Mᵢ of the matrices as given (polar factor).
    m = clusters(1, 3, 1.0, 23)[0] * np.array([1.0, 1.001, 0.999])[:, None, None]
    got = mean_rotation(m, check=False)
    assert h.max_abs(got - h.polar_rotation(m.sum(0))) <= 1e-14
    with pytest.raises(RotationError):
        mean_rotation(m)


# ---- align_vectors -------------------------------------------------------------------------


def pairs(rng, n, noise):
    b = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-1, 1, (n, 1))
    r0 = h.scipy_rotations(1, int(rng.integers(1 << 30)))[0]
    a = b @ r0.T + noise * rng.normal(size=(n, 3))
    return a, b, r0


@pytest.mark.parametrize('noise', [0.0, 1e-6, 0.1, 3.0])
def test_align_matches_scipy(noise):
    rng = np.random.default_rng(30)
    for _ in range(100):
        a, b, _ = pairs(rng, 8, noise)
        w = rng.uniform(0.1, 2, 8)
        for weights in (None, w):
            R, rmsd = align_vectors(a, b, weights)
            ref, rssd = Rotation.align_vectors(a, b, weights)
            assert h.max_abs(R - ref.as_matrix()) <= 1e-13
            # scipy's rssd comes from Σw(|a|² + |b|²) − 2·Σσ, which cancels for small
            # residuals: the reference rmsd is the residual of scipy's rotation, summed here.
            ww = np.ones(8) if weights is None else w
            resid = a - b @ ref.as_matrix().T
            ref_rmsd = np.sqrt(np.sum(ww * np.sum(resid ** 2, -1)) / ww.sum())
            assert abs(rmsd - ref_rmsd) <= 1e-13 * (1 + rmsd)
            if noise >= 0.1:
                assert abs(rmsd - rssd / np.sqrt(ww.sum())) <= 1e-11 * (1 + rmsd)


def test_align_exact_data_recovers_the_rotation():
    rng = np.random.default_rng(31)
    for _ in range(200):
        a, b, r0 = pairs(rng, 5, 0.0)
        R, rmsd = align_vectors(a, b)
        assert h.max_abs(R - r0) <= 1e-13
        assert rmsd <= 1e-15 * 8 * np.abs(a).max()


def test_align_minimises_the_weighted_residual():
    # Perturbing the answer by any small rotation never lowers Σ wᵢ‖aᵢ − R·bᵢ‖².
    rng = np.random.default_rng(32)
    a, b, _ = pairs(rng, 20, 0.5)
    w = rng.uniform(0, 1, 20)
    R, rmsd = align_vectors(a, b, w)
    cost = np.sum(w * np.sum((a - b @ R.T) ** 2, -1))
    assert abs(np.sqrt(cost / w.sum()) - rmsd) <= 1e-14 * rmsd
    bumps = h.notes_rodrigues_eq7(h.random_unit_vectors(rng, 500), rng.uniform(0, 1e-3, 500))
    costs = np.sum(w * np.sum((a - np.einsum('kij,nj->kni', R @ bumps, b)) ** 2, -1), -1)
    assert np.all(costs >= cost - 1e-12 * cost)


def smallest_rotation_ok(R, a, b):
    """R takes b̂ onto â by the angle between them, about an axis ⊥ both (closed form)."""
    a_hat, b_hat = a / np.linalg.norm(a), b / np.linalg.norm(b)
    axis, angle = matrix_to_axis_angle(R)
    between = np.arctan2(np.linalg.norm(np.cross(a_hat, b_hat)), a_hat @ b_hat)
    perpendicular = angle == 0 or (abs(axis @ a_hat) <= 1e-15 * 8
                                   and abs(axis @ b_hat) <= 1e-15 * 8)
    return (h.max_abs(R @ b_hat - a_hat) <= 1e-15 * 8 and abs(angle - between) <= 1e-15 * 8
            and perpendicular)


@pytest.mark.parametrize('a, b', [
    ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
    ([1.0, 2.0, 3.0], [-3.0, 0.5, 2.0]),
    ([0.0, 0.0, 5.0], [0.0, 0.0, 2.0]),
    ([1.0, 1.0, 0.0], [1.0, 1.0 + 1e-9, 0.0]),
    ([0.0, 1.0, 0.0], [0.0, -3.0, 0.0]),
    ([1.0, 2.0, 3.0], [-1.0, -2.0, -3.0]),
    ([-1.0, -2.0, -3.1], [1.0, 2.0, 3.1]),  # opposite only to rounding in the SVD
    ([0.3, -7.0, 1e-3], [-0.6, 14.0, -2e-3]),
])
def test_align_a_single_pair_is_the_smallest_rotation(a, b):
    R, rmsd = align_vectors([a], [b])
    assert is_rotation(R, tol=1e-14)
    assert smallest_rotation_ok(R, np.array(a), np.array(b))
    assert abs(rmsd - abs(np.linalg.norm(a) - np.linalg.norm(b))) <= 1e-14 * np.linalg.norm(a)
    if abs(np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b)) < 0.999:
        # The smallest rotation taking b to a: about b × a by the angle between them (SciPy
        # 1.11's align_vectors of one pair returns some rotation taking b to a, not that one).
        axis = np.cross(b, a)
        angle = np.arctan2(np.linalg.norm(axis), np.dot(a, b))
        ref = Rotation.from_rotvec(angle * axis / np.linalg.norm(axis))
        assert h.max_abs(R - ref.as_matrix()) <= 1e-14


def test_align_parallel_pairs_is_the_smallest_rotation():
    a_dir, b_dir = np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.3, -1.0])
    lengths = np.array([[1.0, 2.0], [0.5, 0.1], [3.0, 7.0]])
    a = lengths[:, :1] * a_dir
    b = lengths[:, 1:] * b_dir
    R, _ = align_vectors(a, b)
    assert smallest_rotation_ok(R, a_dir, b_dir)
    # anti-parallel members weigh against: the same line, so still the smallest rotation
    R2, _ = align_vectors(np.concatenate([a, -a[:1]]), np.concatenate([b, -b[:1]]))
    assert h.max_abs(R2 - R) <= 1e-15 * 8


def test_align_opposite_parallel_pairs_is_a_half_turn_about_an_axis_perpendicular_to_b():
    d = np.array([1.0, 2.0, 3.1])
    R, _ = align_vectors([-d, -2 * d], [d, 3 * d])
    assert smallest_rotation_ok(R, -d, d)


def scipy_rotvec(R):
    return Rotation.from_matrix(R).as_rotvec()


@pytest.mark.parametrize('delta', [0.0, 1e-6, 1e-9, 1e-12, 1e-14, 1e-15, 3e-16])
def test_align_nearly_opposite_pairs_is_the_smallest_rotation(delta):
    # a = b̂ turned by π − δ about a random axis ⊥ b̂ (closed form), scaled; checked against
    # scipy's rotation vector of R: |θ| = the angle between â and b̂, θ̂ ⊥ â and b̂.
    rng = np.random.default_rng(37)
    b = h.random_unit_vectors(rng, 2000)
    n = np.cross(b, h.random_unit_vectors(rng, 2000))
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    a = np.cos(PI - delta) * b + np.sin(PI - delta) * np.cross(n, b)
    scale = 10.0 ** rng.uniform(-3, 3, (2, 2000, 1))
    R, _ = align_vectors((scale[0] * a)[:, None], (scale[1] * b)[:, None])
    a_hat = a / np.linalg.norm(a, axis=-1, keepdims=True)
    assert h.max_abs(np.einsum('kij,kj->ki', R, b) - a_hat) <= 1e-15 * 8
    rotvec = scipy_rotvec(R)
    angle = np.linalg.norm(rotvec, axis=-1)
    axis = rotvec / angle[:, None]
    between = np.arctan2(np.linalg.norm(np.cross(a_hat, b), axis=-1), np.sum(a_hat * b, -1))
    assert h.max_abs(angle - between) <= 1e-15 * 8
    assert h.max_abs(np.sum(axis * b, -1)) <= 1e-15 * 8
    assert h.max_abs(np.sum(axis * a_hat, -1)) <= 1e-15 * 8


def test_align_opposite_pairs_of_any_length_is_a_half_turn():
    rng = np.random.default_rng(38)
    b = rng.normal(size=(2000, 3)) * 10.0 ** rng.uniform(-3, 3, (2000, 1))
    a = -10.0 ** rng.uniform(-3, 3, (2000, 1)) * b
    R, _ = align_vectors(a[:, None], b[:, None])
    b_hat = b / np.linalg.norm(b, axis=-1, keepdims=True)
    assert h.max_abs(np.einsum('kij,kj->ki', R, b_hat) + b_hat) <= 1e-15 * 8
    rotvec = scipy_rotvec(R)
    assert h.max_abs(np.linalg.norm(rotvec, axis=-1) - PI) <= 1e-15 * 8
    assert h.max_abs(np.sum(rotvec * b_hat, -1)) <= 1e-15 * 8


def test_align_batches_and_broadcasting():
    rng = np.random.default_rng(33)
    a = rng.normal(size=(2, 3, 5, 3))
    b = rng.normal(size=(5, 3))
    R, rmsd = align_vectors(a, b, np.arange(1.0, 6.0))
    assert R.shape == (2, 3, 3, 3) and rmsd.shape == (2, 3)
    for i in range(2):
        for j in range(3):
            r1, d1 = align_vectors(a[i, j], b, np.arange(1.0, 6.0))
            assert h.max_abs(r1 - R[i, j]) <= 1e-15 * 8 and abs(d1 - rmsd[i, j]) <= 1e-15 * 8


@pytest.mark.parametrize('scale_a, scale_b', [(1e300, 1.0), (1e-300, 1e300), (1.7e308, 1.7e308)])
def test_align_any_finite_scale(scale_a, scale_b):
    rng = np.random.default_rng(34)
    a, b, r0 = pairs(rng, 6, 0.0)
    R, rmsd = align_vectors(scale_a * (a / np.abs(a).max()), scale_b * (b / np.abs(b).max()))
    assert h.max_abs(R - r0) <= 1e-14
    assert np.isfinite(rmsd)


ALIGN_REFUSALS = {
    'a zero vector in a': (np.diag([1.0, 0.0, 1.0]), np.eye(3), None,
                           re.escape('a[1] is the zero vector')),
    'a zero vector in b': (np.eye(3), np.diag([1.0, 0.0, 1.0]), None,
                           re.escape('b[1] is the zero vector')),
    'counts 3 and 2': (np.ones((3, 3)), np.ones((2, 3)), None, 'a has 3 vectors but b has 2'),
    'counts 1 and 4': (np.ones((1, 3)), np.ones((4, 3)), None, 'a has 1 vectors but b has 4'),
    'weight count': (np.eye(3), np.eye(3), [1.0, 1.0],
                     r'one entry per vector pair \(3\), got 2 entries'),
    'negative weight': (np.eye(3), np.eye(3), [1.0, 1.0, -1.0],
                        r'weights must be ≥ 0, got -1 at index 2'),
    'zero weights': (np.eye(3), np.eye(3), [0.0, 0.0, 0.0],
                     r'weights are all 0: at least one vector pair'),
    'one vector': ([1.0, 0.0, 0.0], [[1.0, 0.0, 0.0]], None,
                   r'a must have shape \(\.\.\., N, 3\)'),
    'no pairs': (np.zeros((0, 3)), np.zeros((0, 3)), None, r'no vector pairs'),
    'batches': (np.ones((2, 4, 3)), np.ones((3, 4, 3)), None, r'do not broadcast'),
    'inf': (np.eye(3), [[1.0, 0, 0], [0, np.inf, 0], [0, 0, 1]], None, r'b must be finite'),
}
"""align_vectors(a, b, weights) that are refused, and what the message says."""


@pytest.mark.parametrize('case', ALIGN_REFUSALS)
def test_align_refusals(case):
    a, b, weights, message = ALIGN_REFUSALS[case]
    with pytest.raises(RotationError, match=message):
        align_vectors(a, b, weights)


def test_align_without_a_best_rotation():
    # H = x xᵀ − x xᵀ = 0: every rotation fits equally badly
    with pytest.raises(RotationError, match=r'not unique: H = Σ wᵢ·aᵢbᵢᵀ vanishes'):
        align_vectors([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]], [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    # b is a mirror image of a: H = diag(1, 1, −1), a circle of best rotations
    with pytest.raises(RotationError, match=r'best rotation is not unique: the singular values'
                                            r' of H = Σ wᵢ·aᵢbᵢᵀ are .* det -1'):
        align_vectors(np.eye(3), np.diag([1.0, 1.0, -1.0]))


# ---- random_rotations ----------------------------------------------------------------------


def haar_angle_cdf(theta):
    """P(angle ≤ θ) of a uniform rotation: ∫ (1 − cos t)/π dt = (θ − sin θ)/π."""
    return (theta - np.sin(theta)) / PI


KS_N = 20_000
KS_LIMIT = 1.95 / np.sqrt(KS_N)  # the Kolmogorov–Smirnov critical value at α = 0.001


def ks_statistic(angles):
    return stats.kstest(angles, haar_angle_cdf).statistic


def test_random_rotations_follow_the_haar_angle_law():
    r = random_rotations(KS_N, rng=2026)
    assert r.shape == (KS_N, 3, 3) and np.all(is_rotation(r, tol=1e-14))
    _, angle = matrix_to_axis_angle(r)
    assert ks_statistic(angle) < KS_LIMIT
    # left invariance: the distance to any fixed rotation follows the same law
    fixed = h.scipy_rotations(1, 5)[0]
    assert ks_statistic(rotation_distance(fixed, r)) < KS_LIMIT
    # each column is uniform on the sphere: its z component is uniform on [−1, 1]
    for col in range(3):
        assert stats.kstest(r[:, 2, col], stats.uniform(-1, 2).cdf).statistic < KS_LIMIT
    assert h.max_abs(r.mean(axis=0)) < 5 / np.sqrt(KS_N)  # E[R] = 0 for Haar


def test_the_haar_test_rejects_non_uniform_samplers():
    # The same statistic and limit fail samplers that are not uniform, and pass an
    # independent uniform one (Euler ZYX with pitch density cos θ2 / 2).
    rng = np.random.default_rng(7)
    axis = rng.normal(size=(KS_N, 3))
    uniform_angle = matrix_to_axis_angle(rodrigues(axis, rng.uniform(0, PI, KS_N)))[1]
    assert ks_statistic(uniform_angle) > 10 * KS_LIMIT            # D ≈ 0.31
    euler = np.stack([rng.uniform(-PI, PI, KS_N), rng.uniform(-PI / 2, PI / 2, KS_N),
                      rng.uniform(-PI, PI, KS_N)], -1)
    assert ks_statistic(matrix_to_axis_angle(euler_to_matrix(euler, 'ZYX'))[1]) > KS_LIMIT
    euler[:, 1] = np.arcsin(rng.uniform(-1, 1, KS_N))
    assert ks_statistic(matrix_to_axis_angle(euler_to_matrix(euler, 'ZYX'))[1]) < KS_LIMIT


def test_random_rotations_shapes_and_seeds():
    one = random_rotations(rng=3)
    assert one.shape == (3, 3) and is_rotation(one, tol=1e-14)
    assert random_rotations(0).shape == (0, 3, 3)
    assert np.array_equal(random_rotations(5, rng=3), random_rotations(5, rng=3))
    assert not np.array_equal(random_rotations(5, rng=3), random_rotations(5, rng=4))
    gen = np.random.default_rng(9)
    first, second = random_rotations(4, rng=gen), random_rotations(4, rng=gen)
    assert not np.array_equal(first, second)  # a Generator is used, not copied
    again = np.random.default_rng(9)
    assert np.array_equal(random_rotations(4, rng=again), first)
    assert np.array_equal(random_rotations(4, rng=again), second)
    assert random_rotations(np.int64(2)).shape == (2, 3, 3)


@pytest.mark.parametrize('n', [-1, 2.5, '3', True])
def test_random_rotations_bad_count(n):
    with pytest.raises(RotationError, match=r'n must be None or an integer ≥ 0'):
        random_rotations(n)


def test_random_rotations_bad_rng():
    with pytest.raises(RotationError, match=r'rng must be a numpy.random.Generator or a seed'):
        random_rotations(2, rng='seed')


def test_unique_tolerance_is_documented_and_small():
    assert 0 < UNIQUE_TOL <= 1e-9


@pytest.mark.parametrize('n', [2 ** 62, 2 ** 64, 10 ** 400, np.uint64(2 ** 63), 10 ** 13],
                         ids=['2**62', '2**64', '10**400', 'uint64 2**63', '10**13'])
def test_random_rotations_too_many_to_allocate(n):
    # 2**62 raised NumPy's ValueError ('array is too big'), a large n a MemoryError
    with pytest.raises(RotationError,
                       match=r'^n = [0-9.e+]+ rotations are too many to allocate'):
        random_rotations(n)


# ---- align_vectors when one pair dominates (a weight or a length far above the rest) -------


def scipy_angle(R, ref):
    """Angle between two rotations, by scipy (quaternions): the reference's own distance."""
    return (Rotation.from_matrix(R).inv() * Rotation.from_matrix(ref)).magnitude()


def scipy_primary(a, b, weights, primary):
    """
    Return the rotation that aligns pair ``primary`` exactly and best fits the rest.

    scipy's rotations throughout, the turn about â by a scan and brentq (not rot_tools' road).
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    w = np.asarray(weights, dtype=float)
    a0 = a[primary] / np.linalg.norm(a[primary])
    b0 = b[primary] / np.linalg.norm(b[primary])
    axis = np.cross(b0, a0)
    angle = np.arctan2(np.linalg.norm(axis), b0 @ a0)
    r1 = Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle if angle else np.zeros(3))
    rest = np.arange(len(a)) != primary
    if not rest.any():
        return r1.as_matrix()
    c, a_rest, w_rest = r1.apply(b[rest]), a[rest], w[rest]

    def torque(phi):
        turned = Rotation.from_rotvec(phi * a0).apply(c)
        return np.sum(w_rest * np.sum(a_rest * np.cross(a0, turned), -1))

    grid = np.linspace(-PI, PI, 721)
    turns = Rotation.from_rotvec(grid[:, None] * a0).as_matrix()
    fits = np.einsum('n,ni,kij,nj->k', w_rest, a_rest, turns, c)
    best = grid[np.argmax(fits)]
    step = grid[1] - grid[0]
    phi = optimize.brentq(torque, best - step, best + step, xtol=1e-15, rtol=4 * EPS)
    return (Rotation.from_rotvec(phi * a0) * r1).as_matrix()


@pytest.mark.parametrize('ratio', [1e8, 1e9, 1e10, 1e12, 1e16, 1e30])
def test_align_dominant_weight_still_fits_the_second_pair(ratio):
    # scipy's test_align_vectors_align_constrain with a finite weight: however large, the
    # second pair still counts.
    a = np.array([[0.0, 1.0, 0.0], [0.0, 1.0, 1.0]])
    expected = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    R, rmsd = align_vectors(a, [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0]], [ratio, 1.0])
    assert h.max_abs(R - expected) <= 1e-15 * 8 + 2 / ratio
    assert rmsd <= 1e-15 * 8
    # an inexact second pair: only its part ⊥ the primary can be matched
    R, rmsd = align_vectors(a, [[1.0, 0.0, 0.0], [1.0, 2.0, 0.0]], [ratio, 1.0])
    assert h.max_abs(R - expected) <= 1e-15 * 8 + 2 / ratio
    assert h.max_abs(R @ [1.0, 2.0, 0.0] - [0.0, 1.0, 2.0]) <= 1e-15 * 8 + 4 / ratio
    assert abs(rmsd - np.sqrt(1.0 / (ratio + 1.0))) <= 1e-13 * rmsd + 2 / ratio + EPS


def dominated_sets(rng, n_sets, n_pairs):
    """Random pair sets: a = R0·b + noise, b of random lengths (scipy as reference)."""
    b = rng.normal(size=(n_sets, n_pairs, 3))
    r0 = Rotation.random(n_sets, random_state=int(rng.integers(1 << 30))).as_matrix()
    a = np.einsum('kij,knj->kni', r0, b) + 0.3 * rng.normal(size=(n_sets, n_pairs, 3))
    return a, b


@pytest.mark.parametrize('ratio', [1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16])
def test_align_dominant_weight_against_scipy(ratio):
    # Two references, each where it is sharp: scipy_primary (off by ~1/ratio) and scipy's
    # finite-weight SVD (off by ~ε·ratio).
    rng = np.random.default_rng(int(np.log10(ratio)))
    a, b = dominated_sets(rng, 60, 4)
    weights = np.array([ratio, 1.0, 1.0, 1.0])
    R, _ = align_vectors(a, b, weights)
    for k in range(len(a)):
        lengths = np.linalg.norm(a[k], axis=-1) * np.linalg.norm(b[k], axis=-1)
        pull = np.sum(lengths[1:]) / (ratio * lengths[0])
        assert scipy_angle(R[k], scipy_primary(a[k], b[k], weights, 0)) <= 4 * pull + 1e-12
        if ratio <= 1e9:
            ref = Rotation.align_vectors(a[k], b[k], weights)[0].as_matrix()
            assert scipy_angle(R[k], ref) <= 200 * EPS * ratio + 1e-13
        # the primary pair is aligned, to its share of the pull
        a0, b0 = a[k, 0] / np.linalg.norm(a[k, 0]), b[k, 0] / np.linalg.norm(b[k, 0])
        assert np.linalg.norm(R[k] @ b0 - a0) <= 4 * pull + 1e-14


@pytest.mark.parametrize('big, small', [(1e3, 1e-3), (1e8, 1e-8), (1e150, 1e-150), (1.0, 1e-9)])
def test_align_dominant_length_against_scipy(big, small):
    # Lengths 1e3 vs 1e-3 with equal weights are a weight ratio of 1e12 in H.
    rng = np.random.default_rng(41)
    a, b = dominated_sets(rng, 60, 3)
    # the infinite-weight answer depends on the small pairs only up to a common scale
    refs = [scipy_primary(a[k], b[k], np.ones(3), 0) for k in range(len(a))]
    a[:, 0] *= big
    b[:, 0] *= big
    a[:, 1:] *= small
    b[:, 1:] *= small
    R, rmsd = align_vectors(a, b)
    for k in range(len(a)):
        lengths = np.linalg.norm(a[k], axis=-1) * np.linalg.norm(b[k], axis=-1)
        pull = np.sum(lengths[1:]) / lengths[0]
        assert scipy_angle(R[k], refs[k]) <= 4 * pull + 1e-12
    assert np.all(np.isfinite(rmsd))


def test_align_dominant_pair_in_a_batch_matches_single_calls():
    rng = np.random.default_rng(42)
    a, b = dominated_sets(rng, 6, 4)
    w = np.ones((6, 4))
    w[::2, 0] = 1e12  # half the sets dominated, half not
    R, rmsd = align_vectors(a, b, w)
    for k in range(6):
        r1, d1 = align_vectors(a[k], b[k], w[k])
        assert h.max_abs(R[k] - r1) <= 1e-15 * 8 and abs(rmsd[k] - d1) <= 1e-14 * (1 + d1)


def test_align_dominant_pair_with_the_rest_cancelling_is_not_unique():
    # About the dominant x, the second pair wants a turn of 0 and the third of π, with equal
    # weights: every turn about x fits them equally (their cost is 4 whatever the angle).
    a = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]
    b = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]]
    with pytest.raises(RotationError, match=r'best rotation is not unique'):
        align_vectors(a, b, [1e12, 1.0, 1.0])


# ---- UNIQUE_TOL: where rounding, not the data, would pick the answer ----------------------


def rot_z_scipy(angle):
    return Rotation.from_rotvec([0.0, 0.0, angle]).as_matrix()


@pytest.mark.parametrize('delta', [1e-12, 1e-11, 1e-10])
def test_a_mean_decided_by_rounding_is_refused(delta):
    # S = Σ Rᵢ has singular values (2, δ, δ): the turn about z is known only to ~ε/δ.
    with pytest.raises(RotationError, match=r'mean rotation is not unique'):
        mean_rotation(np.stack([np.eye(3), rot_z_scipy(PI - delta)]))


@pytest.mark.parametrize('delta', [1e-7, 1e-6])
def test_a_mean_the_data_decides_is_returned(delta):
    # A little further from π apart the data decide it, to ~ε/δ.
    M = mean_rotation(np.stack([np.eye(3), rot_z_scipy(PI - delta)]))
    ref = Rotation.from_rotvec([0.0, 0.0, (PI - delta) / 2]).as_matrix()
    assert scipy_angle(M, ref) <= 64 * EPS / delta
