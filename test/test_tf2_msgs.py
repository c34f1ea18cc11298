"""tf2_msgs on the pip path: the TFMessage tools/build_tf2_msgs.py builds from vendor/."""

import importlib.util
import os
import subprocess
import sys
import textwrap

from conftest import REPO, RUN, TIMEOUT
import pytest

UPSTREAM_HASH = 'RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087'
"""The type hash of tf2_msgs/msg/TFMessage in ROS 2 Jazzy (tf2_msgs 0.36)."""
# What a sourced ROS install or a developer's shell may set; the child runs without them.
ROS_PATHS = ('LD_LIBRARY_PATH', '_ROS_WHEELS_BOOTSTRAP_COMPLETE', 'AMENT_PREFIX_PATH',
             'CMAKE_PREFIX_PATH', 'PYTHONPATH', 'COLCON_PREFIX_PATH', 'ROS_DISTRO',
             'ROS_VERSION')

PUBLISHER = textwrap.dedent("""
    import sys, time
    import rclpy
    from geometry_msgs.msg import TransformStamped
    from tf2_msgs.msg import TFMessage

    topic, token = sys.argv[1], sys.argv[2]
    rclpy.init()
    node = rclpy.create_node('tf_publisher', namespace='/' + token)
    pub = node.create_publisher(TFMessage, topic, 10)
    edges = [('odom_' + token, 'base_' + token, (1.0, 2.0, 3.0), (0.0, 0.0, 0.6, 0.8)),
             ('base_' + token, 'imu_' + token, (-0.5, 0.25, 0.125), (0.5, -0.5, 0.5, 0.5))]
    msg = TFMessage()
    for parent, child, b, q in edges:
        t = TransformStamped()
        t.header.stamp.sec, t.header.stamp.nanosec = 1700000000, 250000000
        t.header.frame_id, t.child_frame_id = parent, child
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = b
        r = t.transform.rotation
        r.x, r.y, r.z, r.w = q
        msg.transforms.append(t)
    print('ready', flush=True)
    deadline = time.monotonic() + float(sys.argv[3])
    while time.monotonic() < deadline:  # a broadcaster's rate, until the test ends it
        pub.publish(msg)
        time.sleep(0.05)
""")


def _import_build_script():
    spec = importlib.util.spec_from_file_location(
        'build_tf2_msgs', REPO / 'tools' / 'build_tf2_msgs.py')
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def tf_publisher(tmp_path):
    """Start a TFMessage publisher on this run's /tf in a child process without ROS paths."""
    env = {k: v for k, v in os.environ.items() if k not in ROS_PATHS}
    token = RUN
    topic = f'/{RUN}/tf'  # this run's /tf
    err = open(tmp_path / 'publisher.err', 'w')
    process = subprocess.Popen(
        [sys.executable, '-c', PUBLISHER, topic, token, str(TIMEOUT * 6)], env=env,
        stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=err, text=True)
    try:
        assert process.stdout.readline() == 'ready\n', (tmp_path / 'publisher.err').read_text()
        yield topic, token
    finally:
        process.kill()
        process.wait()
        err.close()


def test_tfmessage_imports_with_its_type_support():
    from tf2_msgs.msg import TFMessage
    TFMessage.__class__.__import_type_support__()
    assert TFMessage._TYPE_SUPPORT is not None
    assert list(TFMessage.get_fields_and_field_types().items()) == [
        ('transforms', 'sequence<geometry_msgs/TransformStamped>')]


def test_two_processes_exchange_tf_with_the_upstream_type_hash(tester, tf_publisher):
    from tf2_msgs.msg import TFMessage
    topic, token = tf_publisher
    tester.subscribe(topic, TFMessage)
    tester.wait_matched([topic])
    publishers = tester.node.get_publishers_info_by_topic(topic)
    assert [p.topic_type for p in publishers] == ['tf2_msgs/msg/TFMessage']
    # The hash announced by the other process's publisher, and our subscription's own.
    assert str(publishers[0].topic_type_hash) == UPSTREAM_HASH
    subscriptions = tester.node.get_subscriptions_info_by_topic(topic)
    assert [str(s.topic_type_hash) for s in subscriptions] == [UPSTREAM_HASH]

    msg = tester.wait_messages(topic)[0]
    got = [(t.header.frame_id, t.child_frame_id, t.header.stamp.sec, t.header.stamp.nanosec,
            (t.transform.translation.x, t.transform.translation.y, t.transform.translation.z),
            (t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
             t.transform.rotation.w))
           for t in msg.transforms]
    assert got == [
        (f'odom_{token}', f'base_{token}', 1700000000, 250000000, (1.0, 2.0, 3.0),
         (0.0, 0.0, 0.6, 0.8)),
        (f'base_{token}', f'imu_{token}', 1700000000, 250000000, (-0.5, 0.25, 0.125),
         (0.5, -0.5, 0.5, 0.5))]


def test_tf2_msgs_is_installed_in_this_environment_not_sourced():
    spec = importlib.util.find_spec('tf2_msgs')
    assert spec.origin.startswith(sys.prefix), spec.origin


@pytest.mark.parametrize('present, missing', [
    ((), 'C compiler'),
    (('cc',), 'C++ compiler'),
    (('cc', 'c++'), 'make'),
])
def test_build_script_names_the_missing_tool_in_one_line(tmp_path, monkeypatch, capsys,
                                                         present, missing):
    script = _import_build_script()
    for name in present:
        tool = tmp_path / name
        tool.write_text('#!/bin/sh\n')
        tool.chmod(0o755)
    monkeypatch.setenv('PATH', str(tmp_path))
    for variable in ('CC', 'CXX'):
        monkeypatch.delenv(variable, raising=False)
    monkeypatch.setattr(script, 'importable', lambda: False)
    monkeypatch.setattr(script, 'build', lambda: pytest.fail('build started without tools'))
    assert script.main() == 1
    out, err = capsys.readouterr()
    assert out == ''
    assert err.count('\n') == 1, err
    assert f'needs a {missing}' in err if missing != 'make' else 'needs make' in err
    assert 'sudo apt install build-essential' in err


def test_build_script_does_nothing_when_tfmessage_imports(monkeypatch, capsys):
    script = _import_build_script()
    monkeypatch.setattr(script, 'build', lambda: pytest.fail('built although importable'))
    assert script.main() == 0
    assert 'nothing to build' in capsys.readouterr().out
