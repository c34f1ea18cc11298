"""rot_tools.io.boundary: each batch item refused or read as the per-message converter does."""

import math

from hypothesis import example, given, settings as hsettings, strategies as st
import numpy as np
import pytest
from rot_tools.io import bag_read, boundary
from rot_tools.io.boundary import QUATERNION_TOLERANCE, RefusedInput
from scipy.spatial.transform import Rotation

TOL = QUATERNION_TOLERANCE
ODOMETRY_FIELDS = bag_read.SUPPORTED['nav_msgs/msg/Odometry']


def _per_message(q, tol=TOL):
    """(code, R or None) of the per-message converter (what rotation_node runs)."""
    try:
        R = boundary.quaternion_to_rotation(*q, tol)
    except RefusedInput as exc:
        return boundary.CODE[exc.reason], None
    return 0, R


SPECIAL = [0.0, -0.0, 1.0, -1.0, 0.5, 1e-300, 1e300, 1.7e308, math.nan, math.inf, -math.inf,
           1.0 + TOL, 1.0 - TOL, 1.0 + 1.0000001 * TOL, 1.0 - 1.0000001 * TOL,
           math.nextafter(1.0 + TOL, 2.0), math.nextafter(1.0 + TOL, 0.0)]
COMPONENT = st.one_of(st.sampled_from(SPECIAL), st.floats(-2.0, 2.0),
                      st.floats(allow_nan=True, allow_infinity=True))


@hsettings(max_examples=400, deadline=None)
@given(st.tuples(COMPONENT, COMPONENT, COMPONENT, COMPONENT))
@example((0.0, 0.0, 0.0, 1.0 + TOL))
@example((0.0, 0.0, 0.0, 1.0 - TOL))
@example((0.0, 0.0, 0.0, 0.0))
@example((0.0, 0.0, 0.0, math.nan))
def test_batch_and_per_message_give_the_same_verdict(q):
    code, R = _per_message(q)
    codes, norms = boundary.check_batch([q], TOL)
    assert codes.dtype == np.int8 and codes.shape == (1,)
    assert int(codes[0]) == code
    if code == 0:
        Rb = boundary.accepted_rotations([q], norms, codes)
        np.testing.assert_array_equal(Rb[0], R)  # the same normalised q, bit for bit


def test_tolerance_edge_is_the_same_threshold_in_both_engines():
    # norms straddling 1 ± tol by one ulp of the sum: both engines put each on the same side
    ws = np.array([math.nextafter(1.0 + TOL, -1.0) * k for k in (1.0, 1.0 + 1e-16, 1 + 2e-16)]
                  + [1.0 + TOL, 1.0 - TOL, math.nextafter(1.0 - TOL, 2.0)])
    q = np.zeros((len(ws), 4))
    q[:, 3] = ws
    codes, _ = boundary.check_batch(q, TOL)
    assert [int(c) for c in codes] == [_per_message(row)[0] for row in q]


def test_reasons_against_an_independent_rule():
    rng = np.random.default_rng(3)
    q = rng.normal(size=(2000, 4))
    q /= np.linalg.norm(q, axis=1)[:, None]
    q[:500] *= rng.uniform(0.99, 1.01, size=(500, 1))
    q[500:520] = 0.0
    q[520:540, 1] = np.nan
    q[540:560, 2] = np.inf
    codes, norms = boundary.check_batch(q, TOL)
    with np.errstate(invalid='ignore'):
        n = np.sqrt((q ** 2).sum(axis=1))
    want = np.where(np.abs(n - 1) > TOL, 3, 0)
    want[n == 0] = 2
    want[~np.isfinite(q).all(axis=1)] = 1
    np.testing.assert_array_equal(codes, want)
    ok = codes == 0
    R = boundary.accepted_rotations(q, norms, codes)
    np.testing.assert_allclose(R, Rotation.from_quat(q[ok]).as_matrix(), rtol=0, atol=1e-14)


def test_check_order_no_orientation_then_position_then_quaternion():
    q = np.array([[0, 0, 0, 0.0]] * 4)
    pos = np.array([[math.nan, 0, 0], [0, 0, 0], [math.nan, 0, 0], [0, 0, 0]])
    cov0 = np.array([-1.0, -1.0, 0.0, 0.0])
    codes, _ = boundary.check_batch(q, TOL, positions=pos, covariance0=cov0)
    names = [boundary.REFUSAL_REASONS[c - 1] for c in codes]
    assert names == ['no_orientation', 'no_orientation', 'non_finite', 'zero_quaternion']
    # the per-message converters agree
    with pytest.raises(RefusedInput) as info:
        boundary.require_orientation(-1.0)  # checked first, as rotation_node does
    assert info.value.reason == 'no_orientation'
    with pytest.raises(RefusedInput) as info:  # Odometry's pose.pose: position, orientation
        boundary.rigid_motion((math.nan, 0.0, 0.0), (0, 0, 0, 0.0), TOL, 'pose.pose')
    assert info.value.reason == 'non_finite'
    assert str(info.value) == boundary.batch_refusal_text(
        ODOMETRY_FIELDS, boundary.CODE['non_finite'], (0, 0, 0, 0.0), 0.0, TOL,
        (math.nan, 0.0, 0.0)) == 'pose.pose.position.x is nan'


@pytest.mark.parametrize('q, reason, text', [
    ((0, 0, 0, 0.0), 'zero_quaternion', 'pose.pose.orientation is the zero quaternion'),
    ((0, math.inf, 0, 1.0), 'non_finite', 'pose.pose.orientation.y is inf'),
    ((0, 0, 0, 1.5), 'non_unit_quaternion',
     'pose.pose.orientation has norm 1.5, off 1 by 0.5 > quaternion_tolerance 0.001'),
])
def test_batch_text_is_the_per_message_text(q, reason, text):
    with pytest.raises(RefusedInput) as info:
        boundary.rigid_motion((0.0, 0.0, 0.0), q, TOL, 'pose.pose')
    codes, norms = boundary.check_batch([q], TOL, positions=[(0.0, 0.0, 0.0)])
    assert info.value.reason == reason == boundary.REFUSAL_REASONS[codes[0] - 1]
    assert str(info.value) == text == boundary.batch_refusal_text(
        ODOMETRY_FIELDS, int(codes[0]), q, float(norms[0]), TOL, (0.0, 0.0, 0.0))


@pytest.mark.parametrize('tol', [0.25, 0.5, 0.0])
def test_norm_exactly_at_the_tolerance_is_accepted_in_both_engines(tol):
    # |‖q‖ − 1| == tol exactly (1 ± tol is exact in binary): accepted, as "> tol" refuses
    q = np.array([[0.0, 0.0, 0.0, 1.0 + tol], [0.0, 0.0, 1.0 - tol, 0.0],
                  [0.0, 0.0, 0.0, math.nextafter(1.0 + tol, 3.0)]])
    codes, _ = boundary.check_batch(q, tol)
    assert [int(c) for c in codes] == [_per_message(row, tol)[0] for row in q] == [0, 0, 3]
