"""Console-script entries of rotation_node and rotation_client: clean exit on early signals.

Python's default SIGTERM kills the process (status −15) and its SIGINT raises
KeyboardInterrupt wherever the interpreter is. Importing NumPy and rclpy takes ~0.2 s; a
signal in that window must still end the node with status 0 and no traceback. So this module
imports nothing heavy (rot_tools/__init__ is lazy), installs handlers that exit with status
0, and only then imports the node; rclpy.init later installs its own handlers, which shut the
context down and let rotation_node.main return 0. rotation_client, a command, ends on
Ctrl-C with the shell's status for it, 130, at any moment and without a traceback.

Once the node's main has returned, everything ROS is shut down and destroyed explicitly and
the process ends with os._exit: the interpreter's own teardown of the loaded extension
modules and of the DDS library took 0.2–1.6 s on a busy 2-core machine, and SPEC §3 wants
the node gone within a second of the signal, every time.
"""

import os
import signal
import sys


def _exit_cleanly(signum, frame):
    """Exit 0 at once, unless rclpy's own signal handlers are installed.

    rclpy.init installs handlers that shut the context down (the node's loop then ends and
    main returns) and then call this one. From then on raising SystemExit here would land
    in whatever runs at that moment — inside a callback, through the executor's C++.
    """
    rclpy_signals = sys.modules.get('rclpy.signals')
    if rclpy_signals is not None and (rclpy_signals.get_current_signal_handlers_options()
                                      != rclpy_signals.SignalHandlerOptions.NO):
        return
    sys.exit(0)


def rotation_node(args=None):
    """Run rot_tools.rotation_node.main, stopping cleanly on a signal at any moment."""
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _exit_cleanly)
    from rot_tools.rotation_node import main
    exit_now(main(args))


def exit_now(status):
    """End the process with ``status`` once the node's main has returned.

    Destroys the ROS context, flushes stdout and stderr, and skips the interpreter's
    teardown (see the module docstring).
    """
    for signum in (signal.SIGINT, signal.SIGTERM):  # (the EventsExecutor left them default)
        signal.signal(signum, _exit_cleanly)
    import rclpy
    context = rclpy.get_default_context()
    context.try_shutdown()
    context.destroy()  # the DDS participant leaves the graph now, not at a lease timeout
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


def _interrupted(signum, frame):
    sys.exit(130)


def rotation_client(args=None):
    """Run rot_tools.rotation_client.main; Ctrl-C at any moment ends it with status 130."""
    signal.signal(signal.SIGINT, _interrupted)
    from rot_tools.rotation_client import main
    return main(args)
