"""
rotation_client's command line: its commands, their arguments and help, parsed without ROS.

A verb per input of the node (:data:`INPUTS`), then the other commands; ``--help``,
``--version`` and bad arguments end before rclpy is imported.
"""

import argparse
import math
import re

import numpy as np
from rot_tools.io import arguments, interface
from rot_tools.io.report import angle_hint

PROG = 'rotation_client'
DEFAULT_NODE = '/rot_tools'
DEFAULT_TIMEOUT = 5.0
DEFAULT_CHILD_FRAME = 'base_link'

NAME_LIMIT = 247
"""Most characters of a ROS topic or service name (rmw's limit, 255 − 8)."""

SERVICES_USED = ('describe', 'screw_path', 'get_parameters', 'describe_parameters',
                 'set_parameters', 'list_parameters')
"""The node's services the client calls, relative to the node."""

FLOAT32_MAX = float(np.finfo(np.float32).max)
FLOAT32_TINY = float(np.finfo(np.float32).smallest_subnormal)

EULER_TEXT = (
    'A1 A2 A3 of sequence SEQ (radians, or degrees with --deg) are sent as the same\n'
    "rotation in the node's euler_sequence and angle_unit: R = euler_to_matrix(A, SEQ),"
    '\nthen matrix_to_euler(R, node sequence).')
CHILD_TEXT = 'The body is --child-frame (default base_link).'
POSE = 'X Y Z QX QY QZ QW'
QUATERNION = 'QX QY QZ QW'

INPUTS = {
    'pose': (POSE, 'pose.position = X Y Z, pose.orientation = QX QY QZ QW'),
    'euler': ('A1 A2 A3', 'vector = A1 A2 A3'),
    'transform': (POSE, 'transform.translation = X Y Z, transform.rotation = QX QY QZ QW'),
    'pose_with_covariance': (POSE, 'pose.pose.position = X Y Z, '
                             'pose.pose.orientation = QX QY QZ QW'),
    'odometry': (POSE, 'pose.pose.position = X Y Z, pose.pose.orientation = QX QY QZ QW'),
    'imu': (QUATERNION, 'orientation = QX QY QZ QW'),
    'orientation': (QUATERNION, 'quaternion = QX QY QZ QW'),
}
"""The verb of each input of the node (its name): the numbers it takes, and where they go
(rot_tools.ros.client.rotation_client fills the message)."""

WITH_CHILD_FRAME = ('transform', 'odometry')
"""The inputs whose message names the body: child_frame_id = --child-frame."""

WITH_COVARIANCE = ('pose_with_covariance', 'odometry', 'imu')
"""The inputs whose message carries the rotation's covariance: --cov."""
TOPIC_TEXT = "the topic to send to, when the node's input is remapped (default NODE/{name})"
COV_TEXT = ("C11 C12 ... C33: the rotation's covariance, row-major, rad² (rotations about the "
            "parent's fixed X, Y, Z, or roll, pitch, yaw: the node's input_covariance); "
            "printed as ~/rpy_covariance (default: all 0, ROS's unknown)")


SHOWN = 40
"""The most characters of a value typed that a message shows."""

RATES = (1e-3, 1e3)
"""The rates play accepts: slower, a second of recording lasts hours; faster, no timing."""


def quoted(text):
    """Return ``text`` quoted as a message shows it: its first SHOWN characters if longer."""
    if len(text) <= SHOWN:
        return repr(text)
    return f'{text[:SHOWN]!r}… ({len(text)} characters)'


def shortened(line, text):
    """Return ``line`` with each ``text`` in it cut to its first SHOWN characters."""
    if len(text) <= SHOWN:
        return line
    return line.replace(text, f'{text[:SHOWN]}… ({len(text)} characters)')


def names_used():
    """Return the node's topics and services the client uses, relative to the node."""
    return tuple(row.name for row in interface.INPUTS + interface.OUTPUTS) + SERVICES_USED


def _positive(text):
    value = arguments.any_number(text)
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f'must be a number > 0, got {quoted(text.strip())}')
    return value


def _rate(text):
    value = arguments.any_number(text)
    low, high = RATES
    if not low <= value <= high:
        raise argparse.ArgumentTypeError(
            f'must be a number from {low:g} to {high:g}, got {quoted(text.strip())}')
    return value


def _tolerance(text):
    """
    Return a number whose meaning survives float32, the type of GetPlan's tolerance.

    A positive value float32 turns into 0 would ask for the default 20 steps, one it turns
    into inf for a single step: both are refused. NaN, and values ≤ 0 (all mean 20 steps)
    are sent as given.
    """
    value = arguments.any_number(text)
    if math.isfinite(value) and value > 0.0:
        with np.errstate(over='ignore', under='ignore'):
            sent = float(np.float32(value))
        if sent == 0.0:
            raise argparse.ArgumentTypeError(
                f'{text} is below the smallest float32, {FLOAT32_TINY:.2g}: the request '
                'carries a float32, so the node would read 0 (the default 20 steps)')
        if math.isinf(sent):
            raise argparse.ArgumentTypeError(
                f'{text} is above the largest float32, {FLOAT32_MAX:.4g}: the request '
                'carries a float32, so the node would read inf (one step)')
    return value


def _node_name(text):
    name = text if text.startswith('/') else '/' + text
    if not re.fullmatch(r'(/[A-Za-z_][A-Za-z0-9_]*)+', name):
        raise argparse.ArgumentTypeError(f'not a node name like /ns/name: {quoted(text.strip())}')
    longest = max(names_used(), key=len)
    if len(name) + 1 + len(longest) > NAME_LIMIT:
        raise argparse.ArgumentTypeError(
            f'node name of {len(name)} characters is too long: its names such as '
            f"{name[:12]}.../{longest} would exceed ROS's {NAME_LIMIT} characters (at most "
            f'{NAME_LIMIT - 1 - len(longest)} for the node name)')
    return name


def _options(parser, suppress):
    """
    --node, --frame, --timeout, --json: before the command or after its arguments.

    The command parsers get them with SUPPRESS defaults, so a value given before the
    command is not overwritten by the default.
    """
    def default(value):
        return argparse.SUPPRESS if suppress else value
    parser.add_argument('--node', type=_node_name, default=default(DEFAULT_NODE),
                        help=f'the rotation_node to talk to (default {DEFAULT_NODE})')
    parser.add_argument('--frame', default=default('map'),
                        help='frame_id of the message sent (default map)')
    parser.add_argument('--timeout', type=_positive, default=default(DEFAULT_TIMEOUT),
                        metavar='SECONDS', help='bound of every wait: discovery, an answer '
                        f'(default {DEFAULT_TIMEOUT:g})')
    arguments.add_json(parser, default=default(False))


def _wxyz_option(parser, suppress):
    arguments.add_wxyz(parser, 'quaternions are given w first: QW QX QY QZ (default: the ROS '
                       'order, QX QY QZ QW)', argparse.SUPPRESS if suppress else False)


def _leading_options(parser):
    """Add the options before a command: --version, --node, --frame, --timeout, --json, --wxyz."""
    arguments.add_version(parser)
    _options(parser, suppress=False)
    _wxyz_option(parser, suppress=False)


USAGE = {'tf': 'REFERENCE BODY', 'echo': 'OUTPUT', 'set': 'NAME VALUE',
         'param': '{get NAME | list}', 'play': 'BAG'}
"""The words of a command other than its numbers, in its usage line."""


class Command:
    """
    A command of the client: what it does, the numbers it takes, where its quaternions are.

    ``quaternions``: the index in the numbers of each quaternion's QX (w last); ``row``: the
    node's input it sends to (rot_tools.io.interface.Input), or None.
    """

    def __init__(self, summary, numbers, quaternions=(), text='', row=None):
        self.summary, self.numbers, self.quaternions, self.text, self.row = (
            summary, numbers, quaternions, text, row)


def input_command(name):
    """Return the Command sending to the node's input ``name``: its numbers and its help."""
    row = interface.input_named(name)
    numbers, where = INPUTS[name]
    words = numbers.split()
    lines = [f'~/{name}: {row.help}.', where + '.']
    if name == 'euler':
        lines.append(EULER_TEXT)
    if name in WITH_CHILD_FRAME:
        lines.append(CHILD_TEXT)
    quaternions = (words.index('QX'),) if 'QX' in words else ()
    return Command(f'send a {row.type_name} to ~/{name}', numbers, quaternions,
                   '\n'.join(lines), row)


def commands():
    """Return {name: Command}: a command per input of the node, then the others."""
    return {
        **{name: input_command(name) for name in INPUTS},
        'describe': Command("print ~/describe's report of the latest input", ''),
        'screw-path': Command(
            'call ~/screw_path from one pose to another', f'{POSE} {POSE}', (3, 10),
            'The start pose, then the goal pose, each X Y Z QX QY QZ QW; --tolerance bounds '
            'the\nstep between poses (rad and m; <= 0: 20 steps).'),
        'tf': Command(
            'print the transform of BODY in REFERENCE from /tf and /tf_static', '', (),
            'No node needed: listens to /tf and /tf_static itself and prints the report of\n'
            'the transform p_REFERENCE = R·p_BODY + b at its latest common time, once a '
            'second\nuntil Ctrl-C, or once with --once (--node and --frame are not used).'),
        'tf-demo': Command(
            'publish a demo TF tree on /tf and /tf_static until Ctrl-C', '', (),
            'map -> odom (static), odom -> base_link (a robot driving a circle: moving),\n'
            'base_link -> camera (static, tilted down): for rotation_client tf and for a\n'
            'rotation_node following two frames (--node and --frame are not used).'),
        'echo': Command(
            "print each message of one of the node's outputs until Ctrl-C", '', (),
            'OUTPUT is the name of an output:\n' + ', '.join(r.name for r in interface.OUTPUTS)
            + '.\nEach message is printed as it arrives, as the input commands print it.'),
        'diagnostics': Command(
            "print the node's /diagnostics as they arrive, until Ctrl-C", '', (),
            'One block per status: its name, its level (OK, WARN, ERROR or STALE), its message\n'
            'and its values by key. Nothing within --timeout is one line (exit 1) (--node and\n'
            '--frame are not used).'),
        'set': Command(
            "set one of the node's parameters", '', (),
            'VALUE is read as the type the node declares for NAME (its ~/describe_parameters):'
            '\na double takes any number (1e-2 too), a boolean true or false; a value that '
            "does\nnot fit is one line (exit 2). The node's answer is printed: success, or its "
            'reason\nfor refusing (exit 1).'),
        'param': Command(
            "print one of the node's parameters, or their names", '', (),
            'As ros2 param get NODE NAME and ros2 param list NODE print them (Double value '
            'is: 0.001;\nthe names sorted, indented); --json: the value with its name and '
            'type, or the names.'),
        'play': Command(
            "publish a recording's messages on their topics, at their recorded times", '', (),
            'BAG is a ROS 1 .bag, a rosbag2 directory or a file of one (the rosbags library,\n'
            "the bag extra). Remap the topics onto the node's inputs with ROS arguments, and\n"
            "name them with --topics (a bag's own /diagnostics or /tf would go live too):\n"
            '  rotation_client play run.bag --topics /imu/data --ros-args -r '
            '/imu/data:=/rot_tools/imu\n'
            'The topics played are printed first; playing starts once a subscription has '
            'matched\n(within --timeout); a summary line is printed at the end.'),
    }


def _param_verbs(parser):
    """Add param's verbs, get NAME and list, to its parser; the options before or after."""
    verbs = parser.add_commands(lambda p: _options(p, suppress=True), dest='param_command',
                                metavar='VERB', required=True)
    get = verbs.add_parser('get', help="print a parameter's value, as ros2 param get does",
                           usage=f'{PROG} param get NAME [options]',
                           description="Print a parameter's value: 'Double value is: 0.001'.")
    get.add_argument('name', metavar='NAME', help="the parameter's name")
    get.add_argument('--hide-type', action='store_true', help='print the value alone')
    listing = verbs.add_parser('list', help="print the parameters' names, as ros2 param list "
                               'does', usage=f'{PROG} param list [--param-type] [options]',
                               description="Print the node's parameter names, sorted, each "
                               'indented by two spaces.')
    listing.add_argument('--param-type', action='store_true',
                         help="each name followed by its type: '(type: double)'")
    for verb in (get, listing):
        verb.set_defaults(parser=verb)
        _options(verb, suppress=True)


def build_parser():
    """Build the rotation_client ArgumentParser (one subparser per command)."""
    parser = arguments.Parser(
        prog=PROG, description='Send one input to a running rotation_node and print its '
        'answer (YAML, or JSON with --json).\nOptions may come before COMMAND, after its '
        'arguments or between them.\nQuaternions are QX QY QZ QW (the ROS order), or QW QX QY '
        'QZ with --wxyz.',
        epilog='examples:\n  rotation_client euler ZYX 30 20 10 --deg\n'
        "  rotation_client euler xyz 0.1 0.2 0.3     (sent as the node's euler_sequence)\n"
        '  rotation_client pose 1 0 0.5  0 0 1 0\n'
        '  rotation_client pose 1 0 0.5  0 0 0 1 --wxyz     (the same pose, w first)\n'
        '  rotation_client odometry 2 1 0  0 0 0.3826834 0.9238795 --frame odom\n'
        '  rotation_client orientation 0 0 0.7071068 0.7071068 --node /robot/rot_tools\n'
        '  rotation_client imu 0 0 0.7071068 0.7071068 --frame imu_link\n'
        '  rotation_client imu 0 0 0 1 --cov 1e-4 0 0  0 1e-4 0  0 0 4e-4   (~/rpy_covariance)\n'
        '  rotation_client describe --json\n'
        '  rotation_client screw-path 0 0 0 0 0 0 1  0 0 2 0 0 1 0 --tolerance 1.0\n'
        '  rotation_client imu 0 0 0 1 --topic /robot/imu/data     (an input remapped)\n'
        '  rotation_client tf odom base_link --once --deg\n'
        '  rotation_client tf-demo --duration 60\n'
        '  rotation_client echo rpy --count 3\n'
        '  rotation_client diagnostics --once\n'
        '  rotation_client set angle_unit deg\n'
        '  rotation_client param get quaternion_tolerance\n'
        '  rotation_client param list\n'
        '  rotation_client play run.bag --topics /imu/data --ros-args -r '
        '/imu/data:=/rot_tools/imu\n\n'
        'exit status: 0 answered; 1 the node (or a topic, service, answer) not reached '
        'within --timeout,\nnothing to describe, or a parameter the node did not set or '
        "does not have; 2 bad\narguments, a value not of its parameter's type, or an input "
        'the node refused; 130 Ctrl-C.')
    sub = parser.add_commands(_leading_options, dest='command', metavar='COMMAND',
                              required=True)
    for name, command in commands().items():
        usage = ' '.join(filter(None, [PROG, name, 'SEQ' if name == 'euler' else '',
                                       USAGE.get(name, ''),
                                       command.numbers, '[options]']))
        summary = command.summary
        p = sub.add_parser(name, help=summary, usage=usage,
                           description=f'{summary[0].upper()}{summary[1:]}.\n'
                           f'{command.text}'.strip())
        if name == 'euler':
            arguments.add_sequence(p)
            arguments.add_deg(p, 'the angles are in degrees')
        if command.row is not None:
            p.add_argument('--topic', metavar='TOPIC', help=TOPIC_TEXT.format(name=name))
        if name in WITH_COVARIANCE:
            arguments.add_cov(p, COV_TEXT, type=arguments.any_number, metavar='C')
        if name in WITH_CHILD_FRAME:
            p.add_argument('--child-frame', default=DEFAULT_CHILD_FRAME, metavar='FRAME',
                           help=f'child_frame_id: the body (default {DEFAULT_CHILD_FRAME})')
        if name == 'screw-path':
            p.add_argument('--tolerance', type=_tolerance, default=0.0,
                           help='largest step between poses, rad and m (default 0: 20 steps)')
        elif name == 'tf':
            p.add_argument('reference', metavar='REFERENCE', help='the reference frame')
            p.add_argument('body', metavar='BODY', help='the frame whose pose is printed')
            p.add_argument('--once', action='store_true', help='print one report and exit')
            p.add_argument('--seq', type=arguments.sequence, default='ZYX', metavar='SEQ',
                           help='Euler sequence of the report (default ZYX)')
            arguments.add_deg(p, 'Euler angles in degrees')
        elif name == 'tf-demo':
            p.add_argument('--duration', type=_positive, metavar='SECONDS',
                           help='stop after SECONDS (default: until Ctrl-C)')
        elif name == 'echo':
            p.add_argument('output', choices=[r.name for r in interface.OUTPUTS],
                           metavar='OUTPUT', help="the output's name (~/OUTPUT)")
            p.add_argument('--topic', metavar='TOPIC',
                           help='the topic to listen to, when the output is remapped '
                           '(default NODE/OUTPUT)')
            p.add_argument('--once', action='store_true', help='print one message and exit')
            p.add_argument('--count', type=arguments.whole_number, metavar='N',
                           help='print N messages and exit')
        elif name == 'diagnostics':
            p.add_argument('--topic', default='/diagnostics', metavar='TOPIC',
                           help='the topic to listen to (default /diagnostics)')
            p.add_argument('--once', action='store_true', help='print one array and exit')
        elif name == 'set':
            p.add_argument('name', metavar='NAME', help="the parameter's name")
            p.add_argument('value', metavar='VALUE', help='its new value')
        elif name == 'param':
            _param_verbs(p)
        elif name == 'play':
            p.add_argument('bag', metavar='BAG', help='the recording')
            p.add_argument('--rate', type=_rate, default=1.0, metavar='R',
                           help=f'play R times faster than recorded, {RATES[0]:g} to '
                           f'{RATES[1]:g} (default 1)')
            p.add_argument('--topics', nargs='+', metavar='T',
                           help='play these topics only (default: every topic)')
            arguments.add_bag_window(p)
        if command.numbers:
            arguments.add_numbers(p, 'numbers', 'NUMBER', command.numbers,
                                  type=arguments.any_number)
        p.set_defaults(parser=p, expected=len(command.numbers.split()), row=command.row)
        if name != 'param':  # its verbs have them (_param_verbs)
            _options(p, suppress=True)
        if command.quaternions:
            _wxyz_option(p, suppress=True)
    return parser


def parse_args(argv):
    """
    Parse the command line (without ROS arguments); one error line and exit 2 if bad.

    With --wxyz the quaternions are reordered to the ROS order (w last) here.
    """
    args = build_parser().parse_command_line(arguments.negative_numbers_as_values(argv))
    command = commands()[args.command]
    if args.expected and len(args.numbers) != args.expected:
        args.parser.error(f'{args.command} takes {args.expected} numbers '
                          f'({command.numbers}), got {len(args.numbers)}')
    if args.command == 'play' and None not in (args.start, args.end) and args.end < args.start:
        args.parser.error(f'--end {args.end:g} is before --start {args.start:g}')
    if args.wxyz:
        if not command.quaternions:
            args.parser.error(f'--wxyz: {args.command} takes no quaternion')
        for i in command.quaternions:
            w, *xyz = args.numbers[i:i + 4]
            args.numbers[i:i + 4] = [*xyz, w]
    hint = angle_hint(args.numbers) if args.command == 'euler' and not args.deg else ''
    args.hints = [hint] if hint else []
    return args


def without_ros_args(argv):
    """
    ``argv`` without its ROS arguments: each ``--ros-args`` up to ``--`` or the end.

    As rcl reads them; rclpy.init, given the whole command line, checks them.
    """
    kept, ros = [], False
    for arg in argv:
        if ros:
            ros = arg != '--'
        elif arg == '--ros-args':
            ros = True
        else:
            kept.append(arg)
    return kept
