"""hand_eye and screw_congruence on simulated recordings, and against OpenCV's methods."""

import math

from hand_eye_helpers import (
    arm_stations, arm_streams, flipped, inverted, mobile_base, random_mounting,
    rotation_error)
import numpy as np
import pytest
from rot_tools import hand_eye, RotationError, screw_congruence
from rot_tools.core.hand_eye import NEAR_HALF_TURN
from scipy.spatial.transform import Rotation


def _calibrate(recording, **options):
    r = recording
    return hand_eye(r.stamps_a, r.R_a, r.b_a, r.stamps_b, r.R_b, r.b_b, **options)


def _errors(found, recording):
    """Return X's rotation error (degrees) and translation error (m)."""
    return (math.degrees(rotation_error(found.X.R, recording.X[0])),
            float(np.linalg.norm(found.X.b - recording.X[1])))


def test_noise_free_motion_gives_x_and_z_exactly():
    recording = arm_stations(3, noise_deg=0.0, noise_m=0.0)
    found = _calibrate(recording)
    assert rotation_error(found.X.R, recording.X[0]) < 1e-9
    assert np.allclose(found.X.b, recording.X[1], atol=1e-9)
    assert rotation_error(found.Z.R, recording.Z[0]) < 1e-9
    assert np.allclose(found.Z.b, recording.Z[1], atol=1e-9)
    assert found.rejected == () and found.samples == 25 and found.pairs == 300


def test_arm_at_stations_is_at_least_as_exact_as_each_of_opencvs_methods():
    cv2 = pytest.importorskip('cv2')
    methods = {name: getattr(cv2, f'CALIB_HAND_EYE_{name}')
               for name in ('TSAI', 'PARK', 'HORAUD', 'ANDREFF', 'DANIILIDIS')}
    ours, theirs = [], {name: [] for name in methods}
    for seed in range(10):
        recording = arm_stations(seed)
        ours.append(_errors(_calibrate(recording), recording))
        R_marker, t_marker = inverted(recording.R_b, recording.b_b)  # target2cam
        for name, method in methods.items():
            R, t = cv2.calibrateHandEye(list(recording.R_a), list(recording.b_a),
                                        list(R_marker), list(t_marker), method=method)
            rotation = math.degrees(rotation_error(R, recording.X[0]))
            theirs[name].append((rotation, float(np.linalg.norm(t.ravel() - recording.X[1]))))
    mean = np.mean(ours, axis=0)
    best = np.min([np.mean(errors, axis=0) for errors in theirs.values()], axis=0)
    assert mean[0] <= best[0] and mean[1] <= best[1], (mean, theirs)


def test_flipped_detections_are_named_by_stamp_and_left_out():
    recording = flipped(arm_stations(0), [3, 17, 20])
    found = _calibrate(recording)
    assert [r.stamp for r in found.rejected] == [3.0, 17.0, 20.0]
    assert all(r.reason.startswith('its motions differ in A and B by ') for r in found.rejected)
    rotation, translation = _errors(found, recording)
    assert rotation < 0.2 and translation < 2e-3


def test_rejected_samples_leave_the_x_of_a_calibration_without_them():
    recording = flipped(arm_stations(0), [3, 17, 20])
    kept = [k for k in range(25) if k not in (3, 17, 20)]
    clean = _calibrate(recording._replace(
        stamps_a=recording.stamps_a[kept], R_a=recording.R_a[kept], b_a=recording.b_a[kept]))
    found = _calibrate(recording)
    assert rotation_error(found.X.R, clean.X.R) < 1e-12  # the same samples: the same X


def test_mobile_base_names_the_height_unobservable_and_finds_the_rest():
    recording = mobile_base(1)
    found = _calibrate(recording)
    assert math.degrees(rotation_error(found.X.R, recording.X[0])) < 0.3
    assert np.all(np.abs(found.X.b[:2] - recording.X[1][:2]) < 0.01)
    assert found.unobservable.shape == (1, 3)
    assert np.allclose(found.unobservable[0], [0.0, 0.0, 1.0], atol=1e-6)
    assert found.X.b[2] == pytest.approx(0.0, abs=1e-9)
    assert math.isinf(found.sigma.translation[2]) and np.isfinite(found.sigma.rotation).all()


def test_an_arm_turning_about_every_axis_leaves_nothing_unobservable():
    found = _calibrate(arm_stations(2))
    assert found.unobservable.shape == (0, 3) and np.isfinite(found.sigma.translation).all()


def test_streams_at_two_rates_with_an_offset_are_aligned_and_calibrated():
    recording = arm_streams(0, seconds=30.0)
    found = _calibrate(recording, offset='auto')
    assert found.offset == pytest.approx(0.12, abs=0.005)
    rotation, translation = _errors(found, recording)
    assert rotation < 0.2 and translation < 3e-3
    assert found.correlation > 0.9


def test_the_offset_given_by_hand_matches_the_one_found():
    recording = arm_streams(1, seconds=10.0)
    auto = _calibrate(recording, offset='auto')
    given = _calibrate(recording, offset=auto.offset)
    assert given.offset == auto.offset and math.isnan(given.correlation)
    assert rotation_error(given.X.R, auto.X.R) < 1e-12


def test_reported_sigma_is_the_size_of_the_errors_seen():
    normalised = []
    for seed in range(12):
        recording = arm_stations(100 + seed)
        found = _calibrate(recording)
        turn = Rotation.from_matrix(recording.X[0] @ found.X.R.T).as_rotvec()  # in A's axes
        normalised.append(np.concatenate([turn / found.sigma.rotation,
                                          (recording.X[1] - found.X.b) / found.sigma.translation]))
    rms = float(np.sqrt(np.mean(np.square(normalised))))
    assert 0.6 < rms < 1.6, rms


def test_screw_congruence_agrees_with_an_independent_screw_of_each_motion():
    recording = arm_stations(4, noise_deg=0.0, noise_m=0.0)
    c = screw_congruence(recording.R_a, recording.b_a, recording.R_b, recording.b_b)
    i, j = c.pairs[:, 0], c.pairs[:, 1]
    R = np.swapaxes(recording.R_a[i], 1, 2) @ recording.R_a[j]
    t = np.einsum('pji,pj->pi', recording.R_a[i], recording.b_a[j] - recording.b_a[i])
    rotvec = Rotation.from_matrix(R).as_rotvec()
    angle = np.linalg.norm(rotvec, axis=1)
    assert np.allclose(c.angle_a, angle, atol=1e-12)
    along = np.einsum('pi,pi->p', t, rotvec) / angle
    along = np.where(angle > NEAR_HALF_TURN, np.abs(along), along)  # the axis' sign is noise's
    assert np.allclose(c.translation_a, along, atol=1e-12)
    assert np.allclose(c.angle_b, c.angle_a, atol=1e-9)  # A X = X B: one screw, two frames
    assert np.allclose(c.translation_b, c.translation_a, atol=1e-9)


def test_screw_congruence_does_not_depend_on_x():
    recording = arm_stations(5, noise_deg=0.0, noise_m=0.0)
    R_x, b_x = random_mounting(np.random.default_rng(9))
    moved_b = recording.b_b + np.einsum('nij,j->ni', recording.R_b, b_x)  # B·X', another body
    c = screw_congruence(recording.R_a, recording.b_a, recording.R_b @ R_x, moved_b)
    assert np.allclose(c.angle_b, c.angle_a, atol=1e-9)
    assert np.allclose(c.translation_b, c.translation_a, atol=1e-9)


def test_fewer_than_three_matched_samples_are_refused():
    r = arm_stations(0)
    with pytest.raises(RotationError, match=r'2 sample\(s\) of A have B within max_gap'):
        hand_eye(r.stamps_a, r.R_a, r.b_a, r.stamps_b[:2], r.R_b[:2], r.b_b[:2])


def test_streams_that_do_not_overlap_in_time_are_refused():
    r = arm_stations(0)
    with pytest.raises(RotationError, match=r'no overlap in time: A spans \[0.0, 24.0\] s, '
                                            r'B \[100.0, 124.0\] s'):
        hand_eye(r.stamps_a, r.R_a, r.b_a, r.stamps_b + 100.0, r.R_b, r.b_b)


def test_motion_without_a_turn_is_refused():
    r = arm_stations(0)
    still = np.repeat(r.R_a[:1], 25, axis=0)
    with pytest.raises(RotationError, match='A never turns by min_angle = 5°'):
        hand_eye(r.stamps_a, still, r.b_a, r.stamps_b, np.repeat(r.R_b[:1], 25, axis=0), r.b_b)


@pytest.mark.parametrize('scale', [1e-6, 1e150])
def test_positions_in_other_units_up_to_the_reach_scale_x_and_z_alike(scale):
    r = arm_stations(0)
    metres = _calibrate(r)
    found = _calibrate(r._replace(b_a=scale * r.b_a, b_b=scale * r.b_b))
    assert rotation_error(found.X.R, metres.X.R) < 1e-12
    assert np.allclose(found.X.b / scale, metres.X.b, rtol=0, atol=1e-12)
    assert np.allclose(found.Z.b / scale, metres.Z.b, rtol=0, atol=1e-12)


def test_positions_beyond_the_reach_are_refused_saying_how_far():
    r = arm_stations(0)
    far = r.b_b + [0.0, -3e150, 0.0]
    with pytest.raises(RotationError, match=r'^B: positions reach 3e\+150, beyond ±1e\+150, '
                                            r'where .* squared residuals would overflow'):
        hand_eye(r.stamps_a, r.R_a, r.b_a, r.stamps_b, r.R_b, far)


@pytest.mark.parametrize('pairs, shown', [
    ([[0, 1], [2, 1.5]], r'got 1.5 at index \(1, 1\)'), ([[0, 25]], r'got 25.0 at index \(0, 1\)'),
    ([[-1, 3]], r'got -1.0 at index \(0, 0\)')])
def test_pairs_that_are_not_sample_indices_are_refused(pairs, shown):
    r = arm_stations(0)
    with pytest.raises(RotationError, match=r'^pairs must be whole sample indices in \[0, 25\), '
                                            + shown):
        screw_congruence(r.R_a, r.b_a, r.R_b, r.b_b, pairs)


def test_a_turn_about_one_axis_without_translation_across_it_is_refused():
    t = np.arange(10.0)
    R = Rotation.from_rotvec(np.outer(0.3 * t, [0.0, 0.0, 1.0])).as_matrix()
    zero = np.zeros((10, 3))
    with pytest.raises(RotationError, match='the motion does not determine X'):
        hand_eye(t, R, zero, t, R, zero)
