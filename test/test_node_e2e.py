"""rotation_node as a separate process, driven over DDS from this one."""

import math
import os
import re
import shutil
import signal
import tempfile
import time

from conftest import assert_clean_exit, OUTPUTS, REPO, RUN
from geometry_msgs.msg import PoseStamped, TransformStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from nav_msgs.srv import GetPlan
import numpy as np
import pytest
from rcl_interfaces.srv import GetParameters, ListParameters
from rclpy.parameter import Parameter, parameter_value_to_python
from rot_tools import (
    euler_to_matrix, matrix_to_euler, matrix_to_rotvec, quaternion_to_matrix, screw_from_transform,
    screw_log)
from rot_tools.ros.node.rotation_node import PARAMETERS
from scipy.spatial.transform import Rotation
from std_srvs.srv import Trigger
from test_node import pose_stamped, xyz
import yaml

ATOL = 1e-12
PARAMETER_FILE = REPO / 'config' / 'rot_tools.yaml'


class Remote:
    """The tester's view of the node process: publishers, output subscriptions, services."""

    def __init__(self, tester, node, inputs=None):
        self.tester = tester
        self.node = node
        tester.subscribe_outputs(node)
        inputs = inputs or {f'{node}/{name}': msg_type for name, msg_type in (
            ('pose', PoseStamped), ('euler', Vector3Stamped), ('transform', TransformStamped))}
        self.pubs = {topic.rsplit('/', 1)[1]: tester.publisher(topic, msg_type)
                     for topic, msg_type in inputs.items()}
        tester.wait_matched([f'{node}/{name}' for name in OUTPUTS])
        self.stamp = 0

    def latest(self, name):
        received = self.tester.received[f'{self.node}/{name}']
        return received[-1] if received else None

    def describe(self):
        response = self.tester.call(Trigger, f'{self.node}/describe', Trigger.Request())
        assert response.success, response.message
        return yaml.safe_load(response.message)

    def parameters(self, names):
        """{name: value} of the node's parameters, through its ~/get_parameters service."""
        response = self.tester.call(GetParameters, f'{self.node}/get_parameters',
                                    GetParameters.Request(names=list(names)))
        return dict(zip(names, map(parameter_value_to_python, response.values)))

    def send(self, kind, msg, marker=True):
        """Publish msg until its outputs come back (best effort); return {output: message}."""
        names = ('quaternion', 'axis_angle', 'euler_angles', 'screw') + (
            ('screw_axis',) if marker else ())

        def arrived():
            return all(self.latest(n) is not None and self.latest(n).header.stamp.sec ==
                       self.stamp for n in names)
        for _ in range(20):
            self.stamp += 1
            msg.header.stamp.sec = self.stamp
            self.pubs[kind].publish(msg)
            deadline = time.monotonic() + 0.5
            while not arrived() and time.monotonic() < deadline:
                self.tester.spin_once()
            if arrived():
                self.tester.wait_messages(f'{self.node}/rotation_matrix')
                return {n: self.latest(n) for n in names + ('rotation_matrix',)}
        pytest.fail(f'no outputs for {kind} from the node process')


def check_outputs(out, R, b, seq='ZYX', degrees=False):
    np.testing.assert_allclose(np.reshape(out['rotation_matrix'].data, (3, 3)), R,
                               rtol=0, atol=ATOL)
    o = out['quaternion'].quaternion
    np.testing.assert_allclose([o.x, o.y, o.z, o.w],
                               Rotation.from_matrix(R).as_quat(canonical=True), atol=ATOL)
    assert [(d.label, d.size, d.stride) for d in out['rotation_matrix'].layout.dim] == [
        ('rows', 3, 9), ('cols', 3, 3)]
    np.testing.assert_allclose(xyz(out['axis_angle'].vector), matrix_to_rotvec(R), atol=ATOL)
    angles = matrix_to_euler(R, seq)[0]
    np.testing.assert_allclose(xyz(out['euler_angles'].vector),
                               np.degrees(angles) if degrees else angles, rtol=0, atol=1e-10)
    twist = out['screw'].twist
    np.testing.assert_allclose(np.concatenate([xyz(twist.angular), xyz(twist.linear)]),
                               screw_log(R, b), rtol=0, atol=ATOL * 10)
    if 'screw_axis' in out:
        screw = screw_from_transform(R, b)
        points = out['screw_axis'].points
        np.testing.assert_allclose(xyz(points[0]), screw.point, rtol=0, atol=ATOL * 10)
        np.testing.assert_allclose(xyz(points[1]) - xyz(points[0]), screw.direction,
                                   rtol=0, atol=ATOL * 10)
        assert out['screw_axis'].header.frame_id == out['screw'].header.frame_id


def test_node_process_end_to_end(tester, node_process):
    process = node_process()
    node = process.name
    remote = Remote(tester, node)

    # Every input, every output.
    q, p = np.array([0.1, -0.5, 0.3, 0.8]), (1.0, 2.0, -0.5)
    q /= np.linalg.norm(q)
    check_outputs(remote.send('pose', pose_stamped(q, p)), quaternion_to_matrix(q),
                  np.asarray(p))
    euler = Vector3Stamped()
    euler.header.frame_id = 'map'
    euler.vector.x, euler.vector.y, euler.vector.z = 0.5, 0.2, 0.1
    check_outputs(remote.send('euler', euler), euler_to_matrix((0.5, 0.2, 0.1)), np.zeros(3))
    transform = TransformStamped()
    transform.header.frame_id = 'map'
    transform.transform.rotation.z, transform.transform.rotation.w = 1.0, 0.0
    transform.transform.translation.x = 2.0
    out = remote.send('transform', transform)
    check_outputs(out, np.diag([-1.0, -1.0, 1.0]), np.array([2.0, 0.0, 0.0]))
    assert out['screw'].header.frame_id == 'map'

    # ~/describe reports the transform.
    response = tester.call(Trigger, f'{node}/describe', Trigger.Request())
    assert response.success
    report = yaml.safe_load(response.message)
    assert report['source'] == f'{node}/transform' and report['frame_id'] == 'map'
    assert report['screw']['point'] == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)
    assert report['axis_angle']['angle'] == pytest.approx(math.pi, rel=1e-11)
    assert report['refused']['total'] == report['refused']['rodrigues_at_pi'] == 1  # a half turn

    # ~/screw_path.
    request = GetPlan.Request(start=pose_stamped((0, 0, 0, 1), (0, 0, 0), stamp=1),
                              goal=pose_stamped((0, 0, 1, 0), (0, 0, 2), stamp=2), tolerance=0.0)
    plan = tester.call(GetPlan, f'{node}/screw_path', request).plan
    assert len(plan.poses) == 21 and plan.header.frame_id == 'map'
    assert plan.poses[0] == request.start and plan.poses[-1] == request.goal
    assert xyz(plan.poses[10].pose.position) == pytest.approx([0, 0, 1.0], abs=1e-12)

    # A parameter through the parameter service; it applies from the next message.
    results = tester.set_parameters(node, [Parameter('angle_unit', value='deg'),
                                           Parameter('marker_scale', value='big')])
    assert [r.successful for r in results] == [True, False]
    euler.vector.x, euler.vector.y, euler.vector.z = 90.0, 0.0, 0.0
    out = remote.send('euler', euler)
    check_outputs(out, euler_to_matrix((math.pi / 2, 0.0, 0.0)), np.zeros(3), degrees=True)

    # Bad input is refused and counted; the node keeps serving. Inputs are best effort: a
    # sample can be lost, so the bad one is sent until the node has counted it.
    deadline = time.monotonic() + 10.0
    while remote.describe()['refused']['zero_quaternion'] == 0:
        assert time.monotonic() < deadline, 'the zero quaternion was never refused'
        remote.pubs['pose'].publish(pose_stamped((0, 0, 0, 0), (0, 0, 0), stamp=999))
        tester.spin_for(0.2)
    out = remote.send('pose', pose_stamped((0, 0, 0.6, 0.8), (1, 0, 0)))
    check_outputs(out, quaternion_to_matrix((0, 0, 0.6, 0.8)), np.array([1.0, 0.0, 0.0]),
                  degrees=True)
    refused = remote.describe()['refused']
    assert refused['total'] == refused['zero_quaternion'] + refused['rodrigues_at_pi']
    assert refused['zero_quaternion'] >= 1
    assert f'refused input on {node}/pose (zero_quaternion)' in process.err_path.read_text()

    assert process.process.poll() is None
    assert_clean_exit(*process.stop(signal.SIGTERM))


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_signal_ends_the_node_cleanly(tester, node_process, signum):
    process = node_process()
    remote = Remote(tester, process.name)
    remote.send('pose', pose_stamped((0, 0, 1, 0), (1, 0, 0)))
    assert_clean_exit(*process.stop(signum))


@pytest.mark.parametrize('override', ['euler_sequence:=QQQ', 'angle_unit:=grad',
                                      'marker_scale:=true', 'marker_scale:=-1.0',
                                      'marker_scale:=5e-324'])
def test_invalid_start_up_parameter(node_process, override):
    process = node_process('-p', override)
    status = process.process.wait(timeout=20.0)
    stderr = process.err_path.read_text()
    assert status == 2, stderr
    assert 'Traceback' not in stderr, stderr
    assert stderr.startswith('rotation_node: ') and override.split(':=')[0] in stderr


def test_remapped_odometry_in_degrees(tester, node_process):
    """Check that the README's "from a robot" line: -r '~/odometry:=/odom' -p angle_unit:=deg."""
    odom = f'/{RUN}/odom'  # this run's /odom
    process = node_process('-r', f'~/odometry:={odom}', '-p', 'angle_unit:=deg')
    remote = Remote(tester, process.name, {odom: Odometry})
    msg = Odometry()
    msg.header.frame_id, msg.child_frame_id = 'odom', 'base_link'
    q = Rotation.from_euler('ZYX', [135.0, -5.0, 2.5], degrees=True).as_quat()
    o = msg.pose.pose.orientation
    o.x, o.y, o.z, o.w = map(float, q)
    msg.pose.pose.position.x = 1.5
    out = remote.send('odom', msg)
    np.testing.assert_allclose(xyz(out['euler_angles'].vector), [135.0, -5.0, 2.5],
                               rtol=0, atol=1e-12)
    report = remote.describe()
    assert report['source'] == odom and report['source_type'] == 'nav_msgs/msg/Odometry'
    assert f'{process.name}/odometry' not in process.err_path.read_text()  # remapped away
    assert_clean_exit(*process.stop(signal.SIGTERM))


def test_misspelt_parameter_is_warned_about(tester, node_process):
    process = node_process('-p', 'euler_sequnce:=xyz', '-p', 'use_sim_time:=false')
    stderr = process.wait_for_stderr('decomposing')
    (warning,) = [line for line in stderr.splitlines() if 'WARN' in line]
    assert ("parameter override 'euler_sequnce' is not a parameter of this node and is "
            "ignored: did you mean 'euler_sequence'?") in warning
    # It runs, with the default sequence, and the misspelt name is no parameter of it.
    assert Remote(tester, process.name).parameters(['euler_sequence']) == {
        'euler_sequence': 'ZYX'}
    names = tester.call(ListParameters, f'{process.name}/list_parameters',
                        ListParameters.Request()).result.names
    assert 'euler_sequnce' not in names and 'euler_sequence' in names
    assert_clean_exit(*process.stop(signal.SIGINT))


def test_shipped_parameter_file_holds_every_default():
    document = yaml.safe_load(PARAMETER_FILE.read_text())
    assert list(document) == ['/**']
    values = document['/**']['ros__parameters']
    assert values == {name: spec.default for name, spec in PARAMETERS.items()}
    for name, spec in PARAMETERS.items():
        assert type(values[name]) is type(spec.default), name  # 1.0 stays a double, not 1


def test_shipped_parameter_file_names_the_topics_of_each_descriptor():
    """Each parameter's comment in the file and its descriptor name the same ~/topics."""
    comments, lines = {}, []
    for line in PARAMETER_FILE.read_text().splitlines():
        if line.startswith('    #'):
            lines.append(line)
        elif line.startswith('    '):
            comments[line.split(':')[0].strip()] = ' '.join(lines)
            lines = []
    assert list(comments) == list(PARAMETERS)
    for name, spec in PARAMETERS.items():
        topics = set(re.findall(r'~/\w+', spec.descriptor.description))
        assert topics == set(re.findall(r'~/\w+', comments[name])), name
    assert {'~/markers', '~/screw_axis'} <= set(re.findall(r'~/\w+', comments['marker_scale']))


def test_parameter_file_is_applied(tester, node_process, tmp_path):
    shipped = node_process('--params-file', str(PARAMETER_FILE))
    stderr = shipped.wait_for_stderr('decomposing')
    assert 'WARN' not in stderr
    names = list(PARAMETERS)
    assert Remote(tester, shipped.name).parameters(names) == {
        name: spec.default for name, spec in PARAMETERS.items()}
    assert_clean_exit(*shipped.stop(signal.SIGTERM))

    changed = {'euler_sequence': 'xyz', 'angle_unit': 'deg', 'quaternion_tolerance': 0.01,
               'publish_markers': False, 'marker_scale': 2.5, 'input_covariance': 'rpy'}
    edited = tmp_path / 'edited.yaml'
    text = PARAMETER_FILE.read_text()
    for name, value in changed.items():
        default = yaml.safe_dump(PARAMETERS[name].default).split('\n')[0]
        new = yaml.safe_dump(value).split('\n')[0]
        assert f'    {name}: {default}\n' in text
        text = text.replace(f'    {name}: {default}\n', f'    {name}: {new}\n')
    edited.write_text(text)
    process = node_process('--params-file', str(edited))
    remote = Remote(tester, process.name)
    assert remote.parameters(names) == {
        **{name: spec.default for name, spec in PARAMETERS.items()}, **changed}
    euler = Vector3Stamped()
    euler.header.frame_id = 'map'
    euler.vector.x, euler.vector.y, euler.vector.z = 10.0, 20.0, 30.0
    out = remote.send('euler', euler, marker=False)
    R = Rotation.from_euler('xyz', [10.0, 20.0, 30.0], degrees=True).as_matrix()
    np.testing.assert_allclose(np.reshape(out['rotation_matrix'].data, (3, 3)), R,
                               rtol=0, atol=ATOL)
    np.testing.assert_allclose(xyz(out['euler_angles'].vector), [10.0, 20.0, 30.0],
                               rtol=0, atol=1e-12)
    assert tester.received[f'{process.name}/screw_axis'] == []  # publish_markers: false
    assert_clean_exit(*process.stop(signal.SIGTERM))


def test_double_parameters_take_integers_from_a_file_and_from_p(tester, node_process, tmp_path):
    # `marker_scale: 3` in a YAML file and -p marker_scale:=2 are integers to rclpy; they
    # stopped the node at start-up ("expecting type 'DOUBLE'").
    edited = tmp_path / 'integers.yaml'
    text = PARAMETER_FILE.read_text()
    assert '    marker_scale: 1.0\n' in text
    edited.write_text(text.replace('    marker_scale: 1.0\n', '    marker_scale: 3\n'))
    runs = [(node_process('--params-file', str(edited)),
             {'marker_scale': 3.0, 'quaternion_tolerance': 0.001}),
            (node_process('-p', 'marker_scale:=2', '-p', 'quaternion_tolerance:=0'),
             {'marker_scale': 2.0, 'quaternion_tolerance': 0.0})]
    for process, expected in runs:
        assert 'WARN' not in process.wait_for_stderr('decomposing')
        response = tester.call(GetParameters, f'{process.name}/get_parameters',
                               GetParameters.Request(names=list(expected)))
        assert [value.type for value in response.values] == [Parameter.Type.DOUBLE.value] * 2
        assert dict(zip(expected, map(parameter_value_to_python, response.values))) == expected
        assert_clean_exit(*process.stop(signal.SIGINT))


def test_a_remap_the_shell_expanded_is_warned_about(node_process):
    """-r ~/imu:=/x typed unquoted reaches the node as -r $HOME/imu:=/x: one warning line."""
    # (a ROS name holds neither '-' nor '__': mkdtemp's random part may make either)
    home = os.path.join(tempfile.gettempdir(), f'{RUN}_home')
    os.makedirs(home, exist_ok=True)
    try:
        process = node_process('-r', f'{home}/imu:=/x', '-r', '~/pose:=/y',
                               env_extra={'HOME': home})
        stderr = process.wait_for_stderr('decomposing')
    finally:
        shutil.rmtree(home, ignore_errors=True)
    (warning,) = [line for line in stderr.splitlines() if 'WARN' in line]
    assert warning.endswith(
        f'remap -r {home}/imu:=/x starts with the home directory {home}: the shell expanded '
        "an unquoted ~; quote it: -r '~/imu:=/x'")
    assert_clean_exit(*process.stop(signal.SIGINT))


@pytest.mark.parametrize('argv, found', [
    (['p', '--ros-args', '-r', '/home/u/imu:=/x', '--remap', '/home/u:=/y'],
     ['/home/u/imu:=/x', '/home/u:=/y']),
    (['p', '--ros-args', '-r', '~/imu:=/x', '-r', '/home/user/imu:=/x', '-p', '/home/u/a:=1'],
     []),
    (['p', '-r', '/home/u/imu:=/x', '--ros-args', '--', '-r', '/home/u/imu:=/x'], []),
])
def test_home_remaps(argv, found):
    from rot_tools.ros.node.runtime import home_remaps
    assert home_remaps(argv, '/home/u/') == found


FAST_DDS_PROFILE = REPO / 'config' / 'fastdds_profile.xml'


def test_the_opt_in_fast_dds_profile_is_read_whole_with_the_users_two_settings(
        tester, node_process):
    """Check that the shipped profile turns on as doc/node.md says, and the node runs under it."""
    page = (REPO / 'doc' / 'node.md').read_text(encoding='utf-8')
    for setting in ('FASTRTPS_DEFAULT_PROFILES_FILE=', 'RMW_FASTRTPS_USE_QOS_FROM_XML=1'):
        assert f'export {setting}' in page
    process = node_process(env_extra={'FASTRTPS_DEFAULT_PROFILES_FILE': str(FAST_DDS_PROFILE),
                                      'RMW_FASTRTPS_USE_QOS_FROM_XML': '1'})
    remote = Remote(tester, process.name)
    out = remote.send('pose', pose_stamped((0, 0, 1, 0), (1, 0, 0)))
    check_outputs(out, quaternion_to_matrix((0, 0, 1, 0)), np.array([1.0, 0.0, 0.0]))
    assert_clean_exit(*process.stop(signal.SIGINT))
    logs = process.out_path.read_text() + process.err_path.read_text()  # (Fast DDS: stdout)
    assert 'XMLPARSER' not in logs
