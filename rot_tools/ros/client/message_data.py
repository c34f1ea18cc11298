"""
rotation_client's messages as plain data: the input it fills, the answers it prints.

Each input's message is filled by plain code naming its fields (:func:`input_message`); each
output is printed by its name (:data:`PRINTED`), any other message field by field
(:func:`message_data`).
"""

import array

import numpy as np
from rot_tools.core.euler import euler_to_matrix, matrix_to_euler
from rot_tools.io import interface

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


def set_pose(pose, values):
    """Fill a geometry_msgs/Pose from X Y Z QX QY QZ QW."""
    _set_xyz(pose.position, values[:3])
    _set_quaternion(pose.orientation, values[3:])


def pose_data(pose):
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


def message_data(msg):
    """Return a message as plain data: {field: value}, nested alike; bytes as numbers."""
    if hasattr(msg, 'get_fields_and_field_types'):
        return {name: message_data(getattr(msg, name))
                for name in msg.get_fields_and_field_types()}
    if isinstance(msg, bytes):
        return msg[0] if len(msg) == 1 else list(msg)
    if isinstance(msg, (list, tuple, array.array, np.ndarray)):
        return [message_data(item) for item in msg]
    return msg.item() if isinstance(msg, np.generic) else msg


def _values(msg, row, parameters):
    """Return the fields of an output's message but its header (an output without a printer)."""
    return {name: value for name, value in message_data(msg).items() if name != 'header'}


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
    return {**pose_data(msg.pose.pose),
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


def answer_data(answer, parameters):
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


def input_message(args, parameters):
    """
    Return (message, what was sent as plain data) of an input command.

    Euler angles are sent in the node's sequence and unit (``parameters``); the rotation's
    covariance --cov, 9 numbers row-major, is an Imu's orientation_covariance or the rotation
    block of a pose's 6×6 (the rest 0).
    """
    from rot_tools.ros.message_types import message_class
    name, numbers = args.command, list(args.numbers)
    msg = message_class(args.row.type_name)()
    cov = None if getattr(args, 'cov', None) is None else np.reshape(args.cov, (3, 3))
    if name == 'euler':
        sequence, unit = parameters['euler_sequence'], parameters['angle_unit']
        angles = node_angles(numbers, args.sequence, args.deg, sequence, unit == 'deg')
        _set_xyz(msg.vector, angles)
        return msg, {'sequence': sequence, 'unit': unit, 'angles': list(angles)}
    if name == 'orientation':
        _set_quaternion(msg.quaternion, numbers)
        return msg, {'quaternion': _quaternion(msg.quaternion)}
    if name == 'imu':
        _set_quaternion(msg.orientation, numbers)
        sent = {'orientation': _quaternion(msg.orientation)}
        if cov is not None:
            msg.orientation_covariance = cov.ravel()
            sent['orientation_covariance'] = cov.tolist()
        return msg, sent
    if name == 'transform':
        msg.child_frame_id = args.child_frame
        _set_xyz(msg.transform.translation, numbers[:3])
        _set_quaternion(msg.transform.rotation, numbers[3:])
        return msg, {'child_frame_id': msg.child_frame_id,
                     'translation': _xyz(msg.transform.translation),
                     'rotation': _quaternion(msg.transform.rotation)}
    sent = {}
    if name == 'odometry':
        msg.child_frame_id = sent['child_frame_id'] = args.child_frame
    pose = msg.pose if name == 'pose' else msg.pose.pose  # pose_with_covariance, odometry
    set_pose(pose, numbers)
    sent.update(pose_data(pose))
    if cov is not None:
        C = np.zeros((6, 6))
        C[3:, 3:] = cov
        msg.pose.covariance = C.ravel()
        sent['covariance'] = C.tolist()
    return msg, sent


def echo_data(msg, row, parameters):
    """
    One message of an output as plain data: its header's stamp and frame, and its values.

    A message of another type than the output's (``--topic`` elsewhere) is printed whole.
    """
    from rot_tools.ros.message_types import type_name
    if type_name(type(msg)) != row.type_name:
        return message_data(msg)
    data = {}
    if hasattr(msg, 'header'):
        stamp = msg.header.stamp
        data = {'stamp': {'sec': stamp.sec, 'nanosec': stamp.nanosec},
                'frame_id': msg.header.frame_id}
    return {**data, row.name: PRINTED.get(row.name, _values)(msg, row, parameters)}


LEVELS = ('OK', 'WARN', 'ERROR', 'STALE')
"""diagnostic_msgs/DiagnosticStatus' levels by their number, as words."""


def status_data(status, stamp):
    """One DiagnosticStatus as plain data: its level as a word, its values by key."""
    (level,) = status.level  # one byte
    return {'stamp': {'sec': stamp.sec, 'nanosec': stamp.nanosec}, 'name': status.name,
            'level': LEVELS[level] if level < len(LEVELS) else level,
            'message': status.message, 'hardware_id': status.hardware_id,
            'values': {kv.key: kv.value for kv in status.values}}
