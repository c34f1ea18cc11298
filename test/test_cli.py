"""rot-tools as a user runs it: every command through main, to the printed 12 digits."""

import io
import json
import math
import os
from pathlib import Path
import re
import shutil
import subprocess
import sys
from typing import NamedTuple
import warnings

from conftest import strict_json
import numpy as np
import pytest
import rot_tools
from rot_tools import (
    axis_angle_to_matrix, EULER_SEQUENCES, euler_to_matrix, matrix_to_axis_angle,
    matrix_to_euler, nearest_rotation, rot_x, rot_y, rot_z, screw_from_transform,
    transform_from_screw)
from rot_tools.cli import main as cli
from scipy.spatial.transform import Rotation

PRINTED = {'rtol': 1e-11, 'atol': 1e-11}  # what 12 printed digits allow


def _find_script():
    """Find the installed rot-tools: in this venv's bin, an ament prefix, or on PATH."""
    candidates = [
        Path(sys.executable).parent / 'rot-tools',             # pip install into this venv
        Path(sys.prefix) / 'bin' / 'rot-tools',
        Path(sys.prefix) / 'lib' / 'rot_tools' / 'rot-tools',  # setup.cfg install_scripts
    ]
    # colcon install space: <prefix>/lib/python3.X/site-packages/rot_tools/__init__.py
    parents = Path(rot_tools.__file__).resolve().parents
    if len(parents) > 4:
        candidates.append(parents[4] / 'lib' / 'rot_tools' / 'rot-tools')
    found = [str(c) for c in candidates if c.is_file() and os.access(c, os.X_OK)]
    return found[0] if found else shutil.which('rot-tools')


@pytest.fixture(scope='module')
def script():
    path = _find_script()
    if path is None:
        pytest.fail('the rot-tools console script is not installed next to '
                    f'{sys.executable} nor on PATH: install the package first '
                    "(`pip install .` or the README's test command)")
    return path


class Done(NamedTuple):
    """What a run of rot-tools gave: its exit status and the text of its two streams."""

    returncode: int
    stdout: str
    stderr: str


def run(*args):
    """Run rot-tools on these words as its console script does, its streams swapped for buffers."""
    out, err = io.StringIO(), io.StringIO()
    streams, columns = (sys.stdout, sys.stderr), os.environ.get('COLUMNS')
    sys.stdout, sys.stderr = out, err
    os.environ['COLUMNS'] = '80'
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter('default')
            status = cli.main([str(a) for a in args])
    finally:
        sys.stdout, sys.stderr = streams
        if columns is None:
            del os.environ['COLUMNS']
        else:
            os.environ['COLUMNS'] = columns
    said = ''.join(warnings.formatwarning(w.message, w.category, w.filename, w.lineno)
                   for w in caught)
    return Done(status, out.getvalue(), said + err.getvalue())


def test_the_installed_script_runs_main(script):
    """The console script is installed and is main: its status and streams, a report, an error."""
    good = subprocess.run([script, 'rotvec', '0', '0', '1', '--json'], capture_output=True,
                          encoding='utf-8', timeout=60)
    assert (good.returncode, good.stderr) == (0, '')
    assert json.loads(good.stdout) == json.loads(run('rotvec', 0, 0, 1, '--json').stdout)
    bad = subprocess.run([script, 'quaternion', '0', '0', '0', '0'], capture_output=True,
                         encoding='utf-8', timeout=60)
    assert (bad.returncode, bad.stdout) == (2, '')
    assert bad.stderr == run('quaternion', 0, 0, 0, 0).stderr != ''


def ok(*args):
    """Run, require success and a clean stderr, and return the parsed output."""
    proc = run(*args)
    assert (proc.returncode, proc.stderr) == (0, ''), proc.stderr
    if '--json' in args:
        return strict_json(proc.stdout)
    yaml = pytest.importorskip('yaml')
    return yaml.safe_load(proc.stdout)


def close(actual, expected):
    np.testing.assert_allclose(np.asarray(actual, dtype=float), expected, **PRINTED)


def _axis_sign(printed, axis, angle):
    """At θ = π the axis sign is the implementation's choice (and rounding decides it)."""
    return -1.0 if math.pi - angle < 1e-9 and np.dot(printed, axis) < 0 else 1.0


def check_rotation(rep, R, seq='ZYX', deg=False):
    """Every rotation representation in rep against the math module for R."""
    close(rep['matrix'], R)
    axis, angle = matrix_to_axis_angle(R)
    aa = rep['axis_angle']
    axis = axis * _axis_sign(aa['axis'], axis, angle)
    close(aa['axis'], axis)
    close([aa['angle'], aa['angle_deg']], [angle, math.degrees(angle)])
    close(aa['rotation_vector'], axis * angle)
    two = aa['second_solution']
    close(two['axis'], -axis)
    close([two['angle'], two['angle_deg']], [2 * math.pi - angle, 360 - math.degrees(angle)])
    close(axis_angle_to_matrix(two['axis'], two['angle']), R)
    angles, degenerate = matrix_to_euler(R, seq)
    eu = rep['euler']
    assert (eu['sequence'], eu['unit'], eu['degenerate']) == (
        seq, 'deg' if deg else 'rad', bool(degenerate))
    close(eu['angles'], np.degrees(angles) if deg else angles)
    check_rpy(rep['rpy'], R, deg)
    check_quaternion(rep['quaternion'], R)


def check_rpy(printed, R, deg=False):
    """Check rpy: roll, pitch, yaw about the fixed x, y, z axes (scipy's 'xyz'), in the unit."""
    assert list(printed) == ['roll', 'pitch', 'yaw', 'unit']
    assert printed['unit'] == ('deg' if deg else 'rad')
    angles = np.array([printed['roll'], printed['pitch'], printed['yaw']])
    roll, pitch, yaw = np.radians(angles) if deg else angles
    close(rot_z(yaw) @ rot_y(pitch) @ rot_x(roll), R)
    if abs(abs(pitch) - math.pi / 2) > 1e-6:  # unique away from gimbal lock
        reference = Rotation.from_matrix(R).as_euler('xyz')
        close(angles, np.degrees(reference) if deg else reference)


def check_quaternion(printed, R):
    """Return the printed {x, y, z, w} is scipy's canonical quaternion of R (up to sign at π)."""
    assert list(printed) == ['x', 'y', 'z', 'w']
    q = np.array(list(printed.values()))
    reference = Rotation.from_matrix(R).as_quat(canonical=True)  # (x, y, z, w)
    if abs(reference[3]) < 1e-9:  # a half turn: rounding in R decides the sign
        reference *= np.sign(np.dot(q, reference))
    close(q, reference)


# Each subcommand


@pytest.mark.parametrize('fmt', ['yaml', 'json'])
def test_euler_negative_angle_and_options_after_the_arguments(fmt):
    rep = ok('euler', 'ZYX', '-30', '20', '10', '--deg', *(['--json'] * (fmt == 'json')))
    a, b, c = np.radians([-30.0, 20.0, 10.0])
    R = rot_z(a) @ rot_y(b) @ rot_x(c)  # Jia eq. 1
    check_rotation(rep, R, deg=True)
    close(rep['euler']['angles'], [-30.0, 20.0, 10.0])
    assert list(rep) == ['matrix', 'axis_angle', 'rodrigues', 'euler', 'rpy', 'quaternion']


def test_euler_extrinsic_with_output_sequence_and_exponent_numbers():
    rep = ok('euler', 'zyx', '-1.5e-1', '2e-1', '0.3', '--seq', 'XYZ', '--json')
    R = rot_x(0.3) @ rot_y(0.2) @ rot_z(-0.15)  # extrinsic: first angle applied first
    check_rotation(rep, R, seq='XYZ')
    close(rep['euler']['angles'], [0.3, 0.2, -0.15])  # 'zyx' (a, b, c) is 'XYZ' (c, b, a)


def test_options_before_the_command():
    rep = ok('--json', '--deg', '--seq', 'ZXZ', 'euler', 'YXY', '10', '-120', '35')
    check_rotation(rep, euler_to_matrix(np.radians([10.0, -120.0, 35.0]), 'YXY'), 'ZXZ',
                   deg=True)


def test_all_sequences_at_gimbal_lock():
    rep = ok('euler', 'ZYX', '25', '90', '0', '--deg', '--all-sequences', '--json')
    R = rot_z(math.radians(25)) @ rot_y(math.pi / 2)
    check_rotation(rep, R, deg=True)
    assert rep['euler']['degenerate'] is True
    table = rep['euler']['all_sequences']
    assert list(table) == list(EULER_SEQUENCES)
    for seq, entry in table.items():
        angles, degenerate = matrix_to_euler(R, seq)
        assert entry['degenerate'] is bool(degenerate), seq
        close(entry['angles'], np.degrees(angles))
        close(euler_to_matrix(np.radians(entry['angles']), seq), R)
    assert [s for s, e in table.items() if e['degenerate']] == ['ZYX', 'xyz']


def test_matrix_typed_with_six_digits():
    typed = [0.866025, -0.5, 0, 0.5, 0.866025, 0, 0, 0, 1]  # Rot_z(30°) to six digits
    rep = ok('matrix', *typed, '--deg', '--seq', 'zyz')
    R = nearest_rotation(np.reshape(typed, (3, 3)))
    check_rotation(rep, R, seq='zyz', deg=True)
    assert rep['axis_angle']['angle_deg'] == pytest.approx(30.0, abs=1e-4)
    # The same matrix is refused at a tolerance tighter than its typing error (~6e-7).
    proc = run('matrix', *typed, '--tol', '1e-7')
    assert proc.returncode == 2
    assert re.fullmatch(r'rot-tools: error: matrix: R is not orthogonal: '
                        r'max\|RᵀR − I\| = \S+ > tol 1e-07 \(the tolerance is --tol\)\n',
                        proc.stderr)


def test_axis_angle_in_degrees_prints_exact_values():
    proc = run('axis-angle', '0', '0', '1', '90', '--deg')
    assert proc.returncode == 0
    assert '-0.0' not in proc.stdout and 'e-1' not in proc.stdout  # no noise like 6e-17
    assert 'matrix:\n- [0.0, -1.0, 0.0]\n- [1.0, 0.0, 0.0]\n- [0.0, 0.0, 1.0]\n' in proc.stdout
    assert '  angle_deg: 90.0\n' in proc.stdout and '    angle_deg: 270.0\n' in proc.stdout


def test_axis_angle_normalises_the_axis():
    rep = ok('axis-angle', '2', '-1', '2', '2.5', '--json')
    check_rotation(rep, axis_angle_to_matrix([2.0, -1.0, 2.0], 2.5))
    close(rep['axis_angle']['axis'], [2 / 3, -1 / 3, 2 / 3])


@pytest.mark.parametrize('args, vector', [
    (['0', '0', '-1e-3'], [0.0, 0.0, -1e-3]),
    (['0', '-90', '0', '--deg'], [0.0, -math.pi / 2, 0.0]),
    (['3', '-2', '0.5', '--precision', '17'], [3.0, -2.0, 0.5]),  # |v| > π: angle 2π − |v|
])
def test_rotvec(args, vector):
    rep = ok('rotvec', *args, '--json')
    check_rotation(rep, axis_angle_to_matrix(vector, np.linalg.norm(vector)),
                   deg='--deg' in args)


def test_precision():
    rep = ok('rotvec', '0.1', '0.2', '0.3', '--precision', '4', '--json')
    assert rep['axis_angle']['angle'] == 0.3742  # |(0.1, 0.2, 0.3)| = 0.374165...
    assert rep['matrix'][0][0] == round(float(rot_tools.rotvec_to_matrix([.1, .2, .3])[0, 0]), 4)


def _check_screw(rep, R, b):
    s = screw_from_transform(R, b)
    sc = rep['screw']
    sign = _axis_sign(sc['direction'], s.direction, s.angle)  # at π translation follows
    close(rep['translation'], b)
    close(sc['direction'], sign * s.direction)
    close(sc['point'], s.point)
    close(sc['moment'], sign * s.moment)
    close([sc['angle'], sc['angle_deg'], sc['translation'], sc['pitch']],
          [s.angle, math.degrees(s.angle), sign * s.translation, sign * s.pitch])
    close(np.cross(sc['point'], sc['direction']), sc['moment'])
    # Independent check: the printed screw rebuilds the transform.
    R2, b2 = transform_from_screw(sc['direction'], sc['point'], sc['angle'], sc['translation'])
    close(R2, R)
    close(b2, b)
    return sc


@pytest.mark.parametrize('fmt', ['yaml', 'json'])
def test_screw_from_euler(fmt):
    rep = ok('screw', '--euler', 'ZYX', '90', '0', '0', '--translation', '1', '0',
             '0.5', '--deg', *(['--json'] * (fmt == 'json')))
    R = rot_z(math.pi / 2)
    check_rotation(rep, R, deg=True)
    sc = _check_screw(rep, R, [1.0, 0.0, 0.5])
    close(sc['direction'], [0, 0, 1])
    close(sc['point'], [0.5, 0.5, 0])
    close([sc['translation'], sc['pitch']], [0.5, 0.5 / (math.pi / 2)])


@pytest.mark.parametrize('rotation, R', [
    (['--rotation', '0.936293', '-0.289629', '0.198669', '0.312992', '0.944702', '-0.0978434',
      '-0.159345', '0.153792', '0.975170'], None),
    (['--axis-angle', '1', '1', '0', '-180', '--deg'], axis_angle_to_matrix([1, 1, 0], math.pi)),
    (['--rotvec', '-0.2', '0.1', '2.5'], axis_angle_to_matrix([-.2, .1, 2.5], 2.5099800796)),
])
def test_screw_rotation_forms(rotation, R):
    if R is None:  # the --rotation matrix is typed with six digits: projected first
        R = nearest_rotation(np.reshape([float(x) for x in rotation[1:]], (3, 3)))
    b = [-1.0, 2.0, 0.25]
    rep = ok('screw', *rotation, '--translation', *b, '--json')
    check_rotation(rep, R, deg='--deg' in rotation)
    _check_screw(rep, R, b)


def test_pure_translation_pitch_is_inf_in_yaml_and_json():
    proc = run('screw', '--translation', '0', '-3', '4')
    assert proc.returncode == 0 and '  pitch: .inf\n' in proc.stdout
    rep = ok('screw', '--translation', '0', '-3', '4', '--json')
    sc = rep['screw']
    assert sc['pitch'] == 'inf' and float(sc['pitch']) == math.inf
    assert (sc['direction'], sc['angle'], sc['translation']) == ([0.0, -0.6, 0.8], 0.0, 5.0)
    check_rotation(rep, np.eye(3))


def test_yaml_and_json_carry_the_same_report():
    yaml = pytest.importorskip('yaml')
    args = ['screw', '--euler', 'xzx', '0.3', '2', '-1', '--translation', '1', '2', '3',
            '--all-sequences']
    from_yaml = yaml.safe_load(run(*args).stdout)
    from_json = ok(*args, '--json')
    assert from_yaml == from_json


# Quaternions (x, y, z, w: the ROS message order; --wxyz reads w first)


def _four_digits(q):
    """Return q typed with four significant digits, as a person copies it."""
    return [float(f'{x:.4g}') for x in q]


@pytest.mark.parametrize('q', [
    [0.0, 0.0, 0.7071, 0.7071],                        # Rot_z(90°), as typed from a message
    [0.1826, 0.3651, 0.5477, 0.7303],                  # (1, 2, 3, 4)/√30 to four digits
    [0.5, -0.5, 0.5, -0.5],                            # w < 0: printed as −q (w > 0)
    [1.0, 0.0, 0.0, 0.0],                              # half turn about x (w = 0)
    *(_four_digits(Rotation.random(random_state=seed).as_quat()) for seed in range(4)),
])
def test_quaternion_typed_to_four_digits(q):
    rep = ok('quaternion', *q, '--json')
    R = Rotation.from_quat(q).as_matrix()  # scipy normalises q
    check_rotation(rep, R)
    n = np.linalg.norm(q)
    sign = -1.0 if q[3] < 0 or (q[3] == 0 and q[0] < 0) else 1.0
    close(list(rep['quaternion'].values()), sign * np.divide(q, n))  # normalised


def test_quaternion_order_is_ros_and_wxyz_reads_w_first():
    c = math.sqrt(0.5)
    xyzw = ok('quaternion', 0, 0, c, c, '--json')  # z = w = √½: Rot_z(90°)
    close(xyzw['matrix'], [[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    close(list(xyzw['quaternion'].values()), [0, 0, c, c])
    wxyz = ok('quaternion', c, c, 0, 0, '--wxyz', '--json')  # w = x = √½: Rot_x(90°)
    close(wxyz['matrix'], [[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    close(list(wxyz['quaternion'].values()), [c, 0, 0, c])  # printed in ROS order
    assert ok('--wxyz', 'quaternion', c, c, 0, 0, '--json') == wxyz
    q = Rotation.random(random_state=11).as_quat()  # (x, y, z, w)
    rep = ok('quaternion', q[3], *q[:3], '--wxyz', '--precision', '17', '--json')
    check_rotation(rep, Rotation.from_quat(q).as_matrix())  # scipy reads (x, y, z, w)


def test_quaternion_tolerance_default_and_adjustable():
    # |(0, 0, 0.7, 0.7)| = 0.98995: 0.0101 from unit length, refused at the default 1e-3,
    proc = run('quaternion', 0, 0, 0.7, 0.7)
    assert (proc.returncode, proc.stdout) == (2, '')
    assert proc.stderr == ('rot-tools: error: quaternion X Y Z W: quaternion (x, y, z, w) is '
                           'not of unit length: |q| = 0.989949494, off 1 by 0.0101 > tol '
                           '0.001 (the tolerance is --tol)\n')
    # ... accepted and normalised with --tol, given before the command or after.
    for args in (['--tol', '0.02', 'quaternion', 0, 0, 0.7, 0.7],
                 ['quaternion', 0, 0, 0.7, 0.7, '--tol', '0.02']):
        rep = ok(*args, '--json')
        close(rep['matrix'], rot_z(math.pi / 2))
    # Just inside and just outside the default: |q| = 1 ± 9e-4 passes, 1 + 1.1e-3 does not.
    assert run('quaternion', 0, 0, 0, 1.0009).returncode == 0
    assert run('quaternion', 0, 0, 0, 0.9991).returncode == 0
    assert run('quaternion', 0, 0, 0, 1.0011).returncode == 2
    # --tol 0 needs an exactly unit quaternion.
    assert run('quaternion', 0, 0, 0.6, 0.8, '--tol', '0').returncode == 0
    assert run('--tol', '0', 'quaternion', 0, 0, 0.6, 0.8001).returncode == 2


def test_tol_before_the_command_applies_to_a_matrix():
    typed = [0.866025, -0.5, 0, 0.5, 0.866025, 0, 0, 0, 1]  # typing error ~6e-7
    proc = run('--tol', '1e-7', 'matrix', *typed)
    assert proc.returncode == 2 and '> tol 1e-07 (the tolerance is --tol)' in proc.stderr
    assert run('--tol', '1e-6', 'matrix', *typed).returncode == 0
    proc = run('--tol', '1e-7', 'screw', '--rotation', *typed, '--translation', 0, 0, 0)
    assert proc.returncode == 2 and '> tol 1e-07 (the tolerance is --tol)' in proc.stderr


def test_screw_from_a_ros_pose():
    q, b = _four_digits(Rotation.random(random_state=5).as_quat()), [0.5, -1.25, 2.0]
    rep = ok('screw', '--quaternion', *q, '--translation', *b, '--json')
    R = Rotation.from_quat(q).as_matrix()
    check_rotation(rep, R)
    _check_screw(rep, R, b)
    wxyz = ok('screw', '--quaternion', q[3], *q[:3], '--wxyz', '--translation', *b,
              '--json')
    assert wxyz == rep


# Frames (Jia §4), homogeneous matrices, points (Jia §5)


def _typed(values, digits=17):
    return [f'{x:.{digits}g}' for x in np.ravel(values)]


def test_frame_of_the_tracking_example():
    # Jia example 3: the tracking frame's axes are the columns of Rot_z(α)·Rot_y(β); a point
    # q of the station's frame has coordinates q' = Rᵀ·q in it (§4).
    a, b = math.radians(30.0), math.radians(-20.0)
    ca, sa, cb, sb = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
    u, v, w = [ca * cb, sa * cb, -sb], [-sa, ca, 0.0], [ca * sb, sa * sb, cb]
    R = np.array([[ca * cb, -sa, ca * sb], [sa * cb, ca, sa * sb], [-sb, 0.0, cb]])
    q = np.array([1.0, -2.0, 0.5])
    rep = ok('frame', *_typed([u, v, w]), '--point', *q, '--json')
    check_rotation(rep, R)
    close(rep['point']['p'], q)
    close(rep['point']['image'], R @ q)
    close(rep['point']['in_moved_frame'], [np.dot(u, q), np.dot(v, q), np.dot(w, q)])
    assert list(rep) == ['matrix', 'axis_angle', 'rodrigues', 'euler', 'rpy', 'quaternion',
                         'point']


def test_frame_axes_of_any_length_typed_with_six_digits():
    R = Rotation.random(random_state=3).as_matrix()
    axes = (R * [2.0, 0.5, 30.0]).T  # the columns, scaled: u, v, w
    rep = ok('frame', *_typed(axes, 6), '--json')
    M = np.array(rep['matrix'])
    close(M.T @ M, np.eye(3))  # made exactly orthonormal
    np.testing.assert_allclose(M, R, rtol=0, atol=3e-6)  # within the typing error
    check_rotation(rep, M)
    # The same frame is refused at a tolerance tighter than its typing error.
    proc = run('--tol', '1e-9', 'frame', *_typed(axes, 6))
    assert proc.returncode == 2
    assert re.fullmatch(r'rot-tools: error: frame U V W: frame axes . and . are not orthogonal: '
                        r'\|cos\| = \S+ > tol 1e-09 .*\(the tolerance is --tol\)\n', proc.stderr)


def test_frame_tolerance_is_adjustable():
    skew = [1, 0.002, 0, 0, 1, 0, 0, 0, 1]  # u and v 0.11° from orthogonal: |cos| = 0.002
    proc = run('frame', *skew)
    assert proc.returncode == 2 and '|cos| = 0.002 > tol 1e-05' in proc.stderr
    rep = ok('frame', *skew, '--tol', '3e-3', '--json')
    M = np.array(rep['matrix'])
    close(M.T @ M, np.eye(3))
    np.testing.assert_allclose(M, np.eye(3), rtol=0, atol=2e-3)


def test_screw_from_a_frame():
    rep = ok('screw', '--frame', 0, 1, 0, -1, 0, 0, 0, 0, 1, '--translation', 1, 0, 0.5,
             '--json')
    _check_screw(rep, rot_z(math.pi / 2), [1.0, 0.0, 0.5])


def _homogeneous(R, b):
    """[[R, b], [0, 0, 0, 1]] with NumPy only."""
    return np.block([[R, np.reshape(b, (3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]])


@pytest.mark.parametrize('seed', [0, 1])
def test_matrix_of_sixteen_numbers_is_a_homogeneous_transform(seed):
    R = Rotation.random(random_state=seed).as_matrix()
    b = np.random.default_rng(seed).normal(size=3) * 4
    T = _homogeneous(R, b)
    p = np.array([0.25, -3.0, 2.0])
    rep = ok('matrix', *_typed(T), '--point', *p, '--json')
    check_rotation(rep, R)
    _check_screw(rep, R, b)
    close(rep['homogeneous'], T)
    close(rep['point']['image'], (T @ np.append(p, 1.0))[:3])          # 4×4 product
    close(rep['point']['in_moved_frame'], (np.linalg.inv(T) @ np.append(p, 1.0))[:3])
    assert list(rep) == ['matrix', 'axis_angle', 'rodrigues', 'euler', 'rpy', 'quaternion',
                         'translation', 'homogeneous', 'screw', 'point']


def test_homogeneous_matrix_typed_with_six_digits():
    T = _homogeneous(rot_x(0.3) @ rot_z(-1.1), [1.5, -2.0, 0.125])
    rep = ok('matrix', *_typed(T, 6), '--json')
    M = np.array(rep['matrix'])
    close(M.T @ M, np.eye(3))
    np.testing.assert_allclose(M, T[:3, :3], rtol=0, atol=2e-6)
    close(rep['translation'], [1.5, -2.0, 0.125])
    proc = run('matrix', *_typed(T, 6), '--tol', '1e-8')
    assert proc.returncode == 2
    assert proc.stderr.startswith('rot-tools: error: matrix T[:3, :3]: R is not orthogonal: '
                                  'max|RᵀR − I| = ')
    assert proc.stderr.endswith(' > tol 1e-08 (the tolerance is --tol)\n')


def test_every_report_with_a_translation_has_the_homogeneous_matrix():
    R, b = rot_z(math.pi / 2), [1.0, 0.0, 0.5]
    for args in (['screw', '--euler', 'ZYX', '90', '0', '0', '--deg', '--translation', *b],
                 ['screw', '--quaternion', '0', '0', '0.7071', '0.7071', '--translation', *b],
                 ['matrix', *_typed(_homogeneous(R, b))]):
        rep = ok(*args, '--json')
        close(rep['homogeneous'], [[0, -1, 0, 1], [1, 0, 0, 0], [0, 0, 1, 0.5], [0, 0, 0, 1]])
    rep = ok('screw', '--translation', '0', '-3', '4', '--json')
    close(rep['homogeneous'], _homogeneous(np.eye(3), [0, -3, 4]))
    for args in (['euler', 'ZYX', '1', '2', '3'], ['matrix', *_typed(R)],
                 ['quaternion', '0', '0', '0', '1'], ['frame', *_typed(R.T)]):
        assert 'homogeneous' not in ok(*args, '--json')


@pytest.mark.parametrize('args', [
    ['euler', 'ZYX', '30', '-20', '10', '--deg'],
    ['axis-angle', '1', '-2', '0.5', '2.5'],
    ['screw', '--rotvec', '0.3', '-1', '2', '--translation', '-1', '2', '0.25'],
    ['screw', '--translation', '1', '2', '3'],
])
def test_point_image_and_coordinates_in_the_moved_frame(args):
    p = [-1e-3, 2.5, -3.0]
    for where in ('after', 'before'):
        argv = [*args, '--point', *p] if where == 'after' else ['--point', *p, *args]
        rep = ok(*argv, '--json')
        R = np.array(rep['matrix'])
        b = np.array(rep.get('translation', [0.0, 0.0, 0.0]))
        pt = rep['point']
        assert list(pt) == ['p', 'image', 'in_moved_frame']
        close(pt['p'], p)
        close(pt['image'], R @ p + b)
        close(pt['in_moved_frame'], R.T @ (p - b))
        close(R @ pt['in_moved_frame'] + b, p)  # back to the reference frame


# Options anywhere, --version, hints

COMMON_OPTIONS = {  # option → its arguments, for a quaternion input
    '--deg': [], '--seq': ['xzx'], '--all-sequences': [], '--json': [],
    '--precision': ['5'], '--tol': ['1e-2'], '--wxyz': [], '--point': ['-1', '2e-1', '3']}


@pytest.mark.parametrize('option', sorted(COMMON_OPTIONS))
def test_every_option_before_the_command_and_after_its_arguments(option):
    value = COMMON_OPTIONS[option]
    q = ['0.927', '0.1', '-0.2', '0.3'] if option == '--wxyz' else ['0.1', '-0.2', '0.3', '0.927']
    before = run(option, *value, 'quaternion', *q)
    after = run('quaternion', *q, option, *value)
    plain = run('quaternion', '0.1', '-0.2', '0.3', '0.927')
    assert before.returncode == after.returncode == 0, (before.stderr, after.stderr)
    assert before.stdout == after.stdout
    assert (before.stdout == plain.stdout) is (option in ('--tol', '--wxyz'))  # it acted


@pytest.mark.parametrize('between, canonical', [
    ('euler ZYX --deg -30 20 10', 'euler ZYX -30 20 10 --deg'),
    ('euler --seq xyz ZYX 0.1 0.2 0.3', 'euler ZYX 0.1 0.2 0.3 --seq xyz'),
    ('matrix 1 0 0 --tol 1e-3 0 1 0 0 0 1.0004', 'matrix 1 0 0 0 1 0 0 0 1.0004 --tol 1e-3'),
    ('frame 0 1 0 --point 1 2 3 -1 0 0 0 0 1', 'frame 0 1 0 -1 0 0 0 0 1 --point 1 2 3'),
    ('screw --translation 1 2 3 --deg --euler ZYX 90 0 0',
     'screw --euler ZYX 90 0 0 --translation 1 2 3 --deg'),
])
def test_options_between_the_arguments(between, canonical):
    mixed, plain = run(*between.split()), run(*canonical.split())
    assert (mixed.returncode, mixed.stderr) == (0, '') and mixed.stdout == plain.stdout


def test_help_lists_every_option():
    options = [*COMMON_OPTIONS, '--plot', '--version']
    for args in ([], ['quaternion'], ['frame'], ['screw']):
        text = run(*args, '--help').stdout
        for option in options:
            assert re.search(rf'^  {option}\b', text, re.MULTILINE), (args, option)
    text = run('--help').stdout
    for default in ('max|RᵀR − I| and |det R − 1| ≤ TOL, default 1e-05',
                    '|cos| between two axes ≤ TOL, default 1e-05',
                    '||q| − 1| ≤ TOL, default 0.001'):  # which default for which input
        assert default in ' '.join(text.split())


def test_version_is_the_installed_distribution_and_package_xml_version():
    from importlib.metadata import version
    xml = (Path(__file__).resolve().parents[1] / 'package.xml').read_text()
    (in_xml,) = re.findall(r'<version>([^<]+)</version>', xml)
    assert version('rot_tools') == in_xml
    for args in (['--version'], ['euler', 'ZYX', '1', '2', '3', '--version'],
                 ['--json', '--version']):
        proc = run(*args)
        assert (proc.returncode, proc.stdout, proc.stderr) == (0, f'rot-tools {in_xml}\n', '')


@pytest.mark.parametrize('args, size', [
    (['euler', 'ZYX', '90', '0', '0'], '90'),
    (['euler', 'zyx', '0', '-30', '6.3'], '30'),
    (['axis-angle', '0', '0', '1', '180'], '180'),
    (['rotvec', '4', '4', '4'], '6.9282'),             # each component < 2π, the norm > 2π
    (['screw', '--euler', 'ZYX', '0', '0', '45', '--translation', '1', '0', '0'], '45'),
    (['screw', '--rotvec', '0', '7', '0', '--translation', '1', '0', '0'], '7'),
    (['rotvec', '1e300', '-1e300', '0'], '1.41421e+300'),  # its norm, without overflow
])
def test_radians_that_look_like_degrees_get_a_hint(args, size):
    proc = run(*args)
    assert proc.returncode == 0
    assert proc.stderr == (f'rot-tools: hint: an angle of {size} rad is more than 2π: if it '
                           'is in degrees, add --deg\n')
    assert proc.stdout == run(*args, '--precision', '12').stdout  # still radians
    assert run(*args, '--deg').stderr == ''


@pytest.mark.parametrize('args', [
    'euler ZYX 6.28 -6.28 3', 'rotvec 3.6 3.6 3.6', 'axis-angle 1 0 0 -6.2831'])
def test_angles_up_to_2pi_get_no_hint(args):
    proc = run(*args.split())
    assert (proc.returncode, proc.stderr) == (0, '')


def test_radians_value_is_kept_when_hinting():
    rep = json.loads(run('axis-angle', 0, 0, 1, 90, '--json').stdout)
    check_rotation(rep, rot_z(90.0))  # 90 rad, as typed


# Help


@pytest.mark.parametrize('command', ['euler', 'matrix', 'axis-angle', 'rotvec', 'quaternion',
                                     'frame', 'screw'])
def test_help_has_usage_and_examples_that_run(command):
    proc = run(command, '--help')
    assert proc.returncode == 0 and proc.stderr == ''
    assert proc.stdout.startswith(f'usage: rot-tools {command} ')
    examples = proc.stdout.split('\nexamples:\n', 1)[1].splitlines()
    assert examples and all(line.startswith('  rot-tools ') for line in examples)
    first = examples[0].split()[1:]
    assert run(*first).returncode == 0


def test_main_help():
    proc = run('--help')
    assert proc.returncode == 0 and proc.stdout.startswith('usage: rot-tools ')
    for command in ('euler', 'matrix', 'axis-angle', 'rotvec', 'quaternion', 'frame', 'screw'):
        assert f'\n    {command} ' in proc.stdout


# Bad input: one line on stderr, status 2


@pytest.mark.parametrize('args, message', [
    # wrong count
    ('euler ZYX 1 2', 'euler ZYX angles: expected 3 numbers, got 2'),
    ('euler ZYX 1 2 3 4', 'euler ZYX angles: expected 3 numbers, got 4'),
    ('matrix 1 0 0 0 1 0 0 0', 'matrix: expected 9 numbers (R) or 16 (a homogeneous 4×4 '
     'matrix), got 8'),
    ('matrix 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0', 'matrix: expected 9 numbers (R) or 16'),
    ('matrix 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 0', 'matrix: expected 9 numbers (R) or 16 (a '
     'homogeneous 4×4 matrix), got 17'),
    ('axis-angle 0 0 1', 'axis-angle X Y Z ANGLE: expected 4 numbers, got 3'),
    ('rotvec 1 2 3 4', 'rotvec X Y Z: expected 3 numbers, got 4'),
    ('screw --translation 1 2', 'argument --translation: expected 3 arguments'),
    ('screw --rotation 1 0 0 --translation 1 2 3', 'argument --rotation: expected 9 arguments'),
    ('screw --rotvec 1 2 3', 'the following arguments are required: --translation'),
    ('euler', 'the following arguments are required: SEQ'),
    ('', 'the following arguments are required: COMMAND'),
    # not numbers / not finite
    ('euler ZYX 1 x 3', "argument ANGLE: not a number: 'x'"),
    ('matrix 1 0 0 0 1 0 0 0 1,0', "argument ENTRY: not a number: '1,0'"),
    ('screw --euler ZYX 1 q 3 --translation 0 0 0', "argument --euler: not a number: 'q'"),
    ('screw --translation 1 two 3', "argument --translation: not a number: 'two'"),
    ('euler ZYX nan 0 0', "argument ANGLE: not a finite number: 'nan'"),
    ('rotvec -inf 0 0', "argument COMPONENT: not a finite number: '-inf'"),
    ('axis-angle 0 0 1 1e999', "argument NUMBER: not a finite number: '1e999'"),
    ('matrix 1 0 0 0 1 0 0 0 Infinity', "argument ENTRY: not a finite number: 'Infinity'"),
    # not a rotation
    ('matrix 1 0.2 0 0 1 0 0 0 1',
     r'matrix: R is not orthogonal: max|RᵀR − I| = 0.2 > tol 1e-05 '
     '(the tolerance is --tol)'),
    ('matrix 0 0 0 0 0 0 0 0 0', 'matrix: R is not orthogonal: max|RᵀR − I| = 1 '),
    ('matrix 1 0 0 0 1 0 0 0 -1', 'matrix: R is a reflection: det R = -1, expected +1'),
    ('screw --rotation -1 0 0 0 -1 0 0 0 -1 --translation 0 0 0',
     'argument --rotation: R is a reflection: det R = -1, expected +1'),
    ('matrix 1 0 0 0 1 0 0 0 1 --tol -1', "argument --tol: must be >= 0, got '-1'"),
    # sequences
    ('euler ABC 1 2 3', "argument SEQ: unknown Euler sequence 'ABC': use one of the 12"),
    ('euler ZyX 1 2 3', "argument SEQ: unknown Euler sequence 'ZyX'"),
    ('euler XXY 1 2 3', "argument SEQ: unknown Euler sequence 'XXY'"),
    ('rotvec 1 2 3 --seq zyX', "argument --seq: unknown Euler sequence 'zyX'"),
    ('screw --euler XYZW 1 2 3 --translation 0 0 0', 'argument --euler: unknown Euler sequ'),
    # axis
    ('axis-angle 0 0 0 1', 'axis-angle: axis is zero but the angle is 1 rad'),
    ('screw --axis-angle 0 0 0 -2 --translation 1 2 3',
     'argument --axis-angle: axis is zero but the angle is -2 rad'),
    # quaternions
    ('quaternion 0 0 1', 'quaternion X Y Z W: expected 4 numbers, got 3'),
    ('quaternion 0 0 0 1 0', 'quaternion X Y Z W: expected 4 numbers, got 5'),
    ('quaternion 1 0 0 --wxyz', 'quaternion W X Y Z: expected 4 numbers, got 3'),
    ('quaternion 0 0 0 0', 'quaternion X Y Z W: quaternion (x, y, z, w) must be non-zero, '
     'got |q| = 0'),
    ('quaternion 0 0 0 0 --tol 2', 'quaternion X Y Z W: quaternion (x, y, z, w) must be '
     'non-zero'),
    ('quaternion 0 nan 0 1', "argument COMPONENT: not a finite number: 'nan'"),
    ('quaternion 0 0 0 -inf', "argument COMPONENT: not a finite number: '-inf'"),
    ('quaternion 0 0 1 1', 'quaternion X Y Z W: quaternion (x, y, z, w) is not of unit length: '
     '|q| = 1.41421356, off 1 by 0.414 > tol 0.001 (the tolerance is --tol)'),
    ('quaternion 1e200 1e200 0 0', 'quaternion X Y Z W: quaternion (x, y, z, w) is not of unit '
     'length: |q| = 1.41421356e+200, off 1 by 1.41e+200 > tol 0.001'),
    ('--wxyz quaternion 2 0 0 0', 'quaternion W X Y Z: quaternion (x, y, z, w) is not of unit '
     'length: |q| = 2, off 1 by 1 '),
    ('screw --quaternion 0 0 0 2 --translation 0 0 0', 'argument --quaternion: quaternion '
     '(x, y, z, w) is not of unit length: |q| = 2, off 1 by 1 > tol 0.001'),
    ('screw --quaternion 0 0 0 0 --translation 0 0 0', 'argument --quaternion: quaternion '
     '(x, y, z, w) must be non-zero'),
    ('screw --quaternion 0 0 1 --translation 0 0 0', 'argument --quaternion: expected 4 '
     'arguments'),
    ('quaternion 0 0 0 1 --tol x', "argument --tol: not a number: 'x'"),
    ('--tol -1e-3 quaternion 0 0 0 1', "argument --tol: must be >= 0, got '-1e-3'"),
    # frames
    ('frame 1 0 0 0 1 0 0 0', 'frame U V W: expected 9 numbers, got 8'),
    ('frame 1 0 0 0 1 0 0 0 1 1', 'frame U V W: expected 9 numbers, got 10'),
    ('frame 1 0 0 0 1 0 nan 0 1', "argument COMPONENT: not a finite number: 'nan'"),
    ('frame 1 0 0 0 1 0 0 0 -1', 'frame U V W: the frame (u, v, w) is left-handed: '
     '(û × v̂)·ŵ = -1, expected +1'),
    ('frame 0 1 0 1 0 0 0 0 1', 'frame U V W: the frame (u, v, w) is left-handed'),
    ('frame 1 0.1 0 0 1 0 0 0 1', 'frame U V W: frame axes u and v are not orthogonal: '
     '|cos| = 0.0995 > tol 1e-05'),
    ('frame 1 0 0 0 1 0 0 1 1', 'frame U V W: frame axes v and w are not orthogonal: '
     '|cos| = 0.707 > tol 1e-05'),
    ('frame 1 0 0 0 1 0 1 1 1 --tol 0.5', 'frame U V W: frame axes u and w are not '
     'orthogonal: |cos| = 0.577 > tol 0.5'),
    ('frame 1 0 0 0 0 0 0 0 1', 'frame U V W: frame axis v is zero (|v| = 0)'),
    ('frame 1 0 0 0 1 0 0 0 1 --tol 1', 'frame U V W: tol must be in [0, 1), got 1.0'),
    ('screw --frame 1 0 0 0 -1 0 0 0 1 --translation 0 0 0', 'argument --frame: the frame '
     '(u, v, w) is left-handed'),
    ('screw --frame 1 0 0 0 1 0 --translation 0 0 0', 'argument --frame: expected 9 arguments'),
    # homogeneous 4×4
    ('matrix 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0.1 1', 'matrix: T is not a rigid motion: its last '
     'row is [0.0, 0.0, 0.1, 1.0], not [0, 0, 0, 1] (off by 0.1 > 1e-09)'),
    ('matrix 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 2', 'matrix: T is not a rigid motion: its last '
     'row is [0.0, 0.0, 0.0, 2.0], not [0, 0, 0, 1] (off by 1 > 1e-09)'),
    ('matrix 1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1.000001 --tol 0.1', 'matrix: T is not a rigid '
     'motion: its last row is [0.0, 0.0, 0.0, 1.000001], not [0, 0, 0, 1] (off by 1e-06 > '
     '1e-09)'),
    ('matrix 1 0 0 0 0 0 0 0 0 0 0 0 0 0 0 1', 'matrix T[:3, :3]: R is not orthogonal: '
     'max|RᵀR − I| = 1 > tol 1e-05'),
    ('matrix 1 0.2 0 0 0 1 0 0 0 0 1 0 0 0 0 1', 'matrix T[:3, :3]: R is not orthogonal: '
     'max|RᵀR − I| = 0.2 > tol 1e-05 (the tolerance is --tol)'),
    ('matrix 1 0 0 5 0 1 0 6 0 0 -1 7 0 0 0 1', 'matrix T[:3, :3]: R is a reflection: '
     'det R = -1, expected +1'),
    ('matrix 1 0 0 0 0 1 0 0 0 0 1 inf 0 0 0 1', "argument ENTRY: not a finite number: 'inf'"),
    # --point
    ('euler ZYX 1 2 3 --point 1 2', 'argument --point: expected 3 arguments'),
    ('--point 1 nan 3 euler ZYX 1 2 3', "argument --point: not a finite number: 'nan'"),
    ('quaternion 0 0 0 1 --point 1 2 x', "argument --point: not a number: 'x'"),
    ('euler ZYX 0.785398 0 0 --point 1.5e308 1.5e308 0', 'euler: R·p + b overflows float64'),
    ('screw --translation 1e308 0 0 --point 1e308 0 0', 'screw: R·p + b overflows float64'),
    # --wxyz without a quaternion
    ('euler ZYX 1 2 3 --wxyz', '--wxyz: there is no quaternion to read (it applies to '
     'quaternion and screw --quaternion)'),
    ('--wxyz screw --rotvec 1 2 3 --translation 0 0 0', '--wxyz: there is no quaternion'),
    # a hint never comes with an error: the error is the one line
    ('axis-angle 0 0 0 90', 'axis-angle: axis is zero but the angle is 90 rad'),
    ('euler ZYX 90 0', 'euler ZYX angles: expected 3 numbers, got 2'),
    # options
    ('euler ZYX 1 2 3 --precision 0', "argument --precision: expected an integer 1..17, got '0'"),
    ('euler ZYX 1 2 3 --bogus', 'unrecognized arguments: --bogus'),
    ('quat 0 0 0 1', "argument COMMAND: invalid choice: 'quat'"),
    ('euler RPY 0.1 0.2 0.3', "argument SEQ: unknown Euler sequence 'RPY': use one of the 12"),
    ('euler ZYX 1 2 3 --seq rpy', "argument --seq: unknown Euler sequence 'rpy'"),
    ('screw --rotvec 1 2 3 --euler ZYX 1 2 3 --translation 0 0 0',
     'argument --euler: not allowed with argument --rotvec'),
])
def test_bad_input_is_one_line_and_status_2(args, message):
    proc = run(*args.split())
    assert proc.returncode == 2, proc
    assert proc.stdout == ''
    assert proc.stderr.startswith(f'rot-tools: error: {message}'), proc.stderr
    assert proc.stderr.endswith('\n') and proc.stderr.count('\n') == 1, proc.stderr


@pytest.mark.parametrize('name, meant', [('RPY', "extrinsic sequence 'xyz'"),
                                         ('rpy', "extrinsic sequence 'xyz'"),
                                         ('roll-pitch-yaw', "extrinsic sequence 'xyz'"),
                                         ('YPR', "intrinsic sequence 'ZYX'")])
def test_roll_pitch_yaw_as_a_sequence_name_gets_a_hint(name, meant):
    proc = run('euler', 'ZYX', '0.1', '0.2', '0.3', '--seq', name)
    assert proc.returncode == 2 and proc.stderr.count('\n') == 1, proc.stderr
    assert meant in proc.stderr and '~/rpy' in proc.stderr
    # ... and what it points to is right: rpy is the report's roll, pitch, yaw.
    rep = ok('euler', 'xyz', '0.1', '0.2', '0.3')
    close([rep['rpy'][k] for k in ('roll', 'pitch', 'yaw')], [0.1, 0.2, 0.3])
    rep = ok('euler', 'ZYX', '0.3', '0.2', '0.1')
    close([rep['rpy'][k] for k in ('roll', 'pitch', 'yaw')], [0.1, 0.2, 0.3])
