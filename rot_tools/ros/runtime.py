"""
The process around rot_tools' ROS programs: start, signals, executor, spin, exit, errors.

rotation_node.py is the Node and its ``main``; this module runs the process around it, and
knows nothing of that node (rotation_node imports this module, never the other way round):

- :func:`start` is how a ROS program of this package starts — its console script (through
  rot_tools.ros.entry) and ``python -m rot_tools.ros.rotation_node`` alike. Python's default
  SIGTERM kills the process (status −15) and its SIGINT raises KeyboardInterrupt wherever the
  interpreter is; importing NumPy and rclpy takes ~0.2 s. So :func:`start` holds the
  signals (:func:`hold_signals`) *before* it imports the program's module, ends the process
  with status 0 after the import if one came, then installs handlers that exit with status 0
  and runs ``main``, ending the process with :func:`exit_now`. rclpy.init later installs
  its own handlers, which shut the context down and let ``main`` return 0.
  :func:`start_command` is the same for a command (rotation_client): Ctrl-C at any moment
  ends it with the shell's status for it, 130, and no traceback.
- :func:`exit_now`: once ``main`` has returned, everything ROS is shut down and destroyed
  explicitly and the process ends with os._exit: the interpreter's own teardown of the
  loaded extension modules and of the DDS library took 0.2–1.6 s on a busy 2-core machine,
  and a node must be gone within a second of the signal, every time.
- :func:`make_executor`, :func:`guard_callbacks`, :func:`spin`, :func:`serve`: the executor
  the node runs on (rclpy's SingleThreadedExecutor), and its loop.
- :func:`init_ros`, :func:`ros_argument_error`, :func:`fail`: bad ROS arguments (a missing
  or malformed ``--params-file``, a bad ``-p`` or ``-r``, an invalid node name) end the
  program with exactly one line on stderr and exit status 2, not rcl's log line and a
  traceback.
- :func:`program_version`: the installed distribution's version, for ``--version``.
- :func:`use_fast_dds_profile`, :func:`give_large_blocks_back`: the node's middleware profile
  and C allocator, so that a burst of huge messages leaves no memory behind.

This module is light at import (os, re, signal, sys): NumPy and rclpy are imported inside
the functions that need them, so that :func:`start` runs before they load.
"""

import os
import re
import signal
import sys

EXIT_USAGE = 2
"""Exit status of a program given bad arguments (ROS arguments included)."""


# ---------------------------------------------------------------------------------------
# Start and exit


def _exit_cleanly(signum, frame):
    """
    Exit 0 at once, unless rclpy's own signal handlers are installed.

    rclpy.init installs handlers that shut the context down (the node's loop then ends and
    main returns) and then call this one. From then on raising SystemExit here would land
    in whatever runs at that moment — inside a callback, through the executor's C++.
    """
    # (rclpy.signals may be in sys.modules half imported: a signal while it loads)
    options = getattr(sys.modules.get('rclpy.signals'), 'get_current_signal_handlers_options',
                      None)
    if options is not None and options().name != 'NO':
        return
    sys.exit(0)


def _install_exit_handlers():
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _exit_cleanly)


def hold_signals(held=None):
    """
    From now on SIGINT and SIGTERM only append their number to list ``held``; return it.

    While a program's module loads, a handler that raises would raise inside NumPy's and
    rclpy's extension modules as they initialise, where C code may turn the exception into
    another: a SystemExit raised as NumPy's C extension imports datetime became "ImportError:
    Importing the numpy C-extensions failed" and a traceback. So start and start_command
    hold the signals until the import is done. (rot_tools.ros.entry holds them the same way
    before this module loads, and hands its list on.)
    """
    held = [] if held is None else held

    def hold(signum, frame):
        held.append(signum)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, hold)
    return held


def _load(module, held):
    """Import ``module`` (a name) with the signals held (hold_signals); return it."""
    hold_signals(held)
    import importlib
    return importlib.import_module(module)


def start(module, args=None, held=None):
    """
    Run ``module``'s ``main(args)`` as this process, stopping cleanly on a signal; no return.

    ``module`` is a module name (e.g. 'rot_tools.ros.rotation_node'). A signal before main
    runs — while the module loads (its signals held: hold_signals), or already in ``held``
    (the console script's, rot_tools.ros.entry.HELD) — ends the process with status 0 as
    soon as the import is done; from then on one ends main at once, with status 0, until
    rclpy's handlers take over. The process ends with main's status through exit_now (a
    SystemExit's code likewise).
    """
    held = [] if held is None else held
    try:
        program = _load(module, held)
        _install_exit_handlers()
        if held:
            exit_now(0)
        status = program.main(args)
    except SystemExit as exc:
        status = exc.code
    if not isinstance(status, int):
        if status is not None:
            print(status, file=sys.stderr)
        status = 0 if status is None else 1
    exit_now(status)


def _interrupted(signum, frame):
    sys.exit(130)


def start_command(module, args=None, held=None):
    """
    Return ``module``'s ``main(args)``; Ctrl-C at any moment ends it with status 130.

    A signal while the module loads, or in ``held`` (rot_tools.ros.entry.HELD), acts once
    the import is done: SIGINT ends the command with 130, SIGTERM as its default action does
    (status −15). Then SIGINT raises SystemExit(130) wherever main is; SIGTERM has its
    default action.
    """
    held = [] if held is None else held
    program = _load(module, held)
    signal.signal(signal.SIGINT, _interrupted)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if signal.SIGINT in held:
        sys.exit(130)
    if signal.SIGTERM in held:
        os.kill(os.getpid(), signal.SIGTERM)
    return program.main(args)


def exit_now(status):
    """
    End the process with ``status`` once a node's main has returned.

    Destroys rclpy's default context (if rclpy was loaded), flushes stdout and stderr, and
    skips the interpreter's teardown (see the module docstring).
    """
    _install_exit_handlers()  # (a signal during the teardown below: exit 0)
    if 'rclpy' in sys.modules:
        import rclpy
        context = rclpy.get_default_context()
        context.try_shutdown()
        context.destroy()  # the DDS participant leaves the graph now, not at a lease timeout
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


# ---------------------------------------------------------------------------------------
# Command-line and ROS-argument errors: one line, exit 2


def fail(program, text, status=EXIT_USAGE):
    """Print ``program: text`` as one line on stderr and raise SystemExit(status)."""
    print(f'{program}: {text}', file=sys.stderr)
    raise SystemExit(status)


# rcl's messages end in the C source locations of the failure (", at /src/x.c:271").
_C_LOCATION = r',? at [^,]*\.[ch](pp)?:\d+'
_RCL_PARSE = r"Couldn't parse (?P<what>.+?): '(?P<arg>.*)'\. Error: (?P<why>.*)"
_FORMS = {'-p': ' (the form is -p NAME:=VALUE)', '-r': ' (the form is -r FROM:=TO)'}


def ros_argument_error(exc):
    """
    Return one line saying what is wrong in the ROS arguments, or None.

    ``exc`` is an exception raised by rclpy.init (rcl could not parse a ``--params-file``, a
    ``-p`` or a ``-r``; an unknown ``--ros-args`` flag) or while a node was built from the
    arguments (an invalid node name or namespace from ``-r __node:=`` / ``__ns:=``, a
    parameter of the wrong type or an invalid value). None for any other exception.
    """
    from rclpy.exceptions import InvalidParameterValueException, NameValidationException
    from rclpy.exceptions import ParameterException
    # rcl's errors reach Python as RuntimeErrors of classes rclpy does not export: known by
    # their names.
    rcl_error = type(exc).__name__ if isinstance(exc, RuntimeError) else None
    if rcl_error == 'UnknownROSArgsError':
        unknown = re.findall(r"'([^']*)'", str(exc)) or [str(exc)]
        return 'unknown ROS argument ' + ', '.join(unknown) + ' (after --ros-args)'
    if rcl_error == 'RCLError':
        text = re.sub(_C_LOCATION, '', str(exc).replace('failed to initialize rcl: ', ''))
        parse = re.match(_RCL_PARSE, text.strip(), re.S)
        if parse is None:
            return ' '.join(text.split())
        arg, why = parse['arg'], ' '.join(parse['why'].split())
        form = _FORMS.get(arg.split(' ', 1)[0], '')
        return f"bad ROS argument '{arg}': not a valid {parse['what']}{form}: {why}"
    if isinstance(exc, InvalidParameterValueException):
        reason = re.search(r'Reason: (.*): [^:]*$', str(exc), re.S)
        return 'invalid parameter value: ' + (reason[1] if reason else str(exc))
    if isinstance(exc, ParameterException):  # its message ends in ": <parameter name>"
        return str(exc).rsplit(': ', 1)[0]
    if isinstance(exc, NameValidationException):
        first = str(exc).splitlines()[0].rstrip(':')  # then the name and a caret line
        return (f'{first} (names are built from the node name and namespace: '
                '-r __node:=NAME, -r __ns:=/NAMESPACE)')
    return None


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

    For bad ROS arguments (see ros_argument_error) the line is ``program: what is wrong``;
    rcl's own log line about them ("Failed to parse global arguments") is not printed.
    ``args`` is the whole command line as rclpy.init takes it (sys.argv when None).
    """
    import rclpy
    from rclpy.logging import get_logger_level, LoggingSeverity, set_logger_level
    argv = sys.argv if args is None else args
    for path in _missing_params_files(argv):
        fail(program, f'--params-file {path}: no such readable file')
    level = get_logger_level('rcl')
    set_logger_level('rcl', LoggingSeverity.FATAL)
    try:
        rclpy.init(args=args, **kwargs)
    except Exception as exc:  # noqa: BLE001 - every bad ROS argument is one line
        text = ros_argument_error(exc)
        if text is None:
            raise
        fail(program, text)
    finally:
        if get_logger_level('rcl') == LoggingSeverity.FATAL:  # not set by --log-level
            set_logger_level('rcl', level)


def program_version(program):
    """'program 0.1.0': the installed rot_tools distribution's version (setup.py's)."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return f'{program} {version("rot_tools")}'
    except PackageNotFoundError:
        return f'{program} (rot_tools not installed: no distribution metadata)'


# ---------------------------------------------------------------------------------------
# The middleware's profile

FAST_DDS_PROFILE = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                'fastdds_profile.xml')
"""
rotation_node's Fast DDS profile: the builtin transports with a deeper shared-memory port, and
readers whose history gives a sample's memory back once it is taken.
"""

_USER_FAST_DDS_SETTINGS = ('FASTRTPS_DEFAULT_PROFILES_FILE', 'FASTDDS_DEFAULT_PROFILES_FILE',
                           'FASTDDS_BUILTIN_TRANSPORTS', 'SKIP_DEFAULT_XML',
                           'RMW_FASTRTPS_USE_QOS_FROM_XML', 'RMW_FASTRTPS_PUBLICATION_MODE')
_USER_FAST_DDS_FILES = ('DEFAULT_FASTRTPS_PROFILES.xml', 'DEFAULT_FASTDDS_PROFILES.xml')


def use_fast_dds_profile(environ=os.environ):
    """
    Point Fast DDS at FAST_DDS_PROFILE, unless the user configures the middleware; return it.

    Only for Fast DDS (RMW_IMPLEMENTATION unset, ROS 2's default, or rmw_fastrtps_*), and
    only when none of the middleware's own ways of being configured is in use: Fast DDS's
    profile variables, FASTDDS_BUILTIN_TRANSPORTS, SKIP_DEFAULT_XML, a
    DEFAULT_FASTRTPS_PROFILES.xml in the working directory, rmw_fastrtps's
    RMW_FASTRTPS_USE_QOS_FROM_XML or RMW_FASTRTPS_PUBLICATION_MODE. Sets
    RMW_FASTRTPS_USE_QOS_FROM_XML=1 too: without it rmw_fastrtps gives every reader a history
    that keeps each slot at the largest sample it ever held (a burst of 10 MB TFMessages
    then stays in the node's memory); the profile's writers and readers are otherwise as
    rmw_fastrtps sets them. Returns the profile set, or None. Call before rclpy.init
    (Fast DDS reads its profiles once, as the first participant is made).
    """
    rmw = environ.get('RMW_IMPLEMENTATION', '') or 'rmw_fastrtps_cpp'
    if (not rmw.startswith('rmw_fastrtps_') or not os.path.isfile(FAST_DDS_PROFILE)
            or any(name in environ for name in _USER_FAST_DDS_SETTINGS)
            or any(os.path.exists(name) for name in _USER_FAST_DDS_FILES)):
        return None
    environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = FAST_DDS_PROFILE
    environ['RMW_FASTRTPS_USE_QOS_FROM_XML'] = '1'
    return FAST_DDS_PROFILE


M_MMAP_THRESHOLD = -3
"""glibc's mallopt parameter: the size from which a block gets a memory mapping of its own."""
LARGE_BLOCK = 1 << 20
"""Bytes from which the node's blocks are mapped on their own (given back when freed)."""


def give_large_blocks_back():
    """
    Fix glibc's malloc threshold for mapping a block on its own at LARGE_BLOCK bytes.

    By default glibc raises that threshold to the largest block freed so far (up to 32 MB):
    after one 9 MB message has come and gone, later ones come from the heap, and a burst of
    them freed out of order stays in the process (after twenty 9 MB TFMessages, 35–120 MB
    kept in about one run of fifteen). A fixed threshold gives each back to the system as it
    is freed. Nothing is done under a C library without mallopt (musl, macOS).
    """
    import ctypes
    mallopt = getattr(ctypes.CDLL(None), 'mallopt', None)
    if mallopt is not None:
        mallopt(M_MMAP_THRESHOLD, LARGE_BLOCK)


# ---------------------------------------------------------------------------------------
# Executor and spin loop

SPIN_TIMEOUT = 0.1
"""Seconds one spin_once waits at most: the longest a shutdown waits for the loop to notice."""


def make_executor(context=None):
    """
    Return the executor rotation_node runs on: rclpy's SingleThreadedExecutor.

    Chosen on measurement (bench/bench_overload.py, bench/bench_node.py): it waits only in
    the middleware, whose keep-last queues bound what a flood costs (lost inputs, never
    memory), and serves every ready service between two messages of each input. rclpy's
    EventsExecutor queued an event per arriving message without bound (RSS +140–160 MB a
    minute under a flood beyond the node's pace, kept afterwards; service calls waited
    behind the queue for up to 16 s). test_node_executor.py proves signals, services under
    a flood, floods of bad input and bounded memory on it.
    """
    from rclpy.executors import SingleThreadedExecutor
    return SingleThreadedExecutor(context=context)


def _guarded(callback, node, what, service=False):
    """
    Wrap ``callback``: an exception it raises is logged (with its traceback) instead.

    A subscription or timer callback then returns None; a service callback (``service``)
    returns the response it was given, unfilled, so that the client gets a reply. Once the
    context is shut down (a signal: rclpy shuts it down from its handler, while a callback
    may be publishing) a failure is the shutdown's and is not logged. The wrapper has the
    callback's signature (rclpy inspects it).
    """
    import traceback
    from functools import wraps

    @wraps(callback)
    def guarded(*args):
        try:
            return callback(*args)
        except Exception:  # noqa: BLE001 - any bug: log it, keep serving
            if node.context.ok():
                node.get_logger().error(f'{what} callback raised; the node keeps serving:\n'
                                        + traceback.format_exc(), throttle_duration_sec=1.0)
            return args[-1] if service else None
    return guarded


def guard_callbacks(node):
    """
    Wrap every subscription, timer and service callback of ``node`` in _guarded.

    A callback that raises is then logged and the node keeps serving, on any executor (the
    executors would otherwise end the spin; the EventsExecutor would also lose the
    subscription's other queued messages).
    """
    for sub in node.subscriptions:
        sub.callback = _guarded(sub.callback, node, f'subscription {sub.topic_name}')
    for timer in node.timers:
        timer.callback = _guarded(timer.callback, node, 'timer')
    for srv in node.services:
        srv.callback = _guarded(srv.callback, node, f'service {srv.srv_name}', service=True)


def spin(node, executor):
    """
    Spin ``node`` on ``executor`` until the context shuts down (a signal), then stop it.

    The node's callbacks are guarded first (guard_callbacks). rclpy.init installs handlers
    that shut the context down on SIGINT and SIGTERM; the loop then ends within one
    SPIN_TIMEOUT (rclpy.spin could hang on a signal), and an ExternalShutdownException
    raised by spin_once meanwhile is the normal end.
    """
    import rclpy
    from rclpy.executors import ExternalShutdownException
    guard_callbacks(node)
    executor.add_node(node)
    try:
        while rclpy.ok(context=executor.context):
            executor.spin_once(timeout_sec=SPIN_TIMEOUT)
    except ExternalShutdownException:
        pass  # the context shut down during spin_once: the normal end
    finally:
        executor.shutdown()


def serve(make_node, executor_factory=make_executor):
    """
    Build a node, spin it until a signal, destroy it and shut rclpy down.

    The node is make_node(), the executor executor_factory(); rclpy.init is the caller's.
    A signal during the build is a normal stop; any other exception of the build (an
    invalid parameter) is raised after the clean-up. The executor is made first, while the
    context was running an instant before: an executor made on a context a signal has shut
    down fails half built (rclpy then prints 'Exception ignored in Executor.__del__').
    Warnings of the build are shown once it is over, unless a signal shut the context down
    meanwhile: they are then the shutdown's (rclpy's node, shut down as it is made, warns
    "Failed to fini rosout publisher: rcl node implementation is invalid").
    """
    import gc
    import warnings
    import rclpy
    from rclpy.executors import ExternalShutdownException
    node = None
    try:
        if not rclpy.ok():
            return  # a signal during rclpy.init: a normal stop
        executor = executor_factory()
        try:
            with warnings.catch_warnings(record=True) as warned:
                node = make_node()
        finally:
            for w in warned if rclpy.ok() else ():
                warnings.showwarning(w.message, w.category, w.filename, w.lineno, w.file,
                                     w.line)
        # What exists now (modules, the node) lives as long as the process: left out of
        # the collector's full passes, which otherwise stall a message by ~15 ms every few
        # seconds under load (the tail of the latency).
        gc.freeze()
        spin(node, executor)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except Exception:
        if rclpy.ok():
            raise
        # A signal shut the context down while the node was being built: a normal stop.
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
