"""launch/rot_tools.launch.xml: checked against the package, and run as ros2 launch would."""

from pathlib import Path
import re
import signal
import subprocess
import time
import xml.etree.ElementTree as ElementTree

from conftest import console_script, RUN, script_env, TIMEOUT
from geometry_msgs.msg import Vector3Stamped
import numpy as np
import pytest
from rcl_interfaces.srv import GetParameters
from rclpy.parameter import parameter_value_to_python
from rclpy.qos import qos_profile_sensor_data
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import Imu

REPO = Path(__file__).resolve().parents[1]
LAUNCH_FILE = REPO / 'launch' / 'rot_tools.launch.xml'
PACKAGE = 'rot_tools'

_SUBSTITUTION = re.compile(r'\$\((?P<kind>[a-z-]+) (?P<name>[^)]+)\)')


def _substitute(text, args, share):
    def value(match):
        if match['kind'] == 'var':
            return args[match['name']]
        if match['kind'] == 'find-pkg-share' and match['name'] == PACKAGE:
            return str(share)
        pytest.fail(f'substitution {match[0]} is not understood by this test')
    result = _SUBSTITUTION.sub(value, text)
    assert '$(' not in result, f'unknown substitution in {text!r}'
    return result


def _allowed(element, attributes):
    unknown = set(element.attrib) - set(attributes)
    assert not unknown, f'<{element.tag}> attributes {unknown} are not understood by this test'


def launch_command(overrides=None, share=REPO):
    """(pkg, exec, ros_args) of the file's one node, as launch_ros builds it from the file."""
    root = ElementTree.parse(LAUNCH_FILE).getroot()
    assert root.tag == 'launch'
    args, node = {}, None
    for element in root:
        if element.tag == 'arg':
            _allowed(element, ('name', 'default', 'description'))
            args[element.get('name')] = _substitute(element.get('default'), args, share)
        elif element.tag == 'node':
            assert node is None, 'one node'
            node = element
        else:
            pytest.fail(f'<{element.tag}> is not understood by this test')
    unknown = set(overrides or {}) - set(args)
    assert not unknown, f'no launch arguments {unknown}'
    args.update(overrides or {})
    _allowed(node, ('pkg', 'exec', 'name', 'namespace', 'output'))
    namespace = _substitute(node.get('namespace', ''), args, share)
    ros_args = ['--ros-args', '-r', f"__node:={_substitute(node.get('name'), args, share)}",
                '-r', '__ns:=' + (namespace if namespace.startswith('/') else '/' + namespace)]
    for element in node:
        if element.tag == 'param':
            _allowed(element, ('from',))
            ros_args += ['--params-file', _substitute(element.get('from'), args, share)]
        elif element.tag == 'remap':
            _allowed(element, ('from', 'to'))
            to = _substitute(element.get('to'), args, share)
            ros_args += ['-r', f"{element.get('from')}:={to}"]
        else:
            pytest.fail(f'<node> child <{element.tag}> is not understood by this test')
    return node.get('pkg'), node.get('exec'), ros_args


def setup_keywords():
    """Return the keyword arguments setup.py gives setuptools.setup (setup() captured)."""
    import setuptools
    captured = {}
    real = setuptools.setup
    setuptools.setup = captured.update
    try:
        code = compile((REPO / 'setup.py').read_text(), str(REPO / 'setup.py'), 'exec')
        exec(code, {'__name__': '__main__', '__file__': str(REPO / 'setup.py')})
    finally:
        setuptools.setup = real
    return captured


def test_the_launch_file_runs_this_package_s_node_with_the_shipped_parameter_file():
    from catkin_pkg.package import parse_package
    from rot_tools.io.interface import INPUTS
    pkg, executable, ros_args = launch_command()
    assert pkg == parse_package(str(REPO / 'package.xml')).name == PACKAGE
    scripts = dict(entry.split(' = ') for entry in
                   setup_keywords()['entry_points']['console_scripts'])
    assert scripts[executable] == 'rot_tools.ros.node.rotation_node:main'
    (params_file,) = [ros_args[i + 1] for i, a in enumerate(ros_args) if a == '--params-file']
    assert Path(params_file) == REPO / 'config' / 'rot_tools.yaml'
    remaps = [ros_args[i + 1] for i, a in enumerate(ros_args) if a == '-r']
    assert remaps[:2] == ['__node:=rot_tools', '__ns:=/']
    # Every input of the node is a launch argument, and by default left where it is.
    assert remaps[2:] == [f'{kind.topic}:={kind.topic}' for kind in INPUTS]


def test_every_launch_argument_is_described_and_used():
    root = ElementTree.parse(LAUNCH_FILE).getroot()
    text = LAUNCH_FILE.read_text()
    for arg in root.iter('arg'):
        assert arg.get('description'), arg.get('name')
        assert f"$(var {arg.get('name')})" in text, f"{arg.get('name')} is never used"


def test_setup_installs_the_launch_file_and_the_parameter_file():
    data_files = dict(setup_keywords()['data_files'])
    assert 'launch/rot_tools.launch.xml' in data_files[f'share/{PACKAGE}/launch']
    assert 'config/rot_tools.yaml' in data_files[f'share/{PACKAGE}/config']
    for files in data_files.values():
        for name in files:
            assert (REPO / name).is_file(), name


@pytest.fixture
def launched(tmp_path):
    """Start the node as the launch file would; kill it after the test."""
    started = []

    def launch(overrides):
        _, executable, ros_args = launch_command(overrides)
        command = console_script(executable, 'rot_tools.ros.node.rotation_node') + ros_args
        err = tmp_path / f'{len(started)}.err'
        with open(err, 'w') as stderr:
            process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=stderr,
                                       stdin=subprocess.DEVNULL, env=script_env(command))
        started.append((process, err))
        return process, err

    yield launch
    for process, _ in started:
        if process.poll() is None:
            process.kill()
            process.wait()


def test_launched_with_a_namespace_a_remapped_imu_and_a_parameter_file(
        tester, launched, tmp_path):
    namespace = f'/{RUN}/launch'
    imu_topic = f'/{RUN}/robot/imu/data'
    params = tmp_path / 'mine.yaml'
    text = (REPO / 'config' / 'rot_tools.yaml').read_text()
    params.write_text(text.replace('angle_unit: rad', 'angle_unit: deg')
                      .replace('marker_scale: 1.0', 'marker_scale: 3'))
    process, err = launched({'namespace': namespace, 'node_name': 'rotations',
                             'imu': imu_topic, 'params_file': str(params)})
    node = f'{namespace}/rotations'
    deadline = time.monotonic() + 4 * TIMEOUT  # start-up, on a loaded machine
    while 'decomposing' not in err.read_text():
        assert process.poll() is None and time.monotonic() < deadline, err.read_text()
        time.sleep(0.05)
    assert f'{imu_topic} or' in err.read_text()  # the remap took
    tester.subscribe(f'{node}/rpy', Vector3Stamped)
    imu = tester.publisher(imu_topic, Imu, qos_profile_sensor_data)  # the remap took
    tester.wait_matched([f'{node}/rpy'])
    response = tester.call(GetParameters, f'{node}/get_parameters',
                           GetParameters.Request(names=['angle_unit', 'marker_scale']))
    assert list(map(parameter_value_to_python, response.values)) == ['deg', 3.0]
    msg = Imu()
    msg.header.frame_id = 'imu_link'
    q = Rotation.from_euler('xyz', [5.0, -10.0, 30.0], degrees=True).as_quat()
    o = msg.orientation
    o.x, o.y, o.z, o.w = map(float, q)
    received = tester.received[f'{node}/rpy']
    for stamp in range(1, 50):  # best effort: a first sample can race discovery
        msg.header.stamp.sec = stamp
        imu.publish(msg)
        tester.spin_for(0.1)
        if received:
            break
    assert received, 'no ~/rpy for the remapped ~/imu'
    vector = received[-1].vector
    np.testing.assert_allclose([vector.x, vector.y, vector.z], [5.0, -10.0, 30.0],
                               rtol=0, atol=1e-12)
    process.send_signal(signal.SIGINT)
    assert process.wait(timeout=10) == 0
    assert 'Traceback' not in err.read_text()


def test_a_relative_namespace_is_made_absolute_as_launch_ros_does():
    assert launch_command({'namespace': 'robot'})[2][4] == '__ns:=/robot'


def test_doc_node_md_lists_every_launch_argument_and_every_topic_and_parameter():
    from rot_tools.io.interface import INPUTS, OUTPUTS
    from rot_tools.ros.node.rotation_node import PARAMETERS
    doc = (REPO / 'doc' / 'node.md').read_text(encoding='utf-8')
    for arg in ElementTree.parse(LAUNCH_FILE).getroot().iter('arg'):
        assert f"`{arg.get('name')}`" in doc, arg.get('name')
    for kind in INPUTS:
        assert f'| `{kind.topic}` (in) | {kind.type_name} |' in doc, kind.topic
    for kind in OUTPUTS:
        assert f'| `{kind.topic}` | {kind.type_name} |' in doc, kind.topic
    rows = {line.split(' | ')[0][3:-1]: line.split(' | ')[1] for line in doc.splitlines()
            if line.startswith('| `')}  # '| `name` | `default` | ...' (names may share a row)
    for name, spec in PARAMETERS.items():
        default = spec.default
        if isinstance(default, bool) or default == '':
            default = {True: 'true', False: 'false', '': "''"}[default]
        (row,) = [key for key in rows if f'`{name}`' in f'`{key}`'.split(', ')]
        assert rows[row] == f'`{default}`', name
