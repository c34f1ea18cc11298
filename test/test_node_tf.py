"""
rotation_node following two frames of /tf, and `rotation_client tf`, over real DDS.

test/tf_publisher.py publishes the frames; expected values are 4×4 products of what the test
hears and scipy.linalg's T0·expm(s·logm(T0⁻¹T1)) between samples.
"""

import math
import os
import re
import subprocess
import sys
import time
from types import SimpleNamespace

from conftest import assert_clean_exit, console_script, REPO, RUN, script_env, TIMEOUT
from doc_blocks import assert_doc_output
import numpy as np
import pytest
from scipy.linalg import expm, logm
from scipy.spatial.transform import Rotation
import yaml

tf2_msgs = pytest.importorskip('tf2_msgs.msg', reason='tf2_msgs is built by make test-venv')

TF_TYPE_HASH = 'RIHS01_e369d0f05a23ae52508854b66f6aa0437f3449d652e8cbf22d5abe85d020f087'
CHAIN = ['odom', 'base_link', 'camera', 'gimbal']
TOL = 1e-9


# The publisher process and the independent reference


def start_tf_publisher(tf_topic, static_topic, *options, lifetime=120):
    """Start test/tf_publisher.py on the two topics; return its process."""
    args = [sys.executable, str(REPO / 'test' / 'tf_publisher.py'), tf_topic, static_topic,
            '--lifetime', str(lifetime), *options]
    return subprocess.Popen(args, env=script_env(args), stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE)


def stop(process):
    if process.poll() is None:
        process.kill()
    process.wait()


@pytest.fixture
def tf_publisher():
    """Start test/tf_publisher.py processes; kill them after the test."""
    started = []

    def start(tf_topic, static_topic, *options):
        started.append(start_tf_publisher(tf_topic, static_topic, *options))
        return started[-1]

    yield start
    for process in started:
        stop(process)


def nanoseconds(stamp):
    return stamp.sec * 1_000_000_000 + stamp.nanosec


def hom(transform):
    """4×4 matrix of a geometry_msgs/Transform (scipy for the quaternion)."""
    q, t = transform.rotation, transform.translation
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
    T[:3, 3] = t.x, t.y, t.z
    return T


class Reference:
    """Every transform heard on /tf and /tf_static; the pose of a frame at a stamp."""

    def __init__(self, tester, tf_topic, static_topic):
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        self.samples = {}  # child: (parent, {stamp ns: 4×4})
        self.static = {}  # child: (parent, 4×4)
        reliable = {'reliability': ReliabilityPolicy.RELIABLE, 'depth': 1000}
        tester.node.create_subscription(
            tf2_msgs.TFMessage, tf_topic, lambda msg: self._add(msg, False),
            QoSProfile(**reliable))
        tester.node.create_subscription(
            tf2_msgs.TFMessage, static_topic, lambda msg: self._add(msg, True),
            QoSProfile(durability=DurabilityPolicy.TRANSIENT_LOCAL, **reliable))

    def _add(self, msg, static):
        for t in msg.transforms:
            if not all(map(math.isfinite, (t.transform.translation.x, t.transform.translation.y,
                                           t.transform.translation.z))):
                continue
            if static:
                self.static[t.child_frame_id] = (t.header.frame_id, hom(t.transform))
            else:
                parent, samples = self.samples.setdefault(t.child_frame_id,
                                                          (t.header.frame_id, {}))
                samples[nanoseconds(t.header.stamp)] = hom(t.transform)

    def edge(self, child, ns):
        """Return (parent, T) of child's edge at stamp ns, or None without samples around it."""
        if child in self.static:
            return self.static[child]
        parent, samples = self.samples[child]
        if ns in samples:
            return parent, samples[ns]
        before = [s for s in samples if s < ns]
        after = [s for s in samples if s > ns]
        if not before or not after:
            return None
        s0, s1 = max(before), min(after)
        T0, T1 = samples[s0], samples[s1]
        return parent, T0 @ expm((ns - s0) / (s1 - s0) * np.real(logm(np.linalg.inv(T0) @ T1)))

    def pose(self, reference, body, ns):
        """T_reference_body at ns along CHAIN's order (reference an ancestor of body)."""
        T, frame = np.eye(4), body
        while frame != reference:
            found = self.edge(frame, ns)
            if found is None:
                return None
            frame, T_edge = found
            T = T_edge @ T
        return T


def canonical(q):
    """Return the quaternion (x, y, z, w) with w > 0."""
    q = np.asarray(q, dtype=float)
    return -q if q[3] < 0 else q


def twist_of(T):
    """(ω, v) of logm(T) = [[ω×, v], [0, 0]]: the exponential coordinates of T."""
    L = np.real(logm(T))
    return np.array([L[2, 1], L[0, 2], L[1, 0], *L[:3, 3]])


def node_args(namespace, reference='odom', body='gimbal'):
    return ['-p', f'tf_reference_frame:={reference}', '-p', f'tf_body_frame:={body}',
            '-r', f'/tf:={namespace}/tf', '-r', f'/tf_static:={namespace}/tf_static']


def wait_started(tester, topic):
    """Wait (up to 30 s) until the node publishes ``topic``: it has started."""
    sub = tester._subscriptions[topic]
    tester.spin_until(lambda: sub.get_publisher_count() > 0, TIMEOUT * 6,
                      f'a publisher on {topic}')


def describe(tester, node_name):
    from std_srvs.srv import Trigger
    response = tester.call(Trigger, f'{node_name}/describe', Trigger.Request())
    return response, (yaml.safe_load(response.message) if response.success else None)


@pytest.fixture(scope='module')
def followed(tmp_path_factory, tester_context):
    """One node process following odom → gimbal on a /tf of its own, for tests that only read."""
    from conftest import NodeProcess, Tester
    namespace = f'/{RUN}/followed'
    tester = Tester(tester_context, name='followed_tester')
    node = NodeProcess(tmp_path_factory.mktemp('followed'), *node_args(namespace))
    publisher = None
    try:
        reference = Reference(tester, f'{namespace}/tf', f'{namespace}/tf_static')
        tester.subscribe_outputs(node.name)
        wait_started(tester, f'{node.name}/quaternion')
        publisher = start_tf_publisher(f'{namespace}/tf', f'{namespace}/tf_static',
                                       lifetime=600)
        yield SimpleNamespace(tester=tester, node=node, namespace=namespace,
                              reference=reference)
    finally:
        if publisher is not None:
            stop(publisher)
        node.kill()
        tester.close()


@pytest.fixture(scope='module')
def real_tf(tester_context):
    """One tf_publisher on this run's /tf and /tf_static, the names rotation_client reads."""
    from conftest import Tester
    tester = Tester(tester_context, name='real_tf_tester')
    publisher = start_tf_publisher('/tf', '/tf_static', lifetime=600)
    try:
        reference = Reference(tester, '/tf', '/tf_static')
        tester.spin_until(lambda: len(reference.samples.get('gimbal', (0, {}))[1]) >= 3
                          and {'camera', 'rover'} <= set(reference.static), TIMEOUT * 4,
                          'the TF chain and the second tree')
        yield SimpleNamespace(tester=tester, reference=reference)
    finally:
        stop(publisher)
        tester.close()


# The node


def test_node_publishes_the_chain_at_each_new_common_time(followed):
    tester, node, reference = followed.tester, followed.node, followed.reference
    outputs = {name: tester.wait_messages(f'{node.name}/{name}', 1, TIMEOUT * 4)
               for name in ('quaternion', 'axis_angle', 'screw')}
    # Outputs are checked from when the test side hears the chain (maybe after the node).
    tester.spin_until(lambda: len(reference.samples.get('gimbal', (0, {}))[1]) >= 2
                      and 'camera' in reference.static, TIMEOUT * 4, 'the TF chain')
    enough = len(outputs['quaternion']) + 15
    tester.spin_until(lambda: min(map(len, outputs.values())) >= enough, TIMEOUT * 4,
                      f'{enough} outputs of each kind')
    checked = 0
    gimbal_stamps = set(reference.samples['gimbal'][1])
    by_stamp = {name: {nanoseconds(m.header.stamp): m for m in messages}
                for name, messages in outputs.items()}
    for ns, q_msg in by_stamp['quaternion'].items():
        assert q_msg.header.frame_id == 'odom'
        T = reference.pose('odom', 'gimbal', ns)
        if T is None or ns not in by_stamp['axis_angle'] or ns not in by_stamp['screw']:
            continue  # samples the test side had not heard yet (before discovery)
        rotvec_msg, twist_msg = by_stamp['axis_angle'][ns], by_stamp['screw'][ns]
        assert rotvec_msg.header == q_msg.header == twist_msg.header
        # The common time is the gimbal's newest stamp (odom → base_link runs half a period
        # ahead): base_link is interpolated there.
        assert ns in gimbal_stamps
        assert ns not in reference.samples['base_link'][1]
        q = q_msg.quaternion
        assert np.abs(canonical([q.x, q.y, q.z, q.w])
                      - canonical(Rotation.from_matrix(T[:3, :3]).as_quat())).max() <= TOL
        v = rotvec_msg.vector
        assert np.abs([v.x, v.y, v.z] - Rotation.from_matrix(T[:3, :3]).as_rotvec()).max() \
            <= TOL
        w, u = twist_msg.twist.angular, twist_msg.twist.linear
        assert np.abs([w.x, w.y, w.z, u.x, u.y, u.z] - twist_of(T)).max() <= TOL
        checked += 1
    assert checked >= 10
    # Each common time once: no output repeats a stamp.
    stamps = [nanoseconds(m.header.stamp) for m in outputs['quaternion']]
    assert len(set(stamps)) == len(stamps) and stamps == sorted(stamps)


def test_describe_names_source_frames_and_chain_and_the_type_hash_is_upstreams(followed):
    tester, node, namespace = followed.tester, followed.node, followed.namespace
    tester.wait_messages(f'{node.name}/quaternion', 1, TIMEOUT * 4)
    response, data = describe(tester, node.name)
    assert response.success
    assert data['source'] == f'{namespace}/tf'
    assert data['source_type'] == 'tf2_msgs/msg/TFMessage'
    assert data['frame_id'] == 'odom'
    assert data['tf'] == {'source': f'{namespace}/tf', 'reference_frame': 'odom',
                          'body_frame': 'gimbal', 'chain': CHAIN}
    # Every endpoint of /tf and /tf_static has upstream Jazzy's type hash.
    for topic in (f'{namespace}/tf', f'{namespace}/tf_static'):
        tester.spin_until(
            lambda: tester.node.get_publishers_info_by_topic(topic)
            and any(e.node_name == 'rot_tools'
                    for e in tester.node.get_subscriptions_info_by_topic(topic)),
            what=f'the endpoints of {topic} in the graph')
        for endpoints in (tester.node.get_subscriptions_info_by_topic(topic),
                          tester.node.get_publishers_info_by_topic(topic)):
            assert {str(e.topic_type_hash) for e in endpoints} == {TF_TYPE_HASH}
            assert {e.topic_type for e in endpoints} == {'tf2_msgs/msg/TFMessage'}
        subs = tester.node.get_subscriptions_info_by_topic(topic)
        node_subs = [e for e in subs if e.node_name == 'rot_tools']
        assert len(node_subs) == 1
        durability = node_subs[0].qos_profile.durability.name
        assert durability == ('TRANSIENT_LOCAL' if topic.endswith('static') else 'VOLATILE')
        assert node_subs[0].qos_profile.reliability.name == 'RELIABLE'


def test_refusals_are_counted_and_the_node_keeps_serving(node_process, tester, namespace,
                                                         tf_publisher):
    from geometry_msgs.msg import QuaternionStamped
    from rclpy.parameter import Parameter
    node = node_process(*node_args(namespace))
    out = f'{node.name}/quaternion'
    tester.subscribe(out, QuaternionStamped)
    wait_started(tester, f'{node.name}/quaternion')
    tf_publisher(f'{namespace}/tf', f'{namespace}/tf_static', '--bad')

    def counts():
        response, data = describe(tester, node.name)
        return data['refused'] if response.success else {}

    tester.wait_messages(out, 1, TIMEOUT * 4)
    # NaN on /tf and a loop: refused with their reasons, once a second.
    tester.spin_until(lambda: counts().get('non_finite', 0) >= 1
                      and counts().get('tf_loop', 0) >= 1, TIMEOUT * 2, 'non_finite, tf_loop')
    cases = [('odom', 'nowhere', 'tf_unknown_frame'), ('rover', 'gimbal', 'tf_not_connected'),
             # old_marker stopped 20 s ago, beyond the 10 s that base_link's edge keeps.
             ('gimbal', 'old_marker', 'tf_extrapolation')]
    for reference, body, reason in cases:
        before = counts().get(reason, 0)
        results = tester.set_parameters(node.name, [
            Parameter('tf_reference_frame', value=reference),
            Parameter('tf_body_frame', value=body)])
        assert all(r.successful for r in results)
        tester.spin_until(lambda: counts().get(reason, 0) > before, TIMEOUT * 2, reason)
    warnings = node.wait_for_stderr("following 'old_marker' in 'gimbal'")
    assert re.search(r"\(tf_extrapolation\): lookup of '\w+' in '\w+' at t = \S+ s would "
                     r"extrapolate [\d.]+ s before the oldest sample of the edge '\w+' → '\w+'",
                     warnings)
    assert "(tf_unknown_frame): frame '" in warnings
    assert '(non_finite): transform' in warnings and '(tf_loop):' in warnings
    # Back to a good pair: outputs flow again, in the new reference frame.
    tester.set_parameters(node.name, [Parameter('tf_reference_frame', value='base_link'),
                                      Parameter('tf_body_frame', value='gimbal')])
    tester.spin_until(lambda: tester.received[out][-1].header.frame_id == 'base_link',
                      TIMEOUT * 2, 'outputs in base_link')
    # Off: nothing more is published.
    tester.set_parameters(node.name, [Parameter('tf_body_frame', value='')])
    tester.spin_for(0.3)
    seen = len(tester.received[out])
    tester.spin_for(0.5)
    assert len(tester.received[out]) == seen


def test_the_node_describe_shown_in_the_docs(node_process, tester, namespace, tf_publisher):
    from geometry_msgs.msg import QuaternionStamped
    node = node_process(*node_args(namespace, 'odom', 'gimbal'), '-p', 'angle_unit:=deg')
    tester.subscribe(f'{node.name}/quaternion', QuaternionStamped)
    wait_started(tester, f'{node.name}/quaternion')
    tf_publisher(f'{namespace}/tf', f'{namespace}/tf_static', '--still')
    tester.wait_messages(f'{node.name}/quaternion', 1, TIMEOUT * 4)
    response, _ = describe(tester, node.name)
    shown = response.message.replace(namespace, '')
    shown = shown[:shown.index('refused:')]
    assert_doc_output('tf-node-describe', shown)


def tf_sender(tester, namespace):
    """Return send(*transforms): one TFMessage on the namespace's /tf, matched by the node."""
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    pub = tester.publisher(f'{namespace}/tf', tf2_msgs.TFMessage,
                           QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))
    return lambda *transforms: pub.publish(tf2_msgs.TFMessage(transforms=list(transforms)))


def test_node_refuses_a_future_stamp_and_starts_over_when_time_goes_back(
        node_process, tester, namespace):
    from geometry_msgs.msg import QuaternionStamped
    node = node_process(*node_args(namespace, 'odom', 'base_link'))
    out = f'{node.name}/quaternion'
    tester.subscribe(out, QuaternionStamped, qos=1000)
    wait_started(tester, out)
    send = tf_sender(tester, namespace)
    sent = set()

    def follow(seconds, nanosec):
        for sec in seconds:
            send(make_transform('odom', 'base_link', 0.1 * sec, sec=sec, nanosec=nanosec))
            sent.add((sec, nanosec))
        last = (seconds[-1], nanosec)
        tester.spin_until(lambda: any((m.header.stamp.sec, m.header.stamp.nanosec) == last
                                      for m in tester.received[out]), TIMEOUT * 2,
                          f'an output stamped {last}')

    follow(range(1_000, 1_005), 123_456_789)
    send(make_transform('odom', 'base_link', sec=2_000_000_000, nanosec=0))  # the year 2033
    follow(range(1_005, 1_025), 999_999_999)
    _, data = describe(tester, node.name)
    assert (data['stamp']['sec'], data['stamp']['nanosec']) == (1_024, 999_999_999)
    assert data['refused']['tf_future_stamp'] == 1 and data['refused']['tf_time_jump'] == 0
    follow(range(500, 503), 5)  # a bag replayed from its start
    _, data = describe(tester, node.name)
    assert data['refused']['tf_time_jump'] == 1
    assert (data['stamp']['sec'], data['stamp']['nanosec']) == (502, 5)
    # Every output carries an input's stamp, to the nanosecond.
    assert {(m.header.stamp.sec, m.header.stamp.nanosec) for m in tester.received[out]} <= sent
    warnings = node.wait_for_stderr('(tf_time_jump)')
    assert "(tf_future_stamp): transform 'odom' → 'base_link' stamped" in warnings


def test_large_tf_messages_are_cut_the_node_serves_on_and_ctrl_c_ends_it(
        node_process, tester, namespace):
    """A TFMessage of 100,000 transforms is cut to 1,000; Ctrl-C then ends the node cleanly."""
    import signal
    from geometry_msgs.msg import QuaternionStamped
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from rclpy.serialization import serialize_message
    node = node_process(*node_args(namespace, 'odom', 'base_link'))
    out = f'{node.name}/quaternion'
    tester.subscribe(out, QuaternionStamped, qos=1000)
    wait_started(tester, out)
    publisher = tester.publisher(f'{namespace}/tf', tf2_msgs.TFMessage,
                                 QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE))

    def send(*transforms):
        publisher.publish(tf2_msgs.TFMessage(transforms=list(transforms)))

    # 100,000 samples of the followed edge, newest first (out of order), then twice 100,000
    # copies of one transform, serialised once.
    send(*[make_transform('odom', 'base_link', 0.1, sec=1_000 + 99_999 - i, nanosec=0)
           for i in range(100_000)])
    ballast = make_transform('odom', 'ballast', sec=1_000, nanosec=0)
    large = serialize_message(tf2_msgs.TFMessage(transforms=[ballast] * 100_000))
    for _ in range(2):
        publisher.publish(large)
    send(make_transform('odom', 'base_link', 0.2, sec=400_000, nanosec=7))
    tester.spin_until(lambda: any(m.header.stamp.sec == 400_000 for m in tester.received[out]),
                      TIMEOUT * 12, 'the output of the sample after the large messages')
    _, data = describe(tester, node.name)
    assert data['refused']['tf_too_many_transforms'] == 3
    cut = ('(tf_too_many_transforms): a TFMessage of 100,000 transforms: the first 1,000 '
           'taken, 99,000 dropped')
    logged = node.wait_for_stderr(cut).count(cut)
    time.sleep(1.0)  # (the warnings of one reason are throttled to one a second)
    for _ in range(3):
        publisher.publish(large)
    deadline = time.monotonic() + TIMEOUT * 12
    while node.err_path.read_text().count(cut) == logged:  # the first taken, the next made
        assert time.monotonic() < deadline, 'no large message taken'
        time.sleep(0.05)
    assert_clean_exit(*node.stop(signal.SIGINT))


def test_junk_frames_are_forgotten_and_long_names_never_logged_whole(
        ros_context, tester, namespace, monkeypatch):
    """Junk frames are forgotten after the cache; a 1 MB frame name is never logged whole."""
    from geometry_msgs.msg import QuaternionStamped
    from rclpy.parameter import Parameter
    from rot_tools.ros import tf_input
    from rot_tools.ros.node.rotation_node import RotationNode
    monkeypatch.setattr(tf_input, 'CACHE_SECONDS', 1.0)
    node = RotationNode(context=ros_context, namespace=namespace,
                        cli_args=['--ros-args', *node_args(namespace, 'odom', 'base_link')],
                        parameter_overrides=[Parameter('publish_markers', value=False)])
    try:
        tester.add_node(node)
        tester.subscribe_rosout()
        out = f'{node.get_fully_qualified_name()}/quaternion'
        tester.subscribe(out, QuaternionStamped, qos=1000)
        wait_started(tester, out)
        send = tf_sender(tester, namespace)
        # 1,000 junk frames of 250-character names fill the tree (the last one refused) ...
        send(*[make_transform('junk_root', f'junk_{k:04d}_' + 'j' * 240, sec=1_000)
               for k in range(1_000)])
        send(make_transform('odom', 'x' * 1_000_000))  # a name of 1 MB: refused, cut
        tester.spin_until(lambda: node.refused_counts()['tf_bad_frame'] == 1, TIMEOUT * 2,
                          'tf_bad_frame')
        real = make_transform('odom', 'base_link', sec=2_000, nanosec=1)
        send(real)
        tester.spin_until(lambda: node.refused_counts()['tf_too_many_frames'] >= 2,
                          TIMEOUT * 2, 'the real frames refused while the junk fills the tree')
        # ... until they have not been heard for the cache: then the real frames get in.
        for k in range(60):
            real.header.stamp.sec = 2_001 + k
            send(real)
            tester.spin_for(0.2)
            if tester.received[out]:
                break
        assert tester.received[out], 'the real frames never got in'
        logs = [log.msg for log in tester.logs if log.name == node.get_logger().name]
        for reason in ('tf_bad_frame', 'tf_too_many_frames', 'tf_unknown_frame'):
            assert any(f'({reason})' in line for line in logs), (reason, logs)
        assert max(map(len, logs)) < 2_000
    finally:
        tester.remove_node(node)
        node.destroy_node()


# rotation_client tf


def run_client(*args, timeout=60):
    command = console_script('rotation_client',
                             'rot_tools.ros.client.rotation_client') + list(args)
    return subprocess.run(command, env=script_env(command), capture_output=True, text=True,
                          timeout=timeout)


def test_client_tf_once_against_the_reference(real_tf):
    tester, reference = real_tf.tester, real_tf.reference
    result = run_client('tf', 'odom', 'gimbal', '--once', '--timeout', '20')
    assert result.returncode == 0, result.stderr
    report = yaml.safe_load(result.stdout)
    assert report['reference_frame'] == 'odom' and report['body_frame'] == 'gimbal'
    assert report['chain'] == CHAIN
    ns = report['stamp']['sec'] * 1_000_000_000 + report['stamp']['nanosec']
    # The test side catches up with the samples around the client's stamp.
    tester.spin_until(lambda: reference.pose('odom', 'gimbal', ns) is not None,
                      TIMEOUT * 2, "the samples around the client's stamp")
    T = reference.pose('odom', 'gimbal', ns)
    assert np.abs(np.array(report['matrix']) - T[:3, :3]).max() <= TOL
    assert np.abs(np.array(report['translation']) - T[:3, 3]).max() <= TOL
    q = report['quaternion']
    assert np.abs(canonical([q['x'], q['y'], q['z'], q['w']])
                  - canonical(Rotation.from_matrix(T[:3, :3]).as_quat())).max() <= TOL


def test_client_tf_prints_once_a_second_in_the_reference_frame(real_tf):
    command = console_script('rotation_client', 'rot_tools.ros.client.rotation_client') + [
        'tf', 'base_link', 'gimbal', '--deg', '--timeout', '20']
    process = subprocess.Popen(command, env=script_env(command), stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        documents = []
        for line in process.stdout:
            if line == '---\n':
                documents.append([])
            documents[-1].append(line)
            if len(documents) == 3:
                break
    finally:
        process.terminate()
        process.wait(timeout=10)
    reports = [yaml.safe_load(''.join(d)) for d in documents[:2]]
    assert [r['chain'] for r in reports] == [CHAIN[1:]] * 2
    assert all(r['euler']['unit'] == 'deg' for r in reports)
    stamps = [r['stamp']['sec'] + 1e-9 * r['stamp']['nanosec'] for r in reports]
    assert 0.5 < stamps[1] - stamps[0] < 2.0  # once a second, each the latest


@pytest.mark.parametrize('frames, shown', [
    (['odom', 'nowhere'], "frame 'nowhere' did not appear on /tf or /tf_static within 5 s"),
    (['rover', 'gimbal'], "no transform of 'gimbal' in 'rover' within 5 s: frames 'rover' "
                          "and 'gimbal' are not connected")])
def test_client_tf_without_the_frames_is_one_line_and_exit_1(real_tf, frames, shown):
    result = run_client('tf', *frames)  # the default --timeout: 5 s
    assert result.returncode == 1
    assert result.stdout == ''
    assert result.stderr.startswith(f'rotation_client: {shown}')
    assert result.stderr.count('\n') == 1
    if frames[1] == 'nowhere':
        assert_doc_output('tf-client-missing', '$ rotation_client tf odom nowhere\n'
                          + result.stderr + '$ echo $?\n1\n')


def test_client_tf_shown_in_the_docs(tester, namespace, tf_publisher):
    tf_publisher(f'{namespace}/tf', f'{namespace}/tf_static', '--still')
    result = run_client('tf', 'odom', 'gimbal', '--once', '--deg', '--timeout', '20',
                        '--ros-args', '-r', f'/tf:={namespace}/tf',
                        '-r', f'/tf_static:={namespace}/tf_static')
    assert result.returncode == 0, result.stderr
    assert_doc_output('tf-client-once', '$ rotation_client tf odom gimbal --once --deg\n'
                      + result.stdout)
    assert os.environ['ROS_DOMAIN_ID']  # the run's own domain (conftest)


# The follower in-process: each refusal's reason, stamps to the nanosecond


def test_follower_refusals_and_stamps(ros_context):
    import rclpy
    from rot_tools.ros.tf_input import TfFollower
    node = rclpy.create_node('follower', namespace=f'/{RUN}', context=ros_context)
    got, refused = [], []
    follower = TfFollower(node, lambda *a: got.append(a), lambda *a: refused.append(a),
                          max_frames=4)
    try:
        assert follower.add(make_transform('a', 'b', 1.0), False, '/tf')
        assert follower.add(make_transform('b', 'e'), True, '/tf_static')  # a, b, e: 3 of 4
        not_unit = make_transform('b', 'c', q=(0.0, 0.0, 1.0, 1.0))  # |q| = √2
        assert follower.add(not_unit, True, '/tf_static') is False
        for msg, reason in [(make_transform('a', ''), 'tf_bad_frame'),
                            (make_transform('', 'b'), 'tf_bad_frame'),
                            (make_transform('a', 'x', math.nan), 'non_finite'),
                            (make_transform('a', 'x', q=(0.0,) * 4), 'zero_quaternion'),
                            (make_transform('b', 'a'), 'tf_loop'),
                            (make_transform('c', 'd'), 'tf_too_many_frames')]:
            refused.clear()
            assert follower.add(msg, False, '/tf') is False
            assert [r[1] for r in refused] == [reason]
        follower.follow('a', 'b')
        assert len(got) == 1
        header, R, b = got[0]
        assert header.frame_id == 'a'
        assert (header.stamp.sec, header.stamp.nanosec) == (1_700_000_000, 123_456_789)
        assert np.array_equal(R, np.eye(3)) and np.array_equal(b, [1.0, 0.0, 0.0])
        follower.update()  # no new common time: nothing more
        assert len(got) == 1
        follower.add(make_transform('a', 'b', 2.0, nanosec=123_456_790), False, '/tf')
        follower.update()
        assert len(got) == 2 and got[1][0].stamp.nanosec == 123_456_790
        refused.clear()
        follower.follow('a', 'nowhere')
        assert [r[1] for r in refused] == ['tf_unknown_frame']
        assert follower.describe()['chain'].startswith("none: frame 'nowhere' is unknown")
    finally:
        follower.follow('', '')
        node.destroy_node()


def make_transform(parent, child, x=0.0, q=(0.0, 0.0, 0.0, 1.0), sec=1_700_000_000,
                   nanosec=123_456_789):
    from geometry_msgs.msg import TransformStamped
    msg = TransformStamped()
    msg.header.frame_id, msg.child_frame_id = parent, child
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
    msg.transform.translation.x = x
    r = msg.transform.rotation
    r.x, r.y, r.z, r.w = q
    return msg


@pytest.fixture
def follower(ros_context):
    """Yield (follower, outputs, refusals): a TfFollower of an in-process node."""
    import rclpy
    from rot_tools.ros.tf_input import TfFollower
    node = rclpy.create_node('follower', namespace=f'/{RUN}', context=ros_context)
    got, refused = [], []
    follower = TfFollower(node, lambda *a: got.append(a), lambda *a: refused.append(a))
    yield follower, got, refused
    follower.follow('', '')
    node.destroy_node()


def test_follower_output_stamps_are_the_inputs_to_the_nanosecond(follower):
    follower, got, refused = follower
    follower.add(make_transform('a', 's', sec=0, nanosec=0), True, '/tf_static')
    follower.follow('a', 'b')
    refused.clear()  # b is unknown so far
    stamps = [(100, 123_456_789), (102, 999_999_999), (103, 1), (1_700_000_000, 1),
              (1_700_000_000, 2), (1_700_000_000, 3), (1_700_000_001, 999_999_999)]
    for k, (sec, nanosec) in enumerate(stamps):
        assert follower.add(make_transform('a', 'b', float(k), sec=sec, nanosec=nanosec),
                            False, '/tf')
        follower.update()
        assert (got[-1][0].stamp.sec, got[-1][0].stamp.nanosec) == (sec, nanosec)
    assert len(got) == len(stamps) and refused == []
    # A static chain: its newest stamp, 0 here, exactly.
    follower.follow('s', 'a')
    assert (got[-1][0].stamp.sec, got[-1][0].stamp.nanosec) == (0, 0)


def test_follower_refuses_future_stamps_and_starts_over_when_time_goes_back(follower):
    follower, got, refused = follower
    follower.follow('odom', 'base_link')
    now = 1_800_000_000 * 1_000_000_000

    def send(sec, nanosec=0):
        follower.add(make_transform('odom', 'base_link', float(sec), sec=sec, nanosec=nanosec),
                     False, '/tf', now)
        follower.update()

    for sec in range(1_000, 1_005):
        send(sec)
    send(2_000_000_000)  # the year 2033: refused, counted
    assert [r[1] for r in refused] == ['tf_future_stamp']
    assert "'odom' → 'base_link' stamped 200000000 s after the clock of the node" in refused[0][2]
    send(1_800_000_000 + 59)  # within MAX_FUTURE_SECONDS of the clock: taken
    for sec in range(1_005, 1_025):  # more than 10 s back: the edge starts over, counted once
        send(sec, 7)
    assert [r[1] for r in refused] == ['tf_future_stamp', 'tf_time_jump']
    assert 'stamped 1.79999905e+09 s before its newest sample' in refused[1][2]
    assert [(h.stamp.sec, h.stamp.nanosec) for h, _, _ in got[-21:]] == [
        (1_800_000_059, 0)] + [(sec, 7) for sec in range(1_005, 1_025)]
    assert follower.tree.time_range('odom', 'base_link') == (
        follower.seconds(1_014 * 10**9 + 7), follower.seconds(1_024 * 10**9 + 7))
    for sec in range(500, 503):  # a bag replayed from its start: the same
        send(sec)
    assert [r[1] for r in refused][2:] == ['tf_time_jump']
    assert got[-1][0].stamp.sec == 502


def test_follower_forgets_dynamic_edges_not_heard_but_not_static_ones(follower, monkeypatch):
    from rot_tools.ros import tf_input
    follower, got, refused = follower
    follower.add(make_transform('a', 'b'), False, '/tf')
    follower.add(make_transform('a', 'b'), True, '/tf_static')  # b's edge turns static
    follower.add(make_transform('a', 'd'), False, '/tf')
    # Everything heard is now older than the cache, and the sweep is due.
    monkeypatch.setattr(tf_input, 'CACHE_SECONDS', -1.0)
    monkeypatch.setattr(tf_input, 'FORGET_PERIOD', 0.0)
    follower.on_tf(tf2_msgs.TFMessage())
    assert follower.tree.frames == ['a', 'b'] and refused == []


def test_follower_takes_at_most_max_transforms_a_message(follower):
    from rot_tools.ros import tf_input
    follower, got, refused = follower
    follower.follow('odom', 'base_link')
    transforms = [make_transform('odom', 'base_link', float(k), sec=1_000 + k)
                  for k in range(tf_input.MAX_TRANSFORMS_PER_MESSAGE + 500)]
    follower.on_tf(tf2_msgs.TFMessage(transforms=transforms))
    assert [r[1] for r in refused] == ['tf_too_many_transforms']
    assert refused[0][2].startswith('a TFMessage of 1,500 transforms: the first 1,000 taken, '
                                    '500 dropped')
    assert len(got) == 1 and got[0][0].stamp.sec == 1_000 + 999
    # Names beyond MAX_FRAME_NAME bytes are refused, and never repeated whole.
    refused.clear()
    for name in ('x' * 1_000_000, 'é' * 200):  # 1,000,000 bytes; 400 bytes in 200 characters
        follower.on_tf(tf2_msgs.TFMessage(transforms=[make_transform('odom', name)]))
    assert [r[1] for r in refused] == ['tf_bad_frame'] * 2
    assert 'child_frame_id of 1,000,000 bytes, at most MAX_FRAME_NAME = 256' in refused[0][2]
    assert 'child_frame_id of 400 bytes' in refused[1][2]
    assert max(len(r[2]) for r in refused) < 200


def test_the_start_up_refusals_are_those_the_docs_call_normal(follower):
    follower, got, refused = follower
    follower.follow('odom', 'gimbal')
    # /tf before /tf_static, and one dynamic edge's first sample before the other's.
    for transform, static in [(make_transform('odom', 'base_link', sec=10), False),
                              (make_transform('camera', 'gimbal', sec=11), False),
                              (make_transform('base_link', 'camera', sec=0), True),
                              (make_transform('odom', 'base_link', sec=12), False)]:
        assert follower.add(transform, static, '/tf')
        follower.update()
    assert [r[1] for r in refused] == ['tf_unknown_frame', 'tf_not_connected',
                                       'tf_extrapolation']
    assert len(got) == 1 and got[0][0].stamp.sec == 11
    page = (REPO / 'doc' / 'tf.md').read_text(encoding='utf-8')
    start_up = next(p for p in page.split('\n\n') if 'are normal' in p)
    assert 'while the tree fills up at start-up' in start_up
    for reason in {r[1] for r in refused}:
        assert f'`{reason}`' in start_up


def test_without_tf2_msgs_the_node_and_the_client_say_so_in_one_line(tmp_path):
    # A tf2_msgs that cannot be imported: the node exits 2 at start-up, the client 1.
    fake = tmp_path / 'tf2_msgs'
    fake.mkdir()
    (fake / '__init__.py').write_text("raise ImportError('no tf2_msgs here')\n")
    for command, status in [
            (console_script('rotation_node', 'rot_tools.ros.node.rotation_node')
             + ['--ros-args', '-p', 'tf_reference_frame:=odom', '-p', 'tf_body_frame:=a'], 2),
            (console_script('rotation_client', 'rot_tools.ros.client.rotation_client')
             + ['tf', 'odom', 'a'], 1)]:
        env = script_env(command)
        env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(tmp_path),
                                                          env.get('PYTHONPATH')]))
        result = subprocess.run(command, env=env, capture_output=True, text=True, timeout=60)
        assert result.returncode == status
        assert result.stderr.count('\n') == 1
        assert 'tf2_msgs is not importable (no tf2_msgs here): run make' in result.stderr


# Refusals of every kind, one after another


def test_refusals_of_every_kind_in_sequence_are_logged_without_a_traceback(
        node_process, tester, namespace):
    """Warnings and errors alternating are each their refusal line, never a traceback."""
    from geometry_msgs.msg import PoseStamped, QuaternionStamped
    from nav_msgs.srv import GetPlan
    from rclpy.qos import qos_profile_sensor_data
    from sensor_msgs.msg import Imu
    node = node_process(*node_args(namespace, 'odom', 'base_link'))
    tester.subscribe(f'{node.name}/quaternion', QuaternionStamped)
    wait_started(tester, f'{node.name}/quaternion')
    send_tf = tf_sender(tester, namespace)
    pubs = {name: tester.publisher(f'{node.name}/{name}', msg_type, qos_profile_sensor_data)
            for name, msg_type in (('pose', PoseStamped), ('imu', Imu))}

    def pose(q, frame='map'):
        msg = PoseStamped()
        msg.header.frame_id = frame
        o = msg.pose.orientation
        o.x, o.y, o.z, o.w = q
        return msg

    no_orientation = Imu()
    no_orientation.orientation_covariance[0] = -1.0
    topic_inputs = [  # (reason, topic, send)
        ('non_finite', 'pose', lambda: pubs['pose'].publish(pose((math.nan, 0., 0., 1.)))),
        ('zero_quaternion', 'pose', lambda: pubs['pose'].publish(pose((0., 0., 0., 0.)))),
        ('non_unit_quaternion', 'pose', lambda: pubs['pose'].publish(pose((0., 0., 0., 2.)))),
        ('no_orientation', 'imu', lambda: pubs['imu'].publish(no_orientation)),
        ('tf_unknown_frame', 'tf', lambda: send_tf(make_transform('map', 'x'))),
        ('tf_not_connected', 'tf', lambda: send_tf(make_transform('odom', 'a'),
                                                   make_transform('b', 'base_link'))),
        ('tf_bad_frame', 'tf', lambda: send_tf(make_transform('odom', ''))),
        ('tf_loop', 'tf', lambda: send_tf(make_transform('c', 'd'), make_transform('d', 'c'))),
        ('tf_future_stamp', 'tf', lambda: send_tf(make_transform('e', 'f', sec=2 ** 31 - 1))),
        ('tf_time_jump', 'tf', lambda: send_tf(make_transform('g', 'h', sec=1_000),
                                               make_transform('g', 'h', sec=500))),
        ('tf_too_many_transforms', 'tf', lambda: send_tf(*[
            make_transform('odom', 'a', sec=1_000, nanosec=k) for k in range(1_001)])),
    ]
    start, turned = pose((0.0, 0.0, 0.0, 1.0)), pose((0.0, 0.0, 1.0, 0.0))
    near, far = pose((0.0, 0.0, 0.0, 1.0)), pose((0.0, 0.0, 1.0, 0.0))
    near.pose.position.x, far.pose.position.x = -1e308, 1e308  # apart beyond float64
    screw_paths = [  # (reason, start, goal, tolerance)
        ('frame_mismatch', start, pose((0.0, 0.0, 1.0, 0.0), 'odom'), 0.0),
        ('zero_quaternion', pose((0.0, 0.0, 0.0, 0.0)), turned, 0.0),
        ('non_unit_quaternion', start, pose((0.0, 0.0, 2.0, 0.0)), 0.0),
        ('non_finite', start, pose((0.0, 0.0, math.inf, 0.0)), 0.0),
        ('bad_tolerance', start, turned, math.nan),
        ('path_too_long', start, turned, 1e-6),
        ('not_decomposable', near, far, 0.0),
    ]

    def refused():
        return yaml.safe_load(describe(tester, node.name)[0].message)['refused']

    expected = []
    for k, (reason, topic, send) in enumerate(topic_inputs):
        before = refused()[reason]
        for _ in range(20):  # best effort: a message may be lost
            send()
            tester.spin_for(0.1)
            if refused()[reason] > before:
                break
        assert refused()[reason] > before, f'{reason} on {topic} was not counted'
        expected.append(f'refused input on {node.name}/{topic} ({reason}): '
                        if topic != 'tf' else f'refused input on {namespace}/tf ({reason}): ')
        if k < len(screw_paths):  # then an error: the other severity
            reason, path_start, goal, tolerance = screw_paths[k]
            request = GetPlan.Request(start=path_start, goal=goal, tolerance=tolerance)
            reply = tester.call(GetPlan, f'{node.name}/screw_path', request)
            assert reply.plan.poses == [], reason
            expected.append(f'refused input on {node.name}/screw_path ({reason}): ')
    stderr = node.wait_for_stderr(expected[-1])
    assert 'Traceback' not in stderr and 'callback raised' not in stderr, stderr
    missing = [line for line in expected if line not in stderr]
    assert not missing, stderr
