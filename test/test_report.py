"""rot_tools.io.report: the report's keys and values, and its YAML / JSON text."""

import math
import subprocess
import sys

from conftest import strict_json
import numpy as np
import pytest
import rot_tools as rt
from rot_tools import (
    axis_angle_to_matrix, EULER_SEQUENCES, euler_to_matrix, matrix_to_euler, rot_x, rot_y,
    rot_z, RotationError, screw_from_transform)
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.io.report import round_number, to_json, to_yaml, transform_report
from scipy.spatial.transform import Rotation

TOL = 1e-12
R0 = rot_z(0.3) @ rot_y(-0.7) @ rot_x(2.1)
B0 = np.array([0.4, -1.5, 2.0])


def _walk(x):
    yield x
    if isinstance(x, dict):
        for v in x.values():
            yield from _walk(v)
    elif isinstance(x, list):
        for v in x:
            yield from _walk(v)


# transform_report


def test_keys_in_order_and_plain_python_types():
    rep = transform_report(R0, B0, point=[1.0, -2.0, 0.5])
    assert list(rep) == ['matrix', 'axis_angle', 'rodrigues', 'euler', 'rpy', 'quaternion',
                         'translation', 'homogeneous', 'screw', 'point']
    assert list(rep['axis_angle']) == [
        'axis', 'angle', 'angle_deg', 'rotation_vector', 'second_solution']
    assert list(rep['axis_angle']['second_solution']) == ['axis', 'angle', 'angle_deg']
    assert list(rep['euler']) == ['sequence', 'unit', 'angles', 'degenerate']
    assert list(rep['rpy']) == ['roll', 'pitch', 'yaw', 'unit']
    assert list(rep['quaternion']) == ['x', 'y', 'z', 'w']
    assert list(rep['screw']) == [
        'direction', 'point', 'moment', 'angle', 'angle_deg', 'translation', 'pitch']
    assert list(rep['point']) == ['p', 'image', 'in_moved_frame']
    assert list(transform_report(R0)) == [
        'matrix', 'axis_angle', 'rodrigues', 'euler', 'rpy', 'quaternion']
    for item in _walk(rep):
        assert type(item) in (dict, list, float, bool, str), (type(item), item)


def test_values_match_the_math():
    rep = transform_report(R0, B0)
    np.testing.assert_array_equal(rep['matrix'], R0)
    aa = rep['axis_angle']
    np.testing.assert_allclose(axis_angle_to_matrix(aa['axis'], aa['angle']), R0, atol=TOL)
    np.testing.assert_allclose(aa['rotation_vector'], np.multiply(aa['axis'], aa['angle']),
                               atol=TOL)
    assert aa['angle_deg'] == pytest.approx(math.degrees(aa['angle']), abs=TOL)
    eu = rep['euler']
    assert (eu['sequence'], eu['unit'], eu['degenerate']) == ('ZYX', 'rad', False)
    np.testing.assert_allclose(eu['angles'], [0.3, -0.7, 2.1], atol=TOL)
    assert rep['translation'] == B0.tolist()
    s = screw_from_transform(R0, B0)
    sc = rep['screw']
    for key in ('direction', 'point', 'moment'):
        np.testing.assert_array_equal(sc[key], getattr(s, key))
    assert (sc['angle'], sc['translation'], sc['pitch']) == (s.angle, s.translation, s.pitch)
    assert sc['angle_deg'] == pytest.approx(math.degrees(sc['angle']), abs=TOL)


@pytest.mark.parametrize('angle', [0.0, 1e-9, 0.5, 2.0, math.pi - 1e-9, math.pi])
def test_both_axis_angle_solutions_give_the_matrix(angle):
    R = axis_angle_to_matrix([1.0, -2.0, 0.5], angle)
    aa = transform_report(R)['axis_angle']
    two = aa['second_solution']
    assert 0.0 <= aa['angle'] <= math.pi
    assert two['angle'] == pytest.approx(2 * math.pi - aa['angle'], abs=TOL)
    assert two['angle_deg'] == pytest.approx(360.0 - aa['angle_deg'], abs=1e-10)
    np.testing.assert_array_equal(two['axis'], -np.array(aa['axis']))
    np.testing.assert_allclose(axis_angle_to_matrix(aa['axis'], aa['angle']), R, atol=TOL)
    np.testing.assert_allclose(axis_angle_to_matrix(two['axis'], two['angle']), R, atol=TOL)


@pytest.mark.parametrize('axis, angle', [
    ([0.0, 0.0, 1.0], 0.0), ([1.0, -2.0, 0.5], 1e-12), ([0.3, 0.4, -1.0], 2.0),
    ([1.0, -2.0, 0.5], math.pi - 1e-9), ([1.0, -2.0, 0.5], math.pi),
    ([0.0, -1.0, 0.0], math.pi), ([0.0, 0.0, -1.0], math.pi)])
def test_quaternion_is_scipys_canonical_one_in_ros_order(axis, angle):
    axis = np.divide(axis, np.linalg.norm(axis))
    R = axis_angle_to_matrix(axis, angle)
    rep = transform_report(R)['quaternion']
    q = np.array([rep['x'], rep['y'], rep['z'], rep['w']])
    # The closed form (sin(θ/2)·l̂, cos(θ/2)) and scipy; at π (rounding of R decides the sign)
    # up to sign, and the canonical rule: w > 0, or w = 0 and the first non-zero positive.
    expected = np.append(math.sin(angle / 2) * axis, math.cos(angle / 2))
    reference = Rotation.from_matrix(R).as_quat(canonical=True)
    if angle < math.pi:
        np.testing.assert_allclose(q, expected, rtol=0, atol=1e-15)
        np.testing.assert_allclose(q, reference, rtol=0, atol=1e-15)
    else:
        assert min(np.abs(q - s * expected).max() for s in (1, -1)) <= 1e-15
        assert min(np.abs(q - s * reference).max() for s in (1, -1)) <= 1e-15
    assert q[3] > 0 or (q[3] == 0 and q[:3][q[:3] != 0][0] > 0)
    assert np.linalg.norm(q) == pytest.approx(1.0, abs=1e-15)


def test_homogeneous_matrix_only_with_a_translation():
    rep = transform_report(R0, B0)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R0, B0
    assert rep['homogeneous'] == T.tolist()  # exact: it only places the entries
    assert 'homogeneous' not in transform_report(R0)
    assert transform_report(R0, np.zeros(3))['homogeneous'][3] == [0.0, 0.0, 0.0, 1.0]


@pytest.mark.parametrize('b', [None, B0])
def test_point_image_and_coordinates_in_the_moved_frame(b):
    rng = np.random.default_rng(4)
    for p in [np.zeros(3), *rng.normal(size=(5, 3)) * 10]:
        t = np.zeros(3) if b is None else b
        pt = transform_report(R0, b, point=p)['point']
        np.testing.assert_array_equal(pt['p'], p)
        # Independent closed forms (Jia §5 and §4): R·p + b and Rᵀ·(p − b).
        np.testing.assert_allclose(pt['image'], R0 @ p + t, rtol=0, atol=1e-14)
        np.testing.assert_allclose(pt['in_moved_frame'], R0.T @ (p - t), rtol=0, atol=1e-14)
        # The 4×4 product agrees.
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = R0, t
        np.testing.assert_allclose(pt['image'], (T @ np.append(p, 1))[:3], rtol=0, atol=1e-14)
    assert 'point' not in transform_report(R0, b)


def test_degrees_switch_the_euler_angles_only():
    rad = transform_report(R0, B0, seq='zxz')
    deg = transform_report(R0, B0, seq='zxz', degrees=True)
    assert (rad['euler']['unit'], deg['euler']['unit']) == ('rad', 'deg')
    assert deg['euler']['sequence'] == 'zxz'
    np.testing.assert_allclose(deg['euler']['angles'], np.degrees(rad['euler']['angles']),
                               atol=1e-12)
    np.testing.assert_allclose(euler_to_matrix(np.radians(deg['euler']['angles']), 'zxz'), R0,
                               atol=TOL)
    for key in ('axis_angle', 'screw', 'matrix', 'translation', 'quaternion', 'homogeneous'):
        assert deg[key] == rad[key]


@pytest.mark.parametrize('seq', ['ZYX', 'zxz', 'XYZ'])
@pytest.mark.parametrize('degrees', [False, True])
def test_rpy_are_the_fixed_axis_angles_whatever_the_sequence(seq, degrees):
    # REP 103: roll, pitch, yaw about the fixed x, y, z axes = extrinsic 'xyz'; independent
    # reference: scipy, and the closed form R = Rot_z(yaw) Rot_y(pitch) Rot_x(roll).
    rng = np.random.default_rng(11)
    for R in [R0, *Rotation.random(20, random_state=rng).as_matrix()]:
        rpy = transform_report(R, seq=seq, degrees=degrees)['rpy']
        assert rpy['unit'] == ('deg' if degrees else 'rad')
        angles = np.array([rpy['roll'], rpy['pitch'], rpy['yaw']])
        rad = np.radians(angles) if degrees else angles
        np.testing.assert_allclose(rad, Rotation.from_matrix(R).as_euler('xyz'), rtol=0,
                                   atol=1e-12)
        roll, pitch, yaw = rad
        np.testing.assert_allclose(rot_z(yaw) @ rot_y(pitch) @ rot_x(roll), R, rtol=0,
                                   atol=1e-12)
    roll, pitch, yaw = 0.1, -0.2, 0.3
    rep = transform_report(rot_z(yaw) @ rot_y(pitch) @ rot_x(roll), seq=seq)['rpy']
    assert [rep['roll'], rep['pitch'], rep['yaw']] == pytest.approx([roll, pitch, yaw],
                                                                    abs=1e-15)


def test_rpy_at_gimbal_lock():
    # Pitch +90°: roll and yaw turn about the same axis; as for every extrinsic sequence,
    # yaw (θ3) is 0 and roll carries the free angle roll − yaw.
    R = rot_z(0.5) @ rot_y(math.pi / 2) @ rot_x(0.2)
    rpy = transform_report(R)['rpy']
    assert rpy['pitch'] == pytest.approx(math.pi / 2, abs=1e-12)
    assert rpy['yaw'] == 0.0
    assert rpy['roll'] == pytest.approx(0.2 - 0.5, abs=1e-12)
    np.testing.assert_allclose(rot_y(rpy['pitch']) @ rot_x(rpy['roll']), R, atol=1e-12)


def test_gimbal_lock_flag_and_all_sequences():
    R = rot_z(0.4) @ rot_y(math.pi / 2)  # ZYX (0.4, π/2, 0): locked
    rep = transform_report(R, degrees=True, all_sequences=True)
    eu = rep['euler']
    assert eu['degenerate'] is True
    np.testing.assert_allclose(eu['angles'], [math.degrees(0.4), 90.0, 0.0], atol=1e-10)
    table = eu['all_sequences']
    assert list(table) == list(EULER_SEQUENCES) and len(table) == 24
    for seq, entry in table.items():
        angles, degenerate = matrix_to_euler(R, seq)
        assert entry['degenerate'] is bool(degenerate), seq
        np.testing.assert_allclose(entry['angles'], np.degrees(angles), atol=1e-12)
        np.testing.assert_allclose(euler_to_matrix(np.radians(entry['angles']), seq), R,
                                   atol=1e-12)
    # Extrinsic xyz is intrinsic ZYX read backwards: locked too. ZYZ (0.4, π/2, 0) is not.
    assert table['xyz']['degenerate'] and table['xyz']['angles'][1] == 90.0
    assert not table['ZYZ']['degenerate']
    np.testing.assert_allclose(table['ZYZ']['angles'], [math.degrees(0.4), 90.0, 0.0],
                               atol=1e-12)
    assert 'all_sequences' not in transform_report(R)['euler']


def test_pure_translation_has_infinite_pitch():
    rep = transform_report(np.eye(3), [0.0, 3.0, 4.0])
    sc = rep['screw']
    assert sc['pitch'] == math.inf
    np.testing.assert_allclose(sc['direction'], [0.0, 0.6, 0.8], rtol=0, atol=TOL)
    assert (sc['angle'], sc['translation']) == (0.0, pytest.approx(5.0, abs=TOL))
    assert 'pitch: .inf\n' in to_yaml(rep)
    text = to_json(rep)
    assert '"pitch": "inf"' in text
    assert strict_json(text)['screw']['pitch'] == 'inf'
    assert float(strict_json(text)['screw']['pitch']) == math.inf


def test_identity_screw():
    sc = transform_report(np.eye(3), np.zeros(3))['screw']
    assert sc == {'direction': [0.0, 0.0, 1.0], 'point': [0.0, 0.0, 0.0],
                  'moment': [0.0, 0.0, 0.0], 'angle': 0.0, 'angle_deg': 0.0,
                  'translation': 0.0, 'pitch': 0.0}


@pytest.mark.parametrize('args, match', [
    ((np.diag([1.0, 1.0, -1.0]),), 'reflection'),
    ((np.eye(3) * 1.1,), r'not orthogonal: max\|RᵀR − I\| = 0\.21'),
    ((np.stack([np.eye(3)] * 2),), r'one rotation \(3, 3\), got \(2, 3, 3\)'),
    ((np.eye(3), [1.0, 2.0]), r'translation b must have shape \(3,\)'),
    ((np.eye(3), None, 'ZyX'), "unknown Euler sequence 'ZyX'"),
    ((np.eye(3), None, 'ZYX', False, False, [1.0, 2.0]), r'point p must have shape \(3,\)'),
    ((np.eye(3), None, 'ZYX', False, False, np.zeros((2, 3))),
     r'point p must have shape \(3,\), got \(2, 3\)'),
    ((np.eye(3), None, 'ZYX', False, False, [1.0, np.nan, 0.0]), 'point p must be finite'),
])
def test_bad_input_raises(args, match):
    with pytest.raises(RotationError, match=match):
        transform_report(*args)


# Numbers and text


@pytest.mark.parametrize('x, precision, expected', [
    (-0.0, 12, '0.0'),
    (6.123233995736766e-17, 12, '0.0'),
    (-6.123233995736766e-17, 12, '0.0'),
    (math.pi, 12, '3.14159265359'),
    (math.pi, 4, '3.142'),
    (180.00000000000003, 12, '180.0'),
    (123456789.123456789, 12, '123456789.123'),
    (1e-5, 12, '1.0e-05'),
    (1e16, 12, '1.0e+16'),
    (0.1 + 0.2, None, '0.30000000000000004'),
    (math.inf, 12, '.inf'),
    (-math.inf, 12, '-.inf'),
    (math.nan, 12, '.nan'),
])
def test_yaml_numbers(x, precision, expected):
    assert to_yaml({'x': x}, precision=precision) == f'x: {expected}\n'


def test_round_number():
    assert math.copysign(1.0, round_number(-1e-20)) == 1.0
    assert round_number(2.0 / 3.0) == 0.666666666667
    assert round_number(2.0 / 3.0, 3) == 0.667
    assert round_number(-2.0 / 3.0, None) == -2.0 / 3.0
    assert round_number(math.inf) == math.inf


def test_yaml_layout_is_fixed():
    rep = transform_report(rot_z(math.pi / 2), [1.0, 0.0, 0.5], degrees=True,
                           point=[1.0, 2.0, 3.0])
    assert to_yaml(rep) == """\
matrix:
- [0.0, -1.0, 0.0]
- [1.0, 0.0, 0.0]
- [0.0, 0.0, 1.0]
axis_angle:
  axis: [0.0, 0.0, 1.0]
  angle: 1.5707963268
  angle_deg: 90.0
  rotation_vector: [0.0, 0.0, 1.5707963268]
  second_solution:
    axis: [0.0, 0.0, -1.0]
    angle: 4.71238898038
    angle_deg: 270.0
rodrigues: [0.0, 0.0, 1.0]
euler:
  sequence: ZYX
  unit: deg
  angles: [90.0, 0.0, 0.0]
  degenerate: false
rpy:
  roll: 0.0
  pitch: 0.0
  yaw: 90.0
  unit: deg
quaternion:
  x: 0.0
  y: 0.0
  z: 0.707106781187
  w: 0.707106781187
translation: [1.0, 0.0, 0.5]
homogeneous:
- [0.0, -1.0, 0.0, 1.0]
- [1.0, 0.0, 0.0, 0.0]
- [0.0, 0.0, 1.0, 0.5]
- [0.0, 0.0, 0.0, 1.0]
screw:
  direction: [0.0, 0.0, 1.0]
  point: [0.5, 0.5, 0.0]
  moment: [0.5, -0.5, 0.0]
  angle: 1.5707963268
  angle_deg: 90.0
  translation: 0.5
  pitch: 0.318309886184
point:
  p: [1.0, 2.0, 3.0]
  image: [-1.0, 1.0, 3.5]
  in_moved_frame: [2.0, 0.0, 2.5]
"""


def test_yaml_is_one_line_per_value_and_never_aliases():
    # PyYAML folds a long string at its default width of 80, and writes an object seen twice
    # as an anchor (&id001) and an alias (*id001): neither reads well in a report.
    row = [1.0, 2.0]
    text = to_yaml({'why': 'word ' * 40, 'a': row, 'b': row, 'rows': [row, row]})
    assert text == ("why: '" + 'word ' * 40 + "'\n"
                    'a: [1.0, 2.0]\nb: [1.0, 2.0]\nrows:\n- [1.0, 2.0]\n- [1.0, 2.0]\n')


def test_yaml_writes_small_mappings_deep_down_on_one_line():
    # Three or more levels deep, a mapping of scalars and flat lists takes one line (the 24
    # Euler sequences, a bag topic's counts); above, or holding more, it is a block.
    data = {'a': {'b': {'c': {'x': 1, 'v': [1.0, 2.0]}, 'd': {'e': {'f': 'g'}, 'h': [{}]}},
                  'i': {'j': 1}}}
    assert to_yaml(data) == ('a:\n  b:\n    c: {x: 1, v: [1.0, 2.0]}\n    d:\n'
                             '      e: {f: g}\n      h:\n      - {}\n  i:\n    j: 1\n')
    rep = transform_report(rot_z(0.5), all_sequences=True)
    assert '\n    ZYX: {angles: [0.5, 0.0, 0.0], degenerate: false}\n' in to_yaml(rep)


TRICKY = {
    'floats': [0.0, -1.5, 1e-5, 1e16, 2.0 / 3.0, 1e-300, math.inf, -math.inf],
    'ints': [0, -3, 10 ** 20],
    'flags': [True, False, None],
    'strings': ['ZYX', 'zyx', 'yes', 'No', 'on', 'OFF', 'y', 'n', 'null', '~', 'true', '',
                '1.5', '0x1F', '.inf', '-x', ' lead', 'trail ', 'a: b', 'a #b', '#c', '[x]',
                '{y}', '*a', '&b', '!t', '%p', '@q', '`r', "'s'", '"d"', 'line\nbreak',
                'tab\tin', 'ünïcode θ', '/rot_tools/pose', 'map', 'emoji 😀',
                'C:\\U0001F600', 'a\\\\U0001F600 é', '😀\\U0001F600'],
    'nested': {'empty_list': [], 'empty_dict': {}, 'deep': {'a': {'b': {'c': [1.0, 2.0]}}},
               'rows': [[1.0, 2.0], [3.0, 4.0]], 'records': [{'k': 1, 'v': [0.5]}, {'k': 2}],
               'yes': 'key that YAML 1.1 would read as a bool', '3': 'numeric key'},
    'refused': {'total': 3, 'non-finite': 2, 'bad quaternion': 1},
}


def test_yaml_round_trips_through_pyyaml():
    yaml = pytest.importorskip('yaml')
    assert yaml.safe_load(to_yaml(TRICKY, precision=None)) == TRICKY
    rep = transform_report(R0, B0, all_sequences=True)
    assert yaml.safe_load(to_yaml(rep, precision=None)) == rep
    loaded = yaml.safe_load(to_yaml(rep))
    np.testing.assert_allclose(loaded['matrix'], R0, atol=1e-12)
    assert math.isnan(yaml.safe_load(to_yaml({'x': math.nan}))['x'])


def test_json_round_trips():
    text = to_json(TRICKY, precision=None)
    expected = dict(TRICKY, floats=TRICKY['floats'][:-2] + ['inf', '-inf'])
    assert strict_json(text) == expected
    rep = transform_report(R0, B0, all_sequences=True)
    assert strict_json(to_json(rep, precision=None)) == rep
    assert to_json({'x': [-0.0, math.nan], 'k': {'n': 1}}) == (
        '{\n  "x": [\n    0.0,\n    "nan"\n  ],\n  "k": {\n    "n": 1\n  }\n}\n')


def _numbers_of_json(x):
    """Return JSON data with the strings "inf", "-inf", "nan" read as the floats they mean."""
    if isinstance(x, dict):
        return {k: _numbers_of_json(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_numbers_of_json(v) for v in x]
    return float(x) if x in ('inf', '-inf', 'nan') else x


def _reports():
    rng = np.random.default_rng(12)
    for R, b in zip(Rotation.random(8, random_state=rng).as_matrix(),
                    rng.normal(scale=[1e-9, 1.0, 1e6], size=(8, 3))):
        yield transform_report(R, b, seq='zxz', point=rng.normal(size=3))
        yield transform_report(R, all_sequences=True, degrees=True)
    yield transform_report(np.eye(3), [0.0, 3.0, 4.0])  # screw pitch inf
    yield transform_report(rot_y(math.pi / 2), np.zeros(3))  # gimbal lock, identity screw


@pytest.mark.parametrize('precision', [None, 12, 3])
def test_yaml_and_json_read_back_to_the_same_numbers(precision):
    yaml = pytest.importorskip('yaml')
    for rep in _reports():
        from_yaml = yaml.safe_load(to_yaml(rep, precision))
        from_json = _numbers_of_json(strict_json(to_json(rep, precision)))
        assert from_yaml == from_json
        assert from_yaml['matrix'] == [[round_number(x, precision) for x in row]
                                       for row in rep['matrix']]
        if precision is None:
            assert from_yaml == rep  # full precision: every float exactly


def test_numpy_scalars_are_written_as_python_ones():
    data = {'f': np.float32(0.5), 'i': np.int64(-3), 'b': np.bool_(True), 'g': np.float64(-0.0)}
    assert to_yaml(data) == 'f: 0.5\ni: -3\nb: true\ng: 0.0\n'
    assert strict_json(to_json(data)) == {'f': 0.5, 'i': -3, 'b': True, 'g': 0.0}


def test_writers_refuse_unknown_types():
    with pytest.raises(TypeError, match='ndarray'):
        to_yaml({'m': np.eye(3)})
    with pytest.raises(TypeError, match='ndarray'):
        to_json({'m': np.eye(3)})
    with pytest.raises(TypeError, match='takes a dict'):
        to_yaml([1.0])


def test_cli_and_report_need_no_ros():
    code = 'import sys, rot_tools.cli.main, rot_tools.io.report; print("rclpy" in sys.modules)'
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         check=True, timeout=60).stdout
    assert out.strip() == 'False'


def test_decompose_matches_the_separate_functions():
    # One pass must give exactly what each public function gives, batch and single,
    # including angle π (one axis sign for every field) and a pure translation.
    rng = np.random.default_rng(7)
    R = rt.rotvec_to_matrix(rng.normal(size=(200, 3)))
    R = np.concatenate([R, rt.axis_angle_to_matrix(rng.normal(size=(20, 3)), np.pi),
                        np.eye(3)[None], np.eye(3)[None]])
    b = rng.normal(size=(len(R), 3))
    b[-1] = 0.0
    for seq in ('ZYX', 'zxz'):
        d = rt.decompose(R, b, seq)
        axis, angle = rt.matrix_to_axis_angle(R)
        angles, lock = rt.matrix_to_euler(R, seq)
        screw = rt.screw_from_transform(R, b)
        assert np.array_equal(d.axis, axis) and np.array_equal(d.angle, angle)
        assert np.array_equal(d.euler, angles) and np.array_equal(d.degenerate, lock)
        for got, want in zip(d.screw, screw):
            assert np.array_equal(got, want)
        assert np.array_equal(d.twist, rt.screw_log(R, b))
        for i in (0, 200, len(R) - 2, len(R) - 1):
            one = rt.decompose(R[i], b[i], seq)
            assert np.allclose(one.twist, d.twist[i], rtol=0, atol=1e-15)
            assert np.allclose(one.screw.point, d.screw.point[i], rtol=0, atol=1e-15)
            assert one.degenerate == d.degenerate[i]


def test_decompose_fields_are_the_public_functions_bit_for_bit():
    # Every field of the one pass is what its public function gives, bit for bit.
    rng = np.random.default_rng(8)
    R = np.concatenate([rt.rotvec_to_matrix(rng.normal(size=(20, 3))),
                        rt.axis_angle_to_matrix(rng.normal(size=(5, 3)), np.pi),
                        [rot_z(0.5) @ rot_y(np.pi / 2) @ rot_x(0.2)],  # rpy's gimbal lock
                        [rot_x(0.3) @ rot_y(np.pi / 2) @ rot_z(1.0)],  # XYZ's
                        np.eye(3)[None], np.eye(3)[None]])
    b = rng.normal(size=(len(R), 3))
    b[-1] = 0.0
    for seq in ('ZYX', 'xzx', 'XYZ'):
        for Ri, bi in zip(R, b):
            d = rt.decompose(Ri, bi, seq)
            assert type(d.angle) is np.float64 and type(d.degenerate) is np.bool_
            assert d.rotvec.tobytes() == rt.matrix_to_rotvec(Ri).tobytes()
            angles, lock = rt.matrix_to_euler(Ri, seq)
            assert d.euler.tobytes() == angles.tobytes() and d.degenerate == lock
            assert d.rpy.tobytes() == rt.matrix_to_euler(Ri, RPY_SEQUENCE)[0].tobytes()
            assert d.quaternion.tobytes() == rt.matrix_to_quaternion(Ri).tobytes()
            assert d.twist.tobytes() == rt.screw_log(Ri, bi).tobytes()
        d = rt.decompose(R, b, seq)
        assert d.rotvec.shape == (len(R), 3) and d.quaternion.shape == (len(R), 4)
        assert np.array_equal(d.rotvec, rt.matrix_to_rotvec(R))
        assert np.array_equal(d.rpy, rt.matrix_to_euler(R, RPY_SEQUENCE)[0])
        assert np.array_equal(d.quaternion, rt.matrix_to_quaternion(R))


def test_decompose_refuses_a_screw_beyond_float64():
    with pytest.raises(rt.RotationError, match='the screw overflows float64'):
        rt.decompose(rt.rot_z(1e-10), [1e300, 0.0, 0.0])


def test_decompose_refuses_bad_input():
    with pytest.raises(rt.RotationError, match='reflection'):
        rt.decompose(np.diag([1.0, 1.0, -1.0]), np.zeros(3))
    with pytest.raises(rt.RotationError, match='translation b must be finite'):
        rt.decompose(np.eye(3), [0.0, np.nan, 0.0])
    with pytest.raises(rt.RotationError, match='unknown Euler sequence'):
        rt.decompose(np.eye(3), np.zeros(3), 'ZYx')
