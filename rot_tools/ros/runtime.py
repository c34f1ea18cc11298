"""
What rotation_node's main does around rclpy: its arguments, their errors, its loop.

- :func:`user_arguments`, :func:`home_remaps`: the command line outside ``--ros-args`` (so
  that ``--help`` and ``--version`` answer before anything ROS starts), and the remaps whose
  ``~`` the shell expanded.
- :func:`init_ros`, :func:`ros_argument_error`, :func:`fail`: bad ROS arguments (a missing
  or malformed ``--params-file``, a bad ``-p`` or ``-r``, an unknown ``--ros-args`` flag, an
  invalid node name or parameter value) end the program with exactly one line on stderr, the
  text of what rclpy raised, and exit status 2 — not rcl's log line and a traceback.
- :func:`help_rows`, :func:`default_text`: the pieces of ``--help``'s text.
- :func:`spin`: the node's loop on an executor rclpy ships.

Signals are rclpy's: rclpy.init installs its handlers, which shut the context down on SIGINT
and SIGTERM; the loop then ends, and the program returns its status.
"""

import os
import sys
import textwrap
import time
import traceback

import rclpy
from rclpy.exceptions import NameValidationException, ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.logging import get_logger_level, LoggingSeverity, set_logger_level

EXIT_USAGE = 2
"""Exit status of a program given bad arguments (ROS arguments included)."""

SPIN_TIMEOUT = 0.1
"""Seconds one spin_once waits at most: the longest a shutdown waits for the loop to notice."""


def fail(program, text, status=EXIT_USAGE):
    """Print ``program: text`` as one line on stderr and raise SystemExit(status)."""
    print(f'{program}: {text}', file=sys.stderr)
    raise SystemExit(status)


ROS_ARGUMENT_ERRORS = (RuntimeError, NameValidationException, ParameterException)
"""
What bad ROS arguments raise: rclpy.init for arguments rcl cannot parse (RuntimeError: rcl's
errors), and rclpy for a node that cannot be made from them: an invalid node name or
namespace (``-r __node:=``, ``-r __ns:=``), a parameter of the wrong type or an invalid value.
"""


def ros_argument_error(exc):
    """Return the text of ``exc`` (one of ROS_ARGUMENT_ERRORS) on one line."""
    return ' '.join(str(exc).split()) or type(exc).__name__


def user_arguments(argv):
    """
    Return the arguments of ``argv`` (program name first) outside its ROS arguments.

    ROS arguments run from each ``--ros-args`` to the next ``--`` or the end, as rcl reads
    them; unlike rclpy.utilities.remove_ros_args this does not parse them (a bad one is
    init_ros's to report), so a program can answer --help before anything ROS starts.
    """
    found, inside = [], False
    for arg in argv[1:]:
        if arg == '--ros-args':
            inside = True
        elif inside and arg == '--':
            inside = False
        elif not inside:
            found.append(arg)
    return found


def home_remaps(argv, home=None):
    """
    Return the remaps of ``argv`` (``-r`` / ``--remap`` FROM:=TO) whose FROM is in ``home``.

    An unquoted ``-r ~/imu:=/x`` reaches the program as ``-r /root/imu:=/x``: the shell
    expanded the ``~`` to the home directory (``home``, default the user's) and the remap
    names a topic nobody uses, silently.
    """
    home = (home or os.path.expanduser('~')).rstrip('/')
    found, inside = [], False
    for flag, value in zip(argv, list(argv[1:]) + [None]):
        if flag == '--ros-args':
            inside = True
        elif flag == '--':
            inside = False
        elif inside and flag in ('-r', '--remap') and value and home and (
                value.split(':=', 1)[0] + '/').startswith(home + '/'):
            found.append(value)
    return found


def _missing_params_files(args):
    """Return the ``--params-file`` arguments (after --ros-args) naming no readable file."""
    missing = []
    inside = False
    for flag, value in zip(args, list(args[1:]) + [None]):
        if flag == '--ros-args':
            inside = True
        elif flag == '--':
            inside = False
        elif inside and flag == '--params-file' and value is not None and not (
                os.path.isfile(value) and os.access(value, os.R_OK)):
            missing.append(value)
    return missing


def init_ros(program, args=None, **kwargs):
    """
    rclpy.init(args=args, **kwargs), or one line on stderr and SystemExit(2).

    For bad ROS arguments the line is ``program: bad ROS arguments:`` and the text of what
    rclpy.init raised; rcl's own log line about them ("Failed to parse global arguments") is
    not printed.
    ``args`` is the whole command line as rclpy.init takes it (sys.argv when None).
    """
    argv = sys.argv if args is None else args
    for path in _missing_params_files(argv):
        fail(program, f'--params-file {path}: no such readable file')
    level = get_logger_level('rcl')
    set_logger_level('rcl', LoggingSeverity.FATAL)
    try:
        rclpy.init(args=args, **kwargs)
    except ROS_ARGUMENT_ERRORS as exc:
        fail(program, 'bad ROS arguments: ' + ros_argument_error(exc))
    finally:
        if get_logger_level('rcl') == LoggingSeverity.FATAL:  # not set by --log-level
            set_logger_level('rcl', level)


def help_rows(rows, width=99):
    """Return --help's '  name  text' lines of (name, text) pairs, each text wrapped."""
    left = max(len(name) for name, _ in rows) + 4
    lines = []
    for name, text in rows:
        lines += textwrap.wrap(text, width, initial_indent=f'  {name:{left - 2}}',
                               subsequent_indent=' ' * left)
    return lines


def default_text(value):
    """Return a parameter's default as ``--help`` shows it (true/false for a bool)."""
    return ('true' if value else 'false') if isinstance(value, bool) else str(value)


def spin(node, executor):
    """
    Spin ``node`` on ``executor`` until the executor's context shuts down (a signal).

    The loop rclpy.spin runs, one spin_once of at most SPIN_TIMEOUT at a time, with a look at
    the context between two (rclpy.spin could miss a signal's shutdown and wait on). An
    exception that a callback raises — ours, or rclpy's own on a hostile request to a
    parameter service — is logged and the node serves on. It is logged SPIN_TIMEOUT later if
    the context is still up then: a SIGINT that lands inside rclpy's C++ (taking a message)
    comes out as that call's RuntimeError a moment before rclpy's handler shuts the context
    down, and is then the shutdown's, not a failure. KeyboardInterrupt (rclpy's SIGINT
    handler raises it after the shutdown) is raised.
    """
    executor.add_node(node)
    failure = None  # (traceback, time.monotonic()) of a callback's failure not yet logged
    while executor.context.ok():
        try:
            executor.spin_once(timeout_sec=SPIN_TIMEOUT)
        except ExternalShutdownException:
            return  # the context shut down while spin_once waited: the normal end
        except Exception:  # noqa: BLE001 - any callback's failure: log it, keep serving
            failure = failure or (traceback.format_exc(), time.monotonic())
        if failure is not None and time.monotonic() - failure[1] >= SPIN_TIMEOUT:
            if executor.context.ok():
                node.get_logger().error('a callback raised; the node keeps serving:\n'
                                        + failure[0], throttle_duration_sec=1.0)
            failure = None
