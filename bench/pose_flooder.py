"""
Publisher process of bench_node.py: floods PoseStamped at a set rate, on command.

Started by bench_node.py with the pose topics as arguments; publishes with the sensor-data
QoS rotation_node subscribes with (best effort). Waits until every topic has a subscriber,
prints ``ready``, then reads commands on stdin, one a line:

``flood TOPIC RATE SECONDS``  publish RATE msg/s for SECONDS, each message stamped with the
                              wall clock (time.time_ns) just before it is published; prints
                              ``done SENT ELAPSED`` (elapsed seconds of the flood). RATE
                              ``max``: as fast as this process can publish, for SECONDS of
                              wall time (the fastest flood one publisher sends on the
                              loopback: ~57k msg/s on the 2-core machine of bench/README.md)
``quit``                      exit

Messages come from a pool of 1000 random valid poses (unit quaternions), so the node does
its full work on every one.
"""

import math
import random
import sys
import time

from geometry_msgs.msg import PoseStamped
import rclpy
from rclpy.qos import qos_profile_sensor_data

POOL = 1000


def pose_pool(seed=5):
    rng = random.Random(seed)
    pool = []
    for _ in range(POOL):
        q = [rng.gauss(0.0, 1.0) for _ in range(4)]
        n = math.sqrt(sum(c * c for c in q))
        msg = PoseStamped()
        msg.header.frame_id = 'world'
        o, p = msg.pose.orientation, msg.pose.position
        o.x, o.y, o.z, o.w = (c / n for c in q)
        p.x, p.y, p.z = (rng.uniform(-2.0, 2.0) for _ in range(3))
        pool.append(msg)
    return pool


def flood(publisher, pool, rate, seconds):
    """Publish at ``rate`` msg/s for ``seconds`` (catching up in bursts when behind)."""
    total = max(1, int(round(rate * seconds)))
    sent = 0
    start = time.perf_counter()
    while sent < total:
        due = min(total, int((time.perf_counter() - start) * rate) + 1)
        while sent < due:
            msg = pool[sent % POOL]
            now = time.time_ns()
            stamp = msg.header.stamp
            stamp.sec, stamp.nanosec = divmod(now, 1_000_000_000)
            publisher.publish(msg)
            sent += 1
        wait = start + sent / rate - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
    return sent, time.perf_counter() - start


def flood_max(publisher, pool, seconds):
    """Publish back to back for ``seconds`` of wall time; return (sent, elapsed)."""
    sent = 0
    start = time.perf_counter()
    end = start + seconds
    publish, now_ns, clock = publisher.publish, time.time_ns, time.perf_counter
    while clock() < end:
        for _ in range(100):  # look at the clock once per 100 messages
            msg = pool[sent % POOL]
            stamp = msg.header.stamp
            stamp.sec, stamp.nanosec = divmod(now_ns(), 1_000_000_000)
            publish(msg)
            sent += 1
    return sent, time.perf_counter() - start


def main(topics):
    rclpy.init()
    node = rclpy.create_node('bench_pose_flooder')
    publishers = {t: node.create_publisher(PoseStamped, t, qos_profile_sensor_data)
                  for t in topics}
    deadline = time.monotonic() + 30.0
    while any(p.get_subscription_count() < 1 for p in publishers.values()):
        if time.monotonic() > deadline:
            missing = [t for t, p in publishers.items() if p.get_subscription_count() < 1]
            print(f'error no subscriber on {" ".join(missing)}', flush=True)
            return 1
        time.sleep(0.02)
    pool = pose_pool()
    print('ready', flush=True)
    for line in iter(sys.stdin.readline, ''):
        words = line.split()
        if not words or words[0] == 'quit':
            break
        if words[0] == 'flood':
            if words[2] == 'max':
                sent, elapsed = flood_max(publishers[words[1]], pool, float(words[3]))
            else:
                sent, elapsed = flood(publishers[words[1]], pool, float(words[2]),
                                      float(words[3]))
            print(f'done {sent} {elapsed:.6f}', flush=True)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
