"""
rotation_node: orientations and poses republished as every representation of their rotation.

Each input's callback reads its message's fields into one rigid motion (header, R, b)
through the boundary's checks (rot_tools.io.boundary); :meth:`RotationNode.publish_outputs`
publishes every output from that motion's one decomposition, with the input's header. The
topics, services and parameters: doc/node.md and ``rotation_node --help``.
"""

import copy
import difflib
from importlib.metadata import PackageNotFoundError
import math
import os
import sys
import textwrap
import time
from typing import NamedTuple

from geometry_msgs.msg import (PoseStamped, PoseWithCovarianceStamped, QuaternionStamped,
                               TransformStamped, TwistStamped, Vector3Stamped)
from nav_msgs.msg import Odometry
from nav_msgs.srv import GetPlan
from rcl_interfaces.msg import SetParametersResult
from rcl_interfaces.srv import SetParameters, SetParametersAtomically
import rclpy
from rclpy.exceptions import InvalidParameterValueException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.logging import get_logger
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rclpy.time_source import USE_SIM_TIME_NAME
from rclpy.type_description_service import START_TYPE_DESCRIPTION_SERVICE_PARAM
from rot_tools.core.axis_angle import rodrigues_of_one
from rot_tools.core.decomposition import decompose_one
from rot_tools.core.errors import RotationError
from rot_tools.core.transform_tree import shown
from rot_tools.io import boundary, interface
from rot_tools.io.arguments import version_line
from rot_tools.io.boundary import RefusedInput
from rot_tools.io.report import to_yaml, transform_report
from rot_tools.ros import tf_input
from rot_tools.ros.node import diagnostics, rpy_covariance, runtime, screw_path
from rot_tools.ros.node.parameters import PARAMETERS, read_settings, Settings
from rot_tools.ros.node.pictures import MARKER_RATE, Pictures
from rot_tools.ros.node.screw_path import (BAD_TOLERANCE, FRAME_MISMATCH, NOT_DECOMPOSABLE,
                                           PATH_TOO_LONG)
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64MultiArray, MultiArrayDimension
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker, MarkerArray

RODRIGUES_AT_PI = 'rodrigues_at_pi'
"""Why an input has no ~/rodrigues (its other outputs are published): θ = π, g infinite."""

REFUSAL_REASONS = boundary.REFUSAL_REASONS + (
    NOT_DECOMPOSABLE, RODRIGUES_AT_PI, FRAME_MISMATCH, BAD_TOLERANCE, PATH_TOO_LONG
) + tf_input.REFUSAL_REASONS + rpy_covariance.REFUSAL_REASONS
"""Every reason an input is refused for, in the order ~/describe lists the counts."""

PROG = 'rotation_node'
"""The program's name in its messages."""

MAX_REFUSAL_TEXT = 400
"""Longest refusal sentence ~/describe repeats (a refused frame_id may be megabytes)."""

REFUSAL_WARNING_PERIOD = 1.0
"""Seconds between two warnings about refused inputs of one topic for one reason."""

INPUT_QOS = QoSProfile(depth=50, reliability=ReliabilityPolicy.BEST_EFFORT)
"""The inputs' QoS: best effort (any publisher matches), keep last 50: ROS's sensor-data
profile, deeper, so that the node converts every message of a burst (doc/node.md)."""

OUTPUT_QOS = QoSProfile(depth=10)
"""The outputs' QoS: reliable, keep last 10."""

MATRIX_LAYOUT = (('rows', 3, 9), ('cols', 3, 3))
"""(label, size, stride) of ~/rotation_matrix's dimensions: row-major 3×3 (std_msgs' way)."""

RCLPY_PARAMETERS = (USE_SIM_TIME_NAME, START_TYPE_DESCRIPTION_SERVICE_PARAM)
"""The parameters rclpy declares on every node (an override of one is no misspelling)."""


class Source(NamedTuple):
    """Where an input came from: its topic (as resolved) and its message type's name."""

    topic: str
    type_name: str


class Latest(NamedTuple):
    """The latest accepted input, kept for ~/describe (the report is built on request)."""

    source: Source
    header: object
    R: object
    b: object
    settings: Settings


def vector3_stamped(header, xyz):
    """Return a geometry_msgs/Vector3Stamped of ``header`` holding (x, y, z)."""
    msg = Vector3Stamped(header=header)
    msg.vector.x, msg.vector.y, msg.vector.z = xyz
    return msg


def _malformed_requests_refused(callback, logger):
    """
    Wrap a parameter service's callback: a request rclpy cannot read is refused, not raised.

    rclpy's ParameterService reads each parameter with Parameter.from_parameter_msg, which
    raises ValueError for a type outside rcl_interfaces' ParameterType (e.g. 99): the
    exception leaves the executor and ends the node (rclpy 7.1, Jazzy). Here the request is
    answered as refused and one line logged.
    """
    def answering(request, response):
        try:
            return callback(request, response)
        except ValueError as exc:
            logger.error(f'refused a malformed parameter request: {exc}')
            refused = SetParametersResult(successful=False, reason=f'malformed request: {exc}')
            if hasattr(response, 'results'):  # SetParameters: one result per parameter
                response.results = [refused] * len(request.parameters)
            else:  # SetParametersAtomically
                response.result = refused
            return response
    return answering


class RotationNode(Node):
    """Subscribes to every input of the interface and republishes their decompositions."""

    def __init__(self, node_name='rot_tools', **kwargs):
        """Build the node (``kwargs``: rclpy.node.Node's); its parameters declared once."""
        super().__init__(node_name, **kwargs)
        self.add_pre_set_parameters_callback(self._integers_as_doubles)
        try:
            self._declare_parameters()
        except Exception:
            self.destroy_node()
            raise
        self._settings = read_settings(self)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)
        for service in self.services:
            if service.srv_type in (SetParameters, SetParametersAtomically):
                service.callback = _malformed_requests_refused(service.callback,
                                                               self.get_logger())

        self._refused = dict.fromkeys(REFUSAL_REASONS, 0)
        self._last_refusals = {}  # reason: (topic, header or None, text) of the latest
        self._warned = {}  # (topic, reason): time.monotonic() of its last warning
        self._latest = None

        self._rotation_matrix = self.create_publisher(
            Float64MultiArray, '~/rotation_matrix', OUTPUT_QOS)
        self._quaternion = self.create_publisher(QuaternionStamped, '~/quaternion', OUTPUT_QOS)
        self._axis_angle = self.create_publisher(Vector3Stamped, '~/axis_angle', OUTPUT_QOS)
        self._rodrigues = self.create_publisher(Vector3Stamped, '~/rodrigues', OUTPUT_QOS)
        self._euler_angles = self.create_publisher(Vector3Stamped, '~/euler_angles', OUTPUT_QOS)
        self._rpy = self.create_publisher(Vector3Stamped, '~/rpy', OUTPUT_QOS)
        self._screw = self.create_publisher(TwistStamped, '~/screw', OUTPUT_QOS)
        self._covariances = rpy_covariance.RpyCovariances(
            self.create_publisher(PoseWithCovarianceStamped, '~/rpy_covariance', OUTPUT_QOS),
            self._refuse)
        self._pictures = Pictures(
            self, self.create_publisher(MarkerArray, '~/markers', OUTPUT_QOS),
            self.create_publisher(Marker, '~/screw_axis', OUTPUT_QOS),
            self._settings.publish_markers)
        self._diagnostics = diagnostics.Diagnostics(self)  # /diagnostics, once a second

        # The TF tree: one more way of getting (header, R, b): it keeps a tree between
        # messages and gives an output only when the chain has a new common time.
        self._tf = tf_input.TfFollower(self, self._on_tf_transform, self._refuse,
                                       quaternion_tolerance=self._settings.quaternion_tolerance)
        self._tf_source = Source(self._tf.topic, tf_input.TYPE_NAME)
        self._diagnostics.tf = self._tf
        self._tf.follow(self._settings.tf_reference_frame, self._settings.tf_body_frame)

        self._sources = {row.name: Source(self.resolve_topic_name(row.topic), row.type_name)
                         for row in interface.INPUTS}
        for msg_type, name, callback in (
                (PoseStamped, 'pose', self.on_pose),
                (Vector3Stamped, 'euler', self.on_euler),
                (TransformStamped, 'transform', self.on_transform),
                (PoseWithCovarianceStamped, 'pose_with_covariance',
                 self.on_pose_with_covariance),
                (Odometry, 'odometry', self.on_odometry),
                (Imu, 'imu', self.on_imu),
                (QuaternionStamped, 'orientation', self.on_orientation)):
            counted = self._diagnostics.counted(self._sources[name].topic, callback,
                                                imu=msg_type is Imu)
            self.create_subscription(msg_type, '~/' + name, counted, INPUT_QOS)

        self.create_service(Trigger, '~/describe', self._on_describe)
        self.create_service(GetPlan, '~/screw_path', self._on_screw_path)
        self._screw_path_name = self.resolve_service_name('~/screw_path')

    def announce(self):
        """Log that the node is up: its input topics and its Euler settings."""
        self.get_logger().info(
            f'decomposing {self._input_topics()} (euler_sequence '
            f'{self._settings.euler_sequence}, angle_unit '
            f"{'deg' if self._settings.degrees else 'rad'})")

    def _input_topics(self):
        """'/n/pose, /n/euler or /n/transform': the input topics as remapped."""
        topics = [source.topic for source in self._sources.values()]
        if self._tf.following:
            topics.append(f'{self._tf.topic} ({self._tf.reference} ← {self._tf.body})')
        return ', '.join(topics[:-1]) + ' or ' + topics[-1]

    # -- inputs: each message's fields into (header, R, b) ---------------------------------

    def on_pose(self, msg):
        """Take a PoseStamped: R from pose.orientation, b = pose.position."""
        source, settings = self._sources['pose'], self._settings
        p, q = msg.pose.position, msg.pose.orientation
        try:
            R, b = boundary.rigid_motion((p.x, p.y, p.z), (q.x, q.y, q.z, q.w),
                                         settings.quaternion_tolerance, 'pose')
        except RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc), header=msg.header)
            return
        self.publish_outputs(source, msg.header, R, b, settings)

    def on_euler(self, msg):
        """Take a Vector3Stamped: vector.x, .y, .z = θ1, θ2, θ3 of euler_sequence; b = 0."""
        source, settings = self._sources['euler'], self._settings
        v = msg.vector
        try:
            R = boundary.euler_to_rotation((v.x, v.y, v.z), settings.euler_sequence,
                                           settings.degrees)
        except RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc), header=msg.header)
            return
        self.publish_outputs(source, msg.header, R, (0.0, 0.0, 0.0), settings)

    def on_transform(self, msg):
        """Take a TransformStamped: R from transform.rotation, b = transform.translation."""
        source, settings = self._sources['transform'], self._settings
        t, q = msg.transform.translation, msg.transform.rotation
        try:
            R, b = boundary.rigid_motion(
                (t.x, t.y, t.z), (q.x, q.y, q.z, q.w), settings.quaternion_tolerance,
                ('transform.translation', 'transform.rotation'))
        except RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc), header=msg.header)
            return
        self.publish_outputs(source, msg.header, R, b, settings)

    def on_pose_with_covariance(self, msg):
        """Take a PoseWithCovarianceStamped: pose.pose as a pose, and pose.covariance."""
        self._take_pose_with_covariance(self._sources['pose_with_covariance'], msg)

    def on_odometry(self, msg):
        """Take an Odometry: pose.pose (child_frame_id in header.frame_id), pose.covariance."""
        self._take_pose_with_covariance(self._sources['odometry'], msg)

    def _take_pose_with_covariance(self, source, msg):
        """Publish the outputs of msg.pose.pose, then the rpy covariance of msg.pose.covariance."""
        settings = self._settings
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        position, orientation = (p.x, p.y, p.z), (q.x, q.y, q.z, q.w)
        try:
            R, b = boundary.rigid_motion(position, orientation, settings.quaternion_tolerance,
                                         'pose.pose')
        except RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc), header=msg.header)
            return
        if self.publish_outputs(source, msg.header, R, b, settings):
            self._covariances.on_input(source.topic, msg.header, R, position, orientation,
                                       msg.pose.covariance, 'pose.covariance', settings)

    def on_imu(self, msg):
        """Take an Imu: R from orientation, b = 0; refused when it has no orientation."""
        source, settings = self._sources['imu'], self._settings
        q = msg.orientation
        orientation = (q.x, q.y, q.z, q.w)
        try:
            boundary.require_orientation(msg.orientation_covariance[0])
            R = boundary.quaternion_to_rotation(*orientation, settings.quaternion_tolerance)
        except RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc), header=msg.header)
            return
        if self.publish_outputs(source, msg.header, R, (0.0, 0.0, 0.0), settings):
            self._covariances.on_input(source.topic, msg.header, R, (0.0, 0.0, 0.0),
                                       orientation, msg.orientation_covariance,
                                       'orientation_covariance', settings)

    def on_orientation(self, msg):
        """Take a QuaternionStamped: R from quaternion, b = 0."""
        source, settings = self._sources['orientation'], self._settings
        q = msg.quaternion
        try:
            R = boundary.quaternion_to_rotation(q.x, q.y, q.z, q.w,
                                                settings.quaternion_tolerance, 'quaternion')
        except RefusedInput as exc:
            self._refuse(source.topic, exc.reason, str(exc), header=msg.header)
            return
        self.publish_outputs(source, msg.header, R, (0.0, 0.0, 0.0), settings)

    def _on_tf_transform(self, header, R, b):
        """Publish every output of the followed frames at their new common time on /tf."""
        self.publish_outputs(self._tf_source, header, R, b, self._settings)

    # -- outputs: one decomposition into every message --------------------------------------

    def publish_outputs(self, source, header, R, b, settings):
        """
        Publish every output of one accepted input (header, R, b); return whether it was.

        One decomposition gives every number (so at θ = π all share the axis sign); angles
        in angle_unit. At θ = π there is no ~/rodrigues (a refusal, rodrigues_at_pi) but the
        other outputs go.
        """
        try:
            d = decompose_one(R, b, settings.euler_sequence)
        except RotationError as exc:  # a screw beyond float64
            self._refuse(source.topic, NOT_DECOMPOSABLE, str(exc), header=header)
            return False

        matrix = Float64MultiArray(data=R.ravel().tolist())
        matrix.layout.dim = [MultiArrayDimension(label=label, size=size, stride=stride)
                             for label, size, stride in MATRIX_LAYOUT]
        self._rotation_matrix.publish(matrix)

        quaternion = QuaternionStamped(header=header)
        q = quaternion.quaternion
        q.x, q.y, q.z, q.w = d.quaternion
        self._quaternion.publish(quaternion)

        self._axis_angle.publish(vector3_stamped(header, d.rotvec))
        try:
            self._rodrigues.publish(vector3_stamped(header, rodrigues_of_one(*d.quaternion)))
        except RotationError as exc:
            self._refuse(source.topic, RODRIGUES_AT_PI, str(exc), header=header)

        euler, rpy = d.euler, d.rpy
        if settings.degrees:
            euler, rpy = map(math.degrees, euler), map(math.degrees, rpy)
        self._euler_angles.publish(vector3_stamped(header, euler))
        self._rpy.publish(vector3_stamped(header, rpy))

        screw = TwistStamped(header=header)
        angular, linear = screw.twist.angular, screw.twist.linear
        angular.x, angular.y, angular.z, linear.x, linear.y, linear.z = d.twist
        self._screw.publish(screw)

        if settings.publish_markers:
            self._pictures.offer(header, R, b, settings)
        self._latest = Latest(source, header, R, b, settings)
        return True

    def _refuse(self, topic, reason, text, error=False, header=None):
        """
        Count a refused input; warn at most once a REFUSAL_WARNING_PERIOD per (topic, reason).

        Not rclpy's throttle_duration_sec: it throttles per call site, so one fast bad
        stream would silence every other one. ``error``: log at error level (a refused
        service request). The refusal is kept as the latest of its reason for ~/describe
        (``header``: the refused message's).
        """
        self._refused[reason] += 1
        self._diagnostics.refused(topic, reason)
        self._last_refusals[reason] = (topic, header, text)
        now = time.monotonic()
        if now - self._warned.get((topic, reason), -math.inf) >= REFUSAL_WARNING_PERIOD and (
                self.context.ok()):  # (shut down by a signal: the node is stopping)
            self._warned[topic, reason] = now
            # One call site per severity: rclpy's logger keeps a call site's first severity.
            line = f'refused input on {topic} ({reason}): {text}'
            if error:
                self.get_logger().error(line)
            else:
                self.get_logger().warning(line)

    # -- parameters --------------------------------------------------------------------

    def _declare_parameters(self):
        """
        Declare PARAMETERS with their descriptors, taking their start-up overrides.

        An integer given to a double parameter is stored as a double. Raises
        InvalidParameterValueException for an invalid value.
        """
        self.declare_parameters('', [(name, spec.default, copy.deepcopy(spec.descriptor))
                                     for name, spec in PARAMETERS.items()])
        for name, spec in PARAMETERS.items():
            value = self.get_parameter(name).value
            reason = spec.check(value)
            if reason:
                raise InvalidParameterValueException(name, value, reason)
            if type(value) is int and type(spec.default) is float:
                self.set_parameters([Parameter(name, Parameter.Type.DOUBLE, float(value))])

    def warn_about_unknown_override(self, name):
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
        marker_scale:=3`` or ``ros2 param set ... marker_scale 3`` is an integer.
        """
        converted = []
        for parameter in parameters:
            spec = PARAMETERS.get(parameter.name)
            if (spec is not None and parameter.type_ == Parameter.Type.INTEGER
                    and type(spec.default) is float):
                parameter = Parameter(parameter.name, Parameter.Type.DOUBLE,
                                      float(parameter.value))
            converted.append(parameter)
        return converted

    def _on_set_parameters(self, parameters):
        """Refuse invalid values of our parameters, and a parameter without a name."""
        for parameter in parameters:
            if not parameter.name:  # (rclpy would declare it)
                self.get_logger().error(
                    'refused a malformed parameter request: a parameter name is empty')
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
            old, self._settings = self._settings, read_settings(self)
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

    # -- services ----------------------------------------------------------------------

    def refused_counts(self):
        """{'total': N, reason: n, ...} of the inputs refused so far."""
        return {'total': sum(self._refused.values()), **self._refused}

    def last_refusals(self):
        """
        {reason: {source, stamp, message}} of the latest refusal of each reason so far.

        In REFUSAL_REASONS order, only the reasons counted; ``stamp`` only when the refused
        message had a header; ``message`` cut to MAX_REFUSAL_TEXT characters.
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
        ``last_refusals``. Before any accepted input ``success`` is false and the document
        starts with ``note``: a sentence saying so.
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

    def _on_screw_path(self, request, response):
        """
        Constant-screw motion start → goal, poses at most ``tolerance`` apart.

        Every failure is a refusal: counted by reason, logged (throttled per reason), and
        answered with an empty path (rot_tools.ros.node.screw_path).
        """
        header = request.start.header
        response.plan.header = header
        try:
            response.plan = screw_path.screw_path(request, self._settings.quaternion_tolerance)
        except RefusedInput as exc:
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
PICTURES = ('screw_axis', 'markers')


def usage():
    """Return the text of ``rotation_node --help``, from the interface's rows and PARAMETERS."""
    inputs = [(row.topic, f'{row.type_name}: {row.help}') for row in interface.INPUTS]
    outputs = [(row.topic, f'{row.type_name}: {row.help}'
                + (f' (at most {MARKER_RATE:g} a second)' if row.name in PICTURES else ''))
               for row in interface.OUTPUTS]
    parameters = [(f'{name} = {runtime.default_text(spec.default)}', spec.descriptor.description
                   + (f' ({spec.descriptor.additional_constraints})'
                      if spec.descriptor.additional_constraints else ''))
                  for name, spec in PARAMETERS.items()]
    return '\n'.join([
        f'usage: {PROG} [--help] [--version] [--ros-args ROS_ARGUMENT ...]', '',
        textwrap.fill(
            'A ROS 2 node: every input (an orientation or a pose) is turned into one rigid '
            'motion (R, b) and republished as rotation matrix, quaternion, rotation vector, '
            'Rodrigues vector, Euler angles, roll/pitch/yaw and screw (Chasles) '
            "decomposition, with the input's header.", 99),
        '', f'inputs (subscribed best effort, keep last {INPUT_QOS.depth}):',
        *runtime.help_rows(inputs),
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


LOST_INTERRUPT = "Unable to convert call argument '0' to Python object"
"""rclpy's Subscription.take_message raises this when the message's conversion raised."""


def main(args=None):
    """
    Run the node until SIGINT / SIGTERM; return the exit status: 0, or 2 for bad arguments.

    ``args``: the whole command line as rclpy.init takes it, program name first (sys.argv
    when None). ``--help`` and ``--version`` print and return 0 before anything ROS starts;
    any other argument outside ``--ros-args`` is refused, as are bad ROS arguments: one line
    on stderr, status 2.
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
    executor = SingleThreadedExecutor()
    try:
        node = RotationNode()
    except runtime.ROS_ARGUMENT_ERRORS as exc:  # -p values, -r names the node cannot take
        rclpy.try_shutdown()
        runtime.fail(PROG, runtime.ros_argument_error(exc))
    try:
        for name in runtime.override_names(argv, node.get_fully_qualified_name()):
            if name not in PARAMETERS and name not in RCLPY_PARAMETERS:
                node.warn_about_unknown_override(name)
        executor.add_node(node)
        node.announce()
        executor.spin()
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except RuntimeError as exc:
        # Two rclpy races with its own signal handling end spin so, not cleanly; both are the
        # signal's normal stop. Its handler shuts the context down from a thread of its own
        # while spin may be building a wait set on it ('failed to initialize wait set'); and
        # the KeyboardInterrupt of a SIGINT that lands while take_message converts a message
        # is lost in pybind11's cast error (LOST_INTERRUPT), the context still valid.
        if rclpy.ok() and not str(exc).startswith(LOST_INTERRUPT):
            raise
    finally:
        # The reverse of their making: the executor's signal guard condition, which rclpy's
        # signal thread triggers, goes after the node.
        node.destroy_node()
        executor.shutdown()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
