"""Rodrigues axis-angle and its robust inverse, against the matrix exponential."""

from hypothesis import given, settings
import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    axis_angle_to_matrix, is_rotation, matrix_to_axis_angle, matrix_to_rotvec, RotationError,
    rotvec_to_matrix)

N = 10_000
PI = h.PI
# Angles within 1e-12 of 0 and of pi, exactly 0 and pi, and the notes' formulas' trouble spots.
ADVERSARIAL_ANGLES = (0.0, 1e-300, 1e-16, 1e-15, 1e-13, 1e-12, 1e-10, 1e-8, 1e-6,
                      PI - 1e-6, PI - 1e-9, PI - 1e-12, PI - 1e-13, PI - 1e-15, PI)
# Axes: random, coordinate axes both signs, and axes with l_z = 0 (notes' eq. 15 divides by l_z).
SPECIAL_AXES = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1],
                         [0.6, 0.8, 0.0], [-0.6, 0.8, 0.0], [1, 1, 1], [1, -2, 3e-12]])


def adversarial_set():
    rng = np.random.default_rng(20)
    axes = np.concatenate([SPECIAL_AXES, rng.normal(size=(30, 3))])
    axes = axes / np.linalg.norm(axes, axis=-1, keepdims=True)
    axis = np.repeat(axes, len(ADVERSARIAL_ANGLES), axis=0)
    angle = np.tile(ADVERSARIAL_ANGLES, len(axes))
    return axis, angle, h.notes_rodrigues_eq7(axis, angle)


def rotvec_error(got_axis, got_angle, axis, angle):
    """|got rotvec - angle axis|, allowing the opposite axis where pi - angle <= 1e-12."""
    got = got_axis * np.asarray(got_angle)[..., None]
    ref = axis * np.asarray(angle)[..., None]
    err = np.linalg.norm(got - ref, axis=-1)
    flipped = np.linalg.norm(got + ref, axis=-1)
    return np.where(PI - angle <= 1e-12, np.minimum(err, flipped), err)


def test_axis_angle_to_matrix_is_the_matrix_exponential():
    rng = np.random.default_rng(21)
    axis = h.random_unit_vectors(rng, N)
    angle = rng.uniform(-2 * PI, 2 * PI, N)
    got = axis_angle_to_matrix(axis, angle)
    assert got.shape == (N, 3, 3)
    ref = h.expm(h.ref_skew(axis * angle[:, None]))
    assert h.max_abs(got - ref) <= 1e-14
    axis2, angle2, _ = adversarial_set()
    ref2 = h.expm(h.ref_skew(axis2 * angle2[:, None]))
    assert h.max_abs(axis_angle_to_matrix(axis2, angle2) - ref2) <= 1e-14


def test_axis_is_normalised():
    rng = np.random.default_rng(22)
    axis = h.random_unit_vectors(rng, 1000)
    angle = rng.uniform(0, PI, 1000)
    scale = 10.0 ** rng.uniform(-6, 6, size=(1000, 1))
    ref = axis_angle_to_matrix(axis, angle)
    assert h.max_abs(axis_angle_to_matrix(scale * axis, angle) - ref) <= 1e-15 * 4


def test_negative_angle_is_the_opposite_axis():
    rng = np.random.default_rng(23)
    axis = h.random_unit_vectors(rng, 1000)
    angle = rng.uniform(0, PI, 1000)
    assert h.max_abs(axis_angle_to_matrix(axis, -angle)
                     - axis_angle_to_matrix(-axis, angle)) <= 1e-15 * 2


def test_zero_axis_with_zero_angle_is_identity():
    assert np.array_equal(axis_angle_to_matrix([0.0, 0.0, 0.0], 0.0), np.eye(3))
    out = axis_angle_to_matrix(np.zeros((2, 3)), np.zeros(2))
    assert np.array_equal(out, np.broadcast_to(np.eye(3), (2, 3, 3)))


def test_broadcasting_shapes():
    assert axis_angle_to_matrix([0.0, 0.0, 1.0], 0.5).shape == (3, 3)
    assert axis_angle_to_matrix([0.0, 0.0, 1.0], np.linspace(0, 1, 5)).shape == (5, 3, 3)
    assert axis_angle_to_matrix(np.ones((4, 1, 3)), np.linspace(0, 1, 5)).shape == (4, 5, 3, 3)
    assert axis_angle_to_matrix(np.ones((2, 3)), 0.3).shape == (2, 3, 3)
    angles = np.linspace(0, 1, 5)
    out = axis_angle_to_matrix([0.0, 0.0, 1.0], angles)
    assert h.max_abs(out - h.ref_elementary('z', angles)) <= 1e-15 * 2


def test_matrix_to_axis_angle_recovers_the_construction():
    rng = np.random.default_rng(24)
    axis, angle, r = h.random_axis_angle(rng, N)
    got_axis, got_angle = matrix_to_axis_angle(r)
    assert got_axis.shape == (N, 3) and got_angle.shape == (N,)
    assert np.all(got_angle >= 0.0) and np.all(got_angle <= PI)
    assert h.max_abs(np.linalg.norm(got_axis, axis=-1) - 1.0) <= 1e-15 * 2
    assert h.max_abs(got_angle - angle) <= 1e-14
    assert h.max_abs(rotvec_error(got_axis, got_angle, axis, angle)) <= 1e-14


def test_matrix_to_axis_angle_adversarial_angles():
    axis, angle, r = adversarial_set()
    got_axis, got_angle = matrix_to_axis_angle(r)
    assert np.all(got_angle >= 0.0) and np.all(got_angle <= PI)
    assert h.max_abs(np.linalg.norm(got_axis, axis=-1) - 1.0) <= 1e-15 * 2
    assert h.max_abs(got_angle - angle) <= 1e-14
    assert h.max_abs(rotvec_error(got_axis, got_angle, axis, angle)) <= 1e-14
    # Where the angle is above the rounding level, the axis itself is recovered.
    resolved = angle >= 1e-12
    axis_err = np.minimum(np.linalg.norm(got_axis - axis, axis=-1),
                          np.where(PI - angle <= 1e-12,
                                   np.linalg.norm(got_axis + axis, axis=-1), np.inf))
    assert h.max_abs(axis_err[resolved]) <= 1e-14


@pytest.mark.parametrize('angle', [1e-12, PI, PI - 1e-9])
def test_accuracy_targets(angle):
    # angle and rotation vector accurate to 1e-14 (tiny angle, exactly pi, pi - 1e-9).
    rng = np.random.default_rng(25)
    axis = np.concatenate([SPECIAL_AXES / np.linalg.norm(SPECIAL_AXES, axis=-1)[:, None],
                           h.random_unit_vectors(rng, 200)])
    r = h.notes_rodrigues_eq7(axis, angle)
    got_axis, got_angle = matrix_to_axis_angle(r)
    assert h.max_abs(got_angle - angle) <= 1e-14
    rv = matrix_to_rotvec(r)
    ref = axis * angle
    err = np.linalg.norm(rv - ref, axis=-1)
    if angle == PI:
        err = np.minimum(err, np.linalg.norm(rv + ref, axis=-1))
    assert h.max_abs(err) <= 1e-14


def test_identity_gives_axis_z_and_angle_zero():
    axis, angle = matrix_to_axis_angle(np.eye(3))
    assert np.array_equal(axis, [0.0, 0.0, 1.0])
    assert angle == 0.0
    axes, angles = matrix_to_axis_angle(np.broadcast_to(np.eye(3), (2, 4, 3, 3)))
    assert np.array_equal(axes, np.broadcast_to([0.0, 0.0, 1.0], (2, 4, 3)))
    assert np.array_equal(angles, np.zeros((2, 4)))


def test_angle_pi_axis_is_plus_or_minus_the_axis():
    for axis in SPECIAL_AXES / np.linalg.norm(SPECIAL_AXES, axis=-1)[:, None]:
        r = 2.0 * np.outer(axis, axis) - np.eye(3)      # exactly the half turn
        got_axis, got_angle = matrix_to_axis_angle(r)
        assert abs(got_angle - PI) <= 1e-15 * 4
        assert min(h.max_abs(got_axis - axis), h.max_abs(got_axis + axis)) <= 1e-15 * 2


def test_the_24_cube_rotations():
    # 1 identity, 6 quarter turns, 3 + 6 half turns, 8 turns by 2 pi / 3 about diagonals.
    cube = h.cube_rotations()
    for r in (cube, np.where(cube == 0, -0.0, cube)):
        axis, angle = matrix_to_axis_angle(r)
        expected = np.array([0.0] + [PI / 2] * 6 + [PI] * 9 + [2 * PI / 3] * 8)
        assert h.max_abs(np.sort(angle) - np.sort(expected)) <= 1e-15 * 4
        assert h.max_abs(np.linalg.norm(axis, axis=-1) - 1.0) <= 1e-15 * 2
        # axes are along a face normal, an edge or a vertex direction of the cube
        nonzero = np.abs(axis) > 1e-15
        count = nonzero.sum(-1)
        assert np.all(np.abs(np.abs(axis) - np.where(nonzero, 1 / np.sqrt(
            np.maximum(count, 1))[:, None], 0.0)) <= 1e-15 * 2)
        assert h.max_abs(h.notes_rodrigues_eq7(axis, angle) - r) <= 1e-15 * 4


def test_round_trips():
    rng = np.random.default_rng(26)
    axis, angle, r = h.random_axis_angle(rng, N)
    a2, t2, r2 = adversarial_set()
    r = np.concatenate([r, r2])
    got_axis, got_angle = matrix_to_axis_angle(r)
    assert h.max_abs(axis_angle_to_matrix(got_axis, got_angle) - r) <= 1e-12
    assert h.max_abs(rotvec_to_matrix(matrix_to_rotvec(r)) - r) <= 1e-12
    # and the other way round, from (axis, angle) with angle in [0, pi)
    axis = np.concatenate([axis, a2])
    angle = np.concatenate([angle, t2])
    back_axis, back_angle = matrix_to_axis_angle(axis_angle_to_matrix(axis, angle))
    assert h.max_abs(back_angle - angle) <= 1e-12
    assert h.max_abs(rotvec_error(back_axis, back_angle, axis, angle)) <= 1e-12


def test_rotvec_to_matrix_is_the_matrix_exponential():
    rng = np.random.default_rng(27)
    v = h.random_unit_vectors(rng, N) * rng.uniform(0, 3 * PI, size=(N, 1))
    v[:5] = [[0, 0, 0], [1e-300, 0, 0], [0, 1e-12, 0], [0, 0, PI], [PI, 0, 0]]
    got = rotvec_to_matrix(v)
    assert got.shape == (N, 3, 3)
    assert h.max_abs(got - h.expm(h.ref_skew(v))) <= 1e-14
    assert np.array_equal(rotvec_to_matrix([0.0, 0.0, 0.0]), np.eye(3))


def test_matrix_to_rotvec_matches_axis_angle():
    rng = np.random.default_rng(28)
    axis, angle, r = h.random_axis_angle(rng, 1000)
    rv = matrix_to_rotvec(r)
    assert rv.shape == (1000, 3)
    assert h.max_abs(np.linalg.norm(rv, axis=-1) - angle) <= 1e-14
    assert h.max_abs(rv - axis * angle[:, None]) <= 1e-14
    assert matrix_to_rotvec(np.eye(3)).shape == (3,)
    assert np.array_equal(matrix_to_rotvec(np.eye(3)), np.zeros(3))


def test_single_and_batch_shapes():
    rng = np.random.default_rng(29)
    _, _, r = h.random_axis_angle(rng, 12)
    r = r.reshape(3, 4, 3, 3)
    axis, angle = matrix_to_axis_angle(r)
    assert axis.shape == (3, 4, 3) and angle.shape == (3, 4)
    one_axis, one_angle = matrix_to_axis_angle(r[1, 2])
    assert one_axis.shape == (3,) and np.ndim(one_angle) == 0
    assert np.asarray(one_angle).dtype == np.float64
    assert h.max_abs(one_axis - axis[1, 2]) <= 1e-15 and abs(one_angle - angle[1, 2]) <= 1e-15
    assert rotvec_to_matrix(np.zeros((3, 4, 3))).shape == (3, 4, 3, 3)
    assert matrix_to_rotvec(r).shape == (3, 4, 3)


def test_check_false_uses_the_matrix_as_given():
    # θ = atan2(|w|, (tr R − 1)/2), axis w/|w| with w = ½(r32 − r23, r13 − r31, r21 − r12),
    # read from the perturbed matrix as given (no projection onto a rotation).
    r = h.notes_rodrigues_eq7([0.0, 0.6, 0.8], 0.5)
    r[0, 0] += 1e-6
    with pytest.raises(RotationError, match='not orthogonal'):
        matrix_to_axis_angle(r)
    w = 0.5 * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    angle_ref = np.arctan2(np.linalg.norm(w), (np.trace(r) - 1) / 2)
    axis, angle = matrix_to_axis_angle(r, check=False)
    assert abs(angle - angle_ref) <= 1e-16 and abs(angle - 0.5) > 1e-7
    assert h.max_abs(axis - w / np.linalg.norm(w)) <= 1e-16
    assert h.max_abs(matrix_to_rotvec(r, check=False) - angle_ref * w / np.linalg.norm(w)
                     ) <= 1e-16


def test_outputs_are_rotations():
    rng = np.random.default_rng(30)
    axis = rng.normal(size=(N, 3))
    assert np.all(is_rotation(axis_angle_to_matrix(axis, rng.uniform(-10, 10, N)), tol=1e-14))


def test_single_items_match_the_batch_on_adversarial_inputs():
    # A single item may take another code path than a batch; both must agree everywhere.
    axis, angle, r = adversarial_set()
    cube = h.cube_rotations()
    r = np.concatenate([r, cube, np.where(cube == 0, -0.0, cube)])
    batch_axis, batch_angle = matrix_to_axis_angle(r)
    batch_rotvec = matrix_to_rotvec(r)
    batch_matrix = axis_angle_to_matrix(axis, angle)
    batch_from_rotvec = rotvec_to_matrix(batch_rotvec)
    for i in range(len(r)):
        one_axis, one_angle = matrix_to_axis_angle(r[i])
        assert h.max_abs(one_axis - batch_axis[i]) <= 1e-15 * 2, i
        assert abs(one_angle - batch_angle[i]) <= 1e-15 * 4, i
        assert h.max_abs(matrix_to_rotvec(r[i]) - batch_rotvec[i]) <= 1e-15 * 8, i
        assert h.max_abs(rotvec_to_matrix(batch_rotvec[i]) - batch_from_rotvec[i]) <= 1e-15 * 4
        if i < len(angle):
            one = axis_angle_to_matrix(axis[i], angle[i])
            assert h.max_abs(one - batch_matrix[i]) <= 1e-15 * 4, i


def test_batches_larger_than_one_chunk():
    rng = np.random.default_rng(31)
    axis, angle, r = h.random_axis_angle(rng, 70_000)
    got_axis, got_angle = matrix_to_axis_angle(r)
    assert h.max_abs(got_angle - angle) <= 1e-14
    assert h.max_abs(rotvec_error(got_axis, got_angle, axis, angle)) <= 1e-14
    assert h.max_abs(axis_angle_to_matrix(axis, angle) - r) <= 1e-15 * 4


@pytest.mark.parametrize('tiny', [5e-324, 1e-310, 2.3e-308, 1e-300])
def test_subnormal_and_tiny_angles(tiny):
    # Never a silent NaN: a rotation by a subnormal angle is a rotation like any other.
    r = np.eye(3)
    r[1, 0], r[0, 1] = tiny, -tiny
    axis, angle = matrix_to_axis_angle(r)
    assert np.array_equal(axis, [0.0, 0.0, 1.0]) and angle == tiny
    assert np.array_equal(matrix_to_rotvec(r), [0.0, 0.0, tiny])
    batch_axis, batch_angle = matrix_to_axis_angle(np.stack([r, r]))
    assert np.array_equal(batch_axis, [[0.0, 0.0, 1.0]] * 2)
    got = rotvec_to_matrix([0.0, 0.0, tiny])
    assert np.all(np.isfinite(got)) and h.max_abs(got - np.eye(3)) <= 2 * tiny
    got = rotvec_to_matrix([[0.0, 0.0, tiny]] * 2)
    assert np.all(np.isfinite(got)) and h.max_abs(got - np.eye(3)) <= 2 * tiny


@pytest.mark.parametrize('size', [5e-324, 1e-310, 1e-200, 1e200, 1.7e308])
def test_any_non_zero_axis_is_normalised_never_refused(size):
    # A non-zero axis is normalised: however small or large it is, the result is
    # its rotation, one by one and as a batch (no refusal, no NaN).
    for axis in ([size, 0.0, 0.0], [[size, 0.0, 0.0]] * 2):
        got = axis_angle_to_matrix(axis, 1.0)
        assert h.max_abs(got - h.ref_elementary('x', 1.0)) <= 1e-15 * 4
    both = axis_angle_to_matrix([size, -size, 0.0], 0.5)
    assert h.max_abs(both - h.notes_rodrigues_eq7(np.array([1.0, -1.0, 0.0]) / np.sqrt(2), 0.5)
                     ) <= 1e-15 * 4


@settings(**h.HYPOTHESIS_SETTINGS)
@given(axis=h.unit_vectors(), angle=h.angles_in(0.0, PI))
def test_round_trip_property(axis, angle):
    r = h.notes_rodrigues_eq7(axis, angle)
    got_axis, got_angle = matrix_to_axis_angle(r)
    assert abs(got_angle - angle) <= 1e-14
    assert h.max_abs(rotvec_error(got_axis, got_angle, axis, angle)) <= 1e-14
    assert h.max_abs(axis_angle_to_matrix(got_axis, got_angle) - r) <= 1e-12


SMALL_ANGLES = np.logspace(-8, -4, 9)


def off_diagonal(m):
    return m[..., [0, 0, 1, 1, 2, 2], [1, 2, 0, 2, 0, 1]]


@pytest.mark.parametrize('angle', SMALL_ANGLES)
def test_small_angles_keep_their_digits_against_the_exponential(angle):
    # The off-diagonal entries (size ~θ) match the exponential series to a few ulps of θ.
    rng = np.random.default_rng(32)
    axis = np.concatenate([h.random_unit_vectors(rng, 200), [[1, 1, 1]] / np.sqrt(3)])
    ref = off_diagonal(h.expm(h.ref_skew(axis * angle)))
    tol = 4 * np.finfo(float).eps * angle
    for got in (axis_angle_to_matrix(axis, angle), rotvec_to_matrix(axis * angle),
                axis_angle_to_matrix(axis[-1], angle), rotvec_to_matrix(axis[-1] * angle)):
        err = np.abs(off_diagonal(got) - ref[-1 if got.ndim == 2 else slice(None)])
        assert err.max() <= tol, (angle, err.max() / angle)
