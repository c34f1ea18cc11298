"""
rot-tools bag --tf REFERENCE BODY: a TF chain recorded in a bag, through TransformTree.

The bag (written here) holds map → odom and odom → base_link, dynamic and sampled together,
and base_link → imu on /tf_static; the lookups at the samples' stamps are exact compositions,
checked against 4×4 homogeneous matrices built here with scipy.
"""

import csv
import io
import json

import bag_helpers as bh
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
pytest.importorskip('rot_tools.core.transform_tree', reason='TransformTree has not landed')
from rot_tools.cli import main as cli  # noqa: E402
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


def run(capsys, *args):
    status = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


def test_tf_chain_values(capsys, tf_bag):
    path, truth, static = tf_bag
    status, out, err = run(capsys, 'bag', path, '--tf', 'map', 'imu', '--csv', '-')
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
    status, out, err = run(capsys, 'bag', path, '--tf', 'map', 'imu', '--json')
    assert (status, err) == (0, '')
    s = json.loads(out)['topics']['tf:map->imu']
    assert s['chain'] == ['map', 'odom', 'base_link', 'imu']
    assert s['transforms'] == 3 * len(truth) + 1
    assert s['refused']['zero_quaternion'] == 1 and s['refused']['total'] == 1
    assert s['first_refusal'] == 'transform.rotation is the zero quaternion'
    assert s['lookups'] == len(truth)
    assert (s['frame_ids'], s['child_frame_ids']) == (['map'], ['imu'])
    # with --topic, named topics come too; without, only the chain
    assert list(json.loads(run(capsys, 'bag', path, '--tf', 'odom', 'imu', '--json')[1])[
        'topics']) == ['tf:odom->imu']


@pytest.mark.parametrize('frames, contains', [
    (('map', 'camera'), 'frame camera never appears in the bag'),
    (('nowhere', 'imu'), 'frame nowhere never appears'),
])
def test_tf_frames_that_never_appear(capsys, tf_bag, frames, contains):
    path, _, _ = tf_bag
    status, out, err = run(capsys, 'bag', path, '--tf', *frames)
    assert status == 2 and out == ''
    assert err.count('\n') == 1 and err.startswith('rot-tools: error: ') and contains in err


def test_tf_in_a_bag_without_tf(capsys):
    status, _, err = run(capsys, 'bag', bh.REAL, '--tf', 'odom', 'base_link')
    assert status == 2 and 'no tf2_msgs/msg/TFMessage topic' in err and err.count('\n') == 1
