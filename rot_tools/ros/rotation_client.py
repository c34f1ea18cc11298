"""
rotation_client: send one input to a running rotation_node and print what it answered.

ros2cli (``ros2 topic pub``/``echo``, ``ros2 service call``) is not on PyPI, so the pip-only
quick start has this instead (doc/client.md is its manual)::

    rotation_client euler ZYX 30 20 10 --deg
    rotation_client pose X Y Z QX QY QZ QW
    rotation_client odometry X Y Z QX QY QZ QW
    rotation_client transform X Y Z QX QY QZ QW
    rotation_client orientation QX QY QZ QW
    rotation_client imu QX QY QZ QW
    rotation_client describe
    rotation_client screw-path X Y Z QX QY QZ QW  X Y Z QX QY QZ QW [--tolerance T]
    rotation_client tf REFERENCE BODY [--once] [--seq SEQ] [--deg]

Quaternions are read in the ROS order, w last, or w first with ``--wxyz``.

An input command publishes one message, stamped with the current time, on the node's
input of that name (Euler angles of any sequence and unit are sent as the same rotation in
the node's euler_sequence and angle_unit: :func:`node_angles`) and prints the node's answer
on its output topics for that message — matched by header stamp; ``~/rotation_matrix``,
which has no header, is matched by its content against the answer's quaternion — as YAML,
or JSON with ``--json`` (rot_tools.io.report's writers). The node draws pictures
(``~/screw_axis``, ``~/markers``) at a limited rate, the latest input winning, so they are
printed when the node drew this input: the client waits for them at most ``PICTURE_WAIT``
seconds. ``describe`` prints ~/describe's report; ``screw-path`` calls ~/screw_path and
prints the path. ``tf`` needs no node: it listens to /tf and /tf_static itself
(rot_tools.ros.tf_input) and prints the report of BODY in REFERENCE — tf2_echo's job, with every
representation — once a second until Ctrl-C, or once with ``--once``; a frame that does not
appear within ``--timeout`` is one line on stderr, exit status 1.

The node's inputs are best effort, so a first message can be lost while discovery settles:
the input is sent again, with a new stamp, every ``RESEND`` seconds until an answer comes.
When none comes, ~/describe's refusal counts tell whether the node refused it. Fast DDS can
drop the reply to a brand-new service client, so a call is repeated after ``RESEND``
seconds. Every wait is bounded by ``--timeout``.

Exit status: 0 answered; 1 the node, one of its topics or services, or an answer could not
be reached within ``--timeout``, or ~/describe has nothing to report (one line on stderr
naming what); 2 bad arguments, ROS arguments included, or the node refused the input (one
line on stderr with the node's reason). rclpy is used here only, and only once the command
line is known to be good: ``--help``, ``--version`` and bad arguments start nothing.
``rot-tools`` stays ROS-free.
"""

if __name__ == '__main__':
    # ``python -m rot_tools.ros.rotation_client`` runs like the console script: Ctrl-C at any
    # moment, imports included, ends it with status 130 (rot_tools.ros.runtime.start_command).
    import sys
    from rot_tools.ros.runtime import start_command
    sys.exit(start_command('rot_tools.ros.rotation_client'))

import argparse
from collections import deque
import math
import os
import re
import sys
import time

import numpy as np
from rot_tools.core.euler import EULER_SEQUENCES, euler_to_matrix, matrix_to_euler
from rot_tools.core.so3 import quaternion_to_matrix
from rot_tools.io.report import to_json, to_yaml, transform_report
from rot_tools.ros import runtime
import yaml

PROG = 'rotation_client'
DEFAULT_NODE = '/rot_tools'
DEFAULT_TIMEOUT = 5.0
DEFAULT_CHILD_FRAME = 'base_link'
RESEND = 0.5
"""Seconds to wait for an answer before an input is sent again or a call repeated."""

STAMPED_OUTPUTS = ('quaternion', 'axis_angle', 'euler_angles', 'rpy', 'screw')
"""The node's outputs that carry the input's header, published for every input."""

PICTURES = ('screw_axis', 'markers')
"""The node's pictures of an input, when publish_markers: at a limited rate, latest wins."""

PICTURE_WAIT = 1.0
"""Seconds to wait for the pictures of an answer (when the node drew that input)."""

MARKER_TYPES = ('ARROW', 'CUBE', 'SPHERE', 'CYLINDER', 'LINE_STRIP', 'LINE_LIST',
                'CUBE_LIST', 'SPHERE_LIST', 'POINTS', 'TEXT_VIEW_FACING', 'MESH_RESOURCE',
                'TRIANGLE_LIST')
MARKER_ACTIONS = ('ADD', 'DELETE', 'DELETEALL')

MATRIX_MATCH = 1e-9
"""Largest |entry difference| between ~/rotation_matrix and R of the answer's quaternion."""

NAME_LIMIT = 247
"""Most characters of a ROS topic or service name (rmw's limit, 255 − 8)."""

NAMES_USED = ('euler', 'pose', 'odometry', 'transform', 'orientation', 'imu',
              'rotation_matrix', *STAMPED_OUTPUTS, *PICTURES, 'describe', 'screw_path',
              'get_parameters')
"""The node's topics and services the client uses, relative to the node."""

FLOAT32_MAX = float(np.finfo(np.float32).max)
FLOAT32_TINY = float(np.finfo(np.float32).smallest_subnormal)


class Unreachable(Exception):
    """The node, a topic, a service or an answer could not be reached in time (exit 1)."""


class Refused(Exception):
    """The node refused the input (exit 2)."""


# ---------------------------------------------------------------------------------------
# Command line


class _Parser(argparse.ArgumentParser):
    """Errors are one line on stderr (no usage block), exit status 2."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, formatter_class=argparse.RawDescriptionHelpFormatter,
                         **kwargs)
        # '-0.5', '-1e-3', '-inf' and '-nan' are values, not options.
        self._negative_number_matcher = re.compile(r'^-(\d|\.\d|inf|nan)', re.IGNORECASE)

    def error(self, message):
        self.exit(2, f'{PROG}: error: {" ".join(str(message).split())}\n')


class _Version(argparse.Action):
    """--version: the installed distribution's version, printed without starting ROS."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS,
                 help=None):  # noqa: A002
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(runtime.program_version(PROG))
        parser.exit(0)


def _number(text):
    """Any float, NaN and Inf included: the node, not the client, decides what it refuses."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'not a number: {text!r}') from None


def _positive(text):
    value = _number(text)
    if not (math.isfinite(value) and value > 0.0):
        raise argparse.ArgumentTypeError(f'must be a number > 0, got {text!r}')
    return value


def _tolerance(text):
    """
    Return a number whose meaning survives float32, the type of GetPlan's tolerance.

    A positive value float32 turns into 0 would ask for the default 20 steps, one it turns
    into inf for a single step: both are refused. NaN, and values ≤ 0 (all mean 20 steps)
    are sent as given.
    """
    value = _number(text)
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
        raise argparse.ArgumentTypeError(f'not a node name like /ns/name: {text!r}')
    longest = max(NAMES_USED, key=len)
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
    parser.add_argument('--json', action='store_true', default=default(False),
                        help='print JSON instead of YAML')


def _wxyz_option(parser, suppress):
    parser.add_argument('--wxyz', action='store_true',
                        default=argparse.SUPPRESS if suppress else False,
                        help='quaternions are given w first: QW QX QY QZ (default: the ROS '
                        'order, QX QY QZ QW)')


class Command:
    """
    A command of the client: what it does, the numbers it takes, where its quaternions are.

    ``quaternions``: the index in the numbers of each quaternion's QX (w last).
    """

    def __init__(self, summary, numbers, quaternions=(), text=''):
        self.summary, self.numbers, self.quaternions, self.text = (
            summary, numbers, quaternions, text)


_POSE = 'X Y Z QX QY QZ QW'
_CHILD = ('\nThe body is --child-frame (default base_link), at position X Y Z with '
          'orientation QX QY QZ QW\nin --frame.')
COMMANDS_HELP = {
    'euler': Command(
        'send Euler angles to ~/euler', 'A1 A2 A3', (),
        'A1 A2 A3 of sequence SEQ (radians, or degrees with --deg) are sent as the same\n'
        "rotation in the node's euler_sequence and angle_unit: R = euler_to_matrix(A, SEQ),"
        '\nthen matrix_to_euler(R, node sequence).'),
    'pose': Command('send a PoseStamped to ~/pose', _POSE, (3,),
                    'Position X Y Z, orientation QX QY QZ QW.'),
    'odometry': Command('send a nav_msgs/Odometry to ~/odometry', _POSE, (3,),
                        'Its pose.pose: position X Y Z, orientation QX QY QZ QW.' + _CHILD),
    'transform': Command('send a TransformStamped to ~/transform', _POSE, (3,),
                         'Translation X Y Z, rotation QX QY QZ QW.' + _CHILD),
    'orientation': Command('send a QuaternionStamped to ~/orientation', 'QX QY QZ QW', (0,)),
    'imu': Command('send a sensor_msgs/Imu to ~/imu', 'QX QY QZ QW', (0,),
                   'Its orientation; the covariances, angular velocity and acceleration '
                   'are zero.'),
    'describe': Command("print ~/describe's report of the latest input", ''),
    'screw-path': Command(
        'call ~/screw_path from one pose to another', f'{_POSE} {_POSE}', (3, 10),
        'The start pose, then the goal pose, each X Y Z QX QY QZ QW; --tolerance bounds '
        'the\nstep between poses (rad and m; <= 0: 20 steps).'),
    'tf': Command(
        'print the transform of BODY in REFERENCE from /tf and /tf_static', '', (),
        'No node needed: listens to /tf and /tf_static itself and prints the report of\n'
        'the transform p_REFERENCE = R·p_BODY + b at its latest common time, once a second\n'
        'until Ctrl-C, or once with --once (--node and --frame are not used).'),
}
"""name: Command."""


def build_parser():
    """Build the rotation_client ArgumentParser (one subparser per command)."""
    parser = _Parser(
        prog=PROG, description='Send one input to a running rotation_node and print its '
        'answer (YAML, or JSON with --json).\nOptions may come before COMMAND or after its '
        'arguments. Quaternions are QX QY QZ QW (the ROS\norder), or QW QX QY QZ with '
        '--wxyz.',
        epilog='examples:\n  rotation_client euler ZYX 30 20 10 --deg\n'
        "  rotation_client euler xyz 0.1 0.2 0.3     (sent as the node's euler_sequence)\n"
        '  rotation_client pose 1 0 0.5  0 0 1 0\n'
        '  rotation_client pose 1 0 0.5  0 0 0 1 --wxyz     (the same pose, w first)\n'
        '  rotation_client odometry 2 1 0  0 0 0.3826834 0.9238795 --frame odom\n'
        '  rotation_client orientation 0 0 0.7071068 0.7071068 --node /robot/rot_tools\n'
        '  rotation_client imu 0 0 0.7071068 0.7071068 --frame imu_link\n'
        '  rotation_client describe --json\n'
        '  rotation_client screw-path 0 0 0 0 0 0 1  0 0 2 0 0 1 0 --tolerance 1.0\n'
        '  rotation_client tf odom base_link --once --deg\n\n'
        'exit status: 0 answered; 1 the node (or a topic, service, answer) not reached '
        'within --timeout,\nor nothing to describe; 2 bad arguments or an input the node '
        'refused.')
    parser.add_argument('--version', action=_Version, help='print the version and exit')
    _options(parser, suppress=False)
    _wxyz_option(parser, suppress=False)
    sub = parser.add_subparsers(dest='command', metavar='COMMAND', required=True,
                                parser_class=_Parser)
    for name, command in COMMANDS_HELP.items():
        usage = ' '.join(filter(None, [PROG, name, 'SEQ' if name == 'euler' else '',
                                       'REFERENCE BODY' if name == 'tf' else '',
                                       command.numbers, '[options]']))
        summary = command.summary
        p = sub.add_parser(name, help=summary, usage=usage,
                           description=f'{summary[0].upper()}{summary[1:]}.\n'
                           f'{command.text}'.strip())
        if name == 'euler':
            p.add_argument('sequence', choices=EULER_SEQUENCES, metavar='SEQ',
                           help='one of the 24 sequences, upper case intrinsic')
            p.add_argument('--deg', action='store_true', help='the angles are in degrees')
        elif name == 'screw-path':
            p.add_argument('--tolerance', type=_tolerance, default=0.0,
                           help='largest step between poses, rad and m (default 0: 20 steps)')
        elif name == 'tf':
            p.add_argument('reference', metavar='REFERENCE', help='the reference frame')
            p.add_argument('body', metavar='BODY', help='the frame whose pose is printed')
            p.add_argument('--once', action='store_true', help='print one report and exit')
            p.add_argument('--seq', choices=EULER_SEQUENCES, default='ZYX', metavar='SEQ',
                           help='Euler sequence of the report (default ZYX)')
            p.add_argument('--deg', action='store_true', help='Euler angles in degrees')
        elif name in ('odometry', 'transform'):
            p.add_argument('--child-frame', default=DEFAULT_CHILD_FRAME, metavar='FRAME',
                           help=f'child_frame_id: the body (default {DEFAULT_CHILD_FRAME})')
        if command.numbers:
            p.add_argument('numbers', type=_number, nargs='*', metavar='NUMBER',
                           help=command.numbers)
        p.set_defaults(parser=p, expected=len(command.numbers.split()))
        _options(p, suppress=True)
        if command.quaternions:
            _wxyz_option(p, suppress=True)
    return parser


def parse_args(argv):
    """
    Parse the command line (without ROS arguments); one error line and exit 2 if bad.

    With --wxyz the quaternions are reordered to the ROS order (w last) here.
    """
    args = build_parser().parse_args(argv)
    command = COMMANDS_HELP[args.command]
    if args.expected and len(args.numbers) != args.expected:
        args.parser.error(f'{args.command} takes {args.expected} numbers '
                          f'({command.numbers}), got {len(args.numbers)}')
    if args.wxyz:
        if not command.quaternions:
            args.parser.error(f'--wxyz: {args.command} takes no quaternion')
        for i in command.quaternions:
            w, *xyz = args.numbers[i:i + 4]
            args.numbers[i:i + 4] = [*xyz, w]
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


def describe_data(response):
    """
    Return ~/describe's YAML document as data: at least ``refused`` {total, reason: n}.

    The node writes one even before it has accepted an input (then ``success`` is false and
    ``note`` says so). Anything else is not a rotation_node's report: Unreachable.
    """
    try:
        data = yaml.safe_load(response.message)
    except yaml.YAMLError:
        data = None
    if not (isinstance(data, dict) and isinstance(data.get('refused'), dict)):
        text = ' '.join(response.message.split())
        raise Unreachable(f'~/describe did not answer with a rotation_node report: '
                          f'{text[:200]!r}')
    return data


def _counts(data):
    """{reason: n} of describe_data's refusal counts (without the total)."""
    return {reason: n for reason, n in data['refused'].items() if reason != 'total'}


def refusal_text(data, before, source, stamps=None):
    """
    Why the node refused what the client sent to ``source``, or '' if it did not.

    ``data`` is describe_data now, ``before`` the counts before sending. For each reason
    counted since, the node's sentence (what and by how much) from ``last_refusals`` when
    that refusal is of ``source`` — and of one of ``stamps`` (sent header stamps, (sec,
    nanosec)), when given and the refusal has one — else the reason's name alone.
    """
    last = data.get('last_refusals') or {}
    texts = []
    for reason, n in _counts(data).items():
        if n <= before.get(reason, 0):
            continue
        refusal = last.get(reason) or {}
        stamp = refusal.get('stamp')
        ours = refusal.get('source') == source and (
            stamps is None or stamp is None or (stamp['sec'], stamp['nanosec']) in stamps)
        texts.append(f"{refusal['message']} ({reason})" if ours and refusal.get('message')
                     else reason)
    return '; '.join(texts)


# ---------------------------------------------------------------------------------------
# Talking to the node


class Client:
    """A short-lived rclpy node that talks to one rotation_node, every wait bounded."""

    def __init__(self, target, timeout):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.target = target
        self.timeout = timeout
        self.node = rclpy.create_node(f'rotation_client_{os.getpid()}',
                                      start_parameter_services=False)
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)

    def close(self):
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()

    def topic(self, name):
        return f'{self.target}/{name}'

    def spin_until(self, done, seconds):
        """Spin until done() or ``seconds`` have passed; return done()."""
        deadline = time.monotonic() + seconds
        while not done() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)
        return done()

    def missing(self, what):
        """One line for a ``what`` (topic, service) that did not appear in time."""
        names = {f"{namespace.rstrip('/')}/{name}"
                 for name, namespace in self.node.get_node_names_and_namespaces()}
        if self.target not in names:
            domain = os.environ.get('ROS_DOMAIN_ID') or '0'
            return (f'cannot reach node {self.target}: not found within {self.timeout:g} s '
                    f'(is rotation_node running, with ROS_DOMAIN_ID {domain}?)')
        return f'node {self.target} has no {what} (waited {self.timeout:g} s)'

    def call(self, srv_type, name, request):
        """Call the node's service ``name``; the response, or Unreachable."""
        service = self.topic(name)
        client = self.node.create_client(srv_type, service)
        try:
            if not self.spin_until(client.service_is_ready, self.timeout):
                raise Unreachable(self.missing(f'service {service}'))
            deadline = time.monotonic() + self.timeout
            while time.monotonic() < deadline:
                future = client.call_async(request)
                if self.spin_until(future.done, min(RESEND, deadline - time.monotonic())):
                    return future.result()
                client.remove_pending_request(future)  # the reply may have been dropped
            raise Unreachable(f'no reply from service {service} within {self.timeout:g} s')
        finally:
            self.node.destroy_client(client)

    def describe(self):
        from std_srvs.srv import Trigger
        return self.call(Trigger, 'describe', Trigger.Request())

    def parameters(self, names):
        """Return {name: value} of the node's parameters, from its ~/get_parameters service."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python
        response = self.call(GetParameters, 'get_parameters', GetParameters.Request(names=names))
        return dict(zip(names, map(parameter_value_to_python, response.values)))

    def refusal_counts(self):
        """{reason: n} of the refusals the node has counted so far."""
        return _counts(describe_data(self.describe()))

    def refused(self, before, source, stamps=None):
        """Why the node refused what was sent to ``source`` since ``before``, or ''."""
        return refusal_text(describe_data(self.describe()), before, source, stamps)

    def wait_for_match(self, pub, subs):
        """Wait until the node subscribes to ``pub`` and publishes on every one of ``subs``."""
        if not self.spin_until(lambda: pub.get_subscription_count() > 0, self.timeout):
            raise Unreachable(self.missing(f'subscription on {pub.topic_name}'))
        for sub in subs:
            if not self.spin_until(lambda sub=sub: sub.get_publisher_count() > 0,
                                   self.timeout):
                raise Unreachable(self.missing(f'publisher on {sub.topic_name}'))

    def send(self, name, msg, pictures):
        """
        Publish ``msg`` on the node's ~/name until it answers; return (stamp, answer).

        The answer is {output: message}: the outputs stamped as one sent message, the
        ~/rotation_matrix whose content matches, and, when ``pictures``, the pictures of that
        message if the node draws them within PICTURE_WAIT. Refused when the node's refusal
        counts rise instead.
        """
        from geometry_msgs.msg import QuaternionStamped, TwistStamped, Vector3Stamped
        from rclpy.qos import QoSProfile
        from std_msgs.msg import Float64MultiArray
        from visualization_msgs.msg import Marker, MarkerArray
        types = dict(zip(STAMPED_OUTPUTS + PICTURES, (
            QuaternionStamped, Vector3Stamped, Vector3Stamped, Vector3Stamped, TwistStamped,
            Marker, MarkerArray)))
        answers = Answers(msg.header.frame_id)
        outputs = STAMPED_OUTPUTS + (PICTURES if pictures else ())
        qos = QoSProfile(depth=100)
        subs = [self.node.create_subscription(types[output], self.topic(output),
                                              answers.collector(output), qos)
                for output in outputs]
        subs.append(self.node.create_subscription(
            Float64MultiArray, self.topic('rotation_matrix'),
            lambda m: answers.matrices.append(m), qos))
        topic = self.topic(name)
        pub = self.node.create_publisher(type(msg), topic, 10)
        self.wait_for_match(pub, subs)
        before = self.refusal_counts()
        deadline = time.monotonic() + self.timeout
        while True:
            msg.header.stamp = self.node.get_clock().now().to_msg()
            answers.sent.add(_key(msg.header.stamp))
            pub.publish(msg)
            if self.spin_until(answers.complete, min(RESEND, deadline - time.monotonic())):
                break
            refused = self.refused(before, topic, answers.sent)
            if refused:
                raise Refused(f'node {self.target} refused the input on {topic}: {refused}')
            if time.monotonic() >= deadline:
                raise Unreachable(f'no answer from node {self.target} to the input on {topic} '
                                  f'within {self.timeout:g} s')
        stamp = answers.complete()
        answer = answers.by_stamp[stamp]
        R = quaternion_to_matrix(list(_quaternion(answer['quaternion'].quaternion).values()))
        if not self.spin_until(lambda: answers.matrix(R), self.timeout):
            raise Unreachable(f'no matching message on {self.topic("rotation_matrix")} '
                              f'within {self.timeout:g} s')
        # Kept now: while the pictures are awaited, another publisher's inputs may push it
        # out of the latest matrices.
        matrix = answers.matrix(R)
        if pictures:
            self.spin_until(lambda: set(PICTURES) <= set(answer),
                            min(PICTURE_WAIT, self.timeout))
        return stamp, dict(answer, rotation_matrix=matrix)


def _key(stamp):
    return stamp.sec, stamp.nanosec


class Answers:
    """What the node published for the messages sent: stamped outputs by stamp, matrices."""

    def __init__(self, frame_id):
        self.frame_id = frame_id
        self.sent = set()
        """(sec, nanosec) of every message sent."""
        self.by_stamp = {}
        """(sec, nanosec): {output: message} of the stamped outputs."""
        self.matrices = deque(maxlen=100)
        """The latest ~/rotation_matrix messages (they carry no header)."""

    def collector(self, output):
        """Subscription callback keeping the ``output`` messages stamped as a sent one."""
        def collect(msg):
            if output == 'markers':  # a MarkerArray has no header: its markers carry it
                if not msg.markers:
                    return
                header = msg.markers[0].header
            else:
                header = msg.header
            key = _key(header.stamp)
            if key in self.sent and header.frame_id == self.frame_id:
                self.by_stamp.setdefault(key, {})[output] = msg
        return collect

    def complete(self):
        """Return the stamp of a sent message with every one of STAMPED_OUTPUTS, or None."""
        for stamp, answer in self.by_stamp.items():
            if set(STAMPED_OUTPUTS) <= set(answer):
                return stamp
        return None

    def matrix(self, R):
        """Return the latest ~/rotation_matrix equal to R (within MATRIX_MATCH), or None."""
        for m in reversed(self.matrices):
            if np.max(np.abs(np.reshape(m.data, (3, 3)) - R)) <= MATRIX_MATCH:
                return m
        return None


# ---------------------------------------------------------------------------------------
# Commands


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


def _answer_data(answer, parameters):
    """Return the node's answer as plain data, keyed by output topic (relative to the node)."""
    twist = answer['screw'].twist
    data = {
        'rotation_matrix': np.reshape(answer['rotation_matrix'].data, (3, 3)).tolist(),
        'quaternion': _quaternion(answer['quaternion'].quaternion),
        'axis_angle': _xyz(answer['axis_angle'].vector),
        'euler_angles': {'sequence': parameters['euler_sequence'],
                         'unit': parameters['angle_unit'],
                         'angles': _xyz(answer['euler_angles'].vector)},
        'rpy': dict(zip(('roll', 'pitch', 'yaw'), _xyz(answer['rpy'].vector)),
                    unit=parameters['angle_unit']),
        'screw': {'angular': _xyz(twist.angular), 'linear': _xyz(twist.linear)},
    }
    if 'screw_axis' in answer:
        data['screw_axis'] = _marker_data(answer['screw_axis'])
    if 'markers' in answer:
        data['markers'] = [{k: v for k, v in _marker_data(m).items() if k != 'points'}
                           for m in answer['markers'].markers]
    return data


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
    """(message, what was sent as plain data) of an input command."""
    from geometry_msgs.msg import PoseStamped, QuaternionStamped, TransformStamped
    from geometry_msgs.msg import Vector3Stamped
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import Imu
    numbers = args.numbers
    if args.command == 'euler':
        sequence, unit = parameters['euler_sequence'], parameters['angle_unit']
        angles = node_angles(numbers, args.sequence, args.deg, sequence, unit == 'deg')
        msg = Vector3Stamped()
        _set_xyz(msg.vector, angles)
        return msg, {'sequence': sequence, 'unit': unit, 'angles': list(angles)}
    if args.command == 'pose':
        msg = PoseStamped()
        _set_pose(msg.pose, numbers)
        return msg, _pose_data(msg.pose)
    if args.command == 'odometry':
        msg = Odometry(child_frame_id=args.child_frame)
        _set_pose(msg.pose.pose, numbers)
        return msg, {'child_frame_id': msg.child_frame_id, **_pose_data(msg.pose.pose)}
    if args.command == 'transform':
        msg = TransformStamped(child_frame_id=args.child_frame)
        t = msg.transform
        _set_xyz(t.translation, numbers[:3])
        _set_quaternion(t.rotation, numbers[3:])
        return msg, {'child_frame_id': msg.child_frame_id, 'translation': _xyz(t.translation),
                     'rotation': _quaternion(t.rotation)}
    if args.command == 'imu':
        msg = Imu()
        _set_quaternion(msg.orientation, numbers)
        return msg, {'orientation': _quaternion(msg.orientation)}
    msg = QuaternionStamped()
    _set_quaternion(msg.quaternion, numbers)
    return msg, {'quaternion': _quaternion(msg.quaternion)}


def _input_command(client, args):
    """Send one input message (euler, pose, odometry, ...); return the answer's report."""
    from rot_tools.ros.messages import type_name
    parameters = client.parameters(['euler_sequence', 'angle_unit', 'publish_markers'])
    msg, sent = _input_message(args, parameters)
    msg.header.frame_id = args.frame
    name = args.command
    (sec, nanosec), answer = client.send(name, msg, parameters['publish_markers'])
    return {'node': client.target,
            'input': {'topic': client.topic(name), 'type': type_name(type(msg)),
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
        if args.json:
            write(to_json(report), json_text=True)
        else:
            write('---\n' + to_yaml(report))
        sys.stdout.flush()
        due = time.monotonic() + 1.0
        client.spin_until(lambda: time.monotonic() >= due, 1.0)


COMMANDS = {'euler': _input_command, 'pose': _input_command, 'odometry': _input_command,
            'transform': _input_command, 'orientation': _input_command, 'imu': _input_command,
            'describe': _describe_command, 'screw-path': _screw_path_command,
            'tf': _tf_command}


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


def main(argv=None):
    """Run one command; return the exit status (0, 1 unreachable, 2 bad input or refused)."""
    argv = sys.argv if argv is None else [PROG, *argv]
    args = parse_args(without_ros_args(argv)[1:])  # --help, --version: nothing started
    import rclpy
    from rclpy.exceptions import NameValidationException
    from rclpy.signals import SignalHandlerOptions
    client = None
    try:
        # Without rclpy's signal handlers Ctrl-C is a plain KeyboardInterrupt.
        runtime.init_ros(PROG, argv, signal_handler_options=SignalHandlerOptions.NO)
        client = Client(args.node, args.timeout)
        result = COMMANDS[args.command](client, args)
    except Unreachable as exc:
        print(f'{PROG}: {exc}', file=sys.stderr)
        return 1
    except Refused as exc:
        print(f'{PROG}: {exc}', file=sys.stderr)
        return 2
    except NameValidationException as exc:  # a -r __node:= / __ns:= rcl could not use
        print(f'{PROG}: {runtime.ros_argument_error(exc)}', file=sys.stderr)
        return runtime.EXIT_USAGE
    except KeyboardInterrupt:
        return 130
    finally:
        if client is not None:
            client.close()
        rclpy.try_shutdown()
    if isinstance(result, str):  # describe's YAML, as the node wrote it
        write(result)
    elif args.json:
        write(to_json(result), json_text=True)
    else:
        write(to_yaml(result))
    return 0
