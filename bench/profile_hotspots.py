"""
Where the time goes: cProfile of rot_tools' single-call paths and of the node's callback.

Not a ratio benchmark: a tool for whoever optimises rot_tools. It prints

1. for each public conversion called on one item, the time per call and the functions with
   the most own time (cProfile, tottime), so the Python overhead around the formula shows;
2. the in-process cost of rotation_node's ``~/pose`` callback against usual_node.py's (scipy
   per message) and relay_node.py's (constant outputs): the same message object, each
   subscription's callback called directly, as the executor calls it, no DDS transport,
   publishing to topics nobody subscribes; and the node's callback's cProfile.

Run: ``.venv/bin/python bench/profile_hotspots.py [--top N] [--skip-node | --skip-math]``.
"""

import argparse
import cProfile
from functools import partial
import io
import os
import pstats
import sys
import timeit

import numpy as np
import rot_tools as rt
from rot_tools.core.decomposition import decompose

HERE = os.path.dirname(os.path.abspath(__file__))


def profile_calls(label, fn, number, top, sort='tottime'):
    """Time fn() and print its cProfile (sorted by ``sort``), restricted to the top entries."""
    fn()
    per = min(timeit.repeat(fn, number=number, repeat=5)) / number
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(number):
        fn()
    prof.disable()
    out = io.StringIO()
    stats = pstats.Stats(prof, stream=out).strip_dirs().sort_stats(sort)
    stats.print_stats(top)
    body = out.getvalue()
    body = body[body.find('   ncalls'):].rstrip()
    print(f'\n== {label}: {per * 1e6:.2f} us per call (without the profiler); '
          f'profile by {sort}')
    print(body)


def math_paths(top):
    a = np.array([0.3, -0.4, 1.2])
    R = rt.euler_to_matrix(a, 'ZYX')
    v = rt.matrix_to_rotvec(R)
    axis, angle = rt.matrix_to_axis_angle(R)
    b = np.array([0.4, -1.0, 2.5])
    cases = [
        ("euler_to_matrix(a, 'ZYX')", lambda: rt.euler_to_matrix(a, 'ZYX')),
        ("matrix_to_euler(R, 'ZYX')", lambda: rt.matrix_to_euler(R, 'ZYX')),
        ('matrix_to_rotvec(R)', lambda: rt.matrix_to_rotvec(R)),
        ('rotvec_to_matrix(v)', lambda: rt.rotvec_to_matrix(v)),
        ('axis_angle_to_matrix(axis, angle)', lambda: rt.axis_angle_to_matrix(axis, angle)),
        ('validate_rotation(R)', lambda: rt.validate_rotation(R)),
        ('screw_log(R, b)', lambda: rt.screw_log(R, b)),
        ('screw_from_transform(R, b, check=False)',
         lambda: rt.screw_from_transform(R, b, check=False)),
        ("decompose(R, b, 'ZYX') (the node's numbers for one input)",
         lambda: decompose(R, b, 'ZYX')),
    ]
    for label, fn in cases:
        profile_calls(label, fn, 20000, top)


def _pose_callback(node):
    """Return the callback of ``node``'s ~/pose subscription, as the executor calls it."""
    return next(sub.callback for sub in node.subscriptions if sub.topic_name.endswith('/pose'))


def node_callback(top):
    os.environ.setdefault('ROS_DOMAIN_ID', str(1 + (os.getpid() * 11 + 5) % 101))
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    import rclpy
    from geometry_msgs.msg import PoseStamped
    from rclpy.parameter import Parameter
    from rot_tools.ros.node.rotation_node import RotationNode
    sys.path.insert(0, HERE)
    from relay_node import RelayNode
    from usual_node import UsualNode

    rclpy.init()
    try:
        others = {'usual way': UsualNode('profile_usual'), 'relay': RelayNode('profile_relay')}
        nodes = {markers: RotationNode(f'profile_rot_tools_{markers}', parameter_overrides=[
            Parameter('publish_markers', value=markers)]) for markers in (False, True)}
        msg = PoseStamped()
        msg.header.frame_id = 'world'
        q = np.array([0.2, -0.4, 0.5, 0.74])
        q /= np.linalg.norm(q)
        o = msg.pose.orientation
        o.x, o.y, o.z, o.w = (float(c) for c in q)
        msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = 0.4, -1.0, 2.5
        candidates = {'rot_tools, markers off': partial(_pose_callback(nodes[False]), msg),
                      'rot_tools, markers on': partial(_pose_callback(nodes[True]), msg),
                      **{name: partial(_pose_callback(node), msg)
                         for name, node in others.items()}}
        for cb in candidates.values():
            for _ in range(100):  # warm (caches, first calls of NumPy, scipy and rclpy)
                cb()
        times = {}
        for _ in range(5):  # interleaved
            for name, cb in candidates.items():
                t = min(timeit.repeat(cb, number=2000, repeat=1)) / 2000
                times.setdefault(name, []).append(t)
        relay_us = min(times['relay']) * 1e6
        print('\n== ~/pose callback in-process (no subscribers, no transport; the pictures '
              'are drawn on a timer, not called here)')
        for name in candidates:
            us = min(times[name]) * 1e6
            print(f'   {name:24s} {us:6.1f} us ({us / relay_us:.2f}x the relay, '
                  f'{us - relay_us:+.1f} us)')
        profile_calls('rotation_node ~/pose callback, markers off',
                      candidates['rot_tools, markers off'], 5000, 2 * top, sort='cumulative')
        for node in [*nodes.values(), *others.values()]:
            node.destroy_node()
    finally:
        rclpy.try_shutdown()


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--top', type=int, default=10, help='entries per profile (10)')
    parser.add_argument('--skip-node', action='store_true', help='math paths only')
    parser.add_argument('--skip-math', action='store_true', help='the node callbacks only')
    args = parser.parse_args(argv)
    if not args.skip_math:
        math_paths(args.top)
    if not args.skip_node:
        node_callback(args.top)


if __name__ == '__main__':
    main()
