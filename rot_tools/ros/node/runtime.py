"""
What rotation_node's main does around rclpy: its command line and its errors.

``--help`` and ``--version`` answer before anything ROS starts (:func:`user_arguments`); bad
ROS arguments end the program with one line on stderr and exit status 2 (:func:`init_ros`,
:func:`fail`); remaps whose ``~`` the shell expanded and the parameter overrides given are
found for the node's warnings (:func:`home_remaps`, :func:`override_names`).
"""

import os
import sys
import textwrap

import rclpy
from rclpy.exceptions import NameValidationException, ParameterException
import yaml

EXIT_USAGE = 2
"""Exit status of a program given bad arguments (ROS arguments included)."""

ROS_ARGUMENT_ERRORS = (RuntimeError, NameValidationException, ParameterException)
"""
What bad ROS arguments raise: rclpy.init for arguments rcl cannot parse (RuntimeError: rcl's
errors), and rclpy for a node that cannot be made from them: an invalid node name or
namespace (``-r __node:=``, ``-r __ns:=``), a parameter of the wrong type or an invalid value.
"""


def fail(program, text, status=EXIT_USAGE):
    """Print ``program: text`` as one line on stderr and raise SystemExit(status)."""
    print(f'{program}: {text}', file=sys.stderr)
    raise SystemExit(status)


def ros_argument_error(exc):
    """Return the text of ``exc`` (one of ROS_ARGUMENT_ERRORS) on one line."""
    return ' '.join(str(exc).split()) or type(exc).__name__


def _split(argv):
    """Return (arguments outside --ros-args, (flag, next argument) pairs inside)."""
    outside, inside, within = [], [], False
    args = list(argv[1:])
    for k, arg in enumerate(args):
        if arg == '--ros-args':
            within = True
        elif within and arg == '--':
            within = False
        elif within:
            inside.append((arg, args[k + 1] if k + 1 < len(args) else None))
        else:
            outside.append(arg)
    return outside, inside


def user_arguments(argv):
    """
    Return the arguments of ``argv`` (program name first) outside its ROS arguments.

    ROS arguments run from each ``--ros-args`` to the next ``--`` or the end, as rcl reads
    them; they are not parsed here (a bad one is init_ros's to report).
    """
    return _split(argv)[0]


def home_remaps(argv, home=None):
    """
    Return the remaps of ``argv`` (``-r`` / ``--remap`` FROM:=TO) whose FROM is in ``home``.

    An unquoted ``-r ~/imu:=/x`` reaches the program as ``-r /root/imu:=/x``: the shell
    expanded the ``~`` to the home directory (``home``, default the user's).
    """
    home = (home or os.path.expanduser('~')).rstrip('/')
    return [value for flag, value in _split(argv)[1]
            if flag in ('-r', '--remap') and value and home
            and (value.split(':=', 1)[0] + '/').startswith(home + '/')]


def override_names(argv, node_name):
    """
    Return the names of the parameters ``argv`` sets for node ``node_name`` (fully qualified).

    ``-p NAME:=VALUE`` and the ``ros__parameters`` of a ``--params-file`` under ``/**``, the
    node's name or its fully qualified name.
    """
    names = []
    for flag, value in _split(argv)[1]:
        if flag in ('-p', '--param') and value and ':=' in value:
            names.append(value.split(':=', 1)[0])
        elif flag == '--params-file' and value:
            with open(value) as file:
                document = yaml.safe_load(file) or {}
            for key in ('/**', node_name, node_name.lstrip('/'), node_name.rsplit('/', 1)[-1]):
                section = document.get(key)
                if isinstance(section, dict):
                    names += [name for name in section.get('ros__parameters') or {}
                              if name not in names]
    return names


def init_ros(program, args=None, **kwargs):
    """
    rclpy.init(args=args, **kwargs), or one line on stderr and SystemExit(2).

    For bad ROS arguments the line is ``program: bad ROS arguments:`` and the text of what
    rclpy.init raised. ``args`` is the whole command line (sys.argv when None).
    """
    argv = sys.argv if args is None else args
    for flag, value in _split(argv)[1]:
        if flag == '--params-file' and value is not None and not (
                os.path.isfile(value) and os.access(value, os.R_OK)):
            fail(program, f'--params-file {value}: no such readable file')
    try:
        rclpy.init(args=args, **kwargs)
    except ROS_ARGUMENT_ERRORS as exc:
        fail(program, 'bad ROS arguments: ' + ros_argument_error(exc))


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
