"""
Publisher process of the node benchmarks: floods PoseStamped, or TFMessage on /tf, on command.

Started by bench_node.py, bench_memory.py and bench_overload.py with the topics as
arguments. A pose topic gets the sensor-data QoS rotation_node subscribes with (best
effort); a topic named ``tf`` (``/tf``) gets tf2_ros's (rot_tools.ros.tf_input.TF_QOS:
reliable, depth 100), and the process then also publishes, once, the static edge
``map → odom`` on the ``tf_static`` beside it (transient local). Waits until every topic has
a subscriber, prints ``ready``, then reads commands on stdin, one a line:

``flood TOPIC RATE SECONDS [SCENARIO]``
    publish RATE msg/s for SECONDS, each message stamped from the wall clock
    (time.time_ns) just before it is published; prints ``done SENT ELAPSED`` (elapsed
    seconds of the flood). RATE ``max``: as fast as this process can publish, for SECONDS
    of wall time (the fastest flood one publisher sends on the loopback). SCENARIO (a /tf
    topic only; see TF_SCENARIOS): ``steady`` (the default), ``large``, ``reparent`` or ``jump``.
``quit``
    exit

Messages come from a pool of 1000 random valid poses (unit quaternions), so the node does
its full work on every one. The TF stream's messages (tf_pool, tf_message, static_map_odom)
are shared with bench_first_calls.py.
"""

import math
import random
import sys
import time

from geometry_msgs.msg import PoseStamped, TransformStamped
import rclpy
from rclpy.qos import qos_profile_sensor_data

POOL = 1000
NS = 1_000_000_000

TF_SCENARIOS = {
    'steady': 'one transform odom → base_link a message, stamped now',
    'large': 'steady, and every LARGE_PERIOD s one TFMessage of LARGE_TRANSFORMS transforms '
             '(odom → flood_000000 …), LARGE_COUNT in all',
    'reparent': "steady, base_link's parent changing at every message: odom, map, odom … "
                '(map → odom static)',
    'jump': "steady, the stream's clock going back JUMP_SECONDS every second, and every "
            'FUTURE_EVERY-th message stamped FUTURE_SECONDS ahead',
}
"""What a /tf flood sends (the node follows base_link in odom)."""

LARGE_TRANSFORMS = 100_000
LARGE_COUNT = 10
LARGE_PERIOD = 1.0
JUMP_SECONDS = 30
FUTURE_EVERY = 100
FUTURE_SECONDS = 1_000_000


def unit_quaternion(rng):
    """Return a random unit quaternion (x, y, z, w), from four Gaussian samples."""
    q = [rng.gauss(0.0, 1.0) for _ in range(4)]
    norm = math.sqrt(sum(c * c for c in q))
    return [c / norm for c in q]


def pose_pool(seed=5):
    rng = random.Random(seed)
    pool = []
    for _ in range(POOL):
        msg = PoseStamped()
        msg.header.frame_id = 'world'
        o, p = msg.pose.orientation, msg.pose.position
        o.x, o.y, o.z, o.w = unit_quaternion(rng)
        p.x, p.y, p.z = (rng.uniform(-2.0, 2.0) for _ in range(3))
        pool.append(msg)
    return pool


def tf_pool(seed=7):
    """Return POOL TFMessages of one transform odom → base_link each (random valid motions)."""
    from tf2_msgs.msg import TFMessage
    rng = random.Random(seed)
    pool = []
    for _ in range(POOL):
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = 'odom', 'base_link'
        r, b = t.transform.rotation, t.transform.translation
        r.x, r.y, r.z, r.w = unit_quaternion(rng)
        b.x, b.y, b.z = (rng.uniform(-2.0, 2.0) for _ in range(3))
        pool.append(TFMessage(transforms=[t]))
    return pool


def tf_message(pool, k, now_ns, start_ns, scenario):
    """
    Return the k-th TFMessage of ``scenario`` (TF_SCENARIOS), stamped at ``now_ns``.

    start_ns: the stream's start (the jumps of ``jump`` count whole seconds from it). The
    message is one of ``pool`` (tf_pool), changed in place.
    """
    msg = pool[k % POOL]
    transform = msg.transforms[0]
    ns = now_ns
    if scenario == 'reparent':
        transform.header.frame_id = 'map' if k % 2 else 'odom'
    elif scenario == 'jump':
        if k % FUTURE_EVERY == FUTURE_EVERY - 1:
            ns = now_ns + FUTURE_SECONDS * NS
        else:
            ns = now_ns - JUMP_SECONDS * NS * ((now_ns - start_ns) // NS)
    stamp = transform.header.stamp
    stamp.sec, stamp.nanosec = divmod(ns, NS)
    return msg


def large_tf_message(now_ns, count=LARGE_TRANSFORMS):
    """
    Return a TFMessage of ``count`` transforms odom → flood_NNNNNN, serialised.

    Published as bytes (rclpy's publish takes them), so that the flooder does not convert
    the message again at every publication.
    """
    from rclpy.serialization import serialize_message
    from tf2_msgs.msg import TFMessage
    sec, nanosec = divmod(now_ns, NS)
    transforms = []
    for i in range(count):
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = 'odom', f'flood_{i:06d}'
        t.header.stamp.sec, t.header.stamp.nanosec = sec, nanosec
        t.transform.translation.x = i * 1e-3
        t.transform.rotation.w = 1.0
        transforms.append(t)
    return serialize_message(TFMessage(transforms=transforms))


def static_map_odom(now_ns):
    """Return a TFMessage of the static edge map → odom (odom 2 m along map's x)."""
    from tf2_msgs.msg import TFMessage
    t = TransformStamped()
    t.header.frame_id, t.child_frame_id = 'map', 'odom'
    t.header.stamp.sec, t.header.stamp.nanosec = divmod(now_ns, NS)
    t.transform.translation.x = 2.0
    t.transform.rotation.w = 1.0
    return TFMessage(transforms=[t])


class PoseSender:
    """start(scenario) → send(k): publish the k-th PoseStamped of the pool, stamped now."""

    def __init__(self, publisher):
        self.publisher, self.pool = publisher, pose_pool()

    def start(self, scenario):
        pool, publish, now_ns = self.pool, self.publisher.publish, time.time_ns

        def send(k):
            msg = pool[k % POOL]
            stamp = msg.header.stamp
            stamp.sec, stamp.nanosec = divmod(now_ns(), NS)
            publish(msg)
        return send


class TfSender:
    """
    start(scenario) → send(k): publish the k-th TFMessage of a scenario (TF_SCENARIOS).

    The large messages go out through a publisher of their own (``large_publisher``), as from
    another tf2 broadcaster: on the stream's own writer (keep-last 100) the stream's next
    100 messages would push a large one out of the writer's history before all its
    fragments were sent, and the node would never get one whole.
    """

    def __init__(self, publisher, large_publisher):
        self.publisher, self.pool = publisher, tf_pool()
        self.large_publisher, self.large = large_publisher, None

    def start(self, scenario):
        if scenario not in TF_SCENARIOS:
            raise SystemExit(f'unknown scenario {scenario!r}: one of {", ".join(TF_SCENARIOS)}')
        if scenario == 'large' and self.large is None:
            self.large = large_tf_message(time.time_ns())  # (built once, before the clock)
        start_ns = time.time_ns()
        sent_large = [0]
        publish, pool, clock = self.publisher.publish, self.pool, time.time_ns

        def send(k):
            now = clock()
            if (scenario == 'large' and sent_large[0] < LARGE_COUNT
                    and now - start_ns >= sent_large[0] * LARGE_PERIOD * NS):
                sent_large[0] += 1
                self.large_publisher.publish(self.large)
            publish(tf_message(pool, k, now, start_ns, scenario))
        return send


def flood(send, rate, seconds):
    """Call send(k) at ``rate`` a second for ``seconds`` (catching up in bursts when behind)."""
    total = max(1, int(round(rate * seconds)))
    sent = 0
    start = time.perf_counter()
    while sent < total:
        due = min(total, int((time.perf_counter() - start) * rate) + 1)
        while sent < due:
            send(sent)
            sent += 1
        wait = start + sent / rate - time.perf_counter()
        if wait > 0:
            time.sleep(wait)
    return sent, time.perf_counter() - start


def flood_max(send, seconds):
    """Call send(k) back to back for ``seconds`` of wall time; return (sent, elapsed)."""
    sent = 0
    start = time.perf_counter()
    end = start + seconds
    clock = time.perf_counter
    while clock() < end:
        for _ in range(100):  # look at the clock once per 100 messages
            send(sent)
            sent += 1
    return sent, time.perf_counter() - start


def main(topics):
    rclpy.init()
    node = rclpy.create_node('bench_pose_flooder')
    senders = {}
    for topic in topics:
        if topic.rsplit('/', 1)[-1] == 'tf':
            from rot_tools.ros.tf_input import TF_QOS, TF_STATIC_QOS
            from tf2_msgs.msg import TFMessage
            senders[topic] = TfSender(node.create_publisher(TFMessage, topic, TF_QOS),
                                      node.create_publisher(TFMessage, topic, TF_QOS))
            static = node.create_publisher(TFMessage, topic + '_static', TF_STATIC_QOS)
            static.publish(static_map_odom(time.time_ns()))
        else:
            senders[topic] = PoseSender(
                node.create_publisher(PoseStamped, topic, qos_profile_sensor_data))
    deadline = time.monotonic() + 30.0
    while any(s.publisher.get_subscription_count() < 1 for s in senders.values()):
        if time.monotonic() > deadline:
            missing = [t for t, s in senders.items() if s.publisher.get_subscription_count() < 1]
            print(f'error no subscriber on {" ".join(missing)}', flush=True)
            return 1
        time.sleep(0.02)
    print('ready', flush=True)
    for line in iter(sys.stdin.readline, ''):
        words = line.split()
        if not words or words[0] == 'quit':
            break
        if words[0] == 'flood':
            send = senders[words[1]].start(words[4] if len(words) > 4 else 'steady')
            if words[2] == 'max':
                sent, elapsed = flood_max(send, float(words[3]))
            else:
                sent, elapsed = flood(send, float(words[2]), float(words[3]))
            print(f'done {sent} {elapsed:.6f}', flush=True)
    node.destroy_node()
    rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
