"""rot-tools hand-eye: files and bags in, the report, --yaml, the warning, bad input."""

import json
import math
from pathlib import Path

import bag_helpers as bh
from conftest import one_error, run_cli
from doc_blocks import assert_doc_output, console_steps, doc_block
from hand_eye_helpers import (
    arm_stations, arm_streams, eye_to_hand, flipped, inverted, mobile_base, rotation_error,
    write_tum)
import numpy as np
import pytest
from rot_tools import hand_eye
from scipy.spatial.transform import Rotation
import yaml


def eye_in_hand_files(directory, recording):
    """Write hand.tum (the hand in the base) and marker.tum (the marker in the camera)."""
    r = recording
    hand = write_tum(Path(directory) / 'hand.tum', r.stamps_a, r.R_a, r.b_a)
    marker = write_tum(Path(directory) / 'marker.tum', r.stamps_b, *inverted(r.R_b, r.b_b))
    return hand, marker


def test_json_report_holds_x_z_and_their_uncertainty(capsys, tmp_path):
    recording = arm_stations(0)
    hand, marker = eye_in_hand_files(tmp_path, recording)
    status, out, err = run_cli(capsys, 'hand-eye', hand, marker, '--invert-b', '--json')
    assert status == 0 and err == ''
    report = json.loads(out)
    for key in ('offset', 'pairs', 'rejected', 'X', 'Z', 'residual', 'sigma', 'unobservable',
                'static_transform_publisher'):
        assert key in report
    X = report['X']
    R = Rotation.from_quat(X['quaternion']).as_matrix()
    assert np.allclose(R, X['matrix'], atol=1e-11)
    assert math.degrees(rotation_error(R, recording.X[0])) < 0.1
    assert np.allclose(X['translation'], recording.X[1], atol=1e-3)
    assert report['pairs'] == 300 and report['rejected'] == [] and report['unobservable'] == []
    assert len(report['sigma']['rotation']) == 3 and len(report['sigma']['translation']) == 3
    for key in ('axis_angle', 'rpy', 'euler', 'screw', 'homogeneous'):
        assert key in X and key in report['Z']


def test_the_command_reports_what_the_library_finds(capsys, tmp_path):
    recording = arm_stations(1)
    hand, marker = eye_in_hand_files(tmp_path, recording)
    report = json.loads(run_cli(capsys, 'hand-eye', hand, marker, '--invert-b', '--json',
                                '--precision', 15)[1])
    r = recording
    found = hand_eye(r.stamps_a, r.R_a, r.b_a, r.stamps_b, r.R_b, r.b_b)
    assert np.allclose(report['X']['translation'], found.X.b, atol=1e-8)
    assert np.allclose(report['sigma']['rotation'], found.sigma.rotation, rtol=1e-6)
    residual = report['residual']['translation']
    assert residual == pytest.approx(found.residual.translation, rel=1e-6)


def test_deg_gives_the_angles_in_degrees(capsys, tmp_path):
    hand, marker = eye_in_hand_files(tmp_path, arm_stations(2))
    rad = json.loads(run_cli(capsys, 'hand-eye', hand, marker, '--invert-b', '--json')[1])
    deg = json.loads(run_cli(capsys, 'hand-eye', hand, marker, '--invert-b', '--json', '--deg')[1])
    assert deg['unit'] == 'deg' and rad['unit'] == 'rad'
    assert np.allclose(deg['sigma']['rotation'], np.degrees(rad['sigma']['rotation']),
                       rtol=1e-9)
    assert deg['residual']['rotation'] == pytest.approx(
        math.degrees(rad['residual']['rotation']), rel=1e-9)
    assert deg['sigma']['translation'] == rad['sigma']['translation']


def test_inverting_b_is_reading_the_camera_in_the_marker(capsys, tmp_path):
    recording = arm_stations(3)
    hand, marker = eye_in_hand_files(tmp_path, recording)
    camera = write_tum(tmp_path / 'camera.tum', recording.stamps_b, recording.R_b,
                       recording.b_b)
    inverted_b = json.loads(run_cli(capsys, 'hand-eye', hand, marker, '--invert-b', '--json')[1])
    direct = json.loads(run_cli(capsys, 'hand-eye', hand, camera, '--json')[1])
    assert np.allclose(inverted_b['X']['matrix'], direct['X']['matrix'], atol=1e-9)
    assert np.allclose(inverted_b['X']['translation'], direct['X']['translation'], atol=1e-9)


def test_a_mobile_base_says_what_it_cannot_tell_in_one_warning(capsys, tmp_path):
    r = mobile_base(1)
    odom = write_tum(tmp_path / 'odom.tum', r.stamps_a, r.R_a, r.b_a)
    vo = write_tum(tmp_path / 'vo.tum', r.stamps_b, r.R_b, r.b_b)
    status, out, err = run_cli(capsys, 'hand-eye', odom, vo, '--json')
    report = json.loads(out)
    assert status == 0
    assert err == ("warning: X's translation along [0, 0, 1] (in A) is unobservable: the "
                   'motion turns about that axis only; it is set to 0\n')
    assert np.allclose(report['unobservable'], [[0.0, 0.0, 1.0]], atol=1e-9)
    assert report['sigma']['translation'][2] == 'inf'
    assert report['X']['translation'][2] == 0.0


def test_yaml_writes_x_as_the_static_transform_nodes_parameters(capsys, tmp_path):
    recording = arm_stations(4)
    hand, marker = eye_in_hand_files(tmp_path, recording)
    status, out, err = run_cli(capsys, 'hand-eye', hand, marker, '--invert-b', '--json', '--yaml',
                               tmp_path / 'x.yaml')
    assert status == 0
    params = yaml.safe_load((tmp_path / 'x.yaml').read_text())['/**']['ros__parameters']
    X = json.loads(out)['X']
    assert params['frame_id'] == 'body_a' and params['child_frame_id'] == 'body_b'
    assert np.allclose([params['translation'][k] for k in 'xyz'], X['translation'], atol=1e-12)
    q = [params['rotation'][k] for k in 'xyzw']
    assert np.allclose(Rotation.from_quat(q).as_matrix(), X['matrix'], atol=1e-12)
    line = json.loads(out)['static_transform_publisher']
    assert line in (tmp_path / 'x.yaml').read_text()


def test_yaml_over_an_input_is_refused(capsys, tmp_path):
    hand, marker = eye_in_hand_files(tmp_path, arm_stations(0))
    before = hand.read_bytes()
    one_error(capsys, 'hand-eye', hand, marker, '--yaml', hand,
              contains='would overwrite an input')
    assert hand.read_bytes() == before


def test_streams_with_offset_auto_report_it_and_its_correlation(capsys, tmp_path):
    r = arm_streams(2, seconds=20.0)
    hand = write_tum(tmp_path / 'hand.tum', r.stamps_a, r.R_a, r.b_a)
    camera = write_tum(tmp_path / 'camera.tum', r.stamps_b, r.R_b, r.b_b)
    report = json.loads(run_cli(capsys, 'hand-eye', hand, camera, '--offset', 'auto', '--json')[1])
    assert report['offset'] == pytest.approx(0.12, abs=0.005)
    assert report['offset_correlation'] > 0.9


def tf_bag(path, recording):
    """Write a rosbag2 bag of both streams on /tf: base → tool0 (A), camera → marker (B)."""
    b = bh.Builder()
    r = recording
    R_m, t_m = inverted(r.R_b, r.b_b)
    q_a, q_m = Rotation.from_matrix(r.R_a).as_quat(), Rotation.from_matrix(R_m).as_quat()
    messages = []
    for k, stamp in enumerate(r.stamps_a):
        ns = int(round(stamp * 1e9)) + 1000
        messages.append(('/tf', 'tf2_msgs/msg/TFMessage', ns, b.tf_message([
            b.transform_stamped(stamp, r.b_a[k], q_a[k], 'base', 'tool0'),
            b.transform_stamped(stamp, t_m[k], q_m[k], 'camera', 'marker')])))
    return bh.write_bag(path, messages)


def test_poses_on_tf_in_a_bag_give_the_x_of_the_files(capsys, tmp_path):
    pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
    recording = arm_stations(5)
    hand, marker = eye_in_hand_files(tmp_path, recording)
    bag = tf_bag(tmp_path / 'calibration', recording)
    files = json.loads(run_cli(capsys, 'hand-eye', hand, marker, '--invert-b', '--json')[1])
    status, out, err = run_cli(capsys, 'hand-eye', bag, bag, '--a-tf', 'base', 'tool0', '--b-tf',
                               'camera', 'marker', '--invert-b', '--json')
    assert status == 0 and err == ''
    from_bag = json.loads(out)
    assert np.allclose(from_bag['X']['matrix'], files['X']['matrix'], atol=1e-8)
    assert np.allclose(from_bag['X']['translation'], files['X']['translation'], atol=1e-8)
    assert from_bag['static_transform_publisher'].endswith(
        '--frame-id tool0 --child-frame-id camera')


def bad_inputs(tmp_path):
    r = arm_stations(0)
    hand, marker = eye_in_hand_files(tmp_path, r)
    late = write_tum(tmp_path / 'late.tum', r.stamps_b + 100.0, *inverted(r.R_b, r.b_b))
    two = write_tum(tmp_path / 'two.tum', r.stamps_b[:2], *inverted(r.R_b[:2], r.b_b[:2]))
    still = write_tum(tmp_path / 'still.tum', r.stamps_a, np.repeat(r.R_a[:1], 25, axis=0),
                      r.b_a)
    return {
        'no overlap': (('hand-eye', hand, late, '--invert-b'), 'no overlap in time: A spans'),
        'two samples': (('hand-eye', hand, two, '--invert-b'),
                        '2 sample(s) of A have B within max_gap'),
        'no turn': (('hand-eye', still, marker, '--invert-b'), 'A never turns by min_angle = 5°'),
        'missing file': (('hand-eye', hand, tmp_path / 'nothing.tum'), 'cannot read it'),
        'an option of another command': (('--point', 1, 2, 3, 'hand-eye', hand, marker),
                                         '--point does not apply to hand-eye'),
        'a bad offset': (('hand-eye', hand, marker, '--offset', 'soon'),
                         "expected 'auto' or seconds"),
    }


@pytest.mark.parametrize('case', ['no overlap', 'two samples', 'no turn', 'missing file',
                                  'an option of another command', 'a bad offset'])
def test_bad_input_is_one_line_and_status_2(capsys, tmp_path, case):
    words, said = bad_inputs(tmp_path)[case]
    one_error(capsys, *words, contains=said)


# ---- the worked examples of doc/hand_eye.md ---------------------------------------------------


EXAMPLES = {
    'hand-eye-in-hand': (flipped(arm_stations(7), [5, 12]), 'hand.tum', 'marker.tum', True),
    'hand-eye-to-hand': (eye_to_hand(8), 'gripper.tum', 'marker_in_camera.tum', False),
    'hand-eye-base': (mobile_base(9), 'odom.tum', 'vo.tum', False),
}
"""The doc's examples: the recording, the files it is written to, B inverted in its file."""


@pytest.mark.parametrize('tag', sorted(EXAMPLES))
def test_doc_example_is_real_output_and_near_the_truth(capsys, tmp_path, monkeypatch, tag):
    r, name_a, name_b, invert = EXAMPLES[tag]
    write_tum(tmp_path / name_a, r.stamps_a, r.R_a, r.b_a)
    write_tum(tmp_path / name_b, r.stamps_b, *(inverted(r.R_b, r.b_b) if invert else
                                               (r.R_b, r.b_b)))
    monkeypatch.chdir(tmp_path)
    (command, _), = console_steps(doc_block(tag))
    words = command.split()
    assert words[:4] == ['rot-tools', 'hand-eye', name_a, name_b]
    status, out, err = run_cli(capsys, *words[1:])
    assert status == 0, err
    assert_doc_output(tag, f'$ {command}\n{out}{err}')  # ROT_TOOLS_UPDATE_DOCS=1 rewrites it
    report = yaml.safe_load(out)
    hidden = np.abs(np.reshape(report['unobservable'], (-1, 3))).sum(axis=0) > 0.5
    assert rotation_error(np.array(report['X']['matrix']), r.X[0]) < math.radians(0.3)
    assert np.allclose(np.array(report['X']['translation'])[~hidden], r.X[1][~hidden],
                       atol=0.01)
