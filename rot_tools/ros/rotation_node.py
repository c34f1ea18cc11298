"""
rotation_node: orientations and poses republished as matrix, quaternion, Euler, screw.

Every input kind is one row of :data:`INPUTS` — topic, message type, reader, converter — and
every message becomes one rigid transform (header, R, b) at the boundary: its bytes read by
rot_tools.io.cdr (a raw subscription), its fields converted by rot_tools.io.boundary.
From there one path serves them all: one pass of the decomposition kernels
(rot_tools.core.decomposition.decompose_values) gives every number published — rotation
vector θ·l̂,
Euler angles, twist (θ·l̂, θ·m + d·l̂) = screw_log, and the quaternion (matrix_to_quaternion
of R) — and the picture's decomposition runs the same kernels, so at θ = π all outputs of
one input share the axis sign. Outputs carry the input's header. Topics, services and
parameters: doc/node.md, and ``rotation_node --help``.

The pictures (~/markers and ~/screw_axis, rot_tools.io.drawing) cost several times the rest of
an input's work, so they are throttled: at most MARKER_RATE a second, the latest input wins,
and the last input is always drawn. A timer callback draws them, never an input's callback.
"""

if __name__ == '__main__':
    # ``python -m rot_tools.ros.rotation_node`` starts like the console script: the signal
    # handlers first, then this module imported by its name (NumPy and rclpy load then),
    # then main (rot_tools.ros.runtime.start, which never returns).
    from rot_tools.ros.runtime import start
    start('rot_tools.ros.rotation_node')

import difflib
from functools import partial
import math
from operator import attrgetter
import sys
import textwrap
import time
from typing import Callable, NamedTuple

from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped, QuaternionStamped
from geometry_msgs.msg import TransformStamped, TwistStamped, Vector3Stamped
from nav_msgs.msg import Odometry
from nav_msgs.srv import GetPlan
import numpy as np
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
from rcl_interfaces.msg import SetParametersResult
from rclpy.clock import Clock, ClockType
from rclpy.exceptions import InvalidParameterValueException
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import qos_profile_sensor_data, QoSProfile
from rot_tools.core.decomposition import decompose_values
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import EULER_SEQUENCES
from rot_tools.core.screw import screw_from_transform, screw_interpolate
from rot_tools.io import cdr, drawing
from rot_tools.io.report import sequence_hint, to_yaml, transform_report
from rot_tools.ros import messages, runtime, tf_input
from rot_tools.ros.service_host import ServiceHost
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray, Header
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker, MarkerArray

FRAME_MISMATCH = 'frame_mismatch'
BAD_TOLERANCE = 'bad_tolerance'
PATH_TOO_LONG = 'path_too_long'
NOT_DECOMPOSABLE = 'not_decomposable'
MALFORMED = 'malformed'
REFUSAL_REASONS = messages.REFUSAL_REASONS + (
    MALFORMED, NOT_DECOMPOSABLE, FRAME_MISMATCH, BAD_TOLERANCE, PATH_TOO_LONG
) + tf_input.REFUSAL_REASONS
"""Every reason an input is refused for, in the order ~/describe lists the counts."""

DEFAULT_PATH_STEPS = 20
"""Steps of ~/screw_path when the request's tolerance is ≤ 0 (21 poses)."""

MAX_PATH_STEPS = 10_000
"""A tolerance that needs more steps than this is refused (the reply would be huge)."""

MAX_REPLY_BYTES = 16_000_000
"""Largest ~/screw_path reply (serialised bytes); beyond it the request is path_too_long."""

REPLY_BYTES_PER_POSE = 80
"""Serialised bytes of one PoseStamped of a reply, besides its frame_id: stamp 8, string
length 4 and terminating NUL 1, alignment of the pose at most 7, pose 7 × 8 = 56 (76; the
Path's header, sequence length and encapsulation fit in one more)."""

MARKER_RATE = 30.0
"""Most pictures (~/markers with ~/screw_axis) a second: RViz draws 30 frames a second."""

PROG = 'rotation_node'
"""The program's name in its messages."""

MAX_REFUSAL_TEXT = 400
"""Longest refusal sentence ~/describe repeats (a refused frame_id may be megabytes)."""

MIN_MARKER_SCALE = 1e-6
"""Smallest marker_scale (m): the arrows' shafts are 5 % of it, and RViz draws nothing of
a zero width (5e-324 was accepted once)."""

WARM_UP_ROTATION = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
WARM_UP_TRANSLATION = np.array([0.0, 0.0, 1.0])
"""The screw motion drawn (and not published) at start-up: a quarter turn about z, 1 m up."""

REFUSAL_WARNING_PERIOD = 1.0
"""Seconds between two warnings about refused inputs of one topic for one reason."""


class InputKind(NamedTuple):
    """One kind of input: where it arrives, its type, and how it becomes (header, R, b)."""

    topic: str
    msg_type: type
    read: Callable
    """read(data) -> (header, fields): the message's bytes read (rot_tools.io.cdr.stamped_reader:
    the strings skipped and the float64 read after the header); raises cdr.Malformed."""
    convert: Callable
    """convert(fields, settings) -> (R, b); raises messages.RefusedInput."""


_POSE = cdr.stamped_reader(0, 7)  # pose (position, orientation), from any Pose after the header
_CHILD_AND_POSE = cdr.stamped_reader(1, 7)  # child_frame_id, then a Pose or a Transform
INPUTS = (
    InputKind('~/pose', PoseStamped, _POSE, messages.pose_fields_to_rt),
    InputKind('~/euler', Vector3Stamped, cdr.stamped_reader(0, 3), messages.euler_fields_to_rt),
    InputKind('~/transform', TransformStamped, _CHILD_AND_POSE,
              messages.transform_fields_to_rt),
    InputKind('~/pose_with_covariance', PoseWithCovarianceStamped, _POSE,
              messages.pose_pose_fields_to_rt),
    InputKind('~/odometry', Odometry, _CHILD_AND_POSE, messages.pose_pose_fields_to_rt),
    InputKind('~/imu', Imu, cdr.stamped_reader(0, 5), messages.imu_fields_to_rt),  # + cov[0]
    InputKind('~/orientation', QuaternionStamped, cdr.stamped_reader(0, 4),
              messages.quaternion_fields_to_rt),
)
"""Every input of the node; each joins the one path (header, R, b) → outputs."""


class OutputKind(NamedTuple):
    """One output published for every accepted input: topic, type, and what fills it."""

    topic: str
    msg_type: type
    value: str
    """The field of rot_tools.core.decomposition.Values the message carries."""
    encode: Callable
    """encode(head, value) -> the message's serialised bytes (rot_tools.io.cdr; ``head`` is
    cdr.header of the input's header)."""
    angles: bool = False
    """The value is angles, published in angle_unit (the Values are in radians)."""


_VECTOR3_STAMPED = cdr.stamped(3)
OUTPUTS = (
    OutputKind('~/rotation_matrix', Float64MultiArray, 'matrix',
               cdr.float64_multi_array(messages.MATRIX_DIMS)),
    OutputKind('~/quaternion', QuaternionStamped, 'quaternion', cdr.stamped(4)),
    OutputKind('~/axis_angle', Vector3Stamped, 'rotvec', _VECTOR3_STAMPED),
    OutputKind('~/euler_angles', Vector3Stamped, 'euler', _VECTOR3_STAMPED, angles=True),
    OutputKind('~/rpy', Vector3Stamped, 'rpy', _VECTOR3_STAMPED, angles=True),
    OutputKind('~/screw', TwistStamped, 'twist', cdr.stamped(6, order=(3, 4, 5, 0, 1, 2))),
)
"""Every output published for each accepted input, from one decompose_values pass; a new
output is a row here and its field of Values (its kernel output). The messages are written
as bytes (rot_tools.io.cdr: a third of the cost of rclpy's conversion of a message object).
The pictures (~/markers, ~/screw_axis) are not rows: they are drawn at most MARKER_RATE
times a second."""


class Source(NamedTuple):
    """An input subscription as the callbacks see it: topic (resolved), type name, InputKind's."""

    topic: str
    type_name: str
    read: Callable
    convert: Callable


class Settings(NamedTuple):
    """The parameters as the callbacks use them; replaced whole when a parameter changes."""

    euler_sequence: str
    degrees: bool
    quaternion_tolerance: float
    publish_markers: bool
    marker_scale: float
    tf_reference_frame: str
    tf_body_frame: str


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


def _check_sequence(value):
    if value in EULER_SEQUENCES:
        return ''
    return (f'euler_sequence {value!r} is not a sequence: use one of '
            + ' '.join(EULER_SEQUENCES) + sequence_hint(value))


def _check_angle_unit(value):
    return '' if value in ('rad', 'deg') else f"angle_unit {value!r} is not 'rad' or 'deg'"


def _check_tolerance(value):
    if math.isfinite(value) and value >= 0.0:
        return ''
    return f'quaternion_tolerance must be finite and >= 0, got {value}'


def _check_marker_scale(value):
    if math.isfinite(value) and value >= MIN_MARKER_SCALE:
        return ''
    return (f'marker_scale must be finite and >= {MIN_MARKER_SCALE:g} m (thinner arrows are '
            f'not drawn), got {value}')


def _check_tf_frame(value):
    return tf_input.tf2_msgs_missing() if value else ''


def _any_value(value):
    return ''


class ParameterSpec(NamedTuple):
    """One parameter of the node: default, descriptor, and the check of its values."""

    default: object
    descriptor: ParameterDescriptor
    check: Callable = _any_value
    """check(value) -> '' when valid, else why not (rclpy has checked the type and range)."""


PARAMETERS = {
    'euler_sequence': ParameterSpec('ZYX', _descriptor(
        ParameterType.PARAMETER_STRING,
        'Euler sequence of ~/euler input and ~/euler_angles output: upper case intrinsic '
        '(ZYX: R = Rot_z(θ1) Rot_y(θ2) Rot_x(θ3)), lower case extrinsic',
        'one of ' + ' '.join(EULER_SEQUENCES)), _check_sequence),
    'angle_unit': ParameterSpec('rad', _descriptor(
        ParameterType.PARAMETER_STRING,
        'unit of the angles of ~/euler, ~/euler_angles and ~/rpy', "'rad' or 'deg'"),
        _check_angle_unit),
    'quaternion_tolerance': ParameterSpec(1e-3, _descriptor(
        ParameterType.PARAMETER_DOUBLE,
        'largest |‖q‖ − 1| of an input quaternion; within it q is normalised, beyond it the '
        'message is refused', '>= 0, finite',
        FloatingPointRange(from_value=0.0, to_value=math.inf, step=0.0)), _check_tolerance),
    'publish_markers': ParameterSpec(True, _descriptor(
        ParameterType.PARAMETER_BOOL,
        f'publish the picture of each input (at most {MARKER_RATE:g} a second, the latest '
        "wins): the moved frame's axes, screw axis, helical path and label on ~/markers "
        '(MarkerArray) and the screw axis arrow on ~/screw_axis (Marker); switching it off '
        'deletes both')),
    'marker_scale': ParameterSpec(1.0, _descriptor(
        ParameterType.PARAMETER_DOUBLE,
        'length of the frame axes on ~/markers and of the ~/screw_axis arrow (m)',
        f'>= {MIN_MARKER_SCALE:g}, finite',
        FloatingPointRange(from_value=MIN_MARKER_SCALE, to_value=math.inf, step=0.0)),
        _check_marker_scale),
    'tf_reference_frame': ParameterSpec('', _descriptor(
        ParameterType.PARAMETER_STRING,
        'with tf_body_frame: follow the transform of tf_body_frame in this frame on /tf and '
        '/tf_static, publishing every output at each new common time of the chain '
        "(header.frame_id = this frame); '' = off"), _check_tf_frame),
    'tf_body_frame': ParameterSpec('', _descriptor(
        ParameterType.PARAMETER_STRING,
        "with tf_reference_frame: the frame followed on /tf and /tf_static; '' = off"),
        _check_tf_frame),
}
"""Every parameter of the node, by name. A new one is a row here and a field of Settings."""


class RotationNode(Node):
    """Subscribes to every input of INPUTS and republishes their decompositions."""

    def __init__(self, node_name='rot_tools', *, services_apart=False, **kwargs):
        """
        Build the node; ``services_apart``: serve its services from a participant of their own.

        With ``services_apart`` (how ``main`` runs it) the services and parameter services
        live on a hidden node of a second context (rot_tools.ros.service_host), listed in
        ``companions``: whoever spins this node spins those too (rot_tools.ros.runtime.spin).
        """
        super().__init__(node_name, **kwargs)
        self._service_host = None
        try:
            self._declare_parameters()
        except Exception:
            self.destroy_node()
            raise
        self._warn_about_unknown_overrides()
        self._settings = self._read_settings()
        self.add_pre_set_parameters_callback(self._integers_as_doubles)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)

        self._refused = dict.fromkeys(REFUSAL_REASONS, 0)
        self._last_refusals = {}  # reason: (topic, header or None, text) of the latest
        self._warned = {}  # (topic, reason): time.monotonic() of its last warning
        self._latest = None

        # For each output: its publish, encode, its Values field getter and whether it is
        # angles (the hot path).
        qos = QoSProfile(depth=10)
        self._outputs = tuple(
            (self.create_publisher(kind.msg_type, kind.topic, qos).publish, kind.encode,
             attrgetter(kind.value), kind.angles)
            for kind in OUTPUTS)
        self._marker_pub = self.create_publisher(Marker, '~/screw_axis', qos)
        self._markers_pub = self.create_publisher(MarkerArray, '~/markers', qos)
        self._picture_due = None  # the arguments of the latest drawing not yet published
        self._picture_shown = None  # the header of the picture on show (ADDs), or None
        self._picture_sent = -math.inf  # time.monotonic() of the last one published
        # Pictures are drawn by a timer callback, never inside an input's: the next one a
        # MARKER_RATE period after the last (_picture_timer), or at once when that has
        # passed (_picture_soon, period 0: due on the executor's next pass).
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._picture_timer = self.create_timer(
            1.0 / MARKER_RATE, self._publish_picture, clock=steady, autostart=False)
        self._picture_soon = self.create_timer(
            0.0, self._publish_picture, clock=steady, autostart=False)
        self._warm_up_picture()

        # The TF tree: one more way of getting (header, R, b), beside the rows of INPUTS (it
        # needs a tree between messages, two topics with their own QoS, and gives an output
        # only when the chain has a new common time; rot_tools.ros.tf_input).
        self._tf = tf_input.TfFollower(self, self._on_tf_transform, self._refuse,
                                       quaternion_tolerance=self._settings.quaternion_tolerance)
        self._tf_source = Source(self._tf.topic, tf_input.TYPE_NAME, None, None)
        self._tf.follow(self._settings.tf_reference_frame, self._settings.tf_body_frame)

        self._sources = []
        for kind in INPUTS:
            source = Source(self.resolve_topic_name(kind.topic),
                            messages.type_name(kind.msg_type), kind.read, kind.convert)
            # raw: the callback gets the message's bytes (rot_tools.io.cdr reads what it needs)
            self.create_subscription(kind.msg_type, kind.topic, partial(self._on_input, source),
                                     qos_profile_sensor_data, raw=True)
            self._sources.append(source)

        host = self
        if services_apart:
            host = self._service_host = ServiceHost(self)
        host.create_service(Trigger, '~/describe', self._on_describe)
        host.create_service(GetPlan, '~/screw_path', self._on_screw_path)
        self._screw_path_name = self.resolve_service_name('~/screw_path')
        self.get_logger().info(
            f'decomposing {self._input_topics()} (euler_sequence '
            f'{self._settings.euler_sequence}, angle_unit '
            f"{'deg' if self._settings.degrees else 'rad'})")

    @property
    def companions(self):
        """Return the nodes to spin with this one: the hidden node of its services, if any."""
        return () if self._service_host is None else (self._service_host.node,)

    def destroy_node(self):
        """Destroy the node, and the hidden node serving its services apart (if any)."""
        if self._service_host is not None:
            self._service_host.destroy()
            self._service_host = None
        super().destroy_node()

    def _input_topics(self):
        """'/n/pose, /n/euler or /n/transform': the input topics as remapped."""
        topics = [source.topic for source in self._sources]
        if self._tf.following:
            topics.append(f'{self._tf.topic} ({self._tf.reference} ← {self._tf.body})')
        return ', '.join(topics[:-1]) + ' or ' + topics[-1]

    # -- parameters --------------------------------------------------------------------

    def _declare_parameters(self):
        """Declare PARAMETERS; check the start-up overrides (InvalidParameterValueException)."""
        overrides = getattr(self, '_parameter_overrides', {})  # (see the method below)
        for name, override in overrides.items():  # `marker_scale: 3` in a file, -p ...:=3
            if name in PARAMETERS:
                (overrides[name],) = self._integers_as_doubles([override])
        for name, spec in PARAMETERS.items():
            self.declare_parameter(name, spec.default, spec.descriptor)
        for name, spec in PARAMETERS.items():
            value = self.get_parameter(name).value
            reason = spec.check(value)
            if reason:
                raise InvalidParameterValueException(name, value, reason)

    @staticmethod
    def _integers_as_doubles(parameters):
        """
        Return the parameters, with an integer value of a double parameter made a double.

        rclpy types a parameter by its value: ``marker_scale: 3`` in a YAML file, ``-p
        marker_scale:=3`` or ``ros2 param set ... marker_scale 3`` is an integer, which a
        double parameter refuses. Run before rclpy's type check (a pre-set callback, and on
        the start-up overrides).
        """
        converted = []
        for parameter in parameters:
            spec = PARAMETERS.get(parameter.name)
            if (spec is not None and parameter.type_ == Parameter.Type.INTEGER
                    and spec.descriptor.type == ParameterType.PARAMETER_DOUBLE):
                parameter = Parameter(parameter.name, Parameter.Type.DOUBLE,
                                      float(parameter.value))
            converted.append(parameter)
        return converted

    def _read_settings(self):
        value = {name: self.get_parameter(name).value for name in PARAMETERS}
        return Settings(value['euler_sequence'], value['angle_unit'] == 'deg',
                        value['quaternion_tolerance'], value['publish_markers'],
                        value['marker_scale'], value['tf_reference_frame'],
                        value['tf_body_frame'])

    def _on_set_parameters(self, parameters):
        """Refuse invalid values of our parameters (rclpy has checked type and range)."""
        for parameter in parameters:
            spec = PARAMETERS.get(parameter.name)
            if spec is not None:
                reason = spec.check(parameter.value)
                if reason:
                    return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    def _on_parameters_set(self, parameters):
        """Take the new values into use from the next message; publish_markers off clears."""
        if any(parameter.name in PARAMETERS for parameter in parameters):
            was_drawing = self._settings.publish_markers
            old, self._settings = self._settings, self._read_settings()
            if was_drawing and not self._settings.publish_markers:
                self._clear_picture()
            new = self._settings
            self._tf.set_quaternion_tolerance(new.quaternion_tolerance)
            frames = (new.tf_reference_frame, new.tf_body_frame)
            if frames != (old.tf_reference_frame, old.tf_body_frame):
                self._tf.follow(*frames)
                self.get_logger().info(
                    f'following {frames[1]!r} in {frames[0]!r} on {self._tf.topic}'
                    if self._tf.following else f'not following frames on {self._tf.topic}')

    def _warn_about_unknown_overrides(self):
        """
        Warn about each start-up override (-p, --params-file) that names no parameter.

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

    def _on_input(self, source, data):
        """Read one message's bytes to (header, R, b) and publish every output, or refuse it."""
        settings = self._settings
        try:
            header, fields = source.read(data)
        except cdr.Malformed as exc:
            self._refuse(source.topic, MALFORMED, f'not a {source.type_name}: {exc}')
            return
        try:
            R, b = source.convert(fields, settings)
            # Every number published, as plain floats from the generated kernels (the hot
            # path: decompose's arrays cost more than the math); the picture's
            # decomposition is left to the drawing, at most MARKER_RATE times a second.
            values = decompose_values(R, b, settings.euler_sequence)
        except messages.RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc), header=header)
            return
        except RotationError as exc:
            self._refuse(source.topic, NOT_DECOMPOSABLE, str(exc), header=header)
            return
        self._publish(source, header, R, b, values, settings)

    def _on_tf_transform(self, header, R, b):
        """Return the followed frames have a new common time on /tf: publish every output."""
        settings = self._settings
        try:
            values = decompose_values(R, b, settings.euler_sequence)
        except RotationError as exc:
            self._refuse(self._tf_source.topic, NOT_DECOMPOSABLE, str(exc))
            return
        self._publish(self._tf_source, header, R, b, values, settings)

    def _publish(self, source, header, R, b, values, settings):
        """Every output of one accepted input (header, R, b), ``values`` its decomposition."""
        degrees = settings.degrees
        stamp = header.stamp
        head = cdr.header(stamp.sec, stamp.nanosec, header.frame_id)
        for publish, encode, value_of, angles in self._outputs:
            value = value_of(values)
            if angles and degrees:
                value = tuple(map(math.degrees, value))
            publish(encode(head, value))
        if settings.publish_markers:
            self._offer_picture(header, R, b, settings)
        self._latest = Latest(source, header, R, b, settings)

    def _refuse(self, topic, reason, text, error=False, header=None):
        """
        Count a refused input; warn at most once a REFUSAL_WARNING_PERIOD per (topic, reason).

        Not rclpy's throttle_duration_sec: it throttles per call site, so one fast bad
        stream (a raw IMU without orientation at 50 Hz) would silence every other one.
        ``error``: log at error level (a refused service request). The refusal is kept as
        the latest of its reason for ~/describe (``header``: the refused message's).
        """
        self._refused[reason] += 1
        self._last_refusals[reason] = (topic, header, text)
        now = time.monotonic()
        if now - self._warned.get((topic, reason), -math.inf) >= REFUSAL_WARNING_PERIOD:
            self._warned[topic, reason] = now
            log = self.get_logger().error if error else self.get_logger().warning
            log(f'refused input on {topic} ({reason}): {text}')

    # -- markers -----------------------------------------------------------------------

    def _offer_picture(self, header, R, b, settings):
        """
        Have the picture of this input drawn next, as soon as MARKER_RATE allows it.

        An input that arrives while a drawing is due replaces the one waiting: the latest
        wins, and the last input is always drawn.
        """
        self._picture_due = (header, R, b, settings)
        if not (self._picture_timer.is_canceled() and self._picture_soon.is_canceled()):
            return
        if time.monotonic() - self._picture_sent >= 1.0 / MARKER_RATE:
            self._picture_soon.reset()  # due at once
        else:
            self._picture_timer.reset()  # fires one period from now

    def _publish_picture(self):
        """~/markers and ~/screw_axis of the input waiting (DELETEs for the identity)."""
        self._picture_timer.cancel()
        self._picture_soon.cancel()
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
            header, picture.screw.point, picture.screw.direction, settings.marker_scale))

    def _warm_up_picture(self):
        """
        Draw one picture and build its messages, publishing nothing.

        The first drawing of a process pays for one-off work (NumPy's first calls): a few
        ms, paid here at start-up instead of inside the callback of the first input.
        """
        header = Header()
        picture = drawing.picture(WARM_UP_ROTATION, WARM_UP_TRANSLATION, 1.0, False)
        messages.picture_markers(header, picture)
        messages.screw_axis_marker(header, picture.screw.point, picture.screw.direction, 1.0)
        messages.delete_picture_markers(header)
        messages.delete_marker(header, messages.SCREW_AXIS_NS, 0)

    def _delete_picture(self, header):
        """DELETE every marker of ~/markers and ~/screw_axis, in ``header``'s frame."""
        self._picture_shown = None
        self._markers_pub.publish(messages.delete_picture_markers(header))
        self._marker_pub.publish(messages.delete_marker(header, messages.SCREW_AXIS_NS, 0))

    def _clear_picture(self):
        """
        publish_markers was switched off: drop the picture waiting, delete the one shown.

        The DELETEs go once, in the frame of the last picture drawn; nothing is sent when
        nothing is shown (none drawn yet, or the last input was the identity).
        """
        self._picture_timer.cancel()
        self._picture_soon.cancel()
        self._picture_due = None
        if self._picture_shown is not None:
            self._delete_picture(self._picture_shown)

    # -- services ----------------------------------------------------------------------

    def refused_counts(self):
        """{'total': N, reason: n, ...} of the inputs refused so far."""
        return {'total': sum(self._refused.values()), **self._refused}

    def last_refusals(self):
        """
        {reason: {source, stamp, message}} of the latest refusal of each reason so far.

        In REFUSAL_REASONS order, only the reasons counted; ``stamp`` only when the refused
        message had a header; ``message`` is the refusal's sentence (what and by how much),
        cut to MAX_REFUSAL_TEXT characters.
        """
        latest = {}
        for reason in REFUSAL_REASONS:
            if reason not in self._last_refusals:
                continue
            topic, header, text = self._last_refusals[reason]
            entry = {'source': topic}
            if header is not None:
                entry['stamp'] = {'sec': header.stamp.sec, 'nanosec': header.stamp.nanosec}
            if len(text) > MAX_REFUSAL_TEXT:
                text = text[:MAX_REFUSAL_TEXT - 1] + '…'
            entry['message'] = text
            latest[reason] = entry
        return latest

    def _on_describe(self, request, response):
        """
        YAML report of the latest input (rot_tools.io.report), with the refusals' data.

        Always a YAML document ending in ``refused`` (the counts by reason) and
        ``last_refusals`` (last_refusals()). Before any accepted input ``success`` is false
        and the document starts with ``note``: a sentence saying so, for people.
        """
        refused = self.refused_counts()
        latest = self._latest
        if latest is None:
            total = refused['total']
            data = {'note': f'Nothing has been accepted yet on {self._input_topics()} '
                            f"({total} input{'' if total == 1 else 's'} refused)."}
            response.success = False
        else:
            stamp = latest.header.stamp
            data = {'source': latest.source.topic,
                    'source_type': latest.source.type_name,
                    'stamp': {'sec': stamp.sec, 'nanosec': stamp.nanosec},
                    'frame_id': latest.header.frame_id}
            data.update(transform_report(latest.R, latest.b, latest.settings.euler_sequence,
                                         latest.settings.degrees))
            if self._tf.following:
                data['tf'] = self._tf.describe()
            response.success = True
        data['refused'] = refused
        data['last_refusals'] = self.last_refusals()
        response.message = to_yaml(data)
        return response

    def _on_screw_path(self, request, response):
        """
        Constant-screw motion start → goal, poses at most ``tolerance`` apart.

        Every failure is a refusal: counted by reason, logged (throttled per reason), and
        answered with an empty path. The reply is bounded in bytes before it is built.
        """
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
                if not np.isfinite(R0.T @ (b1 - b0)).all():
                    raise messages.RefusedInput(
                        NOT_DECOMPOSABLE, 'start and goal are too far apart: goal.position '
                        '− start.position overflows float64 (beyond ±1.8e308)')
                steps = self._path_steps(R0, b0, R1, b1, request.tolerance)
                self._check_reply_bytes(start.header.frame_id, steps + 1)
                Rs, bs = screw_interpolate(R0, b0, R1, b1, np.linspace(0.0, 1.0, steps + 1),
                                           check=False)
            if not (np.isfinite(Rs).all() and np.isfinite(bs).all()):
                raise messages.RefusedInput(NOT_DECOMPOSABLE, 'values too large to interpolate')
            plan = messages.path_msg(start.header, start, goal, Rs, bs)
        except messages.RefusedInput as exc:
            self._refuse(self._screw_path_name, exc.reason, str(exc), error=True,
                         header=start.header)
            return response
        except (RotationError, ArithmeticError) as exc:  # no screw between start and goal
            self._refuse(self._screw_path_name, NOT_DECOMPOSABLE,
                         f'no screw motion from start to goal: {exc}', error=True,
                         header=start.header)
            return response
        response.plan = plan
        return response

    @staticmethod
    def _path_steps(R0, b0, R1, b1, tolerance):
        """
        Return the number of equal steps keeping consecutive poses ``tolerance`` apart.

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

    @staticmethod
    def _reply_bytes(frame_id, poses):
        """
        Return an upper bound of the serialised size of a GetPlan reply (CDR bytes).

        The path's header and each of its ``poses`` carries a copy of ``frame_id``:
        REPLY_BYTES_PER_POSE plus the frame_id's UTF-8 bytes each (the Path's own header
        and sequence length counted as one more pose).
        """
        size = len(frame_id.encode('utf-8', 'surrogatepass'))
        return (poses + 1) * (size + REPLY_BYTES_PER_POSE)

    @classmethod
    def _check_reply_bytes(cls, frame_id, poses):
        """
        Raise RefusedInput (path_too_long) if the reply would exceed MAX_REPLY_BYTES.

        Checked before anything is built: a 100 kB frame_id × 10,001 poses is a 1 GB
        reply, and the node would hold it twice (messages and their serialisation).
        """
        size = cls._reply_bytes(frame_id, poses)
        if size > MAX_REPLY_BYTES:
            frame_bytes = len(frame_id.encode('utf-8', 'surrogatepass'))
            raise messages.RefusedInput(
                PATH_TOO_LONG, f'a reply of {poses} poses with a frame_id of {frame_bytes} '
                f'bytes would take {size / 1e6:.3g} MB, more than {MAX_REPLY_BYTES / 1e6:g} MB')


def _rows(rows, width=99):
    """'  name  text' lines, the text wrapped under itself."""
    left = max(len(name) for name, _ in rows) + 4
    lines = []
    for name, text in rows:
        lines += textwrap.wrap(text, width, initial_indent=f'  {name:{left - 2}}',
                               subsequent_indent=' ' * left)
    return lines


def _default_text(value):
    return ('true' if value else 'false') if isinstance(value, bool) else str(value)


def usage():
    """Return the text of ``rotation_node --help``, from INPUTS, OUTPUTS and PARAMETERS."""
    inputs = [(kind.topic, messages.type_name(kind.msg_type)) for kind in INPUTS]
    outputs = [(kind.topic, messages.type_name(kind.msg_type)
                + (' (in angle_unit)' if kind.angles else '')) for kind in OUTPUTS]
    outputs += [('~/markers, ~/screw_axis', 'the picture of the motion (MarkerArray, Marker), '
                 f'when publish_markers, at most {MARKER_RATE:g} a second')]
    parameters = [(f'{name} = {_default_text(spec.default)}', spec.descriptor.description
                   + (f' ({spec.descriptor.additional_constraints})'
                      if spec.descriptor.additional_constraints else ''))
                  for name, spec in PARAMETERS.items()]
    return '\n'.join([
        f'usage: {PROG} [--help] [--version] [--ros-args ROS_ARGUMENT ...]', '',
        textwrap.fill(
            'A ROS 2 node: every input (an orientation or a pose) is turned into one rigid '
            'motion (R, b) and republished as rotation matrix, quaternion, rotation vector, '
            'Euler angles, roll/pitch/yaw and screw (Chasles) decomposition, with the '
            "input's header.", 99),
        '', 'inputs (subscribed, sensor-data QoS):', *_rows(inputs),
        '', 'outputs (for every accepted input, reliable, depth 10):', *_rows(outputs),
        '', 'services:', *_rows([('~/describe', "std_srvs/srv/Trigger: the latest input's "
                                  'report and the refusals, as YAML'),
                                 ('~/screw_path', 'nav_msgs/srv/GetPlan: the constant-screw '
                                  'motion from start to goal')]),
        '', 'parameters (-p NAME:=VALUE, --params-file FILE):', *_rows(parameters),
        '', 'examples:',
        f"  {PROG} --ros-args -r __ns:=/robot -r '~/imu:=/robot/imu/data' -p angle_unit:=deg",
        f'  {PROG} --ros-args --params-file rot_tools.yaml   (copied from share/rot_tools/'
        'config)',
        '  ros2 launch rot_tools rot_tools.launch.xml imu:=/robot/imu/data',
        '', "Quote a ~ that starts a word ('~/imu:=...'): the shell would expand it.",
        'The node and its interface are described in doc/node.md.', ''])


def main(args=None):
    """
    Run the node until SIGINT / SIGTERM; exit status 0, or 2 for bad arguments.

    ``args``: the whole command line as rclpy.init takes it, program name first (sys.argv
    when None). ``--help`` and ``--version`` print and return 0 before anything ROS
    starts; any other argument outside ``--ros-args`` is refused. Started by
    rot_tools.ros.runtime.start (the console script, ``python -m rot_tools.ros.rotation_node``),
    which handles an early signal and ends the process.
    """
    argv = sys.argv if args is None else list(args)
    options = runtime.user_arguments(argv)
    if '-h' in options or '--help' in options:
        print(usage(), end='')
        return 0
    if '--version' in options:
        print(runtime.program_version(PROG))
        return 0
    if options:
        runtime.fail(PROG, f'unknown argument {options[0]!r} (ROS arguments go after '
                     f'--ros-args; see {PROG} --help)')
    runtime.init_ros(PROG, argv)
    try:
        runtime.serve(partial(RotationNode, services_apart=True))
    except Exception as exc:  # noqa: BLE001 - bad ROS arguments are one line, exit 2
        text = runtime.ros_argument_error(exc)
        if text is None:
            raise
        runtime.fail(PROG, text)
    return 0
