"""rot-tools bag on the real recording and on rosbag2 copies, against scipy and rosbags."""

import math

import bag_helpers as bh
from conftest import run_cli
import numpy as np
import pytest

rosbags = pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
from rot_tools.cli import bag_output  # noqa: E402
from rot_tools.core.euler import RPY_SEQUENCE  # noqa: E402
from rot_tools.io import bag_read  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

IMU, ODOM = '/imu/data', '/jackal_velocity_controller/odom'


@pytest.fixture(scope='module')
def reference():
    """{topic: dict of arrays} decoded message by message by rosbags (the user's way)."""
    return bh.decode()


EXCERPT = 150
"""Messages on each topic of the excerpt of the real recording (bag_helpers.real_excerpt)."""


@pytest.fixture(scope='module')
def converted(tmp_path_factory):
    """Return an excerpt of the real recording: ROS 1 as recorded, rosbag2 sqlite3 and MCAP."""
    tmp = tmp_path_factory.mktemp('converted')
    ros1 = bh.real_excerpt(tmp / 'excerpt.bag', 2 * EXCERPT)
    return {'ros1': ros1, **{s: bh.convert_real(tmp / s, s, ros1) for s in ('sqlite3', 'mcap')}}


def log_map(R):
    """Rotation vectors of rotations R (n, 3, 3), away from π (written here, not rot_tools)."""
    cos = np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1)
    angle = np.arccos(cos)
    w = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], 1)
    sin = np.sin(angle)
    scale = np.where(angle < 1e-6, 0.5 + angle ** 2 / 12, angle / (2 * np.where(sin == 0, 1, sin)))
    return w * scale[:, None]


def canonical(q):
    """Return q with w > 0 (none of the real bag's quaternions has w = 0)."""
    return q * np.where(q[:, 3] < 0, -1.0, 1.0)[:, None]


def col(rows, *names):
    return np.array([[float(r[n]) for n in names] for r in rows])


# The summary


def test_summary_of_the_real_bag(capsys, reference):
    s = bh.summary_of(capsys, 'bag', bh.REAL)
    assert s['storage'] == 'rosbag1'
    assert list(s['topics']) == [IMU, ODOM]
    imu, odom = s['topics'][IMU], s['topics'][ODOM]
    assert (imu['type'], imu['frame_ids'], imu['messages'], imu['accepted']) == (
        'sensor_msgs/msg/Imu', ['base_link'], 3061, 3061)
    assert (odom['type'], odom['frame_ids'], odom['child_frame_ids'], odom['messages']) == (
        'nav_msgs/msg/Odometry', ['odom'], ['base_link'], 3060)
    assert imu['refused'] == {'total': 0, 'non_finite': 0, 'zero_quaternion': 0,
                              'non_unit_quaternion': 0, 'no_orientation': 0}
    for topic in (IMU, ODOM):
        t, ref = s['topics'][topic], reference[topic]
        assert t['start'] == pytest.approx(ref['stamp'].min(), abs=1e-9)
        assert t['end'] == pytest.approx(ref['stamp'].max(), abs=1e-9)
        assert t['rate'] == pytest.approx((len(ref['stamp']) - 1) / np.ptp(ref['stamp']),
                                          rel=1e-9)
        rot = Rotation.from_quat(ref['q'])
        rpy = np.unwrap(rot.as_euler(RPY_SEQUENCE), axis=0)
        for k, name in enumerate(('roll', 'pitch', 'yaw')):
            np.testing.assert_allclose(t['rpy_range'][name], [rpy[:, k].min(), rpy[:, k].max()],
                                       rtol=0, atol=1e-10)
        # total angle: Σ 2·acos|q_{k-1}·q_k| of the unit quaternions (no matrix involved)
        qn = ref['q'] / np.linalg.norm(ref['q'], axis=1)[:, None]
        dots = np.abs(np.sum(qn[:-1] * qn[1:], axis=1))
        steps = 2 * np.arctan2(np.linalg.norm(
            qn[1:, :3] * qn[:-1, 3:] - qn[:-1, :3] * qn[1:, 3:]
            - np.cross(qn[:-1, :3], qn[1:, :3]), axis=1), dots)
        assert t['total_angle'] == pytest.approx(steps.sum(), rel=1e-9)
        mean = rot.mean()
        got = t['mean_orientation']['quaternion']
        np.testing.assert_allclose([got[c] for c in 'xyzw'], canonical(mean.as_quat()[None])[0],
                                   rtol=0, atol=1e-9)
        np.testing.assert_allclose(list(t['mean_orientation']['rpy'].values()),
                                   mean.as_euler(RPY_SEQUENCE), rtol=0, atol=1e-9)
    # Imu: RMS |ω − mean gyro of the step's ends|, ω from consecutive orientations
    ref = reference[IMU]
    rel = Rotation.from_quat(ref['q'][:-1]).inv() * Rotation.from_quat(ref['q'][1:])
    omega = rel.as_rotvec() / np.diff(ref['stamp'])[:, None]
    diff = omega - 0.5 * (ref['gyro'][:-1] + ref['gyro'][1:])
    assert imu['gyro_rms_difference'] == pytest.approx(
        math.sqrt(np.mean(np.sum(diff ** 2, axis=1))), rel=1e-7)
    assert imu['gyro_rms_difference_unit'] == 'rad/s'
    assert 'gyro_rms_difference' not in odom


def test_summary_in_degrees_and_yaml(capsys):
    yaml = pytest.importorskip('yaml')
    rad = bh.summary_of(capsys, 'bag', bh.REAL)
    status, out, err = run_cli(capsys, '--deg', 'bag', bh.REAL)  # an option before the command
    assert (status, err) == (0, '')
    deg = yaml.safe_load(out)
    for topic in (IMU, ODOM):
        r, d = rad['topics'][topic], deg['topics'][topic]
        assert d['unit'] == 'deg'
        np.testing.assert_allclose(d['rpy_range']['yaw'], np.degrees(r['rpy_range']['yaw']),
                                   rtol=1e-11)
        assert d['total_angle'] == pytest.approx(math.degrees(r['total_angle']), rel=1e-11)
        assert d['messages'] == r['messages']


# The CSV


def test_csv_rows_of_the_real_bag(capsys, reference):
    rows = bh.rows_of(capsys, 'bag', bh.REAL, '--seq', 'ZYX')
    assert list(rows[0]) == bag_output.csv_header('ZYX') == [
        'topic', 'stamp', 'frame_id', 'x', 'y', 'z', 'qx', 'qy', 'qz', 'qw', 'roll', 'pitch',
        'yaw', 'ZYX_1', 'ZYX_2', 'ZYX_3', 'rx', 'ry', 'rz', 'angle', 'wx', 'wy', 'wz',
        'roll_std', 'pitch_std', 'yaw_std']  # σ: test_bag_covariance.py
    for topic in (IMU, ODOM):
        ref = reference[topic]
        mine = [r for r in rows if r['topic'] == topic]
        assert len(mine) == len(ref['q'])
        # stamps exactly as recorded: sec.nanosec
        stamps = [f'{s}.{n:09d}' for s, n in zip(ref['sec'], ref['nsec'])]
        assert [r['stamp'] for r in mine] == stamps
        assert [r['frame_id'] for r in mine] == ref['frame']
        np.testing.assert_allclose(col(mine, 'x', 'y', 'z'), ref['p'], rtol=1e-11, atol=1e-12)
        rot = Rotation.from_quat(ref['q'])
        q = col(mine, 'qx', 'qy', 'qz', 'qw')
        np.testing.assert_allclose(q, canonical(rot.as_quat()), rtol=0, atol=1e-11)
        assert (q[:, 3] > 0).all()
        np.testing.assert_allclose(col(mine, 'roll', 'pitch', 'yaw'),
                                   np.unwrap(rot.as_euler(RPY_SEQUENCE), axis=0), rtol=0,
                                   atol=1e-10)
        np.testing.assert_allclose(col(mine, 'ZYX_1', 'ZYX_2', 'ZYX_3'),
                                   np.unwrap(rot.as_euler('ZYX'), axis=0), rtol=0, atol=1e-10)
        np.testing.assert_allclose(col(mine, 'rx', 'ry', 'rz'), rot.as_rotvec(), rtol=0,
                                   atol=1e-11)
        np.testing.assert_allclose(col(mine, 'angle')[:, 0], rot.magnitude(), rtol=0,
                                   atol=1e-11)
        # body angular velocity from the previous row: log(R_{k-1}ᵀ R_k) / Δt
        assert [mine[0][c] for c in ('wx', 'wy', 'wz')] == ['', '', '']
        R = rot.as_matrix()
        w = log_map(np.einsum('nji,njk->nik', R[:-1], R[1:])) / np.diff(ref['stamp'])[:, None]
        np.testing.assert_allclose(col(mine[1:], 'wx', 'wy', 'wz'), w, rtol=1e-9, atol=1e-9)
    # the yaw of the odometry really turns past ±π (what unwrapping is for)
    yaw = col([r for r in rows if r['topic'] == ODOM], 'yaw')[:, 0]
    assert yaw.max() > 10 * math.pi and np.abs(np.diff(yaw)).max() < 0.1


def test_csv_wrap_and_degrees(capsys, reference):
    rows = bh.rows_of(capsys, 'bag', bh.REAL, '--topic', ODOM, '--wrap', '--deg')
    ref = reference[ODOM]
    rot = Rotation.from_quat(ref['q'])
    got = col(rows, 'roll', 'pitch', 'yaw')
    want = np.degrees(rot.as_euler(RPY_SEQUENCE))
    assert got.max() <= 180 and got.min() > -180
    # ±180° are the same angle: compare on the circle
    np.testing.assert_allclose((got - want + 180) % 360 - 180, 0, atol=1e-9)
    np.testing.assert_allclose(col(rows, 'angle')[:, 0], np.degrees(rot.magnitude()),
                               rtol=0, atol=1e-9)
    R = rot.as_matrix()
    w = log_map(np.einsum('nji,njk->nik', R[:-1], R[1:])) / np.diff(ref['stamp'])[:, None]
    np.testing.assert_allclose(col(rows[1:], 'wx', 'wy', 'wz'), np.degrees(w), rtol=1e-9,
                               atol=1e-7)
    assert {r['topic'] for r in rows} == {ODOM}


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_rosbag2_gives_what_the_ros1_bag_gives(capsys, converted, storage):
    want = bh.rows_of(capsys, 'bag', converted['ros1'], '--seq', 'zyz')
    got = bh.rows_of(capsys, 'bag', converted[storage], '--seq', 'zyz')
    assert got == want and len(got) == 2 * EXCERPT
    s = bh.summary_of(capsys, 'bag', converted[storage])
    assert s['storage'] == f'rosbag2 {storage}'
    assert s['topics'] == bh.summary_of(capsys, 'bag', converted['ros1'])['topics']
    # a file of the bag names the bag too
    inner = next(p for p in converted[storage].iterdir() if p.suffix in ('.db3', '.mcap'))
    assert bh.summary_of(capsys, 'bag', inner)['topics'] == s['topics']


@pytest.mark.parametrize('storage', ['ros1', 'sqlite3', 'mcap'])
def test_columns_are_the_fields_rosbags_decodes(converted, reference, storage):
    """Each topic's columns hold the fields of its messages, as rosbags decodes them."""
    path = bh.REAL if storage == 'ros1' else converted[storage]
    n = {IMU: 3061, ODOM: 3060} if storage == 'ros1' else {IMU: EXCERPT, ODOM: EXCERPT}
    with bag_read.open_bag(path) as reader:
        columns = bag_read.read_topics(reader, list(reader.connections))
    assert set(columns) == {IMU, ODOM}
    for topic, c in columns.items():
        ref = {name: values[:n[topic]] for name, values in reference[topic].items()}
        np.testing.assert_array_equal(c.orientation, ref['q'])
        np.testing.assert_array_equal(c.sec, ref['sec'])
        np.testing.assert_array_equal(c.nanosec, ref['nsec'])
        assert [c.frame_ids[i] for i in c.frame] == ref['frame']
        assert c.record.dtype == np.int64 and (np.diff(c.record) >= 0).all()
    imu, odom = columns[IMU], columns[ODOM]
    np.testing.assert_array_equal(imu.angular_velocity, reference[IMU]['gyro'][:n[IMU]])
    np.testing.assert_array_equal(odom.position, reference[ODOM]['p'][:n[ODOM]])
    assert imu.position is None and odom.angular_velocity is None
    assert imu.covariance.shape == (n[IMU], 9) and odom.covariance.shape == (n[ODOM], 36)
    np.testing.assert_array_equal(imu.covariance0, imu.covariance[:, 0])
    assert odom.child_frame_ids == ['base_link'] and imu.child_frame_ids is None


def test_a_bag_without_type_definitions_is_read_with_ros2_jazzy_s(capsys, tmp_path):
    b = bh.Builder()
    q = Rotation.random(5, random_state=3).as_quat()
    path = bh.without_definitions(bh.write_bag(tmp_path / 'old', [
        ('/q', 'geometry_msgs/msg/QuaternionStamped', k + 1, b.quaternion_stamped(1.0 + k, qk))
        for k, qk in enumerate(q)]))
    from rosbags.highlevel import AnyReader, AnyReaderError
    with pytest.raises(AnyReaderError, match='no type definitions'):
        AnyReader([path]).open()  # as rosbags reads it alone
    rows = bh.rows_of(capsys, 'bag', path)
    np.testing.assert_allclose(col(rows, 'qx', 'qy', 'qz', 'qw'), canonical(q), atol=1e-15)


def test_start_and_end_select_by_record_time(capsys):
    from rosbags.highlevel import AnyReader
    with AnyReader([bh.REAL]) as reader:
        t0 = reader.start_time
        times = {}
        for conn, t, _ in reader.messages():
            times.setdefault(conn.topic, []).append((t - t0) * 1e-9)
    s = bh.summary_of(capsys, 'bag', bh.REAL, '--start', 10, '--end', 20.5)
    for topic, ts in times.items():
        ts = np.array(ts)
        assert s['topics'][topic]['messages'] == int(((ts >= 10) & (ts <= 20.5)).sum()) > 400


def test_csv_to_a_file_and_the_summary_to_stdout(capsys, tmp_path):
    path = tmp_path / 'out.csv'
    status, out, err = run_cli(capsys, 'bag', bh.REAL, '--csv', path, '--topic', IMU)
    assert (status, err) == (0, '')
    assert out.startswith('bag: ') and IMU in out and ODOM not in out
    lines = path.read_text().splitlines()
    assert len(lines) == 3062 and lines[0].startswith('topic,stamp,frame_id,')


def test_plot_one_panel_per_topic(capsys, tmp_path, converted):
    pytest.importorskip('matplotlib')
    svg = tmp_path / 'rpy.svg'
    status, _, err = run_cli(capsys, 'bag', converted['ros1'], '--plot', svg)
    assert (status, err) == (0, f'rot-tools bag: --plot {svg}: roll, pitch, yaw of {IMU}, '
                                f'{ODOM}\n')
    text = svg.read_text()
    for topic in (IMU, ODOM):
        for angle in ('roll', 'pitch', 'yaw'):
            assert f'id="{topic}:{angle}"' in text
    png = tmp_path / 'rpy.png'
    assert run_cli(capsys, 'bag', converted['ros1'], '--plot', png, '--deg')[0] == 0
    assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'


def test_frame_ids_of_many_lengths_are_read_as_recorded(tmp_path):
    """Frame ids of different lengths, empty ones too, in both rosbag2 storages."""
    b = bh.Builder()
    q = Rotation.random(24, random_state=5).as_quat()
    frames = [('a', 'bbb'), ('bbb', 'a'), ('cc', 'dd'), ('', 'child'), ('xy', 'zw'), ('a', 'bbb')]
    messages = []
    for k in range(24):
        frame, child = frames[k % len(frames)]
        stamp = 10.0 + 0.05 * k
        messages.append(('/tf_stamped', 'geometry_msgs/msg/TransformStamped', k + 1,
                         b.transform_stamped(stamp, (k, -k, 0.5), q[k], frame, child)))
        messages.append(('/pose', 'geometry_msgs/msg/PoseStamped', k + 1,
                         b.pose_stamped(stamp, (k, 0, 0), q[k], frame * (k % 3))))
    for storage in ('sqlite3', 'mcap'):
        path = bh.write_bag(tmp_path / storage, messages, storage)
        with bag_read.open_bag(path) as reader:
            columns = bag_read.read_topics(reader, list(reader.connections))
        tf, pose = columns['/tf_stamped'], columns['/pose']
        assert [tf.frame_ids[i] for i in tf.frame] == [frames[k % 6][0] for k in range(24)]
        assert [tf.child_frame_ids[i] for i in tf.child] == [frames[k % 6][1] for k in range(24)]
        assert [pose.frame_ids[i] for i in pose.frame] == [
            frames[k % 6][0] * (k % 3) for k in range(24)]
        np.testing.assert_array_equal(tf.position[:, 0], np.arange(24))
        np.testing.assert_array_equal(pose.orientation, q)


def test_a_topic_read_in_many_chunks_is_one_table(monkeypatch, capsys, converted):
    """Columns read a chunk of messages at a time join into one: frame ids listed once."""
    whole = bh.rows_of(capsys, 'bag', converted['ros1'])
    monkeypatch.setattr(bag_read, 'CHUNK', 7)
    s = bh.summary_of(capsys, 'bag', converted['ros1'])
    assert s['topics'][IMU]['frame_ids'] == ['base_link']
    assert s['topics'][ODOM]['child_frame_ids'] == ['base_link']
    assert bh.rows_of(capsys, 'bag', converted['ros1']) == whole


def test_csv_numbers_are_rounded_then_written_as_the_shortest_text(capsys, converted):
    """--precision rounds each number, written as Python's repr of the rounded float."""
    def round_number(x, digits):  # correctly rounded by Python's formatting
        return float(f'{x:.{digits}g}') if abs(x) >= 1 else round(x, digits) + 0.0

    full = bh.rows_of(capsys, 'bag', converted['ros1'], '--topic', IMU, '--precision', '17')
    four = bh.rows_of(capsys, 'bag', converted['ros1'], '--topic', IMU, '--precision', '4')
    assert len(full) == len(four) == EXCERPT
    assert [r['stamp'] for r in full] == [r['stamp'] for r in four]  # stamps exactly
    names = [n for n in bag_output.csv_header(None) if n not in ('topic', 'stamp', 'frame_id')]
    for long, short in zip(full[1:], four[1:]):
        for name in names:
            assert short[name] == repr(float(short[name]))  # the shortest round-trip text
            assert float(short[name]) == round_number(float(long[name]), 4), name
    assert max(len(r['roll']) for r in full) > 12 >= max(len(r['roll']) for r in four)
    assert four[0]['x'] == '0.0' and four[0]['wx'] == ''  # no position; no previous row
