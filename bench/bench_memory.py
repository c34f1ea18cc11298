"""
Memory of rotation_node under a long flood: its resident set at the start and the end.

Starts ``rotation_node`` by its console script (defaults: markers on) in an isolated DDS
domain, a subscriber to its outputs in this process (so every output is really sent), and
bench/pose_flooder.py; after a warm-up floods ``~/pose`` at 5000 msg/s for 60 s and samples
the node's RSS (/proc/PID/status VmRSS) every second. Memory is *bounded* when the RSS
grows by less than BOUND_MB over the second half of the flood (a leak of a few hundred
bytes per message would show as tens of MB there). Not a test: a script that prints what it
measured.

Run: ``.venv/bin/python bench/bench_memory.py [--rate 5000] [--seconds 60] [--json PATH]``.
"""

import argparse
import os
from pathlib import Path
import signal
import subprocess
import sys
import tempfile
import threading
import time

import benchlib

BENCH = Path(__file__).resolve().parent
BOUND_MB = 2.0
"""Largest RSS growth over the second half of the flood that still counts as bounded."""
NODE = 'bench_memory_rot_tools'


class Listener:
    """This process's subscriber to the node's outputs, spun in a thread; counts ~/screw."""

    def __init__(self):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import QoSProfile
        from rclpy.signals import SignalHandlerOptions
        from geometry_msgs.msg import QuaternionStamped, TwistStamped, Vector3Stamped
        from std_msgs.msg import Float64MultiArray
        from visualization_msgs.msg import Marker, MarkerArray
        self._rclpy = rclpy
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node('bench_memory_listener')
        self.screws = 0
        outputs = {'rotation_matrix': Float64MultiArray, 'quaternion': QuaternionStamped,
                   'axis_angle': Vector3Stamped, 'euler_angles': Vector3Stamped,
                   'rpy': Vector3Stamped, 'screw': TwistStamped, 'screw_axis': Marker,
                   'markers': MarkerArray}
        for name, msg_type in outputs.items():
            cb = self._count if name == 'screw' else (lambda msg: None)
            self.node.create_subscription(msg_type, f'/{NODE}/{name}', cb, QoSProfile(depth=10))
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self._thread = benchlib.spin_in_thread(rclpy, self.executor)

    def _count(self, msg):
        self.screws += 1

    def close(self):
        self._rclpy.try_shutdown()
        self._thread.join(timeout=2.0)


def flood(flooder, rate, seconds):
    """Have the flooder publish; return (sent, elapsed)."""
    flooder.stdin.write(f'flood /{NODE}/pose {rate} {seconds}\n')
    flooder.stdin.flush()
    reply = flooder.stdout.readline().split()
    if not reply or reply[0] != 'done':
        raise RuntimeError(f'pose_flooder answered {reply!r}')
    return int(reply[1]), float(reply[2])


def measure(rate, seconds, logdir):
    python = sys.executable
    node_log = open(os.path.join(logdir, 'node.log'), 'w')
    script = Path(python).parent / 'rotation_node'  # the console script, as a user starts it
    node = subprocess.Popen([str(script) if script.exists() else 'rotation_node', '--ros-args',
                             '-r', f'__node:={NODE}'], stdout=node_log, stderr=subprocess.STDOUT)
    listener = flooder = None
    try:
        listener = Listener()
        flooder = subprocess.Popen([python, str(BENCH / 'pose_flooder.py'), f'/{NODE}/pose'],
                                   stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        if flooder.stdout.readline().strip() != 'ready':
            raise RuntimeError('pose_flooder did not get ready')
        deadline = time.monotonic() + 30.0
        while listener.screws == 0:  # warm-up: outputs flow (discovery both ways)
            if time.monotonic() > deadline or node.poll() is not None:
                raise RuntimeError('rotation_node never answered; see its log')
            flood(flooder, 100, 0.5)
        flood(flooder, rate, 2.0)  # warm: first calls done, queues at size
        time.sleep(1.0)
        samples = [(0.0, benchlib.rss_mb(node.pid))]
        result = {}
        worker = threading.Thread(target=lambda: result.update(
            zip(('sent', 'elapsed'), flood(flooder, rate, seconds))))
        screws0, start = listener.screws, time.monotonic()
        worker.start()
        while worker.is_alive():
            worker.join(timeout=1.0)
            samples.append((time.monotonic() - start, benchlib.rss_mb(node.pid)))
        delivered = listener.screws - screws0
        time.sleep(2.0)
        after = benchlib.rss_mb(node.pid)
        alive = node.poll() is None
    finally:
        if flooder is not None and flooder.poll() is None:
            flooder.stdin.write('quit\n')
            flooder.stdin.flush()
            flooder.wait(timeout=5.0)
        if node.poll() is None:
            node.send_signal(signal.SIGINT)
            node.wait(timeout=5.0)
        if listener is not None:
            listener.close()
        node_log.close()
    half = [mb for t, mb in samples if t >= seconds / 2]
    growth_second_half = max(half) - half[0] if half else float('nan')
    return {'rate': rate, 'seconds': seconds, 'sent': result['sent'],
            'sent_rate': result['sent'] / result['elapsed'], 'delivered': delivered,
            'rss_start_mb': samples[0][1], 'rss_end_mb': samples[-1][1],
            'rss_max_mb': max(mb for _, mb in samples), 'rss_after_mb': after,
            'growth_second_half_mb': growth_second_half,
            'bounded': growth_second_half < BOUND_MB and alive, 'samples': samples}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--rate', type=int, default=5000, help='offered msg/s (5000)')
    parser.add_argument('--seconds', type=float, default=60.0, help='flood length (60)')
    parser.add_argument('--json', metavar='PATH', help='also write the figures as JSON')
    args = parser.parse_args(argv)
    domain = os.environ.get('BENCH_ROS_DOMAIN_ID') or str(1 + (os.getpid() * 5 + 3) % 101)
    os.environ['ROS_DOMAIN_ID'] = domain
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_STATIC_PEERS', None)
    print(f'bench_memory: {benchlib.machine_line()}; ROS_DOMAIN_ID={domain}')
    with tempfile.TemporaryDirectory(prefix='rot_tools_bench_') as logdir:
        m = measure(args.rate, args.seconds, logdir)
    step = max(1, len(m['samples']) // 12)
    rows = [[f'{t:.0f}', f'{mb:.1f}'] for t, mb in m['samples'][::step]]
    rows.append([f"{m['samples'][-1][0]:.0f}", f"{m['rss_end_mb']:.1f}"])
    benchlib.print_table(
        f"rotation_node RSS (MB) under a flood of ~/pose: offered {m['rate']} msg/s, sent "
        f"{m['sent_rate']:.0f} msg/s for {m['seconds']:.0f} s ({m['delivered']} inputs "
        'answered: the node drops what it cannot keep up with)', ['s', 'RSS MB'], rows)
    print(f"  RSS start {m['rss_start_mb']:.1f} MB, end {m['rss_end_mb']:.1f} MB, max "
          f"{m['rss_max_mb']:.1f} MB, 2 s after the flood {m['rss_after_mb']:.1f} MB; growth "
          f"over the second half {m['growth_second_half_mb']:+.1f} MB (bounded: < {BOUND_MB:g} "
          f"MB): {'yes' if m['bounded'] else 'NO'}")
    benchlib.write_json(args.json, m)


if __name__ == '__main__':
    main()
