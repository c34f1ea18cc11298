"""rotation_client as a separate process against rotation_node processes, over DDS.

One node process (a namespace of this run) serves the tests of this module; each runs the
installed ``rotation_client`` script (``python -m rot_tools.rotation_client`` without an
installed package) and reads its stdout, stderr and exit status. Expected values come from
scipy.spatial.transform.Rotation and closed forms, not from rot_tools. The client prints 12
significant digits, so numbers are compared to that.
"""

import json
import math
import signal
import subprocess
import time

from geometry_msgs.msg import QuaternionStamped
import numpy as np
import pytest
from scipy.spatial.transform import Rotation
import yaml

from conftest import console_script, NodeProcess, RUN, script_env

CLIENT = console_script('rotation_client', 'rot_tools.rotation_client')
DIGITS = dict(rel=1e-11, abs=1e-12)
"""Tolerance of a printed number (12 significant digits and decimal places)."""


def run(*args, timeout=60):
    """Run rotation_client with ``args``; return the CompletedProcess (text)."""
    command = CLIENT + [str(a) for a in args]
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout,
                          env=script_env(command), stdin=subprocess.DEVNULL)


def answered(*args):
    """Run rotation_client; return its YAML (or --json) output parsed, after checking it."""
    result = run(*args)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ''
    return json.loads(result.stdout) if '--json' in args else yaml.safe_load(result.stdout)


def one_line_error(result, status):
    """The one stderr line of a failed run, after checking status and output."""
    assert result.returncode == status, (result.stdout, result.stderr)
    assert result.stdout == ''
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith('rotation_client: '), result.stderr
    return lines[0]


@pytest.fixture(scope='module')
def node(tmp_path_factory):
    """A rotation_node process (default parameters) for this module; its name.

    It has accepted one input, so ~/describe always has a report.
    """
    process = NodeProcess(tmp_path_factory.mktemp('client'))
    answered('orientation', 0, 1, 0, 0, '--node', process.name)
    yield process.name
    process.kill()


def approx(values):
    return pytest.approx(np.asarray(values, dtype=float).tolist(), **DIGITS)


def check_answer(answer, rotation, b=(0.0, 0.0, 0.0), drawn=True):
    """The printed answer of the node to an input with rotation ``rotation`` and position b.

    ``drawn``: the node drew this input (nothing else reached it in between), so its
    pictures must be there; else they are checked if they are.
    """
    assert answer['rotation_matrix'] == [approx(row) for row in rotation.as_matrix()]
    q = answer['quaternion']
    assert [q['x'], q['y'], q['z'], q['w']] == approx(rotation.as_quat(canonical=True))
    assert answer['axis_angle'] == approx(rotation.as_rotvec())
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


def test_euler_in_radians_with_options_first(node):
    out = answered('--node', node, '--frame', 'base_link', 'euler', 'ZYX', -0.5, 1e-3, 2.5)
    assert out['input']['frame_id'] == 'base_link'
    check_answer(out['answer'], Rotation.from_euler('ZYX', [-0.5, 1e-3, 2.5]))
    assert out['answer']['euler_angles']['angles'] == approx([-0.5, 1e-3, 2.5])


def test_pose_half_turn_is_a_screw(node):
    """Half a turn about z at (1, 0, 0.5) is a screw along the vertical through (0.5, 0, 0).

    The translation along it is 0.5, so the twist is (0, 0, π; θ·v) with
    v = −l̂ × c + (d/θ)·l̂ = (0, −0.5, 0.5/π).
    """
    out = answered('pose', 1, 0, 0.5, 0, 0, 1, 0, '--node', node)
    assert out['input']['type'] == 'geometry_msgs/msg/PoseStamped'
    assert out['input']['position'] == [1.0, 0.0, 0.5]
    answer = out['answer']
    check_answer(answer, Rotation.from_quat([0, 0, 1, 0]), (1.0, 0.0, 0.5))
    assert answer['quaternion'] == {'x': 0.0, 'y': 0.0, 'z': 1.0, 'w': 0.0}
    assert answer['screw']['linear'] == approx([0.0, -math.pi / 2, 0.5])
    assert answer['screw_axis']['points'] == [approx([0.5, 0, 0]), approx([0.5, 0, 1])]


def test_orientation_as_json(node):
    q = np.array([0.3, -0.1, 0.7, -0.6])
    q /= np.linalg.norm(q)
    out = answered('orientation', *q, '--json', '--node', node)
    assert out['input']['topic'] == f'{node}/orientation'
    assert out['input']['type'] == 'geometry_msgs/msg/QuaternionStamped'
    check_answer(out['answer'], Rotation.from_quat(q))
    assert out['answer']['quaternion']['w'] > 0  # w < 0 was sent: the canonical sign


def test_orientation_identity_has_no_screw_axis(node):
    answer = answered('orientation', 0, 0, 0, 1, '--node', node)['answer']
    check_answer(answer, Rotation.identity())
    assert answer['rotation_matrix'] == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def test_answer_is_matched_among_other_inputs(node, tester):
    """The answer to the client's input, while another publisher streams other orientations.

    Same frame: the outputs are told apart by stamp, the matrix by content.
    """
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


def test_describe_reports_the_input_just_sent(node):
    sent = answered('orientation', 0, 0, math.sin(0.6), math.cos(0.6), '--frame', 'imu_link',
                    '--node', node)['input']
    for report in (answered('describe', '--node', node),
                   answered('describe', '--json', '--node', node)):
        assert report['source'] == f'{node}/orientation'
        assert report['source_type'] == 'geometry_msgs/msg/QuaternionStamped'
        assert report['frame_id'] == 'imu_link' and report['stamp'] == sent['stamp']
        q = report['quaternion']
        assert [q['x'], q['y'], q['z'], q['w']] == approx([0, 0, math.sin(0.6), math.cos(0.6)])
        assert report['euler']['angles'] == approx([1.2, 0.0, 0.0])
        assert 'refused' in report


def test_screw_path(node):
    out = answered('screw-path', 0, 0, 0, 0, 0, 0, 1, 0, 0, 2, 0, 0, 1, 0, '--tolerance', 2.0,
                   '--node', node)
    assert out['service'] == f'{node}/screw_path' and out['frame_id'] == 'map'
    half = math.sqrt(0.5)
    assert out['poses'] == [
        {'position': [0.0, 0.0, 0.0], 'orientation': {'x': 0.0, 'y': 0.0, 'z': 0.0, 'w': 1.0}},
        {'position': approx([0, 0, 1]), 'orientation': {
            'x': 0.0, 'y': 0.0, 'z': pytest.approx(half, **DIGITS),
            'w': pytest.approx(half, **DIGITS)}},
        {'position': [0.0, 0.0, 2.0], 'orientation': {'x': 0.0, 'y': 0.0, 'z': 1.0, 'w': 0.0}}]
    assert len(answered('screw-path', *[0] * 6, 1, 1, *[0] * 5, 1, '--node', node,
                        '--json')['poses']) == 21


@pytest.mark.parametrize('args, reason', [
    (('orientation', 0, 0, 0, 0), 'zero_quaternion'),
    (('orientation', 0, 0, 0, 'inf'), 'non_finite'),
    (('pose', 'nan', 0, 0, 0, 0, 0, 1), 'non_finite'),
    (('pose', 0, 0, 0, 0, 0, 3, 4), 'non_unit_quaternion'),
    (('screw-path', 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1), 'zero_quaternion'),
])
def test_refused_input(node, args, reason):
    before = answered('describe', '--node', node)['refused'][reason]
    line = one_line_error(run(*args, '--node', node), 2)
    assert f'node {node} refused the ' in line and line.endswith(f': {reason}')
    # Counted; the node keeps serving (the next tests send it more).
    assert answered('describe', '--node', node)['refused'][reason] > before


def test_refused_input_before_any_accepted_one(node_process):
    """A fresh node's ~/describe has only its sentence: the reason is read from that."""
    process = node_process()
    line = one_line_error(run('orientation', 0, 0, 0, 0, '--node', process.name), 2)
    assert line == (f'rotation_client: node {process.name} refused the input on '
                    f'{process.name}/orientation: zero_quaternion')
    line = one_line_error(run('describe', '--node', process.name), 1)
    assert line.startswith(f'rotation_client: {process.name}/describe: Nothing has been '
                           'accepted yet on ')
    assert line.endswith('(1 input(s) refused: zero_quaternion 1).')


@pytest.mark.parametrize('sequence, angles, unit', [
    ('xyz', (30.0, 20.0, 10.0), '--deg'),
    ('ZXZ', (0.4, -1.1, 2.9), None),
    ('yxz', (-170.0, 89.9, 45.0), '--deg'),
])
def test_euler_of_another_sequence_is_converted(node, sequence, angles, unit):
    """The node reads ~/euler as ZYX (radians): the same rotation arrives as ZYX angles."""
    out = answered('euler', sequence, *angles, *filter(None, [unit]), '--node', node)
    rotation = Rotation.from_euler(sequence, angles, degrees=unit == '--deg')
    zyx = rotation.as_euler('ZYX')
    assert (out['input']['sequence'], out['input']['unit']) == ('ZYX', 'rad')
    assert out['input']['angles'] == approx(zyx)
    check_answer(out['answer'], rotation)
    assert out['answer']['euler_angles'] == {'sequence': 'ZYX', 'unit': 'rad',
                                             'angles': approx(zyx)}


def test_euler_of_another_sequence_refused_when_not_finite(node):
    line = one_line_error(run('euler', 'xyz', 0, 'nan', 0, '--node', node), 2)
    assert line == (f'rotation_client: node {node} refused the input on {node}/euler: '
                    'non_finite')


def test_unreachable_node(node):
    absent = f'/{RUN}/nobody/rot_tools'
    for args in (('describe',), ('euler', 'ZYX', 1, 2, 3), ('screw-path', *[0] * 14)):
        begin = time.monotonic()
        line = one_line_error(run(*args, '--node', absent, '--timeout', 1.0), 1)
        assert line.startswith(f'rotation_client: cannot reach node {absent}: not found '
                               'within 1 s'), line
        assert time.monotonic() - begin < 30  # bounded (the 1 s wait plus start-up)


def test_unreachable_topic(node_process):
    """The node runs but its ~/pose is remapped away: the client names the topic."""
    process = node_process('-r', f'~/pose:=/{RUN}/elsewhere')
    line = one_line_error(run('pose', 0, 0, 0, 0, 0, 0, 1, '--node', process.name,
                              '--timeout', 2), 1)
    assert line == (f'rotation_client: node {process.name} has no subscription on '
                    f'{process.name}/pose (waited 2 s)')


@pytest.mark.parametrize('args, message', [
    (('euler', 'ZYX', 1, 2), 'euler takes 3 numbers (A1 A2 A3), got 2'),
    (('euler', 'QQQ', 1, 2, 3), "argument SEQ: invalid choice: 'QQQ' (choose from 'XYX'"),
    (('pose', 1, 2, 3, 'x', 0, 0, 1), "not a number: 'x'"),
    (('orientation', 0, 0, 1), 'orientation takes 4 numbers (QX QY QZ QW), got 3'),
    (('screw-path', *[0] * 13), 'screw-path takes 14 numbers'),
    (('describe', '--timeout', '-1'), "--timeout: must be a number > 0, got '-1'"),
    (('describe', '--node', 'bad name'), "not a node name like /ns/name: 'bad name'"),
    (('teleport',), "invalid choice: 'teleport'"),
])
def test_bad_arguments(args, message):
    line = one_line_error(run(*args), 2)
    assert line.startswith('rotation_client: error: ') and message in line


def test_help():
    result = run('--help')
    assert result.returncode == 0 and result.stdout.startswith('usage: rotation_client')
    for command in ('euler', 'pose', 'orientation', 'describe', 'screw-path'):
        assert command in result.stdout
    euler = run('euler', '--help')
    assert euler.returncode == 0
    assert "same\nrotation in the node's euler_sequence and angle_unit" in euler.stdout


def test_interrupt_exits_promptly_and_quietly(tester):
    command = CLIENT + ['describe', '--node', f'/{RUN}/nobody/rot_tools', '--timeout', '60']
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env=script_env(command))
    name = f'rotation_client_{process.pid}'
    # Interrupt it while it waits for discovery: once its node is in the graph.
    tester.spin_until(lambda: name in tester.node.get_node_names(), timeout=30,
                      what=f'node {name}')
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=30)  # well before the 60 s --timeout
    assert process.returncode == 130 and out == '' and err == '', err
