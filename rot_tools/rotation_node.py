"""rotation_node: orientations and poses republished as matrix, quaternion, Euler, screw.

Every input kind is one row of :data:`INPUTS` — topic, message type, converter — and every
message becomes one rigid transform (header, R, b) at the boundary (rot_tools.messages).
From there one path serves them all: one pass of the decomposition kernels
(rot_tools.decomposition.decompose_values) gives every number published — rotation vector θ·l̂,
Euler angles, twist (θ·l̂, θ·m + d·l̂) = screw_log, and the quaternion (matrix_to_quaternion
of R) — and the picture's decomposition runs the same kernels, so at θ = π all outputs of
one input share the axis sign. Outputs carry the input's header. Topics, services and
parameters: SPEC §3, §3.1 and README "Using it in ROS 2".

The pictures (~/markers and ~/screw_axis, rot_tools.drawing) cost several times the rest of
an input's work, so they are throttled: at most MARKER_RATE a second, the latest input wins,
and the last input is always drawn (a timer publishes it when its turn comes).
"""

from contextlib import ExitStack
import difflib
import gc
from functools import partial, wraps
import math
import sys
import time
import traceback
from typing import Callable, NamedTuple

from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, QuaternionStamped
from geometry_msgs.msg import TransformStamped, TwistStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from nav_msgs.srv import GetPlan
import numpy as np
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
from rcl_interfaces.msg import SetParametersResult
import rclpy
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import InvalidHandle
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data, QoSProfile
from rclpy.subscription import Subscription
from rclpy.utilities import timeout_sec_to_nsec
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker, MarkerArray

from rot_tools import drawing, messages
from rot_tools.errors import RotationError
from rot_tools.euler import EULER_SEQUENCES
from rot_tools.decomposition import decompose_values
from rot_tools.report import to_yaml, transform_report
from rot_tools.screw import screw_from_transform, screw_interpolate

FRAME_MISMATCH = 'frame_mismatch'
BAD_TOLERANCE = 'bad_tolerance'
PATH_TOO_LONG = 'path_too_long'
NOT_DECOMPOSABLE = 'not_decomposable'
REFUSAL_REASONS = messages.REFUSAL_REASONS + (
    NOT_DECOMPOSABLE, FRAME_MISMATCH, BAD_TOLERANCE, PATH_TOO_LONG)
"""Every reason an input is refused for, in the order ~/describe lists the counts."""

DEFAULT_PATH_STEPS = 20
"""Steps of ~/screw_path when the request's tolerance is ≤ 0 (21 poses)."""

MAX_PATH_STEPS = 10_000
"""A tolerance that needs more steps than this is refused (the reply would be huge)."""

MARKER_RATE = 30.0
"""Most pictures (~/markers with ~/screw_axis) a second: RViz draws 30 frames a second."""

REFUSAL_WARNING_PERIOD = 1.0
"""Seconds between two warnings about refused inputs of one topic for one reason."""


class InputKind(NamedTuple):
    """One kind of input: where it arrives, its type, and how it becomes (header, R, b)."""

    topic: str
    msg_type: type
    convert: Callable
    """convert(msg, settings) -> (header, R, b); raises messages.RefusedInput."""


INPUTS = (
    InputKind('~/pose', PoseStamped, messages.pose_stamped_to_transform),
    InputKind('~/euler', Vector3Stamped, messages.euler_stamped_to_transform),
    InputKind('~/transform', TransformStamped, messages.transform_stamped_to_transform),
    InputKind('~/pose_with_covariance', PoseWithCovarianceStamped,
              messages.pose_with_covariance_stamped_to_transform),
    InputKind('~/odometry', Odometry, messages.odometry_to_transform),
    InputKind('~/imu', Imu, messages.imu_to_transform),
    InputKind('~/orientation', QuaternionStamped, messages.quaternion_stamped_to_transform),
)
"""Every input of the node (SPEC §3, §3.1); each joins the one path (header, R, b) → outputs."""


class Source(NamedTuple):
    """An input subscription as the callbacks see it: resolved topic, type name, converter."""

    topic: str
    type_name: str
    convert: Callable


class Settings(NamedTuple):
    """The parameters as the callbacks use them; replaced whole when a parameter changes."""

    euler_sequence: str
    degrees: bool
    quaternion_tolerance: float
    publish_markers: bool
    marker_scale: float


class Outputs(NamedTuple):
    """The output messages, reused from one input to the next."""

    matrix: Float64MultiArray
    quaternion: QuaternionStamped
    rotvec: Vector3Stamped
    euler: Vector3Stamped
    twist: TwistStamped
    marker: Marker


class Latest(NamedTuple):
    """The latest accepted input, kept for ~/describe (the report is built on request)."""

    source: Source
    header: object
    R: np.ndarray
    b: np.ndarray
    settings: Settings


def _descriptor(kind, description, constraints='', fp_range=None):
    return ParameterDescriptor(
        type=kind, description=description, additional_constraints=constraints,
        floating_point_range=[fp_range] if fp_range is not None else [])


PARAMETERS = {
    'euler_sequence': ('ZYX', _descriptor(
        ParameterType.PARAMETER_STRING,
        'Euler sequence of ~/euler input and ~/euler_angles output: upper case intrinsic '
        '(ZYX: R = Rot_z(θ1) Rot_y(θ2) Rot_x(θ3)), lower case extrinsic',
        'one of ' + ' '.join(EULER_SEQUENCES))),
    'angle_unit': ('rad', _descriptor(
        ParameterType.PARAMETER_STRING,
        'unit of the angles of ~/euler and ~/euler_angles', "'rad' or 'deg'")),
    'quaternion_tolerance': (1e-3, _descriptor(
        ParameterType.PARAMETER_DOUBLE,
        'largest |‖q‖ − 1| of an input quaternion; within it q is normalised, beyond it the '
        'message is refused', '>= 0, finite',
        FloatingPointRange(from_value=0.0, to_value=math.inf, step=0.0))),
    'publish_markers': (True, _descriptor(
        ParameterType.PARAMETER_BOOL,
        f'publish the picture of each input (at most {MARKER_RATE:g} a second, the latest '
        "wins): the moved frame's axes, screw axis, helical path and label on ~/markers "
        '(MarkerArray) and the screw axis arrow on ~/screw_axis (Marker); switching it off '
        'deletes both')),
    'marker_scale': (1.0, _descriptor(
        ParameterType.PARAMETER_DOUBLE,
        'length of the frame axes on ~/markers and of the ~/screw_axis arrow (m)',
        '> 0, finite',
        FloatingPointRange(from_value=0.0, to_value=math.inf, step=0.0))),
}
"""name: (default, descriptor)."""


def _check_parameter(name, value):
    """Why ``value`` is not valid for parameter ``name`` (types are checked by rclpy), or ''."""
    if name == 'euler_sequence' and value not in EULER_SEQUENCES:
        return (f'euler_sequence {value!r} is not a sequence: use one of '
                + ' '.join(EULER_SEQUENCES))
    if name == 'angle_unit' and value not in ('rad', 'deg'):
        return f"angle_unit {value!r} is not 'rad' or 'deg'"
    if name == 'quaternion_tolerance' and not (math.isfinite(value) and value >= 0.0):
        return f'quaternion_tolerance must be finite and >= 0, got {value}'
    if name == 'marker_scale' and not (math.isfinite(value) and value > 0.0):
        return f'marker_scale must be finite and > 0, got {value}'
    return ''


class RotationNode(Node):
    """Subscribes to every input of INPUTS and republishes their decompositions."""

    def __init__(self, node_name='rot_tools', **kwargs):
        super().__init__(node_name, **kwargs)
        for name, (default, descriptor) in PARAMETERS.items():
            self.declare_parameter(name, default, descriptor)
        for name in PARAMETERS:  # overrides given at start-up are checked here
            value = self.get_parameter(name).value
            reason = _check_parameter(name, value)
            if reason:
                self.destroy_node()
                raise InvalidParameterValueException(name, value, reason)
        self._warn_about_unknown_overrides()
        self._settings = self._read_settings()
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)

        self._refused = dict.fromkeys(REFUSAL_REASONS, 0)
        self._warned = {}  # (topic, reason): time.monotonic() of its last warning
        self._latest = None

        # One message per output, refilled for each input (see rot_tools.messages).
        self._out = Outputs(messages.rotation_matrix_msg(np.eye(3)), QuaternionStamped(),
                            Vector3Stamped(), Vector3Stamped(), TwistStamped(),
                            messages.screw_axis_marker(None, (0, 0, 0), (0, 0, 1), 1.0))
        qos = QoSProfile(depth=10)
        self._matrix_pub = self.create_publisher(Float64MultiArray, '~/rotation_matrix', qos)
        self._quaternion_pub = self.create_publisher(QuaternionStamped, '~/quaternion', qos)
        self._axis_angle_pub = self.create_publisher(Vector3Stamped, '~/axis_angle', qos)
        self._euler_pub = self.create_publisher(Vector3Stamped, '~/euler_angles', qos)
        self._screw_pub = self.create_publisher(TwistStamped, '~/screw', qos)
        self._marker_pub = self.create_publisher(Marker, '~/screw_axis', qos)
        self._markers_pub = self.create_publisher(MarkerArray, '~/markers', qos)
        self._picture_due = None  # the arguments of the latest drawing not yet published
        self._picture_shown = None  # the header of the picture on show (ADDs), or None
        self._picture_sent = -math.inf  # time.monotonic() of the last one published
        self._picture_timer = self.create_timer(
            1.0 / MARKER_RATE, self._publish_picture,
            clock=Clock(clock_type=ClockType.STEADY_TIME), autostart=False)

        self._sources = []
        for kind in INPUTS:
            source = Source(self.resolve_topic_name(kind.topic),
                            messages.type_name(kind.msg_type),
                            kind.convert)
            self.create_subscription(kind.msg_type, kind.topic,
                                     partial(self._on_input, source), qos_profile_sensor_data)
            self._sources.append(source)

        self._describe_srv = self.create_service(Trigger, '~/describe', self._on_describe)
        self._screw_path_srv = self.create_service(
            GetPlan, '~/screw_path', self._on_screw_path)
        self._screw_path_name = self.resolve_service_name('~/screw_path')
        self.get_logger().info(
            f'decomposing {self._input_topics()} (euler_sequence '
            f"{self._settings.euler_sequence}, angle_unit "
            f"{'deg' if self._settings.degrees else 'rad'})")

    def _input_topics(self):
        """'/n/pose, /n/euler or /n/transform': the input topics as remapped."""
        topics = [source.topic for source in self._sources]
        return ', '.join(topics[:-1]) + ' or ' + topics[-1]

    # -- parameters --------------------------------------------------------------------

    def _read_settings(self):
        value = {name: self.get_parameter(name).value for name in PARAMETERS}
        return Settings(value['euler_sequence'], value['angle_unit'] == 'deg',
                        value['quaternion_tolerance'], value['publish_markers'],
                        value['marker_scale'])

    def _on_set_parameters(self, parameters):
        """Refuse invalid values of our parameters (rclpy has checked type and range)."""
        for parameter in parameters:
            if parameter.name in PARAMETERS:
                reason = _check_parameter(parameter.name, parameter.value)
                if reason:
                    return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    def _on_parameters_set(self, parameters):
        """Take the new values into use from the next message; publish_markers off clears."""
        if any(parameter.name in PARAMETERS for parameter in parameters):
            was_drawing = self._settings.publish_markers
            self._settings = self._read_settings()
            if was_drawing and not self._settings.publish_markers:
                self._clear_picture()

    def _warn_about_unknown_overrides(self):
        """Warn about each start-up override (-p, --params-file) that names no parameter.

        rclpy keeps the overrides it was given (command line, parameter files, the
        parameter_overrides argument) in Node._parameter_overrides and has no public
        accessor for them; without this a misspelt ``-p euler_sequnce:=xyz`` is silently
        ignored.
        """
        for name in sorted(getattr(self, '_parameter_overrides', {})):
            if self.has_parameter(name):
                continue
            close = difflib.get_close_matches(name, PARAMETERS, n=1)
            hint = f": did you mean '{close[0]}'?" if close else (
                ': its parameters are ' + ', '.join(PARAMETERS))
            self.get_logger().warning(
                f"parameter override '{name}' is not a parameter of this node and is "
                f'ignored{hint}')

    # -- inputs ----------------------------------------------------------------------------

    def _on_input(self, source, msg):
        """Convert one message to (header, R, b) and publish every output, or refuse it."""
        settings = self._settings
        try:
            header, R, b = source.convert(msg, settings)
            # Every number published, as plain floats from one compiled kernel pass (the
            # hot path: decompose's arrays cost more than the math); the picture's
            # decomposition is left to the drawing, at most MARKER_RATE times a second.
            v = decompose_values(R, b, settings.euler_sequence)
            angles = tuple(map(math.degrees, v.euler)) if settings.degrees else v.euler
        except messages.RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc))
            return
        except RotationError as exc:
            self._refuse(source.topic, NOT_DECOMPOSABLE, str(exc))
            return
        out = self._out
        self._matrix_pub.publish(messages.rotation_matrix_msg(R, out.matrix))
        self._quaternion_pub.publish(
            messages.quaternion_stamped_msg(header, v.quaternion, out.quaternion))
        self._axis_angle_pub.publish(messages.vector3_stamped_msg(header, v.rotvec, out.rotvec))
        self._euler_pub.publish(messages.vector3_stamped_msg(header, angles, out.euler))
        self._screw_pub.publish(messages.twist_stamped_msg(header, v.twist, out.twist))
        if settings.publish_markers:
            self._offer_picture(header, R, b, settings)
        self._latest = Latest(source, header, R, b, settings)

    def _refuse(self, topic, reason, text):
        """Count a refused input; warn at most once a REFUSAL_WARNING_PERIOD per (topic, reason).

        Not rclpy's throttle_duration_sec: it throttles per call site, so one fast bad
        stream (a raw IMU without orientation at 50 Hz) would silence every other one.
        """
        self._refused[reason] += 1
        now = time.monotonic()
        if now - self._warned.get((topic, reason), -math.inf) >= REFUSAL_WARNING_PERIOD:
            self._warned[topic, reason] = now
            self.get_logger().warning(f'refused input on {topic} ({reason}): {text}')

    # -- markers -----------------------------------------------------------------------

    def _offer_picture(self, header, R, b, settings):
        """Publish the picture of this input now, or when MARKER_RATE next allows it.

        An input that arrives while the timer runs replaces the one waiting: the latest
        wins, and the last input is always drawn.
        """
        self._picture_due = (header, R, b, settings)
        if not self._picture_timer.is_canceled():
            return
        if time.monotonic() - self._picture_sent >= 1.0 / MARKER_RATE:
            self._publish_picture()
        else:
            self._picture_timer.reset()  # fires one period from now

    def _publish_picture(self):
        """~/markers and ~/screw_axis of the input waiting (DELETEs for the identity)."""
        self._picture_timer.cancel()
        due, self._picture_due = self._picture_due, None
        if due is None:  # dropped: publish_markers was switched off (_clear_picture)
            return
        header, R, b, settings = due
        self._picture_sent = time.monotonic()
        try:
            picture = drawing.picture(R, b, settings.marker_scale, settings.degrees)
        except RotationError as exc:  # e.g. a huge marker_scale: the old picture goes
            self.get_logger().warning(f'no picture: {exc}', throttle_duration_sec=1.0)
            picture = None
        if picture is None or picture.kind == drawing.IDENTITY:
            self._delete_picture(header)
            return
        self._picture_shown = header
        self._markers_pub.publish(messages.picture_markers(header, picture))
        self._marker_pub.publish(messages.screw_axis_marker(
            header, picture.screw.point, picture.screw.direction, settings.marker_scale,
            self._out.marker))

    def _delete_picture(self, header):
        """DELETE every marker of ~/markers and ~/screw_axis, in ``header``'s frame."""
        self._picture_shown = None
        self._markers_pub.publish(messages.delete_picture_markers(header))
        self._marker_pub.publish(messages.delete_marker(header, messages.SCREW_AXIS_NS, 0))

    def _clear_picture(self):
        """publish_markers was switched off: drop the picture waiting, delete the one shown.

        The DELETEs go once, in the frame of the last picture drawn; nothing is sent when
        nothing is shown (none drawn yet, or the last input was the identity).
        """
        self._picture_timer.cancel()
        self._picture_due = None
        if self._picture_shown is not None:
            self._delete_picture(self._picture_shown)

    # -- services ----------------------------------------------------------------------

    def refused_counts(self):
        """{'total': N, reason: n, ...} of the inputs refused so far."""
        return {'total': sum(self._refused.values()), **self._refused}

    def _on_describe(self, request, response):
        """YAML report of the latest input (rot_tools.report), with the refusal counts."""
        refused = self.refused_counts()
        latest = self._latest
        if latest is None:
            counts = ', '.join(f'{reason} {n}' for reason, n in refused.items()
                               if n and reason != 'total')
            response.success = False
            response.message = (
                f'Nothing has been accepted yet on {self._input_topics()} '
                f"({refused['total']} input(s) refused{': ' + counts if counts else ''}).")
            return response
        stamp = latest.header.stamp
        data = {'source': latest.source.topic,
                'source_type': latest.source.type_name,
                'stamp': {'sec': stamp.sec, 'nanosec': stamp.nanosec},
                'frame_id': latest.header.frame_id}
        data.update(transform_report(latest.R, latest.b, latest.settings.euler_sequence,
                                     latest.settings.degrees))
        data['refused'] = refused
        response.success = True
        response.message = to_yaml(data)
        return response

    def _on_screw_path(self, request, response):
        """Constant-screw motion start → goal, poses at most ``tolerance`` apart."""
        start, goal = request.start, request.goal
        response.plan.header = start.header
        try:
            if start.header.frame_id != goal.header.frame_id:
                raise messages.RefusedInput(
                    FRAME_MISMATCH, f'start is in frame {start.header.frame_id!r}, goal in '
                    f'{goal.header.frame_id!r}')
            q_tol = self._settings.quaternion_tolerance
            R0, b0 = messages.pose_to_rt(start.pose, q_tol, 'start.pose')
            R1, b1 = messages.pose_to_rt(goal.pose, q_tol, 'goal.pose')
            with np.errstate(all='ignore'):
                steps = self._path_steps(R0, b0, R1, b1, request.tolerance)
                Rs, bs = screw_interpolate(R0, b0, R1, b1, np.linspace(0.0, 1.0, steps + 1),
                                           check=False)
            if not (np.isfinite(Rs).all() and np.isfinite(bs).all()):
                raise messages.RefusedInput(NOT_DECOMPOSABLE, 'values too large to interpolate')
        except messages.RefusedInput as exc:
            self._refused[exc.reason] += 1
            self.get_logger().error(f'refused request on {self._screw_path_name} '
                                    f'({exc.reason}): {exc}', throttle_duration_sec=1.0)
            return response
        response.plan = messages.path_msg(start.header, start, goal, Rs, bs)
        return response

    @staticmethod
    def _path_steps(R0, b0, R1, b1, tolerance):
        """Return the number of equal steps keeping consecutive poses ``tolerance`` apart.

        The relative motion T0⁻¹T1 is a screw: angle θ about an axis at distance r from the
        origin of the start frame, translation d along it. Split into n equal steps, each
        turns θ/n, and the origin moves along a helix by a chord ≤ √((rθ)² + d²)/n.
        tolerance ≤ 0 means DEFAULT_PATH_STEPS; NaN, or one needing more than MAX_PATH_STEPS,
        raises RefusedInput.
        """
        if math.isnan(tolerance):
            raise messages.RefusedInput(BAD_TOLERANCE, 'tolerance is NaN')
        if tolerance <= 0.0:
            return DEFAULT_PATH_STEPS
        screw = screw_from_transform(R0.T @ R1, R0.T @ (b1 - b0), check=False)
        theta = float(screw.angle)
        arc = math.hypot(float(np.linalg.norm(screw.point)) * theta, float(screw.translation))
        need = max(theta, arc) / tolerance
        if not need <= MAX_PATH_STEPS:
            raise messages.RefusedInput(
                PATH_TOO_LONG, f'tolerance {tolerance:g} needs {need:.3g} steps, more than '
                f'{MAX_PATH_STEPS}')
        return max(1, math.ceil(need - 1e-9))  # 4 + rounding noise is 4 steps, not 5


SPIN_TIMEOUT = 0.1
"""Seconds one spin_once waits at most: the longest a shutdown waits for the loop to notice."""

BURST = 10
"""Messages taken from one subscription per wake-up at most (the inputs keep the last 10)."""


class WaitSetExecutor(Executor):
    """A lean single-threaded executor: one wait set, services first, bounded bursts.

    Each spin_once waits on every entity of its nodes (subscriptions, services, timers, QoS
    events, its own guard conditions) and then serves what is ready: timers, every waiting
    service request, QoS events, and at most BURST messages of each ready subscription —
    taken one at a time from the middleware's queue and handed straight to the callback.

    Why not rclpy's executors (bench/README.md has the figures):

    - ``rclpy.experimental.EventsExecutor`` queues one event per arriving message with no
      bound. Under a flood beyond the node's pace the queue grew by ~160 MB a minute, stayed
      at its size afterwards, and a service request waited behind the whole queue (up to
      16 s; some never answered).
    - The default SingleThreadedExecutor is fair and bounded — nothing waits outside the
      middleware's keep-last queues — but wraps every callback in a Task and rebuilds its
      wait set in ~60 lines of Python per message: about 2.4 × the CPU per message.

    This one keeps the middleware's bound (keep-last 10 per input: a flood costs lost
    messages, never memory), answers a service within one burst per subscription, and
    costs about what the EventsExecutor does per message. Single-threaded, synchronous
    callbacks only: a node with clients, guard conditions or coroutine callbacks is refused
    (rotation_node has none), and so is create_task.
    """

    def __init__(self, *, context=None, burst=BURST):
        super().__init__(context=context)
        self._burst = burst
        self._wait_set = None
        self._wait_set_size = None

    def create_task(self, callback, *args, **kwargs):
        raise NotImplementedError(f'{type(self).__name__} runs no tasks')

    def spin_once(self, timeout_sec=None):
        """Wait at most ``timeout_sec`` for work; serve everything ready once."""
        if self._is_shutdown:
            return
        subscriptions, services, timers, waitables = [], [], [], []
        for node in self.get_nodes():
            if list(node.clients) or list(node.guards):
                raise RuntimeError(f'{type(self).__name__} serves no clients or guard '
                                   f'conditions ({node.get_fully_qualified_name()} has some)')
            subscriptions.extend(node.subscriptions)
            services.extend(node.services)
            timers.extend(node.timers)
            waitables.extend(node.waitables)
        guards = [self._guard, self._sigint_gc]
        with ExitStack() as in_use:  # nothing is destroyed while the wait set holds it
            subscriptions = _in_use(in_use, subscriptions)
            services = _in_use(in_use, services)
            timers = _in_use(in_use, timers)
            guards = _in_use(in_use, guards)
            events = 0
            for waitable in list(waitables):
                try:
                    in_use.enter_context(waitable)
                except InvalidHandle:
                    waitables.remove(waitable)
                else:
                    events += waitable.get_num_entities().num_events
            in_use.enter_context(self._context.handle)
            wait_set = self._prepare_wait_set(
                len(subscriptions), len(guards), len(timers), len(services), events)
            for sub in subscriptions:
                wait_set.add_subscription(sub.handle)
            for srv in services:
                wait_set.add_service(srv.handle)
            for timer in timers:
                wait_set.add_timer(timer.handle)
            for guard in guards:
                wait_set.add_guard_condition(guard.handle)
            for waitable in waitables:
                waitable.add_to_wait_set(wait_set)

            wait_set.wait(timeout_sec_to_nsec(timeout_sec))
            if self._is_shutdown:
                return
            if not self._context.ok():
                raise ExternalShutdownException()

            ready = set(wait_set.get_ready_entities('timer'))
            for timer in timers:
                if timer.handle.pointer in ready and timer.handle.is_timer_ready():
                    timer.handle.call_timer()
                    timer.callback()
            ready = set(wait_set.get_ready_entities('service'))
            for srv in services:
                if srv.handle.pointer in ready:
                    _serve_requests(srv)
            for waitable in waitables:
                if waitable.is_ready(wait_set):
                    _run_now(waitable.execute(waitable.take_data()))
            ready = set(wait_set.get_ready_entities('subscription'))
            for sub in subscriptions:
                if sub.handle.pointer in ready:
                    self._take_messages(sub)

    def _prepare_wait_set(self, subscriptions, guards, timers, services, events):
        """Return the wait set for these counts of entities, cleared (reused while they stay)."""
        size = (subscriptions, guards, timers, 0, services, events)
        if size != self._wait_set_size:
            self._wait_set = _rclpy.WaitSet(*size, self._context.handle)
            self._wait_set_size = size
        self._wait_set.clear_entities()
        return self._wait_set

    def _take_messages(self, sub):
        """Hand at most BURST queued messages of ``sub`` to its callback, one at a time."""
        take, msg_type, raw, callback = sub.handle.take_message, sub.msg_type, sub.raw, \
            sub.callback
        message_only = sub._callback_type is Subscription.CallbackType.MessageOnly
        for _ in range(self._burst):
            taken = take(msg_type, raw)
            if taken is None:
                return
            if message_only:
                callback(taken[0])
            else:
                callback(*taken)


def _in_use(stack, entities):
    """Return the entities whose handle could be entered on ``stack`` (not the destroyed)."""
    usable = []
    for entity in entities:
        try:
            stack.enter_context(entity.handle)
        except InvalidHandle:
            continue
        usable.append(entity)
    return usable


def _serve_requests(srv):
    """Answer every request waiting on service ``srv``."""
    while True:
        request, header = srv.handle.service_take_request(srv.srv_type.Request)
        if header is None:
            return
        srv.send_response(srv.callback(request, srv.srv_type.Response()), header)


def _run_now(coroutine):
    """Run a coroutine that never suspends (a waitable's execute of a plain callback)."""
    try:
        coroutine.send(None)
    except StopIteration:
        return
    coroutine.close()
    raise RuntimeError('a waitable awaited something; WaitSetExecutor runs no tasks')


def make_executor(context=None):
    """Return the executor rotation_node runs on: a WaitSetExecutor (its docstring says why)."""
    return WaitSetExecutor(context=context)


def _guarded(callback, node, what, service=False):
    """callback(*args), but an exception it raises is logged (with its traceback) instead.

    A subscription or timer callback then returns None; a service callback (``service``)
    returns the response it was given, unfilled, so that the client gets a reply. Once the
    context is shut down (a signal: rclpy shuts it down from its handler, while a callback
    may be publishing) a failure is the shutdown's and is not logged. The wrapper has the
    callback's signature (rclpy inspects it).
    """
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
    """Wrap every subscription, timer and service callback of ``node`` in _guarded.

    A callback that raises is then logged and the node keeps serving, on either executor
    (the EventsExecutor would lose the subscription's other queued messages, the default
    one would end the spin).
    """
    for sub in node.subscriptions:
        sub.callback = _guarded(sub.callback, node, f'subscription {sub.topic_name}')
    for timer in node.timers:
        timer.callback = _guarded(timer.callback, node, 'timer')
    for srv in node.services:
        srv.callback = _guarded(srv.callback, node, f'service {srv.srv_name}', service=True)


def spin(node, executor):
    """Spin ``node`` on ``executor`` until the context shuts down (a signal), then stop it.

    The node's callbacks are guarded first (guard_callbacks). rclpy.init installs handlers
    that shut the context down on SIGINT and SIGTERM; the loop then ends within one
    SPIN_TIMEOUT (rclpy.spin could hang on a signal).
    """
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
    """Build a node, spin it until a signal, destroy it and shut rclpy down.

    The node is make_node(), the executor executor_factory(); rclpy.init is the caller's.
    A signal during the build is a normal stop; any other exception of the build (an
    invalid parameter) is raised after the clean-up.
    """
    node = None
    try:
        node = make_node()
        # What exists now (modules, the node) lives as long as the process: left out of
        # the collector's full passes, which otherwise stall a message by ~15 ms every few
        # seconds under load (the tail of the latency).
        gc.freeze()
        spin(node, executor_factory())
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


def main(args=None):
    """Run the node until SIGINT / SIGTERM; exit status 0, or 2 for an invalid parameter."""
    rclpy.init(args=args)
    try:
        serve(RotationNode)
    except (InvalidParameterTypeException, InvalidParameterValueException) as exc:
        print(f'rotation_node: {exc}', file=sys.stderr)
        return 2
    return 0


if __name__ == '__main__':
    from rot_tools.entry import exit_now
    exit_now(main())
