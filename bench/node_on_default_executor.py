"""rotation_node, unchanged, on rclpy's default executor: the evidence behind make_executor.

RotationNode spun by rotation_node.serve (the node's own loop) on rclpy's default
SingleThreadedExecutor instead of rotation_node.make_executor's. bench_node.py
--node-on-default measures it beside the node itself.

Run: ``.venv/bin/python bench/node_on_default_executor.py [--ros-args ...]``; SIGINT /
SIGTERM end it.
"""

import sys

import rclpy
from rclpy.executors import SingleThreadedExecutor

from rot_tools.rotation_node import RotationNode, serve


def main(args=None):
    rclpy.init(args=args)
    serve(RotationNode, SingleThreadedExecutor)
    return 0


if __name__ == '__main__':
    sys.exit(main())
