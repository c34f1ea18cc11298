"""
``rot-tools bag BAG --csv FILE`` against the same job written the usual way, per message.

The bag is the real recording (../shared/data/jackal_imu_odometry.bag: 3,061 Imu and 3,060
Odometry messages, a ROS 1 bag), or --copies of it joined into one rosbag2 bag. Each side runs
in a process of its own that has imported its libraries already, and only its job is timed:
reading the bag, computing, writing the table to FILE and the summary. The repetitions of the
sides are interleaved (the order rotating from one to the next) and each one's median taken:

- ``rot-tools bag BAG --csv FILE`` (rot_tools.cli.main.main, the console script's function);
- the usual way (``USUAL``): rosbags' ``AnyReader`` and ``deserialize``, then per message
  scipy's ``Rotation`` — the canonical quaternion, roll/pitch/yaw made continuous, the
  rotation vector and angle, the body angular velocity from the previous message, the
  standard deviations of roll, pitch and yaw from the message's covariance — and one
  ``csv.writer`` row of the same columns; then the same summary per topic (counts, stamps,
  ranges, total angle, mean orientation, the IMU's gyro check, the covariances' median);
- for comparison, a smaller job (``ANGLES_ONLY``): the same reading, then per message only
  scipy's roll, pitch and yaw and a row of 12 columns (topic, stamp, position, quaternion as
  recorded, roll, pitch, yaw), no summary;
- rosbags' own read-and-deserialise loop, nothing else: the floor every side stands on.

Goal: rot-tools' time per message ≤ 0.75 × the usual way's. The two tables are compared
(every column within 1e-9) before the times are printed. Nothing is asserted about time.

    .venv/bin/python bench/bench_bag.py [--repeat 5] [--copies 1] [--json FILE]
"""

import argparse
import csv
from pathlib import Path
import shutil
import subprocess
import sys
import tempfile

import benchlib
from rot_tools.core.euler import RPY_SEQUENCE
from rot_tools.io.boundary import QUATERNION_TOLERANCE

REPO = Path(__file__).resolve().parents[1]
REAL = REPO.parent / 'shared' / 'data' / 'jackal_imu_odometry.bag'
GOAL = 0.75

OURS = r"""
import contextlib, os, sys, time
from rot_tools.cli import bag, bag_analysis, fleet, main  # noqa: F401 (before the clock)
from rosbags.highlevel import AnyReader  # noqa: F401

with open(os.devnull, 'w') as devnull, contextlib.redirect_stdout(devnull):
    start = time.perf_counter()
    status = main.main(['bag', sys.argv[1], '--csv', sys.argv[2]])
    seconds = time.perf_counter() - start
sys.exit(status or print(seconds))
"""

USUAL = r"""
import csv, json, math, os, sys, time
from pathlib import Path

import numpy as np
from rosbags.highlevel import AnyReader
from scipy.spatial.transform import Rotation

RPY, TOL = sys.argv[3], float(sys.argv[4])  # REP 103's sequence, the quaternion tolerance
HEADER = ['topic', 'stamp', 'frame_id', 'x', 'y', 'z', 'qx', 'qy', 'qz', 'qw', 'roll',
          'pitch', 'yaw', 'rx', 'ry', 'rz', 'angle', 'wx', 'wy', 'wz', 'roll_std',
          'pitch_std', 'yaw_std']


def pose(msg, msgtype):
    # (orientation, position, rotation's 3x3 covariance, gyro) of the message
    if msgtype == 'sensor_msgs/msg/Imu':
        cov = np.reshape(msg.orientation_covariance, (3, 3))
        return msg.orientation, None, cov, msg.angular_velocity
    cov = np.reshape(msg.pose.covariance, (6, 6))[3:, 3:]
    return msg.pose.pose.orientation, msg.pose.pose.position, cov, None


def rpy_stddev(cov, rpy):
    # roll, pitch, yaw's standard deviations of a rotation's covariance about the fixed axes
    if not cov.any():
        return 'unknown'
    scale = np.abs(cov).max()
    if (not np.isfinite(cov).all() or np.abs(cov - cov.T).max() > 1e-9 * scale
            or np.linalg.eigvalsh(cov).min() < -1e-9 * scale):
        return 'bad'
    _, pitch, yaw = rpy
    cp, sp, cy, sy = math.cos(pitch), math.sin(pitch), math.cos(yaw), math.sin(yaw)
    E = np.array([[cp * cy, -sy, 0.0], [cp * sy, cy, 0.0], [-sp, 0.0, 1.0]])  # ω = E·ṙpy
    if abs(cp) < 1e-9:
        return 'gimbal_lock'
    J = np.linalg.inv(E)
    return np.sqrt(np.diag(J @ cov @ J.T))


class Topic:
    def __init__(self, msgtype):
        self.msgtype, self.frames, self.stamps = msgtype, [], []
        self.accepted, self.refused = 0, {}
        self.previous = self.raw = self.offset = None
        self.low, self.high = np.full(3, np.inf), np.full(3, -np.inf)
        self.total, self.quaternions, self.gyro, self.sigmas = 0.0, [], [], []
        self.covariances = {'good': 0, 'unknown': 0, 'bad': 0, 'gimbal_lock': 0}


def main(path, out_path):
    topics = {}
    with AnyReader([Path(path)]) as reader, open(out_path, 'w', newline='') as out:
        table = csv.writer(out, lineterminator='\n')
        table.writerow(HEADER)
        for conn, _, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            t = topics.setdefault(conn.topic, Topic(conn.msgtype))
            stamp = msg.header.stamp
            ns = stamp.sec * 1_000_000_000 + stamp.nanosec
            t.stamps.append(ns)
            if msg.header.frame_id not in t.frames:
                t.frames.append(msg.header.frame_id)
            q, p, cov, gyro = pose(msg, conn.msgtype)
            q = [q.x, q.y, q.z, q.w]
            p = [p.x, p.y, p.z] if p is not None else [0.0, 0.0, 0.0]
            norm = math.sqrt(sum(c * c for c in q))
            reason = ('no_orientation' if gyro is not None and cov[0, 0] == -1
                      else 'non_finite' if not all(map(math.isfinite, q + p))
                      else 'zero_quaternion' if norm == 0
                      else 'non_unit_quaternion' if abs(norm - 1) > TOL else None)
            if reason:
                t.refused[reason] = t.refused.get(reason, 0) + 1
                continue
            t.accepted += 1
            r = Rotation.from_quat(q)
            rpy = r.as_euler(RPY)
            if t.raw is None:  # continuous along the topic: no jump at ±π
                t.offset = np.zeros(3)
            else:
                t.offset -= 2 * math.pi * np.round((rpy - t.raw) / (2 * math.pi))
            t.raw, angles = rpy, rpy + t.offset
            t.low, t.high = np.minimum(t.low, angles), np.maximum(t.high, angles)
            rotvec = r.as_rotvec()
            omega = ['', '', '']
            if t.previous is not None:
                step = (t.previous[0].inv() * r).as_rotvec()
                t.total += np.linalg.norm(step)
                dt = (ns - t.previous[1]) * 1e-9
                if dt > 0:
                    omega = step / dt
                    if gyro is not None:
                        mean_gyro = 0.5 * (t.previous[2] + [gyro.x, gyro.y, gyro.z])
                        t.gyro.append(np.sum((omega - mean_gyro) ** 2))
                    omega = list(omega)
            t.previous = (r, ns, np.array([gyro.x, gyro.y, gyro.z]) if gyro else None)
            t.quaternions.append(q)
            sigma = rpy_stddev(cov, rpy)
            if isinstance(sigma, str):
                t.covariances[sigma] += 1
                sigma = ['', '', '']
            else:
                t.covariances['good'] += 1
                t.sigmas.append(sigma)
                sigma = list(sigma)
            sec, nsec = divmod(abs(ns), 1_000_000_000)
            table.writerow([conn.topic, f'{"-" if ns < 0 else ""}{sec}.{nsec:09d}',
                            msg.header.frame_id, *p, *r.as_quat(canonical=True), *angles,
                            *rotvec, np.linalg.norm(rotvec), *omega, *sigma])
    summary = {'bag': path, 'topics': {}}
    for name, t in topics.items():
        mean = Rotation.from_quat(t.quaternions).mean()
        start, end = min(t.stamps), max(t.stamps)
        summary['topics'][name] = {
            'type': t.msgtype, 'frame_ids': t.frames, 'messages': len(t.stamps),
            'accepted': t.accepted, 'refused': t.refused, 'start': start / 1e9,
            'end': end / 1e9, 'rate': (len(t.stamps) - 1) / ((end - start) / 1e9),
            'rpy_range': [list(t.low), list(t.high)], 'total_angle': t.total,
            'mean_orientation': {'quaternion': list(mean.as_quat(canonical=True)),
                                 'rpy': list(mean.as_euler(RPY))},
            'gyro_rms_difference': math.sqrt(np.mean(t.gyro)) if t.gyro else None,
            'covariances': t.covariances,
            'rpy_stddev_median': list(np.median(t.sigmas, axis=0)) if t.sigmas else 'unknown'}
    print(json.dumps(summary, indent=2))


with open(os.devnull, 'w') as sys.stdout:
    start = time.perf_counter()
    main(sys.argv[1], sys.argv[2])
    seconds = time.perf_counter() - start
sys.stdout = sys.__stdout__
print(seconds)
"""

ANGLES_ONLY = r"""
import csv, os, sys, time
from pathlib import Path
from rosbags.highlevel import AnyReader
from scipy.spatial.transform import Rotation

RPY = sys.argv[3]
start = time.perf_counter()
with AnyReader([Path(sys.argv[1])]) as reader, open(sys.argv[2], 'w', newline='') as f:
    out = csv.writer(f, lineterminator='\n')
    out.writerow(['topic', 'stamp', 'x', 'y', 'z', 'qx', 'qy', 'qz', 'qw', 'roll', 'pitch',
                  'yaw'])
    for conn, t, raw in reader.messages():
        msg = reader.deserialize(raw, conn.msgtype)
        if conn.msgtype == 'sensor_msgs/msg/Imu':
            q, p = msg.orientation, None
        else:
            q, p = msg.pose.pose.orientation, msg.pose.pose.position
        roll, pitch, yaw = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_euler(RPY)
        stamp = msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec
        xyz = (p.x, p.y, p.z) if p is not None else (0.0, 0.0, 0.0)
        out.writerow([conn.topic, stamp, *xyz, q.x, q.y, q.z, q.w, roll, pitch, yaw])
print(time.perf_counter() - start)
"""

FLOOR = r"""
import sys, time
from pathlib import Path
from rosbags.highlevel import AnyReader

start = time.perf_counter()
with AnyReader([Path(sys.argv[1])]) as reader:
    for conn, _, raw in reader.messages():
        reader.deserialize(raw, conn.msgtype)
print(time.perf_counter() - start)
"""


def side(script, *args, seconds):
    """Return a zero-argument callable running ``script``; it appends the job's time."""
    def run():
        done = subprocess.run([sys.executable, '-c', script, *map(str, args)],
                              capture_output=True, text=True)
        if done.returncode:
            sys.exit(f'{script.strip().splitlines()[0]}... failed: {done.stderr[-2000:]}')
        seconds.append(float(done.stdout))
    return run


def copies_of_the_recording(path, copies):
    """Return a rosbag2 bag of ``copies`` copies of the recording, each later than the last."""
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import get_typestore, Stores
    store = get_typestore(Stores.ROS2_JAZZY)
    with AnyReader([REAL]) as reader:
        messages = [(c.topic, c.msgtype, t, reader.deserialize(raw, c.msgtype))
                    for c, t, raw in reader.messages()]
        span = reader.end_time - reader.start_time + 20_000_000  # + one Imu period
    with Writer(path, version=8) as writer:
        conns = {}
        for k in range(copies):
            for topic, msgtype, t, msg in messages:
                if topic not in conns:
                    conns[topic] = writer.add_connection(topic, msgtype, typestore=store)
                stamp = msg.header.stamp
                ns = stamp.sec * 1_000_000_000 + stamp.nanosec + k * span
                stamp.sec, stamp.nanosec = divmod(ns, 1_000_000_000)
                writer.write(conns[topic], t + k * span, store.serialize_cdr(msg, msgtype))
                stamp.sec, stamp.nanosec = divmod(ns - k * span, 1_000_000_000)
    return len(messages) * copies


def tables_agree(ours, usual):
    """
    Return the largest difference between the two tables' numbers.

    The same rows: rot-tools' topic by topic, the usual way's in the bag's order (sorted
    here by topic, the order kept within each).
    """
    with open(ours, newline='') as a, open(usual, newline='') as b:
        rows_a, rows_b = list(csv.reader(a)), list(csv.reader(b))
    rows_b[1:] = sorted(rows_b[1:], key=lambda row: row[0])
    if len(rows_a) != len(rows_b) or rows_a[0] != rows_b[0]:
        sys.exit(f'the tables differ: {len(rows_a)} and {len(rows_b)} lines')
    worst = 0.0
    for x, y in zip(rows_a[1:], rows_b[1:]):
        if x[:3] != y[:3] or [c == '' for c in x] != [c == '' for c in y]:
            sys.exit(f'the tables differ: {x[:3]} and {y[:3]}')
        numbers = [(float(u), float(v)) for u, v in zip(x[3:], y[3:]) if u != '']
        worst = max([worst] + [abs(u - v) for u, v in numbers])
    return worst


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--repeat', type=int, default=5)
    parser.add_argument('--copies', type=int, default=1,
                        help='copies of the recording in one rosbag2 bag (1: the ROS 1 bag '
                        'itself)')
    parser.add_argument('--json', help='write the figures here (for run_all.py)')
    args = parser.parse_args()
    print(f'bench_bag: {benchlib.machine_line()}')
    with tempfile.TemporaryDirectory(prefix='rot_tools_bag_') as tmp:
        tmp = Path(tmp)
        if args.copies > 1:
            bag = tmp / 'bag'
            messages = copies_of_the_recording(bag, args.copies)
        else:
            bag, messages = REAL, 3061 + 3060
        ours, usual = tmp / 'ours.csv', tmp / 'usual.csv'
        seconds = {'rot-tools bag --csv': [], 'the usual way': [],
                   'the usual way, angles only': [], 'rosbags alone': []}
        benchlib.interleaved({
            'rot-tools bag --csv': side(OURS, bag, ours, seconds=seconds['rot-tools bag --csv']),
            'the usual way': side(USUAL, bag, usual, RPY_SEQUENCE, QUATERNION_TOLERANCE,
                                  seconds=seconds['the usual way']),
            'the usual way, angles only': side(ANGLES_ONLY, bag, tmp / 'angles.csv',
                                               RPY_SEQUENCE,
                                               seconds=seconds['the usual way, angles only']),
            'rosbags alone': side(FLOOR, bag, seconds=seconds['rosbags alone']),
        }, args.repeat)
        worst = tables_agree(ours, usual)
        shutil.rmtree(tmp / 'bag', ignore_errors=True)
    median = {name: benchlib.median(values) for name, values in seconds.items()}
    per_message = {name: s / messages for name, s in median.items()}
    ratio = median['rot-tools bag --csv'] / median['the usual way']
    benchlib.print_table(
        f'{messages} messages ({"the recording" if args.copies == 1 else f"{args.copies} copies"}'
        f'), the job alone (imports before the clock); median of {args.repeat}; the two '
        f'tables agree within {worst:.1e}',
        ['side', 'seconds', 'µs/message'],
        [[name, f'{median[name]:.3f}', f'{1e6 * per_message[name]:.1f}'] for name in median])
    benchlib.print_table('Goal', ['figure', 'measured', 'goal', 'met?'], [
        ['rot-tools bag / the usual way (time per message)', f'{ratio:.2f}', f'<= {GOAL:g}',
         benchlib.verdict(ratio, GOAL)],
        ['(rot-tools bag / the usual way, angles only: a smaller job)',
         f'{median["rot-tools bag --csv"] / median["the usual way, angles only"]:.2f}', '-',
         '-'],
        ['(rosbags alone / the usual way: the floor)',
         f'{median["rosbags alone"] / median["the usual way"]:.2f}', '-', '-']])
    benchlib.write_json(args.json, {
        'messages': messages, 'repeat': args.repeat, 'seconds': median,
        'per_message': per_message, 'ratio': ratio, 'goal': GOAL, 'tables_agree': worst})
    return 0


if __name__ == '__main__':
    sys.exit(main())
