"""
rotation_node's /diagnostics under a 400 Hz IMU: what its once-a-second timer costs.

Not a ratio benchmark: the node's loop runs the IMU's checks in its timer, once a second, and
any time they take is time the loop serves no input; the figure to watch is that tick against
the second between two. A window of 10 s at 400 Hz (4,000 samples, of which it checks every
other one: rot_tools.ros.node.diagnostics' CHECKED) is built from ../shared/data's Jackal IMU
(50 Hz), resampled (scipy's Slerp for the orientation), and given to
rot_tools.ros.node.diagnostics.imu_status as the timer gives it, ``--ticks`` times; each tick
timed alone. Also timed: what keeping one ~/imu message costs its callback (ImuWindow.add),
per message. No DDS: the functions the node calls, called directly.

Run: ``.venv/bin/python bench/bench_diagnostics.py [--rate HZ] [--ticks N] [--json PATH]``.
"""

import argparse
from pathlib import Path
import statistics
import time

import benchlib

BAG = Path(__file__).resolve().parents[2] / 'shared' / 'data' / 'jackal_imu_odometry.bag'


def recorded(rate, seconds, path=BAG):
    """
    Return ``seconds`` of the bag's /imu/data at ``rate`` Hz: Imu messages, arrival times (s).

    Resampled from its 50 Hz: the orientation by scipy's Slerp, the gyro and accelerometer
    linearly; stamped from 1,000,000 s on.
    """
    import numpy as np
    from rosbags.highlevel import AnyReader
    from scipy.spatial.transform import Rotation, Slerp
    from sensor_msgs.msg import Imu
    rows = []
    with AnyReader([path]) as reader:
        connections = [c for c in reader.connections if c.topic == '/imu/data']
        for connection, _, raw in reader.messages(connections=connections):
            m = reader.deserialize(raw, connection.msgtype)
            o, w, a = m.orientation, m.angular_velocity, m.linear_acceleration
            rows.append((m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec,
                         o.x, o.y, o.z, o.w, w.x, w.y, w.z, a.x, a.y, a.z))
            frame = m.header.frame_id
    rows = np.array(rows)
    t = rows[:, 0] - rows[0, 0]
    times = np.arange(0.0, min(seconds, t[-1]), 1.0 / rate)
    q = Slerp(t, Rotation.from_quat(rows[:, 1:5]))(times).as_quat()
    rest = np.stack([np.interp(times, t, rows[:, k]) for k in range(5, 11)], axis=1)
    messages = []
    for k, when in enumerate(times):
        msg = Imu()
        msg.header.frame_id = frame
        fresh = 1_000_000.0 + when
        msg.header.stamp.sec, msg.header.stamp.nanosec = int(fresh), int(fresh % 1 * 1e9)
        o, w, a = msg.orientation, msg.angular_velocity, msg.linear_acceleration
        o.x, o.y, o.z, o.w = map(float, q[k])
        w.x, w.y, w.z, a.x, a.y, a.z = map(float, rest[k])
        messages.append(msg)
    return messages, times


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--rate', type=float, default=400.0, help='the IMU rate (Hz)')
    parser.add_argument('--ticks', type=int, default=20)
    parser.add_argument('--json', type=Path)
    args = parser.parse_args()
    from rot_tools.ros.node import diagnostics
    messages, arrivals = recorded(args.rate, diagnostics.WINDOW)
    window = diagnostics.ImuWindow()
    adds = []
    for msg, arrival in zip(messages, arrivals):
        begin = time.perf_counter()
        window.add(msg, arrival)
        adds.append(time.perf_counter() - begin)
    count, now = len(messages), arrivals[-1]
    ticks = []
    for _ in range(args.ticks):
        begin = time.perf_counter()
        status = diagnostics.imu_status('rot_tools', window, now)
        ticks.append(time.perf_counter() - begin)
    print(benchlib.machine_line())
    print(f'IMU at {args.rate:g} Hz, {count:,} samples in the window: {status.message}')
    print(f'timer tick (imu conventions): median {statistics.median(ticks) * 1e3:.1f} ms, '
          f'worst {max(ticks) * 1e3:.1f} ms of {diagnostics.PERIOD:g} s, over {args.ticks} '
          'ticks')
    print(f'keeping one ~/imu message: median {statistics.median(adds) * 1e6:.1f} µs')
    if args.json:
        benchlib.write_json(args.json, {
            'rate_hz': args.rate, 'samples': count,
            'tick_ms_median': statistics.median(ticks) * 1e3, 'tick_ms_worst': max(ticks) * 1e3,
            'add_us_median': statistics.median(adds) * 1e6})


if __name__ == '__main__':
    main()
