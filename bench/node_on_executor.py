"""
rotation_node, unchanged, on an executor of choice: the evidence behind make_executor.

RotationNode spun by the node's own loop (``serve``) on:

- ``single``: rclpy's ``SingleThreadedExecutor``, the one rotation_node uses
  (``make_executor``);
- ``events``: rclpy's ``rclpy.experimental.EventsExecutor``;
- ``multi``: rclpy's ``MultiThreadedExecutor`` (2 threads), the node's services — its own
  and the parameter services — moved to a callback group of their own, so that a service
  call need not wait for the subscriptions' group.

bench_node.py and bench_overload.py start it with ``--executor NAME`` beside the node
itself.

Run: ``.venv/bin/python bench/node_on_executor.py --executor NAME [--ros-args ...]``;
SIGINT / SIGTERM end it.
"""

import argparse
import sys
import weakref

import rclpy
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import MultiThreadedExecutor
from rot_tools.ros import runtime
from rot_tools.ros.rotation_node import RotationNode
from rot_tools.ros.runtime import make_executor, serve


def events_executor(context=None):
    from rclpy.experimental import EventsExecutor
    return EventsExecutor(context=context)


def multi_threaded_node():
    """Return a RotationNode with every service in one callback group of its own."""
    node = RotationNode()
    services = MutuallyExclusiveCallbackGroup()
    for srv in node.services:
        srv.callback_group.entities.discard(weakref.ref(srv))  # (members: weak references)
        srv.callback_group = services
        services.add_entity(srv)
    return node


EXECUTORS = {
    'single': (RotationNode, make_executor),
    'events': (RotationNode, events_executor),
    'multi': (multi_threaded_node, lambda context=None: MultiThreadedExecutor(2)),
}


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--executor', choices=EXECUTORS, default='single')
    args, ros_args = parser.parse_known_args(argv)
    rclpy.init(args=[sys.argv[0], *ros_args])
    make_node, factory = EXECUTORS[args.executor]
    serve(make_node, factory)
    return 0


if __name__ == '__main__':
    runtime.exit_now(main())  # the node's own exit (no interpreter teardown)
