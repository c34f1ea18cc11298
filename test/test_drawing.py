"""
rot_tools.io.drawing: the geometry both renderers draw, against independent closed forms.

The path must be the helix p(s) = c + Rot(s·θ·l̂)·(p0 − c) + s·d·l̂ (scipy's Rotation).
"""

import math

from hypothesis import example, given, settings, strategies as st
import math_helpers as h
import numpy as np
import pytest
from rot_tools import RotationError
from rot_tools.io import drawing
from rot_tools.io.drawing import picture
from scipy.spatial.transform import Rotation

RNG = np.random.default_rng(1010)


def helix(direction, point, angle, d, p0, s):
    """Points (len(s), 3) of p0 carried by the constant screw motion at fractions s."""
    turns = Rotation.from_rotvec(np.outer(s, angle * h.unit(direction)))
    return point + turns.apply(p0 - point) + np.outer(s * d, h.unit(direction))


def perpendicular(direction, point):
    """Return the component of point ⊥ direction (the axis point closest to the origin)."""
    u = h.unit(direction)
    return point - (point @ u) * u


SCREWS = {
    'quarter_turn_z': ((0, 0, 1), (0.5, 0.5, 0), math.pi / 2, 0.5),
    'oblique': ((1, -2, 0.5), (0.3, 0.1, -0.7), 2.1, -1.3),
    'small_angle': ((0, 1, 1), (2.0, 0.0, 0.0), 0.05, 0.2),
    'near_half_turn': ((1, 1, 1), (0.0, 1.0, -1.0), math.pi - 1e-3, 0.4),
    'far_axis': ((0, 0, 1), (40.0, 0.0, 0.0), 1.0, 0.0),
    'random': (RNG.normal(size=3), RNG.normal(size=3), 2.7, 1.1),
}


@pytest.mark.parametrize('case', SCREWS)
@pytest.mark.parametrize('scale', [1.0, 0.3])
def test_screw_picture(case, scale):
    direction, point, angle, d = SCREWS[case]
    point = perpendicular(direction, np.asarray(point, dtype=np.float64))
    R, b = h.screw_motion(direction, point, angle, d)
    pic = picture(R, b, scale=scale)
    assert pic.kind == drawing.SCREW and pic.traced == 'origin'
    size = 1.0 + np.linalg.norm(point) + abs(d)
    # The moved frame: axes = columns of R, drawn at b.
    np.testing.assert_allclose(pic.frame, R, rtol=0, atol=1e-15)
    np.testing.assert_allclose(pic.origin, b, rtol=0, atol=0)
    assert pic.scale == scale
    # The path: from the origin to b, on the helix at s = k/n.
    path = pic.path
    n = len(path) - 1
    np.testing.assert_array_equal(path[0], np.zeros(3))
    np.testing.assert_allclose(path[-1], b, rtol=0, atol=1e-15 * size)
    s = np.linspace(0.0, 1.0, n + 1)
    np.testing.assert_allclose(path, helix(direction, point, angle, d, np.zeros(3), s),
                               rtol=0, atol=1e-12 * size)
    # Each step turns at most 3°, its chord within SAGITTA·scale of the helix.
    assert angle / n <= drawing.MAX_STEP_ANGLE * (1 + 1e-12)
    mid = helix(direction, point, angle, d, np.zeros(3), (s[:-1] + s[1:]) / 2)
    off = np.linalg.norm(mid - (path[:-1] + path[1:]) / 2, axis=1)
    assert off.max() <= drawing.SAGITTA * scale * (1 + 1e-9)
    # The axis: through c along +l̂, covering the origin, b, the path and the moved frame.
    start, end = pic.axis
    u = h.unit(direction)
    for e in (start, end):
        assert np.linalg.norm(np.cross(e - point, u)) <= 1e-12 * size
    assert (end - start) @ u > 0
    t = np.concatenate([[np.zeros(3), b], path, b + scale * R.T]) @ u  # c ⊥ l̂
    assert (start @ u) == pytest.approx(t.min() - scale, abs=1e-12 * size)
    assert (end @ u) == pytest.approx(t.max() + scale, abs=1e-12 * size)


BESIDE_THE_PATH = {  # (direction, point, angle, d) and the traced p0 (the origin if None)
    'odometry_turn': ((0, 0, 1), (0.5, 0.5 / math.tan(0.005), 0), 0.01, 0.0, None),
    'tiny_turn': ((0, 0, 1), (0.5, 0.5 / math.tan(0.5e-8), 0), 1e-8, 0.0, None),
    'tiny_oblique_screw': ((1, 1, 1), (30.0, -10.0, -20.0), 1e-6, 0.3, None),
    'large_turn': ((1, -2, 0.5), (0.3, 0.1, -0.7), 2.1, -1.3, None),
    'half_turn_screw': ((1, 0, 0), (0.0, 1.0, -1.0), math.pi, 0.5, None),
    'half_turn_rotation': ((0, 0, 1), (0.0, 0.0, 0.0), math.pi, 0.0, (1, 0, 0)),
    'translation': ((1, -2, 2), (0.0, 0.0, 0.0), 0.0, 3.0, None),
    'translation_along_z': ((0, 0, 1), (0.0, 0.0, 0.0), 0.0, 3.0, None),
}


@pytest.mark.parametrize('case', BESIDE_THE_PATH)
@pytest.mark.parametrize('scale', [1.0, 0.2])
def test_the_label_sits_beside_the_path(case, scale):
    """LABEL_OFFSET·scale from the helix, never out at the axis (|c| ~ |b|/θ for a small θ)."""
    direction, point, angle, d, p0 = BESIDE_THE_PATH[case]
    p0 = np.zeros(3) if p0 is None else scale * np.asarray(p0, dtype=np.float64)
    R, b = h.screw_motion(direction, np.asarray(point, dtype=np.float64), angle, d)
    pic = picture(R, b, scale=scale)
    sign = np.sign(pic.screw.direction @ h.unit(direction)) if angle else 1.0  # ± at θ = π
    curve = helix(sign * h.unit(direction), np.asarray(point, dtype=np.float64), angle,
                  sign * d, p0, np.linspace(0.0, 1.0, 20001))
    off = np.linalg.norm(curve - pic.label_at, axis=1).min()
    assert 0.5 * drawing.LABEL_OFFSET * scale <= off
    assert off <= (drawing.LABEL_OFFSET + drawing.SAGITTA + 1e-4) * scale


@pytest.mark.parametrize('angle', [0.01, 1e-5, 1e-9])
@pytest.mark.parametrize('scale', [1.0, 0.25, 4.0])
def test_a_far_axis_is_drawn_at_a_visible_length(angle, scale):
    # A small turn with a translation: the axis is |b|/θ away, its segment still spans the
    # rise along it (0 to d, the frame tips up to scale further) and scale beyond each end.
    direction, d = h.unit((1, 2, 2)), 0.4
    point = perpendicular(direction, np.array([3.0, 0.0, -1.0]) / angle)
    R, b = h.screw_motion(direction, point, angle, d)
    start, end = picture(R, b, scale=scale).axis
    length = (end - start) @ direction
    assert np.linalg.norm(end - start) == pytest.approx(length, rel=1e-9)
    assert 2 * scale + d <= length * (1 + 1e-9)
    assert length <= (4 * scale + d) * (1 + 1e-9)


def test_far_axis_is_sampled_by_the_sagitta():
    pic = picture(*h.screw_motion((0, 0, 1), (40.0, 0.0, 0.0), 1.0, 0.0))
    # 40·Δ²/8 ≤ 2e-3 → Δ ≤ 0.02 rad: 50 steps for 1 rad, more than 1 rad / 3° = 20.
    assert len(pic.path) - 1 == math.ceil(1.0 / math.sqrt(8 * drawing.SAGITTA / 40.0))


def test_segments_are_capped():
    pic = picture(*h.screw_motion((0, 0, 1), (1e6, 0.0, 0.0), 3.0, 0.0))
    assert len(pic.path) - 1 == drawing.MAX_SEGMENTS


def test_half_turn_lies_on_the_helix_of_the_reported_axis_sign():
    # At θ = π the sign of l̂ is the implementation's; the path follows the one it reports.
    point = np.array([0.0, 1.0, 0.0])
    R, b = h.screw_motion((1, 0, 0), point, math.pi, 0.5)
    pic = picture(R, b)
    sign = np.sign(pic.screw.direction @ (1, 0, 0))
    s = np.linspace(0.0, 1.0, len(pic.path))
    np.testing.assert_allclose(
        pic.path, helix(sign * np.array([1.0, 0, 0]), point, math.pi, sign * 0.5,
                        np.zeros(3), s), rtol=0, atol=1e-12)


@pytest.mark.parametrize('direction, traced, k', [
    ((0, 0, 1), 'x-axis tip', 0), ((1, 0, 0), 'y-axis tip', 1), ((1, 0.2, 0), 'z-axis tip', 2),
    ((0.1, 1, 1), 'x-axis tip', 0), ((1, 1, 1), 'x-axis tip', 0)])
def test_pure_rotation_draws_the_arc_of_an_axis_tip(direction, traced, k):
    scale = 0.8
    R, _ = h.screw_motion(direction, np.zeros(3), 1.2, 0.0)
    pic = picture(R, np.zeros(3), scale=scale)
    assert (pic.kind, pic.traced) == (drawing.ROTATION, traced)
    tip = scale * np.eye(3)[k]
    np.testing.assert_array_equal(pic.path[0], tip)
    np.testing.assert_allclose(pic.path[-1], R @ tip, rtol=0, atol=1e-15)
    s = np.linspace(0.0, 1.0, len(pic.path))
    np.testing.assert_allclose(pic.path, helix(direction, np.zeros(3), 1.2, 0.0, tip, s),
                               rtol=0, atol=1e-14)
    start, end = pic.axis
    assert np.linalg.norm(np.cross(start, h.unit(direction))) <= 1e-15
    assert np.linalg.norm(np.cross(end, h.unit(direction))) <= 1e-15


def test_pure_translation_is_a_straight_path_without_axis():
    b = np.array([1.0, -2.0, 2.0])
    pic = picture(np.eye(3), b, scale=0.5)
    assert (pic.kind, pic.traced, pic.axis) == (drawing.TRANSLATION, 'origin', None)
    np.testing.assert_array_equal(pic.path, [np.zeros(3), b])
    assert pic.label == 'theta = 0 rad, d = 3, screw pitch = inf'


def test_identity_has_nothing_to_draw():
    pic = picture(np.eye(3), np.zeros(3))
    assert (pic.kind, pic.axis, pic.path, pic.traced) == (drawing.IDENTITY, None, None, '')


@pytest.mark.parametrize('chord, across', [
    ((1.0, 0.0, 1.0), (-1.0, 0.0, 1.0)),  # 45° from z: across it towards +z
    ((0.0, -3.0, 2.0), (0.0, 2.0, 3.0)),  # 56° from z (|ẑ⊥| = 0.83)
    ((0.0, 1.0, 2.0), (1.0, 0.0, 0.0)),  # 27° from z: towards +x instead
    ((1.0, 0.0, -2.0), (4.0, 0.0, 2.0)),  # 27° from −z: +x, less its part along the chord
    ((1e300, 0.0, 1e300), (-1.0, 0.0, 1.0)),  # |chord|² beyond float64
])
def test_label_direction(chord, across):
    # A straight path of 3 points (middle point = the middle): the label goes
    # LABEL_OFFSET·scale across the chord, towards +z unless within 60° of z.
    chord, across = np.array(chord), h.unit(across)
    path = np.array([np.zeros(3), chord / 2, chord])
    np.testing.assert_allclose(drawing.label_point(path, 2.0),
                               chord / 2 + 2.0 * drawing.LABEL_OFFSET * across,
                               rtol=1e-15, atol=1e-15)


def test_labels_of_the_worked_example():
    # 90° about z through (0.5, 0.5, 0), rising 0.5: pitch 0.5/(π/2) = 0.3183.
    R, b = h.screw_motion((0, 0, 1), np.array([0.5, 0.5, 0.0]), math.pi / 2, 0.5)
    assert picture(R, b, degrees=True).label == (
        'theta = 90 deg, d = 0.5, screw pitch = 0.3183 /rad')
    assert picture(R, b).label == 'theta = 1.571 rad, d = 0.5, screw pitch = 0.3183 /rad'
    R, b = h.screw_motion((0, 0, 1), np.array([0.5, 0.5, 0.0]), math.pi / 2, -0.5)
    assert picture(R, b, degrees=True).label == (
        'theta = 90 deg, d = -0.5, screw pitch = -0.3183 /rad')
    assert picture(R, np.zeros(3), degrees=True).label == (
        'theta = 90 deg, d = 0, screw pitch = 0 /rad')


def test_a_given_decomposition_is_used():
    from rot_tools import decompose
    R, b = h.screw_motion((0, 1, 0), np.array([1.0, 0.0, 0.0]), 0.7, 0.1)
    a, c = picture(R, b), picture(R, b, decomposition=decompose(R, b))
    np.testing.assert_array_equal(a.path, c.path)
    np.testing.assert_array_equal(a.axis, c.axis)


def test_path_segments():
    assert drawing.path_segments(0.0, 5.0, 1.0) == 1
    assert drawing.path_segments(math.pi, 0.0, 1.0) == 60
    assert drawing.path_segments(1e-9, 1e9, 1.0) == 1


def test_a_picture_that_overflows_float64_is_refused():
    R, b = h.screw_motion((0, 0, 1), np.zeros(3), 1.0, 1.0)
    with pytest.raises(RotationError, match=r'overflows float64 \(scale 1e\+308, max\|b_i\| = 1,'):
        picture(R, b, scale=1e308)
    # The largest finite motions still draw (their axis 1e211 away; capped segments).
    pic = picture(*h.screw_motion((0, 0, 1), np.zeros(3), 1e-11, 0.0)[:1], (0.0, 1e200, 0.0))
    assert len(pic.path) == drawing.MAX_SEGMENTS + 1 and np.isfinite(pic.path).all()


@pytest.mark.parametrize('end', [(0.0, 0.0, math.nan), (math.inf, 1.0, 0.0),
                                 (1.0, -math.inf, 1.0)])
def test_the_label_of_a_path_that_overflowed_is_nan(end):
    # (picture then refuses the motion: RotationError, not ZeroDivisionError)
    path = np.array([np.zeros(3), np.ones(3), end])
    assert np.isnan(drawing.label_point(path, 1.0)).all()


HUGE = st.floats(allow_nan=False, allow_infinity=False) | st.sampled_from(
    [1e308, -1.7e308, 1e200, 1e-300, 5e-324, 0.0])


@settings(**h.HYPOTHESIS_SETTINGS)
@given(st.tuples(HUGE, HUGE, HUGE), st.floats(0.0, 4.0), st.tuples(HUGE, HUGE, HUGE),
       st.floats(1e-300, 1e308) | st.sampled_from([1.0, 1e308]))
@example((0.0, 0.0, 1.0), 1e-11, (1.7e308, -1.7e308, 1.7e308), 1.0)
@example((1.0, 1.0, 0.0), 3.0, (1e308, 1e308, 1e308), 1e308)
@example((0.0, 0.0, 1.0), 1.0, (0.0, 0.0, 0.0), 1e308)
def test_any_motion_draws_or_is_refused_with_a_rotation_error(direction, angle, b, scale):
    # Whatever the floats, a picture is finite, or RotationError says it overflows.
    if not any(direction):
        direction = (0.0, 0.0, 1.0)
    direction = np.array(direction) / np.abs(direction).max()
    R = Rotation.from_rotvec(angle * h.unit(direction)).as_matrix()
    try:
        pic = picture(R, np.array(b), scale=scale)
    except RotationError as exc:
        assert 'overflows float64' in str(exc)
        return
    for part in (pic.path, pic.axis, pic.label_at):
        assert part is None or np.isfinite(part).all()
