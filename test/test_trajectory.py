"""An orientation against ground truth: matching, time offset, alignment, mounting, errors."""

import math
import tracemalloc
import warnings

from hypothesis import given, settings, strategies as st
import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    align_rotations, angular_speeds, delta_pairs, error_statistics, estimate_time_offset,
    hand_eye_rotation, interpolate_poses, nearest_stamps, random_rotations, rot_x, rot_z,
    rotation_errors, RotationError, rotvec_to_matrix, skew)
from rot_tools.core.stamps import order_stamps
from scipy import linalg, optimize
from scipy.spatial.transform import Rotation

DEG = math.pi / 180


def motion(t):
    """Smooth rotations turning about all three axes (rotation vectors of sinusoids)."""
    t = np.asarray(t, dtype=float)
    v = np.stack([0.6 * np.sin(1.3 * t) + 0.2 * np.sin(3.1 * t),
                  0.5 * np.sin(0.7 * t + 1) + 0.3 * np.cos(2.3 * t),
                  0.9 * np.sin(0.5 * t) + 0.2 * np.sin(4.1 * t)], axis=-1)
    return Rotation.from_rotvec(v).as_matrix()


def path(t):
    """Positions along a smooth curve that leaves every plane."""
    t = np.asarray(t, dtype=float)
    return np.stack([3 * np.cos(0.4 * t), 2 * np.sin(0.3 * t), 0.5 * t + np.sin(t)], axis=-1)


def angle_between(R1, R2):
    """Geodesic angle by scipy (quaternions): independent of rot_tools."""
    return (Rotation.from_matrix(R1).inv() * Rotation.from_matrix(R2)).magnitude()


def relative(R, i, j):
    return np.swapaxes(R[i], -1, -2) @ R[j]


# ---- interpolate_poses -----------------------------------------------------------------------


def screw_motion(t):
    """T(t) = T0·exp(t·ξ), by scipy's matrix exponential of the 4×4 twist."""
    omega, v = np.array([0.3, -0.5, 0.8]), np.array([1.0, 0.2, -0.4])
    xi = np.zeros((4, 4))
    xi[:3, :3], xi[:3, 3] = skew(omega), v
    T0 = np.eye(4)
    T0[:3, :3], T0[:3, 3] = rot_x(0.4) @ rot_z(-1.1), [2.0, -1.0, 0.5]
    T = np.array([T0 @ linalg.expm(s * xi) for s in np.atleast_1d(t)])
    return T[:, :3, :3], T[:, :3, 3]


def test_interpolation_is_exact_on_a_constant_screw_motion():
    stamps = np.array([0.0, 0.3, 0.45, 1.2, 1.25, 2.0])
    R, b = screw_motion(stamps)
    at = np.random.default_rng(1).uniform(0, 2, 60)
    R_at, b_at, covered = interpolate_poses(stamps, R, b, at, max_gap=1.0)
    assert covered.all()
    R_true, b_true = screw_motion(at)
    assert h.max_abs(R_at - R_true) < 1e-14
    assert h.max_abs(b_at - b_true) < 1e-14


def test_interpolation_covers_only_times_with_both_neighbours_near():
    stamps = np.array([0.0, 0.1, 0.2, 1.0, 1.1])
    R = rot_z(stamps)
    at = np.array([-0.01, 0.0, 0.05, 0.15, 0.25, 0.5, 0.95, 1.0, 1.05, 1.1, 1.2])
    R_at, b_at, covered = interpolate_poses(stamps, R, None, at, max_gap=0.1)
    # 0.25 and 0.95 have one neighbour near and one far; a stamp itself is always covered
    assert covered.tolist() == [False, True, True, True, False, False, False, True, True, True,
                                False]
    assert b_at is None
    assert h.max_abs(R_at - rot_z(at[covered])) < 1e-15  # a turn about z: slerp is exact


def test_interpolated_matching_beats_nearest_on_two_rates():
    t_est = np.arange(0.0, 20.0, 0.01)  # 100 Hz
    t_ref = np.arange(0.004, 20.0, 1 / 7)  # 7 Hz
    R_ref, b_ref = motion(t_ref), path(t_ref)
    R_int, _, covered = interpolate_poses(t_ref, R_ref, b_ref, t_est, max_gap=0.2)
    index, near = nearest_stamps(t_ref, t_est, max_gap=0.2)
    assert covered.sum() > 1900 and near.sum() > 1900
    interpolated = rotation_errors(R_int, motion(t_est[covered])).ape['rmse']
    nearest = rotation_errors(R_ref[index], motion(t_est[near])).ape['rmse']
    assert interpolated < nearest / 5, (interpolated, nearest)


# ---- nearest_stamps --------------------------------------------------------------------------


def brute_nearest(stamps, at, gap):
    d = np.abs(stamps[None, :] - at[:, None])
    index = np.argmin(d, axis=1)  # the first of equal distances: the earlier stamp
    covered = d[np.arange(len(at)), index] <= gap
    return index[covered], covered


@settings(**h.HYPOTHESIS_SETTINGS)
@given(st.lists(st.integers(-50, 50), min_size=1, max_size=12, unique=True),
       st.lists(st.integers(-60, 60), min_size=1, max_size=12), st.integers(0, 5))
def test_nearest_is_the_brute_force_nearest_with_ties_to_the_earlier(stamps, at, gap):
    # integers (then scaled by 1/4): exact ties happen often
    stamps, at = np.sort(np.array(stamps)) / 4, np.array(at) / 4
    index, covered = nearest_stamps(stamps, at, max_gap=gap / 4)
    want_index, want_covered = brute_nearest(stamps, at, gap / 4)
    assert covered.tolist() == want_covered.tolist()
    assert index.tolist() == want_index.tolist()


def test_nearest_tie_goes_to_the_earlier_stamp():
    index, covered = nearest_stamps([1.0, 2.0], [1.5, 1.5000001], max_gap=0.5)
    assert index.tolist() == [0, 1] and covered.all()


# ---- order_stamps ----------------------------------------------------------------------------


@settings(**h.HYPOTHESIS_SETTINGS)
@given(st.lists(st.integers(0, 8), max_size=12), st.booleans())
def test_stamps_are_sorted_keeping_the_first_of_equal_ones(stamps, nanoseconds):
    given_ = np.array(stamps, dtype=np.int64) if nanoseconds else np.array(stamps) / 4 + 1.3e9
    order = order_stamps(given_)
    first = {}  # stamp → the first index that carries it, by a plain walk
    for k, stamp in enumerate(given_.tolist()):
        first.setdefault(stamp, k)
    assert order.index.tolist() == [first[stamp] for stamp in sorted(first)]
    assert order.dropped_duplicates == len(stamps) - len(first)
    assert order.reordered == sum(any(later < earlier for earlier in stamps[:k])
                                  for k, later in enumerate(stamps))


def test_ordering_nanoseconds_keeps_them_apart():
    ns = np.array([1311868229576000100, 1311868229576000000, 1311868229576000100])
    order = order_stamps(ns)  # as floats in seconds, all three would be one stamp
    assert order.index.tolist() == [1, 0] and order == (order.index, 1, 1)


# ---- estimate_time_offset --------------------------------------------------------------------


@pytest.mark.parametrize('offset', [0.237, -0.4132, 0.0, 0.9])
def test_a_known_time_offset_is_recovered_below_one_sample(offset):
    t_ref = np.arange(0.0, 40.0, 0.01)  # 100 Hz
    t_est = np.arange(0.003, 40.0, 0.02)  # 50 Hz, its own clock
    R_est = motion(t_est + offset) @ rot_x(0.7)  # EST's sample at t_est happened at t + offset
    R_ref = rot_z(1.2) @ motion(t_ref)  # in another frame: the speeds do not see it
    found = estimate_time_offset(t_est, R_est, t_ref, R_ref)
    assert abs(found.offset - offset) < 0.2 * 0.01, found
    assert found.correlation > 0.99


def test_the_offset_is_the_one_that_aligns_the_streams():
    t = np.arange(0.0, 30.0, 0.01)
    R_ref = motion(t)
    R_est = motion(t + 0.31)
    offset = estimate_time_offset(t, R_est, t, R_ref).offset
    R_at, _, covered = interpolate_poses(t, R_ref, None, t + offset, max_gap=0.1)
    shifted = rotation_errors(R_at, R_est[covered]).ape['max']
    R_at, _, covered = interpolate_poses(t, R_ref, None, t - offset, max_gap=0.1)
    assert shifted < 1e-3 < rotation_errors(R_at, R_est[covered]).ape['max']


def test_the_offset_is_found_under_gyro_noise():
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 40.0, 0.005)  # 200 Hz
    R_ref = motion(t)
    # 0.02° of jitter per sample, as an orientation filter's: |ω| from 5 ms steps of it
    # is ~0.1 rad/s of noise (0.2° would swamp the motion's speeds)
    noise = rotvec_to_matrix(rng.normal(scale=0.02 * DEG, size=(len(t), 3)))
    R_est = motion(t - 0.0525) @ noise
    found = estimate_time_offset(t, R_est, t, R_ref, max_offset=0.5)
    assert abs(found.offset + 0.0525) < 0.1 * 0.005, found
    assert found.correlation > 0.9


@pytest.mark.parametrize('max_offset', [1e6, 1e300])
def test_a_huge_max_offset_searches_only_where_the_streams_overlap(max_offset):
    t_ref = 1.3e9 + np.arange(0.0, 12.0, 0.01)
    t_est = 1.3e9 + np.arange(0.003, 12.0, 0.02)
    R_est, R_ref = motion(t_est - 1.3e9 + 0.25), motion(t_ref - 1.3e9)
    tracemalloc.start()
    try:
        found = estimate_time_offset(t_est, R_est, t_ref, R_ref, max_offset=max_offset)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert abs(found.offset - 0.25) < 0.2 * 0.01, found  # not a grid of max_offset / 2^20
    assert peak < 20e6  # the 24 s of overlap, not max_offset, size the search


def test_angular_speed_of_a_uniform_turn():
    t = np.array([0.0, 0.5, 0.6, 2.0])
    mid, speed = angular_speeds(t, rot_z(0.3 * t))
    assert mid.tolist() == [0.25, 0.55, 1.3]
    assert h.max_abs(speed - 0.3) < 1e-14


# ---- align_rotations -------------------------------------------------------------------------


def test_rotation_alignment_recovers_the_frame_rotation():
    rng = np.random.default_rng(2)
    R_est = random_rotations(50, rng)
    W = random_rotations(None, rng)
    noise = rotvec_to_matrix(rng.normal(scale=0.01, size=(50, 3)))
    R_ref = W @ R_est @ noise
    found, t = align_rotations(R_ref, R_est, 'rotation')
    assert angle_between(found, W) < 0.01 and not t.any()
    exact, _ = align_rotations(W @ R_est, R_est, 'rotation')
    assert angle_between(exact, W) < 1e-14

    def cost(rotvec):  # the chordal least squares, minimised by scipy from the answer
        M = Rotation.from_rotvec(rotvec).as_matrix()
        return np.sum((R_ref - M @ R_est) ** 2)

    best = optimize.minimize(cost, Rotation.from_matrix(found).as_rotvec(), tol=1e-14)
    assert angle_between(Rotation.from_rotvec(best.x).as_matrix(), found) < 1e-7


def test_yaw_alignment_recovers_a_yaw_and_is_the_best_yaw():
    rng = np.random.default_rng(3)
    R_est = random_rotations(40, rng)
    W, _ = align_rotations(rot_z(2.5) @ R_est, R_est, 'yaw')
    assert h.max_abs(W - rot_z(2.5)) < 1e-14
    R_ref = rot_x(0.2) @ rot_z(-1.0) @ R_est  # not a yaw: the best yaw by brute force
    W, _ = align_rotations(R_ref, R_est, 'yaw')

    def best_of(psi):
        cost = np.sum((R_ref[None] - rot_z(psi)[:, None] @ R_est[None]) ** 2, axis=(1, 2, 3))
        return psi[np.argmin(cost)]

    coarse = best_of(np.linspace(-np.pi, np.pi, 3601))  # every 0.1°, then ±0.1° finely
    best = best_of(np.linspace(coarse - 0.002, coarse + 0.002, 4001))
    assert abs(math.atan2(W[1, 0], W[0, 0]) - best) < 1e-5
    assert W[2, 2] == 1.0


def test_se3_alignment_recovers_a_rigid_motion():
    t = np.linspace(0, 10, 80)
    W = Rotation.from_rotvec([0.3, -1.2, 0.5]).as_matrix()
    shift = np.array([4.0, -2.0, 1.5])
    b_est, R_est = path(t), motion(t)
    b_ref = b_est @ W.T + shift
    found, found_t = align_rotations(W @ R_est, R_est, 'se3', b_ref=b_ref, b_est=b_est)
    assert angle_between(found, W) < 1e-13
    assert h.max_abs(found_t - shift) < 1e-12
    noisy = b_ref + np.random.default_rng(5).normal(scale=0.05, size=b_ref.shape)
    found, _ = align_rotations(R_est, R_est, 'se3', b_ref=noisy, b_est=b_est)
    scipy_fit, _ = Rotation.align_vectors(noisy - noisy.mean(0), b_est - b_est.mean(0))
    assert angle_between(found, scipy_fit.as_matrix()) < 1e-12


def test_posyaw_alignment_is_the_best_yaw_and_translation_of_the_positions():
    rng = np.random.default_rng(11)
    t = np.linspace(0, 10, 60)
    b_est, R_est = path(t), motion(t)
    yaw, shift = rot_z(2.2), np.array([4.0, -2.0, 1.5])
    b_ref = b_est @ yaw.T + shift
    found, found_t = align_rotations(yaw @ R_est, R_est, 'posyaw', b_ref=b_ref, b_est=b_est)
    assert angle_between(found, yaw) < 1e-13 and h.max_abs(found_t - shift) < 1e-12
    # noisy, and tilted (a yaw cannot undo a tilt): the 4-DoF least squares, by scipy
    noisy = (b_est @ (rot_x(0.05) @ yaw).T + shift + rng.normal(scale=0.1, size=b_est.shape))
    W, t_found = align_rotations(R_est, R_est, 'posyaw', b_ref=noisy, b_est=b_est)

    def residuals(x):
        return (noisy - b_est @ rot_z(x[0]).T - x[1:]).ravel()

    best = min((optimize.least_squares(residuals, [psi, 0, 0, 0], xtol=1e-15, ftol=1e-15)
                for psi in (-2.0, 0.0, 2.0)), key=lambda fit: fit.cost)
    assert W[2, 2] == 1.0 and W[2, :2].tolist() == [0.0, 0.0]
    assert abs(np.angle(np.exp(1j * (math.atan2(W[1, 0], W[0, 0]) - best.x[0])))) < 1e-9
    assert h.max_abs(t_found - best.x[1:]) < 1e-8


def test_no_alignment_is_the_identity():
    W, t = align_rotations(motion([1.0, 2.0]), motion([3.0, 4.0]), 'none')
    assert (W == np.eye(3)).all() and not t.any()


# ---- hand_eye_rotation -----------------------------------------------------------------------


def mounted(X, delta=20, noise=0.0, axes=3, seed=6, step=None):
    """Relative rotations of a reference and of a sensor mounted by X on the same body."""
    t = np.arange(0.0, 30.0, 0.01)
    R_ref = motion(t) if axes == 3 else rot_z(np.sin(t) * 2) @ rot_x(0.1)
    rng = np.random.default_rng(seed)
    R_est = rot_z(0.8) @ R_ref @ X  # its own world frame too: hand-eye does not see it
    R_est = R_est @ rotvec_to_matrix(rng.normal(scale=noise, size=(len(t), 3)))
    i = np.arange(0, len(t) - delta, step or delta)
    return relative(R_ref, i, i + delta), relative(R_est, i, i + delta)


def test_a_mounting_rotation_is_recovered():
    X = Rotation.from_euler('xyz', [10, -75, 140], degrees=True).as_matrix()
    A, B = mounted(X)
    found = hand_eye_rotation(A, B)
    assert angle_between(found.rotation, X) < 1e-13
    assert found.residual < 1e-14 and found.axes == 3 and found.warning == ''
    # and for every k, A_k·X = X·B_k
    assert h.max_abs(A @ found.rotation - found.rotation @ B) < 1e-13


def test_a_mounting_rotation_is_recovered_within_a_tenth_of_a_degree_under_noise():
    X = Rotation.from_euler('xyz', [90, 0, -90], degrees=True).as_matrix()
    A, B = mounted(X, delta=50, step=10, noise=0.3 * DEG)  # 0.3° of noise on every sample
    found = hand_eye_rotation(A, B)
    assert angle_between(found.rotation, X) < 0.1 * DEG
    assert 0.5 * DEG < found.residual < 1.0 * DEG  # the noise of two samples, √2·0.3°·√3
    assert found.axes >= 2 and found.warning == ''


def test_motion_about_one_axis_is_flagged_not_trusted():
    X = Rotation.from_euler('xyz', [20, 30, 40], degrees=True).as_matrix()
    A, B = mounted(X, axes=1, noise=0.01 * DEG)
    found = hand_eye_rotation(A, B)
    assert found.axes == 1
    # one axis exactly: said in words, not as a ratio at round-off level
    assert found.warning.startswith('the motion turned about one axis only')
    assert found.singular_values[1] < 0.05 * found.singular_values[0]


def test_park_and_martin_closed_form_agrees():
    X = Rotation.from_euler('zyx', [33, -12, 70], degrees=True).as_matrix()
    A, B = mounted(X, noise=0.5 * DEG, delta=35)
    alpha, beta = Rotation.from_matrix(A).as_rotvec(), Rotation.from_matrix(B).as_rotvec()
    M = beta.T @ alpha  # Σ β_k·α_kᵀ
    vals, vecs = np.linalg.eigh(M.T @ M)
    park_martin = vecs @ np.diag(vals ** -0.5) @ vecs.T @ M.T
    assert angle_between(hand_eye_rotation(A, B).rotation, park_martin) < 1e-12


# ---- rotation_errors -------------------------------------------------------------------------


def test_absolute_errors_and_statistics_against_scipy():
    rng = np.random.default_rng(7)
    R_ref = random_rotations(300, rng)
    R_est = R_ref @ rotvec_to_matrix(rng.normal(scale=0.3, size=(300, 3)))
    R_est[0] = R_ref[0]  # an angle 0
    R_est[1] = R_ref[1] @ rot_x(np.pi)  # an angle π
    errors = rotation_errors(R_ref, R_est)
    want = angle_between(R_ref, R_est)
    assert h.max_abs(errors.angle - want) < 1e-14
    assert errors.angle[0] == 0 and errors.angle[1] == np.pi
    assert errors.ape['rmse'] == pytest.approx(math.sqrt(np.sum(want ** 2) / len(want)),
                                               rel=1e-14)
    assert errors.ape['std'] == pytest.approx(
        math.sqrt(np.sum((want - want.mean()) ** 2) / len(want)), rel=1e-12)
    assert errors.ape['median'] == pytest.approx(np.sort(want)[149:151].mean(), rel=1e-14)
    assert errors.ape['min'] == 0 and errors.ape['max'] == np.pi
    assert errors.ape['mean'] == pytest.approx(want.mean(), rel=1e-14)


def test_error_roll_pitch_yaw_against_scipy_and_continuous():
    t = np.linspace(0, 10, 500)
    yaw = 1.5 * t  # the yaw error grows through ±π: unwrapped, it keeps growing
    E = Rotation.from_euler('xyz', np.stack([0.1 * np.sin(t), 0.2 * np.cos(t), yaw], -1))
    R_ref = motion(t)
    errors = rotation_errors(R_ref, R_ref @ E.as_matrix())
    assert h.max_abs(errors.rpy - np.stack([0.1 * np.sin(t), 0.2 * np.cos(t), yaw], -1)) < 1e-13
    wrapped = Rotation.from_matrix(np.swapaxes(R_ref, 1, 2) @ R_ref @ E.as_matrix())
    assert h.max_abs(np.angle(np.exp(1j * errors.rpy)) - wrapped.as_euler('xyz')) < 1e-12
    # the statistics are over E's angles wrapped to (−π, π], as scipy gives them (−π → π)
    by_scipy = wrapped.as_euler('xyz')
    by_scipy[by_scipy <= -np.pi] += 2 * np.pi
    for k, axis in enumerate(('roll', 'pitch', 'yaw')):
        want = by_scipy[:, k]
        assert errors.rpy_statistics[k] == pytest.approx(
            {'rmse': np.sqrt(np.mean(want ** 2)), 'mean': np.mean(want),
             'median': np.median(want), 'std': np.std(want), 'min': np.min(want),
             'max': np.max(want)}, rel=1e-9, abs=1e-12), axis
    assert errors.rpy_statistics[2]['max'] <= np.pi and errors.rpy_statistics[2]['min'] > -np.pi
    assert errors.rpy_statistics[2]['rmse'] < 2 < errors.rpy[-1, 2] / 7  # not 15 rad


def test_error_angles_at_minus_pi_wrap_to_plus_pi():
    E = rot_x(np.pi) @ rot_z(np.pi)  # roll and yaw at ±π: either sign is the same rotation
    errors = rotation_errors(np.repeat(np.eye(3)[None], 2, 0), np.array([E, E.T]))
    for k in (0, 2):
        assert errors.rpy_statistics[k]['min'] == errors.rpy_statistics[k]['max'] == np.pi


@pytest.mark.parametrize('delta', [1, 2, 5, 7])
def test_relative_errors_against_scipy_as_evo_pairs_them(delta):
    rng = np.random.default_rng(8)
    t = np.arange(0.0, 5.0, 0.05)
    R_ref = motion(t)
    R_est = rot_z(0.9) @ R_ref @ rotvec_to_matrix(rng.normal(scale=0.02, size=(len(t), 3)))
    errors = rotation_errors(R_ref, R_est, delta=delta)
    ids = list(range(0, len(t), delta))  # evo: consecutive pairs of every delta-th pose
    pairs = list(zip(ids, ids[1:]))
    assert errors.pairs.tolist() == [list(p) for p in pairs]
    i, j = np.array(pairs).T
    want = angle_between(relative(R_ref, i, j), relative(R_est, i, j))
    assert h.max_abs(errors.rpe_angle - want) < 1e-14
    assert errors.rpe == pytest.approx(
        {'rmse': np.sqrt(np.mean(want ** 2)), 'mean': np.mean(want), 'median': np.median(want),
         'std': np.std(want), 'min': np.min(want), 'max': np.max(want)}, rel=1e-12)


def test_relative_pairs_in_seconds():
    rng = np.random.default_rng(9)
    t = 1.7e9 + np.cumsum(rng.uniform(0.01, 0.05, 400))
    pairs = delta_pairs(len(t), 0.5, 's', t)
    i, j = pairs.T
    assert i[0] == 0 and (i[1:] == j[:-1]).all()  # chained: non-overlapping
    assert (t[j] - t[i] >= 0.5 - 1e-6).all()
    assert (t[j - 1] - t[i] < 0.5).all()  # the first stamp at least delta later
    assert len(t) - 1 - j[-1] < 50  # the last pair ends within delta of the end
    stamps = np.arange(0, 10) * 0.1  # steps of 0.1 that round below it still count
    assert delta_pairs(10, 0.2, 's', stamps).tolist() == [[0, 2], [2, 4], [4, 6], [6, 8]]


def test_error_statistics_of_known_numbers():
    stats = error_statistics([3.0, 4.0, 0.0, 1.0])
    assert stats == {'rmse': math.sqrt(26 / 4), 'mean': 2.0, 'median': 2.0,
                     'std': math.sqrt(2.5), 'min': 0.0, 'max': 4.0}


# ---- refusals --------------------------------------------------------------------------------


EYE3 = np.repeat(np.eye(3)[None], 3, axis=0)
T3 = np.array([0.0, 1.0, 2.0])
FAR = 1.5e308 + 1e306 * np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


@pytest.mark.parametrize('call, message', [
    (lambda: interpolate_poses([0.0, 1.0, 1.0], EYE3, None, [0.5]),
     r'stamps must be strictly increasing: stamps\[2\] = 1.0 follows stamps\[1\] = 1.0'),
    (lambda: interpolate_poses([0.0], EYE3[:1], None, [0.5]),
     r'stamps has 1 stamp\(s\): at least 2 needed'),
    (lambda: interpolate_poses([[0.0, 1.0]], EYE3, None, [0.5]),
     r'stamps must have shape \(N,\), got \(1, 2\)'),
    (lambda: interpolate_poses([0.0, np.nan, 2.0], EYE3, None, [0.5]),
     r'stamps must be finite: 1 non-finite value\(s\), first nan at index \(1,\)'),
    (lambda: interpolate_poses(T3, EYE3[:2], None, [0.5]), r'R has 2 rotations for 3 stamps'),
    (lambda: interpolate_poses(T3, EYE3 * 2, None, [0.5]), r'not orthogonal'),
    (lambda: interpolate_poses(T3, EYE3, np.zeros((2, 3)), [0.5]),
     r'b must have shape \(3, 3\), one per stamp, got \(2, 3\)'),
    (lambda: interpolate_poses(T3, EYE3, None, [[0.5]]), r'at must have shape \(M,\)'),
    (lambda: interpolate_poses(T3, EYE3, None, [np.inf]), r'at must be finite'),
    (lambda: interpolate_poses(T3, EYE3, None, [0.5], max_gap=-1),
     r'max_gap must be a number ≥ 0, got -1'),
    (lambda: nearest_stamps([], [0.5]), r'stamps has 0 stamp\(s\): at least 1 needed'),
    (lambda: nearest_stamps([2.0, 1.0], [0.5]), r'stamps must be strictly increasing'),
    (lambda: nearest_stamps(T3, [0.5], max_gap=np.nan), r'max_gap must be a number ≥ 0'),
    (lambda: angular_speeds([0.0], EYE3[:1]), r'stamps of R has 1 stamp\(s\): at least 2'),
    (lambda: estimate_time_offset(T3, EYE3, T3, EYE3),
     r'R_est turns at a constant speed \(0 rad/s\): no feature to align in time'),
    (lambda: estimate_time_offset(T3, rot_z(T3 ** 2), T3 + 10, rot_z(T3 ** 2)),
     r'the streams do not overlap within max_offset = 1.0 s: R_ref spans \[10.5, 11.5\] s, '
     r'R_est \[0.5, 1.5\] s'),
    (lambda: estimate_time_offset(T3, rot_z(T3 ** 2), T3, rot_z(T3 ** 2), max_offset='1'),
     r"max_offset must be a number ≥ 0, got '1'"),
    (lambda: align_rotations(EYE3, EYE3, 'scale'),
     r"method must be one of none, rotation, yaw, se3, posyaw, got 'scale'"),
    (lambda: align_rotations(EYE3, EYE3, 'posyaw', b_est=np.eye(3)),
     r"method 'posyaw' fits positions: give b_ref and b_est"),
    (lambda: align_rotations(EYE3[:1], EYE3[:1], 'posyaw', b_ref=np.eye(3)[:1],
                             b_est=np.eye(3)[:1]),
     r"method 'posyaw' needs at least 2 positions, got 1"),
    (lambda: align_rotations(EYE3, EYE3, 'posyaw', b_ref=np.eye(3), b_est=np.diag([0, 0, 1.0])),
     r"method 'posyaw' needs positions that move in x and y: b_est moves along z only"),
    (lambda: align_rotations(EYE3, EYE3[:2]),
     r'R_ref has 3 rotations but R_est has 2: pairs are needed'),
    (lambda: align_rotations(EYE3[0], EYE3[0]), r'R_ref must have shape \(N, 3, 3\)'),
    (lambda: align_rotations(EYE3, EYE3, 'se3'), r"method 'se3' fits positions"),
    (lambda: align_rotations(EYE3[:2], EYE3[:2], 'se3', b_ref=np.eye(2, 3), b_est=np.eye(2, 3)),
     r"method 'se3' needs at least 3 positions, got 2"),
    (lambda: align_rotations(EYE3, EYE3, 'se3', b_ref=np.eye(3), b_est=np.ones((3, 3))),
     r"method 'se3' needs positions that move: b_est stands still"),
    (lambda: align_rotations(EYE3, EYE3, 'se3', b_ref=-FAR, b_est=FAR),
     r'b_ref, b_est: positions of ±1.5e\+308 leave float64 in the fit'),
    (lambda: align_rotations(EYE3, EYE3, 'posyaw', b_ref=-FAR, b_est=FAR),
     r'b_ref, b_est: positions of ±1.5e\+308 leave float64 in the fit'),
    (lambda: angular_speeds([0.0, 5e-324], EYE3[:2] @ rot_x([0.0, 1.0])),
     r'R turns faster than float64 holds: 1.0 rad in 5e-324 s at stamp 0.0'),
    (lambda: angular_speeds([-1e308, 1e308], EYE3[:2]),
     r'stamps of R span -1e\+308 to 1e\+308 s: their differences overflow float64'),
    (lambda: align_rotations(EYE3, EYE3, 'se3', b_ref=np.eye(3), b_est=np.eye(3)[:2]),
     r'b_est must have shape \(3, 3\), one per stamp, got \(2, 3\)'),
    (lambda: align_rotations(rot_x([np.pi]), np.eye(3)[None], 'yaw'),
     r'the yaw alignment is not unique: every turn about z fits as well'),
    (lambda: hand_eye_rotation(EYE3, EYE3[:2]), r'R_ref has 3 rotations but R_est has 2'),
    (lambda: hand_eye_rotation(EYE3[:1], EYE3[:1]), r'1 pair\(s\) of rotations: at least 2'),
    (lambda: hand_eye_rotation(rot_z([0.1, 0.2, 0.0]), rot_z([0.1, 0.0, 0.3])),
     r'1 of 3 relative rotations turn \(in A and B both\): the motion never turns enough'),
    (lambda: rotation_errors(EYE3[:1], EYE3[:1]), r'1 pair\(s\) of rotations: at least 2'),
    (lambda: rotation_errors(EYE3, EYE3, delta=3), r'delta = 3 frames leaves no pair among 3'),
    (lambda: rotation_errors(EYE3, EYE3, delta=1.5),
     r'delta in frames must be an integer ≥ 1, got 1.5'),
    (lambda: rotation_errors(EYE3, EYE3, delta=True), r'delta in frames must be an integer'),
    (lambda: rotation_errors(EYE3, EYE3, delta='x'), r"must be an integer ≥ 1, got 'x'"),
    (lambda: rotation_errors(EYE3, EYE3, unit='m'),
     r"unit must be 'f' \(frames\) or 's' \(seconds\), got 'm'"),
    (lambda: rotation_errors(EYE3, EYE3, 0.5, 's'), r"delta in seconds \(unit 's'\) needs"),
    (lambda: rotation_errors(EYE3, EYE3, 0.5, 's', [0, 1]), r'stamps has 2 entries for 3 poses'),
    (lambda: rotation_errors(EYE3, EYE3, 0, 's', T3), r'delta in seconds must be > 0, got 0'),
    (lambda: rotation_errors(EYE3, EYE3, 5.0, 's', T3), r'delta = 5.0 s leaves no pair'),
])
def test_bad_input_is_refused_saying_what(call, message):
    with pytest.raises(RotationError, match=message):
        call()


DAY = np.array(['2020-01-01T00:00:00', '2020-01-01T00:00:01', '2020-01-01T00:00:02'],
               dtype='datetime64[s]')
UNIX = np.array([1311868229.476, 1311868229.526, 1311868229.576])


@pytest.mark.parametrize('call, message', [
    (lambda: delta_pairs(3, 1e-7, 's', UNIX),
     r'delta = 1e-07 s is within the rounding of stamps near 1311868229.576 s \(1.2e-06 s\)'),
    (lambda: delta_pairs(3, 1e-300, 's', [0.0, 1.0, 2.0]),
     r'delta = 1e-300 s is within the rounding of stamps near 2.0 s'),
    (lambda: delta_pairs(3, 0.5, 's', DAY),
     r'stamps must be numbers, got datetime64\[s\] values: seconds are needed'),
    (lambda: interpolate_poses(DAY, EYE3, None, [0.5]), r'stamps must be numbers, got datetime64'),
    (lambda: delta_pairs(3, 1, 's', np.array([1, 2, 3], dtype='timedelta64[ms]')),
     r'stamps must be numbers, got timedelta64\[ms\] values'),
    (lambda: delta_pairs('x', 1), r"count must be a whole number ≥ 0, got 'x'"),
    (lambda: delta_pairs(-1, 1), r'count must be a whole number ≥ 0, got -1'),
    (lambda: delta_pairs(2.5, 1), r'count must be a whole number ≥ 0, got 2.5'),
    (lambda: delta_pairs(True, 1), r'count must be a whole number ≥ 0, got True'),
    (lambda: delta_pairs(10 ** 30, 1), r'count must be at most 268435456 poses, got 1e\+30'),
    (lambda: delta_pairs(3, np.float64(1.5)), r'delta in frames must be an integer ≥ 1, got 1.5$'),
    (lambda: delta_pairs(3, 1, 's', [1e308, -1e308, 1e308]),
     r'stamps must be strictly increasing: stamps\[1\] = -1e\+308 follows stamps\[0\] = 1e\+308'),
    (lambda: delta_pairs(3, 1, 's', [0.0, 1e308, 1.7e308]), r'within the rounding of stamps'),
    (lambda: delta_pairs(3, 2.0, 's', [0.0, 0.5, 1.0]), r'delta = 2.0 s leaves no pair among 3'),
    (lambda: error_statistics([]), r'x has no value: statistics need at least one'),
    (lambda: error_statistics([1.0, np.nan]), r'x must be finite: 1 non-finite value'),
    (lambda: error_statistics([[1.0, 2.0]]), r'x must have shape \(K,\), got \(1, 2\)'),
    (lambda: error_statistics(5.0), r'x must have shape \(K,\), got \(\)'),
    (lambda: error_statistics('abc'), r'x must be numeric'),
    (lambda: error_statistics([1 + 1j]), r'x must be real'),
    (lambda: error_statistics(DAY), r'x must be numbers, got datetime64'),
])
def test_hostile_input_is_refused_saying_what(call, message):
    with pytest.raises(RotationError, match=message):
        call()


def test_statistics_of_huge_errors_do_not_overflow():
    stats = error_statistics([-1e308, 1e308, 1e308])
    assert stats['mean'] == pytest.approx(1e308 / 3, rel=1e-15)
    assert stats['rmse'] == pytest.approx(1e308, rel=1e-15)
    assert stats['std'] == pytest.approx(math.sqrt(8 / 9) * 1e308, rel=1e-15)
    assert stats['min'] == -1e308 and stats['max'] == 1e308 and stats['median'] == 1e308


def test_pairs_in_seconds_on_unix_time_at_the_resolution_of_the_stamps():
    t = 1311868229.576 + np.arange(6) * 2.4e-6  # steps of ten ulps
    assert delta_pairs(6, 4e-6, 's', t).tolist() == [[0, 2], [2, 4]]
    assert delta_pairs(6, 4e-6, 's', t, overlapping=True).tolist() == [
        [0, 2], [1, 3], [2, 4], [3, 5]]
    assert delta_pairs(6, 2, overlapping=True).tolist() == [[0, 2], [1, 3], [2, 4], [3, 5]]
    assert delta_pairs(3, 1e308, 's', [0.0, 1e308, 1.7e308]).tolist() == [[0, 1]]


HOSTILE = st.one_of(
    st.none(), st.booleans(), st.integers(-3, 12), st.integers(-2 ** 80, 2 ** 80),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=3),
    st.complex_numbers(max_magnitude=10), st.just(np.datetime64('2020-01-01')),
    st.lists(st.floats(allow_nan=True, allow_infinity=True), max_size=6),
    st.lists(st.integers(-5, 5), max_size=6).map(np.array),
    st.lists(st.floats(-1e9, 1e9), min_size=1, max_size=6).map(lambda x: np.sort(x) + 1.3e9),
    st.just(DAY), st.just([[0.0, 1.0]]), st.just(np.zeros((0, 3))))


def _finite(result):
    if isinstance(result, dict):
        return all(math.isfinite(v) for v in result.values())
    return result.dtype.kind == 'i' and result.ndim == 2 and result.shape[1] == 2


@settings(**{**h.HYPOTHESIS_SETTINGS, 'max_examples': 150})
@given(HOSTILE, HOSTILE, st.sampled_from(['f', 's', 'x', None]), HOSTILE, HOSTILE,
       st.booleans())
def test_hostile_pairs_and_statistics_give_a_refusal_or_finite_numbers(
        count, delta, unit, stamps, x, overlapping):
    with warnings.catch_warnings():
        warnings.simplefilter('error')  # a RuntimeWarning is a failure too
        for call in (lambda: delta_pairs(count, delta, unit, stamps, overlapping=overlapping),
                     lambda: delta_pairs(len(stamps) if hasattr(stamps, '__len__') else 3,
                                         delta, 's', stamps),
                     lambda: error_statistics(x)):
            try:
                result = call()
            except RotationError:
                continue
            assert _finite(result), result


def test_an_offset_at_the_edge_of_the_search_is_refused():
    t = np.arange(0.0, 30.0, 0.01)
    with pytest.raises(RotationError, match=r'the best offset lies at the edge, \+0.2 s: the '
                       r'true one may lie beyond max_offset = 0.2 s'):
        estimate_time_offset(t, motion(t + 0.5), t, motion(t), max_offset=0.2)
