"""
rotation_node: orientations and poses republished as matrix, quaternion, Euler, screw.

Every input and output is one row of rot_tools.io.interface — topic, message type, fields,
formula — and every message becomes one rigid transform (header, R, b) at the boundary: the
numbers at its row's field paths (rot_tools.ros.topics) converted by its row's formula
(rot_tools.io.boundary). From there one path serves them all: one decomposition, as Python
numbers (rot_tools.core.decomposition.decompose_one), gives every number published —
rotation vector θ·l̂, Euler angles, roll/pitch/yaw, twist (θ·l̂, θ·m + d·l̂) = screw_log and
the quaternion — each output row naming the field it publishes, and the picture's
decomposition runs the same kernels, so at θ = π all outputs of one input share the axis
sign. Outputs carry the input's header. Topics, services and parameters: doc/node.md, and
``rotation_node --help``.

The pictures (~/markers and ~/screw_axis) are throttled: rot_tools.ros.pictures. The reply of
~/screw_path: rot_tools.ros.screw_path. The covariance of roll, pitch and yaw of the inputs that
carry a covariance (~/rpy_covariance): rot_tools.ros.rpy_covariance.
"""

import difflib
from functools import partial, wraps
from importlib.metadata import PackageNotFoundError
import math
import os
import sys
import textwrap
import time
import traceback
from typing import Callable, NamedTuple

from nav_msgs.srv import GetPlan
import numpy as np
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
from rcl_interfaces.msg import SetParametersResult
import rclpy
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from rclpy.exceptions import InvalidParameterValueException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.logging import get_logger
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time_source import USE_SIM_TIME_NAME
from rclpy.type_description_service import START_TYPE_DESCRIPTION_SERVICE_PARAM
from rot_tools.core.decomposition import decompose_one
from rot_tools.core.errors import RotationError
from rot_tools.core.euler import EULER_SEQUENCES
from rot_tools.core.transform_tree import shown
from rot_tools.io import boundary
from rot_tools.io.arguments import version_line
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.io.report import sequence_hint, to_yaml, transform_report
from rot_tools.ros import diagnostics, rpy_covariance, runtime, screw_path, tf_input
from rot_tools.ros.pictures import (MARKER_RATE, Pictures, WARM_UP_ROTATION,
                                    WARM_UP_TRANSLATION)
from rot_tools.ros.screw_path import (BAD_TOLERANCE, FRAME_MISMATCH, NOT_DECOMPOSABLE,
                                      PATH_TOO_LONG)
from rot_tools.ros.topics import INPUTS, OUTPUTS
from std_srvs.srv import Trigger

REFUSAL_REASONS = boundary.REFUSAL_REASONS + (
    NOT_DECOMPOSABLE, FRAME_MISMATCH, BAD_TOLERANCE, PATH_TOO_LONG
) + tf_input.REFUSAL_REASONS + rpy_covariance.REFUSAL_REASONS
"""Every reason an input is refused for, in the order ~/describe lists the counts."""

PROG = 'rotation_node'
"""The program's name in its messages."""

MAX_REFUSAL_TEXT = 400
"""Longest refusal sentence ~/describe repeats (a refused frame_id may be megabytes)."""

MIN_MARKER_SCALE = 1e-6
"""Smallest marker_scale (m): the arrows' shafts are 5 % of it, and RViz draws nothing of
a zero width (5e-324 was accepted once)."""

REFUSAL_WARNING_PERIOD = 1.0
"""Seconds between two warnings about refused inputs of one topic for one reason."""


class Source(NamedTuple):
    """An input as the callbacks see it: topic (resolved), type name, its row's read, convert."""

    topic: str
    type_name: str
    read: Callable
    convert: Callable
    fields: dict
    covariance: rpy_covariance.Reader = None
    """How its covariance is read, for an input that carries one (~/rpy_covariance)."""


class Publishing(NamedTuple):
    """One output published for every input: its publisher's publish, message and writer."""

    publish: Callable
    message: object
    """The output's message, filled and published again for every input."""
    write: Callable
    """write(message, numbers): the numbers into the row's fields (rot_tools.ros.topics)."""
    numbers: Callable
    """numbers(R, decomposition, degrees): what the output publishes (rot_tools.ros.topics)."""
    stamped: bool


class Settings(NamedTuple):
    """The parameters as the callbacks use them; replaced whole when a parameter changes."""

    euler_sequence: str
    degrees: bool
    quaternion_tolerance: float
    publish_markers: bool
    marker_scale: float
    tf_reference_frame: str
    tf_body_frame: str
    input_covariance: str


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
    return (f'euler_sequence {shown(value)} is not a sequence: use one of '
            + ' '.join(EULER_SEQUENCES) + sequence_hint(value))


def _check_angle_unit(value):
    return '' if value in ('rad', 'deg') else f"angle_unit {shown(value)} is not 'rad' or 'deg'"


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


def _answers_even_if_it_raises(callback):
    """
    Wrap a service callback of the node: an exception it raises is logged, the request answered.

    The client then gets the response as it was given (success false, an empty path) instead of
    no reply at all; the node serves on.
    """
    @wraps(callback)
    def answering(node, request, response):
        try:
            return callback(node, request, response)
        except Exception:  # noqa: BLE001 - any bug: log it, answer, keep serving
            node.get_logger().error(f'{callback.__name__} raised; the node keeps serving:\n'
                                    + traceback.format_exc(), throttle_duration_sec=1.0)
            return response
    return answering


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
    'quaternion_tolerance': ParameterSpec(QUATERNION_TOLERANCE, _descriptor(
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
    'input_covariance': ParameterSpec('rotvec', _descriptor(
        ParameterType.PARAMETER_STRING,
        'how the rotation covariance of ~/imu, ~/pose_with_covariance and ~/odometry is read '
        "for ~/rpy_covariance: rotvec (rotations about the parent frame's fixed X, Y, Z, as "
        'ROS documents it) or rpy (already roll, pitch, yaw)', "'rotvec' or 'rpy'"),
        rpy_covariance.check_reading),
}
"""Every parameter of the node, by name. A new one is a row here and a field of Settings."""

NO_PUBLISHER_EVENTS = PublisherEventCallbacks(use_default_callbacks=False)
NO_SUBSCRIPTION_EVENTS = SubscriptionEventCallbacks(use_default_callbacks=False)
"""No QoS event handlers on the node's topics (rclpy adds two per publisher and subscription by
default, each one more entity for the executor to wait on with every message): the warnings
they would print are printed by the other side
(doc/node.md, "Executor, services and the middleware")."""

INPUT_QOS = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
"""The inputs' QoS: best effort (any publisher matches), volatile, keep last 50.

ROS's sensor-data profile, but 50 deep instead of 5 (1 ms at 5,000 msg/s): the node converts
every message of a burst, not the latest only (doc/node.md)."""

RCLPY_PARAMETERS = (USE_SIM_TIME_NAME, START_TYPE_DESCRIPTION_SERVICE_PARAM)
"""The parameters rclpy declares on every node (an override of one is no misspelling)."""


class RotationNode(Node):
    """Subscribes to every input of INPUTS and republishes their decompositions."""

    def __init__(self, node_name='rot_tools', **kwargs):
        """
        Build the node (``kwargs``: rclpy.node.Node's).

        Every start-up override (-p, --params-file, ``parameter_overrides``) is declared by
        rclpy as the node is built (automatically_declare_parameters_from_overrides): that
        is how the node reads them; _declare_parameters keeps its own and reports the rest.
        """
        super().__init__(node_name, automatically_declare_parameters_from_overrides=True,
                         **kwargs)
        try:
            self._declare_parameters()
        except Exception:
            self.destroy_node()
            raise
        self._settings = self._read_settings()
        self.add_pre_set_parameters_callback(self._integers_as_doubles)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)

        self._refused = dict.fromkeys(REFUSAL_REASONS, 0)
        self._last_refusals = {}  # reason: (topic, header or None, text) of the latest
        self._warned = {}  # (topic, reason): time.monotonic() of its last warning
        self._latest = None

        # Each output published per input: its publisher, its message (filled and published
        # for every input), the writer of its fields and the row; the pictures' publishers
        # by name.
        qos = QoSProfile(depth=10)
        publishers = {kind.row.name: self.create_publisher(
            kind.msg_type, kind.topic, qos, event_callbacks=NO_PUBLISHER_EVENTS)
            for kind in OUTPUTS}
        self._outputs = tuple(
            Publishing(publishers[kind.row.name].publish, kind.message(), kind.write,
                       kind.numbers, kind.row.stamped)
            for kind in OUTPUTS if kind.row.value is not None and not kind.row.covariance)
        # The first calls of the kernels and of the writers pay for one-off work: made here, on
        # one motion written into every output's message and not published (as the pictures
        # draw one), not with the first input.
        warm_up = decompose_one(WARM_UP_ROTATION, WARM_UP_TRANSLATION,
                                self._settings.euler_sequence)
        for output in self._outputs:
            output.write(output.message, output.numbers(WARM_UP_ROTATION, warm_up, False))
        self._pictures = Pictures(self, publishers['markers'], publishers['screw_axis'],
                                  self._settings.publish_markers)
        self._covariances = rpy_covariance.RpyCovariances(publishers, OUTPUTS, self._refuse)
        self._diagnostics = diagnostics.Diagnostics(self)  # /diagnostics, once a second

        # The TF tree: one more way of getting (header, R, b), beside the rows of INPUTS (it
        # needs a tree between messages, two topics with their own QoS, and gives an output
        # only when the chain has a new common time; rot_tools.ros.tf_input).
        self._tf = tf_input.TfFollower(self, self._on_tf_transform, self._refuse,
                                       quaternion_tolerance=self._settings.quaternion_tolerance)
        self._tf_source = Source(self._tf.topic, tf_input.TYPE_NAME, None, None, {})
        self._diagnostics.tf = self._tf
        self._tf.follow(self._settings.tf_reference_frame, self._settings.tf_body_frame)

        self._sources = []
        for kind in INPUTS:
            source = Source(self.resolve_topic_name(kind.topic), kind.row.type_name, kind.read,
                            kind.row.convert, kind.row.fields,
                            rpy_covariance.covariance_reader(kind.row)
                            if kind.row.covariance else None)
            callback = self._diagnostics.counted(source.topic, partial(self._on_input, source),
                                                 imu=kind.row.name == 'imu')
            self.create_subscription(kind.msg_type, kind.topic, callback, INPUT_QOS,
                                     event_callbacks=NO_SUBSCRIPTION_EVENTS)
            self._sources.append(source)

        self.create_service(Trigger, '~/describe', self._on_describe)
        self.create_service(GetPlan, '~/screw_path', self._on_screw_path)
        self._screw_path_name = self.resolve_service_name('~/screw_path')
        self.get_logger().info(
            f'decomposing {self._input_topics()} (euler_sequence '
            f'{self._settings.euler_sequence}, angle_unit '
            f"{'deg' if self._settings.degrees else 'rad'})")

    def _input_topics(self):
        """'/n/pose, /n/euler or /n/transform': the input topics as remapped."""
        topics = [source.topic for source in self._sources]
        if self._tf.following:
            topics.append(f'{self._tf.topic} ({self._tf.reference} ← {self._tf.body})')
        return ', '.join(topics[:-1]) + ' or ' + topics[-1]

    # -- parameters --------------------------------------------------------------------

    def _declare_parameters(self):
        """
        Declare PARAMETERS, their start-up overrides taken; warn about any other override.

        rclpy has declared every override as it stands (the Node was built with
        automatically_declare_parameters_from_overrides): each of PARAMETERS is declared
        again with its descriptor and default, then set to its override's value, if any
        (an integer made a double for a double parameter: _integers_as_doubles); an
        override that names no
        parameter of the node is reported (a misspelt ``-p euler_sequnce:=xyz`` would
        otherwise be silently ignored) and undeclared. Raises
        InvalidParameterValueException for an invalid value.
        """
        overrides = {}
        for name in self.list_parameters([], 0).names:
            if name in PARAMETERS:
                (overrides[name],) = self._integers_as_doubles([self.get_parameter(name)])
                self.undeclare_parameter(name)
            elif name not in RCLPY_PARAMETERS:
                self._warn_about_unknown_override(name)
                self.undeclare_parameter(name)
        for name, spec in PARAMETERS.items():
            self.declare_parameter(name, spec.default, spec.descriptor, ignore_override=True)
            if name in overrides:  # (checked against the descriptor: type and range)
                (result,) = self.set_parameters([overrides[name]])
                if not result.successful:
                    raise InvalidParameterValueException(
                        name, overrides[name].value, f'{name}: {result.reason}')
        for name, spec in PARAMETERS.items():
            value = self.get_parameter(name).value
            reason = spec.check(value)
            if reason:
                raise InvalidParameterValueException(name, value, reason)

    def _warn_about_unknown_override(self, name):
        """Warn that start-up override ``name`` is not a parameter of this node."""
        close = difflib.get_close_matches(name, PARAMETERS, n=1)
        hint = f": did you mean '{close[0]}'?" if close else (
            ': its parameters are ' + ', '.join(PARAMETERS))
        self.get_logger().warning(
            f"parameter override '{name}' is not a parameter of this node and is "
            f'ignored{hint}')

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
                        value['tf_body_frame'], value['input_covariance'])

    def _on_set_parameters(self, parameters):
        """
        Refuse invalid values of our parameters (rclpy has checked type and range).

        And a parameter without a name, which rclpy would otherwise declare.
        """
        for parameter in parameters:
            if not parameter.name:
                return SetParametersResult(successful=False, reason='a parameter name is empty')
            spec = PARAMETERS.get(parameter.name)
            if spec is not None:
                reason = spec.check(parameter.value)
                if reason:
                    return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    def _on_parameters_set(self, parameters):
        """Take the new values into use from the next message; publish_markers starts, stops."""
        if any(parameter.name in PARAMETERS for parameter in parameters):
            old, self._settings = self._settings, self._read_settings()
            new = self._settings
            if old.publish_markers and not new.publish_markers:
                self._pictures.stop()
            elif new.publish_markers and not old.publish_markers:
                self._pictures.start()
            self._tf.set_quaternion_tolerance(new.quaternion_tolerance)
            frames = (new.tf_reference_frame, new.tf_body_frame)
            if frames != (old.tf_reference_frame, old.tf_body_frame):
                self._tf.follow(*frames)
                self.get_logger().info(
                    f'following {shown(frames[1])} in {shown(frames[0])} on {self._tf.topic}'
                    if self._tf.following else f'not following frames on {self._tf.topic}')

    # -- inputs ----------------------------------------------------------------------------

    def _on_input(self, source, msg):
        """
        Turn one input message into (header, R, b) and publish every output, or refuse it.

        An input that carries a covariance then has its ~/rpy_covariance
        (rot_tools.ros.rpy_covariance): the other inputs (~/pose's flood) pay nothing for it.
        """
        settings = self._settings
        header = msg.header
        values = source.read(msg)
        try:
            R, b = source.convert(values, settings, source.fields)
            numbers = decompose_one(R, b, settings.euler_sequence)
        except boundary.RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc), header=header)
            return
        except RotationError as exc:
            self._refuse(source.topic, NOT_DECOMPOSABLE, str(exc), header=header)
            return
        self._publish(source, header, R, b, numbers, settings)
        if source.covariance is not None:
            self._covariances.on_input(source.topic, source.covariance, msg, header, R, values,
                                       settings)

    def _on_tf_transform(self, header, R, b):
        """Return the followed frames have a new common time on /tf: publish every output."""
        settings = self._settings
        try:
            numbers = decompose_one(R, b, settings.euler_sequence)
        except RotationError as exc:
            self._refuse(self._tf_source.topic, NOT_DECOMPOSABLE, str(exc))
            return
        self._publish(self._tf_source, header, R, b, numbers, settings)

    def _publish(self, source, header, R, b, numbers, settings):
        """Every output of one accepted input (header, R, b); ``numbers``: its decompose_one."""
        for output in self._outputs:
            msg = output.message
            if output.stamped:
                msg.header = header
            output.write(msg, output.numbers(R, numbers, settings.degrees))
            output.publish(msg)
        if settings.publish_markers:
            self._pictures.offer(header, R, b, settings)
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
        self._diagnostics.refused(topic, reason)
        self._last_refusals[reason] = (topic, header, text)
        now = time.monotonic()
        if now - self._warned.get((topic, reason), -math.inf) >= REFUSAL_WARNING_PERIOD and (
                self.context.ok()):  # (shut down by a signal: the node is stopping)
            self._warned[topic, reason] = now
            # One call site per severity: rclpy's logger keeps a call site's first severity
            # and raises ValueError when that site logs at another one.
            line = f'refused input on {topic} ({reason}): {text}'
            if error:
                self.get_logger().error(line)
            else:
                self.get_logger().warning(line)

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

    @_answers_even_if_it_raises
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
            data.update(self._covariances.describe())
            response.success = True
        data['refused'] = refused
        data['last_refusals'] = self.last_refusals()
        response.message = to_yaml(data)
        return response

    @_answers_even_if_it_raises
    def _on_screw_path(self, request, response):
        """
        Constant-screw motion start → goal, poses at most ``tolerance`` apart.

        Every failure is a refusal: counted by reason, logged (throttled per reason), and
        answered with an empty path (rot_tools.ros.screw_path).
        """
        header = request.start.header
        response.plan.header = header
        try:
            response.plan = screw_path.screw_path(request, self._settings.quaternion_tolerance)
        except boundary.RefusedInput as exc:
            self._refuse(self._screw_path_name, exc.reason, str(exc), error=True, header=header)
        except (RotationError, ArithmeticError) as exc:  # no screw between start and goal
            self._refuse(self._screw_path_name, NOT_DECOMPOSABLE,
                         f'no screw motion from start to goal: {exc}', error=True,
                         header=header)
        return response


DIAGNOSTICS = [
    ('imu conventions', "the conventions of ~/imu's last 10 s (rot-tools imu-check's checks): "
     'OK, WARN naming the checks at fault, or STALE under 5 s of input'),
    ('inputs', "each input's rate and refusals")]
SERVICES = [('~/describe', "std_srvs/srv/Trigger: the latest input's report and the refusals, "
             'as YAML'),
            ('~/screw_path', 'nav_msgs/srv/GetPlan: the constant-screw motion from start to '
             'goal')]


def usage():
    """Return the text of ``rotation_node --help``, from the interface's rows and PARAMETERS."""
    inputs = [(kind.topic, f'{kind.row.type_name}: {kind.row.help}') for kind in INPUTS]
    outputs = [(kind.topic, f'{kind.row.type_name}: {kind.row.help}'
                + ('' if kind.row.value else f' (at most {MARKER_RATE:g} a second)'))
               for kind in OUTPUTS]
    parameters = [(f'{name} = {runtime.default_text(spec.default)}', spec.descriptor.description
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
        '', 'inputs (subscribed best effort, keep last 50):', *runtime.help_rows(inputs),
        '', 'outputs (for every accepted input, reliable, depth 10):',
        *runtime.help_rows(outputs),
        '', '/diagnostics (diagnostic_msgs/msg/DiagnosticArray, once a second):',
        *runtime.help_rows(DIAGNOSTICS),
        '', 'services:', *runtime.help_rows(SERVICES),
        '', 'parameters (-p NAME:=VALUE, --params-file FILE):', *runtime.help_rows(parameters),
        '', 'examples:',
        f"  {PROG} --ros-args -r __ns:=/robot -r '~/imu:=/robot/imu/data' -p angle_unit:=deg",
        f'  {PROG} --ros-args --params-file rot_tools.yaml   (copied from share/rot_tools/'
        'config)',
        '  ros2 launch rot_tools rot_tools.launch.xml imu:=/robot/imu/data',
        '', "Quote a ~ that starts a word ('~/imu:=...'): the shell would expand it.",
        'The node and its interface are described in doc/node.md.', ''])


def main(args=None):
    """
    Run the node until SIGINT / SIGTERM; return the exit status: 0, or 2 for bad arguments.

    ``args``: the whole command line as rclpy.init takes it, program name first (sys.argv
    when None). ``--help`` and ``--version`` print and return 0 before anything ROS starts;
    any other argument outside ``--ros-args`` is refused, as are bad ROS arguments: one line
    on stderr, status 2. Signals are rclpy's: its handlers shut the context down and the
    loop (rot_tools.ros.runtime.spin) ends.
    """
    argv = sys.argv if args is None else list(args)
    options = runtime.user_arguments(argv)
    if '-h' in options or '--help' in options:
        print(usage(), end='')
        return 0
    if '--version' in options:
        try:
            print(version_line(PROG))
        except PackageNotFoundError:
            runtime.fail(PROG, '--version: rot_tools is not installed (no distribution metadata)')
        return 0
    if options:
        runtime.fail(PROG, f'unknown argument {options[0]!r} (ROS arguments go after '
                     f'--ros-args; see {PROG} --help)')
    runtime.init_ros(PROG, argv)
    home = os.path.expanduser('~')
    for remap in runtime.home_remaps(argv, home):
        quoted = "'~" + remap[len(home.rstrip('/')):] + "'"
        get_logger(PROG).warning(
            f'remap -r {remap} starts with the home directory {home}: the shell expanded an '
            f'unquoted ~; quote it: -r {quoted}')
    executor = node = None
    try:
        executor = SingleThreadedExecutor()
        node = RotationNode()
        runtime.spin(node, executor)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except runtime.ROS_ARGUMENT_ERRORS as exc:  # -p values, -r names the node cannot take
        if rclpy.ok():
            runtime.fail(PROG, runtime.ros_argument_error(exc))
    except Exception:
        if rclpy.ok():
            raise
        # A signal shut the context down while the node was being made: a normal stop.
    finally:
        if executor is not None:
            executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
