"""
The Rodrigues (Gibbs) vector g = tan(θ/2)·l̂: library, ``rot-tools rodrigues``, the report.

Cross-checked against scipy's rotation vector and matrices; at θ = π g is refused.
"""

import math
import re

import numpy as np
import pytest
from rot_tools import (matrix_to_rodrigues, quaternion_to_matrix, rodrigues_to_matrix, rot_x,
                       rot_z, RotationError)
from rot_tools.core.axis_angle import quaternion_to_rodrigues, rodrigues_of_one
from scipy.spatial.transform import Rotation
import yaml

RNG = np.random.default_rng(20261207)
EPS = np.finfo(float).eps


def scipy_rodrigues(R):
    """Return g = tan(θ/2)·axis from scipy's rotation vector θ·axis."""
    rotvec = Rotation.from_matrix(R).as_rotvec()
    angle = np.linalg.norm(rotvec, axis=-1, keepdims=True)
    return np.where(angle > 0, np.tan(angle / 2) * rotvec / np.where(angle > 0, angle, 1), 0.0)


def test_a_quarter_turn_about_z_is_the_unit_z():
    np.testing.assert_allclose(matrix_to_rodrigues(rot_z(math.pi / 2)), [0.0, 0.0, 1.0],
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(rodrigues_to_matrix([0.0, 0.0, 1.0]), rot_z(math.pi / 2),
                               rtol=0, atol=1e-15)


def test_random_rotations_match_scipy():
    R = Rotation.random(1000, random_state=7).as_matrix()
    g = matrix_to_rodrigues(R)
    assert g.shape == (1000, 3)
    np.testing.assert_allclose(g, scipy_rodrigues(R), rtol=1e-9, atol=1e-12)


def test_random_vectors_give_scipys_matrices():
    g = RNG.normal(size=(1000, 3)) * np.exp(RNG.uniform(-20, 20, size=(1000, 1)))
    norm = np.linalg.norm(g, axis=1, keepdims=True)
    rotvec = 2.0 * np.arctan(norm) * g / norm  # θ = 2·atan|g| about g/|g|
    np.testing.assert_allclose(rodrigues_to_matrix(g), Rotation.from_rotvec(rotvec).as_matrix(),
                               rtol=0, atol=1e-13)


@pytest.mark.parametrize('angle', [0.0, 1e-300, 1e-12, 1e-6, 0.5, 2.0, math.pi - 1e-3,
                                   math.pi - 1e-6, math.pi - 1e-9])
def test_matrix_round_trips_near_zero_and_near_pi(angle):
    axis = np.array([0.3, -0.4, 0.866])
    axis /= np.linalg.norm(axis)
    R = Rotation.from_rotvec(angle * axis).as_matrix()
    g = matrix_to_rodrigues(R)
    np.testing.assert_allclose(rodrigues_to_matrix(g), R, rtol=0, atol=1e-14)
    # R's entries hold cos(θ/2) = w to their rounding only: g relative ~ ε/(π − θ).
    np.testing.assert_allclose(g, math.tan(angle / 2) * axis,
                               rtol=8 * EPS / (math.pi - angle) + 1e-14, atol=1e-300)


@pytest.mark.parametrize('size', [0.0, 1e-300, 1e-8, 1.0, 1e8, 1e15])
def test_vector_round_trips_from_tiny_to_huge(size):
    direction = np.array([-2.0, 1.0, 0.5]) / math.sqrt(5.25)
    g = size * direction
    back = matrix_to_rodrigues(rodrigues_to_matrix(g))
    # Near π the matrix holds w = 1/√(1 + |g|²) to its rounding only: |g| relative ~ ε|g|.
    np.testing.assert_allclose(back, g, rtol=10 * EPS * (1 + size), atol=1e-300)


def test_a_vector_beyond_float_precision_is_the_half_turn():
    direction = np.array([-2.0, 1.0, 0.5]) / math.sqrt(5.25)
    np.testing.assert_allclose(rodrigues_to_matrix(1e300 * direction),
                               Rotation.from_rotvec(math.pi * direction).as_matrix(),
                               rtol=0, atol=1e-15)


@pytest.mark.parametrize('R', [np.diag([1.0, -1.0, -1.0]),
                               quaternion_to_matrix([0.6, 0.0, 0.8, 0.0])],
                         ids=['about_x', 'oblique'])
def test_a_half_turn_has_no_rodrigues_vector(R):
    with pytest.raises(RotationError, match=r'infinite at θ = π'):
        matrix_to_rodrigues(R)


def test_a_half_turn_in_a_batch_is_named():
    R = np.stack([np.eye(3), rot_x(0.5), np.diag([-1.0, 1.0, -1.0])])
    with pytest.raises(RotationError, match=r'infinite at θ = π \(quaternion w = 0\) \(item \(2,'):
        matrix_to_rodrigues(R)


@pytest.mark.parametrize('g', [(math.inf, 0.0, 0.0), (0.0, math.nan, 1.0)])
def test_a_non_finite_vector_is_refused(g):
    with pytest.raises(RotationError, match='Rodrigues vector g must be finite'):
        rodrigues_to_matrix(g)


def test_the_one_item_path_is_the_batch_formula():
    q = RNG.normal(size=(1000, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    q[:10, 3] = [0.0, -0.0, 1e-300, -1e-300, 1e-17, 1.0, -1.0, 1e-8, -1e-10, 0.5]
    for item, batch in zip(q[2:], quaternion_to_rodrigues(q[2:])):
        assert list(rodrigues_of_one(*map(float, item))) == batch.tolist()
    for item in q[:2]:
        with pytest.raises(RotationError, match='infinite at θ = π'):
            rodrigues_of_one(*map(float, item))


def _a_hair_from_a_half_turn(w):
    """Return the rotation about z with quaternion (0, 0, 1, w): θ = π − 2·asin(w)."""
    R = np.diag([-1.0, -1.0, 1.0])
    R[1, 0], R[0, 1] = 2.0 * w, -2.0 * w
    return R


def test_a_rotation_whose_vector_overflows_float64_is_refused_with_its_distance_from_pi():
    # w = 5e-311: g = (0, 0, 1/w) = 2e310 is beyond float64, not inf; w = 1e-300: finite.
    message = ('the Rodrigues vector tan(θ/2)·l̂ overflows float64 (beyond ±1.8e308): θ is '
               '1e-310 rad from π (quaternion w = 5e-311)')
    R = _a_hair_from_a_half_turn(5e-311)
    with pytest.raises(RotationError, match=re.escape(message) + '$'):
        matrix_to_rodrigues(R)
    with pytest.raises(RotationError, match=re.escape(message + ' (item (1,))') + '$'):
        matrix_to_rodrigues(np.stack([np.eye(3), R]))
    with pytest.raises(RotationError, match=re.escape(message) + '$'):
        rodrigues_of_one(0.0, 0.0, 1.0, 5e-311)
    np.testing.assert_allclose(matrix_to_rodrigues(_a_hair_from_a_half_turn(1e-300)),
                               [0.0, 0.0, 1e300], rtol=4 * EPS, atol=0)


def test_a_non_rotation_is_refused():
    with pytest.raises(RotationError):
        matrix_to_rodrigues(np.diag([1.0, 1.0, -1.0]))


# rot-tools rodrigues and the report


def test_rot_tools_rodrigues_prints_every_representation():
    from test_cli import run
    done = run('rodrigues', '0', '0', '1', '--deg')
    assert (done.returncode, done.stderr) == (0, '')
    report = yaml.safe_load(done.stdout)
    assert report['rodrigues'] == [0.0, 0.0, 1.0]
    assert report['axis_angle']['angle_deg'] == 90.0
    assert report['euler']['angles'] == [90.0, 0.0, 0.0]
    assert report['quaternion']['w'] == pytest.approx(math.sqrt(0.5), abs=1e-12)


def test_rot_tools_rodrigues_refuses_a_non_finite_vector():
    from test_cli import run
    done = run('rodrigues', '0', 'inf', '0')
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1


def test_the_report_of_a_half_turn_has_no_rodrigues_vector():
    from test_cli import run
    done = run('quaternion', '1', '0', '0', '0')
    assert yaml.safe_load(done.stdout)['rodrigues'] is None
