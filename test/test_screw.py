"""Chasles' screw decomposition, its inverse, exponential coordinates and interpolation."""

from hypothesis import given, settings
import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    PURE_TRANSLATION_ANGLE, RotationError, Screw, screw_exp, screw_from_transform,
    screw_interpolate, screw_log, transform_from_screw)

N = 10_000
PI = h.PI


def build(axis, point, angle, d):
    """Transform (R, b) of the screw (axis, point, angle, d); `point` is any axis point."""
    axis = np.asarray(axis, dtype=float)
    r = h.notes_rodrigues_eq7(axis, angle)
    b = -h.rotate_minus_identity(axis, angle, point) + np.asarray(d)[..., None] * axis
    return r, b


def random_screws(rng, n):
    axis = h.random_unit_vectors(rng, n)
    p = rng.normal(size=(n, 3)) * 10.0 ** rng.uniform(-3, 3, size=(n, 1))
    point = p - np.sum(p * axis, -1, keepdims=True) * axis
    angle = rng.uniform(0.0, PI, n)
    d = rng.normal(size=n) * 10.0 ** rng.uniform(-3, 3, size=n)
    return axis, point, angle, d


def adversarial_screws():
    """Pure rotations, angle pi with translation, tiny angles with large translations."""
    rng = np.random.default_rng(40)
    rows = []
    for angle in (1e-11, 1e-10, 1e-8, 1e-6, 0.5, PI - 1e-9, PI - 1e-12, PI):
        for scale in (0.0, 1.0, 1e3):
            for d in (0.0, 1.0, -1e3):
                axis = h.random_unit_vectors(rng, 1)[0]
                p = rng.normal(size=3)
                p = scale * (p - (p @ axis) * axis) / np.linalg.norm(p - (p @ axis) * axis)
                rows.append((axis, p, angle, d))
    # Transforms with a given translation b (rather than a given axis point): the axis point
    # is then ~|b|/angle away, up to 1e13 for angle 1e-10 and |b| = 1e3.
    for angle in (1e-11, 1e-10, 1e-8, PI):
        for bnorm in (1.0, 1e3):
            axis = h.random_unit_vectors(rng, 1)[0]
            b = bnorm * h.random_unit_vectors(rng, 1)[0]
            bperp = b - (b @ axis) * axis
            c = 0.5 * (bperp + np.cross(axis, bperp) / np.tan(angle / 2))
            rows.append((axis, c, angle, b @ axis))
    axis, point, angle, d = (np.array(col) for col in zip(*rows))
    return axis, point, angle, d


def all_screws():
    rng = np.random.default_rng(41)
    parts = [random_screws(rng, N), adversarial_screws()]
    return tuple(np.concatenate(col) for col in zip(*parts))


def transform_scale(b):
    return 1.0 + np.linalg.norm(b, axis=-1)


def check_defining_properties(scr, axis0, angle0, r, b):
    """Check the defining properties of `scr` for (r, b) = screw(axis0, ., angle0, .)."""
    scale = transform_scale(b)
    u, c = scr.direction, scr.point
    # c is computed from b (b_perp = b - (b.l) l rounds at eps |b|), so its scale is |c| + |b|
    cscale = 1.0 + np.linalg.norm(c, axis=-1) + np.linalg.norm(b, axis=-1)
    assert h.max_abs(np.linalg.norm(u, axis=-1) - 1.0) <= 1e-15 * 2
    assert np.all(scr.angle >= 0.0) and np.all(scr.angle <= PI)
    assert h.max_abs(scr.angle - angle0) <= 1e-14
    # the direction is the construction axis (its sign is free only at angle pi)
    same = np.sum(u * axis0, -1) > 0
    assert np.all(same | (PI - angle0 <= 1e-12))
    # point on the axis, closest to the origin: point . direction = 0
    assert np.all(np.abs(np.sum(c * u, -1)) <= 1e-14 * cscale)
    # moment = point x direction (Pluecker)
    assert np.all(np.abs(scr.moment - np.cross(c, u)).max(-1) <= 1e-14 * cscale)
    # translation d is the component of b along the axis
    assert np.all(np.abs(scr.translation - np.sum(b * u, -1)) <= 1e-14 * scale)
    # points of the axis move along it by d: R c + b = c + d l
    resid = h.rotate_minus_identity(axis0, angle0, c) + b - scr.translation[..., None] * u
    assert np.all(np.abs(resid).max(-1) <= 1e-12 * scale)
    # pitch = d / angle
    pitch = scr.pitch
    rotating = scr.angle > 0
    assert np.all(np.abs(pitch[rotating] - scr.translation[rotating] / scr.angle[rotating])
                  <= 1e-15 * 4 * np.abs(pitch[rotating]))


def test_screw_is_a_named_tuple_of_the_spec_fields():
    scr = screw_from_transform(h.ref_elementary('z', 0.5), [1.0, 2.0, 3.0])
    assert isinstance(scr, Screw)
    assert Screw._fields == ('direction', 'point', 'moment', 'angle', 'translation', 'pitch')


def test_screw_from_transform_defining_properties():
    axis, point, angle, d = all_screws()
    r, b = build(axis, point, angle, d)
    scr = screw_from_transform(r, b)
    assert scr.direction.shape == (len(angle), 3) and scr.angle.shape == (len(angle),)
    check_defining_properties(scr, axis, angle, r, b)


def test_screw_from_transform_recovers_the_construction():
    # Away from angle 0 and pi the screw is unique and conditioned well enough to compare.
    rng = np.random.default_rng(42)
    axis, point, angle, d = random_screws(rng, N)
    keep = (angle > 0.1) & (angle < PI - 0.1)
    axis, point, angle, d = axis[keep], point[keep], angle[keep], d[keep]
    r, b = build(axis, point, angle, d)
    scr = screw_from_transform(r, b)
    scale = transform_scale(b)
    assert h.max_abs(scr.direction - axis) <= 1e-14
    assert np.all(np.abs(scr.point - point).max(-1) <= 1e-12 * scale)
    assert np.all(np.abs(scr.translation - d) <= 1e-12 * scale)
    assert h.max_abs(scr.angle - angle) <= 1e-14


def test_transform_from_screw_round_trip():
    axis, point, angle, d = all_screws()
    r, b = build(axis, point, angle, d)
    scr = screw_from_transform(r, b)
    r2, b2 = transform_from_screw(scr.direction, scr.point, scr.angle, scr.translation)
    assert h.max_abs(r2 - r) <= 1e-12
    assert np.all(np.abs(b2 - b).max(-1) <= 1e-12 * transform_scale(b))


def test_transform_from_screw_matches_the_construction():
    axis, point, angle, d = all_screws()
    r, b = build(axis, point, angle, d)
    r2, b2 = transform_from_screw(axis, point, angle, d)
    assert h.max_abs(r2 - r) <= 1e-14
    assert np.all(np.abs(b2 - b).max(-1) <= 1e-12 * transform_scale(b))


def test_transform_from_screw_any_axis_point_and_unnormalised_direction():
    rng = np.random.default_rng(43)
    axis, point, angle, d = random_screws(rng, 1000)
    r, b = build(axis, point, angle, d)
    shift = rng.uniform(-100, 100, size=(1000, 1)) * axis
    r2, b2 = transform_from_screw(7.5 * axis, point + shift, angle, d)
    assert h.max_abs(r2 - r) <= 1e-14
    tol = 1e-12 * (transform_scale(b) + np.linalg.norm(point + shift, axis=-1))
    assert np.all(np.abs(b2 - b).max(-1) <= tol)


def test_pure_translation():
    for b in ([1.0, 2.0, -2.0], [0.0, 0.0, -5.0], [1e-9, 0.0, 0.0], [1e3, -1e3, 1e3]):
        b = np.array(b)
        scr = screw_from_transform(np.eye(3), b)
        assert h.max_abs(scr.direction - b / np.linalg.norm(b)) <= 4e-16
        assert np.array_equal(scr.point, np.zeros(3))
        assert np.array_equal(scr.moment, np.zeros(3))
        assert scr.angle == 0.0
        assert abs(scr.translation - np.linalg.norm(b)) <= 1e-15 * np.linalg.norm(b)
        assert np.isinf(scr.pitch) and scr.pitch > 0
        expected = np.concatenate([np.zeros(3), b])
        assert h.max_abs(screw_log(np.eye(3), b) - expected) <= 4e-16 * h.max_abs(b)
        r2, b2 = transform_from_screw(scr.direction, scr.point, scr.angle, scr.translation)
        assert np.array_equal(r2, np.eye(3)) and h.max_abs(b2 - b) <= 1e-15 * 4 * np.abs(b).max()


def test_angle_below_threshold_is_a_pure_translation():
    assert 0.0 < PURE_TRANSLATION_ANGLE <= 1e-9
    angle = PURE_TRANSLATION_ANGLE / 10
    r = h.notes_rodrigues_eq7([0.0, 1.0, 0.0], angle)
    b = np.array([3.0, 0.0, 4.0])
    scr = screw_from_transform(r, b)
    assert scr.angle == 0.0 and np.isinf(scr.pitch)
    assert h.max_abs(scr.direction - b / 5.0) <= 4e-16 and scr.translation == 5.0
    r2, b2 = transform_from_screw(scr.direction, scr.point, scr.angle, scr.translation)
    assert h.max_abs(r2 - r) <= 1e-12 and h.max_abs(b2 - b) <= 1e-12 * 6


def test_identity():
    scr = screw_from_transform(np.eye(3), np.zeros(3))
    assert np.array_equal(scr.direction, [0.0, 0.0, 1.0])
    assert np.array_equal(scr.point, np.zeros(3)) and np.array_equal(scr.moment, np.zeros(3))
    assert scr.angle == 0.0 and scr.translation == 0.0 and scr.pitch == 0.0
    assert np.array_equal(screw_log(np.eye(3), np.zeros(3)), np.zeros(6))
    r, b = screw_exp(np.zeros(6))
    assert np.array_equal(r, np.eye(3)) and np.array_equal(b, np.zeros(3))


def test_pure_rotation_about_an_axis_through_the_origin_and_elsewhere():
    rng = np.random.default_rng(44)
    axis, point, angle, _ = random_screws(rng, 1000)
    r, b0 = build(axis, np.zeros_like(point), angle, np.zeros(1000))
    scr = screw_from_transform(r, b0)
    assert np.array_equal(b0, np.zeros_like(b0))
    assert h.max_abs(scr.point) == 0.0 and h.max_abs(scr.translation) == 0.0
    assert h.max_abs(scr.pitch) == 0.0
    r, b = build(axis, point, angle, np.zeros(1000))
    scr = screw_from_transform(r, b)
    assert np.all(np.abs(scr.translation) <= 1e-14 * transform_scale(b))
    assert np.all(np.abs(scr.pitch) * angle <= 1e-14 * transform_scale(b))
    check_defining_properties(scr, axis, angle, r, b)


def test_angle_pi_with_translation():
    rng = np.random.default_rng(45)
    axis = h.random_unit_vectors(rng, 500)
    r = 2.0 * axis[:, :, None] * axis[:, None, :] - np.eye(3)
    b = rng.normal(size=(500, 3)) * 10
    scr = screw_from_transform(r, b)
    assert h.max_abs(scr.angle - PI) <= 1e-15 * 4
    # the axis point is half the perpendicular part of b, the translation the parallel part
    u = scr.direction
    bperp = b - np.sum(b * u, -1, keepdims=True) * u
    assert h.max_abs(np.abs(np.sum(u * axis, -1)) - 1.0) <= 1e-14
    assert np.all(np.abs(scr.point - 0.5 * bperp).max(-1) <= 1e-14 * transform_scale(b))
    # the sign of the direction is the implementation's choice; moment and twist follow it
    tw = screw_log(r, b)
    assert h.max_abs(tw[:, :3] - PI * u) <= 1e-14
    expected_v = PI * np.cross(scr.point, u) + scr.translation[:, None] * u
    assert np.all(np.abs(tw[:, 3:] - expected_v).max(-1) <= 1e-13 * transform_scale(b))
    r2, b2 = screw_exp(tw)
    assert h.max_abs(r2 - r) <= 1e-12
    assert np.all(np.abs(b2 - b).max(-1) <= 1e-12 * transform_scale(b))


def test_screw_log_matches_the_construction():
    axis, point, angle, d = all_screws()
    r, b = build(axis, point, angle, d)
    tw = screw_log(r, b)
    assert tw.shape == (len(angle), 6)
    scr = screw_from_transform(r, b)
    sign = np.where(np.sum(scr.direction * axis, -1) < 0, -1.0, 1.0)   # only at angle pi
    assert np.all((sign > 0) | (PI - angle <= 1e-12))
    u, dd = sign[:, None] * axis, sign * d
    # (θ·l̂, θ·c × l̂ + d·l̂) at every angle: exponential coordinates have no threshold
    expected = np.concatenate([angle[:, None] * u,
                               angle[:, None] * np.cross(point, u) + dd[:, None] * u], -1)
    scale = transform_scale(b)
    assert np.all(np.abs(tw[:, :3] - expected[:, :3]).max(-1) <= 1e-14)
    assert np.all(np.abs(tw[:, 3:] - expected[:, 3:]).max(-1) <= 1e-12 * scale)


def test_cube_rotations_with_translations():
    rng = np.random.default_rng(50)
    cube = h.cube_rotations()
    r = np.concatenate([cube, np.where(cube == 0, -0.0, cube)] * 3)
    b = rng.normal(size=(len(r), 3)) * np.repeat([0.0, 1.0, 1e3], 48)[:, None]
    scale = transform_scale(b)
    scr = screw_from_transform(r, b)
    r2, b2 = transform_from_screw(scr.direction, scr.point, scr.angle, scr.translation)
    assert h.max_abs(r2 - r) <= 1e-15 * 4
    assert np.all(np.abs(b2 - b).max(-1) <= 1e-12 * scale)
    # R c + b = c + d l
    resid = np.einsum('nij,nj->ni', r, scr.point) + b - scr.point - (
        scr.translation[:, None] * scr.direction)
    assert np.all(np.abs(resid).max(-1) <= 1e-12 * scale)
    r3, b3 = screw_exp(screw_log(r, b))
    assert h.max_abs(r3 - r) <= 1e-12
    assert np.all(np.abs(b3 - b).max(-1) <= 1e-12 * scale)


def test_screw_exp_is_the_matrix_exponential_of_the_twist():
    rng = np.random.default_rng(46)
    w = h.random_unit_vectors(rng, N) * rng.uniform(0, 3 * PI, size=(N, 1))
    v = rng.normal(size=(N, 3)) * 10.0 ** rng.uniform(-3, 3, size=(N, 1))
    w[:6] = [[0, 0, 0], [1e-12, 0, 0], [0, 1e-10, 0], [0, 0, 1e-8], [PI, 0, 0], [0, 0, -PI]]
    twist = np.concatenate([w, v], -1)
    r, b = screw_exp(twist)
    r_ref, b_ref = h.expm_twist(twist)
    assert r.shape == (N, 3, 3) and b.shape == (N, 3)
    assert h.max_abs(r - r_ref) <= 1e-14
    assert np.all(np.abs(b - b_ref).max(-1) <= 1e-13 * transform_scale(b_ref))


def test_screw_exp_of_screw_log_round_trip():
    axis, point, angle, d = all_screws()
    r, b = build(axis, point, angle, d)
    r2, b2 = screw_exp(screw_log(r, b))
    assert h.max_abs(r2 - r) <= 1e-12
    assert np.all(np.abs(b2 - b).max(-1) <= 1e-12 * transform_scale(b))


def test_screw_log_of_screw_exp_round_trip():
    rng = np.random.default_rng(47)
    w = h.random_unit_vectors(rng, N) * rng.uniform(0, PI * (1 - 1e-9), size=(N, 1))
    v = rng.normal(size=(N, 3)) * 10.0 ** rng.uniform(-3, 3, size=(N, 1))
    twist = np.concatenate([w, v], -1)
    back = screw_log(*screw_exp(twist))
    assert h.max_abs(back[:, :3] - w) <= 1e-12
    assert np.all(np.abs(back[:, 3:] - v).max(-1) <= 1e-12 * (1 + np.linalg.norm(v, axis=-1)))


def test_batch_shapes():
    rng = np.random.default_rng(48)
    axis, point, angle, d = random_screws(rng, 20)
    r, b = build(axis, point, angle, d)
    r, b = r.reshape(4, 5, 3, 3), b.reshape(4, 5, 3)
    scr = screw_from_transform(r, b)
    assert scr.direction.shape == (4, 5, 3) and scr.point.shape == (4, 5, 3)
    assert scr.moment.shape == (4, 5, 3)
    for field in (scr.angle, scr.translation, scr.pitch):
        assert np.shape(field) == (4, 5)
    one = screw_from_transform(r[3, 2], b[3, 2])
    assert one.direction.shape == (3,) and np.ndim(one.angle) == 0 and np.ndim(one.pitch) == 0
    assert abs(one.translation - scr.translation[3, 2]) <= 1e-12 * transform_scale(b[3, 2])
    assert screw_log(r, b).shape == (4, 5, 6) and screw_log(r[0, 0], b[0, 0]).shape == (6,)
    r2, b2 = screw_exp(np.zeros((4, 5, 6)))
    assert r2.shape == (4, 5, 3, 3) and b2.shape == (4, 5, 3)
    r3, b3 = transform_from_screw(scr.direction, scr.point, scr.angle, scr.translation)
    assert r3.shape == (4, 5, 3, 3) and b3.shape == (4, 5, 3)


def test_single_items_match_the_batch():
    # A single item may take another code path than a batch; both must agree everywhere,
    # including the identity, pure translations, angle pi and tiny angles.
    axis, point, angle, d = adversarial_screws()
    r, b = build(axis, point, angle, d)
    cube = h.cube_rotations()
    extra_r = np.concatenate([cube, np.eye(3)[None], np.eye(3)[None],
                              h.notes_rodrigues_eq7([0.0, 0.0, 1.0], [1e-13, 1e-13])])
    extra_b = np.concatenate([np.full((24, 3), 2.0), np.zeros((1, 3)), [[0.0, 3.0, 4.0]],
                              np.zeros((1, 3)), [[1.0, 0.0, 0.0]]])
    r, b = np.concatenate([r, extra_r]), np.concatenate([b, extra_b])
    scr = screw_from_transform(r, b)
    tw = screw_log(r, b)
    r_exp, b_exp = screw_exp(tw)
    r_tfs, b_tfs = transform_from_screw(scr.direction, scr.point, scr.angle, scr.translation)
    for i in range(len(r)):
        scale = 1e-15 * 8 * transform_scale(b[i])
        one = screw_from_transform(r[i], b[i])
        for name in Screw._fields:
            x, y = getattr(one, name), getattr(scr, name)[i]
            if name == 'pitch' and np.isinf(y):
                assert x == y, i
                continue
            big = 1.0 + np.abs(y).max() if name in ('point', 'moment', 'pitch') else 1.0
            assert h.max_abs(x - y) <= scale * big, (i, name)
        assert h.max_abs(screw_log(r[i], b[i]) - tw[i]) <= scale * (1 + h.max_abs(tw[i])), i
        r1, b1 = screw_exp(tw[i])
        assert h.max_abs(r1 - r_exp[i]) <= 1e-15 * 4 and h.max_abs(b1 - b_exp[i]) <= scale, i
        r1, b1 = transform_from_screw(scr.direction[i], scr.point[i], scr.angle[i],
                                      scr.translation[i])
        assert h.max_abs(r1 - r_tfs[i]) <= 1e-15 * 4 and h.max_abs(b1 - b_tfs[i]) <= scale, i


def test_below_threshold_without_translation_is_the_identity():
    r = h.notes_rodrigues_eq7([0.6, 0.0, 0.8], [1e-13, 0.0])
    for scr in (screw_from_transform(r, np.zeros((2, 3))),
                screw_from_transform(r[0], np.zeros(3))):
        assert np.array_equal(scr.direction, np.broadcast_to([0.0, 0.0, 1.0],
                                                             np.shape(scr.direction)))
        for name in ('point', 'moment', 'angle', 'translation', 'pitch'):
            assert np.all(getattr(scr, name) == 0.0), name


def test_transform_from_screw_any_angle():
    rng = np.random.default_rng(51)
    axis, point, _, d = random_screws(rng, 1000)
    angle = rng.uniform(-3 * PI, 3 * PI, 1000)
    r, b = build(axis, point, angle, d)
    r2, b2 = transform_from_screw(axis, point, angle, d)
    assert h.max_abs(r2 - r) <= 1e-14
    assert np.all(np.abs(b2 - b).max(-1) <= 1e-12 * transform_scale(b))


@pytest.mark.parametrize('tiny', [5e-324, 1e-310, 1e-200])
def test_screw_exp_tiny_rotation_never_nan(tiny):
    for twist in ([tiny, 0.0, 0.0, 0.0, 1.0, 2.0], [[tiny, 0.0, 0.0, 0.0, 1.0, 2.0]] * 2):
        r, b = screw_exp(twist)
        assert h.max_abs(r - np.eye(3)) <= 2 * tiny
        assert h.max_abs(b - [0.0, 1.0, 2.0]) <= 1e-15 * 4


def test_batches_larger_than_one_chunk():
    rng = np.random.default_rng(52)
    axis, point, angle, d = random_screws(rng, 70_000)
    r, b = build(axis, point, angle, d)
    scr = screw_from_transform(r, b)
    check_defining_properties(scr, axis, angle, r, b)
    r2, b2 = screw_exp(screw_log(r, b))
    assert h.max_abs(r2 - r) <= 1e-12
    assert np.all(np.abs(b2 - b).max(-1) <= 1e-12 * transform_scale(b))


def test_check_false_uses_the_matrix_as_given():
    # θ and l̂ read from the matrix as given, then the defining formulas with them.
    r = h.notes_rodrigues_eq7([0.0, 0.6, 0.8], 0.5)
    r[0, 0] += 1e-6
    b = np.array([1.0, -2.0, 0.5])
    with pytest.raises(RotationError, match='not orthogonal'):
        screw_from_transform(r, b)
    w = 0.5 * np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    theta = np.arctan2(np.linalg.norm(w), (np.trace(r) - 1) / 2)
    axis = w / np.linalg.norm(w)
    d = b @ axis
    bperp = b - d * axis
    cot = 1 / np.tan(theta / 2)
    point = 0.5 * (bperp + cot * np.cross(axis, bperp))
    scr = screw_from_transform(r, b, check=False)
    assert abs(scr.angle - theta) <= 1e-16 and abs(theta - 0.5) > 1e-7
    assert h.max_abs(scr.direction - axis) <= 1e-16
    assert abs(scr.translation - d) <= 1e-15 and abs(scr.pitch - d / theta) <= 1e-14
    assert h.max_abs(scr.point - point) <= 1e-14
    twist = np.concatenate([theta * axis, -theta / 2 * np.cross(axis, b)
                            + theta / 2 * cot * bperp + d * axis])
    assert h.max_abs(screw_log(r, b, check=False) - twist) <= 1e-15


def compose(r0, b0, r1, b1):
    return r0 @ r1, np.einsum('...ij,...j->...i', r0, b1) + b0


def inverse(r, b):
    rt = np.swapaxes(r, -1, -2)
    return rt, -np.einsum('...ij,...j->...i', rt, b)


def test_screw_interpolate_ends_and_constant_screw():
    rng = np.random.default_rng(49)
    n = N
    r0, b0 = build(*random_screws(rng, n))
    axis, point, angle, d = random_screws(rng, n)
    angle = np.minimum(angle, PI - 1e-3)
    rel_r, rel_b = build(axis, point, angle, d)
    r1, b1 = compose(r0, b0, rel_r, rel_b)
    scale = transform_scale(b0) + transform_scale(b1)
    ra, ba = screw_interpolate(r0, b0, r1, b1, np.zeros(n))
    assert h.max_abs(ra - r0) <= 1e-12 and np.all(np.abs(ba - b0).max(-1) <= 1e-12 * scale)
    ra, ba = screw_interpolate(r0, b0, r1, b1, np.ones(n))
    assert h.max_abs(ra - r1) <= 1e-12 and np.all(np.abs(ba - b1).max(-1) <= 1e-12 * scale)
    # T(s) = T0 exp(s log(T0^-1 T1)): the relative motion is the known screw scaled by s
    for s in (0.25, 0.5, 0.9):
        rs, bs = screw_interpolate(r0, b0, r1, b1, np.full(n, s))
        ref = compose(r0, b0, *build(axis, point, s * angle, s * d))
        assert h.max_abs(rs - ref[0]) <= 1e-12
        assert np.all(np.abs(bs - ref[1]).max(-1) <= 1e-12 * scale)
    # midpoint property T(1/2) T0^-1 T(1/2) = T1, whatever the sign choice
    rm, bm = screw_interpolate(r0, b0, r1, b1, np.full(n, 0.5))
    rr, bb = compose(*compose(rm, bm, *inverse(r0, b0)), rm, bm)
    assert h.max_abs(rr - r1) <= 1e-12 and np.all(np.abs(bb - b1).max(-1) <= 1e-12 * scale)


def test_screw_interpolate_shapes():
    r0, b0 = np.eye(3), np.zeros(3)
    r1, b1 = h.ref_elementary('z', 1.0), np.array([0.0, 0.0, 2.0])
    rs, bs = screw_interpolate(r0, b0, r1, b1, np.linspace(0, 1, 7))
    assert rs.shape == (7, 3, 3) and bs.shape == (7, 3)
    r, b = screw_interpolate(r0, b0, r1, b1, 0.5)
    assert r.shape == (3, 3) and b.shape == (3,)
    assert h.max_abs(r - h.ref_elementary('z', 0.5)) <= 1e-15 * 4
    # screw about z through the origin, pitch 2 / 1: half way is half the lift
    assert h.max_abs(b - [0.0, 0.0, 1.0]) <= 1e-15 * 4


@settings(**h.HYPOTHESIS_SETTINGS)
@given(axis=h.unit_vectors(), p=h.unit_vectors(), dist=h.angles_in(0.0, 1e3),
       angle=h.angles_in(0.0, PI), d=h.angles_in(-1e3, 1e3))
def test_round_trip_property(axis, p, dist, angle, d):
    point = dist * (p - (p @ axis) * axis)
    r, b = build(axis, point, angle, d)
    scale = 1.0 + np.linalg.norm(b)
    scr = screw_from_transform(r, b)
    r2, b2 = transform_from_screw(scr.direction, scr.point, scr.angle, scr.translation)
    assert h.max_abs(r2 - r) <= 1e-12 and h.max_abs(b2 - b) <= 1e-12 * scale
    r3, b3 = screw_exp(screw_log(r, b))
    assert h.max_abs(r3 - r) <= 1e-12 and h.max_abs(b3 - b) <= 1e-12 * scale


@pytest.mark.parametrize('angle', [1e-10, 1e-8])
def test_tiny_angle_with_large_translation(angle):
    # The axis point is ~|b| / angle = 1e13 away; everything must still reproduce (R, b).
    axis = np.array([0.0, 0.6, 0.8])
    b = np.array([1e3, -2e3, 5e2])
    bperp = b - (b @ axis) * axis
    c = 0.5 * (bperp + np.cross(axis, bperp) / np.tan(angle / 2))
    r = h.notes_rodrigues_eq7(axis, angle)
    scr = screw_from_transform(r, b)
    scale = 1.0 + np.linalg.norm(b)
    assert abs(scr.angle - angle) <= 1e-14 * angle
    assert h.max_abs(scr.point - c) <= 1e-12 * np.linalg.norm(c)
    assert abs(scr.translation - b @ axis) <= 1e-12 * scale
    r2, b2 = transform_from_screw(scr.direction, scr.point, scr.angle, scr.translation)
    assert h.max_abs(r2 - r) <= 1e-12 and h.max_abs(b2 - b) <= 1e-12 * scale
    r3, b3 = screw_exp(screw_log(r, b))
    assert h.max_abs(r3 - r) <= 1e-12 and h.max_abs(b3 - b) <= 1e-12 * scale


# ---- exponential coordinates have no threshold (by definition) ----------------------

TINY_ANGLES = (5e-324, 1e-300, 1e-15, 1e-14, 1e-13, 5e-13, PURE_TRANSLATION_ANGLE, 2e-12, 1e-10)


@pytest.mark.parametrize('angle', TINY_ANGLES)
def test_screw_log_keeps_the_rotation_vector_at_tiny_angles(angle):
    # θ·l̂ keeps its digits for every θ > 0; θ·v is the matrix logarithm's translation part,
    # checked by the exponential series of the twist (math_helpers.expm_twist).
    axis = np.array([0.36, -0.48, 0.8])
    r = h.notes_rodrigues_eq7(axis, angle)
    b = np.array([3.0, -1.0, 2.0])
    for tw in (screw_log(r, b), screw_log(np.stack([r, r]), b)[1]):
        assert np.all(np.abs(tw[:3] - angle * axis) <= 1e-15 * angle), tw
        assert h.max_abs(tw[3:] - b) <= 1e-15 * 4 + 2 * angle * 4
        r_exp, b_exp = h.expm_twist(tw)
        assert h.max_abs(r_exp - r) <= 1e-16 + 2 * angle
        assert h.max_abs(b_exp - b) <= 1e-15 * 4
        r2, b2 = screw_exp(tw)
        assert h.max_abs(r2 - r) <= 1e-16 and h.max_abs(b2 - b) <= 1e-15 * 4
    # the Screw alone calls θ below PURE_TRANSLATION_ANGLE a pure translation
    scr = screw_from_transform(r, b)
    if angle < PURE_TRANSLATION_ANGLE:
        assert scr.angle == 0.0 and np.isinf(scr.pitch)
    else:
        assert abs(scr.angle - angle) <= 1e-15 * angle


def test_screw_log_of_a_tiny_pure_rotation_is_its_rotation_vector():
    # b = 0: the twist is (θ·l̂, 0) for every θ, down to the smallest subnormal.
    rng = np.random.default_rng(53)
    axis = h.random_unit_vectors(rng, 200)
    angle = 10.0 ** rng.uniform(-320, -2, 200)
    r = h.notes_rodrigues_eq7(axis, angle)
    tw = screw_log(r, np.zeros(3))
    assert np.all(np.abs(tw[:, :3] - angle[:, None] * axis).max(-1) <= 1e-15 * angle + 1e-323)
    assert h.max_abs(tw[:, 3:]) == 0.0


def test_decompose_twist_is_screw_log_at_tiny_angles():
    from rot_tools import decompose
    for angle in TINY_ANGLES:
        r = h.notes_rodrigues_eq7([0.0, 0.6, 0.8], angle)
        b = np.array([1.0, 2.0, -4.0])
        assert np.array_equal(decompose(r, b).twist, screw_log(r, b))


@pytest.mark.parametrize('angle', [1e-8, 2e-8, 1e-7, 1e-6, 3e-6, 1e-5])
def test_screw_exp_between_series_and_closed_form(angle):
    # b must match the exponential series of the twist to 1e-14 relative at small θ.
    rng = np.random.default_rng(54)
    w = h.random_unit_vectors(rng, 100) * angle
    v = rng.normal(size=(100, 3)) * 10.0 ** rng.uniform(-2, 2, size=(100, 1))
    twist = np.concatenate([w, v], -1)
    r_ref, b_ref = h.expm_twist(twist)
    scale = np.linalg.norm(v, axis=-1)
    for r, b in (screw_exp(twist), screw_exp(twist[7])):
        assert np.all(np.abs(b - b_ref[7 if b.ndim == 1 else slice(None)]).max(-1)
                      <= 1e-14 * scale[7 if b.ndim == 1 else slice(None)])
        assert h.max_abs(r - r_ref[7 if r.ndim == 2 else slice(None)]) <= 1e-16 * 4
