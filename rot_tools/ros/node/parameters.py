"""
rotation_node's parameters: each declared once, with a descriptor and a check of its values.

A new parameter is a row of PARAMETERS and a field of Settings.
"""

import math
from typing import Callable, NamedTuple

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor, ParameterType
from rot_tools.core.euler import EULER_SEQUENCES
from rot_tools.core.transform_tree import shown
from rot_tools.io.boundary import QUATERNION_TOLERANCE
from rot_tools.io.report import sequence_hint
from rot_tools.ros import tf_input
from rot_tools.ros.node import rpy_covariance
from rot_tools.ros.node.pictures import MARKER_RATE

MIN_MARKER_SCALE = 1e-6
"""Smallest marker_scale (m): the arrows' shafts are 5 % of it, and RViz draws nothing of
a zero width."""


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


def _not_a_number(name, value):
    """Return why ``value`` of double parameter ``name`` has the wrong type, or ''."""
    if type(value) in (int, float):
        return ''
    return f'Wrong parameter type: {name} is a double, got {value!r}'


def _check_sequence(value):
    if value in EULER_SEQUENCES:
        return ''
    return (f'euler_sequence {shown(value)} is not a sequence: use one of '
            + ' '.join(EULER_SEQUENCES) + sequence_hint(value))


def _check_angle_unit(value):
    return '' if value in ('rad', 'deg') else f"angle_unit {shown(value)} is not 'rad' or 'deg'"


def _check_tolerance(value):
    if _not_a_number('quaternion_tolerance', value):
        return _not_a_number('quaternion_tolerance', value)
    if math.isfinite(value) and value >= 0.0:
        return ''
    return f'quaternion_tolerance must be finite and >= 0, got {value}'


def _check_marker_scale(value):
    if _not_a_number('marker_scale', value):
        return _not_a_number('marker_scale', value)
    if math.isfinite(value) and value >= MIN_MARKER_SCALE:
        return ''
    return (f'marker_scale must be finite and >= {MIN_MARKER_SCALE:g} m (thinner arrows are '
            f'not drawn), got {value}')


def _check_tf_frame(value):
    return tf_input.tf2_msgs_missing() if value else ''


def _any_value(value):
    return ''


def _text(type_, description, constraints=''):
    return ParameterDescriptor(type=type_, description=description,
                               additional_constraints=constraints)


def _double(description, constraints, low):
    """
    Return the descriptor of a double parameter that also takes an integer (3 for 3.0).

    rclpy types a value by how it is written (``-p marker_scale:=3`` is an integer), so the
    type is checked by the parameter's check instead of rclpy's, and the node stores a
    double (RotationNode._integers_as_doubles).
    """
    return ParameterDescriptor(
        type=ParameterType.PARAMETER_DOUBLE, description=description,
        additional_constraints=constraints, dynamic_typing=True,
        floating_point_range=[FloatingPointRange(from_value=low, to_value=math.inf, step=0.0)])


class ParameterSpec(NamedTuple):
    """One parameter of the node: default, descriptor, and the check of its values."""

    default: object
    descriptor: ParameterDescriptor
    check: Callable = _any_value
    """check(value) -> '' when valid, else why not."""


PARAMETERS = {
    'euler_sequence': ParameterSpec('ZYX', _text(
        ParameterType.PARAMETER_STRING,
        'Euler sequence of ~/euler input and ~/euler_angles output: upper case intrinsic '
        '(ZYX: R = Rot_z(θ1) Rot_y(θ2) Rot_x(θ3)), lower case extrinsic',
        'one of ' + ' '.join(EULER_SEQUENCES)), _check_sequence),
    'angle_unit': ParameterSpec('rad', _text(
        ParameterType.PARAMETER_STRING,
        'unit of the angles of ~/euler, ~/euler_angles and ~/rpy', "'rad' or 'deg'"),
        _check_angle_unit),
    'quaternion_tolerance': ParameterSpec(QUATERNION_TOLERANCE, _double(
        'largest |‖q‖ − 1| of an input quaternion; within it q is normalised, beyond it the '
        'message is refused', '>= 0, finite', 0.0), _check_tolerance),
    'publish_markers': ParameterSpec(True, _text(
        ParameterType.PARAMETER_BOOL,
        f'publish the picture of each input (at most {MARKER_RATE:g} a second, the latest '
        "wins): the moved frame's axes, screw axis, helical path and label on ~/markers "
        '(MarkerArray) and the screw axis arrow on ~/screw_axis (Marker); switching it off '
        'deletes both')),
    'marker_scale': ParameterSpec(1.0, _double(
        'length of the frame axes on ~/markers and of the ~/screw_axis arrow (m)',
        f'>= {MIN_MARKER_SCALE:g}, finite', MIN_MARKER_SCALE), _check_marker_scale),
    'tf_reference_frame': ParameterSpec('', _text(
        ParameterType.PARAMETER_STRING,
        'with tf_body_frame: follow the transform of tf_body_frame in this frame on /tf and '
        '/tf_static, publishing every output at each new common time of the chain '
        "(header.frame_id = this frame); '' = off"), _check_tf_frame),
    'tf_body_frame': ParameterSpec('', _text(
        ParameterType.PARAMETER_STRING,
        "with tf_reference_frame: the frame followed on /tf and /tf_static; '' = off"),
        _check_tf_frame),
    'input_covariance': ParameterSpec('rotvec', _text(
        ParameterType.PARAMETER_STRING,
        'how the rotation covariance of ~/imu, ~/pose_with_covariance and ~/odometry is read '
        "for ~/rpy_covariance: rotvec (rotations about the parent frame's fixed X, Y, Z, as "
        'ROS documents it) or rpy (already roll, pitch, yaw)', "'rotvec' or 'rpy'"),
        rpy_covariance.check_reading),
}
"""Every parameter of the node, by name."""


def read_settings(node):
    """Return the Settings of ``node``'s parameters as they are now."""
    value = {name: node.get_parameter(name).value for name in PARAMETERS}
    return Settings(value['euler_sequence'], value['angle_unit'] == 'deg',
                    float(value['quaternion_tolerance']), value['publish_markers'],
                    float(value['marker_scale']), value['tf_reference_frame'],
                    value['tf_body_frame'], value['input_covariance'])
