"""
rotation_client's tools around the inputs: the angle hint, echo, set and tf-demo.

Against a rotation_node process of this run (conftest's isolated domain and namespaces), over
DDS: the commands run in this process (test_client.Here) where what is tested is the
command, as a process where it is the process (a stream printed as it comes, Ctrl-C, a closed
pipe, a module that does not import); expected values come from closed forms and scipy, not
from rot_tools.
"""

import json
import math
import re
import subprocess
import sys
import threading

from conftest import DISCOVERY_TIMEOUT, NodeProcess, REPO, RUN, script_env
from doc_blocks import assert_doc_output
import pytest
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from scipy.spatial.transform import Rotation
from test_client import approx, DIGITS, Here, interrupt, one_line_error, popen
import yaml

HINT = ('rotation_client: hint: an angle of 30 rad is more than 2π: if it is in degrees, '
        'add --deg\n')


@pytest.fixture(scope='module')
def here(ros_context):
    """Run rotation_client's commands in this process (test_client.Here)."""
    return Here(ros_context)


@pytest.fixture(scope='module')
def node(tmp_path_factory, here):
    """Return the name of a rotation_node process (default parameters) for this module."""
    process = NodeProcess(tmp_path_factory.mktemp('tools'))
    here.answered('orientation', 0, 0, 0, 1, '--node', process.name, '--timeout', 20)
    yield process.name
    process.kill()


def wait_subscribed(tester, topic):
    """Wait until something (the client under test) subscribes to ``topic``."""
    tester.spin_until(lambda: tester.node.count_subscribers(topic) > 0, DISCOVERY_TIMEOUT,
                      f'a subscription on {topic}')


# ---------------------------------------------------------------------------------------
# The angle hint


@pytest.mark.parametrize('args, hint', [
    (('ZYX', 30, 20, 10), HINT),
    (('xyz', 10, -30, 20), HINT),
    (('ZYX', 30, 20, 10, '--deg'), ''),
    (('ZYX', 6.2, -6.2, 1), ''),
])
def test_angle_hint(here, node, args, hint):
    """Radians typed beyond 2π: one hint line on stderr after the answer, status 0."""
    result = here('euler', *args, '--node', node)
    assert result.returncode == 0 and result.stderr == hint, result.stderr
    assert yaml.safe_load(result.stdout)['answer']['euler_angles']['unit'] == 'rad'


# ---------------------------------------------------------------------------------------
# echo


def test_echo_once_prints_the_answer(here, node, tester):
    echo = popen('echo', 'rpy', '--once', '--json', '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/rpy')
    sent = here.answered('orientation', 0, math.sin(0.2), 0, math.cos(0.2), '--node', node)
    out, err = echo.communicate(timeout=60)
    assert echo.returncode == 0 and err == '', err
    data = json.loads(out)
    assert data['frame_id'] == 'map' and set(data) == {'stamp', 'frame_id', 'rpy'}
    assert data['stamp']['sec'] >= sent['input']['stamp']['sec']
    assert data['rpy'] == {'roll': 0.0, 'pitch': pytest.approx(0.4, **DIGITS), 'yaw': 0.0,
                           'unit': 'rad'}


def test_echo_count_prints_each_message(here, node, tester):
    echo = popen('echo', 'quaternion', '--count', 3, '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/quaternion')
    for angle in (0.1, 0.2, 0.3):
        here.answered('euler', 'ZYX', angle, 0, 0, '--node', node)
    out, err = echo.communicate(timeout=60)
    assert echo.returncode == 0 and err == '', err
    documents = list(yaml.safe_load_all(out))
    assert len(documents) == 3
    # Each input is sent until answered, so one may come twice; the last is the last sent.
    assert documents[-1]['quaternion'] == {'x': 0.0, 'y': 0.0, 'z': approx(math.sin(0.15)),
                                           'w': approx(math.cos(0.15))}


def test_echo_into_a_pipe_closed_early_ends_quietly(node, tester):
    """rotation_client echo rpy | head -1: status 141 (SIGPIPE's), no traceback."""
    from geometry_msgs.msg import QuaternionStamped
    from rclpy.qos import qos_profile_sensor_data
    echo = popen('echo', 'rpy', '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/rpy')
    pub = tester.publisher(f'{node}/orientation', QuaternionStamped,
                           qos_profile_sensor_data)
    msg = QuaternionStamped()
    msg.header.frame_id, msg.quaternion.w = 'map', 1.0

    def publish_until(done):
        for _ in range(200):
            if done():
                return
            msg.header.stamp.sec += 1
            pub.publish(msg)
            tester.spin_for(0.05)

    first = []
    reader = threading.Thread(target=lambda: first.append(echo.stdout.readline()), daemon=True)
    reader.start()
    publish_until(lambda: first)
    reader.join(timeout=30)
    assert first == ['---\n']
    echo.stdout.close()  # as head does once it has its lines
    publish_until(lambda: echo.poll() is not None)
    err = echo.stderr.read()
    assert (echo.wait(timeout=30), err) == (141, '')


def test_echo_unknown_output_and_unreachable(here, node):
    line = one_line_error(here('echo', 'nothing'), 2)
    assert "argument OUTPUT: invalid choice: 'nothing'" in line
    line = one_line_error(here('echo', 'rpy', '--count', '0'), 2)
    assert "--count: must be a whole number >= 1, got '0'" in line
    absent = f'/{RUN}/nobody/rot_tools'
    line = one_line_error(here('echo', 'rpy', '--node', absent, '--timeout', 1), 1)
    assert line.startswith(f'rotation_client: cannot reach node {absent}')


# ---------------------------------------------------------------------------------------
# set


def set_line(result):
    assert result.returncode == 0 and result.stderr == '', result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) == 1
    return lines[0]


@pytest.fixture
def restored(node, tester):
    """Return the module's node; its parameters set back to their defaults after the test."""
    from rclpy.parameter import Parameter
    yield node
    defaults = {'angle_unit': 'rad', 'euler_sequence': 'ZYX',
                'quaternion_tolerance': QUATERNION_TOLERANCE, 'publish_markers': True}
    results = tester.set_parameters(node, [Parameter(name, value=value)
                                           for name, value in defaults.items()])
    assert all(result.successful for result in results)


def test_set_types_values_as_the_node_declares_them(here, restored):
    name = restored
    assert set_line(here('set', 'angle_unit', 'deg', '--node', name)) == (
        f"node {name}: angle_unit = 'deg'")
    # An integer for a double, digits for a string, 'false' for a bool; 1e-2, which YAML (and
    # so ros2 param set) reads as a string, for a double.
    assert set_line(here('set', 'quaternion_tolerance', '1', '--node', name)) == (
        f'node {name}: quaternion_tolerance = 1.0')
    assert set_line(here('set', 'quaternion_tolerance', '1e-2', '--node', name)) == (
        f'node {name}: quaternion_tolerance = 0.01')
    assert here('param', 'get', 'quaternion_tolerance', '--node', name).stdout == (
        'Double value is: 0.01\n')
    assert set_line(here('set', 'euler_sequence', 'xyz', '--node', name)) == (
        f"node {name}: euler_sequence = 'xyz'")
    assert set_line(here('set', 'publish_markers', 'false', '--node', name)) == (
        f'node {name}: publish_markers = False')
    answer = here.answered('euler', 'xyz', 90, 0, 0, '--deg', '--node', name)
    assert answer['input']['unit'] == 'deg' and answer['input']['sequence'] == 'xyz'
    assert answer['answer']['euler_angles']['angles'] == approx([90, 0, 0])
    assert 'markers' not in answer['answer']


@pytest.mark.parametrize('args, why', [
    (('angle_unit', 'degrees'), "node {node} refused angle_unit = 'degrees': angle_unit "
     "'degrees' is not 'rad' or 'deg'"),
    (('quaternion_tolerance', '-1'), 'node {node} refused quaternion_tolerance = -1.0: '
     'Parameter quaternion_tolerance out of range'),
    (('nothing', '1'), "node {node} has no parameter 'nothing'"),
])
def test_set_refused_is_the_nodes_reason(here, node, args, why):
    line = one_line_error(here('set', *args, '--node', node), 1)
    assert line.startswith('rotation_client: ' + why.format(node=node)), line


@pytest.mark.parametrize('args, why', [
    (('quaternion_tolerance', 'abc'), "'abc' is not a number"),
    (('quaternion_tolerance', 'true'), "'true' is not a number"),
    (('publish_markers', '1'), "'1' is not true or false"),
    (('publish_markers', 'maybe'), "'maybe' is not true or false"),
])
def test_set_a_value_that_does_not_fit_the_type(here, node, args, why):
    """One line naming the parameter's type, exit 2; nothing is sent."""
    kind = 'double' if args[0] == 'quaternion_tolerance' else 'boolean'
    line = one_line_error(here('set', *args, '--node', node), 2)
    assert line == (f'rotation_client: parameter {args[0]} of node {node} is a {kind}: {why}')


# ---------------------------------------------------------------------------------------
# param get / list


def test_param_get_prints_as_ros2_param_get(here, node):
    from rot_tools.io.boundary import QUATERNION_TOLERANCE
    lines = {name: here('param', 'get', name, '--node', node)
             for name in ('quaternion_tolerance', 'angle_unit', 'publish_markers')}
    assert {name: (r.returncode, r.stdout, r.stderr) for name, r in lines.items()} == {
        'quaternion_tolerance': (0, f'Double value is: {QUATERNION_TOLERANCE}\n', ''),
        'angle_unit': (0, 'String value is: rad\n', ''),
        'publish_markers': (0, 'Boolean value is: True\n', '')}
    hidden = here('param', 'get', 'marker_scale', '--hide-type', '--node', node)
    assert (hidden.returncode, hidden.stdout) == (0, '1.0\n')
    assert here.answered('--json', 'param', 'get', 'euler_sequence', '--node', node) == {
        'name': 'euler_sequence', 'type': 'string', 'value': 'ZYX'}
    line = one_line_error(here('param', 'get', 'nothing', '--node', node), 1)
    assert line == f"rotation_client: node {node} has no parameter 'nothing'"


def test_param_list_prints_as_ros2_param_list(here, node):
    """Every parameter of the node (rclpy's own too), sorted, indented by two spaces."""
    from rot_tools.ros.rotation_node import PARAMETERS, RCLPY_PARAMETERS
    names = sorted([*PARAMETERS, *RCLPY_PARAMETERS])
    result = here('param', 'list', '--node', node)
    assert (result.returncode, result.stderr) == (0, '')
    assert result.stdout == ''.join(f'  {name}\n' for name in names)
    typed = here('param', 'list', '--param-type', '--node', node).stdout.splitlines()
    assert [line.split(' (type: ')[0] for line in typed] == [f'  {name}' for name in names]
    assert '  quaternion_tolerance (type: double)' in typed
    assert '  publish_markers (type: boolean)' in typed
    assert here.answered('param', 'list', '--json', '--node', node) == names
    absent = f'/{RUN}/nobody/rot_tools'
    line = one_line_error(here('param', 'list', '--node', absent, '--timeout', 1), 1)
    assert line.startswith(f'rotation_client: cannot reach node {absent}: not found')


@pytest.mark.parametrize('args, message', [
    (('param',), 'the following arguments are required: VERB'),
    (('param', 'get'), 'the following arguments are required: NAME'),
    (('param', 'set', 'x', '1'), "argument VERB: invalid choice: 'set'"),
    (('param', 'list', 'x'), 'unrecognized arguments: x'),
])
def test_param_bad_arguments(here, args, message):
    line = one_line_error(here(*args), 2)
    assert line.startswith('rotation_client: error: ') and message in line, line


# ---------------------------------------------------------------------------------------
# tf-demo


def remapped(namespace):
    """Return the ROS arguments that move /tf and /tf_static into ``namespace``."""
    return ('--ros-args', '-r', f'/tf:={namespace}/tf',
            '-r', f'/tf_static:={namespace}/tf_static')


def test_tf_demo_publishes_the_tree(here, tester, namespace):
    from rot_tools.ros.tf_input import TF_QOS, TF_STATIC_QOS
    from tf2_msgs.msg import TFMessage
    tester.subscribe(f'{namespace}/tf', TFMessage, TF_QOS)
    tester.subscribe(f'{namespace}/tf_static', TFMessage, TF_STATIC_QOS)
    demo = popen('tf-demo', *remapped(namespace))
    try:
        line = demo.stdout.readline()
        assert line == (f'publishing map -> odom -> base_link -> camera on {namespace}/tf and '
                        f'{namespace}/tf_static until Ctrl-C\n')
        static = tester.wait_messages(f'{namespace}/tf_static', 1, DISCOVERY_TIMEOUT)[0]
        edges = {(t.header.frame_id, t.child_frame_id): t.transform for t in static.transforms}
        camera = edges['base_link', 'camera']
        q = camera.rotation
        assert Rotation.from_quat([q.x, q.y, q.z, q.w]).as_euler('ZYX', degrees=True) == approx(
            [0, 15, 0])
        assert set(edges) == {('map', 'odom'), ('base_link', 'camera')}
        moving = tester.wait_messages(f'{namespace}/tf', 5, DISCOVERY_TIMEOUT)
        for msg in moving:
            (t,) = msg.transforms
            assert (t.header.frame_id, t.child_frame_id) == ('odom', 'base_link')
            q, b = t.transform.rotation, t.transform.translation
            yaw = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_euler('ZYX')[0]
            # On the circle of radius 1 about (0, 1, 0), facing along it.
            assert [b.x, b.y, b.z] == pytest.approx([math.sin(yaw), 1 - math.cos(yaw), 0],
                                                    abs=1e-12)
        result = here('tf', 'map', 'camera', '--once', '--deg', '--timeout', 20,
                      *remapped(namespace))
        assert result.returncode == 0, result.stderr
        report = yaml.safe_load(result.stdout)
        assert report['chain'] == ['map', 'odom', 'base_link', 'camera']
        assert (report['rpy']['roll'], report['rpy']['pitch']) == (0.0, 15.0)
        command = "rotation_client tf map camera --once --deg | sed -n '1,3p;/^rpy:/,/pitch:/p'"
        lines = result.stdout.splitlines(keepends=True)
        rpy = lines.index('rpy:\n')
        assert_doc_output('readme-tf', ('$ rotation_client tf-demo &\n' + line).replace(
            namespace, '') + f'$ {command}\n' + ''.join(lines[:3] + lines[rpy:rpy + 3]))
    finally:
        stopped = interrupt(demo)
    assert stopped == (130, '', '')


def test_tf_demo_for_a_duration(here, namespace):
    result = here('tf-demo', '--duration', 1, *remapped(namespace))
    assert result.returncode == 0 and result.stderr == '', result.stderr
    assert result.stdout.endswith(f'{namespace}/tf_static for 1 s\n')


def test_tf_demo_without_tf2_msgs():
    """One line and exit 1 when tf2_msgs does not import."""
    probe = (
        'import sys\n'
        'class Refuse:\n'
        '    def find_spec(self, name, path=None, target=None):\n'
        "        if name.split('.')[0] == 'tf2_msgs':\n"
        "            raise ImportError('refused: ' + name)\n"
        'sys.meta_path.insert(0, Refuse())\n'
        'from rot_tools.ros.rotation_client import main\n'
        "sys.exit(main(['tf-demo']))\n")
    command = [sys.executable, '-c', probe]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60,
                            env=script_env(command), cwd=REPO)
    assert result.returncode == 1 and result.stdout == ''
    assert result.stderr.count('\n') == 1
    assert result.stderr.startswith('rotation_client: tf2_msgs is not importable'), (
        result.stderr)


# ---------------------------------------------------------------------------------------
# Ctrl-C


def test_echo_interrupted_exits_130_quietly(here, node, tester):
    echo = popen('echo', 'rpy', '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/rpy')
    here.answered('orientation', 0, 0, 0, 1, '--node', node)
    tester.spin_for(0.2)
    status, out, err = interrupt(echo)
    assert (status, err) == (130, '')
    assert out.startswith('---\n')


# ---------------------------------------------------------------------------------------
# doc/client.md's examples of echo and set


def test_doc_examples(here, node, tester):
    shown = (node, '/rot_tools')
    echo = popen('echo', 'rpy', '--once', '--node', node, '--timeout', 20)
    wait_subscribed(tester, f'{node}/rpy')
    here.answered('pose', 1, 0, 0.5, 0, 0, 1, 0, '--node', node)
    out, err = echo.communicate(timeout=60)
    assert echo.returncode == 0, err
    text = '$ rotation_client echo rpy --once\n' + out
    assert_doc_output('client-echo', _stamps_elided(text))
    lines = []
    for args in (('set', 'angle_unit', 'deg'), ('set', 'angle_unit', 'degrees'),
                 ('euler', 'ZYX', 30, 20, 10)):
        result = here(*args, '--node', node)
        lines.append(f'$ rotation_client {" ".join(map(str, args))}'
                     + (' > /dev/null' if args[0] == 'euler' else '') + '\n')
        lines.append(('' if args[0] == 'euler' else result.stdout) + result.stderr)
        if result.returncode:
            lines.append(f'$ echo $?\n{result.returncode}\n')
    here('set', 'angle_unit', 'rad', '--node', node)
    assert_doc_output('client-set', ''.join(lines).replace(*shown))


def _stamps_elided(text):
    return re.sub(r'(\n\s*sec: )\d+(\n\s*nanosec: )\d+', r'\1...\2...', text)
