"""
The whole `rot-tools bag --csv` on a bag of >= 1e6 orientation messages, against two scripts.

The bag is written here from the real recording (../shared/data/jackal_imu_odometry.bag: 3,061
Imu and 3,060 Odometry messages, 61 s): its messages, converted to CDR by rosbags, are
repeated with their header stamps and record times shifted by the recording's length until
there are at least --messages of them, into a rosbag2 bag (sqlite3, or MCAP with
--storage mcap). Then, in the same run, each timed --repeat times, the repetitions of the
three interleaved (the order rotating from one repetition to the next) and each one's median
taken, as every benchmark here does:

- ``rot-tools bag BAG --csv FILE`` as a user runs it (the console script, a subprocess);
- (a) the script users write today: rosbags' reader and deserialiser, then per message scipy's
  ``Rotation.from_quat(q).as_euler('xyz')``, one CSV row (csv.writer) of topic, stamp,
  position, quaternion, roll, pitch, yaw;
- (b) rosbags' own read-and-deserialise loop, nothing else.

Goals: rot-tools ≤ 0.2 × (a) and ≤ 1.5 × (b). Prints each side's wall time and CPU time
(user + system of its process: on a machine shared with other work the wall time of a
minutes-long run depends on what else ran meanwhile, its CPU time much less) and the two
ratios of each.

    .venv/bin/python bench/bench_bag.py [--messages 1000000] [--storage sqlite3|mcap]
"""

import argparse
from pathlib import Path
import resource
import shutil
import statistics
import struct
import subprocess
import sys
import tempfile
import time

REPO = Path(__file__).resolve().parents[1]
REAL = REPO.parent / 'shared' / 'data' / 'jackal_imu_odometry.bag'

SCRIPT_A = r"""
import csv, sys
from pathlib import Path
from rosbags.highlevel import AnyReader
from scipy.spatial.transform import Rotation

with AnyReader([Path(sys.argv[1])]) as reader, open(sys.argv[2], 'w', newline='') as f:
    out = csv.writer(f)
    out.writerow(['topic', 'stamp', 'x', 'y', 'z', 'qx', 'qy', 'qz', 'qw',
                  'roll', 'pitch', 'yaw'])
    for conn, t, raw in reader.messages():
        msg = reader.deserialize(raw, conn.msgtype)
        if conn.msgtype == 'sensor_msgs/msg/Imu':
            q, p = msg.orientation, None
        else:
            q, p = msg.pose.pose.orientation, msg.pose.pose.position
        roll, pitch, yaw = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_euler('xyz')
        stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        xyz = (p.x, p.y, p.z) if p is not None else (0.0, 0.0, 0.0)
        out.writerow([conn.topic, stamp, *xyz, q.x, q.y, q.z, q.w, roll, pitch, yaw])
"""

SCRIPT_B = r"""
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader

with AnyReader([Path(sys.argv[1])]) as reader:
    for conn, t, raw in reader.messages():
        reader.deserialize(raw, conn.msgtype)
"""


def write_bag(dst, count, storage):
    """Return a rosbag2 bag of >= count messages: the real recording, repeated, shifted in time."""
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import get_typestore, Stores

    from rosbags.convert import convert

    store = get_typestore(Stores.ROS2_JAZZY)
    once = Path(dst).parent / 'once'  # the recording as rosbag2: its messages in CDR
    convert([REAL], once, 'sqlite3', 8, None, 'file', None, None, [], [], [], [])
    with AnyReader([once]) as reader:
        msgs = [(c.topic, c.msgtype, t, bytearray(raw)) for c, t, raw in reader.messages()]
        span = reader.end_time - reader.start_time + 20_000_000  # + one Imu period
    shutil.rmtree(once)
    plugin = StoragePlugin.MCAP if storage == 'mcap' else StoragePlugin.SQLITE3
    written = 0
    with Writer(dst, version=8, storage_plugin=plugin) as writer:
        conns = {}
        for topic, msgtype, _, _ in msgs:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
        copy = 0
        while written < count:
            shift = copy * span
            for topic, _, t, data in msgs:
                sec, nsec = struct.unpack_from('<iI', data, 4)  # header.stamp after CDR's 4
                total = sec * 1_000_000_000 + nsec + shift
                struct.pack_into('<iI', data, 4, total // 1_000_000_000, total % 1_000_000_000)
                writer.write(conns[topic], t + shift, bytes(data))
                struct.pack_into('<iI', data, 4, sec, nsec)
            written += len(msgs)
            copy += 1
    return written


def timed(cmd):
    """(wall seconds, CPU seconds: user + system) of one run of cmd."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode:
        sys.exit(f'{cmd[:3]} failed: {done.stderr[-2000:]}')
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def interleaved(commands, repeat):
    """{name: (median wall s, median CPU s)} of the commands, in a rotating order."""
    names = list(commands)
    runs = {name: [] for name in names}
    for k in range(repeat):
        for name in names[k % len(names):] + names[:k % len(names)]:
            runs[name].append(timed(commands[name]))
    return {name: (statistics.median(w for w, _ in times), statistics.median(c for _, c in times))
            for name, times in runs.items()}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--messages', type=int, default=1_000_000)
    parser.add_argument('--storage', choices=('sqlite3', 'mcap'), default='sqlite3')
    parser.add_argument('--repeat', type=int, default=1,
                        help='repetitions of each side (the median is taken); (a) takes ~3 min '
                        'for 1e6 messages on this machine')
    args = parser.parse_args()
    script = Path(sys.executable).parent / 'rot-tools'
    with tempfile.TemporaryDirectory(prefix='bench_bag_') as tmp:
        tmp = Path(tmp)
        bag = tmp / 'bag'
        start = time.perf_counter()
        n = write_bag(bag, args.messages, args.storage)
        print(f'wrote {n} messages ({args.storage}, '
              f'{sum(f.stat().st_size for f in bag.iterdir()) / 1e6:.0f} MB) in '
              f'{time.perf_counter() - start:.1f} s')
        (tmp / 'a.py').write_text(SCRIPT_A)
        (tmp / 'b.py').write_text(SCRIPT_B)
        times = interleaved({
            'ours': [str(script), 'bag', str(bag), '--csv', str(tmp / 'ours.csv')],
            'a': [sys.executable, str(tmp / 'a.py'), str(bag), str(tmp / 'a.csv')],
            'b': [sys.executable, str(tmp / 'b.py'), str(bag)]}, args.repeat)
        rows = sum(1 for _ in open(tmp / 'ours.csv')) - 1
        labels = {'ours': f'rot-tools bag --csv ({rows} rows)',
                  'a': '(a) rosbags + scipy per message + csv',
                  'b': '(b) rosbags read + deserialise'}
        for name, (wall, cpu) in times.items():
            print(f'{labels[name]:<42} wall {wall:7.2f} s   CPU {cpu:7.2f} s '
                  f'({cpu / n * 1e6:.2f} µs/message)')
        for k, what in enumerate(('wall', 'CPU')):
            ours, a, b = (times[name][k] for name in ('ours', 'a', 'b'))
            print(f'{what:>4}: ratio to (a) {ours / a:.3f} (goal <= 0.2), ratio to (b) '
                  f'{ours / b:.3f} (goal <= 1.5)')
        shutil.rmtree(bag, ignore_errors=True)


if __name__ == '__main__':
    main()
