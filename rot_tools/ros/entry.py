"""
Console-script entries of rotation_node and rotation_client (setup.py's console_scripts).

A console script's first act is ``from rot_tools.ros.entry import rotation_node`` (or
rotation_client), so this module's first statements hold SIGINT and SIGTERM: a signal from
then on is kept in HELD, and the program ends as it ends on that signal (rotation_node:
status 0; rotation_client: 130 on SIGINT, SIGTERM's default on SIGTERM) once its module has
loaded — not with Python's KeyboardInterrupt traceback. rot_tools.ros.runtime goes on
holding them the same way (hold_signals) while the program's module, NumPy and rclpy load:
see rot_tools.ros.runtime.start.

Before this module runs, the interpreter starts (on the pip path twice: the ROS wheels'
bootstrap starts it again with the libraries' path set), then the console script loads
rot_tools' and rot_tools.ros' ``__init__`` (light: PEP 562) and this module the signal
module: a signal until then is Python's to handle (SIGTERM kills the process with status
−15, SIGINT raises KeyboardInterrupt). This module and rot_tools.ros.runtime import nothing
heavy, and neither imports the programs' modules by name.
"""

import signal

HELD = []
"""The signals that arrived before the program's own handlers were installed."""


def _hold(signum, frame):
    # (rot_tools.ros.runtime.hold_signals does the same; it cannot be imported yet)
    HELD.append(signum)


signal.signal(signal.SIGINT, _hold)
signal.signal(signal.SIGTERM, _hold)

from rot_tools.ros import runtime  # noqa: E402 - after the handlers, as the docstring says


def rotation_node(args=None):
    """Run rot_tools.ros.rotation_node.main as this process (rot_tools.ros.runtime.start)."""
    runtime.start('rot_tools.ros.rotation_node', args, held=HELD)


def rotation_client(args=None):
    """Run rot_tools.ros.rotation_client.main; Ctrl-C at any moment ends it with status 130."""
    return runtime.start_command('rot_tools.ros.rotation_client', args, held=HELD)
