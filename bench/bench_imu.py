"""
``rot-tools imu-check BAG`` against ``rot-tools bag BAG`` on an hour of 400 Hz IMU.

The bag is written here (rosbags' rosbag2 writer, MCAP or sqlite3): the IMU of the real
recording (../shared/data/jackal_imu_odometry.bag, /imu/data, 50 Hz) resampled to 400 Hz
(scipy's Slerp for the orientation, linear for the gyro and the accelerometer), then repeated
with shifted stamps until it lasts --minutes (60: 1,440,000 messages). Every other copy runs
backwards in time (the samples in reverse order, the gyro negated), so the orientation goes on
without a jump from one copy to the next and the whole hour is a consistent IMU. (The
recording's orientation is stamped 10 ms early against its gyro, half a period at 50 Hz; a
backward copy has it 10 ms late, so over many copies the two average out. imu-check's table of
the bag is printed first.)

Each side runs in a process of its own that has imported its libraries already, and only its
job is timed (rot_tools.cli.main.main with the command line, its standard output discarded):

- ``rot-tools imu-check BAG``: reads the Imu topic (stamps, orientation, gyro,
  accelerometer) and runs every check;
- ``rot-tools bag BAG``: reads the same topic and prints its summary.

The repetitions are interleaved (the order rotating from one to the next) and each side's
median is taken. Goal: imu-check ≤ 2 × bag. Each process's peak RSS is printed beside its
time. Nothing is asserted.

    .venv/bin/python bench/bench_imu.py [--minutes 60] [--repeat 3] [--storage mcap]
                                        [--keep DIR] [--json FILE]
"""

import argparse
from pathlib import Path
import shutil
import subprocess
import sys
import tempfile

import benchlib
import numpy as np

REPO = Path(__file__).resolve().parents[1]
REAL = REPO.parent / 'shared' / 'data' / 'jackal_imu_odometry.bag'
GOAL = 2.0
RATE = 400
TOPIC, IMU_TYPE = '/imu/data', 'sensor_msgs/msg/Imu'

TIMED = r"""
import contextlib, os, resource, sys, time
from rot_tools.cli import bag, bag_analysis, imu_check, main  # noqa: F401 (before the clock)
from rot_tools.core import imu  # noqa: F401
from rosbags.highlevel import AnyReader  # noqa: F401

with open(os.devnull, 'w') as devnull, contextlib.redirect_stdout(devnull):
    start = time.perf_counter()
    status = main.main(sys.argv[1:])
    seconds = time.perf_counter() - start
print(status, seconds, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


def real_imu():
    """Return the real recording's IMU: stamps (s), quaternions, gyro, accelerometer."""
    from rosbags.highlevel import AnyReader
    rows = []
    with AnyReader([REAL]) as reader:
        connections = [c for c in reader.connections if c.topic == TOPIC]
        for conn, _, raw in reader.messages(connections=connections):
            m = reader.deserialize(raw, conn.msgtype)
            o, w, a = m.orientation, m.angular_velocity, m.linear_acceleration
            rows.append((m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec,
                         o.x, o.y, o.z, o.w, w.x, w.y, w.z, a.x, a.y, a.z))
    rows = np.array(rows)
    return rows[:, 0] - rows[0, 0], rows[:, 1:5], rows[:, 5:8], rows[:, 8:11]


def resampled(t, q, gyro, accel):
    """Return the samples at RATE Hz over the recording: (quaternions, gyro, accelerometer)."""
    from scipy.spatial.transform import Rotation, Slerp
    at = np.arange(int(t[-1] * RATE) + 1) / RATE
    q400 = Slerp(t, Rotation.from_quat(q))(at).as_quat()
    linear = [np.column_stack([np.interp(at, t, x[:, k]) for k in range(3)])
              for x in (gyro, accel)]
    return q400, linear[0], linear[1]


def hour(n, count):
    """
    Yield (k, sample index, gyro sign) of ``count`` messages over n samples: forward, back.

    A backward copy starts at the sample after the one the forward copy ended on (and so on),
    so that no orientation repeats at two stamps in a row.
    """
    forward = np.arange(n)
    backward = forward[::-1][1:]
    k, direction = 0, 1
    order = forward
    while k < count:
        for index in order:
            if k == count:
                return
            yield k, int(index), direction
            k += 1
        direction = -direction
        order = backward if direction < 0 else forward[1:]


def write_bag(path, minutes, storage):
    """Write ``minutes`` of 400 Hz IMU at ``path``; return the number of messages."""
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores
    store = get_typestore(Stores.ROS2_JAZZY)
    types = store.types
    Time, Header = types['builtin_interfaces/msg/Time'], types['std_msgs/msg/Header']
    Vector3, Quaternion = types['geometry_msgs/msg/Vector3'], types['geometry_msgs/msg/Quaternion']
    q, gyro, accel = resampled(*real_imu())
    covariance = np.zeros(9)
    covariance[[0, 4, 8]] = 2.5e-5

    def vector(v):
        return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))

    # one message object per sample and direction, only its header changed per message
    messages = {}
    for direction in (1, -1):
        for i in range(len(q)):
            messages[i, direction] = types[IMU_TYPE](
                header=None, orientation=Quaternion(x=float(q[i, 0]), y=float(q[i, 1]),
                                                    z=float(q[i, 2]), w=float(q[i, 3])),
                orientation_covariance=covariance, angular_velocity=vector(direction * gyro[i]),
                angular_velocity_covariance=covariance, linear_acceleration=vector(accel[i]),
                linear_acceleration_covariance=covariance)
    count = int(minutes * 60 * RATE)
    start = 1_700_000_000 * 10**9
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    with Writer(path, version=8, storage_plugin=plugin) as writer:
        conn = writer.add_connection(TOPIC, IMU_TYPE, typestore=store)
        for k, index, direction in hour(len(q), count):
            ns = start + k * 10**9 // RATE
            message = messages[index, direction]
            message.header = Header(stamp=Time(sec=ns // 10**9, nanosec=ns % 10**9),
                                    frame_id='base_link')
            writer.write(conn, ns, store.serialize_cdr(message, IMU_TYPE))
    return count


def timed(argv):
    """Run rot-tools ``argv`` in a process of its own; return (status, seconds, peak RSS MB)."""
    done = subprocess.run([sys.executable, '-c', TIMED, *map(str, argv)],
                          capture_output=True, text=True, cwd=REPO)
    if done.returncode != 0:
        raise SystemExit(f'{" ".join(map(str, argv))} failed:\n{done.stderr}')
    status, seconds, rss = done.stdout.split()
    return int(status), float(seconds), int(rss) / 1024


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--minutes', type=float, default=60,
                        help='length of the bag written (default 60: 1,440,000 messages)')
    parser.add_argument('--repeat', type=int, default=3, help='runs of each side (default 3)')
    parser.add_argument('--storage', choices=('mcap', 'sqlite3'), default='mcap')
    parser.add_argument('--keep', metavar='DIR',
                        help='write the bag in DIR and keep it; an existing DIR is reused')
    parser.add_argument('--json', metavar='FILE', help='write the figures to FILE')
    args = parser.parse_args()
    print(benchlib.machine_line())
    scratch = None
    if args.keep:
        path = Path(args.keep)
    else:
        scratch = Path(tempfile.mkdtemp(prefix='bench_imu_'))
        path = scratch / 'imu_hour'
    try:
        if not (path / 'metadata.yaml').exists():
            count = write_bag(path, args.minutes, args.storage)
            print(f'wrote {count} Imu messages ({args.minutes:g} min at {RATE} Hz) to {path}')
        check = subprocess.run([sys.executable, '-m', 'rot_tools.cli.main', 'imu-check',
                                str(path)], capture_output=True, text=True, cwd=REPO)
        print(check.stdout + check.stderr, end='')
        results = {}

        def side(name, argv):
            def run():
                results.setdefault(name, []).append(timed(argv))
            return run

        benchlib.interleaved({'imu-check': side('imu-check', ['imu-check', path]),
                              'bag': side('bag', ['bag', path])}, args.repeat)
        seconds = {name: benchlib.median([r[1] for r in runs]) for name, runs in results.items()}
        rss = {name: max(r[2] for r in runs) for name, runs in results.items()}
        ratio = seconds['imu-check'] / seconds['bag']
        rows = [[name, f'{seconds[name]:.1f}', f'{rss[name]:.0f}'] for name in seconds]
        benchlib.print_table(f'the same bag, {args.repeat} interleaved runs each (median)',
                             ['command', 'seconds', 'peak RSS MB'], rows)
        print(f'\nimu-check / bag: {ratio:.2f} (goal {benchlib.fmt_goal(GOAL)}: '
              f'{benchlib.verdict(ratio, GOAL)})')
        benchlib.write_json(args.json, {
            'messages': int(args.minutes * 60 * RATE), 'storage': args.storage,
            'seconds': seconds, 'peak_rss_mb': rss, 'ratio': ratio, 'goal': GOAL,
            'met': ratio <= GOAL, 'runs': results})
    finally:
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)


if __name__ == '__main__':
    main()
