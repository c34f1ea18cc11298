"""
What one picture (~/markers + ~/screw_axis) costs rotation_node, next to an input's work.

In-process, no transport: a RotationNode's ~/pose callback is called on 1000 random poses
(unit quaternions, positions in [-2, 2]^3) with publish_markers off, then again with the
picture of every input drawn and published at once (what each input would cost without the
node's MARKER_RATE throttle). Best of --repeats passes; no subscriber is matched, so the
publishes serialise but send nothing. This is why the node throttles its pictures.

Run: ``.venv/bin/python bench/picture_cost.py``.
"""

import argparse
import math
import os
import time

import numpy as np


def poses(n, seed=3):
    """Return n random PoseStamped, serialised: rotation_node subscribes raw (the bytes)."""
    from geometry_msgs.msg import PoseStamped
    from rclpy.serialization import serialize_message
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        msg = PoseStamped()
        msg.header.frame_id = 'map'
        o, p = msg.pose.orientation, msg.pose.position
        o.x, o.y, o.z, o.w = q.tolist()
        p.x, p.y, p.z = rng.uniform(-2.0, 2.0, 3).tolist()
        out.append(serialize_message(msg))
    return out


def best_per_call(f, msgs, repeats):
    best = math.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for msg in msgs:
            f(msg)
        best = min(best, (time.perf_counter() - start) / len(msgs))
    return best


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--n', type=int, default=1000, help='poses (1000)')
    parser.add_argument('--repeats', type=int, default=5, help='passes, best taken (5)')
    args = parser.parse_args(argv)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    import rclpy
    from rclpy.parameter import Parameter
    from rot_tools.ros.rotation_node import MARKER_RATE, RotationNode

    rclpy.init()
    node = RotationNode('bench_picture_cost',
                        parameter_overrides=[Parameter('publish_markers', value=False)])
    try:
        source = node._sources[0]  # ~/pose
        msgs = poses(args.n)
        work = best_per_call(lambda msg: node._on_input(source, msg), msgs, args.repeats)
        node._settings = node._settings._replace(publish_markers=True)

        def with_picture(msg):
            node._on_input(source, msg)
            node._publish_picture()  # at once, as without the throttle
        both = best_per_call(with_picture, msgs, args.repeats)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    print(f'per input, best of {args.repeats} passes over {args.n} random poses:')
    print(f'  the work of an input, no picture:   {work * 1e6:7.0f} us')
    print(f'  the same with its picture drawn:    {both * 1e6:7.0f} us '
          f'(the picture: {(both - work) * 1e6:.0f} us, {(both - work) / work:.1f} x the work)')
    print(f'  throttled to {MARKER_RATE:g} pictures/s, they cost at most '
          f'{(both - work) * MARKER_RATE:.1%} of a core')


if __name__ == '__main__':
    main()
