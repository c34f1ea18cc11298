"""
What one picture (~/markers + ~/screw_axis) costs rotation_node, next to an input's work.

In-process, no transport: a RotationNode's ``~/pose`` subscription callback is called, as the
executor calls it, on 1000 random PoseStamped (unit quaternions, positions in [-2, 2]^3) with
publish_markers off; then, with publish_markers on, each input is followed by a call of every
timer callback of the node (the pictures are drawn on a timer), so that every input's picture
is drawn and published at once (what each input would cost without the node's limited
picture rate). Best of --repeats passes; no subscriber is matched, so the publishes convert
but send nothing. This is why the node limits its pictures' rate.

Run: ``.venv/bin/python bench/picture_cost.py``.
"""

import argparse
import math
import os
import time

import numpy as np


def poses(n, seed=3):
    """Return n random PoseStamped message objects."""
    from geometry_msgs.msg import PoseStamped
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
        out.append(msg)
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
    from rot_tools.ros.node.pictures import MARKER_RATE
    from rot_tools.ros.node.rotation_node import RotationNode

    rclpy.init()
    nodes = {markers: RotationNode(f'bench_picture_cost_{markers}', parameter_overrides=[
        Parameter('publish_markers', value=markers)]) for markers in (False, True)}
    try:
        msgs = poses(args.n)
        on_pose = {markers: next(sub.callback for sub in node.subscriptions
                                 if sub.topic_name.endswith('/pose'))
                   for markers, node in nodes.items()}
        timers = [timer.callback for timer in nodes[True].timers]
        work = best_per_call(on_pose[False], msgs, args.repeats)

        def with_picture(msg):
            on_pose[True](msg)
            for timer in timers:  # at once, as without the limited rate
                timer()
        both = best_per_call(with_picture, msgs, args.repeats)
    finally:
        for node in nodes.values():
            node.destroy_node()
        rclpy.try_shutdown()
    print(f'per input, best of {args.repeats} passes over {args.n} random poses:')
    print(f'  the work of an input, no picture:   {work * 1e6:7.0f} us')
    print(f'  the same with its picture drawn:    {both * 1e6:7.0f} us '
          f'(the picture: {(both - work) * 1e6:.0f} us, {(both - work) / work:.1f} x the work)')
    print(f'  at most {MARKER_RATE:g} pictures/s, they cost at most '
          f'{(both - work) * MARKER_RATE:.1%} of a core')


if __name__ == '__main__':
    main()
