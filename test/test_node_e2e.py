"""End-to-end: rotation_node as a separate process, driven over DDS from this one.

Starts the ``rotation_node`` console script (next to this Python, or on PATH; without an
installed package, ``python -m rot_tools.rotation_node``), publishes to every input,
receives every output, calls both services and a parameter service, then stops it with
SIGTERM or SIGINT: exit status 0 within a second, and no traceback.
"""

import math
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys
import time

from geometry_msgs.msg import PoseStamped, TransformStamped, Vector3Stamped
from nav_msgs.srv import GetPlan
import numpy as np
import pytest
from rclpy.parameter import Parameter
from std_srvs.srv import Trigger
import yaml

from rot_tools import (
    euler_to_matrix, matrix_to_euler, matrix_to_rotvec, quaternion_to_matrix, screw_from_transform,
    screw_log)

ATOL = 1e-12
NODE = '/rot_tools'
STOP_WITHIN = 1.0
"""Seconds from the signal to the exit (SPEC §3: within a second)."""


def node_command():
    """Return the rotation_node console script of this environment, else python -m."""
    here = Path(sys.executable).parent / 'rotation_node'
    script = str(here) if here.exists() else shutil.which('rotation_node')
    return [script] if script else [sys.executable, '-m', 'rot_tools.rotation_node']


class NodeProcess:
    """rotation_node in a child process, its stdout / stderr in files."""

    def __init__(self, tmp_path, *ros_args):
        self.out_path, self.err_path = tmp_path / 'stdout.txt', tmp_path / 'stderr.txt'
        args = node_command() + (['--ros-args', *ros_args] if ros_args else [])
        env = dict(os.environ, PYTHONUNBUFFERED='1')
        if args[0] == sys.executable:  # not installed: run from this checkout
            root = str(Path(__file__).resolve().parents[1])
            env['PYTHONPATH'] = os.pathsep.join(filter(None, [root, env.get('PYTHONPATH')]))
        with open(self.out_path, 'w') as out, open(self.err_path, 'w') as err:
            self.process = subprocess.Popen(args, stdout=out, stderr=err, env=env)

    def stop(self, signum, within=STOP_WITHIN):
        """Send ``signum``; return (exit status, seconds to exit, stderr)."""
        begin = time.monotonic()
        self.process.send_signal(signum)
        try:
            status = self.process.wait(timeout=10.0)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
            pytest.fail(f'rotation_node ignored signal {signum} for 10 s')
        return status, time.monotonic() - begin, self.err_path.read_text()

    def kill(self):
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()


@pytest.fixture
def node_process(tmp_path):
    """Start rotation_node (default name, default parameters); kill it if a test fails."""
    started = []

    def start(*ros_args):
        started.append(NodeProcess(tmp_path, *ros_args))
        return started[-1]

    yield start
    for process in started:
        process.kill()


def pose_stamped(q, p, stamp):
    msg = PoseStamped()
    msg.header.frame_id = 'map'
    msg.header.stamp.sec = stamp
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = map(float, p)
    o = msg.pose.orientation
    o.x, o.y, o.z, o.w = map(float, q)
    return msg


def xyz(v):
    return np.array([v.x, v.y, v.z])


class Remote:
    """The tester's view of the node process: publishers, output subscriptions, services."""

    def __init__(self, tester):
        self.tester = tester
        tester.subscribe_outputs(NODE)
        self.pubs = {name: tester.publisher(f'{NODE}/{name}', msg_type) for name, msg_type in
                     (('pose', PoseStamped), ('euler', Vector3Stamped),
                      ('transform', TransformStamped))}
        tester.wait_matched()
        self.stamp = 0

    def latest(self, name):
        received = self.tester.received[f'{NODE}/{name}']
        return received[-1] if received else None

    def send(self, kind, msg, marker=True):
        """Publish msg until its outputs come back; return {output: message}.

        Inputs are best effort: a first sample can race the node's side of discovery.
        """
        names = ('axis_angle', 'euler_angles', 'screw') + (('screw_axis',) if marker else ())

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
                self.tester.wait_messages(f'{NODE}/rotation_matrix')
                return {n: self.latest(n) for n in names + ('rotation_matrix',)}
        pytest.fail(f'no outputs for {kind} from the node process')


def check_outputs(out, R, b, seq='ZYX', degrees=False):
    np.testing.assert_allclose(np.reshape(out['rotation_matrix'].data, (3, 3)), R,
                               rtol=0, atol=ATOL)
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


def assert_clean_exit(status, seconds, stderr):
    assert status == 0, stderr
    assert 'Traceback' not in stderr and 'KeyboardInterrupt' not in stderr, stderr
    assert seconds < STOP_WITHIN, f'took {seconds:.2f} s to stop'


def test_node_process_end_to_end(tester, node_process):
    process = node_process()
    remote = Remote(tester)

    # Every input, every output.
    q, p = np.array([0.1, -0.5, 0.3, 0.8]), (1.0, 2.0, -0.5)
    q /= np.linalg.norm(q)
    check_outputs(remote.send('pose', pose_stamped(q, p, 0)), quaternion_to_matrix(q),
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
    response = tester.call(Trigger, f'{NODE}/describe', Trigger.Request())
    assert response.success
    report = yaml.safe_load(response.message)
    assert report['source'] == f'{NODE}/transform' and report['frame_id'] == 'map'
    assert report['screw']['point'] == pytest.approx([1.0, 0.0, 0.0], abs=1e-12)
    assert report['axis_angle']['angle'] == pytest.approx(math.pi, rel=1e-11)
    assert report['refused']['total'] == 0

    # ~/screw_path.
    request = GetPlan.Request(start=pose_stamped((0, 0, 0, 1), (0, 0, 0), 1),
                              goal=pose_stamped((0, 0, 1, 0), (0, 0, 2), 2), tolerance=0.0)
    plan = tester.call(GetPlan, f'{NODE}/screw_path', request).plan
    assert len(plan.poses) == 21 and plan.header.frame_id == 'map'
    assert plan.poses[0] == request.start and plan.poses[-1] == request.goal
    assert xyz(plan.poses[10].pose.position) == pytest.approx([0, 0, 1.0], abs=1e-12)

    # A parameter through the parameter service; it applies from the next message.
    results = tester.set_parameters(NODE, [Parameter('angle_unit', value='deg'),
                                           Parameter('marker_scale', value='big')])
    assert [r.successful for r in results] == [True, False]
    euler.vector.x, euler.vector.y, euler.vector.z = 90.0, 0.0, 0.0
    out = remote.send('euler', euler)
    check_outputs(out, euler_to_matrix((math.pi / 2, 0.0, 0.0)), np.zeros(3), degrees=True)

    # Bad input is refused and counted; the node keeps serving.
    remote.pubs['pose'].publish(pose_stamped((0, 0, 0, 0), (0, 0, 0), 999))
    remote.send('pose', pose_stamped((0, 0, 1, 0), (1, 0, 0), 0))
    response = tester.call(Trigger, f'{NODE}/describe', Trigger.Request())
    refused = yaml.safe_load(response.message)['refused']
    assert refused['total'] == refused['zero_quaternion'] <= 1  # best effort: 0 or 1

    assert process.process.poll() is None
    assert_clean_exit(*process.stop(signal.SIGTERM))


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM])
def test_signal_ends_the_node_cleanly(tester, node_process, signum):
    process = node_process()
    remote = Remote(tester)
    remote.send('pose', pose_stamped((0, 0, 1, 0), (1, 0, 0), 0))
    assert_clean_exit(*process.stop(signum))


@pytest.mark.parametrize('override', ['euler_sequence:=QQQ', 'angle_unit:=grad',
                                      'marker_scale:=2', 'marker_scale:=-1.0'])
def test_invalid_start_up_parameter(node_process, override):
    process = node_process('-p', override)
    status = process.process.wait(timeout=20.0)
    stderr = process.err_path.read_text()
    assert status == 2, stderr
    assert 'Traceback' not in stderr, stderr
    assert stderr.startswith('rotation_node: ') and override.split(':=')[0] in stderr
