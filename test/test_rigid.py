"""Frames and rigid motions (Jia §4, §5) against plain NumPy 4×4 products."""

import re

import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    compose_transforms, frame_to_matrix, homogeneous_to_transform, invert_transform,
    is_rotation, RotationError, transform_from_screw, transform_points,
    transform_to_homogeneous)

N = 10_000
PI = h.PI


def random_rotations(rng, n):
    return h.random_axis_angle(rng, n)[2]


def apply_h(t, p):
    """Image of points p (..., 3) under homogeneous matrices t (..., 4, 4)."""
    p1 = np.concatenate([p, np.ones(p.shape[:-1] + (1,))], -1)
    return np.einsum('...ij,...j->...i', t, p1)[..., :3]


def scale_of(*vectors):
    return 1.0 + sum(np.linalg.norm(v, axis=-1) for v in vectors)


def motions(rng, n):
    """Return n random rigid motions with translations spread over 1e-3 … 1e3."""
    return random_rotations(rng, n), h.random_translations(rng, n)


# ---- frames (Jia §4) ------------------------------------------------------------------


def test_frame_columns_are_the_normalised_axes():
    rng = np.random.default_rng(200)
    r = random_rotations(rng, N)
    lengths = 10.0 ** rng.uniform(-3, 3, size=(N, 3))
    u, v, w = (r[:, :, i] * lengths[:, i:i + 1] for i in range(3))
    got = frame_to_matrix(u, v, w)
    assert got.shape == (N, 3, 3)
    assert h.max_abs(got - r) <= 1e-15 * 2
    assert np.all(is_rotation(got))
    one = frame_to_matrix(u[7], v[7], w[7])
    assert one.shape == (3, 3) and h.max_abs(one - got[7]) == 0.0


def test_frame_point_coordinates_notes_sec4():
    # A point with coordinates p in u-v-w is p_u·û + p_v·v̂ + p_w·ŵ = R·p in x-y-z; a point
    # q of x-y-z has coordinates q' = Rᵀ·q in u-v-w, and R·q' gives q back.
    rng = np.random.default_rng(201)
    r = random_rotations(rng, 1000)
    R = frame_to_matrix(r[:, :, 0], r[:, :, 1], r[:, :, 2])
    p = rng.normal(size=(1000, 3))
    by_axes = p[:, :1] * r[:, :, 0] + p[:, 1:2] * r[:, :, 1] + p[:, 2:] * r[:, :, 2]
    assert h.max_abs(transform_points(R, np.zeros(3), p) - by_axes) <= 1e-15 * 4
    q = rng.normal(size=(1000, 3))
    q_frame = transform_points(*invert_transform(R, np.zeros(3)), q)
    # each coordinate is the projection on the frame's axis: q_u = q·û, ...
    assert h.max_abs(q_frame - np.einsum('nji,nj->ni', r, q)) <= 1e-15 * 4
    assert h.max_abs(np.einsum('nij,nj->ni', R, q_frame) - q) <= 1e-15 * 8


def test_frame_of_the_tracking_example():
    # Jia example 3: after Rot_z(α)·Rot_y(β) the x'-axis points at the object,
    # (cos α cos β, sin α cos β, −sin β); y' = (−sin α, cos α, 0); z' = x' × y'.
    for alpha, beta in ((0.3, 0.2), (-2.0, 1.1), (PI, -PI / 2), (0.0, 0.0)):
        x1 = [np.cos(alpha) * np.cos(beta), np.sin(alpha) * np.cos(beta), -np.sin(beta)]
        y1 = [-np.sin(alpha), np.cos(alpha), 0.0]
        R = frame_to_matrix(x1, y1, np.cross(x1, y1))
        ref = h.ref_elementary('z', alpha) @ h.ref_elementary('y', beta)
        assert h.max_abs(R - ref) <= 1e-15 * 2


def test_frame_broadcasts_its_axes():
    w = np.array([0.0, 0.0, 2.0])
    angles = np.linspace(-3, 3, 12).reshape(3, 4)
    u = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], -1)
    v = np.stack([-np.sin(angles), np.cos(angles), np.zeros_like(angles)], -1)
    got = frame_to_matrix(u, v, w)
    assert got.shape == (3, 4, 3, 3)
    assert h.max_abs(got - h.ref_elementary('z', angles)) <= 1e-15 * 2


def test_frame_tolerance():
    u, w = [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]
    frame_to_matrix(u, [5e-10, 1.0, 0.0], w)
    with pytest.raises(RotationError, match='not orthogonal'):
        frame_to_matrix(u, [5e-9, 1.0, 0.0], w)
    got = frame_to_matrix(u, [5e-9, 1.0, 0.0], w, tol=1e-8)
    assert h.max_abs(got[:, 1] - np.array([5e-9, 1.0, 0.0]) / np.hypot(5e-9, 1.0)) == 0.0


@pytest.mark.parametrize('which', [0, 1, 2])
def test_frame_with_a_zero_axis(which):
    axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    axes[which] = [0.0, 0.0, 0.0]
    name = 'uvw'[which]
    with pytest.raises(RotationError, match=fr'axis {name} is zero \(\|{name}\| = 0\)'):
        frame_to_matrix(*axes)


@pytest.mark.parametrize('pair, eps', [('u and v', 1e-8), ('u and w', 0.3), ('v and w', -2e-4)])
def test_frame_not_orthogonal_names_the_pair_and_the_size(pair, eps):
    axes = [np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])]
    first, second = ('uvw'.index(pair[0]), 'uvw'.index(pair[-1]))
    axes[second] = axes[second] + eps * axes[first]
    with pytest.raises(RotationError, match=f'frame axes {pair} are not orthogonal') as info:
        frame_to_matrix(*axes)
    cos = abs(eps) / np.hypot(1.0, eps)
    assert h.mentions_magnitude(str(info.value), cos, factor=1.01), str(info.value)
    degrees = np.degrees(np.arcsin(cos))
    assert h.mentions_magnitude(str(info.value), degrees, factor=1.01), str(info.value)


@pytest.mark.parametrize('axes', [
    ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]),
    ([0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]),
    ([-2.0, 0.0, 0.0], [0.0, -3.0, 0.0], [0.0, 0.0, -0.5]),
])
def test_left_handed_frame(axes):
    with pytest.raises(RotationError, match=r'left-handed: \(û × v̂\)·ŵ = -1, expected \+1'):
        frame_to_matrix(*axes)


def test_frame_defect_inside_a_batch_names_the_item():
    rng = np.random.default_rng(202)
    r = random_rotations(rng, 6)
    u, v, w = r[:, :, 0].copy(), r[:, :, 1].copy(), r[:, :, 2].copy()
    w[4] = -w[4]
    with pytest.raises(RotationError, match=r'left-handed.*item \(4,\)'):
        frame_to_matrix(u, v, w)
    w[4] = -w[4]
    v[2] = 0.0
    with pytest.raises(RotationError, match=r'axis v is zero.*item \(2,\)'):
        frame_to_matrix(u, v, w)
    v[2] = r[2, :, 1] + 1e-3 * u[2]
    with pytest.raises(RotationError, match=r'u and v are not orthogonal.*item \(2,\)'):
        frame_to_matrix(u, v, w)


@pytest.mark.parametrize('tol', [-1e-9, 1.0, float('nan'), float('inf')])
def test_frame_bad_tolerance(tol):
    with pytest.raises(RotationError, match=r'tol must be in \[0, 1\)'):
        frame_to_matrix([1, 0, 0], [0, 1, 0], [0, 0, 1], tol=tol)


@pytest.mark.parametrize('bad', [np.nan, np.inf])
def test_frame_non_finite_axis(bad):
    with pytest.raises(RotationError, match=r'frame axis w must be finite'):
        frame_to_matrix([1, 0, 0], [0, 1, 0], [0, bad, 1])


def test_frame_wrong_shape():
    with pytest.raises(RotationError, match=r'frame axis u must have shape \(\.\.\., 3\)'):
        frame_to_matrix([1, 0], [0, 1, 0], [0, 0, 1])


# ---- transform_points ----------------------------------------------------------------------


def test_transform_points_is_the_homogeneous_product():
    rng = np.random.default_rng(203)
    r, b = motions(rng, N)
    p = h.random_translations(rng, N)
    got = transform_points(r, b, p)
    assert got.shape == (N, 3)
    ref = apply_h(h.homogeneous(r, b), p)
    assert np.all(np.abs(got - ref).max(-1) <= 1e-15 * 4 * scale_of(b, p))


def test_transform_points_broadcasting():
    rng = np.random.default_rng(204)
    r, b = motions(rng, 4)
    p = rng.normal(size=(5, 3))
    # one motion over many points
    many = transform_points(r[0], b[0], p)
    assert many.shape == (5, 3)
    assert h.max_abs(many - (p @ r[0].T + b[0])) <= 1e-14
    # many motions over one point
    one = transform_points(r, b, p[0])
    assert one.shape == (4, 3)
    assert h.max_abs(one - (np.einsum('nij,j->ni', r, p[0]) + b)) <= 1e-14
    # every motion over every point
    grid = transform_points(r[:, None], b[:, None], p[None])
    assert grid.shape == (4, 5, 3)
    for i in range(4):
        for j in range(5):
            assert h.max_abs(grid[i, j] - transform_points(r[i], b[i], p[j])) == 0.0
    # a single translation shared by a batch of rotations
    assert transform_points(r, b[0], p[0]).shape == (4, 3)
    with pytest.raises(RotationError, match='broadcast'):
        transform_points(r, b, p)


def test_a_translation_before_a_rotation_notes_sec5():
    # R(p + b) = R·p + R·b: "a translation b followed by R" is R followed by R·b.
    rng = np.random.default_rng(205)
    r, b = motions(rng, 1000)
    p = rng.normal(size=(1000, 3))
    first_translate = np.einsum('nij,nj->ni', r, p + b)
    R, rb = compose_transforms(r, np.zeros(3), np.eye(3), b)
    assert h.max_abs(R - r) == 0.0
    assert np.all(np.abs(transform_points(R, rb, p) - first_translate).max(-1)
                  <= 1e-15 * 8 * scale_of(b, p))


def test_rotation_about_a_line_through_a_point_notes_sec5():
    # R(p − q) + q = R·p + (I − R)·q: the motion (R, (I − R)·q), which is also the screw of
    # angle θ and no translation about the line through q.
    rng = np.random.default_rng(206)
    axis = h.random_unit_vectors(rng, 1000)
    angle = rng.uniform(-PI, PI, 1000)
    r = h.notes_rodrigues_eq7(axis, angle)
    q = rng.normal(size=(1000, 3)) * 10
    p = rng.normal(size=(1000, 3)) * 10
    b = q - np.einsum('nij,nj->ni', r, q)
    expected = np.einsum('nij,nj->ni', r, p - q) + q
    assert h.max_abs(transform_points(r, b, p) - expected) <= 1e-13
    R_line, b_line = transform_from_screw(axis, q, angle, np.zeros(1000))
    assert h.max_abs(R_line - r) <= 1e-15 * 4
    assert h.max_abs(transform_points(R_line, b_line, p) - expected) <= 1e-13
    # points on the line stay put
    on_line = q + rng.normal(size=(1000, 1)) * axis
    assert h.max_abs(transform_points(r, b, on_line) - on_line) <= 1e-13


# ---- compose, invert ------------------------------------------------------------------------


def test_compose_is_the_product_of_homogeneous_matrices():
    rng = np.random.default_rng(207)
    r1, b1 = motions(rng, N)
    r2, b2 = motions(rng, N)
    R, b = compose_transforms(r1, b1, r2, b2)
    assert R.shape == (N, 3, 3) and b.shape == (N, 3)
    ref = h.homogeneous(r1, b1) @ h.homogeneous(r2, b2)
    assert h.max_abs(R - ref[:, :3, :3]) <= 1e-15 * 4
    assert np.all(np.abs(b - ref[:, :3, 3]).max(-1) <= 1e-15 * 4 * scale_of(b1, b2))
    # T2 is applied first
    p = rng.normal(size=(N, 3))
    twice = transform_points(r1, b1, transform_points(r2, b2, p))
    assert np.all(np.abs(transform_points(R, b, p) - twice).max(-1)
                  <= 1e-14 * scale_of(b1, b2, p))


def test_a_chain_of_rotations_and_translations_is_one_motion():
    # Jia §5: any sequence of rotations and translations is one rotation followed by one
    # translation. Apply 20 random steps to points one by one, and compose them once.
    rng = np.random.default_rng(208)
    p = rng.normal(size=(100, 3))
    moved = p.copy()
    R, b = np.eye(3), np.zeros(3)
    for step in range(20):
        if step % 2:
            r_step, b_step = random_rotations(rng, 1)[0], np.zeros(3)
        else:
            r_step, b_step = np.eye(3), rng.normal(size=3)
        moved = moved @ r_step.T + b_step
        R, b = compose_transforms(r_step, b_step, R, b)
    assert is_rotation(R, tol=1e-14)
    assert h.max_abs(transform_points(R, b, p) - moved) <= 1e-13


def test_compose_is_associative():
    rng = np.random.default_rng(209)
    (r1, b1), (r2, b2), (r3, b3) = motions(rng, 1000), motions(rng, 1000), motions(rng, 1000)
    left = compose_transforms(*compose_transforms(r1, b1, r2, b2), r3, b3)
    right = compose_transforms(r1, b1, *compose_transforms(r2, b2, r3, b3))
    assert h.max_abs(left[0] - right[0]) <= 1e-15 * 8
    assert np.all(np.abs(left[1] - right[1]).max(-1) <= 1e-15 * 8 * scale_of(b1, b2, b3))


def test_invert_is_the_inverse_homogeneous_matrix():
    rng = np.random.default_rng(210)
    r, b = motions(rng, N)
    Rt, back = invert_transform(r, b)
    assert np.array_equal(Rt, np.swapaxes(r, -1, -2))
    ref = np.linalg.inv(h.homogeneous(r, b))
    assert np.all(np.abs(back - ref[:, :3, 3]).max(-1) <= 1e-14 * scale_of(b))
    assert np.array_equal(invert_transform(np.eye(3), np.zeros(3))[1], np.zeros(3))
    assert not np.signbit(invert_transform(np.eye(3), np.zeros(3))[1]).any()


def test_compose_with_invert_is_the_identity():
    rng = np.random.default_rng(211)
    r, b = motions(rng, N)
    for R, b0 in (compose_transforms(r, b, *invert_transform(r, b)),
                  compose_transforms(*invert_transform(r, b), r, b)):
        assert h.max_abs(R - np.eye(3)) <= 1e-15 * 4
        assert np.all(np.abs(b0).max(-1) <= 1e-15 * 4 * scale_of(b))
    assert h.max_abs(compose_transforms(r, b, *invert_transform(r, b))[1]) <= 1e-12


def test_coordinates_in_the_moved_frame():
    # invert + transform_points: Rᵀ·(p − b), the coordinates of p in the moved frame; moving
    # them with (R, b) gives p back.
    rng = np.random.default_rng(212)
    r, b = motions(rng, 1000)
    p = rng.normal(size=(1000, 3)) * 100
    local = transform_points(*invert_transform(r, b), p)
    assert np.all(np.abs(local - np.einsum('nji,nj->ni', r, p - b)).max(-1)
                  <= 1e-14 * scale_of(b, p))
    assert np.all(np.abs(transform_points(r, b, local) - p).max(-1) <= 1e-14 * scale_of(b, p))


def test_shapes_of_compose_and_invert():
    rng = np.random.default_rng(213)
    r, b = motions(rng, 6)
    R, bb = compose_transforms(r.reshape(2, 3, 3, 3), b.reshape(2, 3, 3), np.eye(3), [0, 0, 1])
    assert R.shape == (2, 3, 3, 3) and bb.shape == (2, 3, 3)
    R, bb = compose_transforms(r[0], b[0], r[1], b[1])
    assert R.shape == (3, 3) and bb.shape == (3,)
    Rt, back = invert_transform(r[0], b[0])
    assert Rt.shape == (3, 3) and back.shape == (3,)
    Rt, back = invert_transform(r, b[0])
    assert Rt.shape == (6, 3, 3) and back.shape == (6, 3)


# ---- homogeneous matrices -------------------------------------------------------------------


def test_homogeneous_round_trip_is_exact():
    rng = np.random.default_rng(214)
    r, b = motions(rng, N)
    T = transform_to_homogeneous(r, b)
    assert T.shape == (N, 4, 4)
    assert np.array_equal(T, h.homogeneous(r, b))
    R2, b2 = homogeneous_to_transform(T)
    assert np.array_equal(R2, r) and np.array_equal(b2, b)
    one = transform_to_homogeneous(r[3], b[3])
    assert one.shape == (4, 4) and np.array_equal(one, T[3])
    R1, b1 = homogeneous_to_transform(T[3])
    assert R1.shape == (3, 3) and b1.shape == (3,) and np.array_equal(R1, r[3])
    assert transform_to_homogeneous(r, np.zeros(3)).shape == (N, 4, 4)


def test_homogeneous_product_is_compose():
    rng = np.random.default_rng(215)
    (r1, b1), (r2, b2) = motions(rng, 1000), motions(rng, 1000)
    product = transform_to_homogeneous(r1, b1) @ transform_to_homogeneous(r2, b2)
    R, b = homogeneous_to_transform(product)
    Rc, bc = compose_transforms(r1, b1, r2, b2)
    assert h.max_abs(R - Rc) <= 1e-15 * 4
    assert np.all(np.abs(b - bc).max(-1) <= 1e-15 * 4 * scale_of(b1, b2))


def test_homogeneous_last_row_within_tolerance_is_accepted():
    T = h.homogeneous(h.ref_elementary('x', 0.4), [1.0, 2.0, 3.0])
    T[3] = [5e-10, -5e-10, 0.0, 1.0 + 5e-10]
    R, b = homogeneous_to_transform(T)
    assert np.array_equal(R, T[:3, :3]) and np.array_equal(b, [1.0, 2.0, 3.0])


@pytest.mark.parametrize('index, value', [(0, 1e-3), (1, -2e-9), (2, 0.5), (3, 2.0), (3, 0.0)])
def test_homogeneous_last_row_not_0001(index, value):
    T = h.homogeneous(np.eye(3), [1.0, 2.0, 3.0])
    T[3, index] = value
    off = abs(value - (index == 3))
    with pytest.raises(RotationError, match=r'last row is .* not \[0, 0, 0, 1\]') as info:
        homogeneous_to_transform(T)
    assert h.mentions_magnitude(str(info.value).split('off by')[1], off), str(info.value)
    # check=False skips the R validation only: the last row is still checked
    with pytest.raises(RotationError, match=r'last row'):
        homogeneous_to_transform(T, check=False)


def test_homogeneous_last_row_inside_a_batch():
    T = transform_to_homogeneous(h.ref_elementary('z', np.linspace(0, 3, 5)), np.zeros(3))
    T[3, 3, 1] = 1e-6
    with pytest.raises(RotationError, match=r'off by 1e-06 > 1e-09\) \(worst at item \(3,\)\)'):
        homogeneous_to_transform(T)


def test_homogeneous_rotation_block_is_validated():
    T = h.homogeneous(np.eye(3), [0.0, 0.0, 1.0])
    T[0, 1] = 1e-3
    with pytest.raises(RotationError, match=r'R \(T\[:3, :3\]\) is not orthogonal'):
        homogeneous_to_transform(T)
    R, b = homogeneous_to_transform(T, check=False)
    assert np.array_equal(R, T[:3, :3]) and np.array_equal(b, [0.0, 0.0, 1.0])
    T = h.homogeneous(np.diag([1.0, -1.0, 1.0]), np.zeros(3))
    with pytest.raises(RotationError, match=r'R \(T\[:3, :3\]\) is a reflection: det R = -1'):
        homogeneous_to_transform(T)


@pytest.mark.parametrize('bad', [np.nan, np.inf])
def test_homogeneous_non_finite(bad):
    for check in (True, False):
        T = np.eye(4)
        T[1, 3] = bad
        with pytest.raises(RotationError, match=r'T must be finite'):
            homogeneous_to_transform(T, check=check)


@pytest.mark.parametrize('shape', [(3, 3), (4, 3), (3, 4), (2, 4)])
def test_homogeneous_wrong_shape(shape):
    with pytest.raises(RotationError, match=r'T must have shape \(\.\.\., 4, 4\)'):
        homogeneous_to_transform(np.zeros(shape))


# ---- validation of R, check=False, overflow ------------------------------------------------

BAD_R = np.eye(3) + np.diag([0.0, 1e-6, 0.0])


def test_compose_names_the_second_rotation():
    with pytest.raises(RotationError, match=r'R2 is not orthogonal'):
        compose_transforms(np.eye(3), np.zeros(3), BAD_R, np.zeros(3))
    with pytest.raises(RotationError, match=r'R2 is a reflection'):
        compose_transforms(np.eye(3), np.zeros(3), np.diag([-1.0, 1.0, 1.0]), np.zeros(3))


def test_check_false_computes_with_the_matrix_as_given():
    # check=False skips validation and computes the same formulas with the matrix given.
    rng = np.random.default_rng(216)
    m = rng.normal(size=(3, 3))
    m2 = rng.normal(size=(3, 3))
    b, b2, p = rng.normal(size=(3, 3))
    assert h.max_abs(transform_points(m, b, p, check=False) - (m @ p + b)) <= 1e-14
    R, bb = compose_transforms(m, b, m2, b2, check=False)
    assert h.max_abs(R - m @ m2) <= 1e-14 and h.max_abs(bb - (m @ b2 + b)) <= 1e-14
    Rt, back = invert_transform(m, b, check=False)
    assert np.array_equal(Rt, m.T) and h.max_abs(back + m.T @ b) <= 1e-14
    assert np.array_equal(transform_to_homogeneous(m, b, check=False), h.homogeneous(m, b))
    with pytest.raises(RotationError):
        transform_points(m, b, p)


@pytest.mark.parametrize('call, what', [
    (lambda: transform_points(np.eye(3), [1e308, 0, 0], [1e308, 0, 0]), 'R·p + b'),
    (lambda: transform_points(np.diag([-1.0, -1.0, 1.0]), [0, 0, 1e308], [[0, 0, 1e308]] * 2),
     'R·p + b'),
    (lambda: compose_transforms(np.eye(3), [0, 1.5e308, 0], np.eye(3), [0, 1.5e308, 0]),
     'R1·b2 + b1'),
    (lambda: invert_transform(h.ref_elementary('z', PI / 4), [1.7e308, 1.7e308, 0]),
     '−Rᵀ·b'),
])
def test_overflow_is_refused(call, what):
    with pytest.raises(RotationError, match=re.escape(f'{what} overflows float64')):
        call()


def test_overflow_inside_a_batch_names_the_item():
    with pytest.raises(RotationError, match=r'overflows float64.*first at item \(1,\)'):
        transform_points(np.eye(3), [1e308, 0, 0], [[0, 0, 0], [1e308, 0, 0]])


def _scaled_reference(R, v, b):
    """R·v + b computed by numpy in units of 1e308, where nothing overflows."""
    return (np.einsum('...ij,...j->...i', R, v / 1e308) + b / 1e308) * 1e308


def _overflow_case_frame():
    # For b = 1.7e308·(1, 1, −1), Rᵀ·b fits but the first two terms of u·b overflow.
    u = np.array([2.0, 2.0, 1.0]) / 3
    e = np.array([1.0, 1.0, -4.0]) / np.sqrt(18)
    v = (e + np.cross(u, e)) / np.sqrt(2)
    return np.stack([u, v, np.cross(u, v)], axis=-1)


@pytest.mark.parametrize('angle', [3.0, 2.6, -2.6])
def test_results_that_fit_are_returned_though_a_partial_sum_overflows(angle):
    R = h.ref_elementary('z', angle)
    b = np.array([-1.7e308, -1.7e308, 0.0])
    with np.errstate(over='ignore'):
        assert not np.isfinite(R @ b).all()  # R·b alone leaves float64; R·b + b does not
    ref = _scaled_reference(R, b, b)
    tol = 1e-15 * 8 * 1.7e308
    assert h.max_abs(compose_transforms(R, b, R, b)[1] - ref) <= tol
    assert h.max_abs(transform_points(R, b, b) - ref) <= tol
    many = transform_points(R, b, [b, np.zeros(3), b])  # the batch engine, item by item
    assert h.max_abs(many[[0, 2]] - ref) <= tol and np.array_equal(many[1], b)
    F = _overflow_case_frame()
    back = np.array([1.7e308, 1.7e308, -1.7e308])
    assert h.max_abs(invert_transform(F, back)[1] + _scaled_reference(F.T, back, 0.0)) <= tol


def test_large_but_representable_values_pass():
    R, b = compose_transforms(np.eye(3), [1e307, 0, 0], np.diag([1.0, -1.0, -1.0]),
                              [1e307, 0, 0])
    assert np.array_equal(b, [2e307, 0, 0])
    assert np.array_equal(transform_points(np.eye(3), [-1e308, 0, 0], [1e308, 0, 0]), [0, 0, 0])


@pytest.mark.parametrize('bad', [np.nan, np.inf])
def test_non_finite_inputs(bad):
    v = np.array([0.0, bad, 0.0])
    with pytest.raises(RotationError, match=r'point p must be finite'):
        transform_points(np.eye(3), np.zeros(3), v)
    with pytest.raises(RotationError, match=r'translation b2 must be finite'):
        compose_transforms(np.eye(3), np.zeros(3), np.eye(3), v)
    with pytest.raises(RotationError, match=r'translation b must be finite'):
        invert_transform(np.eye(3), v)
    with pytest.raises(RotationError, match=r'R2 must be finite'):
        compose_transforms(np.eye(3), np.zeros(3), np.diag(v + 1), np.zeros(3))
