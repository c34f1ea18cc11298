"""
Covariance across representations: first order against sampling and central differences.

Monte Carlo (10^5 seeded samples, within 3 %) and central differences (to 1e-7).
"""

from fractions import Fraction
import re

import math_helpers as h
import numpy as np
import pytest
import rot_tools as rt
from rot_tools import (change_covariance_frame, euler_covariance_to_rotvec, EULER_SEQUENCES,
                       RotationError, rotvec_covariance_to_euler, transform_pose_covariance)
from rot_tools.core.covariance import gimbal_lock_distance
from rot_tools.io.message_covariance import BAD, fault, near_lock_note, OK, rpy_covariances
from rot_tools.io.message_covariance import stddev_correlation

R0 = rt.rotvec_to_matrix([1.0, -0.19, 2.09])
"""θ2 is at least 0.77 rad from gimbal lock in every sequence (checked below)."""

FRAMES = ('parent', 'body')
SAMPLES = 100_000
H = 1e-5  # central-difference step: truncation ~H², rounding ~1e-16/H, both ≤ 1e-10


def _spd(stddev_deg, seed):
    """Return a covariance with the given standard deviations (degrees) along random axes."""
    A = rt.random_rotations(rng=seed)
    return A @ np.diag(np.radians(stddev_deg) ** 2) @ A.T


C0 = _spd([2.0, 1.0, 0.5], 3)


def _lock_distance(angles, seq):
    t2 = angles[..., 1]
    if seq[0].lower() == seq[2].lower():
        return np.minimum(np.abs(t2), np.abs(np.pi - t2))
    return np.pi / 2 - np.abs(t2)


def _perturbed(R, error, frame):
    return error @ R if frame == 'parent' else R @ error


def _error_of(R_true, R, frame):
    return rt.matrix_to_rotvec(R_true @ R.T if frame == 'parent' else R.T @ R_true)


def _relative(got, want):
    return np.linalg.norm(got - want) / np.linalg.norm(want)


@pytest.fixture(scope='module')
def errors():
    """10^5 draws of N(0, C0), and the rotations of them as rotation vectors."""
    d = np.random.default_rng(2024).standard_normal((SAMPLES, 3)) @ np.linalg.cholesky(C0).T
    return d, rt.rotvec_to_matrix(d)


def test_the_test_rotation_is_far_from_gimbal_lock_in_every_sequence():
    for seq in EULER_SEQUENCES:
        assert _lock_distance(rt.matrix_to_euler(R0, seq)[0], seq) > 0.77


@pytest.mark.parametrize('frame', FRAMES)
@pytest.mark.parametrize('seq', EULER_SEQUENCES)
def test_rotvec_to_euler_agrees_with_monte_carlo(seq, frame, errors):
    d, exp_d = errors
    mean = rt.matrix_to_euler(R0, seq)[0]
    angles = rt.matrix_to_euler(_perturbed(R0, exp_d, frame), seq)[0]
    sampled = np.cov(h.wrap(angles - mean).T)
    cov, degenerate = rotvec_covariance_to_euler(R0, C0, seq, frame)
    assert not degenerate
    assert _relative(sampled, cov) < 0.03


@pytest.mark.parametrize('frame', FRAMES)
@pytest.mark.parametrize('seq', EULER_SEQUENCES)
def test_euler_to_rotvec_agrees_with_monte_carlo(seq, frame, errors):
    d, _ = errors  # here the errors of the angles
    mean = rt.matrix_to_euler(R0, seq)[0]
    sampled = np.cov(_error_of(rt.euler_to_matrix(mean + d, seq), R0, frame).T)
    cov, degenerate = euler_covariance_to_rotvec(mean, C0, seq, frame)
    assert not degenerate
    assert _relative(sampled, cov) < 0.03


def _central(f):
    """Return the Jacobian of f at 0 by central differences, columns per coordinate."""
    return np.stack([(f(H * e) - f(-H * e)) / (2 * H) for e in np.eye(3)], axis=-1)


@pytest.mark.parametrize('frame', FRAMES)
@pytest.mark.parametrize('seq', EULER_SEQUENCES)
def test_jacobians_agree_with_central_differences(seq, frame):
    mean = rt.matrix_to_euler(R0, seq)[0]

    def angles(delta):
        return rt.matrix_to_euler(_perturbed(R0, rt.rotvec_to_matrix(delta), frame), seq)[0]

    def rotvec(d_angles):
        return _error_of(rt.euler_to_matrix(mean + d_angles, seq), R0, frame)

    J, E = _central(angles), _central(rotvec)
    assert _relative(rotvec_covariance_to_euler(R0, C0, seq, frame)[0], J @ C0 @ J.T) < 1e-7
    assert _relative(euler_covariance_to_rotvec(mean, C0, seq, frame)[0], E @ C0 @ E.T) < 1e-7
    # a 6×6 pose covariance: position block kept, cross terms through the same Jacobian
    C6 = _pose_covariance(5)
    cov6, _ = rotvec_covariance_to_euler(R0, C6, seq, frame)
    J6 = np.eye(6)
    J6[3:, 3:] = J
    assert _relative(cov6, J6 @ C6 @ J6.T) < 1e-7
    np.testing.assert_array_equal(cov6[:3, :3], C6[:3, :3])


def _pose_covariance(seed):
    """Return a correlated 6×6 covariance: position ≤ 0.1 m, rotations ≤ 2°."""
    rng = np.random.default_rng(seed)
    A = np.linalg.qr(rng.standard_normal((6, 6)))[0]
    C = A @ np.diag(np.array([0.1, 0.05, 0.02, 0.035, 0.02, 0.01]) ** 2) @ A.T
    return 0.5 * (C + C.T)


@pytest.mark.parametrize('frame', FRAMES)
@pytest.mark.parametrize('seq', ['xyz', 'ZYX', 'ZXZ', 'yxy'])
def test_euler_to_rotvec_to_euler_is_the_identity(seq, frame):
    R = rt.random_rotations(200, rng=11)
    angles = rt.matrix_to_euler(R, seq)[0]
    keep = _lock_distance(angles, seq) > 0.05
    C = np.stack([_spd(s, k) for k, s in enumerate(np.random.default_rng(1).uniform(
        0.1, 2.0, (200, 3)))])
    rotvec_cov, _ = euler_covariance_to_rotvec(angles[keep], C[keep], seq, frame)
    back, degenerate = rotvec_covariance_to_euler(R[keep], rotvec_cov, seq, frame)
    assert not degenerate.any() and keep.sum() > 150
    assert np.max(np.linalg.norm(back - C[keep], axis=(-2, -1))
                  / np.linalg.norm(C[keep], axis=(-2, -1))) < 1e-9


@pytest.mark.parametrize('frame', FRAMES)
@pytest.mark.parametrize('seq', ['xyz', 'ZYZ'])
def test_a_batch_is_a_loop_of_single_items_with_nan_at_gimbal_lock(seq, frame):
    R = rt.random_rotations(12, rng=5).reshape(3, 4, 3, 3)
    locked = [0.3, np.pi / 2, 0.2] if seq == 'xyz' else [0.3, 0.0, 0.2]
    R[1, 2] = rt.euler_to_matrix(locked, seq)
    angles = rt.matrix_to_euler(R, seq)[0]
    C = np.stack([_spd([2.0, 0.5, 1.0], k) for k in range(12)]).reshape(3, 4, 3, 3)
    for convert, first in ((rotvec_covariance_to_euler, R), (euler_covariance_to_rotvec, angles)):
        cov, degenerate = convert(first, C, seq, frame)
        assert cov.shape == (3, 4, 3, 3) and degenerate.shape == (3, 4)
        assert degenerate.sum() == 1 and degenerate[1, 2] and np.isnan(cov[1, 2]).all()
        for index in np.ndindex(3, 4):
            if index != (1, 2):
                one, flag = convert(first[index], C[index], seq, frame)
                assert not flag and isinstance(flag, np.bool_) and one.shape == (3, 3)
                np.testing.assert_allclose(cov[index], one, rtol=1e-14, atol=1e-20)
        shared, _ = convert(first[0, 0], C[0], seq, frame)  # one rotation, four covariances
        assert shared.shape == (4, 3, 3)
        np.testing.assert_allclose(shared[0], cov[0, 0], rtol=1e-14, atol=1e-20)


@pytest.mark.parametrize('seq, angles, distance', [
    ('xyz', [0.3, np.pi / 2 - 3e-7, 0.2], '3e-07'), ('ZYX', [0.3, -np.pi / 2, 0.2], '6.12e-17'),
    ('ZXZ', [0.3, 5e-8, 0.2], '5e-08'), ('yzy', [0.3, np.pi - 4e-7, 0.2], '4e-07')])
def test_one_item_at_gimbal_lock_is_refused_with_its_distance(seq, angles, distance):
    pattern = (rf"the '{seq}' angles are {distance}\S* rad from gimbal lock .*within "
               r'GIMBAL_LOCK_TOL = 1e-06')
    with pytest.raises(RotationError, match=pattern):
        euler_covariance_to_rotvec(angles, C0, seq)
    with pytest.raises(RotationError, match=r'gimbal lock'):
        rotvec_covariance_to_euler(rt.euler_to_matrix(angles, seq), C0, seq, 'body')


def test_just_beyond_the_lock_tolerance_the_covariance_is_given():
    cov, degenerate = rotvec_covariance_to_euler(
        rt.euler_to_matrix([0.3, np.pi / 2 - 2e-6, 0.2], 'xyz'), C0, 'xyz')
    assert not degenerate and np.isfinite(cov).all() and cov[0, 0] > 1e6


def test_asymmetry_is_refused_with_its_size_and_the_worst_item():
    C = C0.copy()
    C[0, 1] += 1e-6
    message = re.escape('cov is not symmetric: max|C − Cᵀ| = 1e-06')
    with pytest.raises(RotationError, match=message):
        change_covariance_frame(C, R0)
    batch = np.stack([C0, C0, C0])
    batch[1, 0, 2] += 1e-9
    batch[2, 2, 1] += 1e-8
    with pytest.raises(RotationError, match=r'= 1e-08 > .*\(item \(2,\)\)$'):
        rotvec_covariance_to_euler(R0, batch)
    C[0, 1] = C0[0, 1] + 1e-9 * 0.9 * np.abs(C0).max()  # within 1e-9·max|C|: taken
    assert np.isfinite(change_covariance_frame(C, R0)).all()


def test_the_worst_item_is_ranked_against_its_own_scale_even_when_subnormal():
    batch = np.zeros((2, 3, 3))
    batch[0, 0, 1] = 0.5  # half as asymmetric as its largest entry
    batch[0, 0, 0] = 1.0
    batch[1, 0, 1] = 5e-324  # wholly asymmetric; its bound 1e-9·max|C| underflows to 0
    with pytest.raises(RotationError, match=r'= 4.94e-324 > 1e-09·max\|C\| = 0 \(item \(1,\)\)$'):
        change_covariance_frame(batch, R0)


def test_a_negative_eigenvalue_is_refused_with_its_size():
    A = rt.random_rotations(rng=4)
    bad = A @ np.diag([1e-4, 2e-4, -1e-6]) @ A.T
    with pytest.raises(RotationError, match=r'not positive semi-definite: its lowest eigenvalue '
                                            r'is -1e-06, below -1e-09·max\|C\|'):
        euler_covariance_to_rotvec([0.1, 0.2, 0.3], 0.5 * (bad + bad.T))
    C6 = np.eye(6)
    C6[4, 4] = -0.5
    with pytest.raises(RotationError, match='cov6 is not positive semi-definite.* -0.5,'):
        transform_pose_covariance(R0, [1, 2, 3], C6)


def test_a_covariance_psd_only_after_rounding_is_accepted():
    A = rt.random_rotations(rng=4)
    for lowest, taken in ((-5e-14, True), (-5e-13, False)):  # max|C| ~2e-4: bound ~2e-13
        C = A @ np.diag([1e-4, 2e-4, lowest]) @ A.T
        C = 0.5 * (C + C.T)
        assert np.linalg.eigvalsh(C)[0] < 0
        if taken:
            cov, _ = rotvec_covariance_to_euler(R0, C, 'ZYX')
            assert np.isfinite(cov).all()
        else:
            with pytest.raises(RotationError, match='lowest eigenvalue is -5'):
                rotvec_covariance_to_euler(R0, C, 'ZYX')
    rank_one = np.outer([1.0, 2.0, 3.0], [1.0, 2.0, 3.0]) * 1e-4  # eigenvalues 0 to rounding
    assert np.isfinite(change_covariance_frame(rank_one, R0)).all()
    assert (change_covariance_frame(np.zeros((3, 3)), R0) == 0).all()


BIG = 1.7976931348623157e308
"""float64's largest: C + Cᵀ of such entries overflows, and eigvalsh may not converge."""


def test_covariances_at_the_edge_of_float64_are_checked_without_overflow():
    not_psd = np.array([[BIG, -1e308, 0], [-1e308, 5e-324, 0], [0, 0, 1]])  # NaN unscaled
    lowest = np.linalg.eigvalsh(not_psd / BIG)[0] * BIG
    assert lowest < -1e307
    hard = np.array([[1e308, 0, 1e308], [0, 1, 0], [1e308, 0, 1e308]])  # PSD, rank 2
    asymmetric = np.diag([BIG, 1.0, 1.0])
    asymmetric[0, 1] = 1e300
    with np.errstate(over='raise', invalid='raise', divide='raise'):  # no warning on the way
        with pytest.raises(RotationError, match=re.escape(f'eigenvalue is {lowest:.3g}, below')):
            change_covariance_frame(not_psd, R0)
        with pytest.raises(RotationError, match=r'max\|C − Cᵀ\| = 1e\+300 > .*\(item \(1,\)\)'):
            change_covariance_frame(np.stack([hard, asymmetric, not_psd]), R0)
        assert np.isfinite(change_covariance_frame(hard * 1e-10, R0)).all()
        # the rotated covariance itself is beyond float64 (2e308 of [1, 0, 1]·[1, 0, 1]ᵀ)
        with pytest.raises(RotationError, match='turned covariance overflows float64'):
            change_covariance_frame(hard, R0)


@pytest.mark.parametrize('bad', [np.nan, np.inf, -np.inf])
def test_nan_and_inf_are_refused(bad):
    C = C0.copy()
    C[1, 1] = bad
    with pytest.raises(RotationError, match='cov must be finite'):
        rotvec_covariance_to_euler(R0, C)
    with pytest.raises(RotationError, match='Euler angles must be finite'):
        euler_covariance_to_rotvec([0.1, bad, 0.3], C0)
    with pytest.raises(RotationError, match='b must be finite'):
        transform_pose_covariance(R0, [0, bad, 0], np.eye(6))


@pytest.mark.parametrize('call, message', [
    (lambda: rotvec_covariance_to_euler(R0, np.eye(4)), r'cov must have shape \(\.\.\., 3, 3\)'),
    (lambda: rotvec_covariance_to_euler(R0, [[1, 0], [0]]), r'cov must be numeric'),
    (lambda: euler_covariance_to_rotvec([0, 0, 0], 'abc'), r'cov must be numeric'),
    (lambda: rotvec_covariance_to_euler(R0[:2], C0), r'R must have shape'),
    (lambda: euler_covariance_to_rotvec([0.1, 0.2], C0), r'Euler angles must have shape'),
    (lambda: transform_pose_covariance(R0, [0, 0, 0], C0), r'cov6 must have shape .*6, 6'),
    (lambda: transform_pose_covariance(R0, [0, 0], np.eye(6)), r'b must have shape'),
    (lambda: change_covariance_frame(np.eye(6), R0), r'cov must have shape'),
    (lambda: rotvec_covariance_to_euler(rt.random_rotations(2, rng=1), np.stack([C0] * 3)),
     r'batch shapes \(2,\) and \(3,\) do not broadcast'),
    (lambda: rotvec_covariance_to_euler(R0, C0, 'xyZ'), r"unknown Euler sequence 'xyZ'"),
    (lambda: euler_covariance_to_rotvec([0, 0, 0], C0, 'xyz', 'world'),
     r"frame must be 'parent' or 'body', got 'world'"),
    (lambda: rotvec_covariance_to_euler(R0, C0, frame=None), r'frame must be'),
    (lambda: transform_pose_covariance(R0, [0, 0, 0], np.eye(6), 'tf2'),
     r"convention must be 'ros' or 'se3', got 'tf2'"),
    (lambda: change_covariance_frame(C0, 2 * R0), r'R is not orthogonal'),
])
def test_bad_input_is_refused(call, message):
    with pytest.raises(RotationError, match=message):
        call()


def _pose_sample(C6, count, seed):
    return np.random.default_rng(seed).standard_normal((count, 6)) @ np.linalg.cholesky(C6).T


def test_ros_convention_agrees_with_sampling_the_transformed_pose():
    """Position and rotation-vector errors in the parent frame, carried by (R, b)."""
    C6 = _pose_covariance(7)
    R, b = rt.rotvec_to_matrix([0.4, -1.2, 0.7]), np.array([3.0, -2.0, 1.5])
    R_pose, p = rt.rotvec_to_matrix([-0.3, 0.8, 2.5]), np.array([1.0, 4.0, -2.0])
    xi = _pose_sample(C6, SAMPLES, 8)
    p_true, R_true = p + xi[:, :3], rt.rotvec_to_matrix(xi[:, 3:]) @ R_pose
    p_moved = rt.transform_points(R, b, p_true) - rt.transform_points(R, b, p)
    r_moved = rt.matrix_to_rotvec(R @ R_true @ (R @ R_pose).T)
    sampled = np.cov(np.hstack([p_moved, r_moved]).T)
    got = transform_pose_covariance(R, b, np.cov(xi.T), 'ros')
    assert _relative(got, sampled) < 1e-9  # a linear map: equal to rounding
    assert _relative(transform_pose_covariance(R, b, C6), sampled) < 0.03
    assert _relative(transform_pose_covariance(R, -b, C6), sampled) < 0.03  # b plays no part


def test_se3_convention_agrees_with_sampling_the_transformed_pose():
    """Exponential coordinates ξ = (v, ω) on the left: T_true = exp(ξ^)·T, carried by G."""
    C6 = _pose_covariance(9)
    R, b = rt.rotvec_to_matrix([0.4, -1.2, 0.7]), np.array([3.0, -2.0, 1.5])
    R_pose, p = rt.rotvec_to_matrix([-0.3, 0.8, 2.5]), np.array([1.0, 4.0, -2.0])
    xi = _pose_sample(C6, 20_000, 10)
    R_err, b_err = rt.screw_exp(np.hstack([xi[:, 3:], xi[:, :3]]))  # screw_exp takes (ω, v)
    R_true, p_true = rt.compose_transforms(R_err, b_err, R_pose, p)
    moved = rt.compose_transforms(R, b, R_true, p_true)
    nominal_inverse = rt.invert_transform(*rt.compose_transforms(R, b, R_pose, p))
    twist = rt.screw_log(*rt.compose_transforms(*moved, *nominal_inverse))
    sampled = np.cov(np.hstack([twist[:, 3:], twist[:, :3]]).T)
    got = transform_pose_covariance(R, b, np.cov(xi.T), 'se3')
    assert _relative(got, sampled) < 1e-9
    assert _relative(transform_pose_covariance(R, b, np.cov(xi.T), 'ros'), sampled) > 0.1


def test_change_covariance_frame_agrees_with_sampling_and_batches():
    x = np.random.default_rng(12).standard_normal((SAMPLES, 3)) @ np.linalg.cholesky(C0).T
    R = rt.random_rotations(4, rng=13)
    got = change_covariance_frame(np.cov(x.T), R)
    for k in range(4):
        sampled = np.cov(rt.transform_points(R[k], [0, 0, 0], x).T)
        assert _relative(got[k], sampled) < 1e-9
        np.testing.assert_array_equal(got[k], change_covariance_frame(np.cov(x.T), R[k]))
    pose = np.zeros((6, 6))
    pose[3:, 3:] = C0
    np.testing.assert_allclose(transform_pose_covariance(R[0], [1, 2, 3], pose)[3:, 3:],
                               change_covariance_frame(C0, R[0]), rtol=1e-14)


# The ends of float64: converted at the scale of 1, exact arithmetic as the reference


def _exact_sandwich(M, C):
    """M·C·Mᵀ of the float64 entries in exact rational arithmetic, rounded once to float64."""
    M = [[Fraction(float(x)) for x in row] for row in np.asarray(M)]
    C = [[Fraction(float(x)) for x in row] for row in np.asarray(C)]
    n, m = len(M), len(C)
    MC = [[sum(M[i][k] * C[k][j] for k in range(m)) for j in range(m)] for i in range(n)]
    return np.array([[float(sum(MC[i][k] * M[j][k] for k in range(m))) for j in range(n)]
                     for i in range(n)])


def _adjoint(R, b):
    """[[R, [b]×·R], [0, R]], written out here."""
    bx = np.array([[0.0, -b[2], b[1]], [b[2], 0.0, -b[0]], [-b[1], b[0], 0.0]])
    return np.block([[R, bx @ R], [np.zeros((3, 3)), R]])


B0 = np.array([3.0, -2.0, 1.5])
SANDWICHES = {  # name: (the call on C, M such that the result is M·C·Mᵀ, C's size)
    'change_covariance_frame': (lambda C: change_covariance_frame(C, R0), R0, 3),
    'transform_pose_covariance ros': (
        lambda C: transform_pose_covariance(R0, B0, C), np.kron(np.eye(2), R0), 6),
    'transform_pose_covariance se3': (
        lambda C: transform_pose_covariance(R0, B0, C, 'se3'), _adjoint(R0, B0), 6),
}


@pytest.mark.parametrize('name', SANDWICHES)
@pytest.mark.parametrize('size', ['huge', 'subnormal'])
def test_huge_and_subnormal_covariances_are_carried_as_exact_arithmetic_carries_them(
        name, size):
    """s·I stays finite up to float64's largest result, 5e-324·I does not vanish."""
    call, M, n = SANDWICHES[name]
    scale = 0.9 * BIG / np.abs(M @ M.T).max() if size == 'huge' else 5e-324
    C = scale * np.eye(n)
    with np.errstate(over='raise', invalid='raise', divide='raise'):  # no warning
        got = call(C)
    want = _exact_sandwich(M, C)
    assert np.all(np.diag(got) > 0) and np.all(np.diag(got) <= np.diag(want) * (1 + 1e-15))
    np.testing.assert_allclose(got, want, rtol=0, atol=4e-16 * np.abs(want).max())
    np.testing.assert_array_equal(got, got.T)


@pytest.mark.parametrize('seq', ['xyz', 'ZYX', 'zxz'])
@pytest.mark.parametrize('scale', [1e307, 5e-324])
def test_euler_covariances_of_huge_and_subnormal_ones_are_linear_in_them(seq, scale):
    """f(s·C) = s·f(C) (one rounding): the conversions at s = 1 are checked above."""
    angles = rt.matrix_to_euler(R0, seq).angles
    unit = np.diag([1.0, 0.5, 0.25]) if scale > 1 else np.eye(3)  # (0.5·5e-324 is 0)
    with np.errstate(over='raise', invalid='raise', divide='raise'):
        to_euler = rotvec_covariance_to_euler(R0, scale * unit, seq).cov
        to_rotvec = euler_covariance_to_rotvec(angles, scale * unit, seq, 'body').cov
    for got, at_one in ((to_euler, rotvec_covariance_to_euler(R0, unit, seq).cov),
                        (to_rotvec, euler_covariance_to_rotvec(angles, unit, seq, 'body').cov)):
        assert np.diag(got).max() > 0, got
        np.testing.assert_allclose(got, scale * at_one, rtol=1e-15, atol=5e-324)


def test_the_issue_s_subnormal_covariance_is_kept_in_every_function():
    C = 5e-324 * np.eye(3)
    pose = 5e-324 * np.eye(6)
    for got in (change_covariance_frame(C, R0), rotvec_covariance_to_euler(R0, C).cov,
                euler_covariance_to_rotvec([0.1, 0.2, 0.3], C).cov,
                transform_pose_covariance(R0, B0, pose)):
        assert np.diag(got).min() == 5e-324, got


def test_a_covariance_converted_beyond_float64_is_refused():
    big = np.diag([BIG, BIG, BIG])
    with np.errstate(over='raise', invalid='raise', divide='raise'):
        with pytest.raises(RotationError, match=re.escape(
                'rotvec_covariance_to_euler: the converted covariance overflows float64 '
                '(beyond ±1.8e308), first at item (1,)')):
            rotvec_covariance_to_euler(np.stack([R0, R0]), np.stack([C0, big]))
        with pytest.raises(RotationError, match='transform_pose_covariance: the transformed '
                           r'covariance overflows float64 \(beyond ±1.8e308\)$'):
            transform_pose_covariance(R0, B0, np.diag([1.0] * 5 + [BIG]), 'se3')
        # at gimbal lock an item is NaN (degenerate), whatever its size
        lock = rt.euler_to_matrix([0.1, np.pi / 2, 0.2], 'xyz')
        out = rotvec_covariance_to_euler(np.stack([R0, lock]), np.stack([C0, big]), 'xyz')
        assert out.degenerate.tolist() == [False, True] and np.isnan(out.cov[1]).all()


@pytest.mark.parametrize('seq', ['xyz', 'ZYX', 'zxz', 'XZX'])
def test_gimbal_lock_distance_is_the_middle_angle_s(seq):
    angles = rt.matrix_to_euler(rt.random_rotations(50, rng=5), seq).angles
    np.testing.assert_allclose(gimbal_lock_distance(angles, seq), _lock_distance(angles, seq),
                               rtol=0, atol=1e-15)
    near = gimbal_lock_distance([0.3, np.pi / 2 - 1.7e-6, 1.1])
    assert near == pytest.approx(1.7e-6, rel=1e-9)


def test_a_covariance_near_gimbal_lock_has_a_note():
    """1.7e-6 rad from the lock, 0.01 rad of pitch: roll and yaw's 5,700 rad mean nothing."""
    rpy = [0.3, np.pi / 2 - 1.7e-6, 1.1]
    R = rt.euler_to_matrix(rpy, 'xyz')
    C, (status,) = rpy_covariances(R[None], (1e-4 * np.eye(3)).ravel()[None])
    sigma, _ = stddev_correlation(C[0])
    assert status == OK and sigma[0] > 5000 and sigma[1] == pytest.approx(0.01, rel=0.01)
    note = near_lock_note(gimbal_lock_distance(rpy), sigma[1])
    assert note.startswith('pitch is 1.7e-06 rad from gimbal lock (pitch = ±90°), within 3 of '
                           'its standard deviations (0.01 rad)'), note
    assert near_lock_note(0.05, 0.01) == ''  # 5 standard deviations away
    assert near_lock_note(1.7e-6, 1e-9) == ''  # first order holds: errors tiny against it


def test_message_covariances_at_the_ends_of_float64():
    """What the node and rot-tools bag publish: finite or BAD (said why), never inf or 0."""
    R = rt.euler_to_matrix([0.3, -0.5, 1.1], 'xyz')
    covs = np.stack([np.eye(3).ravel() * k for k in (1e308, BIG, 5e-324)])
    with np.errstate(over='raise', invalid='raise', divide='raise'):
        C, status = rpy_covariances(np.stack([R] * 3), covs)
    assert status.tolist() == [OK, BAD, OK]
    assert np.isfinite(C[0]).all() and np.isnan(C[1]).all()
    assert np.diag(C[2]).min() == 5e-324
    assert fault(covs[1]) == ('covariance: its covariance of roll, pitch, yaw overflows float64 '
                              '(beyond ±1.8e308)')
    with np.errstate(over='raise', invalid='raise', divide='raise'):  # read as roll, pitch, yaw
        C, status = rpy_covariances(np.stack([R] * 3), covs, 'rpy')
    assert status.tolist() == [OK] * 3
    np.testing.assert_array_equal(C, covs.reshape(3, 3, 3))
