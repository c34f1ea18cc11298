"""Every invalid input raises RotationError (a ValueError) saying what was wrong and how much."""

import math
import re

from api_sweep import (
    assert_sweeps_every_public_function, parameters, public_functions, TIME_SERIES)
import hand_eye_helpers as he
import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    align_rotations, align_vectors, angular_speeds, axis_angle_to_matrix,
    change_covariance_frame, check_imu, compose_transforms, decompose, delta_pairs,
    error_statistics, estimate_time_offset, euler_covariance_to_rotvec, euler_to_matrix,
    frame_to_matrix, hand_eye, hand_eye_rotation, homogeneous_to_transform, interpolate_poses,
    invert_transform, is_rotation, matrix_to_axis_angle, matrix_to_euler, matrix_to_quaternion,
    matrix_to_rodrigues, matrix_to_rotvec, mean_rotation, nearest_rotation, nearest_stamps,
    quaternion_to_matrix, random_rotations, rodrigues_to_matrix, rot_x, rot_y, rot_z,
    rotation_distance, rotation_errors, RotationError, rotvec_covariance_to_euler,
    rotvec_to_matrix, screw_congruence, screw_exp, screw_from_transform,
    screw_interpolate, screw_log, skew, transform_from_screw, transform_points,
    transform_pose_covariance, transform_to_homogeneous, validate_rotation)

I3 = np.eye(3)
Z3 = np.zeros(3)
COV = np.diag([0.01, 0.02, 0.03])
NON_FINITE = r'(?i)finite|nan|inf'
NOT_ORTHOGONAL = r'R1?( \(T\[:3, :3\]\))? is not orthogonal: max\|RᵀR − I\| = '


def shape_pattern(got):
    """Message names the expected trailing shape and the shape it got."""
    return r'(?i)shape.*' + re.escape(str(tuple(got)))


def non_orthogonal(eps):
    """R with max|R^T R - I| = eps and det R = 1 exactly (one off-diagonal entry perturbed)."""
    r = np.eye(3)
    r[0, 1] = eps
    return r


# ---- the exception type ----------------------------------------------------------------


def test_rotation_error_is_a_value_error():
    assert issubclass(RotationError, ValueError)
    with pytest.raises(ValueError):
        validate_rotation(np.zeros((2, 2)))


# ---- rotation matrices: every function that takes R ------------------------------------

TAKES_R = {
    'validate_rotation': validate_rotation,
    'matrix_to_euler': matrix_to_euler,
    'matrix_to_axis_angle': matrix_to_axis_angle,
    'matrix_to_rotvec': matrix_to_rotvec,
    'matrix_to_rodrigues': matrix_to_rodrigues,
    'screw_from_transform': lambda r: screw_from_transform(r, np.zeros(np.shape(r)[:-1])),
    'screw_log': lambda r: screw_log(r, np.zeros(np.shape(r)[:-1])),
    'screw_interpolate': lambda r: screw_interpolate(r, Z3, I3, Z3, 0.5),
    'decompose': lambda r: decompose(r, Z3),
    'matrix_to_quaternion': matrix_to_quaternion,
    'transform_points': lambda r: transform_points(r, Z3, Z3),
    'compose_transforms': lambda r: compose_transforms(r, Z3, I3, Z3),
    'invert_transform': lambda r: invert_transform(r, Z3),
    'transform_to_homogeneous': lambda r: transform_to_homogeneous(r, Z3),
    'rotation_distance': lambda r: rotation_distance(r, I3),
    'mean_rotation': lambda r: mean_rotation(r[None] if np.shape(r) == (3, 3) else r),
    'change_covariance_frame': lambda r: change_covariance_frame(COV, r),
    'rotvec_covariance_to_euler': lambda r: rotvec_covariance_to_euler(r, COV),
    'transform_pose_covariance': lambda r: transform_pose_covariance(r, Z3, np.eye(6)),
}
"""How each public function that takes a rotation matrix is called with one (``r``)."""

MATRIX_PARAMETERS = {'R', 'R0', 'R1', 'R2'}

NOT_REFUSING_R = dict(
    TIME_SERIES, is_rotation='answers False for a matrix that is not a rotation',
    nearest_rotation='projects any matrix onto the nearest rotation')
"""Public functions that take a rotation matrix and are not swept by TAKES_R, and why."""


def test_every_function_taking_a_rotation_matrix_refuses_a_bad_one():
    takes_r = {name for name in public_functions() if parameters(name) & MATRIX_PARAMETERS}
    excused = {name: 'takes no rotation matrix' for name in public_functions() - takes_r}
    assert_sweeps_every_public_function(set(TAKES_R), dict(NOT_REFUSING_R, **excused))


@pytest.mark.parametrize('name', TAKES_R)
@pytest.mark.parametrize('shape', [(3,), (3, 4), (4, 3), (2, 2), (2, 2, 2), (5, 3, 2)])
def test_wrong_matrix_shape(name, shape):
    with pytest.raises(RotationError, match=shape_pattern(shape)):
        TAKES_R[name](np.zeros(shape))


@pytest.mark.parametrize('name', TAKES_R)
@pytest.mark.parametrize('bad', [np.nan, np.inf, -np.inf])
def test_non_finite_matrix(name, bad):
    r = np.stack([I3, I3])
    r[1, 2, 0] = bad
    with pytest.raises(RotationError, match=NON_FINITE) as info:
        TAKES_R[name](r)
    assert str(bad).lower().lstrip('-') in str(info.value).lower()


@pytest.mark.parametrize('name', TAKES_R)
@pytest.mark.parametrize('eps', [1e-8, 1e-3, 0.5])
def test_non_orthogonal_matrix_names_the_error_size(name, eps):
    with pytest.raises(RotationError, match=NOT_ORTHOGONAL) as info:
        TAKES_R[name](non_orthogonal(eps))
    assert h.mentions_magnitude(str(info.value), eps), str(info.value)


@pytest.mark.parametrize('name', TAKES_R)
def test_scaled_matrix_names_the_error_size(name):
    with pytest.raises(RotationError, match=NOT_ORTHOGONAL) as info:
        TAKES_R[name](1.01 * rot_z(0.3))
    assert h.mentions_magnitude(str(info.value), 1.01 ** 2 - 1), str(info.value)


@pytest.mark.parametrize('name', TAKES_R)
@pytest.mark.parametrize('reflection', [np.diag([1.0, 1.0, -1.0]), -I3, -rot_x(0.4)])
def test_reflection(name, reflection):
    with pytest.raises(RotationError, match=r'(?i)reflection|det') as info:
        TAKES_R[name](reflection)
    assert -1.0 in h.numbers_in(str(info.value)), str(info.value)


def test_non_orthogonal_item_inside_a_batch():
    batch = rot_z(np.linspace(0, 3, 6))
    batch[4] = non_orthogonal(1e-4)
    with pytest.raises(RotationError, match=NOT_ORTHOGONAL) as info:
        matrix_to_axis_angle(batch)
    assert h.mentions_magnitude(str(info.value), 1e-4)


def test_within_tolerance_is_accepted_beyond_is_refused():
    validate_rotation(non_orthogonal(5e-10))
    with pytest.raises(RotationError, match=NOT_ORTHOGONAL):
        validate_rotation(non_orthogonal(5e-9))
    validate_rotation(non_orthogonal(5e-9), tol=1e-8)


def test_non_numeric_matrix():
    with pytest.raises(RotationError):
        validate_rotation('not a matrix')


def test_nearest_rotation_refuses_what_cannot_be_projected():
    with pytest.raises(RotationError, match=shape_pattern((2, 3))):
        nearest_rotation(np.zeros((2, 3)))
    with pytest.raises(RotationError, match=NON_FINITE):
        nearest_rotation(np.full((3, 3), np.nan))
    with pytest.raises(RotationError, match=r'(?i)det|reflection|singular'):
        nearest_rotation(np.diag([1.0, 1.0, -1.0]))


# ---- check=False skips validation ------------------------------------------------------


WITH_CHECK = {
    'matrix_to_euler': lambda m, c: matrix_to_euler(m, check=c),
    'matrix_to_axis_angle': lambda m, c: matrix_to_axis_angle(m, check=c),
    'matrix_to_rotvec': lambda m, c: matrix_to_rotvec(m, check=c),
    'matrix_to_rodrigues': lambda m, c: matrix_to_rodrigues(m, check=c),
    'matrix_to_quaternion': lambda m, c: matrix_to_quaternion(m, check=c),
    'screw_from_transform': lambda m, c: screw_from_transform(m, Z3, check=c),
    'screw_log': lambda m, c: screw_log(m, Z3, check=c),
    'screw_interpolate': lambda m, c: screw_interpolate(m, Z3, I3, Z3, 0.5, check=c),
    'decompose': lambda m, c: decompose(m, Z3, check=c),
    'transform_points': lambda m, c: transform_points(m, Z3, [1.0, 2.0, 3.0], check=c),
    'compose_transforms': lambda m, c: compose_transforms(m, Z3, I3, Z3, check=c),
    'invert_transform': lambda m, c: invert_transform(m, Z3, check=c),
    'transform_to_homogeneous': lambda m, c: transform_to_homogeneous(m, Z3, check=c),
    'rotation_distance': lambda m, c: rotation_distance(m, I3, check=c),
    'mean_rotation': lambda m, c: mean_rotation(
        np.stack([m, np.broadcast_to(I3, np.shape(m))], -3), check=c),
    'homogeneous_to_transform': lambda m, c: homogeneous_to_transform(
        h.homogeneous(m, Z3), check=c),
}
"""How each public function with a check switch is called on a matrix ``m``."""


@pytest.mark.parametrize('name', WITH_CHECK)
def test_check_false_skips_validation(name):
    # Without the check the answer moves by about the perturbation (1e-6): no error, no NaN.
    call = WITH_CHECK[name]
    r = rot_z(0.4) @ rot_y(0.3)
    bad = non_orthogonal(1e-6) @ r
    with pytest.raises(RotationError, match=NOT_ORTHOGONAL):
        call(bad, True)
    clean, loose = flatten(call(r, True)), flatten(call(bad, False))
    assert np.all(np.isfinite(loose))
    assert 1e-9 < h.max_abs(loose - clean) <= 1e-5, h.max_abs(loose - clean)


def test_the_check_switch_is_swept_in_every_function_that_has_one():
    with_check = {name for name in public_functions() if 'check' in parameters(name)}
    assert_sweeps_every_public_function(set(WITH_CHECK), {
        name: 'has no check switch' for name in public_functions() - with_check})


def flatten(result):
    """Every number of a function's result, as one flat float array."""
    if isinstance(result, tuple):
        return np.concatenate([flatten(x) for x in result])
    return np.ravel(np.asarray(result, dtype=float))


# ---- vectors, angles, quaternions and twists: shape and finiteness ------------------------


SHAPED = {
    'is_rotation': (lambda s: is_rotation(np.zeros(s)), [(3,), (3, 4), (2, 2), (4, 3, 2)]),
    'euler_to_matrix': (lambda s: euler_to_matrix(np.zeros(s), 'ZYX'), [(), (2,), (4,), (5, 2)]),
    'skew': (lambda s: skew(np.zeros(s)), [(), (2,), (4,), (3, 2)]),
    'axis_angle_to_matrix': (lambda s: axis_angle_to_matrix(np.ones(s), 0.5),
                             [(), (2,), (4,), (2, 4)]),
    'rotvec_to_matrix': (lambda s: rotvec_to_matrix(np.ones(s)), [(), (2,), (4,)]),
    'quaternion_to_matrix': (lambda s: quaternion_to_matrix(np.ones(s)), [(), (3,), (5,), (2, 3)]),
    'screw_from_transform': (lambda s: screw_from_transform(I3, np.zeros(s)), [(), (2,), (4,)]),
    'screw_log': (lambda s: screw_log(I3, np.zeros(s)), [(), (2,), (4,)]),
    'screw_exp': (lambda s: screw_exp(np.zeros(s)), [(), (3,), (5,), (7,)]),
    'transform_from_screw direction': (
        lambda s: transform_from_screw(np.zeros(s), Z3, 1.0, 0.0), [(4,)]),
    'transform_from_screw point': (
        lambda s: transform_from_screw([0.0, 0.0, 1.0], np.zeros(s), 1.0, 0.0), [(4,)]),
}
"""How each function of vectors is called with an argument of shape s, and shapes it refuses."""


@pytest.mark.parametrize('name, shape', [(name, shape) for name, (_, shapes) in SHAPED.items()
                                         for shape in shapes])
def test_wrong_input_shape(name, shape):
    with pytest.raises(RotationError, match=shape_pattern(shape)):
        SHAPED[name][0](shape)


def finite_in(field):
    """Message saying that ``field`` must be finite."""
    return r'(?i)' + field + r'.*(finite|nan|inf)'


GIVEN_NON_FINITE = {
    'euler_to_matrix': (lambda x: euler_to_matrix([[0.0] * 3, [0.0, x, 0.0]], 'XYZ'), NON_FINITE),
    'rot_x': (lambda x: rot_x([0.0, x]), NON_FINITE),
    'rot_y': (lambda x: rot_y([0.0, x]), NON_FINITE),
    'rot_z': (lambda x: rot_z([0.0, x]), NON_FINITE),
    'skew': (lambda x: skew([1.0, x, 2.0]), NON_FINITE),
    'axis_angle_to_matrix axis': (lambda x: axis_angle_to_matrix([0.0, x, 1.0], 0.5),
                                  finite_in('axis')),
    'axis_angle_to_matrix angle': (lambda x: axis_angle_to_matrix([0.0, 0.0, 1.0], [0.1, x]),
                                   finite_in('angle')),
    'rotvec_to_matrix': (lambda x: rotvec_to_matrix([[0.0, 0.0, 1.0], [x, 0.0, 0.0]]), NON_FINITE),
    'quaternion_to_matrix': (lambda x: quaternion_to_matrix([0.0, x, 0.0, 1.0]), NON_FINITE),
    'screw_from_transform': (lambda x: screw_from_transform(I3, [0.0, x, 1.0]),
                             finite_in('translation')),
    'screw_log': (lambda x: screw_log(I3, [0.0, x, 1.0]), finite_in('translation')),
    'screw_exp': (lambda x: screw_exp([0.0, 0.0, 1.0, x, 0.0, 0.0]), NON_FINITE),
    'screw_interpolate fraction': (
        lambda x: screw_interpolate(I3, Z3, rot_z(1.0), [1.0, 0.0, 0.0], x), NON_FINITE),
    'transform_from_screw direction': (
        lambda x: transform_from_screw([0.0, x, 1.0], Z3, 1.0, 0.5), NON_FINITE),
    'transform_from_screw point': (
        lambda x: transform_from_screw([0.0, 0.0, 1.0], [0.0, x, 1.0], 1.0, 0.5), NON_FINITE),
    'transform_from_screw angle': (
        lambda x: transform_from_screw([0.0, 0.0, 1.0], Z3, x, 0.5), NON_FINITE),
    'transform_from_screw translation': (
        lambda x: transform_from_screw([0.0, 0.0, 1.0], Z3, 1.0, x), NON_FINITE),
}
"""How each function of vectors is called with one number ``x``, and its message if not finite."""


@pytest.mark.parametrize('name', GIVEN_NON_FINITE)
@pytest.mark.parametrize('bad', [np.nan, np.inf, -np.inf])
def test_non_finite_input(name, bad):
    call, message = GIVEN_NON_FINITE[name]
    with pytest.raises(RotationError, match=message):
        call(bad)


# ---- Euler -----------------------------------------------------------------------------


@pytest.mark.parametrize('seq', ['ZYx', 'zYX', 'XXY', 'xxy', 'ABC', '', 'ZYXZ', 'ZY', 'XYW',
                                 ' ZYX', 'Z-Y-X'])
def test_unknown_euler_sequence(seq):
    with pytest.raises(RotationError, match=r'(?i)sequence.*' + re.escape(repr(seq))):
        euler_to_matrix(Z3, seq)
    with pytest.raises(RotationError, match=r'(?i)sequence.*' + re.escape(repr(seq))):
        matrix_to_euler(I3, seq)


@pytest.mark.parametrize('seq', [None, 123, ('Z', 'Y', 'X')])
def test_euler_sequence_not_a_string(seq):
    with pytest.raises(RotationError, match=r'(?i)sequence'):
        euler_to_matrix(Z3, seq)


# ---- axis-angle and rotation vectors ---------------------------------------------------


@pytest.mark.parametrize('angle', [0.5, -1e-3, 1e-12, np.pi])
def test_zero_axis_with_non_zero_angle(angle):
    with pytest.raises(RotationError, match=r'(?i)zero') as info:
        axis_angle_to_matrix(Z3, angle)
    assert h.mentions_magnitude(str(info.value), angle, factor=1.01), str(info.value)


def test_zero_axis_inside_a_batch():
    with pytest.raises(RotationError, match=r'(?i)zero'):
        axis_angle_to_matrix([[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]], [0.5, 0.3])


def test_axis_and_angle_shapes_that_do_not_broadcast():
    with pytest.raises(RotationError, match=r'(?i)broadcast|shape'):
        axis_angle_to_matrix(np.ones((3, 3)), np.ones(4))


# ---- quaternions -----------------------------------------------------------------------


def test_zero_quaternion():
    with pytest.raises(RotationError, match=r'non-zero, got \|q\| = 0$'):
        quaternion_to_matrix([0.0, 0.0, 0.0, 0.0])
    with pytest.raises(RotationError, match=r'non-zero, got \|q\| = 0 \(item \(1,\)\)$'):
        quaternion_to_matrix([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])
    q = np.ones((2, 3, 4))
    q[1, 2] = 0.0
    with pytest.raises(RotationError, match=r'\|q\| = 0 \(item \(1, 2\)\)$'):
        quaternion_to_matrix(q, tol=10.0)


def test_quaternion_tolerance_refuses_a_quaternion_too_far_from_unit_length():
    # |q| from math.hypot; within tol the matrix is the normalised textbook one.
    rng = np.random.default_rng(41)
    q = rng.normal(size=(50, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q *= 1.0 + rng.uniform(-9e-4, 9e-4, (50, 1))
    ref = h.ref_quaternion_to_matrix(q)
    assert h.max_abs(quaternion_to_matrix(q, tol=1e-3) - ref) <= 1e-15 * 8
    assert h.max_abs(quaternion_to_matrix(q[7], tol=1e-3) - ref[7]) <= 1e-15 * 8
    assert h.max_abs(quaternion_to_matrix(3 * q) - ref) <= 1e-15 * 8  # tol=None: any size
    sizes = np.array([math.hypot(*x) for x in q])
    worst = int(np.argmax(np.abs(sizes - 1)))
    off = abs(sizes[worst] - 1)
    with pytest.raises(RotationError) as info:
        quaternion_to_matrix(q, tol=0.99 * off)
    message = str(info.value)
    assert message.startswith('quaternion (x, y, z, w) is not of unit length: |q| = ')
    assert message.endswith(f'(worst at item ({worst},))')
    assert h.mentions_magnitude(message, sizes[worst], 1 + 1e-9)
    assert h.mentions_magnitude(message, off, 1.01)
    quaternion_to_matrix(q, tol=1.01 * off)


@pytest.mark.parametrize('q, tol, size, off', [
    ([0.0, 0.0, 0.7, 0.7], 1e-3, '0.989949494', '0.0101'),
    ([0.0, 0.0, 0.0, 1.0011], 1e-3, '1.0011', '0.0011'),
    ([1e200, 1e200, 0.0, 0.0], 1.0, '1.41421356e+200', '1.41e+200'),
    ([1.5e308, 1.5e308, 0.0, 0.0], 1.0, '2.12132034e+308', '2.12e+308'),
    ([0.0, 0.0, 0.6, 0.8 + 2e-16], 0.0, '1', '2.22e-16'),
])
def test_quaternion_tolerance_message(q, tol, size, off):
    with pytest.raises(RotationError, match=re.escape(
            f'is not of unit length: |q| = {size}, off 1 by {off} > tol {tol:g}') + '$'):
        quaternion_to_matrix(q, tol=tol)


def test_quaternion_tolerance_edges():
    assert np.array_equal(quaternion_to_matrix([0.0, 0.0, 0.6, 0.8], tol=0.0),
                          quaternion_to_matrix([0.0, 0.0, 0.6, 0.8]))
    quaternion_to_matrix([0.0, 0.0, 0.0, 0.9991], tol=1e-3)
    for bad in (-1e-3, float('nan'), '1e-3'):
        with pytest.raises(RotationError, match=r'tol must be a number ≥ 0'):
            quaternion_to_matrix([0.0, 0.0, 0.0, 1.0], tol=bad)


# ---- screws ----------------------------------------------------------------------------


def test_transform_from_screw_zero_direction():
    with pytest.raises(RotationError, match=r'(?i)direction.*(zero|0)'):
        transform_from_screw(Z3, Z3, 1.0, 0.0)


def test_screw_interpolate_bad_end_transform():
    with pytest.raises(RotationError, match=NOT_ORTHOGONAL):
        screw_interpolate(I3, Z3, 2.0 * I3, Z3, 0.5)
    with pytest.raises(RotationError, match=NON_FINITE):
        screw_interpolate(I3, Z3, I3, [np.inf, 0.0, 0.0], 0.5)


@pytest.mark.parametrize('lock_tol', [-1e-9, float('nan'), float('inf'), 1.0, '1e-6', None,
                                      True])
def test_bad_gimbal_lock_tolerance(lock_tol):
    with pytest.raises(RotationError, match=r'lock_tol must be in \[0, π/4\) rad'):
        matrix_to_euler(np.eye(3), 'ZYX', lock_tol=lock_tol)


@pytest.mark.parametrize('tol', [-1e-9, float('nan'), '1e-9', None, True, [1e-9]])
def test_bad_rotation_tolerance(tol):
    """Check that a tolerance of another type is refused like a negative one (not a TypeError)."""
    for check in (is_rotation, validate_rotation):
        with pytest.raises(RotationError, match=r'^tol must be a number ≥ 0, got '):
            check(np.eye(3), tol=tol)
    with pytest.raises(RotationError, match=r'^tol must be in \[0, 1\), got '):
        frame_to_matrix([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], tol=tol)


# ---- finite input never gives inf or NaN: overflow is a RotationError -----------------------

OVERFLOW = r'overflows float64'


@pytest.mark.parametrize('b', [[1e300, 1e300, 0.0], [-3e299, 0.0, 1e300]])
@pytest.mark.parametrize('f', [screw_from_transform, decompose])
def test_screw_of_a_huge_translation_at_a_tiny_angle(f, b):
    # The axis point is ~|b|/θ = 1e311 away: refused, saying |b| and θ.
    with pytest.raises(RotationError, match=OVERFLOW) as info:
        f(rot_z(1e-11), b)
    message = str(info.value)
    assert h.mentions_magnitude(message, 1e300, 1.01) and h.mentions_magnitude(message, 1e-11)
    with pytest.raises(RotationError, match=OVERFLOW + r'.*first at item \(1,\)'):
        f(rot_z([0.5, 1e-11]), b)


def test_screw_pitch_overflow_along_the_axis():
    # b along the axis: the point stays 0, the pitch d/θ = 1e300/1e-11 overflows.
    with pytest.raises(RotationError, match=OVERFLOW):
        screw_from_transform(rot_z(1e-11), [0.0, 0.0, 1e300])


def test_pure_translation_beyond_float64():
    with pytest.raises(RotationError, match=r'screw translation \|b\| ' + OVERFLOW) as info:
        screw_from_transform(I3, [1.5e308, 1.5e308, 0.0])
    assert h.mentions_magnitude(str(info.value), 1.5e308, 1.01)


def test_screw_log_overflow():
    with pytest.raises(RotationError, match=r'θ·v of screw_log .*' + OVERFLOW):
        screw_log(rot_z(1.0), [1.7e308, 1.7e308, 0.0])
    # representable: a 1e300 translation at a tiny angle has θ·v ≈ b
    tw = screw_log(rot_z(1e-11), [1e300, 1e300, 0.0])
    assert np.all(np.isfinite(tw)) and h.max_abs(tw[3:] / 1e300 - [1, 1, 0]) <= 1e-11


def test_a_screw_point_that_fits_is_returned_near_the_largest_float():
    # c ≈ (9.1, −7.9, 0)e308 fits though b + cot 1.5·ẑ × b does not; checked by R·c + b = c.
    R = h.ref_elementary('z', 3.0)
    b = np.array([1.7e308, -1.7e308, 0.0])
    screw = screw_from_transform(R, b)
    c = screw.point / 1e308
    assert h.max_abs(R @ c + b / 1e308 - c) <= 1e-15 * 8 and c[2] == 0
    assert screw.translation == 0 and screw.pitch == 0 and np.isfinite(screw.moment).all()
    batch = screw_from_transform(np.stack([R, R]), b)
    assert batch.point.tobytes() == np.stack([screw.point] * 2).tobytes()


def test_screw_log_that_fits_is_returned_though_b_dot_the_axis_overflows():
    # b = 1.7e308·(1, 1, 0) along the axis l̂ = (1, 1, 0)/√2: d = b·l̂ = 2.4e308 leaves float64
    # on the way, but the twist (θ·l̂, d·l̂) = (θ·l̂, b) fits.
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    b = np.array([1.7e308, 1.7e308, 0.0])
    twist = screw_log(h.notes_rodrigues_eq7(axis, 0.5), b)
    assert h.max_abs(twist[:3] - 0.5 * axis) <= 1e-15 * 8
    assert h.max_abs(twist[3:] / 1e308 - b / 1e308) <= 1e-15 * 8


def test_screw_exp_overflow():
    with pytest.raises(RotationError, match=r'rotation angle \|ω\| of the twist ' + OVERFLOW):
        screw_exp([1.5e308, 1.5e308, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(RotationError, match=r'b of screw_exp ' + OVERFLOW):
        screw_exp([0.0, 0.0, np.pi / 2, 1.7e308, 1.7e308, 0.0])
    with pytest.raises(RotationError, match=OVERFLOW + r'.*first at item \(1,\)'):
        screw_exp([[0.0] * 6, [0.0, 0.0, np.pi / 2, 1.7e308, 1.7e308, 0.0]])


def test_transform_from_screw_overflow():
    with pytest.raises(RotationError, match=r'\(I − R\)·point \+ d·l̂ .*' + OVERFLOW):
        transform_from_screw([0.0, 0.0, 1.0], [1.7e308, 0.0, 0.0], np.pi, 0.0)
    # a far point with a huge angle is fine when b itself is representable
    r, b = transform_from_screw([0.0, 0.0, 1.0], [1e300, 0.0, 0.0], 1e10, 0.0)
    assert np.all(np.isfinite(r)) and np.all(np.isfinite(b))


def test_rotation_vector_overflow():
    with pytest.raises(RotationError, match=r'angle \|θ·l̂\| of the rotation vector ' + OVERFLOW):
        rotvec_to_matrix([1.5e308, 1.5e308, 0.0])
    with pytest.raises(RotationError, match=OVERFLOW + r'.*first at item \(0,\)'):
        rotvec_to_matrix([[1.5e308, 1.5e308, 0.0], [0.0, 0.0, 1.0]])


@pytest.mark.parametrize('b0, b1, s, what', [
    ([-1e308, 0, 0], [1e308, 0, 0], 0.5, r'R0ᵀ·\(b1 − b0\)'),
    (Z3, [1e308, 0, 0], 10.0, r's·log\(T0⁻¹·T1\)'),
    ([1e308, 0, 0], [1.5e308, 0, 0], 3.0, r'b\(s\)'),
])
def test_screw_interpolate_overflow(b0, b1, s, what):
    with pytest.raises(RotationError, match=what + ' of screw_interpolate ' + OVERFLOW):
        screw_interpolate(I3, b0, I3, b1, s)


HUGE = (1.7e308, -1.7e308, 1e300, 1e-300, 5e-324, 0.0, 1.0)


def huge_vectors():
    rng = np.random.default_rng(90)
    return np.array([rng.choice(HUGE, 3) for _ in range(200)] + [[1.5e308, 1.5e308, 0.0]])


def finite_or_refused(call, *args):
    """Tell whether ``call`` answers with finite numbers or raises RotationError."""
    try:
        out = call(*args)
    except RotationError:
        return True
    leaves = out if isinstance(out, tuple) else (out,)
    return all(np.all(np.isfinite(leaf)) for leaf in leaves)


def _diagonal(w):
    """Return matrices with the entries of ``w`` (..., 3) on their diagonals."""
    return w[..., :, None] * I3


RIG = he.arm_stations(1, stations=7)
"""A small hand-eye recording: a camera on a hand, seen from seven stations."""


def _rig_moved(r, w):
    """Return RIG's poses (R_a, b_a, R_b, b_b) in worlds moved by w and turned by r."""
    scale = abs(w[0])
    with np.errstate(over='ignore'):
        return (r @ RIG.R_a, scale * RIG.b_a @ r.T + w, RIG.R_b, scale * RIG.b_b + w[::-1])


def _hand_eye_numbers(result):
    """Every number of a HandEyeCalibration but its correlation (NaN for a given offset)."""
    return flatten(result._replace(correlation=0.0, rejected=np.array(
        [rejection.stamp for rejection in result.rejected])))


def _of_each(call, r, w):
    """Return call(r, w) as a tuple for one r (3, 3) and w (3,); one per item for a batch."""
    if np.ndim(w) == 1:
        return (call(r, w),)
    return tuple(call(r_k, w_k) for r_k, w_k in zip(r, w))


FINITE_CALLS = {
    'rotvec_to_matrix': lambda r, w: rotvec_to_matrix(w),
    'rodrigues_to_matrix': lambda r, w: rodrigues_to_matrix(w),
    'axis_angle_to_matrix': lambda r, w: axis_angle_to_matrix(w, 1.0),
    'euler_to_matrix': lambda r, w: euler_to_matrix(w, 'ZYX'),
    'quaternion_to_matrix': lambda r, w: quaternion_to_matrix(
        np.concatenate([w, np.full(w.shape[:-1] + (1,), 1e300)], -1)),
    'rot_x': lambda r, w: rot_x(w[..., 0]),
    'rot_y': lambda r, w: rot_y(w[..., 1]),
    'rot_z': lambda r, w: rot_z(w[..., 2]),
    'skew': lambda r, w: skew(w),
    'screw_exp': lambda r, w: screw_exp(np.concatenate([w, w[..., ::-1]], -1)),
    'transform_from_screw': lambda r, w: transform_from_screw(w, w[..., ::-1], 2.0, w[..., 0]),
    'screw_log': lambda r, w: screw_log(r, w),
    'transform_points': lambda r, w: transform_points(r, w, w[..., ::-1]),
    'compose_transforms': lambda r, w: compose_transforms(r, w, r, w),
    'invert_transform': lambda r, w: invert_transform(r, w),
    'transform_to_homogeneous': lambda r, w: transform_to_homogeneous(r, w),
    'homogeneous_to_transform': lambda r, w: homogeneous_to_transform(h.homogeneous(r, w)),
    'screw_interpolate': lambda r, w: screw_interpolate(r, w, I3, -w, 3.0),
    'align_vectors': lambda r, w: align_vectors(np.stack([w, w[..., ::-1]], -2),
                                                np.stack([w[..., ::-1], w], -2)),
    'frame_to_matrix': lambda r, w: frame_to_matrix(w, w[..., ::-1], w[..., [1, 2, 0]]),
    'nearest_rotation': lambda r, w: nearest_rotation(_diagonal(w)),
    'mean_rotation': lambda r, w: mean_rotation(np.stack([r, r], -3), w[..., :2]),
    'change_covariance_frame': lambda r, w: change_covariance_frame(_diagonal(np.abs(w)), r),
    'rotvec_covariance_to_euler': lambda r, w: rotvec_covariance_to_euler(
        np.broadcast_to(I3, r.shape), _diagonal(np.abs(w))),
    'euler_covariance_to_rotvec': lambda r, w: euler_covariance_to_rotvec(
        w, _diagonal(np.abs(w))),
    'transform_pose_covariance': lambda r, w: transform_pose_covariance(
        r, w, np.kron(I3[:2, :2], _diagonal(np.abs(w)))),
    'hand_eye': lambda r, w: _of_each(lambda r, w: _hand_eye_numbers(hand_eye(
        RIG.stamps_a, *_rig_moved(r, w)[:2], RIG.stamps_b, *_rig_moved(r, w)[2:])), r, w),
    'screw_congruence': lambda r, w: _of_each(
        lambda r, w: flatten(screw_congruence(*_rig_moved(r, w))), r, w),
}
"""How each public function of items is called on rotations ``r`` and extreme vectors ``w``."""

NOT_OF_EXTREMES = dict(
    {name: why for name, why in TIME_SERIES.items() if name not in FINITE_CALLS},
    random_rotations='draws rotations: takes a count',
    is_rotation='answers True or False', validate_rotation='gives back its input',
    matrix_to_axis_angle='takes a rotation only', matrix_to_rotvec='takes a rotation only',
    matrix_to_rodrigues='takes a rotation only',
    matrix_to_quaternion='takes a rotation only', matrix_to_euler='takes a rotation only',
    rotation_distance='takes rotations only',
    screw_from_transform='its pitch is inf for a pure translation: the test below',
    decompose='its pitch is inf for a pure translation: the test below')
"""The public functions not called on extreme vectors, and why."""


def test_the_sweep_of_extremes_calls_every_public_function():
    assert_sweeps_every_public_function(set(FINITE_CALLS), NOT_OF_EXTREMES)


@pytest.mark.parametrize('name', sorted(FINITE_CALLS))
@pytest.mark.parametrize('batch', [False, True])
def test_no_function_returns_inf_or_nan_for_finite_input(name, batch):
    # Finite numbers or RotationError (never a plain ValueError or OverflowError from math,
    # never inf or NaN), for vectors of huge, tiny and subnormal entries.
    rotations = np.concatenate([h.cube_rotations(), rot_z([1e-11, 1e-13, 0.5, np.pi])])
    rng = np.random.default_rng(91)
    wrong = []
    for v in huge_vectors():
        r = rotations[rng.integers(len(rotations))]
        w, r = (np.stack([v, v]), np.stack([r, r])) if batch else (v, r)
        if not finite_or_refused(FINITE_CALLS[name], r, w):
            wrong.append(v)
    assert wrong == [], wrong[:3]


@pytest.mark.parametrize('name', ['screw_from_transform', 'decompose'])
def test_a_motion_is_finite_but_the_pitch_of_a_pure_translation(name):
    # (the pitch, translation / angle, is inf where the angle is 0 and b is not)
    rotations = np.concatenate([h.cube_rotations(), rot_z([1e-11, 1e-13, 0.5, np.pi])])
    rng = np.random.default_rng(92)
    for w in huge_vectors():
        try:
            found = {'screw_from_transform': screw_from_transform, 'decompose': decompose}[
                name](rotations[rng.integers(len(rotations))], w)
        except RotationError:
            continue
        parts = found._asdict()
        screw = parts.pop('screw') if name == 'decompose' else found
        parts.update(screw._asdict())
        pitch = parts.pop('pitch')
        assert all(np.all(np.isfinite(part)) for part in parts.values()), (w, parts)
        assert np.all(np.isfinite(pitch) | (screw.angle == 0)), w


@pytest.mark.parametrize('scale', [1.7e308, 1e300, 1e-300])
def test_nearest_rotation_of_any_finite_scale(scale):
    r = rot_z(0.3) @ rot_x(-1.2)
    assert h.max_abs(nearest_rotation(scale * r) - r) <= 1e-15 * 4
    assert np.array_equal(nearest_rotation(5e-324 * I3), I3)


# ---- a size printed beside its tolerance reads as bigger --------------------------------------


@pytest.mark.parametrize('call', [
    lambda: frame_to_matrix([1.0, 0.0, 0.0], [1.0, 1e-300, 0.0], [0.0, 0.0, 1.0], 0.99999999),
    lambda: frame_to_matrix([1.0, 0.0, 0.0], [1.0, 1e-4, 0.0], [0.0, 0.0, 1.0], 0.99999999),
    lambda: validate_rotation(np.diag([1.0, 1.0, 1.0 + 1.0000001e-5]), tol=2e-5),
    lambda: quaternion_to_matrix([0.0, 0.0, 0.0, 1.0010001], tol=1e-3),
    lambda: homogeneous_to_transform(np.diag([1.0, 1.0, 1.0, 1.0 + 1.0000002e-9])),
])
def test_a_size_beyond_its_tolerance_is_printed_with_the_digits_that_show_it(call):
    with pytest.raises(RotationError) as info:
        call()
    shown, bound = re.search(r'(\S+) > (?:tol )?([^\s)]+)', str(info.value)).groups()
    assert float(shown) > float(bound)


def test_sizes_far_from_their_tolerance_keep_three_digits():
    with pytest.raises(RotationError, match=re.escape(
            '|cos| = 0.0995 > tol 1e-05 (the angle between them is 90° − 5.71°)')):
        frame_to_matrix([1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], 1e-5)
    with pytest.raises(RotationError, match=re.escape(
            '|cos| = 1 > tol 0.99999999 (the angle between them is 90° − 90°)')):
        frame_to_matrix([1.0, 0.0, 0.0], [1.0, 1e-300, 0.0], [0.0, 0.0, 1.0], 0.99999999)


# ---- check=False on matrices that are not rotations: no exception but RotationError ----------

GARBAGE = [np.full((3, 3), v) for v in (1e308, -1e308, 1e200, 1e-320, 0.0, np.nan, np.inf)] + [
    np.diag([1e308, -1e308, 1.0]), np.diag([-1.0, 1.0, 1.0]),
    np.random.default_rng(43).normal(size=(3, 3)) * 1e300]


@pytest.mark.parametrize('name', sorted(WITH_CHECK))
@pytest.mark.parametrize('batch', [False, True])
def test_unchecked_garbage_gives_a_result_or_a_rotation_error(name, batch):
    for R in GARBAGE:
        try:
            with np.errstate(all='ignore'):
                WITH_CHECK[name](np.stack([R, np.eye(3)]) if batch else R, False)
        except RotationError:
            pass


def test_unchecked_mean_of_huge_or_non_finite_matrices():
    with pytest.raises(RotationError, match='not unique'):  # (not NumPy's LinAlgError)
        mean_rotation(np.full((3, 3, 3), 1e308), check=False)
    for bad in (np.nan, np.inf):  # (an SVD raises on NaN and may not end on Inf)
        with pytest.raises(RotationError, match=r'R must be finite'):
            mean_rotation(np.stack([np.eye(3), np.diag([1.0, bad, 1.0])]), check=False)
    # finite matrices of any size: the polar factor of their sum (Newton's iteration)
    m = np.stack([rot_z(0.3), rot_x(0.2), np.diag([1.0, 1.1, 0.9])]) * 1e306
    assert h.max_abs(mean_rotation(m, check=False) - h.polar_rotation(m.sum(0) / 1e306)) <= 1e-14


# ---- any Python or NumPy input: a RotationError, never another exception -------------------
# (Python ints beyond float64, complex numbers, tolerances of any numeric type, sizes)

# Every public function that coerces numbers, called with good arguments; CORRUPT replaces
# one argument at a time.
def _calls():
    q = [0.0, 0.0, 0.0, 1.0]
    v3 = [0.1, 0.2, 0.3]
    cov = COV.tolist()
    turning = [rot_z(0.1 * k).tolist() for k in range(10)]
    stamps = [0.01 * k for k in range(10)]
    return {
        'rot_x': (rot_x, [0.3]), 'rot_y': (rot_y, [0.3]), 'rot_z': (rot_z, [0.3]),
        'skew': (skew, [v3]),
        'is_rotation': (is_rotation, [I3.tolist()]),
        'validate_rotation': (validate_rotation, [I3.tolist()]),
        'nearest_rotation': (nearest_rotation, [I3.tolist()]),
        'euler_to_matrix': (euler_to_matrix, [v3]),
        'matrix_to_euler': (matrix_to_euler, [I3.tolist()]),
        'axis_angle_to_matrix': (axis_angle_to_matrix, [[0.0, 0.0, 1.0], 0.5]),
        'matrix_to_axis_angle': (matrix_to_axis_angle, [I3.tolist()]),
        'rotvec_to_matrix': (rotvec_to_matrix, [v3]),
        'matrix_to_rotvec': (matrix_to_rotvec, [I3.tolist()]),
        'rodrigues_to_matrix': (rodrigues_to_matrix, [v3]),
        'matrix_to_rodrigues': (matrix_to_rodrigues, [I3.tolist()]),
        'quaternion_to_matrix': (quaternion_to_matrix, [q]),
        'matrix_to_quaternion': (matrix_to_quaternion, [I3.tolist()]),
        'screw_from_transform': (screw_from_transform, [I3.tolist(), v3]),
        'transform_from_screw': (transform_from_screw, [[0.0, 0.0, 1.0], v3, 0.5, 0.1]),
        'screw_log': (screw_log, [I3.tolist(), v3]),
        'screw_exp': (screw_exp, [[0.1, 0.2, 0.3, 0.4, 0.5, 0.6]]),
        'screw_interpolate': (screw_interpolate, [I3.tolist(), v3, I3.tolist(), v3, 0.5]),
        'decompose': (decompose, [I3.tolist(), v3]),
        'frame_to_matrix': (frame_to_matrix, [[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]]),
        'transform_points': (transform_points, [I3.tolist(), v3, v3]),
        'compose_transforms': (compose_transforms, [I3.tolist(), v3, I3.tolist(), v3]),
        'invert_transform': (invert_transform, [I3.tolist(), v3]),
        'transform_to_homogeneous': (transform_to_homogeneous, [I3.tolist(), v3]),
        'homogeneous_to_transform': (homogeneous_to_transform, [np.eye(4).tolist()]),
        'rotation_distance': (rotation_distance, [I3.tolist(), I3.tolist()]),
        'mean_rotation': (mean_rotation, [[I3.tolist(), I3.tolist()]]),
        'align_vectors': (align_vectors, [[[1.0, 0, 0], [0, 1.0, 0]], [[1.0, 0, 0], [0, 1.0, 0]]]),
        'random_rotations': (random_rotations, [3]),
        'change_covariance_frame': (change_covariance_frame, [cov, I3.tolist()]),
        'euler_covariance_to_rotvec': (euler_covariance_to_rotvec, [v3, cov]),
        'rotvec_covariance_to_euler': (rotvec_covariance_to_euler, [I3.tolist(), cov]),
        'transform_pose_covariance': (transform_pose_covariance,
                                      [I3.tolist(), v3, np.eye(6).tolist()]),
        'align_rotations': (align_rotations, [turning, turning]),
        'angular_speeds': (angular_speeds, [stamps, turning]),
        'error_statistics': (error_statistics, [v3]),
        'estimate_time_offset': (estimate_time_offset, [stamps, turning, stamps, turning, 0.02]),
        'hand_eye_rotation': (hand_eye_rotation, [turning[1:], turning[1:]]),
        'interpolate_poses': (interpolate_poses, [stamps, turning, [v3] * 10, [0.015]]),
        'nearest_stamps': (nearest_stamps, [stamps, [0.015]]),
        'rotation_errors': (rotation_errors, [turning, turning]),
        'delta_pairs': (delta_pairs, [10]),
        'check_imu': (check_imu, [stamps, [q] * 10, [[0.0, 0.0, 0.0]] * 10,
                                  [[0.0, 0.0, 9.81]] * 10]),
        # (its keyword arguments offset and min_angle given in places 7 and 8, to be swept too)
        'hand_eye': (lambda *args: hand_eye(*args[:6], offset=args[6], min_angle=args[7]),
                     [RIG.stamps_a.tolist(), RIG.R_a.tolist(), RIG.b_a.tolist(),
                      RIG.stamps_b.tolist(), RIG.R_b.tolist(), RIG.b_b.tolist(), 0.0, 0.05]),
        'screw_congruence': (screw_congruence, [RIG.R_a.tolist(), RIG.b_a.tolist(),
                                                RIG.R_b.tolist(), RIG.b_b.tolist(),
                                                [[0, 1], [2, 6]]]),
    }


CALLS = _calls()


def _replace_first_number(x, new):
    """Return x (a number or nested lists) with its first number replaced by ``new``."""
    if isinstance(x, list):
        return [_replace_first_number(x[0], new)] + x[1:]
    return new


def _arguments(name):
    """(index, argument) for every argument of CALLS[name] that holds numbers."""
    f, args = CALLS[name]
    return [(i, a) for i, a in enumerate(args)]


def test_the_sweep_of_python_numbers_calls_every_public_function():
    assert_sweeps_every_public_function(set(CALLS), {})


@pytest.mark.parametrize('name', sorted(CALLS))
def test_good_arguments_of_the_sweep_are_accepted(name):
    f, args = CALLS[name]
    f(*args)  # the sweeps below corrupt these: they must be valid to begin with


@pytest.mark.parametrize('name', sorted(CALLS))
def test_python_int_beyond_float64_is_a_rotation_error(name):
    # (float() of such an int raises OverflowError: the functions must say what is wrong)
    f, args = CALLS[name]
    for i, arg in _arguments(name):
        for huge in (10 ** 400, -(10 ** 309)):
            bad = list(args)
            bad[i] = _replace_first_number(arg, huge)
            with pytest.raises(RotationError, match=r'float64|, got '):
                f(*bad)


@pytest.mark.parametrize('name', sorted(CALLS))
def test_complex_input_is_a_rotation_error(name):
    # (np.asarray(x, dtype=float64) drops the imaginary part of a complex array: refused
    # instead, as complex Python numbers are)
    f, args = CALLS[name]
    for i, arg in _arguments(name):
        variants = [_replace_first_number(arg, 1 + 2j), _replace_first_number(arg, 0.5 + 0j),
                    np.asarray(arg, dtype=complex), np.asarray(arg, dtype=np.complex64),
                    _replace_first_number(arg, np.complex128(1j))]
        for variant in variants:
            bad = list(args)
            bad[i] = variant
            with pytest.raises(RotationError, match=r'complex|, got '):
                f(*bad)


def test_python_ints_within_float64_still_work():
    assert h.max_abs(rot_x(2 ** 1000) - rot_x(float(2 ** 1000))) == 0
    assert h.max_abs(rot_z([1, 2 ** 80]) - rot_z([1.0, float(2 ** 80)])) == 0


def test_complex_message_names_the_input_and_the_imaginary_part():
    with pytest.raises(RotationError, match=r'^angle must be real, got complex'):
        rot_x(np.array([0.1 + 0.5j]))


def test_int_beyond_float64_message():
    with pytest.raises(RotationError,
                       match=r'^angle must be numeric within float64 \(±1.8e308\)'):
        rot_x(10 ** 400)


@pytest.mark.parametrize('tol', [
    __import__('fractions').Fraction(1, 10 ** 6), __import__('decimal').Decimal('1e-6'),
    np.float32(1e-6), np.float16(0.001), np.int64(0), 0, np.array(1e-6)])
def test_tolerances_of_any_real_numeric_type(tol):
    # (NumPy's float64 <= Fraction is a Python bool, not a NumPy one)
    near = non_orthogonal(1e-7)
    far = non_orthogonal(1e-2)
    expect_near = float(tol) >= 1e-7
    assert is_rotation(near, tol=tol) is expect_near
    assert is_rotation(np.stack([near, far]), tol=tol).tolist() == [expect_near, False]
    if expect_near:
        validate_rotation(near, tol=tol)
    with pytest.raises(RotationError, match=NOT_ORTHOGONAL):
        validate_rotation(far, tol=tol)
    with pytest.raises(RotationError, match=r'not of unit length'):
        quaternion_to_matrix([0.0, 0.0, 0.0, 1.1], tol=tol)
    quaternion_to_matrix([0.0, 0.0, 0.0, 1.0], tol=tol)
    with pytest.raises(RotationError, match=r'not orthogonal'):
        frame_to_matrix([1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], tol=tol)
    frame_to_matrix([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], tol=tol)
    angles, locked = matrix_to_euler(rot_y(np.pi / 2 - 1e-9), lock_tol=tol)
    assert bool(locked) is (float(tol) >= 1e-9)


@pytest.mark.parametrize('tol', [1j, 1e-9 + 0j, np.complex128(1e-9), 10 ** 400,
                                 __import__('fractions').Fraction(10 ** 400),
                                 __import__('decimal').Decimal('NaN'), np.array([1e-9])])
def test_tolerances_that_are_not_a_real_float64_are_refused(tol):
    for check in (is_rotation, validate_rotation):
        with pytest.raises(RotationError, match=r'^tol must be a number ≥ 0'):
            check(np.eye(3), tol=tol)
    with pytest.raises(RotationError, match=r'^tol must be a number ≥ 0'):
        quaternion_to_matrix([0.0, 0.0, 0.0, 1.0], tol=tol)
    with pytest.raises(RotationError, match=r'^tol must be in \[0, 1\)'):
        frame_to_matrix([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], tol=tol)
    with pytest.raises(RotationError, match=r'^lock_tol must be in \[0, π/4\) rad'):
        matrix_to_euler(np.eye(3), lock_tol=tol)
