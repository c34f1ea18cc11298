"""rot-tools bag's checks of an Imu's orientation against its gyro, and of positions."""

import json
import math

import bag_helpers as bh
from conftest import run_cli
import numpy as np
import pytest

rosbags = pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
from rot_tools.cli.bag_analysis import GYRO_NOISE  # noqa: E402
from rot_tools.core.imu import GYRO_TOL  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

IMU, ODOM = '/imu/data', '/jackal_velocity_controller/odom'


@pytest.fixture(scope='module')
def real():
    """{topic: {'stamp', 'q', 'p', 'gyro', ...}} of the real recording, decoded by rosbags."""
    return bh.decode()


@pytest.fixture(scope='module')
def w_first(tmp_path_factory):
    """Return a copy of the real IMU whose quaternion fields x, y, z, w hold w, x, y, z."""
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag1 import Writer
    path = tmp_path_factory.mktemp('w_first') / 'imu_w_first.bag'
    with AnyReader([bh.REAL]) as reader, Writer(path) as writer:
        (conn,) = [c for c in reader.connections if c.topic == IMU]
        out = writer.add_connection(IMU, conn.msgtype, msgdef=conn.msgdef.data,
                                    md5sum=conn.digest)
        for _, t, raw in reader.messages(connections=[conn]):
            msg = reader.deserialize(raw, conn.msgtype)
            q = msg.orientation
            q.x, q.y, q.z, q.w = q.w, q.x, q.y, q.z
            writer.write(out, t, reader.typestore.serialize_ros1(msg, conn.msgtype))
    return path


# ---- the orientation against the gyro ------------------------------------------------------


def test_the_threshold_is_the_noise_and_imu_check_s_gyro_scale_tolerance(capsys, real):
    """Check the threshold: GYRO_NOISE + GYRO_TOL × the gyro's RMS rate over the steps."""
    status, out, err = run_cli(capsys, 'bag', bh.REAL, '--topic', IMU, '--json')
    imu = json.loads(out)['topics'][IMU]
    gyro = real[IMU]['gyro']
    at_step = 0.5 * (gyro[:-1] + gyro[1:])
    rate = math.sqrt(np.mean(np.sum(at_step ** 2, axis=1)))
    assert imu['gyro_rms_threshold'] == pytest.approx(GYRO_NOISE + GYRO_TOL * rate, rel=1e-12)


def test_the_real_imu_agrees_with_its_gyro(capsys):
    status, out, err = run_cli(capsys, 'bag', bh.REAL, '--json')
    imu = json.loads(out)['topics'][IMU]
    assert (status, err) == (0, '')
    assert imu['gyro_rms_difference'] < imu['gyro_rms_threshold']
    assert 'gyro_warning' not in imu


def test_a_quaternion_written_w_first_is_flagged(capsys, w_first, real):
    status, out, err = run_cli(capsys, 'bag', w_first, '--json', '--deg')
    imu = json.loads(out)['topics'][IMU]
    # ω from the orientations as written, against the gyro (scipy, independent of rot_tools)
    q, t, gyro = real[IMU]['q'], real[IMU]['stamp'], real[IMU]['gyro']
    written = Rotation.from_quat(q[:, [3, 0, 1, 2]])
    omega = (written[:-1].inv() * written[1:]).as_rotvec() / np.diff(t)[:, None]
    diff = omega - 0.5 * (gyro[:-1] + gyro[1:])
    rms = math.degrees(math.sqrt(np.mean(np.sum(diff ** 2, axis=1))))
    assert imu['gyro_rms_difference'] == pytest.approx(rms, rel=1e-7)
    assert imu['gyro_rms_difference'] > imu['gyro_rms_threshold']
    said = (f'the RMS difference of their rates, {rms:.4g} deg/s, exceeds '
            f"{imu['gyro_rms_threshold']:.4g} deg/s")
    assert said in imu['gyro_warning']
    assert status == 0
    assert err == f"warning: {IMU}: {imu['gyro_warning']}\n"


def test_the_warning_goes_to_stderr_with_the_csv_on_stdout(capsys, w_first):
    status, out, err = run_cli(capsys, 'bag', w_first, '--csv', '-')
    assert status == 0 and out.startswith('topic,stamp,')
    assert len(err.splitlines()) == 1
    assert err.startswith(f'warning: {IMU}: the orientation disagrees with the gyro: ')
    assert 'rad/s' in err


# ---- positions ---------------------------------------------------------------------------


def test_the_odometry_s_position_ranges_and_largest_speed(capsys, real):
    status, out, err = run_cli(capsys, 'bag', bh.REAL, '--json')
    odom = json.loads(out)['topics'][ODOM]
    p, t = real[ODOM]['p'], real[ODOM]['stamp']
    for k, name in enumerate('xyz'):
        np.testing.assert_allclose(odom['position_range'][name], [p[:, k].min(), p[:, k].max()],
                                   rtol=1e-11, atol=1e-11)
    speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(t)
    assert odom['max_speed'] == pytest.approx(speed.max(), rel=1e-6)
    assert odom['max_speed_stamp'] == pytest.approx(t[np.argmax(speed) + 1], abs=1e-9)


def test_an_imu_has_no_positions(capsys):
    status, out, err = run_cli(capsys, 'bag', bh.REAL, '--json')
    imu = json.loads(out)['topics'][IMU]
    assert not {'position_range', 'max_speed'} & set(imu)


def falling_odometry(path):
    """Return a bag of an odometry still for 1 s, then falling at 80 m/s to z = −3,754 m."""
    b = bh.Builder()
    messages = []
    for k in range(500):
        stamp = 100.0 + 0.1 * k
        z = -min(max(0.0, 8.0 * (k - 10)), 3754.0)
        messages.append(('/odom', 'nav_msgs/msg/Odometry', int(stamp * 1e9),
                         b.odometry(stamp, (1.0, 2.0, z), (0, 0, 0, 1.0))))
    return bh.write_bag(path, messages)


def test_an_odometry_falling_at_80_m_s_is_seen(capsys, tmp_path):
    status, out, err = run_cli(capsys, 'bag', falling_odometry(tmp_path / 'fall'), '--json')
    odom = json.loads(out)['topics']['/odom']
    assert odom['position_range'] == {'x': [1.0, 1.0], 'y': [2.0, 2.0], 'z': [-3754.0, 0.0]}
    assert odom['max_speed'] == pytest.approx(80.0, rel=1e-9)
    assert odom['max_speed_stamp'] == pytest.approx(101.1, abs=1e-9)
