"""
The node's messages other than its per-input outputs: the pictures and ~/screw_path's Path.

The screw-axis Marker and the MarkerArray of a rot_tools.io.drawing.Picture, and the poses of
a Path. Quaternions are (x, y, z, w), the ROS message order.
"""

from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from nav_msgs.msg import Path
import numpy as np
from rot_tools.core.axis_angle import matrix_to_axis_angle
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray


SCREW_AXIS_COLOR = (1.0, 0.5, 0.0, 1.0)
SCREW_AXIS_NS = 'screw_axis'
"""Namespace of the ~/screw_axis Marker (id 0)."""

MARKERS_NS = 'rot_tools'
"""Namespace of the ~/markers MarkerArray."""

TRIAD_IDS, AXIS_ID, PATH_ID, LABEL_ID = (0, 1, 2), 3, 4, 5
"""Fixed ids of the ~/markers MarkerArray: the moved x, y, z axes, the screw axis, the path,
the label. Each input sends every one of them (ADD or DELETE), so it replaces the last."""

MARKER_IDS = TRIAD_IDS + (AXIS_ID, PATH_ID, LABEL_ID)

TRIAD_COLORS = ((1.0, 0.0, 0.0, 1.0), (0.0, 1.0, 0.0, 1.0), (0.0, 0.0, 1.0, 1.0))
PATH_COLOR = (1.0, 0.0, 1.0, 1.0)
LABEL_COLOR = (1.0, 1.0, 1.0, 1.0)
"""Colours (r, g, b, a): the moved x, y, z axes red, green, blue; the path magenta; the
label white (the screw axis orange)."""


def point_msg(p):
    """geometry_msgs/Point of a 3-vector."""
    return Point(x=float(p[0]), y=float(p[1]), z=float(p[2]))


def marker(header, ns, marker_id, marker_type=Marker.ARROW, action=Marker.ADD,
           position=(0.0, 0.0, 0.0), scale=(0.0, 0.0, 0.0), color=(0.0, 0.0, 0.0, 0.0),
           points=(), text=''):
    """
    Return a visualization_msgs/Marker in ``header``'s frame.

    Its pose is ``position`` with the identity orientation (w = 1: RViz rejects q = 0);
    ``points`` (n, 3) carry the geometry; no lifetime (0: until replaced), no colours per
    point, texture or mesh.
    """
    msg = Marker(header=header, ns=ns, id=marker_id, type=marker_type, action=action, text=text,
                 points=[point_msg(p) for p in points],
                 color=ColorRGBA(r=color[0], g=color[1], b=color[2], a=color[3]))
    msg.pose.position = point_msg(position)
    msg.pose.orientation.w = 1.0
    msg.scale.x, msg.scale.y, msg.scale.z = map(float, scale)
    return msg


def screw_axis_marker(header, point, direction, scale):
    """
    visualization_msgs/Marker: an ARROW from ``point`` to ``point + scale·direction``.

    Points in ``header.frame_id``, identity pose, id 0 so each new axis replaces the last.
    scale.x/y/z are shaft diameter, head diameter and head length, proportional to the
    arrow's length.
    """
    point = np.asarray(point, dtype=np.float64)
    tip = point + scale * np.asarray(direction, dtype=np.float64)
    return marker(header, SCREW_AXIS_NS, 0, color=SCREW_AXIS_COLOR,
                  scale=(0.05 * scale, 0.1 * scale, 0.2 * scale), points=(point, tip))


def delete_marker(header, ns, marker_id):
    """visualization_msgs/Marker that deletes marker (ns, marker_id) of the frame."""
    return marker(header, ns, marker_id, action=Marker.DELETE)


def delete_picture_markers(header):
    """visualization_msgs/MarkerArray that deletes every marker of picture_markers."""
    return MarkerArray(markers=[delete_marker(header, MARKERS_NS, i) for i in MARKER_IDS])


def picture_markers(header, picture):
    """
    visualization_msgs/MarkerArray of a rot_tools.io.drawing.Picture (see MARKER_IDS).

    In ``header.frame_id``, namespace MARKERS_NS: the moved frame's x, y, z axes as red,
    green and blue ARROWs from b (picture.scale long), the screw axis as an orange ARROW
    along +l̂, the path as a magenta LINE_STRIP and the label as TEXT_VIEW_FACING text at
    picture.label_at. What the picture does not hold (the axis of a pure translation,
    everything of the identity) is a DELETE of its id. Every pose is the identity
    (orientation.w = 1) but the label's position, the points carry the geometry; sizes are
    fractions of the scale.
    """
    s = picture.scale
    if picture.path is None:
        return delete_picture_markers(header)
    tail = picture.origin
    markers = [marker(header, MARKERS_NS, i, color=color, scale=(0.05 * s, 0.1 * s, 0.2 * s),
                      points=(tail, tail + s * picture.frame[:, k]))
               for k, (i, color) in enumerate(zip(TRIAD_IDS, TRIAD_COLORS))]
    if picture.axis is None:
        markers.append(delete_marker(header, MARKERS_NS, AXIS_ID))
    else:
        markers.append(marker(header, MARKERS_NS, AXIS_ID, color=SCREW_AXIS_COLOR,
                              scale=(0.02 * s, 0.06 * s, 0.15 * s), points=picture.axis))
    markers.append(marker(header, MARKERS_NS, PATH_ID, marker_type=Marker.LINE_STRIP,
                          color=PATH_COLOR, scale=(0.02 * s, 0.0, 0.0), points=picture.path))
    markers.append(marker(header, MARKERS_NS, LABEL_ID, marker_type=Marker.TEXT_VIEW_FACING,
                          color=LABEL_COLOR, scale=(0.0, 0.0, 0.15 * s),
                          position=picture.label_at,
                          text=f'{picture.label}\npath: {picture.traced}'))
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
