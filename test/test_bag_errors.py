"""
rot-tools bag on bad input: refusals counted by reason, or one line and exit status 2.

Bad messages of every type read, damaged, empty and missing bags, wrong options: never a
traceback nor a warning.
"""

import csv
import io
import json
import math
import os
import re
import subprocess
import sys

import bag_helpers as bh
from conftest import console_script, script_env
import numpy as np
import pytest

rosbags = pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
from rot_tools.core.euler import RPY_SEQUENCE  # noqa: E402
from rot_tools.io.boundary import QUATERNION_TOLERANCE  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402
from test_cli import run  # noqa: E402

TOL = QUATERNION_TOLERANCE
RNG = np.random.default_rng(18)
NAN, INF = math.nan, math.inf


def unit_quaternions(n):
    q = RNG.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def expected_reason(q, p=None, cov0=0.0):
    """Return what rotation_node refuses a message for, decided without rot_tools."""
    if cov0 == -1.0:
        return 'no_orientation'
    if p is not None and not np.isfinite(p).all():
        return 'non_finite'
    if not np.isfinite(q).all():
        return 'non_finite'
    n = math.sqrt(sum(x * x for x in q))
    if n == 0:
        return 'zero_quaternion'
    return 'non_unit_quaternion' if abs(n - 1) > TOL else None


def bad_messages():
    """[(topic, type, t, msg)] and {topic: [(q, p, cov0)]} of a bag of bad and good inputs."""
    b = bh.Builder()
    plan = {}
    q = unit_quaternions(30)
    pose = [(q[k], RNG.normal(size=3), 0.0) for k in range(30)]
    pose[3] = (q[3], np.array([NAN, 0, 0]), 0.0)
    pose[5] = (q[5] * 1.01, pose[5][1], 0.0)
    pose[7] = (np.array([q[7][0], q[7][1], INF, q[7][3]]), pose[7][1], 0.0)
    pose[9] = (np.zeros(4), pose[9][1], 0.0)
    pose[11] = (q[11] * (1 + 0.9 * TOL), pose[11][1], 0.0)  # within the tolerance
    pose[13] = (np.zeros(4), np.array([0, INF, 0]), 0.0)  # position first
    plan['/pose'] = ('geometry_msgs/msg/PoseStamped', pose,
                     lambda s, q, p, c: b.pose_stamped(s, p, q))
    plan['/odom_w0'] = ('nav_msgs/msg/Odometry',
                        [(np.zeros(4), np.array([k, 0.0, 0.0]), 0.0) for k in range(20)],
                        lambda s, q, p, c: b.odometry(s, p, q))
    imu = [(q[k], None, 0.0) for k in range(10)]
    imu[2] = (q[2], None, -1.0)
    imu[4] = (np.zeros(4), None, -1.0)  # no orientation first
    imu[6] = (np.array([NAN, 0, 0, 1.0]), None, 0.0)
    plan['/imu'] = ('sensor_msgs/msg/Imu', imu, lambda s, q, p, c: b.imu(s, q, cov0=c))
    plan['/q'] = ('geometry_msgs/msg/QuaternionStamped', [(q[k], None, 0.0) for k in range(5)],
                  lambda s, q, p, c: b.quaternion_stamped(s, q))
    tf = [(q[k], RNG.normal(size=3), 0.0) for k in range(6)]
    tf[1] = (q[1], np.array([0, 0, NAN]), 0.0)
    tf[2] = (q[2] * 0.99, tf[2][1], 0.0)
    plan['/transform'] = ('geometry_msgs/msg/TransformStamped', tf,
                          lambda s, q, p, c: b.transform_stamped(s, p, q))
    plan['/pwc'] = ('geometry_msgs/msg/PoseWithCovarianceStamped',
                    [(q[k], RNG.normal(size=3), 0.0) for k in range(5)],
                    lambda s, q, p, c: b.pose_with_covariance_stamped(s, p, q))
    messages = []
    for topic, (msgtype, items, make) in plan.items():
        for k, (qk, pk, ck) in enumerate(items):
            stamp = 100.0 + 0.1 * k
            messages.append((topic, msgtype, int(stamp * 1e9), make(stamp, qk, pk, ck)))
    messages.append(('/chatter', 'std_msgs/msg/String', 100_000_000_000, b.string('hello')))
    messages.sort(key=lambda m: m[2])
    return messages, {t: (m, items) for t, (m, items, _) in plan.items()}


@pytest.fixture(scope='module', params=['sqlite3', 'mcap'])
def bad_bag(request, tmp_path_factory):
    messages, plan = bad_messages()
    path = bh.write_bag(tmp_path_factory.mktemp('bad') / 'bag', messages, request.param)
    return path, plan


def test_refusals_are_counted_by_reason(capsys, bad_bag):
    path, plan = bad_bag
    status, out, err = bh.run_quiet(capsys, 'bag', path, '--json')
    assert (status, err) == (0, '')
    topics = json.loads(out)['topics']
    assert set(topics) == set(plan)  # /chatter (std_msgs/String) is not read
    for topic, (msgtype, items) in plan.items():
        reasons = [expected_reason(q, p, c) for q, p, c in items]
        s = topics[topic]
        assert s['type'] == msgtype
        assert s['messages'] == len(items)
        assert s['accepted'] == reasons.count(None)
        for reason in ('non_finite', 'zero_quaternion', 'non_unit_quaternion',
                       'no_orientation'):
            assert s['refused'][reason] == reasons.count(reason), (topic, reason)
        assert s['refused']['total'] == len(items) - reasons.count(None)
    assert topics['/odom_w0']['refused']['zero_quaternion'] == 20
    assert topics['/odom_w0']['first_refusal'] == 'pose.pose.orientation is the zero quaternion'
    assert 'rpy_range' not in topics['/odom_w0']
    assert topics['/pose']['first_refusal'] == 'pose.position.x is nan'
    assert topics['/imu']['first_refusal'] == (
        'orientation_covariance[0] is -1: the IMU gives no orientation estimate')
    assert topics['/transform']['first_refusal'] == 'transform.translation.z is nan'
    assert 'first_refusal' not in topics['/q']


def test_accepted_rows_are_the_normalised_inputs(capsys, bad_bag):
    path, plan = bad_bag
    status, out, err = bh.run_quiet(capsys, 'bag', path, '--csv', '-')
    assert (status, err) == (0, '')
    rows = list(csv.DictReader(io.StringIO(out)))
    assert not [r for r in rows if r['topic'] == '/odom_w0']
    for topic, (_, items) in plan.items():
        good = [(q, p) for q, p, c in items if expected_reason(q, p, c) is None]
        mine = [r for r in rows if r['topic'] == topic]
        assert len(mine) == len(good)
        if not good:
            continue
        q = np.array([g[0] for g in good])
        rot = Rotation.from_quat(q)  # scipy normalises
        got = np.array([[float(r[c]) for c in ('qx', 'qy', 'qz', 'qw')] for r in mine])
        want = rot.as_quat() * np.where(rot.as_quat()[:, 3] < 0, -1, 1)[:, None]
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-11)
        rpy = np.array([[float(r[c]) for c in ('roll', 'pitch', 'yaw')] for r in mine])
        np.testing.assert_allclose(rpy, np.unwrap(rot.as_euler(RPY_SEQUENCE), axis=0), atol=1e-10)
        if good[0][1] is not None:
            xyz = np.array([[float(r[c]) for c in 'xyz'] for r in mine])
            np.testing.assert_allclose(xyz, [g[1] for g in good], rtol=1e-11)
        # ω is from the previous *accepted* message
        R = rot.as_matrix()
        stamps = np.array([float(r['stamp']) for r in mine])
        if len(mine) > 1:
            rel = Rotation.from_matrix(np.einsum('nji,njk->nik', R[:-1], R[1:]))
            w = rel.as_rotvec() / np.diff(stamps)[:, None]
            got_w = np.array([[float(r[c]) for c in ('wx', 'wy', 'wz')] for r in mine[1:]])
            np.testing.assert_allclose(got_w, w, rtol=1e-9, atol=1e-9)


def test_tolerance_option(capsys, bad_bag):
    path, plan = bad_bag
    s = bh.summary_of(capsys, 'bag', path, '--tol', '0.02', '--topic', '/pose', run=bh.run_quiet)
    # the 1.01 × q now passes; zero, NaN and Inf still do not
    assert s['topics']['/pose']['refused'] == {
        'total': 4, 'non_finite': 3, 'zero_quaternion': 1, 'non_unit_quaternion': 0,
        'no_orientation': 0}


# One line and exit status 2


@pytest.fixture(scope='module')
def script():
    return console_script('rot-tools', 'rot_tools.cli.main')


def one_line_error(script, *args, env=None, contains=''):
    """Assert one error line, no warning, nothing else, status 2; with ``env``, by ``script``."""
    if env is None:
        proc = run(*args)  # in this process, Python's warnings on stderr
    else:
        proc = subprocess.run(script + [str(a) for a in args], capture_output=True, text=True,
                              timeout=120, env=env)
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    assert proc.stdout == ''
    lines = proc.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith('rot-tools: error: '), proc.stderr
    assert contains in lines[0], lines[0]
    return lines[0]


@pytest.fixture(scope='module')
def damaged(tmp_path_factory):
    """Damaged copies of the real recording (of its first 300 messages), in each format."""
    tmp = tmp_path_factory.mktemp('damaged')
    out = {}
    excerpt = bh.real_excerpt(tmp / 'excerpt.bag')
    data = excerpt.read_bytes()
    out['truncated ros1'] = tmp / 'truncated.bag'
    out['truncated ros1'].write_bytes(data[:len(data) // 2])
    out['garbage ros1'] = tmp / 'garbage.bag'
    out['garbage ros1'].write_bytes(bytes(RNG.integers(0, 256, 4096, dtype=np.uint8)))
    out['flipped ros1'] = tmp / 'flipped.bag'  # a record header's bytes inverted
    out['flipped ros1'].write_bytes(flipped(data, len(data) // 2, 5, 97))
    out['zeroed ros1'] = tmp / 'zeroed.bag'  # 2,000 bytes zeroed: a chunk's records
    middle = len(data) // 2
    out['zeroed ros1'].write_bytes(data[:middle] + bytes(2000) + data[middle + 2000:])
    for storage in ('sqlite3', 'mcap'):
        bag = bh.convert_real(tmp / storage, storage, excerpt)
        inner = next(p for p in bag.iterdir() if p.suffix in ('.db3', '.mcap'))
        raw = inner.read_bytes()
        inner.write_bytes(raw[:len(raw) // 3])
        out[f'truncated {storage}'] = bag
        if storage == 'mcap':  # a message's bytes inverted: it no longer decodes
            out['flipped mcap'] = tmp / 'flipped.mcap'
            out['flipped mcap'].write_bytes(flipped(raw, len(raw) // 3, 20, 131))
            # 2,000 bytes zeroed: rosbags' reader skips the chunk they hit, saying nothing
            out['zeroed mcap'] = tmp / 'zeroed.mcap'
            middle = len(raw) // 2
            out['zeroed mcap'].write_bytes(raw[:middle] + bytes(2000) + raw[middle + 2000:])
    return out


def flipped(data, start, count, step):
    """Return bytes with ``count`` of them inverted, every ``step`` from ``start``."""
    data = bytearray(data)
    for k in range(count):
        data[start + k * step] ^= 0xff
    return bytes(data)


@pytest.mark.parametrize('which', ['truncated ros1', 'garbage ros1', 'flipped ros1',
                                   'zeroed ros1', 'truncated sqlite3', 'truncated mcap',
                                   'flipped mcap', 'zeroed mcap'])
def test_damaged_bags_are_one_line_naming_the_bag(script, damaged, which):
    one_line_error(script, 'bag', damaged[which], contains=f'bag: {damaged[which]}: ')


def test_a_chunk_the_reader_skips_is_an_error_not_a_shorter_topic(script, damaged):
    one_line_error(script, 'bag', damaged['zeroed mcap'],
                   contains='messages its index lists could be read: the bag is damaged')


def test_a_message_that_does_not_decode(script, tmp_path):
    """Check a message cut short: the fast path refuses its layout, rosbags too."""
    from rosbags.rosbag2 import Writer
    b = bh.Builder()
    path = tmp_path / 'cut'
    with Writer(path, version=8) as writer:
        conn = writer.add_connection('/pose', 'geometry_msgs/msg/PoseStamped',
                                     typestore=b.store)
        for k in range(5):
            raw = b.store.serialize_cdr(b.pose_stamped(1.0 + k, (0, 0, 0), (0, 0, 0, 1.0)),
                                        'geometry_msgs/msg/PoseStamped')
            writer.write(conn, k + 1, bytes(raw[:-20]) if k == 3 else bytes(raw))
    line = one_line_error(script, 'bag', path, contains='/pose: message 3 cannot be decoded')
    assert 'PoseStamped' in line


def test_missing_and_empty_bags(script, tmp_path):
    one_line_error(script, 'bag', tmp_path / 'nope.bag', contains='no such file')
    (tmp_path / 'empty.bag').write_bytes(b'')
    one_line_error(script, 'bag', tmp_path / 'empty.bag', contains='empty')
    (tmp_path / 'dir').mkdir()
    one_line_error(script, 'bag', tmp_path / 'dir', contains='metadata.yaml')
    from rosbags.rosbag2 import Writer
    with Writer(tmp_path / 'none', version=8) as writer:
        writer.add_connection('/pose', 'geometry_msgs/msg/PoseStamped',
                              typestore=bh.store())
    one_line_error(script, 'bag', tmp_path / 'none', contains='holds no messages')


def test_topics_asked_for(script, bad_bag):
    path, _ = bad_bag
    one_line_error(script, 'bag', path, '--topic', '/chatter',
                   contains='topic /chatter is a std_msgs/msg/String, not one of')
    one_line_error(script, 'bag', path, '--topic', '/nope', contains='no topic /nope in the bag')


def test_a_bag_without_a_topic_to_read(script, tmp_path):
    b = bh.Builder()
    path = bh.write_bag(tmp_path / 'chat', [('/chatter', 'std_msgs/msg/String', 1,
                                             b.string('hi'))])
    one_line_error(script, 'bag', path, contains='no topic of a type read here')


def test_a_bag_with_nothing_asked_for_is_skipped(capsys, tmp_path):
    """Check what is BagSkipped (a fleet's ``skipped``) and what a BagError (``failed``)."""
    from rot_tools.cli import bag_analysis
    from rot_tools.io import bag_read
    from rosbags.rosbag2 import Writer
    b = bh.Builder()
    chat = bh.write_bag(tmp_path / 'chat', [('/chatter', 'std_msgs/msg/String', 1,
                                             b.string('hi'))])
    both = bh.write_bag(tmp_path / 'both', [
        ('/chatter', 'std_msgs/msg/String', 1, b.string('hi')),
        ('/pose', 'geometry_msgs/msg/PoseStamped', 2, b.pose_stamped(1.0, (0, 0, 0),
                                                                     (0, 0, 0, 1.0)))])
    with Writer(tmp_path / 'none', version=8) as writer:
        writer.add_connection('/pose', 'geometry_msgs/msg/PoseStamped', typestore=bh.store())
    cases = [
        (True, (chat,), 'no topic of a type read here in the bag: /chatter (std_msgs/msg/String)'),
        (True, (tmp_path / 'none',), 'the bag holds no messages'),
        (True, (both, '--topic', '/nope', '--topic', '/nada'),
         'none of the topics asked for (/nope, /nada) is in the bag (its topics: /chatter, '
         '/pose)'),
        (False, (both, '--topic', '/pose', '--topic', '/nope'), 'no topic /nope in the bag'),
        (False, (both, '--topic', '/chatter'), 'topic /chatter is a std_msgs/msg/String')]
    for skipped, (bag, *options), contains in cases:
        with pytest.raises(bag_read.BagError, match=re.escape(contains)) as caught:
            bag_analysis.analyse(bag, options[1::2])
        assert isinstance(caught.value, bag_read.BagSkipped) == skipped, contains
        status, out, err = bh.run_quiet(capsys, 'bag', bag, *options)
        assert (status, out) == (2, '') and err.count('\n') == 1 and contains in err, err


@pytest.mark.parametrize('args, contains', [
    (('--start', '5', '--end', '2'), '--end 2 is before --start 5'),
    (('--start', '-1'), 'must be >= 0'),
    (('--end', 'nan'), 'not a finite number'),
    (('--point', '1', '2', '3'), 'unrecognized arguments: --point'),
    (('--seq', 'ABC'), 'unknown Euler sequence'),
    (('--plot', 'x.pdf'), 'must end in .png or .svg'),
    (('--csv',), 'expected one argument'),
])
def test_bad_options(script, args, contains):
    one_line_error(script, 'bag', bh.REAL, *args, contains=contains)


@pytest.mark.parametrize('option', [('--point', '1', '2', '3'), ('--wxyz',),
                                    ('--all-sequences',)])
def test_options_of_other_commands_before_bag(script, option):
    one_line_error(script, *option, 'bag', bh.REAL, contains=f'{option[0]} does not apply to bag')


def test_without_rosbags(script, tmp_path):
    fake = tmp_path / 'fake' / 'rosbags'
    fake.mkdir(parents=True)
    (fake / '__init__.py').write_text("raise ImportError('no rosbags here', name='rosbags')\n")
    env = script_env(script)
    env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(fake.parent),
                                                      env.get('PYTHONPATH')]))
    one_line_error(script, 'bag', bh.REAL, env=env,
                   contains="the 'bag' extra: pip install -e '.[bag]' in the rot_tools checkout")


class Terminal(io.StringIO):
    """A text stream that says it is a terminal, as a tty's stderr does."""

    def isatty(self):
        return True


def test_progress_bar_only_on_a_terminal(capsys, monkeypatch, bad_bag):
    path, plan = bad_bag
    status, out, err = bh.run_quiet(capsys, 'bag', path)
    assert (status, err) == (0, '') and out.startswith('bag: ')
    terminal = Terminal()
    monkeypatch.setattr(sys, 'stderr', terminal)
    status, out, _ = bh.run_quiet(capsys, 'bag', path)
    total = sum(len(items) for _, items in plan.values())
    bar = bh.without_gyro_warnings(terminal.getvalue())
    assert status == 0 and out.startswith('bag: ')
    assert bar.startswith('\rrot-tools bag: [') and f'{total}/{total} messages' in bar
    assert bar.endswith('\r' + ' ' * 79 + '\r')  # wiped before the summary
