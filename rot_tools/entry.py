"""Console-script entries of rotation_node and rotation_client: clean exit on early signals.

Python's default SIGTERM kills the process (status −15) and its SIGINT raises
KeyboardInterrupt wherever the interpreter is. Importing NumPy and rclpy takes ~0.2 s; a
signal in that window must still end the node with status 0 and no traceback. So this module
imports nothing heavy (rot_tools/__init__ is lazy), installs handlers that exit with status
0, and only then imports the node; rclpy.init later installs its own handlers, which shut the
context down and let rotation_node.main return 0. rotation_client, a command, ends on
Ctrl-C with the shell's status for it, 130, at any moment and without a traceback.
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


def _interrupted(signum, frame):
    sys.exit(130)


def rotation_client(args=None):
    """Run rot_tools.rotation_client.main; Ctrl-C at any moment ends it with status 130."""
    signal.signal(signal.SIGINT, _interrupted)
    from rot_tools.rotation_client import main
    return main(args)
