"""Elementary rotations, skew, validity checks, nearest rotation, quaternion boundary."""

from hypothesis import given, settings
import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    is_rotation, matrix_to_quaternion, nearest_rotation, quaternion_to_matrix, rot_x, rot_y,
    rot_z, RotationError, skew, validate_rotation)

N = 10_000
PI = h.PI
ELEMENTARY = {'x': rot_x, 'y': rot_y, 'z': rot_z}


@pytest.mark.parametrize('axis', 'xyz')
def test_elementary_rotations_match_the_notes_matrices(axis):
    rng = np.random.default_rng(1)
    special = np.array([0.0, h.PI, -h.PI, h.PI / 2, -h.PI / 2, 1e-12, 2 * h.PI, 7.0])
    angles = np.concatenate([rng.uniform(-2 * h.PI, 2 * h.PI, N), special])
    got = ELEMENTARY[axis](angles)
    assert got.shape == (N + special.size, 3, 3)
    assert got.dtype == np.float64
    assert h.max_abs(got - h.ref_elementary(axis, angles)) <= 1e-15
    assert np.all(is_rotation(got))


@pytest.mark.parametrize('axis', 'xyz')
def test_elementary_rotation_shapes(axis):
    f = ELEMENTARY[axis]
    assert f(0.3).shape == (3, 3)
    assert f(np.float64(0.3)).shape == (3, 3)
    assert f([0.1, 0.2]).shape == (2, 3, 3)
    batch = np.linspace(-3, 3, 10).reshape(2, 5)
    out = f(batch)
    assert out.shape == (2, 5, 3, 3)
    assert h.max_abs(out[1, 3] - f(batch[1, 3])) == 0.0


def test_elementary_rotations_rotate_counter_clockwise():
    # Rot_z(90 deg) takes x to y, Rot_x takes y to z, Rot_y takes z to x (right hand).
    e = np.eye(3)
    assert h.max_abs(rot_z(h.PI / 2) @ e[0] - e[1]) <= 1e-16
    assert h.max_abs(rot_x(h.PI / 2) @ e[1] - e[2]) <= 1e-16
    assert h.max_abs(rot_y(h.PI / 2) @ e[2] - e[0]) <= 1e-16


def test_skew_is_cross_product():
    rng = np.random.default_rng(2)
    v = rng.normal(size=(N, 3)) * 10.0 ** rng.uniform(-3, 3, size=(N, 1))
    w = rng.normal(size=(N, 3))
    s = skew(v)
    assert s.shape == (N, 3, 3)
    assert h.max_abs(s - h.ref_skew(v)) == 0.0
    assert h.max_abs(s + np.swapaxes(s, -1, -2)) == 0.0
    cross = np.cross(v, w)
    err = np.abs(np.einsum('nij,nj->ni', s, w) - cross).max(-1)
    assert np.all(err <= 1e-15 * np.linalg.norm(v, axis=-1) * np.linalg.norm(w, axis=-1))


def test_skew_shapes():
    assert skew([1.0, 2.0, 3.0]).shape == (3, 3)
    assert skew(np.ones((4, 5, 3))).shape == (4, 5, 3, 3)
    assert h.max_abs(skew([1.0, 2.0, 3.0]) @ [4.0, 5.0, 6.0] - np.cross([1, 2, 3], [4, 5, 6])) == 0


def test_is_rotation_on_random_rotations():
    rng = np.random.default_rng(3)
    _, _, r = h.random_axis_angle(rng, N)
    ok = is_rotation(r)
    assert ok.shape == (N,)
    assert ok.dtype == np.bool_
    assert ok.all()


def test_is_rotation_single_item_is_a_bool():
    out = is_rotation(np.eye(3))
    assert np.ndim(out) == 0
    assert isinstance(out, (bool, np.bool_))
    assert out
    assert not is_rotation(2.0 * np.eye(3))


def test_is_rotation_tolerance():
    r = rot_z(0.4) @ rot_x(1.1)
    small = r.copy()
    small[0, 1] += 1e-10          # max|R^T R - I| ~ 1e-10 <= 1e-9
    large = r.copy()
    large[0, 1] += 1e-8           # ~ 1e-8 > 1e-9
    assert is_rotation(small)
    assert not is_rotation(large)
    assert is_rotation(large, tol=1e-7)
    assert not is_rotation(small, tol=1e-11)


def test_is_rotation_rejects_reflections_and_scalings():
    assert not is_rotation(np.diag([1.0, 1.0, -1.0]))
    assert not is_rotation(-rot_y(0.7))
    assert not is_rotation(np.zeros((3, 3)))
    assert not is_rotation(1.001 * np.eye(3))


def test_is_rotation_false_for_non_finite_items_in_a_batch():
    batch = np.stack([np.eye(3)] * 4)
    batch[1, 0, 0] = np.nan
    batch[2, 2, 1] = np.inf
    batch[3, 1, 2] = -np.inf
    assert is_rotation(batch).tolist() == [True, False, False, False]
    assert not is_rotation(np.full((3, 3), np.nan))


def test_is_rotation_keeps_2d_batch_shape():
    batch = rot_x(np.linspace(0, 3, 12).reshape(3, 4))
    batch[2, 1] = np.diag([1.0, -1.0, 1.0])
    out = is_rotation(batch)
    assert out.shape == (3, 4)
    assert out.sum() == 11 and not out[2, 1]


def test_validate_rotation_returns_its_input():
    rng = np.random.default_rng(4)
    _, _, r = h.random_axis_angle(rng, 100)
    assert np.array_equal(validate_rotation(r), r)
    assert np.array_equal(validate_rotation(r[0]), r[0])
    assert validate_rotation(r.reshape(10, 10, 3, 3)).shape == (10, 10, 3, 3)
    nearly = r[0].copy()
    nearly[2, 2] += 5e-10
    assert np.array_equal(validate_rotation(nearly), nearly)
    assert np.array_equal(validate_rotation(nearly, tol=1e-9), nearly)


def test_nearest_rotation_of_a_rotation_is_itself():
    rng = np.random.default_rng(5)
    _, _, r = h.random_axis_angle(rng, N)
    assert h.max_abs(nearest_rotation(r) - r) <= 1e-15 * 4


def test_nearest_rotation_is_the_polar_factor():
    # Independent reference: Newton's iteration for the orthogonal polar factor (no SVD).
    rng = np.random.default_rng(6)
    _, _, r = h.random_axis_angle(rng, 2000)
    noisy = r + 1e-3 * rng.normal(size=r.shape)
    got = nearest_rotation(noisy)
    assert got.shape == noisy.shape
    assert np.all(is_rotation(got, tol=1e-14))
    assert h.max_abs(got - h.polar_rotation(noisy)) <= 1e-14


def test_nearest_rotation_of_a_six_digit_matrix():
    r = rot_z(0.5) @ rot_y(-0.3) @ rot_x(2.0)
    typed = np.array([[float(f'{x:.6g}') for x in row] for row in r])
    assert not is_rotation(typed)
    got = nearest_rotation(typed)
    assert got.shape == (3, 3)
    assert is_rotation(got, tol=1e-14)
    assert h.max_abs(got - r) <= 1e-6


def test_quaternion_to_matrix_matches_textbook_formula():
    rng = np.random.default_rng(7)
    q = rng.normal(size=(N, 4)) * 10.0 ** rng.uniform(-3, 3, size=(N, 1))
    got = quaternion_to_matrix(q)
    assert got.shape == (N, 3, 3)
    assert h.max_abs(got - h.ref_quaternion_to_matrix(q)) <= 1e-14
    assert np.all(is_rotation(got, tol=1e-14))


@pytest.mark.parametrize('axis', 'xyz')
def test_quaternion_order_is_x_y_z_w(axis):
    # q = sin(t/2) e_axis in the first three slots, cos(t/2) last gives Rot_axis(t).
    for t in (0.0, 0.3, -1.2, h.PI / 2, h.PI, 3.0):
        q = np.zeros(4)
        q['xyz'.index(axis)] = np.sin(t / 2)
        q[3] = np.cos(t / 2)
        assert h.max_abs(quaternion_to_matrix(q) - h.ref_elementary(axis, t)) <= 1e-15 * 4
    assert np.array_equal(quaternion_to_matrix([0.0, 0.0, 0.0, 1.0]), np.eye(3))


def test_quaternion_sign_and_scale_do_not_matter():
    rng = np.random.default_rng(8)
    q = rng.normal(size=(100, 4))
    ref = quaternion_to_matrix(q)
    assert h.max_abs(quaternion_to_matrix(-q) - ref) <= 1e-15 * 4
    assert h.max_abs(quaternion_to_matrix(1e-3 * q) - ref) <= 1e-15 * 4
    assert h.max_abs(quaternion_to_matrix(1e5 * q) - ref) <= 1e-15 * 4


def test_quaternion_shapes():
    assert quaternion_to_matrix([0.0, 0.0, 0.0, 1.0]).shape == (3, 3)
    assert quaternion_to_matrix(np.ones((2, 3, 4))).shape == (2, 3, 3, 3)


def test_single_items_match_the_batch():
    rng = np.random.default_rng(9)
    q = np.concatenate([rng.normal(size=(200, 4)), np.eye(4), -np.eye(4)])
    batch = quaternion_to_matrix(q)
    for i in range(len(q)):
        assert h.max_abs(quaternion_to_matrix(q[i]) - batch[i]) <= 1e-15 * 4, i
    angles = np.array([0.0, PI, -PI, PI / 2, 1e-300, 5e-324, 1e10])
    for f in (rot_x, rot_y, rot_z):
        batch = f(angles)
        for i, a in enumerate(angles):
            assert h.max_abs(f(a) - batch[i]) <= 1e-15, (f, a)
    _, _, r = h.random_axis_angle(rng, 50)
    r[3, 0, 0] += 1e-8
    flags = is_rotation(r)
    assert [bool(is_rotation(x)) for x in r] == flags.tolist()


@pytest.mark.parametrize('scale', [5e-324, 1e-310, 1e-300, 1e-200, 1e-160, 1e-100, 1e100, 1e160,
                                   1e200, 1e300, 1.7e308])
def test_quaternion_of_any_finite_scale_is_normalised_never_refused(scale):
    # q is normalised; only a zero or non-finite q is an error: a finite non-zero q
    # of any scale gives its rotation, one by one and as a batch (no refusal, no NaN).
    base = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.5, 0.0, 0.5], [0.3, -0.2, 0.9, 0.1]])
    if scale < 1e-300:  # subnormal: integer multiples of the scale are exact
        base = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 1.0], [3.0, -2.0, 9.0, 1.0]])
        assert np.array_equal(scale * base / scale, base)
    q = scale * base
    ref = h.ref_quaternion_to_matrix(base)
    for one, expected in zip(q, ref):
        assert h.max_abs(quaternion_to_matrix(one) - expected) <= 1e-15 * 4, (scale, one)
    assert h.max_abs(quaternion_to_matrix(q) - ref) <= 1e-15 * 4


@settings(**h.HYPOTHESIS_SETTINGS)
@given(axis=h.unit_vectors(), angle=h.angles_in(-10.0, 10.0))
def test_quaternion_property_is_rodrigues(axis, angle):
    q = np.append(np.sin(angle / 2) * axis, np.cos(angle / 2))
    assert h.max_abs(quaternion_to_matrix(q) - h.notes_rodrigues_eq7(axis, angle)) <= 1e-14


def test_matrix_to_quaternion_matches_scipy_canonical():
    from scipy.spatial.transform import Rotation
    # random_state and a Generator: older SciPy takes no rng=, and both draw the same rotations
    R = Rotation.random(N, random_state=np.random.default_rng(7)).as_matrix()
    q = matrix_to_quaternion(R)
    assert q.shape == (N, 4)
    assert h.max_abs(q - Rotation.from_matrix(R).as_quat(canonical=True)) <= 1e-15
    assert h.max_abs(quaternion_to_matrix(q) - R) <= 1e-15


@pytest.mark.parametrize('angle', [0.0, 1e-12, PI / 2, PI - 1e-9, PI])
@pytest.mark.parametrize('axis', [(1, 0, 0), (0, 1, 0), (0, 0, 1), (0, -1, 1), (-1, 2, -3)])
def test_matrix_to_quaternion_closed_form(axis, angle):
    # q = (sin(θ/2)·l̂, cos(θ/2)), canonical as it stands: cos(θ/2) > 0 for θ ≤ fl(π) < π.
    axis = np.array(axis, dtype=float) / np.linalg.norm(axis)
    exact = np.append(np.sin(angle / 2) * axis, np.cos(angle / 2))
    R = np.cos(angle) * np.eye(3) + (1 - np.cos(angle)) * np.outer(axis, axis) + np.sin(
        angle) * h.ref_skew(axis)
    q = matrix_to_quaternion(R)
    assert h.max_abs(q - exact) <= 2e-16
    assert q[3] > 0 or (q[3] == 0 and q[np.flatnonzero(q)[0]] > 0)


@pytest.mark.parametrize('R, q', [
    (np.diag([-1.0, -1.0, 1.0]), [0.0, 0.0, 1.0, 0.0]),
    (np.diag([1.0, -1.0, -1.0]), [1.0, 0.0, 0.0, 0.0]),
    ([[-1, 0, 0], [0, 0, -1], [0, -1, 0]], [0.0, 0.5 ** 0.5, -(0.5 ** 0.5), 0.0]),
    ([[0, 1, 0], [1, 0, 0], [0, 0, -1]], [0.5 ** 0.5, 0.5 ** 0.5, 0.0, 0.0]),
])
def test_matrix_to_quaternion_half_turn_sign(R, q):
    # Exactly π (w = 0): the first non-zero of x, y, z is positive.
    assert h.max_abs(matrix_to_quaternion(R) - np.array(q)) <= 2e-16


def adversarial_rotations():
    """Return rotations near 0 and π, the cube rotations (±0.0 entries) and gimbal locks."""
    rng = np.random.default_rng(80)
    axes = np.concatenate([np.eye(3), -np.eye(3), [[0.6, 0.8, 0.0], [1, 1, 1], [1, -2, 3e-12]],
                           rng.normal(size=(20, 3))])
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    angles = np.array([0.0, 1e-300, 1e-15, 1e-12, 1e-8, 1.0, PI / 2, PI - 1e-6, PI - 1e-9,
                       PI - 1e-12, PI])
    axis = np.repeat(axes, len(angles), axis=0)
    angle = np.tile(angles, len(axes))
    cube = h.cube_rotations()
    lock = h.ref_euler(np.stack([rng.uniform(-PI, PI, 20), np.full(20, PI / 2),
                                 rng.uniform(-PI, PI, 20)], -1), 'ZYX')
    return np.concatenate([h.notes_rodrigues_eq7(axis, angle), cube,
                           np.where(cube == 0, -0.0, cube), lock]), axis, angle


def exact_quaternion(axis, angle):
    """(sin(θ/2)·l̂, cos(θ/2)): canonical as it stands for θ ∈ [0, fl(π)] (cos(θ/2) > 0)."""
    half = np.asarray(angle)[..., None] / 2
    return np.concatenate([np.sin(half) * axis, np.cos(half)], -1)


def test_matrix_to_quaternion_adversarial_closed_forms():
    # Against (sin(θ/2)·l̂, cos(θ/2)) to a few ulps.
    r, axis, angle = adversarial_rotations()
    n = len(angle)
    q = matrix_to_quaternion(r[:n])
    assert h.max_abs(q - exact_quaternion(axis, angle)) <= 1e-15
    for i in range(0, n, 7):
        assert h.max_abs(matrix_to_quaternion(r[i]) - q[i]) == 0.0, i


def test_quaternion_round_trip_random_and_adversarial():
    r_adv, _, _ = adversarial_rotations()
    for r in (h.scipy_rotations(N, 81), r_adv):
        q = matrix_to_quaternion(r)
        assert h.max_abs(np.linalg.norm(q, axis=-1) - 1.0) <= 2e-16 * 2
        assert h.max_abs(quaternion_to_matrix(q) - r) <= 1e-15
        assert h.max_abs(h.ref_quaternion_to_matrix(q) - r) <= 2e-15  # (its own rounding)


def test_quaternion_round_trip_from_quaternions():
    # matrix_to_quaternion(quaternion_to_matrix(q)) is q/|q| with the canonical sign, for any
    # non-zero q, including w = 0 and the tiny-angle w ≈ 1.
    rng = np.random.default_rng(82)
    q = rng.normal(size=(N, 4))
    q[:100, 3] = 0.0
    q[100:200, :3] *= 1e-10
    unit_q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    got = matrix_to_quaternion(quaternion_to_matrix(q))
    canonical = np.where(unit_q[:, 3:] < 0, -unit_q, unit_q)
    first = np.take_along_axis(canonical, np.argmax(canonical[:, :3] != 0, axis=1)[:, None], 1)
    canonical = np.where((canonical[:, 3:] == 0) & (first < 0), -canonical, canonical)
    assert h.max_abs(got - canonical) <= 1e-15


def test_matrix_to_quaternion_canonical_sign_everywhere():
    r_adv, _, _ = adversarial_rotations()
    for r in (h.scipy_rotations(N, 83), r_adv):
        q = matrix_to_quaternion(r)
        w = q[:, 3]
        assert np.all(w >= 0)
        half = q[w == 0, :3]
        first = half[np.arange(len(half)), np.argmax(half != 0, axis=1)]
        assert np.all(first > 0)
        assert not np.signbit(q[q == 0]).any()  # no −0.0


def scipy_canonical(r):
    from scipy.spatial.transform import Rotation
    return Rotation.from_matrix(r).as_quat(canonical=True)


def test_matrix_to_quaternion_matches_scipy_on_adversarial_sets():
    r, _, _ = adversarial_rotations()
    q, ref = matrix_to_quaternion(r), scipy_canonical(r)
    # at exactly π scipy's w may come out as ±1e-17 and flip its sign choice: compare ±q there
    close = np.minimum(np.abs(q - ref).max(-1), np.abs(q + ref).max(-1))
    assert np.all(np.where(np.abs(ref[:, 3]) > 1e-8, np.abs(q - ref).max(-1), close) <= 1e-15)


def test_matrix_to_quaternion_check_false_uses_the_matrix_as_given():
    # Without the check a slightly non-orthogonal matrix still gives a unit quaternion, within
    # the perturbation of the rotation's own.
    r = h.notes_rodrigues_eq7([0.0, 0.6, 0.8], 2.0)
    bad = r.copy()
    bad[0, 1] += 1e-6
    with pytest.raises(RotationError, match='not orthogonal'):
        matrix_to_quaternion(bad)
    q = matrix_to_quaternion(bad, check=False)
    assert abs(np.linalg.norm(q) - 1.0) <= 2e-16 * 2
    assert h.max_abs(q - exact_quaternion(np.array([0.0, 0.6, 0.8]), 2.0)) <= 1e-6
    assert h.max_abs(q - matrix_to_quaternion(r)) > 1e-9


def test_matrix_to_quaternion_shapes():
    r = h.scipy_rotations(24, 84).reshape(2, 3, 4, 3, 3)
    q = matrix_to_quaternion(r)
    assert q.shape == (2, 3, 4, 4)
    assert matrix_to_quaternion(np.eye(3)).shape == (4,)
    assert np.array_equal(matrix_to_quaternion(np.eye(3)), [0.0, 0.0, 0.0, 1.0])
    assert matrix_to_quaternion(np.zeros((0, 3, 3))).shape == (0, 4)
