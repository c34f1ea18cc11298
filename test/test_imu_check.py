"""rot-tools imu-check in-process: faulty copies of the real recording, bad input."""

import json
import math
import re

import bag_helpers as bh
from conftest import run_cli
from doc_blocks import assert_doc_output, console_steps, doc_block, REPO
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
from rot_tools.cli import imu_check, imu_recording  # noqa: E402
from rot_tools.core.stamps import plain  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

IMU, ODOM = '/imu/data', '/jackal_velocity_controller/odom'

WINDOW = (0.0, 20.0)
"""The seconds of the real recording (from its first IMU stamp) written into the test bags."""

CHECKS = ('quaternion', 'stamps', 'accel_units', 'orientation_vs_accel', 'gyro_units', 'gyro_axes',
          'gyro_bias', 'time_offset', 'accel_sign', 'world_up', 'mounting')

G = 9.80665


class Recording:
    """The real recording's window, decoded by rosbags: record times (ns), stamps (s), fields."""

    def __init__(self):
        real = bh.decode()
        imu, odom = real[IMU], real[ODOM]
        t0 = imu['stamp'][0]
        keep = (imu['stamp'] >= t0 + WINDOW[0]) & (imu['stamp'] < t0 + WINDOW[1])
        self.imu_record, self.imu_stamp = imu['record'][keep], imu['stamp'][keep]
        self.q, self.gyro, self.accel = imu['q'][keep], imu['gyro'][keep], imu['accel'][keep]
        keep = (odom['stamp'] >= t0 + WINDOW[0]) & (odom['stamp'] < t0 + WINDOW[1])
        self.odom_record, self.odom_stamp, self.odom_q = (
            odom['record'][keep], odom['stamp'][keep], odom['q'][keep])


@pytest.fixture(scope='module')
def real():
    return Recording()


@pytest.fixture(scope='module')
def clean(real, tmp_path_factory):
    """Write the window as recorded as rosbag2 bags: 'imu' alone, 'odom' alone, 'both'."""
    folder = tmp_path_factory.mktemp('clean')
    return {'imu': write(folder / 'imu', real), 'odom': odometry_bag(folder / 'odom', real),
            'both': write(folder / 'both', real, odom=True)}


def imu_message(b, stamp, q, gyro, accel, cov0=0.0, frame='base_link'):
    covariance = np.zeros(9)
    covariance[0] = cov0
    return b.make(bh.IMU_TYPE, header=b.header(stamp, frame), orientation=b.quaternion(q),
                  orientation_covariance=covariance, angular_velocity=b.vector(gyro),
                  angular_velocity_covariance=np.zeros(9), linear_acceleration=b.vector(accel),
                  linear_acceleration_covariance=np.zeros(9))


def write(path, rec, q=None, gyro=None, accel=None, cov0=0.0, odom=False, topic=IMU,
          more=(), storage='sqlite3', stamps=None):
    """Write the window as a rosbag2 bag, the IMU's fields replaced by those given."""
    b = bh.Builder()
    stamps = rec.imu_stamp if stamps is None else stamps
    q = rec.q if q is None else q
    gyro = rec.gyro if gyro is None else gyro
    accel = rec.accel if accel is None else accel
    messages = [(topic, bh.IMU_TYPE, int(t), imu_message(b, s, q[k], gyro[k], accel[k], cov0))
                for k, (t, s) in enumerate(zip(rec.imu_record, stamps))]
    if odom:
        messages += [(ODOM, bh.ODOM_TYPE, int(t), b.odometry(s, (0, 0, 0), rec.odom_q[k]))
                     for k, (t, s) in enumerate(zip(rec.odom_record, rec.odom_stamp))]
    messages += list(more)
    messages.sort(key=lambda m: m[2])
    return bh.write_bag(path, messages, storage)


def run_json(capsys, *argv):
    status, out, err = run_cli(capsys, *argv, '--json')
    assert err == ''
    return status, json.loads(out)


def found(data):
    return {name for name, check in data['checks'].items() if check['status'] == 'fault'}


def table_faults(out):
    """Return the names of the table's rows at fault."""
    rows = [line.split() for line in out.splitlines()]
    return {row[0] for row in rows if row[:1] and row[0] in CHECKS and row[1] == 'fault'}


def one_error_line(status, out, err, *words):
    assert status == 2 and out == ''
    assert err.startswith('rot-tools: error: imu-check: ') and err.count('\n') == 1, err
    assert 'Traceback' not in err
    for word in words:
        assert word in err, err


# Faults put in


def test_accelerometer_in_g(real, tmp_path, capsys):
    accel = real.accel / G
    bag = write(tmp_path / 'g', real, accel=accel)
    status, data = run_json(capsys, 'imu-check', bag)
    assert status == 1 and found(data) == {'accel_units'} and data['faults'] == 1
    norm = np.linalg.norm(accel, axis=1)
    still = np.linalg.norm(real.gyro, axis=1) < 0.05  # the body turning slowly, from the gyro
    expected = G / np.median(norm[still])
    assert data['checks']['accel_units']['scale'] == pytest.approx(expected, rel=0.03)
    (fix,) = data['fix']
    assert fix.startswith('accel_units: linear_acceleration reads in g: multiply it by 9.80665')


def test_gyro_in_degrees(real, tmp_path, capsys):
    gyro = np.degrees(real.gyro)
    gyro[7] = np.nan  # a message left out, with a warning
    bag = write(tmp_path / 'deg', real, gyro=gyro)
    status, out, err = run_cli(capsys, 'imu-check', bag)
    assert status == 1
    assert err == (f'warning: {IMU}: 1 of {len(gyro)} messages left out: 1 with a NaN or Inf '
                   'in angular_velocity or linear_acceleration\n')
    assert table_faults(out) == {'gyro_units'}
    scale = float(re.search(r'gyro_units\s+fault\s+scale (\S+)', out).group(1))
    assert scale == pytest.approx(math.pi / 180, rel=0.03)
    assert '1 fault\n  gyro_units: angular_velocity reads in deg/s: multiply it by π/180 = ' \
        '0.0174533' in out


def recipe(line, fields):
    """Apply a fix's axis map ('x = -orientation.y, ...') to fields {name: (N,)}; return (N, k)."""
    columns = []
    for part in line.split(', '):
        sign, name = re.fullmatch(r'\w = ([+-]?)([\w.]+)', part).groups()
        columns.append(-fields[name] if sign == '-' else fields[name])
    return np.column_stack(columns)


def one_fault(out, name):
    """Return the table's text from its '1 fault' line on, after checking that only ``name`` is."""
    assert table_faults(out) == {name}
    return out[out.index('\n1 fault\n') + 1:]


def test_quaternion_written_w_first(real, tmp_path, capsys):
    """The fields x, y, z, w hold w, x, y, z: only the quaternion check is at fault."""
    written = real.q[:, [3, 0, 1, 2]]
    status, out, err = run_cli(capsys, 'imu-check', write(tmp_path / 'w_first', real, q=written))
    assert status == 1 and err == ''
    assert re.search(r'\nquaternion +fault +w-first ', out)
    shown = one_fault(out, 'quaternion')
    assert_doc_output('imu-fix-w-first', shown)
    assert 'In the driver fill orientation.x = q.x(), orientation.y = q.y(), orientation.z = ' \
        'q.z(), orientation.w = q.w()' in shown
    fields = {f'orientation.{a}': written[:, k] for k, a in enumerate('xyzw')}
    read = recipe(shown.split('reads right as ')[1].splitlines()[0], fields)
    assert np.array_equal(read, real.q)


def test_quaternion_inverted(real, tmp_path, capsys):
    """The conjugate, the world in the IMU frame: only the quaternion check is at fault."""
    written = Rotation.from_quat(real.q).inv().as_quat()
    status, out, err = run_cli(capsys, 'imu-check', write(tmp_path / 'inverted', real, q=written))
    assert status == 1 and err == ''
    assert re.search(r'\nquaternion +fault +inverted ', out)
    shown = one_fault(out, 'quaternion')
    assert_doc_output('imu-fix-inverted', shown)
    assert 'In the driver publish its conjugate' in shown
    fields = {f'orientation.{a}': written[:, k] for k, a in enumerate('xyzw')}
    read = Rotation.from_quat(recipe(shown.split('reads right as ')[1].splitlines()[0], fields))
    assert np.degrees((read.inv() * Rotation.from_quat(real.q)).magnitude()).max() < 1e-6


def test_gyro_axis_negated_is_a_mirror(real, tmp_path, capsys):
    """A left-handed gyro: the fix negates its y axis; no rotation is offered for it."""
    gyro = real.gyro * [1, -1, 1]
    bag = write(tmp_path / 'mirror', real, gyro=gyro, odom=True)
    status, out, err = run_cli(capsys, 'imu-check', bag, '--ref-topic', ODOM)
    assert status == 1 and err == ''
    assert re.search(r'\ngyro_axes +fault +x = \+x, y = -y, z = \+z, mirror, negate y ', out)
    shown = one_fault(out, 'gyro_axes')
    assert_doc_output('imu-fix-mirror', shown)
    fix = shown.splitlines()[1]
    assert fix.startswith("  gyro_axes: the gyro's axes are a mirror of the orientation's (a "
                          'left-handed frame: no turn of the IMU gives it): negate the '
                          "gyro's y axis; in all, publish ")
    applied = recipe(fix.split('publish ')[1][:-len(' of what it reads now')],
                     dict(zip('xyz', gyro.T)))
    assert np.array_equal(applied, real.gyro)
    assert 'static_transform_publisher' not in out


def test_ned_device_with_the_odometry(real, tmp_path, capsys):
    """The whole IMU in NED: world north-east-down, the sensor forward-right-down."""
    ned_enu = Rotation.from_matrix([[0, 1, 0], [1, 0, 0], [0, 0, -1]])  # ENU coordinates → NED
    flu_frd = Rotation.from_euler('x', math.pi)  # the FRD sensor frame in the FLU one
    q = (ned_enu * Rotation.from_quat(real.q) * flu_frd).as_quat()
    frd = flu_frd.inv()
    bag = write(tmp_path / 'ned', real, q=q, gyro=frd.apply(real.gyro),
                accel=frd.apply(real.accel), odom=True)
    status, out, err = run_cli(capsys, 'imu-check', bag, '--ref-topic', ODOM)
    assert status == 1 and err == ''
    assert table_faults(out) == {'orientation_vs_accel', 'world_up'}
    lines = [line for line in out.splitlines() if 'static_transform_publisher' in line]
    assert lines[0].startswith("  world_up: the orientation's world is NED (z down)")
    assert lines[0].endswith(' --qx 1 --qy 0 --qz 0 --qw 0 --frame-id base_link '
                             "--child-frame-id imu_link_ned (and set the IMU's frame_id to "
                             "imu_link_ned: its messages are stamped base_link, the body's "
                             'frame)')
    for line in lines:  # FRD, and the measured mounting where the motion leaves it apart
        command = line[line.index('ros2 run'):].split(' (')[0].split()
        assert command[:4] == ['ros2', 'run', 'tf2_ros', 'static_transform_publisher']
        options = dict(zip(command[4::2], command[5::2]))
        assert options['--frame-id'] == 'base_link'
        assert options['--child-frame-id'] == 'imu_link_ned'
        assert [options[k] for k in ('--x', '--y', '--z')] == ['0', '0', '0']
        q = [float(options[k]) for k in ('--qx', '--qy', '--qz', '--qw')]
        up = Rotation.from_quat(q).apply([0, 0, 1])  # the sensor's z in the body frame: down
        assert math.degrees(math.acos(np.clip(-up[2], -1, 1))) < 3


def test_imu_without_orientation(real, tmp_path, capsys):
    bag = write(tmp_path / 'no_q', real, q=np.zeros((len(real.q), 4)), cov0=-1.0)
    status, data = run_json(capsys, 'imu-check', bag)
    checks = data['checks']
    for name in ('orientation_vs_accel', 'gyro_units', 'gyro_axes', 'time_offset',
                 'accel_sign', 'world_up', 'mounting'):
        assert checks[name]['status'] == 'unknown', name
    assert checks['accel_units']['status'] == 'ok'
    assert status == 0 and data['faults'] == 0 and data['fix'] == []


def test_clean_window_with_the_odometry_json(real, clean, capsys):
    status, data = run_json(capsys, 'imu-check', clean['both'], '--ref-topic', ODOM, '--start', 5,
                            '--end', 15)
    assert status == 0 and data['faults'] == 0 and data['fix'] == []
    start = min(real.imu_record[0], real.odom_record[0])
    inside = (real.imu_record >= start + 5e9) & (real.imu_record <= start + 15e9)
    assert list(data) == ['imu', 'checks', 'faults', 'fix']
    assert data['imu'] == {'topic': IMU, 'frame': 'base_link', 'messages': int(inside.sum()),
                           'rate': pytest.approx(50, rel=1e-3)}
    assert list(data['checks']) == list(CHECKS)
    named = {'quaternion': ['reading'],
             'stamps': ['period', 'gap', 'backwards', 'spread', 'rate', 'arrival_time'],
             'accel_units': ['scale'], 'orientation_vs_accel': ['angle'],
             'gyro_units': ['scale'], 'gyro_axes': ['matrix', 'mirror', 'negate'],
             'gyro_bias': ['bias'], 'time_offset': ['seconds'],
             'accel_sign': ['angle'], 'world_up': ['angle'],
             'mounting': ['quaternion', 'warning']}
    for name, check in data['checks'].items():
        assert list(check) == ['status', 'message'] + named[name], name
        assert check['status'] == 'ok', (name, check)
    assert data['checks']['quaternion']['reading'] == 'as recorded'
    assert data['checks']['stamps']['rate'] == data['imu']['rate']
    assert data['checks']['gyro_axes']['matrix'] == [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    assert data['checks']['gyro_axes']['mirror'] is False
    assert len(data['checks']['gyro_bias']['bias']) == 3
    assert len(data['checks']['mounting']['quaternion']) == 4


# Every window of the clean recording


def window(recording, start, end):
    """Return the Recording's samples stamped from ``start`` to ``end`` s of the IMU's first."""
    imu, ref = recording.imu, recording.reference
    k = (imu.stamps >= start) & (imu.stamps <= end)
    j = (ref.stamps >= start) & (ref.stamps <= end)
    return recording._replace(
        imu=imu._replace(messages=int(k.sum()), stamps=imu.stamps[k],
                         quaternions=imu.quaternions[k],
                         angular_velocity=imu.angular_velocity[k],
                         linear_acceleration=imu.linear_acceleration[k]),
        reference=ref._replace(stamps=ref.stamps[j], quaternions=ref.quaternions[j]))


def test_no_fault_in_any_window_of_the_clean_recording(capsys, monkeypatch):
    """Windows of 2, 5 and 10 s over the whole clean recording: no fault."""
    whole = imu_recording.read(bh.REAL, ref_topic=ODOM)
    monkeypatch.setattr(imu_recording, 'read',
                        lambda *args, **_: window(whole, args[4], args[5]))
    span = whole.imu.stamps[-1]
    windows = [(start, start + length) for length in (2, 5, 10)
               for start in np.arange(0.0, span - length, 1.5)]
    assert len(windows) >= 100
    found_faults = {}
    for start, end in windows:
        status, data = run_json(capsys, 'imu-check', bh.REAL, '--ref-topic', ODOM,
                                '--start', start, '--end', end)
        if status != 0:
            found_faults[f'{start:g}-{end:g} s'] = sorted(found(data))
    assert found_faults == {}


# The reference from another recording of the run (--ref-bag)


DAY = 27 * 3600
"""Two recordings of other runs, apart by this many seconds (as two bags merged by hand)."""


def odometry_bag(path, rec, shift=0.0):
    """Write the window's odometry alone as a rosbag2 bag, stamps and record times shifted."""
    b = bh.Builder()
    return bh.write_bag(path, [
        (ODOM, bh.ODOM_TYPE, int(t + shift * 1e9), b.odometry(s + shift, (0, 0, 0), rec.odom_q[k]))
        for k, (t, s) in enumerate(zip(rec.odom_record, rec.odom_stamp))])


def span(ns):
    """Write a span of times (ns) as imu-check names it."""
    return f'{plain(int(ns.min()) / 1e9)}–{plain(int(ns.max()) / 1e9)} s'


def test_the_reference_from_another_recording(clean, capsys):
    both, imu, odom = clean['both'], clean['imu'], clean['odom']
    argv = ('--ref-topic', ODOM, '--start', 2, '--end', 18)
    status, data = run_json(capsys, 'imu-check', imu, '--ref-bag', odom, *argv)
    assert (status, data) == run_json(capsys, 'imu-check', both, *argv)
    assert status == 0 and data['checks']['mounting']['status'] == 'ok'


def test_the_tf_reference_from_another_recording(real, clean, tmp_path, capsys):
    """The odometry's orientations as TF (odom → base_link) in the other bag."""
    b = bh.Builder()
    tf = bh.write_bag(tmp_path / 'tf', [
        ('/tf', 'tf2_msgs/msg/TFMessage', int(t), b.tf_message([b.transform_stamped(
            s, (0, 0, 0), q, 'odom', 'base_link')]))
        for t, s, q in zip(real.odom_record, real.odom_stamp, real.odom_q)])
    status, by_tf = run_json(capsys, 'imu-check', clean['imu'], '--ref-bag', tf, '--ref-tf',
                             'odom', 'base_link')
    by_topic = run_json(capsys, 'imu-check', clean['both'], '--ref-topic', ODOM)[1]
    assert status == 0
    for name in ('accel_sign', 'world_up', 'mounting'):
        assert by_tf['checks'][name]['status'] == by_topic['checks'][name]['status'] == 'ok'
    assert by_tf['checks']['mounting']['quaternion'] == pytest.approx(
        by_topic['checks']['mounting']['quaternion'], abs=1e-6)


def test_a_ref_bag_without_what_was_asked_is_named(clean, capsys):
    imu, odom = clean['imu'], clean['odom']
    one_error_line(*run_cli(capsys, 'imu-check', imu, '--ref-bag', odom, '--ref-tf', 'odom',
                            'base_link'),
                   f'imu-check: --ref-bag {odom}: --ref-tf: the bag has no '
                   'tf2_msgs/msg/TFMessage topic\n')
    one_error_line(*run_cli(capsys, 'imu-check', imu, '--ref-bag', odom, '--ref-topic', '/odom'),
                   f'imu-check: --ref-bag {odom}: --ref-topic: no topic /odom in the bag')


def test_recordings_that_do_not_overlap_are_refused(real, clean, tmp_path, capsys):
    imu = clean['imu']
    odom = odometry_bag(tmp_path / 'odom', real, DAY)
    one_error_line(*run_cli(capsys, 'imu-check', imu, '--ref-bag', odom, '--ref-topic', ODOM),
                   f'imu-check: {imu} (recorded {span(real.imu_record)}) and --ref-bag {odom} '
                   f'(recorded {span(real.odom_record + DAY * 10 ** 9)}) do not overlap in '
                   'time: 27.0 h apart\n')


def test_topics_stamped_a_day_apart_are_refused(real, tmp_path, capsys):
    """Two bags merged by hand: each topic's stamps are of its own run."""
    b = bh.Builder()
    later = [(ODOM, bh.ODOM_TYPE, int(t), b.odometry(s + DAY, (0, 0, 0), q))
             for t, s, q in zip(real.odom_record, real.odom_stamp, real.odom_q)]
    bag = write(tmp_path / 'merged', real, more=later)
    imu_ns = np.round(real.imu_stamp * 1e9).astype(np.int64)
    odom_ns = np.round((real.odom_stamp + DAY) * 1e9).astype(np.int64)
    one_error_line(*run_cli(capsys, 'imu-check', bag, '--ref-topic', ODOM),
                   f'imu-check: {IMU} (stamped {span(imu_ns)}) and {ODOM} (stamped '
                   f'{span(odom_ns)}) do not overlap in time: 27.0 h apart\n')


# doc/imu.md's example: the whole real recording, without and with the odometry


def test_doc_example_is_real_output(capsys, monkeypatch):
    """doc/imu.md's example: its commands run here, in-process, from the repository root."""
    monkeypatch.chdir(REPO)
    shown = ''
    for command, _ in console_steps(doc_block('imu-check-jackal')):
        argv = command.split()
        assert argv[0] == 'rot-tools'
        status, out, err = run_cli(capsys, *argv[1:])
        assert status == 0 and err == ''
        shown += f'$ {command}\n{out}'
    assert_doc_output('imu-check-jackal', shown)  # ROT_TOOLS_UPDATE_DOCS=1 rewrites it


# Bad input: one line, exit status 2


def test_missing_path_and_files_that_are_not_bags(tmp_path, capsys):
    one_error_line(*run_cli(capsys, 'imu-check', tmp_path / 'none.bag'), 'no such file')
    text = tmp_path / 'notes.txt'
    text.write_text('not a bag\n')
    one_error_line(*run_cli(capsys, 'imu-check', text), 'not a bag')
    fake = tmp_path / 'fake.bag'
    fake.write_bytes(b'#ROSBAG V2.0\n' + bytes(range(256)) * 4)
    one_error_line(*run_cli(capsys, 'imu-check', fake), 'cannot read the bag')


def test_bag_without_an_imu_and_with_two(real, tmp_path, capsys):
    b = bh.Builder()
    odometry = [(ODOM, bh.ODOM_TYPE, int(t), b.odometry(s, (0, 0, 0), real.odom_q[k]))
                for k, (t, s) in enumerate(zip(real.odom_record[:20], real.odom_stamp[:20]))]
    bag = bh.write_bag(tmp_path / 'odom_only', odometry)
    one_error_line(*run_cli(capsys, 'imu-check', bag),
                   'no sensor_msgs/msg/Imu topic in the bag', ODOM)
    imu = [(topic, bh.IMU_TYPE, int(t), imu_message(b, s, real.q[k], real.gyro[k], real.accel[k]))
           for topic in ('/imu/a', '/imu/b')
           for k, (t, s) in enumerate(zip(real.imu_record[:20], real.imu_stamp[:20]))]
    bag = bh.write_bag(tmp_path / 'two', imu + odometry)
    one_error_line(*run_cli(capsys, 'imu-check', bag), '/imu/a, /imu/b', '--imu-topic')
    one_error_line(*run_cli(capsys, 'imu-check', bag, '--imu-topic', ODOM), 'not a sensor_msgs')
    one_error_line(*run_cli(capsys, 'imu-check', bag, '--imu-topic', '/imu/c'), 'no topic /imu/c')
    one_error_line(*run_cli(capsys, 'imu-check', bag, '--imu-topic', '/imu/a', '--ref-topic',
                            '/imu/b'), 'not a reference orientation')
    status, out, err = run_cli(capsys, 'imu-check', bag, '--imu-topic', '/imu/a', '--ref-tf',
                               'odom', 'base_link')
    one_error_line(status, out, err, '--ref-tf: the bag has no tf2_msgs/msg/TFMessage topic')
    assert '--tf:' not in err
    one_error_line(*run_cli(capsys, 'imu-check', bag, '--imu-topic', '/imu/a', '--start', 100),
                   'no message between --start and --end')
    one_error_line(*run_cli(capsys, 'imu-check', bag, '--imu-topic', '/imu/a', '--end', 0.1),
                   '/imu/a: stamps has 6 sample(s): at least 10 needed')


def test_every_message_left_out_says_why(real, tmp_path, capsys):
    q = real.q * 2  # not unit quaternions: the boundary refuses them
    q[:5] = np.nan
    bag = write(tmp_path / 'refused', real, q=q)
    one_error_line(*run_cli(capsys, 'imu-check', bag),
                   f'imu-check: {IMU}: all {len(q)} messages left out: 5 with a NaN or Inf in '
                   f'the orientation, {len(q) - 5} with a quaternion whose norm is off 1 by '
                   'more than 0.001: nothing to check\n')


def test_messages_left_out_are_told_before_an_error(real, tmp_path, capsys):
    accel = real.accel.copy()
    accel[4:] = np.inf  # 4 messages left: too few for the checks
    bag = write(tmp_path / 'few', real, accel=accel)
    status, out, err = run_cli(capsys, 'imu-check', bag)
    warning, line = err.splitlines()
    assert status == 2 and out == ''
    assert warning == (f'warning: {IMU}: {len(accel) - 4} of {len(accel)} messages left out: '
                       f'{len(accel) - 4} with a NaN or Inf in angular_velocity or '
                       'linear_acceleration')
    assert line == (f'rot-tools: error: imu-check: {IMU}: stamps has 4 sample(s): at least 10 '
                    'needed')


def test_messages_left_out_are_told_before_an_error_of_the_reference(real, tmp_path, capsys):
    gyro = real.gyro.copy()
    gyro[3] = np.nan
    b = bh.Builder()
    frozen = [(ODOM, bh.ODOM_TYPE, int(t), b.odometry(real.odom_stamp[0], (0, 0, 0), q))
              for t, q in zip(real.odom_record, real.odom_q)]
    bag = write(tmp_path / 'frozen', real, gyro=gyro, more=frozen)
    status, out, err = run_cli(capsys, 'imu-check', bag, '--ref-topic', ODOM)
    warning, line = err.splitlines()
    assert status == 2 and out == ''
    assert warning.startswith(f'warning: {IMU}: 1 of {len(gyro)} messages left out: ')
    assert line.startswith(f'rot-tools: error: imu-check: {ODOM}: the reference has 1 distinct')


def test_a_finite_spike_is_left_out_as_a_nan_is(real, tmp_path, capsys):
    gyro = real.gyro.copy()
    gyro[5, 0] = 1.5e298
    bag = write(tmp_path / 'spike', real, gyro=gyro)
    status, out, err = run_cli(capsys, 'imu-check', bag)
    assert status == 0 and out.endswith('\nno fault\n')
    assert err == (f'warning: {IMU}: 1 of {len(gyro)} messages left out: 1 with a reading '
                   'beyond 1e+09 in angular_velocity or linear_acceleration (no sensor reads '
                   'that)\n')


def test_a_reference_with_one_stamp_is_named(real, tmp_path, capsys):
    b = bh.Builder()
    frozen = [(ODOM, bh.ODOM_TYPE, int(t), b.odometry(real.odom_stamp[0], (0, 0, 0), q))
              for t, q in zip(real.odom_record, real.odom_q)]
    bag = write(tmp_path / 'frozen', real, more=frozen)
    one_error_line(*run_cli(capsys, 'imu-check', bag, '--ref-topic', ODOM),
                   f'imu-check: {ODOM}: the reference has 1 distinct stamp(s) among its '
                   f'{len(frozen)} usable orientations: at least 10 needed\n')


def test_the_rate_is_the_stamps_rate(real, tmp_path, capsys):
    stamp = real.imu_stamp.copy()
    stamp[500:] += 100.0  # a gap of 100 s: over the whole span, 8 messages a second
    bag = write(tmp_path / 'gap', real, stamps=stamp)
    status, out, err = run_cli(capsys, 'imu-check', bag)
    assert status == 1 and err == ''
    assert out.startswith(f'imu: {IMU} (frame base_link), {len(stamp)} messages, 50 Hz\n')
    assert re.search(r'\nstamps +fault +period 0.02 s, ', out)
    assert json.loads(run_cli(capsys, 'imu-check', bag, '--json')[1])['imu']['rate'] == \
        pytest.approx(50, rel=1e-3)


def test_stamps_taken_on_arrival_are_shown(real, tmp_path, capsys):
    """Steps of 18 and 22 ms at random, as a driver stamping messages read in bursts."""
    steps = np.where(np.random.default_rng(5).random(len(real.imu_stamp) - 1) < 0.5,
                     0.018, 0.022)
    stamp = real.imu_stamp[0] + np.concatenate([[0.0], np.cumsum(steps)])
    status, out, err = run_cli(capsys, 'imu-check', write(tmp_path / 'bursts', real, stamps=stamp))
    rate = f'{1 / np.median(steps):.4g} Hz'
    assert out.startswith(f'imu: {IMU} (frame base_link), {len(stamp)} messages, {rate}\n')
    row = re.search(r'\nstamps +ok +(.*)', out).group(1)
    assert row.startswith(f'period {np.median(steps):g} s, gap 0.022 s, backwards 0, spread ')
    assert f', rate {rate}, arrival-time stamping suspected ' in row
    assert 'the steps fall into two groups, 18 ms and 22 ms' in row


def damage(path, at=0.5, size=2000):
    """Overwrite ``size`` bytes of a file from ``at`` of its length with junk."""
    data = bytearray(path.read_bytes())
    k = int(len(data) * at)
    data[k:k + size] = (bytes(range(256)) * (size // 256 + 1))[:size]
    path.write_bytes(bytes(data))


def test_damaged_bags_are_named(real, tmp_path, capsys):
    """The damage is met while the messages are read, after the bag opened."""
    ros1 = bh.real_excerpt(tmp_path / 'excerpt.bag', 600)
    damage(ros1)
    one_error_line(*run_cli(capsys, 'imu-check', ros1), f'{ros1}: cannot read the bag: ')
    mcap = write(tmp_path / 'mcap', real, storage='mcap')
    damage(next(mcap.glob('*.mcap')), at=0.1)
    one_error_line(*run_cli(capsys, 'imu-check', mcap), f'{mcap}: cannot read the bag: ')


def test_options_that_do_not_fit(capsys):
    for argv, words in (
            (['--ref-topic', ODOM, '--ref-tf', 'odom', 'base_link'], ['one reference']),
            (['--ref-bag', bh.REAL], ['--ref-bag: say which reference to take from it']),
            (['--start', 10, '--end', 5], ['--end 5 is before --start 10']),
            (['--start', -1], ['>= 0 seconds'])):
        status, out, err = run_cli(capsys, 'imu-check', bh.REAL, *argv)
        assert status == 2 and out == '' and err.count('\n') == 1, err
        assert err.startswith('rot-tools: error: ')
        for word in words:
            assert word in err, err
    status, out, err = run_cli(capsys, '--plot', 'x.png', 'imu-check', bh.REAL)
    assert (status, out, err) == (2, '', 'rot-tools: error: --plot does not apply to '
                                  'imu-check\n')


# The pieces


def test_axis_map_and_static_transform_line():
    assert imu_check.axis_map([[0, 1, 0], [1, 0, 0], [0, 0, -1]]) == 'x = +y, y = +x, z = -z'
    line = imu_check.static_transform([-1, 0, 0, 0], 'base_link', 'imu_link')
    assert line == ('ros2 run tf2_ros static_transform_publisher --x 0 --y 0 --z 0 --qx 1 '
                    '--qy 0 --qz 0 --qw 0 --frame-id base_link --child-frame-id imu_link')
    side = Rotation.from_euler('y', 90, degrees=True).as_quat()
    line = imu_check.static_transform(side, 'base_link', 'imu_link')
    assert f'\n{line}\n' in (REPO / 'doc' / 'imu.md').read_text()  # the doc's example


def test_deg_converts_angles_and_rates_only():
    from rot_tools.core import imu
    bias = imu.GyroBiasCheck('fault', 'm', [0.02, -0.01, 0.0])
    angle = imu.AngleCheck('ok', 'm', math.pi / 2)
    offset = imu.TimeOffsetCheck('ok', 'm', 0.1)
    assert imu_check.numbers(bias, True) == {'bias': pytest.approx([1.1459156, -0.5729578, 0])}
    assert imu_check.numbers(angle, True) == {'angle': pytest.approx(90)}
    assert imu_check.numbers(angle, False) == {'angle': pytest.approx(math.pi / 2)}
    assert imu_check.numbers(offset, True) == {'seconds': 0.1}
