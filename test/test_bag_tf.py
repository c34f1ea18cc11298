"""rot-tools bag --tf REFERENCE BODY: a TF chain in a bag, against 4×4 products (scipy)."""

import csv
import io
import json

import bag_helpers as bh
from conftest import one_error, run_cli
from doc_blocks import assert_doc_output
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
pytest.importorskip('rot_tools.core.transform_tree', reason='TransformTree has not landed')
from rot_tools.cli import bag_analysis  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402


@pytest.fixture(scope='module', params=['sqlite3', 'mcap'])
def tf_bag(request, tmp_path_factory):
    messages, truth, static = bh.tf_chain_messages()
    path = bh.write_bag(tmp_path_factory.mktemp('tf') / 'bag', messages, request.param)
    return path, truth, static


def homogeneous(q, t):
    T = np.eye(4)
    T[:3, :3] = Rotation.from_quat(q).as_matrix()
    T[:3, 3] = t
    return T


def test_tf_chain_values(capsys, tf_bag):
    path, truth, static = tf_bag
    status, out, err = run_cli(capsys, 'bag', path, '--tf', 'map', 'imu', '--csv', '-')
    assert (status, err) == (0, '')
    rows = list(csv.DictReader(io.StringIO(out)))
    assert len(rows) == len(truth)
    assert {r['topic'] for r in rows} == {'tf:map->imu'}
    assert {r['frame_id'] for r in rows} == {'map'}
    T_static = homogeneous(*static)
    for row, (stamp, sample) in zip(rows, sorted(truth.items())):
        assert float(row['stamp']) == pytest.approx(stamp, abs=1e-9)
        want = homogeneous(*sample['map', 'odom']) @ homogeneous(
            *sample['odom', 'base_link']) @ T_static
        q = Rotation.from_matrix(want[:3, :3]).as_quat()
        q *= 1 if q[3] > 0 else -1
        np.testing.assert_allclose([float(row[c]) for c in ('qx', 'qy', 'qz', 'qw')], q,
                                   atol=1e-11)
        np.testing.assert_allclose([float(row[c]) for c in 'xyz'], want[:3, 3], atol=1e-11)


def test_tf_summary_counts_refused_transforms(capsys, tf_bag):
    path, truth, _ = tf_bag
    status, out, err = run_cli(capsys, 'bag', path, '--tf', 'map', 'imu', '--json')
    assert (status, err) == (0, '')
    s = json.loads(out)['topics']['tf:map->imu']
    assert s['chain'] == ['map', 'odom', 'base_link', 'imu']
    assert s['transforms'] == 3 * len(truth) + 1
    assert s['refused']['zero_quaternion'] == 1 and s['refused']['total'] == 1
    assert s['first_refusal'] == 'transform.rotation is the zero quaternion'
    assert s['lookups'] == len(truth)
    assert (s['frame_ids'], s['child_frame_ids']) == (['map'], ['imu'])
    # with --topic, named topics come too; without, only the chain
    assert list(json.loads(run_cli(capsys, 'bag', path, '--tf', 'odom', 'imu', '--json')[1])[
        'topics']) == ['tf:odom->imu']


@pytest.mark.parametrize('frames, contains', [
    (('map', 'camera'), 'frame camera never appears in the bag'),
    (('nowhere', 'imu'), 'frame nowhere never appears'),
])
def test_tf_frames_that_never_appear(capsys, tf_bag, frames, contains):
    path, _, _ = tf_bag
    one_error(capsys, 'bag', path, '--tf', *frames, contains=contains)


def test_tf_in_a_bag_without_tf(capsys):
    status, _, err = run_cli(capsys, 'bag', bh.REAL, '--tf', 'odom', 'base_link')
    assert status == 2 and 'no tf2_msgs/msg/TFMessage topic' in err and err.count('\n') == 1


def test_a_tf_only_bag_without_tf_names_the_option_and_its_frames(capsys, tf_bag):
    """Skipped (nothing to read without --tf), with the words that read it."""
    from rot_tools.io import bag_read
    path = tf_bag[0]
    status, out, err = run_cli(capsys, 'bag', path)
    assert (status, out) == (2, '') and err == (
        'rot-tools: error: bag: no topic of a type read here in the bag: /tf '
        '(tf2_msgs/msg/TFMessage), /tf_static (tf2_msgs/msg/TFMessage); its TF holds the frames '
        'base_link, imu, map, odom, wheel (base_link -> imu, map -> odom, odom -> base_link, '
        'odom -> wheel): give --tf PARENT CHILD to follow CHILD in PARENT\n')
    assert_doc_output('bag-tf-only', f'$ rot-tools bag tf_only_bag\n{err}')
    with pytest.raises(bag_read.BagSkipped):
        bag_analysis.analyse(path)
    for frames in (('map', 'nowhere'), ('odom', 'base_link')):
        with pytest.raises(bag_read.BagSkipped):
            bag_analysis.analyse(bh.REAL if frames[1] == 'base_link' else path, tf=frames)


def tf_bag_of(tmp_path, samples):
    """Return a bag of /tf messages: samples [(stamp ns, parent, child, q, t)], one each."""
    b = bh.Builder()
    messages = []
    for k, (ns, parent, child, q, t) in enumerate(samples):
        sec, nanosec = divmod(ns, 10**9)
        tf = b.transform_stamped(0.0, t, q, parent, child)
        tf.header.stamp.sec, tf.header.stamp.nanosec = sec, nanosec
        messages.append(('/tf', 'tf2_msgs/msg/TFMessage', 10**9 + k, b.tf_message([tf])))
    return bh.write_bag(tmp_path / 'bag', messages)


def random_transforms(rng, n):
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None], rng.normal(size=(n, 3))


def test_tf_an_empty_frame_and_a_loop_are_counted_and_the_rest_goes_on(capsys, tmp_path):
    messages, truth, _ = bh.tf_chain_messages()
    b = bh.Builder()
    q = np.array([0.0, 0.0, 0.0, 1.0])
    bad = [b.transform_stamped(1.05, (1, 2, 3), q, 'odom', ''),  # an empty child_frame_id
           b.transform_stamped(1.05, (1, 2, 3), q, 'x', 'y'),
           b.transform_stamped(1.06, (1, 2, 3), q, 'y', 'x')]  # x and y: a loop
    messages.append(('/tf', 'tf2_msgs/msg/TFMessage', 1_050_000_000, b.tf_message(bad)))
    path = bh.write_bag(tmp_path / 'bag', messages)
    status, out, err = run_cli(capsys, 'bag', path, '--tf', 'map', 'imu', '--json')
    assert (status, err) == (0, '')
    s = json.loads(out)['topics']['tf:map->imu']
    assert s['refused'] == {'total': 3, 'non_finite': 0, 'zero_quaternion': 1,
                            'non_unit_quaternion': 0, 'no_orientation': 0, 'bad_frame': 1,
                            'loop': 1, 'too_many_frames': 0}
    assert s['lookups'] == len(truth) and s['accepted'] == s['transforms'] - 3


def test_tf_a_reparented_frame_is_used_under_each_parent(capsys, tmp_path):
    """base_link under odom for 1.0–2.0 s, then straight under map for 2.1–3.0 s."""
    rng = np.random.default_rng(3)
    samples, truth = [], {}
    q, t = random_transforms(rng, 60)
    for k in range(21):
        ns = 10**9 + k * 10**8
        samples.append((ns, 'map', 'odom', q[k], t[k]))
        parent = 'odom' if k <= 10 else 'map'
        samples.append((ns, parent, 'base_link', q[30 + k], t[30 + k]))
        T = homogeneous(q[30 + k], t[30 + k])
        truth[ns] = homogeneous(q[k], t[k]) @ T if parent == 'odom' else T
    path = tf_bag_of(tmp_path, samples)
    status, out, err = run_cli(capsys, 'bag', path, '--tf', 'map', 'base_link', '--json')
    assert (status, err) == (0, '')
    s = json.loads(out)['topics']['tf:map->base_link']
    assert (s['accepted'], s['lookups']) == (42, 21)
    assert s['chain'] == [['map', 'odom', 'base_link'], ['map', 'base_link']]
    rows = list(csv.DictReader(io.StringIO(
        run_cli(capsys, 'bag', path, '--tf', 'map', 'base_link', '--csv', '-')[1])))
    assert [r['stamp'] for r in rows] == [f'{ns // 10**9}.{ns % 10**9:09d}' for ns in truth]
    for row, want in zip(rows, truth.values()):
        np.testing.assert_allclose([float(row[c]) for c in 'xyz'], want[:3, 3], atol=1e-11)


def test_tf_stamps_nanoseconds_apart_are_distinct_lookups(capsys, tmp_path):
    rng = np.random.default_rng(4)
    base = 1_700_000_000 * 10**9
    offsets = [0, 1, 2, 3, 50, 100, 101, 200]
    q, t = random_transforms(rng, len(offsets))
    path = tf_bag_of(tmp_path, [(base + d, 'map', 'body', q[k], t[k])
                                for k, d in enumerate(offsets)])
    status, out, err = run_cli(capsys, 'bag', path, '--tf', 'map', 'body', '--csv', '-')
    assert (status, err) == (0, '')
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [r['stamp'] for r in rows] == [f'1700000000.{d:09d}' for d in offsets]
    for row, qk, tk in zip(rows, q, t):  # each lookup is its own sample, exactly
        np.testing.assert_allclose([float(row[c]) for c in 'xyz'], tk, atol=1e-11)
        qk = qk * np.sign(qk[3])
        np.testing.assert_allclose([float(row[c]) for c in ('qx', 'qy', 'qz', 'qw')], qk,
                                   atol=1e-11)
