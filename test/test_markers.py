"""The node's MarkerArray and ~/screw_axis DELETE, expected from (R, b), not io.drawing."""

import math

from geometry_msgs.msg import Point
import numpy as np
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rot_tools.io.drawing import picture
from rot_tools.ros.node import messages
from scipy.spatial.transform import Rotation
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

HEADER = Header(frame_id='odom')
HEADER.stamp.sec = 42


def received(msg):
    """Return ``msg`` as a subscriber gets it: serialised by rclpy and read back."""
    return deserialize_message(serialize_message(msg), type(msg))


def picture_markers(header, pic):
    """Return the MarkerArray of messages.picture_markers, as a subscriber gets it."""
    return received(messages.picture_markers(header, pic))


def delete_marker(header, ns, marker_id):
    return received(messages.delete_marker(header, ns, marker_id))


def xyz(v):
    return np.array([v.x, v.y, v.z])


def by_id(array):
    return {m.id: m for m in array.markers}


def check_common(array):
    """Check unique (ns, id), the input's header and unit quaternions on every marker."""
    keys = [(m.ns, m.id) for m in array.markers]
    assert len(set(keys)) == len(keys) == 6
    assert {m.ns for m in array.markers} == {'rot_tools'}
    for m in array.markers:
        assert (m.header.frame_id, m.header.stamp.sec) == ('odom', 42)
        q = m.pose.orientation
        assert (q.x, q.y, q.z, q.w) == (0.0, 0.0, 0.0, 1.0)


def test_screw_markers():
    axis, c, theta, d = np.array([0.0, 0.6, 0.8]), np.array([1.0, 0.0, 0.0]), 2.0, 0.7
    R = Rotation.from_rotvec(theta * axis).as_matrix()
    b = (np.eye(3) - R) @ c + d * axis
    scale = 0.4
    array = picture_markers(HEADER, picture(R, b, scale=scale))
    check_common(array)
    m = by_id(array)
    assert all(x.action == Marker.ADD for x in array.markers)
    for k, color in enumerate(((1, 0, 0), (0, 1, 0), (0, 0, 1))):  # x red, y green, z blue
        arrow = m[messages.TRIAD_IDS[k]]
        assert arrow.type == Marker.ARROW
        assert (arrow.color.r, arrow.color.g, arrow.color.b, arrow.color.a) == (*color, 1.0)
        np.testing.assert_allclose(xyz(arrow.points[0]), b, rtol=0, atol=1e-15)
        np.testing.assert_allclose(xyz(arrow.points[1]) - b, scale * R[:, k], rtol=0,
                                   atol=1e-15)
        assert arrow.scale.x == pytest.approx(0.05 * scale)
    screw_axis = m[messages.AXIS_ID]
    assert screw_axis.type == Marker.ARROW and len(screw_axis.points) == 2
    start, end = xyz(screw_axis.points[0]), xyz(screw_axis.points[1])
    for e in (start, end):
        assert np.linalg.norm(np.cross(e - c, axis)) < 1e-12
    np.testing.assert_allclose((end - start) / np.linalg.norm(end - start), axis,
                               rtol=0, atol=1e-12)  # along +l̂
    path = m[messages.PATH_ID]
    assert path.type == Marker.LINE_STRIP and path.scale.x > 0
    points = np.array([xyz(p) for p in path.points])
    s = np.linspace(0.0, 1.0, len(points))
    turns = Rotation.from_rotvec(np.outer(s, theta * axis))
    np.testing.assert_allclose(points, c + turns.apply(-c) + np.outer(s * d, axis),
                               rtol=0, atol=1e-12)
    label = m[messages.LABEL_ID]
    assert label.type == Marker.TEXT_VIEW_FACING and label.scale.z > 0
    assert label.text == (f'theta = 2 rad, d = 0.7, screw pitch = {0.7 / 2:.4g} /rad\n'
                          'path: origin')


@pytest.mark.parametrize('theta', [0.01, 1e-8])
def test_a_small_turn_is_labelled_beside_the_motion(theta):
    # A small turn about z, b = (1, 0, 0): the axis 100 or 1e8 away, the label by the path.
    R = Rotation.from_rotvec([0.0, 0.0, theta]).as_matrix()
    b, scale = np.array([1.0, 0.0, 0.0]), 0.5
    m = by_id(picture_markers(HEADER, picture(R, b, scale=scale)))
    at = xyz(m[messages.LABEL_ID].pose.position)
    on_chord = np.clip(at @ b, 0.0, 1.0) * b
    assert np.linalg.norm(at - on_chord) <= 0.35 * scale
    start, end = (xyz(p) for p in m[messages.AXIS_ID].points)
    np.testing.assert_allclose(start[:2], (0.5, 0.5 / math.tan(theta / 2)), rtol=1e-9)
    assert end - start == pytest.approx((0, 0, 3 * scale))  # the frame's z tip ± scale
    for k in range(3):
        arrow = m[messages.TRIAD_IDS[k]]
        np.testing.assert_allclose(xyz(arrow.points[1]) - b, scale * R[:, k], atol=1e-15)


def test_pure_translation_deletes_the_axis():
    array = picture_markers(HEADER, picture(np.eye(3), (0.0, 3.0, 4.0)))
    check_common(array)
    m = by_id(array)
    assert m[messages.AXIS_ID].action == Marker.DELETE
    assert all(m[i].action == Marker.ADD for i in messages.MARKER_IDS
               if i != messages.AXIS_ID)
    assert [xyz(p).tolist() for p in m[messages.PATH_ID].points] == [[0, 0, 0], [0, 3, 4]]
    assert 'screw pitch = inf' in m[messages.LABEL_ID].text


def test_pure_rotation_labels_the_traced_tip():
    R = Rotation.from_rotvec([0.0, 0.0, math.pi / 2]).as_matrix()
    array = picture_markers(HEADER, picture(R, np.zeros(3), degrees=True))
    m = by_id(array)
    assert m[messages.LABEL_ID].text == ('theta = 90 deg, d = 0, screw pitch = 0 /rad\n'
                                         'path: x-axis tip')
    np.testing.assert_allclose(xyz(m[messages.PATH_ID].points[-1]), (0, 1, 0), atol=1e-15)


def test_identity_deletes_every_marker():
    array = picture_markers(HEADER, picture(np.eye(3), np.zeros(3)))
    check_common(array)
    assert [m.action for m in array.markers] == [Marker.DELETE] * 6


def test_delete_marker():
    m = delete_marker(HEADER, 'screw_axis', 0)
    assert (m.ns, m.id, m.action, m.header.frame_id) == ('screw_axis', 0, Marker.DELETE, 'odom')
    assert m.pose.orientation.w == 1.0


def reference_marker(header, ns, marker_id, kind, action, color=(0, 0, 0, 0), size=(0, 0, 0),
                     points=(), position=(0, 0, 0), text=''):
    """Return the Marker built with rclpy's message objects, field by field."""
    msg = Marker(header=header, ns=ns, id=marker_id, type=kind, action=action,
                 color=ColorRGBA(r=float(color[0]), g=float(color[1]), b=float(color[2]),
                                 a=float(color[3])),
                 points=[Point(x=float(x), y=float(y), z=float(z)) for x, y, z in points],
                 text=text)
    msg.scale.x, msg.scale.y, msg.scale.z = map(float, size)
    msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = map(float, position)
    msg.pose.orientation.w = 1.0
    return msg


@pytest.mark.parametrize('frame_id', ['odom', 'base_link_3', ''])
def test_the_markers_are_those_built_field_by_field(frame_id):
    header = Header(frame_id=frame_id)
    header.stamp.sec, header.stamp.nanosec = -3, 4_000_000_000
    R = Rotation.from_rotvec([0.3, -0.2, 1.1]).as_matrix()
    pic = picture(R, np.array([0.5, -1.0, 2.0]), scale=0.7, degrees=True)
    s, ADD, ARROW = pic.scale, Marker.ADD, Marker.ARROW
    expected = [reference_marker(header, 'rot_tools', k, ARROW, ADD, color,
                                 (0.05 * s, 0.1 * s, 0.2 * s),
                                 (pic.origin, pic.origin + s * pic.frame[:, k]))
                for k, color in enumerate(((1, 0, 0, 1), (0, 1, 0, 1), (0, 0, 1, 1)))]
    expected += [
        reference_marker(header, 'rot_tools', 3, ARROW, ADD, (1, 0.5, 0, 1),
                         (0.02 * s, 0.06 * s, 0.15 * s), pic.axis),
        reference_marker(header, 'rot_tools', 4, Marker.LINE_STRIP, ADD, (1, 0, 1, 1),
                         (0.02 * s, 0, 0), pic.path),
        reference_marker(header, 'rot_tools', 5, Marker.TEXT_VIEW_FACING, ADD, (1, 1, 1, 1),
                         (0, 0, 0.15 * s), position=pic.label_at,
                         text=f'{pic.label}\npath: {pic.traced}')]
    for ours, reference in (
            (messages.picture_markers(header, pic), MarkerArray(markers=expected)),
            (messages.delete_picture_markers(header), MarkerArray(markers=[
                reference_marker(header, 'rot_tools', i, ARROW, Marker.DELETE)
                for i in range(6)])),
            (messages.screw_axis_marker(header, (1, 2, 3), (0, 0.6, 0.8), 2.0),
             reference_marker(header, 'screw_axis', 0, ARROW, ADD, (1, 0.5, 0, 1),
                              (0.1, 0.2, 0.4), ((1, 2, 3), (1, 3.2, 4.6))))):
        assert type(ours) is type(reference)
        assert received(ours) == reference
