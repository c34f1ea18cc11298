"""ViSP's eye-in-hand tutorial: rot-tools hand-eye agrees within its reported uncertainty."""

import json
from pathlib import Path

import numpy as np
from rot_tools.cli import main as cli
from scipy.spatial.transform import Rotation

DATA = Path(__file__).resolve().parent / 'data' / 'visp_hand_eye'

PUBLISHED = {'translation': [0.05345567035, -0.009516983454, -0.04510223842],
             'theta_u': [-0.0234728216, -0.07938837693, 1.574587196]}
"""eMc as ViSP's tutorial (tutorial-calibration-extrinsic) prints it: metres, θu in rad."""


def calibration(capsys):
    status = cli.main(['hand-eye', str(DATA / 'flange_in_base.tum'),
                       str(DATA / 'chessboard_in_camera.tum'), '--invert-b', '--json',
                       '--precision', '15'])
    out, err = capsys.readouterr()
    assert status == 0 and err == ''
    return json.loads(out)


def test_every_station_of_the_real_recording_is_consistent(capsys):
    report = calibration(capsys)
    assert report['samples'] == 8 and report['pairs'] == 28 and report['rejected'] == []


def test_the_real_recording_gives_the_published_x_within_three_sigma(capsys):
    report = calibration(capsys)
    sigma = report['sigma']
    translation = np.array(report['X']['translation']) - PUBLISHED['translation']
    assert np.all(np.abs(translation) <= 3 * np.array(sigma['translation'])), translation
    published = Rotation.from_rotvec(PUBLISHED['theta_u']).as_matrix()
    turn = Rotation.from_matrix(published @ np.array(report['X']['matrix']).T).as_rotvec()
    assert np.all(np.abs(turn) <= 3 * np.array(sigma['rotation'])), turn
