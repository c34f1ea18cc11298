"""
rotation_node's interface: every input and every output, one row each.

An input row says where the input arrives (``~/NAME``), its message type, the fields read,
in the message's order, and the formula that turns them into one rigid motion (R, b)
(rot_tools.io.boundary). An output row says where it goes, its type, the fields written and,
by name, the value they hold: a field of the input's decomposition
(rot_tools.core.decomposition.Decomposition), or the input's own R. The rows are read by the
node (its subscriptions and publishers, and the fields it reads and writes by their paths),
by ``rotation_client`` (its commands: a verb per input, its arguments and help; the answer,
output by output, by name), by ``rot-tools bag`` (the types it reads, and their fields) and
by every ``--help`` that lists them. A new input or output is one row here and its formula.

Fields are given by role (:data:`MEMBERS`): ``{role: path}`` in the message's order, e.g.
``{'position': 'pose.position', 'orientation': 'pose.orientation'}``, the path's members
(x, y, z, ...) read in turn. Strings (``child_frame_id``) are not read by the node.
Message types are names ('geometry_msgs/msg/PoseStamped'): this module imports no ROS.
"""

from typing import Callable, NamedTuple

from rot_tools.io import boundary

MEMBERS = {
    'child_frame_id': None,
    'position': ('x', 'y', 'z'),
    'orientation': ('x', 'y', 'z', 'w'),
    'angles': ('x', 'y', 'z'),
    'covariance0': ('[0]',),
    'angular_velocity': ('x', 'y', 'z'),
}
"""The roles of an input's fields, and the float64 members of each (None: a string).

position: a Point or Vector3 (b); orientation: a Quaternion, (x, y, z, w); angles: a
Vector3 holding θ1, θ2, θ3; covariance0: the first element of a float64 array (an Imu's
orientation_covariance[0]); angular_velocity: a Vector3 (read by ``rot-tools bag`` only)."""


def members(path, names):
    """Return the paths of a field's float64 members: 'q', 'xy' → ('q.x', 'q.y')."""
    return tuple(path + ('' if name.startswith('[') else '.') + name for name in names)


class Input(NamedTuple):
    """One input of the node: ~/name, its type, the fields read, their formula, its help."""

    name: str
    """The topic's name under the node (``~/name``) and rotation_client's verb."""
    type_name: str
    fields: dict
    """{role: path} read by the node and by ``rot-tools bag``, in the message's order."""
    convert: Callable
    """convert(values, settings, fields) -> (R, b) (rot_tools.io.boundary); ``values`` are
    the numbers at the paths of :meth:`floats`, in order; raises boundary.RefusedInput."""
    help: str  # noqa: A003
    bag_fields: dict = {}
    """{role: path} that only ``rot-tools bag`` reads (an Imu's gyro, for its check)."""
    covariance: tuple = ()
    """(path, size) of the float64 array holding the rotation's covariance, row-major (9: an
    Imu's orientation_covariance; 36: a PoseWithCovariance's x, y, z, rx, ry, rz), or ()
    (rot_tools.io.message_covariance reads it)."""

    @property
    def topic(self):
        """Return '~/name'."""
        return '~/' + self.name

    def strings(self):
        """Return the paths of the string fields (not read by the node), in order."""
        return tuple(path for role, path in self.fields.items() if MEMBERS[role] is None)

    def floats(self):
        """Return the paths of the float64 read, in the message's order."""
        return tuple(leaf for role, path in self.fields.items() if MEMBERS[role] is not None
                     for leaf in members(path, MEMBERS[role]))

    def slots(self):
        """Return {role: slice}: where each role's numbers are among those of floats()."""
        at, slots = 0, {}
        for role, path in self.fields.items():
            if MEMBERS[role] is not None:
                slots[role] = slice(at, at + len(MEMBERS[role]))
                at += len(MEMBERS[role])
        return slots


MATRIX = 'matrix'
"""The value of an output that publishes the input's R itself (row-major), not a field of its
decomposition."""

POSE_COVARIANCE = 'pose_covariance'
"""The value of an output that publishes a :class:`PoseCovariance` (an input's covariance)."""


class Output(NamedTuple):
    """One output of the node: ~/name, its type, the fields written and the value they hold."""

    name: str
    """The topic's name under the node (``~/name``); rotation_client prints it by this name."""
    type_name: str
    fields: tuple
    """Paths of the float64 written, in the order of the value's numbers."""
    value: str = None
    """The name of what ``fields`` hold: a field of rot_tools.core.decomposition.Decomposition
    (``'rotvec'``, ``'quaternion'``, ...), :data:`MATRIX` or :data:`POSE_COVARIANCE`; None for
    a picture, which the node draws at most MARKER_RATE times a second instead of once per
    input."""
    help: str = ''  # noqa: A003
    angles: bool = False
    """The numbers are angles, published in angle_unit (the decomposition's are in radians)."""
    layout: tuple = ()
    """(label, size, stride) of each dimension of a std_msgs MultiArray; () for a type that
    starts with a std_msgs/Header."""
    covariance: bool = False
    """Published only for an input that carries a covariance (Input.covariance), when it is
    known and converts; its value is then a :class:`PoseCovariance`."""

    @property
    def topic(self):
        """Return '~/name'."""
        return '~/' + self.name

    @property
    def stamped(self):
        """Tell whether the message carries the input's header."""
        return not self.layout


class PoseCovariance(NamedTuple):
    """What ~/rpy_covariance writes: the input's pose and a 6×6 covariance, row-major."""

    position: tuple
    orientation: tuple
    """(x, y, z, w) as the input gave it."""
    covariance: tuple
    """36 numbers: x, y, z, roll, pitch, yaw (rad, m)."""


def _xyz(path):
    return members(path, 'xyz')


_POSE = {'position': 'pose.position', 'orientation': 'pose.orientation'}
_POSE_POSE = {'position': 'pose.pose.position', 'orientation': 'pose.pose.orientation'}

INPUTS = (
    Input('pose', 'geometry_msgs/msg/PoseStamped', _POSE, boundary.pose_fields_to_rt,
          "a body's orientation and position in header.frame_id"),
    Input('euler', 'geometry_msgs/msg/Vector3Stamped', {'angles': 'vector'},
          boundary.euler_fields_to_rt,
          'x, y, z = θ1, θ2, θ3 of euler_sequence, in angle_unit (b = 0)'),
    Input('transform', 'geometry_msgs/msg/TransformStamped',
          {'child_frame_id': 'child_frame_id', **boundary.TRANSFORM_FIELDS},
          boundary.pose_fields_to_rt,
          'rotation and translation of child_frame_id in header.frame_id'),
    Input('pose_with_covariance', 'geometry_msgs/msg/PoseWithCovarianceStamped', _POSE_POSE,
          boundary.pose_fields_to_rt, 'pose.pose, and pose.covariance',
          covariance=('pose.covariance', 36)),
    Input('odometry', 'nav_msgs/msg/Odometry',
          {'child_frame_id': 'child_frame_id', **_POSE_POSE}, boundary.pose_fields_to_rt,
          'pose.pose: the body child_frame_id in header.frame_id, and pose.covariance (the '
          'twist is not used)',
          covariance=('pose.covariance', 36)),
    Input('imu', 'sensor_msgs/msg/Imu',
          {'orientation': 'orientation', 'covariance0': 'orientation_covariance'},
          boundary.imu_fields_to_rt,
          'orientation (b = 0) and orientation_covariance; refused when '
          'orientation_covariance[0] is -1 (no estimate)',
          bag_fields={'angular_velocity': 'angular_velocity'},
          covariance=('orientation_covariance', 9)),
    Input('orientation', 'geometry_msgs/msg/QuaternionStamped',
          {'orientation': 'quaternion'}, boundary.quaternion_fields_to_rt,
          'quaternion (b = 0)'),
)
"""Every input of the node; each joins the one path (header, R, b) → outputs."""

MATRIX_LAYOUT = (('rows', 3, 9), ('cols', 3, 3))
"""(label, size, stride) of the dimensions of a row-major 3x3 matrix in a std_msgs/MultiArray
(std_msgs' own convention): ~/rotation_matrix's layout."""

OUTPUTS = (
    Output('rotation_matrix', 'std_msgs/msg/Float64MultiArray',
           members('data', [f'[{k}]' for k in range(9)]), MATRIX,
           'R, 9 values row-major (the type has no header)', layout=MATRIX_LAYOUT),
    Output('quaternion', 'geometry_msgs/msg/QuaternionStamped',
           members('quaternion', 'xyzw'), 'quaternion',
           'R as (x, y, z, w), the canonical sign of matrix_to_quaternion'),
    Output('axis_angle', 'geometry_msgs/msg/Vector3Stamped', _xyz('vector'), 'rotvec',
           'rotation vector θ·l̂ (rad; its norm is the angle)'),
    Output('euler_angles', 'geometry_msgs/msg/Vector3Stamped', _xyz('vector'), 'euler',
           'θ1, θ2, θ3 of euler_sequence, in angle_unit', angles=True),
    Output('rpy', 'geometry_msgs/msg/Vector3Stamped', _xyz('vector'), 'rpy',
           'roll, pitch, yaw (REP 103: about the fixed x, y, z axes), in angle_unit',
           angles=True),
    Output('screw', 'geometry_msgs/msg/TwistStamped',
           _xyz('twist.angular') + _xyz('twist.linear'), 'twist',
           'exponential coordinates: angular = θ·l̂, linear = θ·v (screw_log)'),
    Output('rpy_covariance', 'geometry_msgs/msg/PoseWithCovarianceStamped',
           members('pose.pose.position', 'xyz') + members('pose.pose.orientation', 'xyzw')
           + members('pose.covariance', [f'[{k}]' for k in range(36)]), POSE_COVARIANCE,
           'for an input with a known covariance (~/imu, ~/pose_with_covariance, ~/odometry): '
           'its pose, and the covariance of x, y, z, roll, pitch, yaw (rad², whatever '
           'angle_unit; read as input_covariance says), none at gimbal lock',
           covariance=True),
    Output('screw_axis', 'visualization_msgs/msg/Marker', (), None,
           'when publish_markers: the screw axis, an ARROW (DELETE for the identity)'),
    Output('markers', 'visualization_msgs/msg/MarkerArray', (), None,
           "when publish_markers: the moved frame's axes, the screw axis, the helical path "
           'and a label'),
)
"""Every output of the node. Those with a ``value`` are published for every accepted input,
from one decompose pass, but a ``covariance`` one (for an input carrying a covariance,
rot_tools.io.message_covariance); the pictures (``value`` None) at a limited rate."""

TF_FIELDS = {'child_frame_id': 'child_frame_id', **boundary.TRANSFORM_FIELDS}
"""The fields of each transform of a tf2_msgs/TFMessage (a TransformStamped's)."""


def input_named(name):
    """Return the input row ``name`` (KeyError if none)."""
    return {row.name: row for row in INPUTS}[name]


def output_named(name):
    """Return the output row ``name`` (KeyError if none)."""
    return {row.name: row for row in OUTPUTS}[name]


def recorded_inputs():
    """
    Return {type name: {role: path}} of the inputs ``rot-tools bag`` reads.

    Every input with an orientation (a bag's Vector3Stamped says nothing of an Euler
    sequence, so ~/euler's type is not read), its fields and its bag_fields.
    """
    return {row.type_name: {**row.fields, **row.bag_fields} for row in INPUTS
            if 'orientation' in row.fields}
