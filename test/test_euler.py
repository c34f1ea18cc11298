"""Euler angles: all 24 sequence names against explicit elementary-rotation products."""

import re

from hypothesis import given, settings, strategies as st
import math_helpers as h
import numpy as np
import pytest
from rot_tools import (
    EULER_SEQUENCES, euler_to_matrix, GIMBAL_LOCK_TOL, matrix_to_euler, RotationError)

N = 10_000
PI = h.PI
LOCK_OFFSETS = (0.0, 1e-9, -1e-9, 1e-7, -1e-7, 1e-5, -1e-5)


def roundtrip_tolerance(distance, degenerate):
    """1e-12, and about twice the distance to the lock when flagged."""
    return np.where(degenerate, 2.0 * np.abs(distance) + 1e-12, 1e-12)


def lock_distance(angles, seq):
    """Distance of the middle angle to the nearest singular value."""
    return np.min([np.abs(angles[..., 1] - v) for v in h.singular_values(seq)], axis=0)


def input_lock_distance(middle, seq):
    """Distance to gimbal lock of the rotation with middle angle `middle` (any value)."""
    middle = np.asarray(middle, dtype=float)
    if seq.upper() in h.TAIT_BRYAN:
        return np.arcsin(np.abs(np.cos(middle)))
    return np.arcsin(np.abs(np.sin(middle)))


def assert_canonical(angles, seq):
    lo, hi = h.middle_range(seq)
    assert np.all(angles[..., 0] > -PI) and np.all(angles[..., 0] <= PI)
    assert np.all(angles[..., 2] > -PI) and np.all(angles[..., 2] <= PI)
    assert np.all(angles[..., 1] >= lo) and np.all(angles[..., 1] <= hi)


def test_sequence_names():
    assert len(EULER_SEQUENCES) == 24
    assert set(EULER_SEQUENCES) == set(h.ALL_SEQUENCES)


def test_gimbal_lock_tolerance_is_documented_and_small():
    assert 0.0 < GIMBAL_LOCK_TOL <= 1e-6


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_euler_to_matrix_is_the_product_of_elementary_rotations(seq):
    rng = np.random.default_rng(10)
    angles = rng.uniform(-2 * PI, 2 * PI, size=(N, 3))
    got = euler_to_matrix(angles, seq)
    assert got.shape == (N, 3, 3)
    assert h.max_abs(got - h.ref_euler(angles, seq)) <= 1e-14


def test_intrinsic_and_extrinsic_are_reversed_products():
    # 'xyz' (fixed axes) == 'ZYX' (moving axes) with the angles reversed (scipy's naming).
    a = np.array([0.3, -0.7, 1.9])
    assert h.max_abs(euler_to_matrix(a, 'xyz') - euler_to_matrix(a[::-1], 'ZYX')) <= 1e-15
    expected = h.ref_elementary('z', 1.9) @ h.ref_elementary('y', -0.7) @ h.ref_elementary(
        'x', 0.3)
    assert h.max_abs(euler_to_matrix(a, 'xyz') - expected) <= 1e-15
    assert h.max_abs(euler_to_matrix(a, 'XYZ') - expected) > 0.1


def test_default_sequence_is_zyx():
    a = np.array([0.3, -0.7, 1.9])
    assert np.array_equal(euler_to_matrix(a), euler_to_matrix(a, 'ZYX'))
    r = h.ref_euler(a, 'ZYX')
    assert np.array_equal(matrix_to_euler(r)[0], matrix_to_euler(r, 'ZYX')[0])


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_matrix_to_euler_round_trip_on_random_rotations(seq):
    # Rotations drawn from axis-angle (independent of any Euler code).
    rng = np.random.default_rng(11)
    _, _, r = h.random_axis_angle(rng, N)
    angles, degenerate = matrix_to_euler(r, seq)
    assert angles.shape == (N, 3) and degenerate.shape == (N,)
    assert degenerate.dtype == np.bool_
    assert_canonical(angles, seq)
    assert not degenerate.any()      # none of these 10,000 is within 1e-6 rad of the lock
    assert h.max_abs(h.ref_euler(angles, seq) - r) <= 1e-12


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_matrix_to_euler_recovers_the_constructing_angles(seq):
    rng = np.random.default_rng(12)
    angles = h.random_euler_angles(rng, N, seq)
    keep = lock_distance(angles, seq) > 1e-3      # away from the lock the angles are unique
    angles = angles[keep]
    got, degenerate = matrix_to_euler(h.ref_euler(angles, seq), seq)
    assert not degenerate.any()
    assert h.max_abs(got[:, 1] - angles[:, 1]) <= 1e-12
    assert h.angle_error(got[:, 0], angles[:, 0]) <= 1e-12
    assert h.angle_error(got[:, 2], angles[:, 2]) <= 1e-12


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_gimbal_lock_and_near_lock(seq):
    rng = np.random.default_rng(13)
    n = 40
    for lock in h.singular_values(seq):
        for offset in LOCK_OFFSETS:
            angles = np.stack([rng.uniform(-PI, PI, n), np.full(n, lock + offset),
                               rng.uniform(-PI, PI, n)], axis=-1)
            angles[:4, 0] = [0.0, PI, -PI, PI / 2]
            angles[:4, 2] = [0.0, PI, PI / 2, -PI]
            r = h.ref_euler(angles, seq)
            got, degenerate = matrix_to_euler(r, seq)
            assert_canonical(got, seq)
            expect_flag = abs(offset) <= GIMBAL_LOCK_TOL
            assert np.all(degenerate == expect_flag), (lock, offset)
            if expect_flag:
                assert np.all(got[:, 2] == 0.0)
                assert np.all(lock_distance(got, seq) <= GIMBAL_LOCK_TOL)
            err = np.abs(h.ref_euler(got, seq) - r).max(axis=(-1, -2))
            tol = 2.0 * abs(offset) + 1e-12 if expect_flag else 1e-12
            assert err.max() <= tol, (lock, offset, err.max())


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_exact_lock_free_angle_goes_to_theta1(seq):
    # At the lock only theta1 (+/-) theta3 is defined; with theta3 = 0, theta1 must be it.
    for lock in h.singular_values(seq):
        for t1 in (0.4, -2.5, PI):
            r = h.ref_euler([t1, lock, 0.0], seq)
            got, degenerate = matrix_to_euler(r, seq)
            assert degenerate
            assert got[2] == 0.0
            assert h.angle_error(got[0], t1) <= 1e-12
            assert abs(got[1] - lock) <= 1e-12


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_single_items_match_the_batch(seq):
    # A single item may take another code path than a batch; both must agree, at the lock too.
    rng = np.random.default_rng(15)
    rows = []
    for lock in h.singular_values(seq):
        for offset in LOCK_OFFSETS:
            for t1, t3 in ((0.0, 0.0), (PI, PI), (-PI, 0.5), (rng.uniform(-PI, PI), 2.0)):
                rows.append((t1, lock + offset, t3))
    angles = np.concatenate([np.array(rows), h.random_euler_angles(rng, 50, seq)])
    cube = h.cube_rotations()
    r = np.concatenate([h.ref_euler(angles, seq), cube, np.where(cube == 0, -0.0, cube)])
    batch, flags = matrix_to_euler(r, seq)
    batch_matrix = euler_to_matrix(angles, seq)
    for i in range(len(r)):
        one, flag = matrix_to_euler(r[i], seq)
        assert flag == flags[i], i
        assert h.angle_error(one, batch[i]) <= 1e-15 * 8, i
        if i < len(angles):
            assert h.max_abs(euler_to_matrix(angles[i], seq) - batch_matrix[i]) <= 1e-15 * 4


def test_batches_larger_than_one_chunk():
    rng = np.random.default_rng(16)
    angles = h.random_euler_angles(rng, 70_000, 'yxy')
    r = h.ref_euler(angles, 'yxy')
    assert h.max_abs(euler_to_matrix(angles, 'yxy') - r) <= 1e-14
    got, degenerate = matrix_to_euler(r, 'yxy')
    assert not degenerate.any()
    assert h.max_abs(h.ref_euler(got, 'yxy') - r) <= 1e-12


def test_lock_tolerance_keyword():
    r = h.ref_euler([0.3, PI / 2 - 1e-5, 0.2], 'ZYX')
    assert not matrix_to_euler(r, 'ZYX')[1]
    angles, degenerate = matrix_to_euler(r, 'ZYX', lock_tol=1e-4)
    assert degenerate and angles[2] == 0.0
    assert h.max_abs(h.ref_euler(angles, 'ZYX') - r) <= 2e-5 + 1e-12


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_minus_pi_is_reported_as_plus_pi(seq):
    # Build R with theta1 = theta3 = pi, once with +0.0 and once with -0.0 in the zero entries:
    # atan2(-0.0, -1) is -pi, which the contract reports as +pi.
    mid = 0.6 if seq.upper() in h.TAIT_BRYAN else 1.1
    for t1, t3 in ((PI, PI), (-PI, -PI), (PI, 0.3), (0.3, -PI)):
        r = h.ref_euler([t1, mid, t3], seq)
        for rr in (r, np.where(np.abs(r) < 1e-15, -0.0, r), np.where(np.abs(r) < 1e-15, 0.0, r)):
            got, degenerate = matrix_to_euler(rr, seq)
            assert not degenerate
            assert_canonical(got, seq)
            assert h.max_abs(h.ref_euler(got, seq) - rr) <= 1e-12


def expected_cube_lock(r, seq):
    """Independent lock test for exact matrices: the entry that is +/-sin or cos of theta2."""
    i1, i3 = 'xyz'.index(seq[0].lower()), 'xyz'.index(seq[2].lower())
    if seq.upper() in h.PROPER:
        return np.abs(r[..., i1, i1]) == 1.0
    if seq.isupper():
        return np.abs(r[..., i1, i3]) == 1.0
    return np.abs(r[..., i3, i1]) == 1.0


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_the_24_cube_rotations(seq):
    # Exact 0 / +-1 entries (with +0.0 and with -0.0): locks, half turns and +-pi boundaries.
    cube = h.cube_rotations()
    for r in (cube, np.where(cube == 0, -0.0, cube), cube + 0.0):
        got, degenerate = matrix_to_euler(r, seq)
        assert_canonical(got, seq)
        assert np.array_equal(degenerate, expected_cube_lock(r, seq))
        assert np.all(got[degenerate, 2] == 0.0)
        assert h.max_abs(h.ref_euler(got, seq) - r) <= 1e-15 * 4


def test_pitch_range_zyx_includes_negative_pitch():
    got, _ = matrix_to_euler(h.ref_elementary('y', -0.5), 'ZYX')
    assert h.max_abs(got - [0.0, -0.5, 0.0]) <= 1e-15


@pytest.mark.parametrize('seq', [None, 123, ('Z', 'Y', 'X'), ['Z', 'Y', 'X'], 'zyX', b'ZYX'])
def test_matrix_to_euler_refuses_other_sequences_on_every_path(seq):
    # One plain rotation reads the sequence's table itself (no call): an unhashable name or
    # one not in it must still be refused as parse_sequence refuses it, and a batch too.
    for R in (np.eye(3), np.eye(3)[None], np.eye(3).tolist()):
        with pytest.raises(RotationError, match=r'unknown Euler sequence ' + re.escape(repr(seq))):
            matrix_to_euler(R, seq)


def test_single_and_batch_shapes():
    rng = np.random.default_rng(14)
    angles = h.random_euler_angles(rng, 20, 'XYZ').reshape(4, 5, 3)
    r = euler_to_matrix(angles, 'XYZ')
    assert r.shape == (4, 5, 3, 3)
    got, degenerate = matrix_to_euler(r, 'XYZ')
    assert got.shape == (4, 5, 3) and degenerate.shape == (4, 5)
    single, flag = matrix_to_euler(r[2, 3], 'XYZ')
    assert single.shape == (3,) and np.ndim(flag) == 0
    assert isinstance(flag, (bool, np.bool_))
    assert h.max_abs(single - got[2, 3]) <= 1e-15
    assert euler_to_matrix([0.1, 0.2, 0.3]).shape == (3, 3)
    assert euler_to_matrix(np.zeros((0, 3))).shape == (0, 3, 3)


def test_check_false_uses_the_matrix_as_given():
    # ZYX (i, j, k) = (z, y, x): θ1 = atan2(r21, r11) and θ2 = atan2(−r31, hypot(r11, r21))
    # read the matrix as given (entries as printed in Jia eq. 1); θ3 is peeled from
    # Rot_z(θ1)ᵀ·R and stays within the perturbation of the true roll.
    r = h.ref_euler([0.1, 0.2, 0.3], 'ZYX')
    r[0, 0] += 1e-6
    with pytest.raises(RotationError, match='not orthogonal'):
        matrix_to_euler(r, 'ZYX')
    angles, degenerate = matrix_to_euler(r, 'ZYX', check=False)
    assert not degenerate
    assert abs(angles[0] - np.arctan2(r[1, 0], r[0, 0])) <= 1e-16
    assert abs(angles[1] - np.arctan2(-r[2, 0], np.hypot(r[0, 0], r[1, 0]))) <= 1e-16
    assert abs(angles[2] - 0.3) <= 2e-6
    assert h.max_abs(angles - [0.1, 0.2, 0.3]) > 1e-8  # the perturbation was not projected


@pytest.mark.parametrize('seq', h.ALL_SEQUENCES)
def test_lock_tolerance_zero(seq):
    # lock_tol = 0 is allowed and flags only an exact lock (distance 0 ≤ 0): the cube
    # rotations at lock are flagged, and 1e-9 rad away nothing is.
    cube = h.cube_rotations()
    expected = expected_cube_lock(cube, seq)
    angles, degenerate = matrix_to_euler(cube, seq, lock_tol=0.0)
    assert expected.any() and np.array_equal(degenerate, expected)
    assert np.all(angles[degenerate, 2] == 0.0)
    for value in h.singular_values(seq):
        near = h.ref_euler([[0.3, value + 1e-9, -0.2], [0.3, value - 1e-9, -0.2]], seq)
        _, flags = matrix_to_euler(near, seq, lock_tol=0.0)
        assert not flags.any()
        _, flags = matrix_to_euler(near, seq, lock_tol=2e-9)
        assert flags.all()


@settings(**h.HYPOTHESIS_SETTINGS)
@given(seq=st.sampled_from(h.ALL_SEQUENCES),
       angles=st.tuples(h.angles_in(-7.0, 7.0), h.angles_in(-7.0, 7.0), h.angles_in(-7.0, 7.0)))
def test_round_trip_property(seq, angles):
    r = h.ref_euler(np.array(angles), seq)
    got, degenerate = matrix_to_euler(r, seq)
    assert_canonical(got, seq)
    tol = roundtrip_tolerance(input_lock_distance(angles[1], seq), degenerate)
    assert h.max_abs(euler_to_matrix(got, seq) - r) <= tol
