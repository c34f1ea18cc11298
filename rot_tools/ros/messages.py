"""
ROS messages <-> NumPy: the boundary of rotation_node, and the only ROS-aware helpers.

Inbound, every input message becomes one rigid transform ``(header, R, b)``: R a (3, 3)
rotation, b a (3,) translation (b = 0 for an input that carries only an orientation), by
its row's converter (rot_tools.io.interface). A message that cannot be one transform — a
NaN/Inf in a field that is used, a zero quaternion, a quaternion whose norm is further than
the tolerance from 1, an Imu that says it has no orientation — raises
:class:`RefusedInput`, whose ``reason`` is a short key for counting. The converters and
their checks are ROS-free and live in rot_tools.io.boundary (``rot-tools bag`` runs the same
checks on recorded messages, as batches); the names the node uses are re-exported here.

Quaternions are (x, y, z, w), the ROS message order. Inbound they go through
rot_tools.quaternion_to_matrix; outbound, ~/quaternion is rot_tools.matrix_to_quaternion of R
(canonical sign), and path poses write q = (sin(θ/2)·l̂, cos(θ/2)) from the axis-angle of R,
signed for continuity along the path.

Outbound helpers build the node's other messages from NumPy values: poses and Path
(message objects), and the pictures — the screw-axis Marker and the MarkerArray of a
rot_tools.io.drawing.Picture — as serialised bytes (rot_tools.io.cdr.Writer: ~60 µs for a
picture's MarkerArray, where building Marker objects and rclpy's conversion of them took
~200 µs). The per-input outputs are bytes too (rot_tools.io.cdr, from the rows of
rot_tools.io.interface).
"""

import importlib
import struct

from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from nav_msgs.msg import Path
import numpy as np
from rot_tools.core.axis_angle import matrix_to_axis_angle
from rot_tools.io import cdr
# The inbound boundary is ROS-free and shared with `rot-tools bag`: rot_tools.io.boundary. Its
# names are re-exported here, where rotation_node has always found them.
from rot_tools.io.boundary import (  # noqa: F401
    NO_ORIENTATION, NON_FINITE, NON_UNIT_QUATERNION, pose_to_rt, REFUSAL_REASONS, RefusedInput,
    ZERO_QUATERNION)
from std_msgs.msg import Header
from visualization_msgs.msg import Marker


def type_name(msg_type):
    """'nav_msgs/msg/Odometry' for the message class nav_msgs.msg.Odometry."""
    return f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"


def message_class(name):
    """Return the message class nav_msgs.msg.Odometry of 'nav_msgs/msg/Odometry' (imported)."""
    package, kind, class_name = name.split('/')
    return getattr(importlib.import_module(f'{package}.{kind}'), class_name)


def field_value(msg, path):
    """Return the field at ``path`` of a message: 'pose.position', 'data[3]'."""
    for name in path.split('.'):
        name, _, index = name.partition('[')
        msg = getattr(msg, name)
        if index:
            msg = msg[int(index[:-1])]
    return msg


# ---------------------------------------------------------------------------------------
# Outbound: NumPy -> message


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


def _payload(write):
    """Return the payload ``write(writer)`` writes: constant fields, encoded once."""
    w = cdr.Writer()
    write(w)
    return w.payload()


_COLOR_TO_FRAME_LOCKED = struct.Struct('<4f2i?')
"""A Marker's color (float32 r, g, b, a), lifetime (sec, nanosec) and frame_locked."""

_UNUSED_BEFORE_TEXT = _payload(lambda w: (
    w.uint32(0), w.string(''), w.header(Header()), w.string(''), w.uint32(0), w.uint32(0)))
"""A Marker's empty colors, texture_resource, texture (sensor_msgs/CompressedImage: header,
format, data) and uv_coordinates: after a sequence of points, at an offset that is a
multiple of 4, as everything in it is aligned to at most 4."""

_UNUSED_AFTER_TEXT = _payload(lambda w: (
    w.string(''), w.string(''), w.uint32(0), w.boolean(False)))
"""A Marker's empty mesh_resource and mesh_file (filename, data), and
mesh_use_embedded_materials false; put aligned to 4."""


def _write_marker(w, header, ns, marker_id, kind=Marker.ARROW, action=Marker.ADD,
                  position=(0.0, 0.0, 0.0), scale=(0.0, 0.0, 0.0),
                  color=(0.0, 0.0, 0.0, 0.0), points=(), text=''):
    """
    Append a visualization_msgs/Marker to the rot_tools.io.cdr.Writer ``w``.

    Its pose is ``position`` with the identity orientation (w = 1: RViz rejects q = 0); no
    lifetime (0: until replaced), no colours per point, texture or mesh.
    """
    w.header(header)
    w.string(ns)
    w.int32(marker_id, kind, action)
    w.float64(*position, 0.0, 0.0, 0.0, 1.0, *scale)
    w.put(4, _COLOR_TO_FRAME_LOCKED.pack(*color, 0, 0, False))
    w.points(points)
    w.put(4, _UNUSED_BEFORE_TEXT)
    w.string(text)
    w.put(4, _UNUSED_AFTER_TEXT)


def _marker(header, **fields):
    """Return the bytes of one Marker (the arguments of _write_marker)."""
    w = cdr.Writer()
    _write_marker(w, header, **fields)
    return w.data()


def _marker_array(header, markers):
    """Return the bytes of a MarkerArray; ``markers``: each one's fields for _write_marker."""
    w = cdr.Writer()
    w.uint32(len(markers))
    for fields in markers:
        _write_marker(w, header, **fields)
    return w.data()


def screw_axis_marker(header, point, direction, scale):
    """
    visualization_msgs/Marker bytes: an ARROW from ``point`` to ``point + scale·direction``.

    Points in ``header.frame_id``, identity pose, id 0 so each new axis replaces the last.
    scale.x/y/z are shaft diameter, head diameter and head length, proportional to the
    arrow's length.
    """
    point = np.asarray(point, dtype=np.float64)
    tip = point + scale * np.asarray(direction, dtype=np.float64)
    return _marker(header, ns=SCREW_AXIS_NS, marker_id=0, color=SCREW_AXIS_COLOR,
                   scale=(0.05 * scale, 0.1 * scale, 0.2 * scale), points=(point, tip))


def delete_marker(header, ns, marker_id):
    """visualization_msgs/Marker bytes that delete marker (ns, marker_id) of the frame."""
    return _marker(header, ns=ns, marker_id=marker_id, action=Marker.DELETE)


def _deletes(ids):
    return [{'ns': MARKERS_NS, 'marker_id': i, 'action': Marker.DELETE} for i in ids]


def delete_picture_markers(header):
    """visualization_msgs/MarkerArray bytes that delete every marker of picture_markers."""
    return _marker_array(header, _deletes(MARKER_IDS))


def picture_markers(header, picture):
    """
    visualization_msgs/MarkerArray bytes of a rot_tools.io.drawing.Picture (see MARKER_IDS).

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
    markers = [{'ns': MARKERS_NS, 'marker_id': i, 'color': color,
                'scale': (0.05 * s, 0.1 * s, 0.2 * s),
                'points': (tail, tail + s * picture.frame[:, k])}
               for k, (i, color) in enumerate(zip(TRIAD_IDS, TRIAD_COLORS))]
    if picture.axis is None:
        markers += _deletes((AXIS_ID,))
    else:
        markers.append({'ns': MARKERS_NS, 'marker_id': AXIS_ID, 'color': SCREW_AXIS_COLOR,
                        'scale': (0.02 * s, 0.06 * s, 0.15 * s), 'points': picture.axis})
    markers.append({'ns': MARKERS_NS, 'marker_id': PATH_ID, 'kind': Marker.LINE_STRIP,
                    'color': PATH_COLOR, 'scale': (0.02 * s, 0.0, 0.0),
                    'points': picture.path})
    markers.append({'ns': MARKERS_NS, 'marker_id': LABEL_ID, 'kind': Marker.TEXT_VIEW_FACING,
                    'color': LABEL_COLOR, 'scale': (0.0, 0.0, 0.15 * s),
                    'position': tuple(map(float, picture.label_at)),
                    'text': f'{picture.label}\npath: {picture.traced}'})
    return _marker_array(header, markers)


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
