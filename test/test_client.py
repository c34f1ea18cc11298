"""
rotation_client against a rotation_node process, over DDS: in this process, and as a process.

Most commands run here (:class:`Here`); what only a process shows runs the installed script.
Expected values come from scipy's Rotation and closed forms, to the printed 12 digits.
"""

from collections import Counter
from contextlib import redirect_stderr, redirect_stdout
import io
import json
import math
from pathlib import Path
import signal
import string
import subprocess
import sys
import time
from typing import NamedTuple

from conftest import console_script, DISCOVERY_TIMEOUT, NodeProcess, REPO, RUN, script_env
from conftest import STOP_WITHIN
from doc_blocks import assert_doc_output
from geometry_msgs.msg import QuaternionStamped
import numpy as np
import pytest
from rot_tools.core.euler import RPY_SEQUENCE
from scipy.spatial.transform import Rotation
from test_node_covariance import expected_covariance
import yaml

CLIENT = console_script('rotation_client', 'rot_tools.ros.client.rotation_client')
DIGITS = {'rel': 1e-11, 'abs': 1e-12}
"""Tolerance of a printed number (12 significant digits and decimal places)."""


def run(*args, timeout=60, **env):
    """Run rotation_client as a process (``env`` added); return the CompletedProcess, as text."""
    command = CLIENT + [str(a) for a in args]
    return subprocess.run(command, capture_output=True, encoding='utf-8', timeout=timeout,
                          env=dict(script_env(command), **env), stdin=subprocess.DEVNULL)


def parsed(result, args):
    """Return a run's YAML (or --json) output parsed, after checking status and stderr."""
    assert result.returncode == 0, result.stderr
    assert result.stderr == ''
    return json.loads(result.stdout) if '--json' in args else yaml.safe_load(result.stdout)


def answered(*args, **env):
    """Run rotation_client as a process; return its output parsed (:func:`parsed`)."""
    return parsed(run(*args, **env), args)


class Result(NamedTuple):
    """What a command run in this process did: as subprocess.CompletedProcess names it."""

    returncode: int
    stdout: str
    stderr: str


class Here:
    """rotation_client's commands run in this process, in one rclpy context; ``here(*args)``."""

    def __init__(self, context):
        self.context = context
        self.client = None

    def close(self):
        """Destroy the Client's node."""
        if self.client is not None:
            self.client.close()

    def __call__(self, *args):
        from rot_tools.ros.client.arguments import parse_args
        from rclpy.signals import uninstall_signal_handlers
        from rot_tools.ros.client.session import Client
        from rot_tools.ros.client.rotation_client import main, run_command
        words = [str(a) for a in args]
        out, err = io.StringIO(), io.StringIO()
        with redirect_stdout(out), redirect_stderr(err):
            try:
                if '--ros-args' in words:
                    try:
                        status = main(words)
                    finally:
                        uninstall_signal_handlers()
                else:
                    args = parse_args(words)
                    if self.client is None:
                        self.client = Client(args.node, args.timeout, self.context)
                    status = run_command(args, self.context, self.client)
            except SystemExit as exc:  # the parser: --help, --version, bad arguments
                status = exc.code
        return Result(status, out.getvalue(), err.getvalue())

    def answered(self, *args):
        """Run a command here; return its output parsed (:func:`parsed`)."""
        return parsed(self(*args), args)


def one_line_error(result, status):
    """Return the one stderr line of a failed run, after checking status and output."""
    assert result.returncode == status, (result.stdout, result.stderr)
    assert result.stdout == ''
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith('rotation_client: '), result.stderr
    return lines[0]


@pytest.fixture(scope='module')
def node(tmp_path_factory, here):
    """Return the name of this module's rotation_node process; it has accepted one input."""
    process = NodeProcess(tmp_path_factory.mktemp('client'))
    here.answered('orientation', 0, 1, 0, 0, '--node', process.name, '--timeout', 20)
    yield process.name
    process.kill()


def approx(values):
    return pytest.approx(np.asarray(values, dtype=float).tolist(), **DIGITS)


def check_answer(answer, rotation, b=(0.0, 0.0, 0.0), drawn=True):
    """Check an answer to ``rotation`` and b; ``drawn``: its markers must be there."""
    assert answer['rotation_matrix'] == [approx(row) for row in rotation.as_matrix()]
    q = answer['quaternion']
    assert [q['x'], q['y'], q['z'], q['w']] == approx(rotation.as_quat(canonical=True))
    assert answer['axis_angle'] == approx(rotation.as_rotvec())
    roll, pitch, yaw = rotation.as_euler(RPY_SEQUENCE)  # REP 103: about the fixed x, y, z
    assert answer['rpy'] == {'roll': pytest.approx(roll, **DIGITS),
                             'pitch': pytest.approx(pitch, **DIGITS),
                             'yaw': pytest.approx(yaw, **DIGITS), 'unit': 'rad'}
    assert answer['screw']['angular'] == approx(rotation.as_rotvec())
    if not drawn and 'markers' not in answer:
        assert 'screw_axis' not in answer
        return
    ids = [m['id'] for m in answer['markers']]
    assert ids == [0, 1, 2, 3, 4, 5]
    if any(b) or rotation.magnitude() > 0:
        assert answer['screw_axis']['type'] == 'ARROW'
        assert answer['screw_axis']['action'] == 'ADD'
        tail, tip = answer['screw_axis']['points']
        direction = np.subtract(tip, tail)
        assert np.linalg.norm(direction) == pytest.approx(1.0, abs=1e-11)
        assert answer['markers'][0] == {'id': 0, 'action': 'ADD', 'type': 'ARROW'}
    else:  # the identity: nothing to draw, so the last picture is deleted
        assert answer['screw_axis'] == {'id': 0, 'action': 'DELETE'}
        assert {m['action'] for m in answer['markers']} == {'DELETE'}


def test_euler_in_degrees(node):
    out = answered('euler', 'ZYX', 30, 20, 10, '--deg', '--node', node)
    rotation = Rotation.from_euler('ZYX', [30, 20, 10], degrees=True)
    assert out['node'] == node
    sent = out['input']
    assert sent['topic'] == f'{node}/euler'
    assert sent['type'] == 'geometry_msgs/msg/Vector3Stamped' and sent['frame_id'] == 'map'
    assert (sent['sequence'], sent['unit']) == ('ZYX', 'rad')  # the node's unit: converted
    assert sent['angles'] == approx(np.radians([30, 20, 10]))
    answer = out['answer']
    check_answer(answer, rotation)
    assert answer['euler_angles'] == {'sequence': 'ZYX', 'unit': 'rad',
                                      'angles': approx(np.radians([30, 20, 10]))}
    assert answer['screw']['linear'] == [0.0, 0.0, 0.0]
    # the screw axis of a pure rotation passes through the origin, along the rotation vector
    tail, tip = answer['screw_axis']['points']
    assert tail == [0.0, 0.0, 0.0]
    rotvec = rotation.as_rotvec()
    assert tip == approx(rotvec / np.linalg.norm(rotvec))


def test_euler_in_radians_with_options_first(here, node):
    out = here.answered('--node', node, '--frame', 'base_link', 'euler', 'ZYX', -0.5, 1e-3, 2.5)
    assert out['input']['frame_id'] == 'base_link'
    check_answer(out['answer'], Rotation.from_euler('ZYX', [-0.5, 1e-3, 2.5]))
    assert out['answer']['euler_angles']['angles'] == approx([-0.5, 1e-3, 2.5])


def test_pose_half_turn_is_a_screw(here, node):
    """
    Half a turn about z at (1, 0, 0.5) is a screw along the vertical through (0.5, 0, 0).

    The translation along it is 0.5, so the twist is (0, 0, π; θ·v) with
    v = −l̂ × c + (d/θ)·l̂ = (0, −0.5, 0.5/π).
    """
    out = here.answered('pose', 1, 0, 0.5, 0, 0, 1, 0, '--node', node)
    assert out['input']['type'] == 'geometry_msgs/msg/PoseStamped'
    assert out['input']['position'] == [1.0, 0.0, 0.5]
    answer = out['answer']
    check_answer(answer, Rotation.from_quat([0, 0, 1, 0]), (1.0, 0.0, 0.5))
    assert answer['quaternion'] == {'x': 0.0, 'y': 0.0, 'z': 1.0, 'w': 0.0}
    assert answer['screw']['linear'] == approx([0.0, -math.pi / 2, 0.5])
    assert answer['screw_axis']['points'] == [approx([0.5, 0, 0]), approx([0.5, 0, 1])]


def test_orientation_as_json(here, node):
    q = np.array([0.3, -0.1, 0.7, -0.6])
    q /= np.linalg.norm(q)
    out = here.answered('orientation', *q, '--json', '--node', node)
    assert out['input']['topic'] == f'{node}/orientation'
    assert out['input']['type'] == 'geometry_msgs/msg/QuaternionStamped'
    check_answer(out['answer'], Rotation.from_quat(q))
    assert out['answer']['quaternion']['w'] > 0  # w < 0 was sent: the canonical sign


def test_orientation_identity_has_no_screw_axis(here, node):
    answer = here.answered('orientation', 0, 0, 0, 1, '--node', node)['answer']
    check_answer(answer, Rotation.identity())
    assert answer['rotation_matrix'] == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


@pytest.mark.parametrize('verb, topic_type', [
    ('pose', 'geometry_msgs/msg/PoseStamped'),
    ('odometry', 'nav_msgs/msg/Odometry'),
    ('transform', 'geometry_msgs/msg/TransformStamped'),
])
def test_pose_like_verbs(here, node, verb, topic_type):
    """pose, odometry and transform send X Y Z QX QY QZ QW; --wxyz reads QW QX QY QZ."""
    q = np.array([-0.2, 0.5, 0.1, 0.8])
    q /= np.linalg.norm(q)
    b = [0.5, -2.0, 1.5]
    out = here.answered(verb, *b, *q, '--frame', 'odom', '--node', node)
    wxyz = here.answered(verb, *b, q[3], *q[:3], '--wxyz', '--frame', 'odom', '--node', node)
    for sent in (out['input'], wxyz['input']):
        assert sent['topic'] == f'{node}/{verb}' and sent['type'] == topic_type
        assert sent['frame_id'] == 'odom'
        position, orientation = ('translation', 'rotation') if verb == 'transform' else (
            'position', 'orientation')
        assert sent[position] == approx(b)
        o = sent[orientation]
        assert [o['x'], o['y'], o['z'], o['w']] == approx(q)  # w last, however given
        if verb != 'pose':
            assert sent['child_frame_id'] == 'base_link'
    rotation = Rotation.from_quat(q)
    for answer in (out['answer'], wxyz['answer']):
        check_answer(answer, rotation, b)
        # the screw's translation along its axis: d = l̂ · b
        axis = rotation.as_rotvec() / rotation.magnitude()
        assert answer['screw']['linear'] @ axis == pytest.approx(axis @ b, **DIGITS)


def test_odometry_child_frame(here, node):
    out = here.answered('odometry', 0, 0, 0, 0, 0, 0, 1, '--child-frame', 'robot', '--node', node)
    assert out['input']['child_frame_id'] == 'robot'


@pytest.mark.parametrize('verb, topic_type', [
    ('orientation', 'geometry_msgs/msg/QuaternionStamped'),
    ('imu', 'sensor_msgs/msg/Imu'),
])
def test_orientation_like_verbs(here, node, verb, topic_type):
    """Test that orientation and imu send QX QY QZ QW; --wxyz reads QW QX QY QZ."""
    q = np.array([0.6, -0.3, 0.2, -0.7])
    q /= np.linalg.norm(q)
    out = here.answered(verb, *q, '--node', node)
    wxyz = here.answered('--wxyz', verb, q[3], *q[:3], '--node', node)
    key = 'quaternion' if verb == 'orientation' else 'orientation'
    for sent in (out['input'], wxyz['input']):
        assert sent['topic'] == f'{node}/{verb}' and sent['type'] == topic_type
        o = sent[key]
        assert [o['x'], o['y'], o['z'], o['w']] == approx(q)
    for answer in (out['answer'], wxyz['answer']):
        check_answer(answer, Rotation.from_quat(q))
        assert answer['screw']['linear'] == [0.0, 0.0, 0.0]


def test_screw_path_wxyz(here, node):
    """--wxyz reads both quaternions of screw-path w first."""
    xyzw = here.answered('screw-path', 0, 0, 0, 0, 0, 0, 1, 0, 0, 2, 0, 0, 1, 0, '--node', node)
    wxyz = here.answered('screw-path', 0, 0, 0, 1, 0, 0, 0, 0, 0, 2, 0, 0, 0, 1, '--wxyz',
                         '--node', node)
    assert wxyz['poses'] == xyzw['poses'] and len(wxyz['poses']) == 21
    assert wxyz['poses'][-1]['orientation'] == {'x': 0.0, 'y': 0.0, 'z': 1.0, 'w': 0.0}


def test_answer_is_matched_among_other_inputs(node, tester):
    """Check the answer to the client's input, while another publisher streams others."""
    pub = tester.publisher(f'{node}/orientation', QuaternionStamped)
    rng = np.random.default_rng(5)
    command = CLIENT + ['euler', 'ZYX', '0.1', '-0.2', '0.3', '--node', node]
    client = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                              text=True, env=script_env(command))
    sent = 0
    while client.poll() is None:
        msg = QuaternionStamped()
        msg.header.frame_id = 'map'
        msg.header.stamp.sec = sent
        q = rng.normal(size=4)
        o = msg.quaternion
        o.x, o.y, o.z, o.w = q / np.linalg.norm(q)
        pub.publish(msg)
        sent += 1
        tester.spin_for(0.01)
    out, err = client.communicate(timeout=30)
    assert client.returncode == 0, err
    assert sent > 20  # the stream really ran alongside
    answer = yaml.safe_load(out)['answer']
    # The node throttles its pictures, the latest input winning: maybe it did not draw ours.
    check_answer(answer, Rotation.from_euler('ZYX', [0.1, -0.2, 0.3]), drawn=False)
    assert answer['euler_angles']['angles'] == approx([0.1, -0.2, 0.3])


def test_describe_reports_the_input_just_sent(here, node):
    sent = here.answered('orientation', 0, 0, math.sin(0.6), math.cos(0.6),
                         '--frame', 'imu_link', '--node', node)['input']
    for report in (here.answered('describe', '--node', node),
                   here.answered('describe', '--json', '--node', node)):
        assert report['source'] == f'{node}/orientation'
        assert report['source_type'] == 'geometry_msgs/msg/QuaternionStamped'
        assert report['frame_id'] == 'imu_link' and report['stamp'] == sent['stamp']
        q = report['quaternion']
        assert [q['x'], q['y'], q['z'], q['w']] == approx([0, 0, math.sin(0.6), math.cos(0.6)])
        assert report['euler']['angles'] == approx([1.2, 0.0, 0.0])
        assert 'refused' in report


COV = np.array([[4e-4, 1e-4, 0.0], [1e-4, 2e-4, -5e-5], [0.0, -5e-5, 1e-4]])
"""A rotation's covariance (rad²) given to --cov."""


@pytest.mark.parametrize('verb, position', [('imu', ()), ('odometry', (1.0, -2.0, 0.5))])
def test_cov_is_sent_and_the_rpy_covariance_printed(here, node, verb, position):
    q = Rotation.from_euler('xyz', [0.2, -0.4, 1.0]).as_quat()
    out = here.answered(verb, *position, *q, '--cov', *COV.ravel(), '--node', node)
    sent = np.asarray(out['input']['orientation_covariance' if verb == 'imu' else 'covariance'])
    np.testing.assert_array_equal(sent[-3:, -3:], COV)
    assert not sent[:-3].any() and not sent[:, :-3].any()  # a pose's other terms: 0
    printed = out['answer']['rpy_covariance']
    assert printed['position'] == list(position or (0.0, 0.0, 0.0))
    assert [printed['orientation'][k] for k in 'xyzw'] == approx(q)
    expected = expected_covariance(q, sent)
    np.testing.assert_allclose(printed['covariance'], expected, rtol=0,
                               atol=1e-9 * np.abs(expected).max())
    unknown = here.answered(verb, *position, *q, '--cov', *[0] * 9, '--node', node)
    assert unknown['answer']['rpy_covariance'] == 'unknown'


def send_until(done, send, tries=40):
    """Call send() until done(), waiting half a second after each; fail after ``tries``."""
    for _ in range(tries):
        send()
        deadline = time.monotonic() + 0.5
        while not done() and time.monotonic() < deadline:
            time.sleep(0.01)
        if done():
            return
    pytest.fail(f'not done after {tries} sends')


def test_echo_rpy_covariance(here, node, tester):
    """Check doc/client.md's example: facing +Y, an error about the fixed X axis is pitch."""
    command = CLIENT + ['echo', 'rpy_covariance', '--once', '--node', node, '--timeout', '20']
    echo = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=script_env(command), stdin=subprocess.DEVNULL)
    topic = f'{node}/rpy_covariance'
    tester.spin_until(lambda: tester.node.count_subscribers(topic) > 0, DISCOVERY_TIMEOUT,
                      f'a subscription on {topic}')
    send_until(lambda: echo.poll() is not None, lambda: here.answered(
        *'imu 0 0 0.7071068 0.7071068 --frame imu_link --cov'.split(), *COV.ravel(),
        '--node', node))
    out, err = echo.communicate(timeout=60)
    assert (echo.returncode, err) == (0, '')
    assert_doc_output('client-covariance', '$ rotation_client echo rpy_covariance --once\n'
                      + out)
    data = yaml.safe_load(out)
    assert data['frame_id'] == 'imu_link'
    printed = data['rpy_covariance']
    assert printed['position'] == [0.0, 0.0, 0.0]
    assert printed['orientation'] == {'x': 0.0, 'y': 0.0, 'z': 0.7071068, 'w': 0.7071068}
    turn = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])  # E⁻¹ at yaw 90°
    np.testing.assert_allclose(np.asarray(printed['covariance'])[3:, 3:],
                               turn @ COV @ turn.T, rtol=0, atol=1e-12)
    assert not np.asarray(printed['covariance'])[:3].any()


def test_frame_id_beyond_ascii_round_trips(here, node):
    """
    Check that an emoji (beyond U+FFFF) and an accent in frame_id: sent, reported, printed as such.

    On an ASCII stdout, as escapes that YAML and JSON read back to the same characters.
    """
    frame = 'caméra_😀'
    sent = here.answered('orientation', 0, 0, 0, 1, '--frame', frame, '--node', node)
    assert sent['input']['frame_id'] == frame
    for args in (('describe',), ('describe', '--json')):
        for result in (here(*args, '--node', node),
                       run(*args, '--node', node, PYTHONIOENCODING='ascii')):
            assert result.returncode == 0 and result.stderr == '', result.stderr
            report = (json.loads if '--json' in args else yaml.safe_load)(result.stdout)
            assert report['frame_id'] == frame and report['stamp'] == sent['input']['stamp']
            assert (frame in result.stdout) != result.stdout.isascii()


def test_screw_path(here, node):
    out = here.answered('screw-path', 0, 0, 0, 0, 0, 0, 1, 0, 0, 2, 0, 0, 1, 0,
                        '--tolerance', 2.0, '--node', node)
    assert out['service'] == f'{node}/screw_path' and out['frame_id'] == 'map'
    half = math.sqrt(0.5)
    assert out['poses'] == [
        {'position': [0.0, 0.0, 0.0], 'orientation': {'x': 0.0, 'y': 0.0, 'z': 0.0, 'w': 1.0}},
        {'position': approx([0, 0, 1]), 'orientation': {
            'x': 0.0, 'y': 0.0, 'z': pytest.approx(half, **DIGITS),
            'w': pytest.approx(half, **DIGITS)}},
        {'position': [0.0, 0.0, 2.0], 'orientation': {'x': 0.0, 'y': 0.0, 'z': 1.0, 'w': 0.0}}]
    assert len(here.answered('screw-path', *[0] * 6, 1, 1, *[0] * 5, 1, '--node', node,
                             '--json')['poses']) == 21


REFUSED = [
    (('orientation', 0, 0, 0, 0), 'input on {node}/orientation: quaternion is the zero '
     'quaternion (zero_quaternion)'),
    (('orientation', 0, 0, 0, 'inf'), 'input on {node}/orientation: quaternion.w is inf '
     '(non_finite)'),
    (('pose', 'nan', 0, 0, 0, 0, 0, 1), 'input on {node}/pose: pose.position.x is nan '
     '(non_finite)'),
    (('orientation', 0, 0, 0.5, 0.5), 'input on {node}/orientation: quaternion has norm '
     '0.707106781, off 1 by 0.293 > quaternion_tolerance 0.001 (non_unit_quaternion)'),
    (('imu', 0, 0, 0, 2), 'input on {node}/imu: orientation has norm 2, off 1 by 1 > '
     'quaternion_tolerance 0.001 (non_unit_quaternion)'),
    (('transform', 0, 'inf', 0, 0, 0, 0, 1), 'input on {node}/transform: '
     'transform.translation.y is inf (non_finite)'),
    (('odometry', 0, 0, 0, 1, 0, 0, 1, '--wxyz'), 'input on {node}/odometry: '
     'pose.pose.orientation has norm 1.41421356, off 1 by 0.414 > quaternion_tolerance 0.001 '
     '(non_unit_quaternion)'),
    (('screw-path', 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1), 'screw_path request: '
     'start.pose.orientation is the zero quaternion (zero_quaternion)'),
    (('screw-path', -1e308, 0, 0, 0, 0, 0, 1, 1e308, 0, 0, 0, 0, 0, 1), 'screw_path '
     'request: start and goal are too far apart: goal.position − start.position overflows '
     'float64 (beyond ±1.8e308) (not_decomposable)'),
    (('screw-path', *[0] * 6, 1, 1, 0, 0, *[0] * 3, 1, '--tolerance', 1e-6), 'screw_path '
     'request: tolerance 1e-06 needs 1e+06 steps, more than 10000 (path_too_long)'),
    (('imu', 0, 0, 0, 1, '--cov', 1, 0, 0, 0, 1, 0, 0, 0, -1), 'covariance sent to '
     '{node}/imu: orientation_covariance is not positive semi-definite: its lowest eigenvalue '
     'is -1, below -1e-09·max|C| = -1e-09 (bad_covariance)'),
]
"""Inputs the node refuses, and the end of the client's line: the node's sentence, the reason."""


def test_refused_input(here, node):
    """Each is one line, the node's sentence; the node counts its reason and keeps serving."""
    reasons = Counter(why.rpartition('(')[2].rstrip(')') for _, why in REFUSED)
    before = here.answered('describe', '--node', node)['refused']
    for args, why in REFUSED:
        line = one_line_error(here(*args, '--node', node), 2)
        assert line == f'rotation_client: node {node} refused the ' + why.format(node=node)
    after = here.answered('describe', '--node', node)['refused']
    # (A refused input may be sent again before the client reads the count: at least once.)
    assert {r: after[r] - before.get(r, 0) >= n for r, n in reasons.items()} == dict.fromkeys(
        reasons, True)


@pytest.mark.parametrize('sequence, angles, unit', [
    ('xyz', (30.0, 20.0, 10.0), '--deg'),
    ('ZXZ', (0.4, -1.1, 2.9), None),
    ('yxz', (-170.0, 89.9, 45.0), '--deg'),
])
def test_euler_of_another_sequence_is_converted(here, node, sequence, angles, unit):
    """Check that the node reads ~/euler as ZYX (radians): the same rotation arrives."""
    out = here.answered('euler', sequence, *angles, *filter(None, [unit]), '--node', node)
    rotation = Rotation.from_euler(sequence, angles, degrees=unit == '--deg')
    zyx = rotation.as_euler('ZYX')
    assert (out['input']['sequence'], out['input']['unit']) == ('ZYX', 'rad')
    assert out['input']['angles'] == approx(zyx)
    check_answer(out['answer'], rotation)
    assert out['answer']['euler_angles'] == {'sequence': 'ZYX', 'unit': 'rad',
                                             'angles': approx(zyx)}


def test_euler_of_another_sequence_refused_when_not_finite(here, node):
    line = one_line_error(here('euler', 'xyz', 0, 'nan', 0, '--node', node), 2)
    assert line == (f'rotation_client: node {node} refused the input on {node}/euler: '
                    'vector.y is nan (non_finite)')


def test_unreachable_node(here, node):
    absent = f'/{RUN}/nobody/rot_tools'
    for args in (('describe',), ('euler', 'ZYX', 1, 2, 3), ('screw-path', *[0] * 14)):
        begin = time.monotonic()
        line = one_line_error(here(*args, '--node', absent, '--timeout', 1.0), 1)
        assert line.startswith(f'rotation_client: cannot reach node {absent}: not found '
                               'within 1 s'), line
        assert time.monotonic() - begin < 30  # bounded (the 1 s wait plus start-up)


def test_a_fresh_and_remapped_node(here, node_process):
    """Check a node whose ~/pose and ~/imu are remapped, from its start (describe, --topic)."""
    remapped = f'/{RUN}/robot/imu/data'
    process = node_process('-r', f'~/pose:=/{RUN}/elsewhere', '-r', f'~/imu:={remapped}')
    name = process.name
    # Once it runs (on a loaded machine its start-up alone can take the client's timeout).
    process.wait_for_stderr('decomposing ')
    line = one_line_error(here('orientation', 0, 0, 0, 0, '--node', name, '--timeout', 20), 2)
    assert line == (f'rotation_client: node {name} refused the input on {name}/orientation: '
                    'quaternion is the zero quaternion (zero_quaternion)')
    line = one_line_error(here('describe', '--node', name), 1)
    assert line.startswith(f'rotation_client: {name}/describe: Nothing has been accepted yet '
                           'on ')
    assert line.endswith('(1 input refused).')
    line = one_line_error(here('pose', 0, 0, 0, 0, 0, 0, 1, '--node', name, '--timeout', 2), 1)
    assert line == (f'rotation_client: node {name} has no subscription on {name}/pose '
                    '(waited 2 s)')
    q = [0.0, 0.0, math.sin(0.3), math.cos(0.3)]
    out = here.answered('imu', *q, '--topic', remapped, '--node', name)
    assert out['input']['topic'] == remapped
    assert out['answer']['axis_angle'] == approx([0.0, 0.0, 0.6])
    # A refusal of what was sent there is the node's sentence (matched by source).
    line = one_line_error(here('imu', 0, 0, 0, 0, '--topic', remapped, '--node', name), 2)
    assert line == (f'rotation_client: node {name} refused the input on {remapped}: '
                    'orientation is the zero quaternion (zero_quaternion)')
    # Remapped by the client's own ROS arguments: the topic printed is the one used.
    out = here.answered('imu', *q, '--node', name, '--ros-args', '-r', f'{name}/imu:={remapped}')
    assert out['input']['topic'] == remapped


@pytest.mark.parametrize('args, message', [
    (('euler', 'ZYX', 1, 2), 'euler takes 3 numbers (A1 A2 A3), got 2'),
    (('euler', 'QQQ', 1, 2, 3), "argument SEQ: unknown Euler sequence 'QQQ': use one of the 12"),
    (('pose', 1, 2, 3, 'x', 0, 0, 1), "not a number: 'x'"),
    (('orientation', 0, 0, 1), 'orientation takes 4 numbers (QX QY QZ QW), got 3'),
    (('screw-path', *[0] * 13), 'screw-path takes 14 numbers'),
    (('describe', '--timeout', '-1'), "--timeout: must be a number > 0, got '-1'"),
    (('describe', '--timeout', '0'), "--timeout: must be a number > 0, got '0'"),
    (('describe', '--timeout', 'nan'), "--timeout: must be a number > 0, got 'nan'"),
    (('euler', 'ZYX', 1, 2, 3, 4), 'euler takes 3 numbers (A1 A2 A3), got 4'),
    (('pose', *[0] * 8), 'pose takes 7 numbers (X Y Z QX QY QZ QW), got 8'),
    (('odometry', *[0] * 8), 'odometry takes 7 numbers (X Y Z QX QY QZ QW), got 8'),
    (('transform', *[0] * 6), 'transform takes 7 numbers (X Y Z QX QY QZ QW), got 6'),
    (('orientation', *[0] * 5), 'orientation takes 4 numbers (QX QY QZ QW), got 5'),
    (('imu', *[0] * 5), 'imu takes 4 numbers (QX QY QZ QW), got 5'),
    (('imu', 0, 0, 0, 1, '--cov', 1, 2), 'argument --cov: expected 9 arguments'),
    (('pose', *[0] * 7, '--cov', *[0] * 9), 'unrecognized arguments: --cov'),
    (('screw-path', *[0] * 15), 'screw-path takes 14 numbers'),
    (('screw-path', *[0] * 14, '--tolerance', '1e-300'),
     'argument --tolerance: 1e-300 is below the smallest float32, 1.4e-45: the request '
     'carries a float32, so the node would read 0 (the default 20 steps)'),
    (('screw-path', *[0] * 14, '--tolerance', '1e39'),
     'argument --tolerance: 1e39 is above the largest float32, 3.403e+38: the request '
     'carries a float32, so the node would read inf (one step)'),
    (('euler', 'ZYX', 1, 2, 3, '--wxyz'), 'unrecognized arguments: --wxyz'),
    (('--wxyz', 'describe'), '--wxyz: describe takes no quaternion'),
    (('describe', '--node', '/' + 'n' * 239),
     'argument --node: node name of 240 characters is too long'),
    (('describe', '--node', 'bad name'), "not a node name like /ns/name: 'bad name'"),
    (('teleport',), "invalid choice: 'teleport'"),
])
def test_bad_arguments(here, args, message):
    line = one_line_error(here(*args), 2)
    assert line.startswith('rotation_client: error: ') and message in line


@pytest.mark.parametrize('tolerance, poses', [
    ('3.4e38', 2), ('-1e-300', 21), ('-1e39', 21), ('2e-45', 'path_too_long')])
def test_tolerances_float32_keeps_are_sent(here, node, tolerance, poses):
    """Tolerances whose meaning float32 keeps are sent as given (its largest, -0, -inf, tiny)."""
    path = ('screw-path', *[0] * 6, 1, 1, 0, 0, *[0] * 3, 1, '--tolerance', tolerance,
            '--node', node)
    if poses == 'path_too_long':
        assert one_line_error(here(*path), 2).endswith(
            'refused the screw_path request: tolerance 1.4013e-45 needs 7.14e+44 steps, more '
            'than 10000 (path_too_long)')
    else:
        assert len(here.answered(*path)['poses']) == poses


@pytest.mark.parametrize('ros_args, message', [
    (('--ros-args', '-p', 'foo'), "'-p foo'"),
    (('--ros-args', '-r', 'bad'), "'-r bad'"),
    (('--ros-args', '--params-file', '/nonexistent.yaml'), '/nonexistent.yaml'),
    (('--ros-args', '--no-such-flag'), '--no-such-flag'),
])
def test_bad_ros_arguments(here, capfd, ros_args, message):
    """Bad ROS arguments are one line and exit 2, before anything is started."""
    line = one_line_error(here('describe', *ros_args), 2)
    assert message in line and 'Traceback' not in line, line
    assert capfd.readouterr() == ('', '')  # nothing else, rcl's own log line included


def test_version(here):
    """--version prints the installed version and exits 0 without importing rclpy."""
    from importlib.metadata import version
    expected = f'rotation_client {version("rot_tools")}\n'
    result = here('--version')
    assert (result.returncode, result.stdout, result.stderr) == (0, expected, '')
    probe = (
        'import sys\n'
        'class RefuseRos:\n'
        '    def find_spec(self, name, path=None, target=None):\n'
        "        if name.split('.')[0] in ('rclpy', 'rosidl_parser', 'std_srvs'):\n"
        "            raise ImportError('refused: ' + name)\n"
        'sys.meta_path.insert(0, RefuseRos())\n'
        'from rot_tools.ros.client.rotation_client import main\n'
        "main(['--version', '--ros-args', '-p', 'foo'])\n")
    command = [sys.executable, '-c', probe]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60,
                            env=script_env(command), cwd=REPO)
    assert (result.returncode, result.stdout, result.stderr) == (0, expected, '')


def test_help(here):
    result = here('--help')
    assert result.returncode == 0 and result.stdout.startswith('usage: rotation_client')
    for command in ('euler', 'pose', 'odometry', 'transform', 'orientation', 'imu',
                    'describe', 'screw-path', 'param', 'play', '--wxyz', '--version'):
        assert command in result.stdout
    euler = here('euler', '--help')
    assert euler.returncode == 0
    assert "same\nrotation in the node's euler_sequence and angle_unit" in euler.stdout


def popen(*args):
    """Start rotation_client with ``args`` in a session of its own (see :func:`interrupt`)."""
    command = CLIENT + [str(a) for a in args]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env=script_env(command), stdin=subprocess.DEVNULL,
                            start_new_session=True)


def _session(sid):
    """Return the pids of the processes still in session ``sid`` (zombies included)."""
    pids = []
    for stat in Path('/proc').glob('[0-9]*/stat'):
        try:
            fields = stat.read_text().rsplit(')', 1)[1].split()
        except OSError:  # ended meanwhile
            continue
        if int(fields[3]) == sid:
            pids.append(int(stat.parent.name))
    return pids


def interrupt(process):
    """SIGINT a client of :func:`popen`; check a clean end, none of its session left; return it."""
    process.send_signal(signal.SIGINT)
    try:
        process.wait(timeout=STOP_WITHIN)
    except subprocess.TimeoutExpired:
        process.kill()
        pytest.fail(f'the client still ran {STOP_WITHIN:g} s after SIGINT')
    left = [p for p in _session(process.pid) if p != process.pid]
    out, err = process.communicate(timeout=30)
    assert 'Traceback' not in err, err
    assert left == [], f'processes left of the client: {left}'
    return process.returncode, out, err


def test_interrupt_exits_promptly_and_quietly(tester):
    process = popen('describe', '--node', f'/{RUN}/nobody/rot_tools', '--timeout', '60')
    name = f'rotation_client_{process.pid}'
    # Interrupt it while it waits for discovery: once its node is in the graph.
    tester.spin_until(lambda: name in tester.node.get_node_names(), timeout=30,
                      what=f'node {name}')
    assert interrupt(process) == (130, '', '')


# doc/client.md's examples are this output


def console(here, *commands, names=()):
    """Return the transcript of ``commands``, each (shown, extra), as doc/client.md shows it."""
    lines = []
    for shown, extra in commands:
        result = here(*shown.split(), *extra)
        lines.append(f'$ rotation_client {shown}\n{result.stdout}{result.stderr}')
        if result.returncode:
            lines.append(f'$ echo $?\n{result.returncode}\n')
    text = ''.join(lines)
    for real, doc in names:
        text = text.replace(real, doc)
    return text


def test_doc_examples(here, node):
    shown = (node, '/rot_tools')
    assert_doc_output('client-euler', console(
        here, ('euler ZYX 30 20 10 --deg', ('--node', node)), names=[shown]))
    assert_doc_output('client-screw-path', console(
        here, ('screw-path 0 0 0 0 0 0 1  0 0 2 0 0 1 0 --tolerance 2.0', ('--node', node)),
        names=[shown]))
    absent = f'/{RUN}/arm/rot_tools'
    assert_doc_output('client-errors', console(
        here, ('orientation 0 0 0 0', ('--node', node)),
        ('pose 1 2 3 0 0 0.5 0.5', ('--node', node)),
        ('describe --node /arm/rot_tools --timeout 2', ('--node', absent)),
        ('screw-path 0 0 0 0 0 0 1  0 0 2 0 0 1 0 --tolerance 1e-300', ()),
        names=[shown, (absent, '/arm/rot_tools')]))


# The node's sentence on refusal, from ~/describe's data


def test_refusal_text_uses_the_nodes_sentence():
    from rot_tools.ros.client.session import refusal_text
    topic = '/rot_tools/orientation'
    data = {'refused': {'total': 3, 'non_finite': 1, 'non_unit_quaternion': 2},
            'last_refusals': {
                'non_finite': {'source': '/rot_tools/pose', 'stamp': {'sec': 5, 'nanosec': 0},
                               'message': 'pose.position.x is nan'},
                'non_unit_quaternion': {
                    'source': topic, 'stamp': {'sec': 7, 'nanosec': 9},
                    'message': 'orientation has norm 0.707, off 1 by 0.293 > '
                               'quaternion_tolerance 0.001'}}}
    sentence = ('orientation has norm 0.707, off 1 by 0.293 > quaternion_tolerance 0.001 '
                '(non_unit_quaternion)')
    # Counted since: the sentence when the refusal is of what was sent (source, stamp).
    assert refusal_text(data, {'non_unit_quaternion': 1, 'non_finite': 1}, topic,
                        {(7, 9)}) == sentence
    assert refusal_text(data, {'non_unit_quaternion': 1, 'non_finite': 1}, topic) == sentence
    # Not counted since: nothing.
    assert refusal_text(data, {'non_unit_quaternion': 2, 'non_finite': 1}, topic) == ''
    # Another message refused last for that reason: the reason's name, never its sentence.
    assert refusal_text(data, {'non_unit_quaternion': 1, 'non_finite': 1}, topic, {(7, 8)}) == (
        'non_unit_quaternion')
    assert refusal_text(data, {}, topic, {(7, 9)}) == f'non_finite; {sentence}'
    assert refusal_text(data, {'non_unit_quaternion': 2}, topic) == 'non_finite'
    # A node without last_refusals: the reasons' names.
    del data['last_refusals']
    assert refusal_text(data, {}, topic) == 'non_finite; non_unit_quaternion'


# Text beyond ASCII in the reports (rot_tools.io.report's YAML and JSON strings)


def must_escape(c):
    """Characters YAML 1.1 does not allow printed, its line breaks, and the byte order mark."""
    o = ord(c)
    printable = (0x20 <= o <= 0x7e or 0xa0 <= o <= 0xd7ff or 0xe000 <= o <= 0xfffd
                 or o >= 0x10000)
    return not printable or c in '\u2028\u2029\ufeff'


@pytest.mark.parametrize('text', [
    'caméra_😀', '𝄞 ∮ ŋ ü', 'nbsp\xa0', 'tab\t, newline\n, cr\r',
    'nul\x00 bel\x07 esc\x1b del\x7f', 'c1\x85\x9f', 'ls\u2028 ps\u2029', 'bom\ufeff',
    '\ufffe\uffff', 'lone \ud83d and \ude00', 'quote " backslash \\'])
def test_report_strings_round_trip(text):
    """Every string reads back the same from the YAML and the JSON report (PyYAML, json)."""
    from rot_tools.io.report import to_json, to_yaml
    data = {'frame_id': text, text: [text]}
    yaml_text, json_text = to_yaml(data), to_json(data)
    assert yaml.safe_load(yaml_text) == data
    assert json.loads(json_text) == data
    for written in (yaml_text, json_text):
        written.encode('utf-8')  # no lone surrogate left
        # (not the newline: it also ends the YAML and JSON lines)
        for c in set(text) - set(' "\\\n') - set(string.ascii_letters + string.digits):
            assert (c in written) != must_escape(c), (c, written)


def test_every_input_of_the_node_has_a_verb():
    """The client fills each input's message by name: a new input needs its verb."""
    from rot_tools.io import interface
    from rot_tools.ros.client.arguments import INPUTS
    assert set(INPUTS) == {row.name for row in interface.INPUTS}
