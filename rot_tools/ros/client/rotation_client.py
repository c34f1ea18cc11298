"""
rotation_client: send one input to a running rotation_node and print what it answered.

One function per command (COMMANDS), run by :func:`run_command` in an rclpy context of its
own; doc/client.md is the manual, ``rotation_client --help`` the summary.
"""

from collections import deque
import math
import os
import re
import signal
import sys
import time

from rot_tools.io import interface
from rot_tools.io.arguments import install_hint
from rot_tools.io.report import to_json, to_yaml, transform_report
from rot_tools.ros.client import message_data
from rot_tools.ros.client.arguments import INPUTS, parse_args, PROG, quoted, shortened
from rot_tools.ros.client.arguments import without_ros_args
from rot_tools.ros.client.session import BadInput, Client, describe_data, Refused, Unreachable
import yaml


def _input_command(client, args):
    """Send one input message (euler, pose, odometry, ...); return the answer's report."""
    parameters = client.parameters(['euler_sequence', 'angle_unit', 'publish_markers'])
    msg, sent = message_data.input_message(args, parameters)
    msg.header.frame_id = args.frame
    topic, (sec, nanosec), answer = client.send(args.command, msg,
                                                parameters['publish_markers'], args.topic,
                                                getattr(args, 'cov', None) is not None)
    return {'node': client.target,
            'input': {'topic': topic, 'type': args.row.type_name,
                      'frame_id': args.frame, 'stamp': {'sec': sec, 'nanosec': nanosec},
                      **sent},
            'answer': message_data.answer_data(answer, parameters)}


def _describe_command(client, args):
    response = client.describe()
    if not response.success:
        note = describe_data(response).get('note', response.message)
        raise Unreachable(f'{client.topic("describe")}: {" ".join(str(note).split())}')
    return yaml.safe_load(response.message) if args.json else response.message


def _screw_path_command(client, args):
    from nav_msgs.srv import GetPlan
    request = GetPlan.Request(tolerance=args.tolerance)
    for pose, values in ((request.start, args.numbers[:7]), (request.goal, args.numbers[7:])):
        pose.header.frame_id = args.frame
        pose.header.stamp = client.node.get_clock().now().to_msg()
        message_data.set_pose(pose.pose, values)
    before = client.refusal_counts()
    plan = client.call(GetPlan, 'screw_path', request).plan
    if not plan.poses:
        stamp = request.start.header.stamp
        refused = client.refused(before, client.topic('screw_path'),
                                 {(stamp.sec, stamp.nanosec)})
        raise Refused(f'node {client.target} refused the screw_path request: '
                      + (refused or 'an empty path'))
    return {'node': client.target, 'service': client.topic('screw_path'),
            'frame_id': plan.header.frame_id,
            'poses': [message_data.pose_data(p.pose) for p in plan.poses]}


def _tf_report(follower, header, R, b, args):
    stamp = header.stamp
    return {'reference_frame': follower.reference, 'body_frame': follower.body,
            'chain': follower.tree.chain(follower.reference, follower.body),
            'stamp': {'sec': stamp.sec, 'nanosec': stamp.nanosec},
            **transform_report(R, b, args.seq, args.deg)}


def _print_document(data, args):
    """Print one document of a stream at once: YAML after '---', or JSON with --json."""
    if args.json:
        write(to_json(data), json_text=True)
    else:
        write('---\n' + to_yaml(data))
    flush()


def _tf_command(client, args):
    """tf: print BODY in REFERENCE from /tf and /tf_static, once or once a second."""
    from rot_tools.ros import tf_input  # tf2_msgs: only this command needs it
    latest = []

    def keep(header, R, b):
        latest[:] = [(header, R, b)]
    follower = tf_input.TfFollower(client.node, keep, lambda topic, reason, text: None)
    try:
        follower.follow(args.reference, args.body)
    except RuntimeError as exc:  # no tf2_msgs
        raise Unreachable(str(exc)) from None
    if not client.spin_until(lambda: latest, args.timeout):
        raise Unreachable(follower.why_not(args.timeout))
    while True:
        report = _tf_report(follower, *latest[0], args)
        if args.once:
            return report
        _print_document(report, args)
        due = time.monotonic() + 1.0
        client.spin_until(lambda: time.monotonic() >= due, 1.0)


def _tf_demo_command(client, args):
    """tf-demo: publish the demo tree until Ctrl-C or --duration; nothing to print after."""
    from rot_tools.ros import tf_input
    from rot_tools.ros.client import tf_demo
    missing = tf_input.tf2_msgs_missing()
    if missing:
        raise Unreachable(missing)
    demo = tf_demo.TfDemo(client.node)
    try:
        until = 'until Ctrl-C' if args.duration is None else f'for {args.duration:g} s'
        write(f'publishing {tf_demo.frames()} on {demo.tf.topic_name} and '
              f'{demo.tf_static.topic_name} {until}\n')
        flush()
        end = math.inf if args.duration is None else time.monotonic() + args.duration
        while time.monotonic() < end:
            client.spin_until(lambda: time.monotonic() >= end, 1.0)
    finally:
        demo.close()
    return None


def _echo_command(client, args):
    """
    echo: print each message of the node's output until Ctrl-C, --once or --count N.

    The subscription is made first, so that nothing published once it has matched is missed;
    a topic of another type (``--topic``) is then listened to with the type it has.
    """
    from rclpy.qos import QoSProfile
    from rot_tools.ros.message_types import message_class
    row = interface.output_named(args.output)
    received = deque()
    qos = QoSProfile(depth=100)
    sub = client.subscribe(message_class(row.type_name), args.topic or client.topic(row.name),
                           received.append, qos)
    parameters = client.parameters(['euler_sequence', 'angle_unit'])

    topic = sub.topic_name  # remapped

    def other_types():
        return sorted({info.topic_type for info in
                       client.node.get_publishers_info_by_topic(topic)} - {row.type_name})
    if not client.spin_until(lambda: sub.get_publisher_count() > 0 or other_types(),
                             args.timeout):
        raise Unreachable(client.missing(f'publisher on {topic}'))
    if not sub.get_publisher_count():
        client.unsubscribe(sub)
        client.subscribe(message_class(other_types()[0]), topic, received.append, qos)
    left = 1 if args.once else args.count or math.inf
    while left > 0:
        client.spin_until(lambda: received, 1.0)
        while received and left > 0:
            _print_document(message_data.echo_data(received.popleft(), row, parameters),
                            args)
            left -= 1
    return None


def _diagnostics_command(client, args):
    """diagnostics: print each status on /diagnostics as it arrives, until Ctrl-C or --once."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.qos import QoSProfile
    received = deque()
    sub = client.subscribe(DiagnosticArray, args.topic, received.append, QoSProfile(depth=100))
    if not client.spin_until(lambda: received, args.timeout):
        domain = os.environ.get('ROS_DOMAIN_ID') or '0'
        raise Unreachable(f'nothing on {sub.topic_name} within {args.timeout:g} s' + (
            '' if sub.get_publisher_count() else
            f' (no publisher: is rotation_node running, with ROS_DOMAIN_ID {domain}?)'))
    while True:
        while received:
            statuses = received.popleft()
            for status in statuses.status:
                stamp = statuses.header.stamp
                _print_document(message_data.status_data(status, stamp), args)
            if args.once:
                return None
        client.spin_until(lambda: received, 1.0)


def _set_command(client, args):
    """set: set one parameter as the node declares it; its answer, Refused or Unreachable."""
    from rcl_interfaces.msg import Parameter, ParameterType
    from rot_tools.ros.client import param
    kind = client.parameter_type(args.name)
    if kind in (None, ParameterType.PARAMETER_NOT_SET):
        raise Unreachable(f'node {client.target} has no parameter {quoted(args.name)}')
    try:
        value = param.typed_value(kind, args.value)
    except param.DoesNotFit as exc:
        raise BadInput(param.refusal(args.name, client.target, kind, args.value,
                                     *exc.args)) from None
    result = client.set_parameter(Parameter(name=args.name, value=value))
    shown = f'{args.name} = {param.shown(value)}'
    if not result.successful:
        raise Unreachable(shortened(f'node {client.target} refused {shown}: '
                                    + ' '.join(result.reason.split()), args.value))
    return f'node {client.target}: {shown}\n'


def _param_command(client, args):
    """Print a parameter (param get NAME) or their names (param list), as ros2 param does."""
    from rcl_interfaces.msg import ParameterType
    from rot_tools.ros.client import param
    if args.param_command == 'get':
        values = client.parameter_values([args.name])  # none, or NOT_SET: not declared
        if not values or values[0].type == ParameterType.PARAMETER_NOT_SET:
            raise Unreachable(f'node {client.target} has no parameter {quoted(args.name)}')
        (value,) = values
        python = param.python_value(value)
        if args.json:
            return {'name': args.name, 'type': param.TYPE_NAMES[value.type],
                    'value': python}
        return f'{python}\n' if args.hide_type else param.get_line(value) + '\n'
    names = client.parameter_names()
    types = client.parameter_types(names) if args.param_type else None
    if args.json:
        return ({name: param.TYPE_NAMES.get(types[name], 'not set')
                 for name in sorted(names)} if types else sorted(names))
    return ''.join(line + '\n' for line in param.list_lines(names, types))


def _play_command(client, args):
    """play: publish a bag's messages on their topics at their recorded times; its summary."""
    from rot_tools.io import bag_read
    missing = bag_read.rosbags_missing()
    if missing:
        raise Unreachable(f"play needs the rosbags library ({missing} is missing), the 'bag' "
                          f"extra: {install_hint('bag')}")
    from rot_tools.ros.client import bag_player
    try:
        with bag_read.open_bag(args.bag) as reader:
            try:
                played, skipped = bag_player.topics(reader, args.topics)
            except KeyError as exc:
                names = sorted({c.topic for c in reader.connections})
                raise BadInput(shortened(f'{args.bag} has no topic {exc.args[0]}: its topics '
                                         'are ' + ', '.join(names), exc.args[0])) from None
            if not played:
                raise BadInput(f'{args.bag}: nothing to play: ' + '; '.join(
                    f'{s.topic} ({s.msgtype}: {s.why})' for s in skipped))
            player = bag_player.Player(client.publisher, client.spin_until, played)
            write(''.join(line + '\n' for line in player.plan(skipped)))
            flush()
            if len(player.wait_for_subscribers(args.timeout)) == len(played):
                raise Unreachable(player.nobody_listens(args.timeout, client.target,
                                                        client.found()))
            start, stop = (None if seconds is None
                           else reader.start_time + int(round(seconds * 1e9)) + after
                           for seconds, after in ((args.start, 0), (args.end, 1)))
            result = player.play(reader, args.rate, start, stop)
    except bag_read.BagError as exc:
        raise BadInput(str(exc)) from None
    return bag_player.summary(args.bag, result, args.rate) + '\n'


COMMANDS = {**dict.fromkeys(INPUTS, _input_command),
            'describe': _describe_command, 'screw-path': _screw_path_command,
            'tf': _tf_command, 'tf-demo': _tf_demo_command, 'echo': _echo_command,
            'diagnostics': _diagnostics_command,
            'set': _set_command, 'param': _param_command, 'play': _play_command}
"""What runs each command: every input of the node is sent by _input_command."""


class StdoutFailed(Exception):
    """Stdout could not be written: its reader went away (BrokenPipeError) or a full disk."""


def write(text, json_text=False):
    r"""
    Print ``text`` on stdout, in its encoding even when that is not UTF-8.

    Characters it cannot encode are escaped as YAML or JSON read them back: the report's
    writers put every non-ASCII character in a double-quoted string, where YAML reads
    Python's backslash escapes, JSON \uXXXX (surrogate pairs beyond U+FFFF).
    """
    try:
        text.encode(sys.stdout.encoding or 'utf-8')
    except UnicodeEncodeError:
        if json_text:
            text = re.sub(r'[^\x00-\x7f]', lambda m: _json_escape(m.group()), text)
        else:
            sys.stdout.reconfigure(errors='backslashreplace')
    try:
        sys.stdout.write(text)
    except OSError as exc:
        raise StdoutFailed(exc) from None


def flush():
    """Flush stdout; StdoutFailed if it cannot be written."""
    try:
        sys.stdout.flush()
    except OSError as exc:
        raise StdoutFailed(exc) from None


def _json_escape(c):
    code = ord(c)
    if code < 0x10000:
        return f'\\u{code:04x}'
    code -= 0x10000
    return f'\\u{0xd800 + (code >> 10):04x}\\u{0xdc00 + (code & 0x3ff):04x}'


EXIT_UNREACHABLE = 1
EXIT_STDOUT = 1
"""Stdout cannot be written (``> /dev/full``)."""
EXIT_USAGE = 2
"""Bad arguments (ROS arguments included), or an input the node refused."""
EXIT_INTERRUPTED = 128 + signal.SIGINT
"""Ctrl-C: the shell's status for a program ended by SIGINT."""
EXIT_TERMINATED = 128 + signal.SIGTERM
"""SIGTERM: rclpy's handler shut the context down under the command."""
EXIT_BROKEN_PIPE = 128 + signal.SIGPIPE
"""The reader of stdout went away (``echo rpy | head -3``): the shell's status for SIGPIPE."""


def stdout_failed(exc):
    """
    Return the exit status for stdout that ``exc`` (an OSError) could not write.

    Its reader gone (``| head``): EXIT_BROKEN_PIPE, quietly; else one line, EXIT_STDOUT.
    Stdout then goes to /dev/null, so that Python's own flush at exit has nothing to fail on.
    """
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    if isinstance(exc, BrokenPipeError):
        return EXIT_BROKEN_PIPE
    print(f'{PROG}: cannot write to stdout: {exc.strerror or exc}', file=sys.stderr)
    return EXIT_STDOUT


def _init_ros(argv, context):
    """
    rclpy.init of ``context`` with the command line's ROS arguments; None, or why not.

    rclpy's signal handlers are installed as for its default context (Ctrl-C and SIGTERM
    shut the context down). rcl refuses a malformed ``-p`` or ``-r``, a missing
    ``--params-file`` or an unknown flag with a RuntimeError whose text names the argument;
    its own log line about it is kept quiet, as the one line says it all.
    """
    import rclpy
    from rclpy.logging import get_logger_level, LoggingSeverity, set_logger_level
    from rclpy.signals import SignalHandlerOptions
    level = get_logger_level('rcl')
    set_logger_level('rcl', LoggingSeverity.FATAL)
    try:
        rclpy.init(args=argv, context=context, signal_handler_options=SignalHandlerOptions.ALL)
    except RuntimeError as exc:
        return f'bad ROS arguments (after --ros-args): {" ".join(str(exc).split())}'
    finally:
        if get_logger_level('rcl') == LoggingSeverity.FATAL:  # not set by --log-level
            set_logger_level('rcl', level)
    return None


def _print_result(result, args):
    if result is None:  # printed as it went (echo, tf-demo)
        return
    if isinstance(result, str):  # describe's YAML as the node wrote it; set's line
        write(result)
    elif args.json:
        write(to_json(result), json_text=True)
    else:
        write(to_yaml(result))
    for hint in args.hints:
        flush()
        print(f'{PROG}: hint: {hint}', file=sys.stderr)


def run_command(args, context, client=None):
    """
    Run the command of ``args`` (parsed) in ``context`` (rclpy, initialised); its exit status.

    A client node of its own in the context talks to the node, or ``client`` (a Client of
    that context, kept by the caller: :meth:`Client.aim` at ``args``' node); the result is
    printed, a failure is one line on stderr. :func:`main` runs it in a context made for it;
    a program that has one already may run several commands in it, with one Client.
    """
    from rclpy.exceptions import NameValidationException
    kept = client is not None
    try:
        if kept:
            client.aim(args.node, args.timeout)
        else:
            client = Client(args.node, args.timeout, context)
        _print_result(COMMANDS[args.command](client, args), args)
        flush()
        return 0
    except Unreachable as exc:
        print(f'{PROG}: {exc}', file=sys.stderr)
        return EXIT_UNREACHABLE
    except (Refused, BadInput) as exc:
        print(f'{PROG}: {exc}', file=sys.stderr)
        return EXIT_USAGE
    except NameValidationException as exc:  # a -r __node:= / __ns:= that makes a bad name
        print(f'{PROG}: bad ROS arguments (after --ros-args): {str(exc).splitlines()[0]}',
              file=sys.stderr)
        return EXIT_USAGE
    except StdoutFailed as exc:
        return stdout_failed(exc.args[0])
    except Exception:
        if context.ok():
            raise
        return EXIT_TERMINATED  # the context was shut down under the command: SIGTERM
    finally:
        if kept:
            client.release()
        elif client is not None:
            client.close()


def _run(args, argv):
    """
    Start ROS, run the command, print its result; return the exit status.

    The command's rclpy context is its own (not rclpy's default one), shut down at its end:
    main may run again in the same process.
    """
    import rclpy
    context = rclpy.Context()
    why = _init_ros(argv, context)
    if why is not None:
        print(f'{PROG}: {why}', file=sys.stderr)
        return EXIT_USAGE
    try:
        return run_command(args, context)
    finally:
        context.try_shutdown()


def main(args=None):
    """
    Run one command of ``args`` (default: the command line); return the exit status.

    0 answered; 1 unreachable; 2 bad arguments or refused; 130 Ctrl-C; 141 stdout's reader
    gone. --help, --version and bad arguments end in the parser, before ROS is imported.
    rclpy.init installs rclpy's signal handlers: on Ctrl-C they shut the context down and
    Python raises KeyboardInterrupt wherever the command is, caught here; on SIGTERM the
    context shuts down alike, and the command ends with 143.
    """
    argv = [PROG, *(sys.argv[1:] if args is None else args)]
    try:
        parsed = parse_args(without_ros_args(argv)[1:])
    except OSError as exc:  # --help or --version printed where it cannot be written
        return stdout_failed(exc)
    except SystemExit:  # --help or --version printed, or a bad argument said
        try:
            flush()
        except StdoutFailed as exc:
            return stdout_failed(exc.args[0])
        raise
    try:
        return _run(parsed, argv)
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED


if __name__ == '__main__':
    sys.exit(main())
