"""Console-script entry of rotation_node, light enough to catch a signal during start-up.

Python's default SIGTERM kills the process (status −15) and its SIGINT raises
KeyboardInterrupt wherever the interpreter is. Importing NumPy and rclpy takes ~0.2 s; a
signal in that window must still end the node with status 0 and no traceback. So this module
imports nothing heavy (rot_tools/__init__ is lazy), installs handlers that exit with status
0, and only then imports the node; rclpy.init later installs its own handlers, which shut the
context down and let rotation_node.main return 0.
"""

import signal
import sys


def _exit_cleanly(signum, frame):
    sys.exit(0)


def rotation_node(args=None):
    """Run rot_tools.rotation_node.main, stopping cleanly on a signal at any moment."""
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _exit_cleanly)
    from rot_tools.rotation_node import main
    return main(args)
