"""
ROS messages <-> NumPy: the boundary of rotation_node, and the only ROS-aware helpers.

Inbound, every input message becomes one rigid transform ``(header, R, b)``: R a (3, 3)
rotation, b a (3,) translation (b = 0 for an input that carries only an orientation). Every
converter has the form ``convert(msg, settings)``, where ``settings`` is rotation_node's
Settings: the converters read ``quaternion_tolerance``, and the Euler one
``euler_sequence`` and ``degrees``. A message that cannot be one transform — a NaN/Inf in a
field that is used, a zero quaternion, a quaternion whose norm is further than the tolerance
from 1, an Imu that says it has no orientation — raises :class:`RefusedInput`, whose
``reason`` is a short key for counting. The converters and their checks are ROS-free and
live in rot_tools.boundary (``rot-tools bag`` runs the same checks on recorded messages, as
batches); they are re-exported here.

Quaternions are (x, y, z, w), the ROS message order. Inbound they go through
rot_tools.quaternion_to_matrix; outbound, ~/quaternion is rot_tools.matrix_to_quaternion of R
(canonical sign), and path poses write q = (sin(θ/2)·l̂, cos(θ/2)) from the axis-angle of R,
signed for continuity along the path.

Outbound helpers build the node's other messages from NumPy values: the screw-axis Marker,
poses and Path, and the MarkerArray of a rot_tools.drawing.Picture (the per-input outputs
are written as bytes, rot_tools.cdr; MATRIX_DIMS is ~/rotation_matrix's layout).
"""

from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from nav_msgs.msg import Path
import numpy as np
from rot_tools.axis_angle import matrix_to_axis_angle
# The inbound boundary is ROS-free and shared with `rot-tools bag`: rot_tools.boundary. Its
# names are re-exported here, where rotation_node has always found them.
from rot_tools.boundary import (  # noqa: F401
    euler_stamped_to_transform, imu_to_transform, NO_ORIENTATION, NON_FINITE,
    NON_UNIT_QUATERNION, odometry_to_transform, pose_stamped_to_transform,
    pose_to_rt, pose_with_covariance_stamped_to_transform, quaternion_msg_to_matrix,
    quaternion_stamped_to_transform, REFUSAL_REASONS, RefusedInput,
    transform_stamped_to_transform, ZERO_QUATERNION)
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray


def type_name(msg_type):
    """'nav_msgs/msg/Odometry' for the message class nav_msgs.msg.Odometry."""
    return f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"


# ---------------------------------------------------------------------------------------
# Outbound: NumPy -> message

MATRIX_DIMS = (('rows', 3, 9), ('cols', 3, 3))
"""(label, size, stride) of the dimensions of a row-major 3x3 matrix in a std_msgs/MultiArray
(std_msgs' own convention): ~/rotation_matrix's layout."""


def _set_xyz(target, v):
    target.x, target.y, target.z = float(v[0]), float(v[1]), float(v[2])


SCREW_AXIS_COLOR = ColorRGBA(r=1.0, g=0.5, b=0.0, a=1.0)
SCREW_AXIS_NS = 'screw_axis'
"""Namespace of the ~/screw_axis Marker (id 0)."""


def screw_axis_marker(header, point, direction, scale, msg=None, ns=SCREW_AXIS_NS):
    """
    visualization_msgs/Marker: an ARROW from ``point`` to ``point + scale·direction``.

    Points in ``header.frame_id``, identity pose (orientation.w = 1: RViz rejects q = 0),
    id 0 so each new axis replaces the last. scale.x/y/z are shaft diameter, head diameter
    and head length, proportional to the arrow's length.
    """
    if msg is None:  # (the node refills one: building a Marker costs more than the math)
        msg = Marker(ns=ns, id=0, type=Marker.ARROW, action=Marker.ADD,
                     points=[Point(), Point()], color=SCREW_AXIS_COLOR)
        msg.pose.orientation.w = 1.0
    msg.header = header
    px, py, pz = float(point[0]), float(point[1]), float(point[2])
    tail, tip = msg.points
    tail.x, tail.y, tail.z = px, py, pz
    tip.x = px + scale * float(direction[0])
    tip.y = py + scale * float(direction[1])
    tip.z = pz + scale * float(direction[2])
    _set_xyz(msg.scale, (0.05 * scale, 0.1 * scale, 0.2 * scale))
    return msg


def delete_marker(header, ns, marker_id):
    """visualization_msgs/Marker that deletes marker (ns, marker_id) of ``header.frame_id``."""
    msg = Marker(header=header, ns=ns, id=marker_id, action=Marker.DELETE)
    msg.pose.orientation.w = 1.0
    return msg


MARKERS_NS = 'rot_tools'
"""Namespace of the ~/markers MarkerArray."""

TRIAD_IDS, AXIS_ID, PATH_ID, LABEL_ID = (0, 1, 2), 3, 4, 5
"""Fixed ids of the ~/markers MarkerArray: the moved x, y, z axes, the screw axis, the path,
the label. Each input sends every one of them (ADD or DELETE), so it replaces the last."""

MARKER_IDS = TRIAD_IDS + (AXIS_ID, PATH_ID, LABEL_ID)

TRIAD_COLORS = (ColorRGBA(r=1.0, g=0.0, b=0.0, a=1.0), ColorRGBA(r=0.0, g=1.0, b=0.0, a=1.0),
                ColorRGBA(r=0.0, g=0.0, b=1.0, a=1.0))
PATH_COLOR = ColorRGBA(r=1.0, g=0.0, b=1.0, a=1.0)
LABEL_COLOR = ColorRGBA(r=1.0, g=1.0, b=1.0, a=1.0)


def _points(points):
    return [Point(x=x, y=y, z=z) for x, y, z in np.asarray(points, dtype=np.float64).tolist()]


def _marker(header, marker_id, kind, color, size, points=None):
    """Return an ADD Marker of ``kind`` in namespace MARKERS_NS with an identity pose."""
    msg = Marker(header=header, ns=MARKERS_NS, id=marker_id, type=kind, action=Marker.ADD,
                 color=color, points=_points(points) if points is not None else [])
    _set_xyz(msg.scale, size)
    msg.pose.orientation.w = 1.0
    return msg


def delete_picture_markers(header):
    """visualization_msgs/MarkerArray that deletes every marker of picture_markers."""
    return MarkerArray(markers=[delete_marker(header, MARKERS_NS, i) for i in MARKER_IDS])


def picture_markers(header, picture):
    """
    visualization_msgs/MarkerArray of a rot_tools.drawing.Picture (see MARKER_IDS).

    In ``header.frame_id``, namespace MARKERS_NS: the moved frame's x, y, z axes as red,
    green and blue ARROWs from b (picture.scale long), the screw axis as an orange ARROW
    along +l̂, the path as a magenta LINE_STRIP and the label as TEXT_VIEW_FACING text at
    picture.label_at. What the picture does not hold (the axis of a pure translation,
    everything of the identity) is a DELETE of its id. Every pose is the identity
    (orientation.w = 1), the points carry the geometry; sizes are fractions of the scale.
    """
    s = picture.scale
    if picture.path is None:
        return delete_picture_markers(header)
    tail = picture.origin
    markers = [_marker(header, i, Marker.ARROW, color, (0.05 * s, 0.1 * s, 0.2 * s),
                       (tail, tail + s * picture.frame[:, k]))
               for k, (i, color) in enumerate(zip(TRIAD_IDS, TRIAD_COLORS))]
    if picture.axis is None:
        markers.append(delete_marker(header, MARKERS_NS, AXIS_ID))
    else:
        markers.append(_marker(header, AXIS_ID, Marker.ARROW, SCREW_AXIS_COLOR,
                               (0.02 * s, 0.06 * s, 0.15 * s), picture.axis))
    markers.append(_marker(header, PATH_ID, Marker.LINE_STRIP, PATH_COLOR,
                           (0.02 * s, 0.0, 0.0), picture.path))
    label = _marker(header, LABEL_ID, Marker.TEXT_VIEW_FACING, LABEL_COLOR, (0.0, 0.0, 0.15 * s))
    label.text = f'{picture.label}\npath: {picture.traced}'
    _set_xyz(label.pose.position, picture.label_at)
    markers.append(label)
    return MarkerArray(markers=markers)


def matrices_to_quaternions(R, first=None):
    """
    Quaternions (n, 4) as (x, y, z, w) of rotations R (n, 3, 3), continuous in sign.

    q = (sin(θ/2)·l̂, cos(θ/2)) from matrix_to_axis_angle. q and −q are the same rotation;
    each q is signed so that its dot product with the previous one (with ``first`` (4,) for
    the first, when given) is not negative, as interpolating consumers expect.
    """
    axis, angle = matrix_to_axis_angle(R, check=False)
    half = 0.5 * np.asarray(angle)
    q = np.concatenate([axis * np.sin(half)[..., None], np.cos(half)[..., None]], axis=-1)
    prev = np.concatenate([[first if first is not None else q[0]], q[:-1]])
    flips = np.einsum('ij,ij->i', q, prev) < 0
    return q * np.where(np.cumsum(flips) % 2 == 1, -1.0, 1.0)[:, None]


def pose_msg(position, quaternion):
    """geometry_msgs/Pose of a position (3,) and a quaternion (x, y, z, w)."""
    return Pose(position=Point(x=float(position[0]), y=float(position[1]),
                               z=float(position[2])),
                orientation=Quaternion(x=float(quaternion[0]), y=float(quaternion[1]),
                                       z=float(quaternion[2]), w=float(quaternion[3])))


def path_msg(header, start, goal, R, b):
    """
    nav_msgs/Path: ``start``, the poses (R[k], b[k]) in between, then ``goal``.

    start and goal are PoseStamped copied as given; R (n, 3, 3) and b (n, 3) include both
    ends (only the inner n − 2 are converted); every inner pose gets ``header``.
    """
    q0 = start.pose.orientation
    first = np.array((q0.x, q0.y, q0.z, q0.w))
    first /= np.linalg.norm(first)
    inner = []
    if len(R) > 2:
        quats = matrices_to_quaternions(R[1:-1], first)
        inner = [PoseStamped(header=header, pose=pose_msg(p, q)) for p, q in zip(b[1:-1], quats)]
    return Path(header=header, poses=[start] + inner + [goal])
