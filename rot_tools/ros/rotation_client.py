"""
rotation_client: send one input to a running rotation_node and print what it answered.

ros2cli (``ros2 topic pub``/``echo``, ``ros2 service call``) is not on PyPI, so the pip-only
quick start has this instead (doc/client.md is its manual)::

    rotation_client euler ZYX 30 20 10 --deg
    rotation_client pose X Y Z QX QY QZ QW
    rotation_client pose_with_covariance X Y Z QX QY QZ QW [--cov C11 C12 ... C33]
    rotation_client odometry X Y Z QX QY QZ QW [--cov C11 C12 ... C33]
    rotation_client transform X Y Z QX QY QZ QW
    rotation_client orientation QX QY QZ QW
    rotation_client imu QX QY QZ QW [--cov C11 C12 ... C33]
    rotation_client describe
    rotation_client screw-path X Y Z QX QY QZ QW  X Y Z QX QY QZ QW [--tolerance T]
    rotation_client tf REFERENCE BODY [--once] [--seq SEQ] [--deg]
    rotation_client tf-demo [--duration S]
    rotation_client echo OUTPUT [--once | --count N]
    rotation_client set NAME VALUE
    rotation_client param get NAME | param list
    rotation_client play BAG [--rate R] [--topics T ...] [--start S] [--end S]

Quaternions are read in the ROS order, w last, or w first with ``--wxyz``.

An input command — one per input of the node, rot_tools.io.interface.INPUTS — publishes one
message, stamped with the current time, on the node's input of that name (Euler angles of any
sequence and unit are sent as the same rotation in the node's euler_sequence and angle_unit:
:func:`node_angles`) and prints the node's answer on its output topics for that message, output
by output by name (rot_tools.ros.client_session) — as YAML, or JSON with ``--json``
(rot_tools.io.report's writers). ``--topic`` sends to an input remapped away from
``NODE/NAME``; the topic printed is the one used. ``--cov`` (an input that carries a
covariance) sends 9 numbers, row-major, rad², as the rotation's covariance (the rest of a
pose's 6×6 is 0; without it all is 0, ROS's "unknown"), and the answer adds
``~/rpy_covariance``, or ~/describe's word for why the node published none. Euler angles
typed in radians larger than 2π get rot-tools' hint on stderr (rot_tools.io.report.angle_hint).
The command line is parsed by rot_tools.ros.client_arguments. The node draws pictures
(``~/screw_axis``, ``~/markers``) at a limited rate, the latest input winning, so they are
printed when the node drew this input: the client waits for them at most ``PICTURE_WAIT``
seconds. ``describe`` prints ~/describe's
report; ``screw-path`` calls ~/screw_path and prints the path. ``tf`` needs no node: it listens
to /tf and /tf_static itself (rot_tools.ros.node.tf_input) and prints the report of BODY in
REFERENCE — tf2_echo's job, with every representation — once a second until Ctrl-C, or once
with ``--once``; a frame that does not appear within ``--timeout`` is one line on stderr, exit
status 1. ``tf-demo`` publishes a small moving tree (rot_tools.ros.tf_demo) until Ctrl-C or
``--duration``. ``echo OUTPUT`` prints each message of that output as it arrives, as the input
commands print it, until Ctrl-C, ``--once`` or ``--count N``. ``set NAME VALUE`` reads the type
the node declares for NAME (~/describe_parameters), sends VALUE as that type (~/set_parameters)
and prints the node's answer in one line: a refusal, with the node's reason, is exit status 1;
a VALUE that is not of that type is one line, exit status 2, and nothing is sent. ``param get
NAME`` and ``param list`` print what ``ros2 param get`` and ``ros2 param list`` print of the
node (rot_tools.ros.client_parameters). ``play BAG`` publishes a recording's messages on their
topics at their recorded times, ``--rate`` times faster (rot_tools.ros.bag_player; the rosbags
library, the ``bag`` extra): remapped with ``--ros-args -r``, a recording drives the node.

The node's inputs are best effort, so a first message can be lost while discovery settles:
the input is sent again, with a new stamp, every ``RESEND`` seconds until an answer comes.
When none comes, ~/describe's refusal counts tell whether the node refused it. Fast DDS can
drop the reply to a brand-new service client, so a call is repeated after ``RESEND``
seconds. Every wait is bounded by ``--timeout``.

Exit status: 0 answered; 1 the node, one of its topics or services, or an answer could not
be reached within ``--timeout``, or ~/describe has nothing to report, or the node did not
set a parameter, or nothing subscribed to what play publishes, or rosbags is missing (one
line on stderr naming what); 2 bad arguments, ROS arguments included, a parameter value not
of the parameter's type, a bag that cannot be played, or the node refused the input (one line
on stderr with the node's reason); 130 Ctrl-C; 141 the reader of stdout went away; 143
SIGTERM. rclpy is used here only, and only once the command line is known to be good:
``--help``, ``--version`` and bad arguments start nothing. The process is the caller's:
rclpy's own signal handlers, no other. ``rot-tools`` stays ROS-free.
"""

from collections import deque
import math
import os
import re
import signal
import sys
import time

import numpy as np
from rot_tools.core.euler import euler_to_matrix, matrix_to_euler
from rot_tools.io import interface
from rot_tools.io.arguments import install_hint
from rot_tools.io.report import to_json, to_yaml, transform_report
from rot_tools.ros.client_arguments import parse_args, PROG, without_ros_args
from rot_tools.ros.client_session import BadInput, Client, describe_data, Refused, Unreachable
import yaml

MARKER_TYPES = ('ARROW', 'CUBE', 'SPHERE', 'CYLINDER', 'LINE_STRIP', 'LINE_LIST',
                'CUBE_LIST', 'SPHERE_LIST', 'POINTS', 'TEXT_VIEW_FACING', 'MESH_RESOURCE',
                'TRIANGLE_LIST')
MARKER_ACTIONS = ('ADD', 'DELETE', 'DELETEALL')


# ---------------------------------------------------------------------------------------
# Messages and plain data


def _xyz(v):
    return [v.x, v.y, v.z]


def _quaternion(q):
    return {'x': q.x, 'y': q.y, 'z': q.z, 'w': q.w}


def _set_xyz(v, values):
    v.x, v.y, v.z = values


def _set_quaternion(q, values):
    q.x, q.y, q.z, q.w = values


def _set_pose(pose, values):
    """Fill a geometry_msgs/Pose from X Y Z QX QY QZ QW."""
    _set_xyz(pose.position, values[:3])
    _set_quaternion(pose.orientation, values[3:])


def _pose_data(pose):
    return {'position': _xyz(pose.position), 'orientation': _quaternion(pose.orientation)}


# ---------------------------------------------------------------------------------------
# The answer, output by output


def _marker_data(marker):
    """{id, action} of a Marker, and for an ADD its type and points."""
    from visualization_msgs.msg import Marker
    types = {getattr(Marker, name): name for name in MARKER_TYPES}
    actions = {getattr(Marker, name): name for name in MARKER_ACTIONS}
    data = {'id': marker.id, 'action': actions.get(marker.action, marker.action)}
    if marker.action == Marker.ADD:
        data['type'] = types.get(marker.type, marker.type)
        if marker.points:
            data['points'] = [_xyz(p) for p in marker.points]
    return data


def _values(msg, row, parameters):
    """Return {field path: value} of an output's message (an output without a printer)."""
    from rot_tools.io.fields import field_value
    return {path: field_value(msg, path) for path in row.fields}


def _angles(msg, row, parameters):
    return {'sequence': parameters['euler_sequence'], 'unit': parameters['angle_unit'],
            'angles': _xyz(msg.vector)}


def _rpy(msg, row, parameters):
    return dict(zip(('roll', 'pitch', 'yaw'), _xyz(msg.vector)),
                unit=parameters['angle_unit'])


def _markers(msg, row, parameters):
    return [{k: v for k, v in _marker_data(m).items() if k != 'points'} for m in msg.markers]


def _pose_covariance(msg, row, parameters):
    """Return the pose and the 6×6 covariance (x, y, z, roll, pitch, yaw), or why there is none."""
    if isinstance(msg, str):  # not published: ~/describe's phrase (unknown, gimbal lock)
        return msg
    return {**_pose_data(msg.pose.pose),
            'covariance': np.reshape(msg.pose.covariance, (6, 6)).tolist()}


PRINTED = {
    'rotation_matrix': lambda msg, row, parameters: np.reshape(msg.data, (3, 3)).tolist(),
    'quaternion': lambda msg, row, parameters: _quaternion(msg.quaternion),
    'axis_angle': lambda msg, row, parameters: _xyz(msg.vector),
    'euler_angles': _angles,
    'rpy': _rpy,
    'screw': lambda msg, row, parameters: {'angular': _xyz(msg.twist.angular),
                                           'linear': _xyz(msg.twist.linear)},
    'screw_axis': lambda msg, row, parameters: _marker_data(msg),
    'markers': _markers,
    'rpy_covariance': _pose_covariance,
}
"""How each output is printed, by its name: printer(message, row, the node's parameters).
An output not here is printed as {field path: value} (_values)."""


def _answer_data(answer, parameters):
    """Return the node's answer as plain data, keyed by output name, in the table's order."""
    return {row.name: PRINTED.get(row.name, _values)(answer[row.name], row, parameters)
            for row in interface.OUTPUTS if row.name in answer}


# ---------------------------------------------------------------------------------------
# Commands


def node_angles(angles, sequence, degrees, node_sequence, node_degrees):
    """
    Euler angles of ``sequence`` (degrees when ``degrees``) as the node reads ~/euler.

    The same rotation R = euler_to_matrix(angles, sequence), as the angles of the node's
    euler_sequence (matrix_to_euler of R; at gimbal lock its choice of the pair) in its
    angle_unit. Angles already of the node's sequence are only converted in unit; so are
    NaN and Inf, which have no rotation: the node refuses them.
    """
    values = np.asarray(angles, dtype=np.float64)
    if sequence != node_sequence and np.isfinite(values).all():
        R = euler_to_matrix(np.radians(values) if degrees else values, sequence)
        values, degrees = matrix_to_euler(R, node_sequence)[0], False
    if degrees != node_degrees:
        values = np.degrees(values) if node_degrees else np.radians(values)
    return tuple(values.tolist())


def _input_message(args, parameters):
    """
    Return (message, what was sent as plain data) of an input command, from its row.

    Each role of the row's fields takes its numbers in turn (a position X Y Z, an
    orientation QX QY QZ QW, Euler angles sent in the node's sequence and unit); a
    child_frame_id is --child-frame. Keyed by each field's last name (orientation,
    rotation, quaternion, ...); Euler angles by sequence, unit, angles.
    """
    from rot_tools.io.fields import field_value
    from rot_tools.ros.node.messages import message_class
    row = args.row
    msg = message_class(row.type_name)()
    numbers = iter(args.numbers)
    sent = {}
    for role, path in row.fields.items():
        parent, _, name = path.rpartition('.')
        if role == 'child_frame_id':
            setattr(field_value(msg, parent) if parent else msg, name, args.child_frame)
            sent[name] = args.child_frame
        elif role == 'position':
            _set_xyz(field_value(msg, path), [next(numbers) for _ in range(3)])
            sent[name] = _xyz(field_value(msg, path))
        elif role == 'orientation':
            _set_quaternion(field_value(msg, path), [next(numbers) for _ in range(4)])
            sent[name] = _quaternion(field_value(msg, path))
        elif role == 'angles':
            sequence, unit = parameters['euler_sequence'], parameters['angle_unit']
            angles = node_angles([next(numbers) for _ in range(3)], args.sequence, args.deg,
                                 sequence, unit == 'deg')
            _set_xyz(field_value(msg, path), angles)
            sent.update(sequence=sequence, unit=unit, angles=list(angles))
    if getattr(args, 'cov', None) is not None:
        sent.update(_set_covariance(msg, row.covariance, args.cov))
    return msg, sent


def _set_covariance(msg, covariance, rotation):
    """
    Put the 9 numbers of ``rotation`` (row-major) in the covariance array (path, size) of msg.

    9 numbers: the array itself (an Imu's orientation_covariance); 36: its rotation block,
    the rest 0. Return {the array's name: its rows} as sent.
    """
    from rot_tools.io.fields import field_value
    path, size = covariance
    n = 3 if size == 9 else 6
    C = np.zeros((n, n))
    C[n - 3:, n - 3:] = np.reshape(rotation, (3, 3))
    parent, _, name = path.rpartition('.')
    setattr(field_value(msg, parent) if parent else msg, name, C.ravel().tolist())
    return {name: C.tolist()}


def _input_command(client, args):
    """Send one input message (euler, pose, odometry, ...); return the answer's report."""
    parameters = client.parameters(['euler_sequence', 'angle_unit', 'publish_markers'])
    msg, sent = _input_message(args, parameters)
    msg.header.frame_id = args.frame
    topic, (sec, nanosec), answer = client.send(args.command, msg,
                                                parameters['publish_markers'], args.topic,
                                                getattr(args, 'cov', None) is not None)
    return {'node': client.target,
            'input': {'topic': topic, 'type': args.row.type_name,
                      'frame_id': args.frame, 'stamp': {'sec': sec, 'nanosec': nanosec},
                      **sent},
            'answer': _answer_data(answer, parameters)}


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
        _set_pose(pose.pose, values)
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
            'poses': [_pose_data(p.pose) for p in plan.poses]}


def _tf_report(follower, header, R, b, args):
    stamp = header.stamp
    return {'reference_frame': follower.reference, 'body_frame': follower.body,
            'chain': follower.tree.chain(follower.reference, follower.body),
            'stamp': {'sec': stamp.sec, 'nanosec': stamp.nanosec},
            **transform_report(R, b, args.seq, args.deg)}


def _tf_command(client, args):
    """tf: print BODY in REFERENCE from /tf and /tf_static, once or once a second."""
    from rot_tools.ros.node import tf_input  # tf2_msgs: only this command needs it
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
        if args.json:
            write(to_json(report), json_text=True)
        else:
            write('---\n' + to_yaml(report))
        sys.stdout.flush()
        due = time.monotonic() + 1.0
        client.spin_until(lambda: time.monotonic() >= due, 1.0)


def _tf_demo_command(client, args):
    """tf-demo: publish the demo tree until Ctrl-C or --duration; nothing to print after."""
    from rot_tools.ros import tf_demo
    from rot_tools.ros.node import tf_input
    missing = tf_input.tf2_msgs_missing()
    if missing:
        raise Unreachable(missing)
    demo = tf_demo.TfDemo(client.node)
    try:
        until = 'until Ctrl-C' if args.duration is None else f'for {args.duration:g} s'
        write(f'publishing {tf_demo.frames()} on {demo.tf.topic_name} and '
              f'{demo.tf_static.topic_name} {until}\n')
        sys.stdout.flush()
        end = math.inf if args.duration is None else time.monotonic() + args.duration
        while time.monotonic() < end:
            client.spin_until(lambda: time.monotonic() >= end, 1.0)
    finally:
        demo.close()
    return None


def _echo_data(msg, row, parameters):
    """One message of an output as plain data: its header's stamp and frame, and its values."""
    data = {}
    if hasattr(msg, 'header'):
        stamp = msg.header.stamp
        data = {'stamp': {'sec': stamp.sec, 'nanosec': stamp.nanosec},
                'frame_id': msg.header.frame_id}
    return {**data, row.name: PRINTED.get(row.name, _values)(msg, row, parameters)}


def _echo_command(client, args):
    """echo: print each message of the node's output until Ctrl-C, --once or --count N."""
    from rclpy.qos import QoSProfile
    from rot_tools.ros.node.messages import message_class
    row = interface.output_named(args.output)
    parameters = client.parameters(['euler_sequence', 'angle_unit'])
    received = deque()
    sub = client.subscribe(message_class(row.type_name), args.topic or client.topic(row.name),
                           received.append, QoSProfile(depth=100))
    if not client.spin_until(lambda: sub.get_publisher_count() > 0, args.timeout):
        raise Unreachable(client.missing(f'publisher on {sub.topic_name}'))
    left = 1 if args.once else args.count or math.inf
    while left > 0:
        client.spin_until(lambda: received, 1.0)
        while received and left > 0:
            data = _echo_data(received.popleft(), row, parameters)
            if args.json:
                write(to_json(data), json_text=True)
            else:
                write('---\n' + to_yaml(data))
            sys.stdout.flush()
            left -= 1
    return None


def _set_command(client, args):
    """set: set one parameter as the node declares it; its answer, Refused or Unreachable."""
    from rcl_interfaces.msg import Parameter, ParameterType
    from rot_tools.ros import client_parameters
    kind = client.parameter_type(args.name)
    if kind in (None, ParameterType.PARAMETER_NOT_SET):
        raise Unreachable(f'node {client.target} has no parameter {args.name!r}')
    try:
        value = client_parameters.typed_value(kind, args.value)
    except client_parameters.DoesNotFit:
        raise BadInput(client_parameters.refusal(args.name, client.target, kind,
                                                 args.value)) from None
    result = client.set_parameter(Parameter(name=args.name, value=value))
    shown = f'{args.name} = {client_parameters.shown(value)}'
    if not result.successful:
        raise Unreachable(f'node {client.target} refused {shown}: '
                          + ' '.join(result.reason.split()))
    return f'node {client.target}: {shown}\n'


def _param_command(client, args):
    """Print a parameter (param get NAME) or their names (param list), as ros2 param does."""
    from rcl_interfaces.msg import ParameterType
    from rot_tools.ros import client_parameters
    if args.param_command == 'get':
        values = client.parameter_values([args.name])  # none, or NOT_SET: not declared
        if not values or values[0].type == ParameterType.PARAMETER_NOT_SET:
            raise Unreachable(f'node {client.target} has no parameter {args.name!r}')
        (value,) = values
        python = client_parameters.python_value(value)
        if args.json:
            return {'name': args.name, 'type': client_parameters.TYPE_NAMES[value.type],
                    'value': python}
        return f'{python}\n' if args.hide_type else client_parameters.get_line(value) + '\n'
    names = client.parameter_names()
    types = client.parameter_types(names) if args.param_type else None
    if args.json:
        return ({name: client_parameters.TYPE_NAMES.get(types[name], 'not set')
                 for name in sorted(names)} if types else sorted(names))
    return ''.join(line + '\n' for line in client_parameters.list_lines(names, types))


def _play_command(client, args):
    """play: publish a bag's messages on their topics at their recorded times; its summary."""
    from rot_tools.io import bag_read
    missing = bag_read.rosbags_missing()
    if missing:
        raise Unreachable(f"play needs the rosbags library ({missing} is missing), the 'bag' "
                          f"extra: {install_hint('bag')}")
    from rot_tools.ros import bag_player
    try:
        with bag_read.open_bag(args.bag) as reader:
            try:
                played, skipped = bag_player.topics(reader, args.topics)
            except KeyError as exc:
                names = sorted({c.topic for c in reader.connections})
                raise BadInput(f'{args.bag} has no topic {exc.args[0]}: its topics are '
                               + ', '.join(names)) from None
            if not played:
                raise BadInput(f'{args.bag}: nothing to play: ' + '; '.join(
                    f'{s.topic} ({s.msgtype}: {s.why})' for s in skipped))
            player = bag_player.Player(client.publisher, client.spin_until, played)
            if len(player.wait_for_subscribers(args.timeout)) == len(played):
                raise Unreachable(player.nobody_listens(args.timeout, client.target))
            start, stop = (None if seconds is None
                           else reader.start_time + int(round(seconds * 1e9)) + after
                           for seconds, after in ((args.start, 0), (args.end, 1)))
            result = player.play(reader, args.rate, start, stop)
    except bag_read.BagError as exc:
        raise BadInput(str(exc)) from None
    return bag_player.summary(args.bag, result._replace(skipped=skipped), args.rate) + '\n'


COMMANDS = {**{row.name: _input_command for row in interface.INPUTS},
            'describe': _describe_command, 'screw-path': _screw_path_command,
            'tf': _tf_command, 'tf-demo': _tf_demo_command, 'echo': _echo_command,
            'set': _set_command, 'param': _param_command, 'play': _play_command}
"""What runs each command: every input of the node is sent by _input_command."""


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
    sys.stdout.write(text)


def _json_escape(c):
    code = ord(c)
    if code < 0x10000:
        return f'\\u{code:04x}'
    code -= 0x10000
    return f'\\u{0xd800 + (code >> 10):04x}\\u{0xdc00 + (code & 0x3ff):04x}'


EXIT_UNREACHABLE = 1
EXIT_USAGE = 2
"""Bad arguments (ROS arguments included), or an input the node refused."""
EXIT_INTERRUPTED = 128 + signal.SIGINT
"""Ctrl-C: the shell's status for a program ended by SIGINT."""
EXIT_TERMINATED = 128 + signal.SIGTERM
"""SIGTERM: rclpy's handler shut the context down under the command."""
EXIT_BROKEN_PIPE = 128 + signal.SIGPIPE
"""The reader of stdout went away (``echo rpy | head -3``): the shell's status for SIGPIPE."""


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
        sys.stdout.flush()
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
    except BrokenPipeError:
        # Python's own flush of stdout at exit would fail again: stdout goes nowhere now.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE
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
    parsed = parse_args(without_ros_args(argv)[1:])
    try:
        return _run(parsed, argv)
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED


if __name__ == '__main__':
    sys.exit(main())
