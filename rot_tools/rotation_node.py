"""rotation_node: republish poses, Euler angles and transforms as matrix, axis-angle, screw.

Every input message becomes one rigid transform (header, R, b) at the boundary
(rot_tools.messages); its screw (Chasles) decomposition is computed once and every output —
rotation vector θ·l̂, twist (θ·l̂, θ·m + d·l̂) = screw_log, marker along the axis — is read
off it, so at θ = π all outputs of one input share the axis sign. Outputs carry the input's
header. Topics, services and parameters: SPEC §3 and README "Using it in ROS 2".
"""

import math
import sys
from typing import NamedTuple

from geometry_msgs.msg import PoseStamped, TransformStamped, TwistStamped, Vector3Stamped
from nav_msgs.srv import GetPlan
import numpy as np
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
from rcl_interfaces.msg import SetParametersResult
import rclpy
from rclpy.exceptions import InvalidParameterTypeException, InvalidParameterValueException
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data, QoSProfile
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from visualization_msgs.msg import Marker

from rot_tools import messages
from rot_tools.errors import RotationError
from rot_tools.euler import EULER_SEQUENCES
from rot_tools.report import decompose, to_yaml, transform_report
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
    rotvec: Vector3Stamped
    euler: Vector3Stamped
    twist: TwistStamped
    marker: Marker


class Latest(NamedTuple):
    """The latest accepted input, kept for ~/describe (the report is built on request)."""

    topic: str
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
        ParameterType.PARAMETER_BOOL, 'publish the screw axis as a Marker on ~/screw_axis')),
    'marker_scale': (1.0, _descriptor(
        ParameterType.PARAMETER_DOUBLE, 'length of the ~/screw_axis arrow (m)', '> 0, finite',
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
    """Subscribes to pose / Euler / transform topics and republishes their decompositions."""

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
        self._settings = self._read_settings()
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self.add_post_set_parameters_callback(self._on_parameters_set)

        self._refused = dict.fromkeys(REFUSAL_REASONS, 0)
        self._latest = None

        # One message per output, refilled for each input (see rot_tools.messages).
        self._out = Outputs(messages.rotation_matrix_msg(np.eye(3)), Vector3Stamped(),
                            Vector3Stamped(), TwistStamped(),
                            messages.screw_axis_marker(None, (0, 0, 0), (0, 0, 1), 1.0))
        qos = QoSProfile(depth=10)
        self._matrix_pub = self.create_publisher(Float64MultiArray, '~/rotation_matrix', qos)
        self._axis_angle_pub = self.create_publisher(Vector3Stamped, '~/axis_angle', qos)
        self._euler_pub = self.create_publisher(Vector3Stamped, '~/euler_angles', qos)
        self._screw_pub = self.create_publisher(TwistStamped, '~/screw', qos)
        self._marker_pub = self.create_publisher(Marker, '~/screw_axis', qos)

        self._pose_sub = self.create_subscription(
            PoseStamped, '~/pose', self._on_pose, qos_profile_sensor_data)
        self._euler_sub = self.create_subscription(
            Vector3Stamped, '~/euler', self._on_euler, qos_profile_sensor_data)
        self._transform_sub = self.create_subscription(
            TransformStamped, '~/transform', self._on_transform, qos_profile_sensor_data)

        self._describe_srv = self.create_service(Trigger, '~/describe', self._on_describe)
        self._screw_path_srv = self.create_service(
            GetPlan, '~/screw_path', self._on_screw_path)
        self._screw_path_name = self.resolve_service_name('~/screw_path')
        self.get_logger().info(
            f'decomposing {self._pose_sub.topic_name}, {self._euler_sub.topic_name} and '
            f'{self._transform_sub.topic_name} (euler_sequence {self._settings.euler_sequence}'
            f", angle_unit {'deg' if self._settings.degrees else 'rad'})")

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
        """Take the new values into use from the next message."""
        if any(parameter.name in PARAMETERS for parameter in parameters):
            self._settings = self._read_settings()

    # -- inputs ------------------------------------------------------------------------

    def _on_pose(self, msg):
        settings = self._settings
        self._process(self._pose_sub.topic_name, settings, messages.pose_stamped_to_transform,
                      msg, settings.quaternion_tolerance)

    def _on_euler(self, msg):
        settings = self._settings
        self._process(self._euler_sub.topic_name, settings,
                      messages.euler_stamped_to_transform,
                      msg, settings.euler_sequence, settings.degrees)

    def _on_transform(self, msg):
        settings = self._settings
        self._process(self._transform_sub.topic_name, settings,
                      messages.transform_stamped_to_transform,
                      msg, settings.quaternion_tolerance)

    def _refuse(self, topic, reason, text):
        self._refused[reason] += 1
        self.get_logger().warning(f'refused input on {topic} ({reason}): {text}',
                                  throttle_duration_sec=1.0)

    def _process(self, topic, settings, convert, *args):
        """Convert one message to (header, R, b) and publish every output, or refuse it."""
        try:
            header, R, b = convert(*args)
            d = decompose(R, b, settings.euler_sequence, check=False)  # floats: no warnings
            if not all(map(math.isfinite, d.twist.tolist() + d.screw.point.tolist())):
                raise messages.RefusedInput(
                    NOT_DECOMPOSABLE, 'values too large to decompose in float64')
            rotvec = d.axis * d.angle
            angles = np.degrees(d.euler) if settings.degrees else d.euler
        except messages.RefusedInput as exc:
            self._refuse(topic, exc.reason, str(exc))
            return
        except RotationError as exc:
            self._refuse(topic, NOT_DECOMPOSABLE, str(exc))
            return
        out = self._out
        self._matrix_pub.publish(messages.rotation_matrix_msg(R, out.matrix))
        self._axis_angle_pub.publish(messages.vector3_stamped_msg(header, rotvec, out.rotvec))
        self._euler_pub.publish(messages.vector3_stamped_msg(header, angles, out.euler))
        self._screw_pub.publish(messages.twist_stamped_msg(header, d.twist, out.twist))
        screw = d.screw
        if settings.publish_markers and (screw.angle != 0.0 or screw.translation != 0.0):
            self._marker_pub.publish(messages.screw_axis_marker(
                header, screw.point, screw.direction, settings.marker_scale, out.marker))
        self._latest = Latest(topic, header, R, b, settings)

    # -- services ----------------------------------------------------------------------

    def refused_counts(self):
        """{'total': N, reason: n, ...} of the inputs refused so far."""
        return {'total': sum(self._refused.values()), **self._refused}

    def _on_describe(self, request, response):
        """YAML report of the latest input (rot_tools.report), with the refusal counts."""
        refused = self.refused_counts()
        latest = self._latest
        if latest is None:
            response.success = False
            response.message = (
                'Nothing has been received yet on {}, {} or {} ({} input(s) refused).'.format(
                    self._pose_sub.topic_name, self._euler_sub.topic_name,
                    self._transform_sub.topic_name, refused['total']))
            return response
        stamp = latest.header.stamp
        data = {'source': latest.topic,
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


def main(args=None):
    """Run the node until SIGINT / SIGTERM; exit status 0, or 2 for an invalid parameter.

    rclpy.init installs handlers that shut the context down on SIGINT and SIGTERM; the loop
    below then ends within one spin_once timeout (rclpy.spin could hang on a signal).
    """
    rclpy.init(args=args)
    node = None
    try:
        node = RotationNode()
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except (InvalidParameterTypeException, InvalidParameterValueException) as exc:
        print(f'rotation_node: {exc}', file=sys.stderr)
        return 2
    except Exception:
        if rclpy.ok():
            raise
        # A signal shut the context down while the node was being built: a normal stop.
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
