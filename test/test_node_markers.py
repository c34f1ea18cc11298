"""rotation_node's ~/markers and ~/screw_axis, expected from the input alone."""

import math
import time

import numpy as np
import pytest
from rcl_interfaces.msg import Log
from rclpy.qos import DurabilityPolicy, ReliabilityPolicy
from rot_tools.ros.node import pictures
from rot_tools.ros.node.diagnostics import PERIOD
from rot_tools.ros.node.pictures import MARKER_RATE
from scipy.spatial.transform import Rotation
from test_node import (  # noqa: F401  (make_rig and rig are fixtures)
    euler_stamped, make_rig, pose_stamped, quat, rig, set_one, transform_stamped, xyz)
from visualization_msgs.msg import Marker

TRIAD, AXIS, PATH, LABEL = (0, 1, 2), 3, 4, 5
COLORS = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))  # x red, y green, z blue


def expected_screw(q, b):
    """(R, l̂, c, θ, d) of the pose (q, b), independently of rot_tools (θ < π)."""
    rotation = Rotation.from_quat(q)
    R, rotvec = rotation.as_matrix(), rotation.as_rotvec()
    theta = np.linalg.norm(rotvec)
    u = rotvec / theta
    d = float(np.dot(b, u))
    c = np.linalg.lstsq(np.eye(3) - R, b - d * u, rcond=None)[0]
    return R, u, c, theta, d


def helix(u, c, theta, d, p0, n):
    """p0 carried by the constant-screw motion, at s = 0, 1/n, ..., 1."""
    s = np.linspace(0.0, 1.0, n + 1)
    return c + Rotation.from_rotvec(np.outer(s, theta * u)).apply(p0 - c) + np.outer(s * d, u)


def check_array(array, stamp, frame):
    """Check unique (ns, id) 0..5 in namespace rot_tools, the header, unit quaternions."""
    keys = [(m.ns, m.id) for m in array.markers]
    assert sorted(keys) == [('rot_tools', i) for i in range(6)]
    for m in array.markers:
        assert (m.header.stamp.sec, m.header.frame_id) == (stamp, frame)
        assert quat(m.pose.orientation).tolist() == [0.0, 0.0, 0.0, 1.0]
    return {m.id: m for m in array.markers}


def check_triad(m, R, b, scale):
    for k in TRIAD:
        arrow = m[k]
        assert (arrow.type, arrow.action) == (Marker.ARROW, Marker.ADD)
        assert (arrow.color.r, arrow.color.g, arrow.color.b) == COLORS[k]
        assert arrow.color.a == 1.0 and arrow.scale.x > 0 and arrow.scale.y > 0
        np.testing.assert_allclose(xyz(arrow.points[0]), b, rtol=0, atol=1e-12)
        np.testing.assert_allclose(xyz(arrow.points[1]) - b, scale * R[:, k], rtol=0,
                                   atol=1e-12)


POSES = {
    'general': ((0.2, -0.4, 0.5, 0.74162), (1.0, -0.5, 2.0), 1.0),
    'quarter_turn_z': ((0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)), (1.0, 0.0, 0.5), 1.0),
    'small_scale': ((0.6, 0.0, 0.0, 0.8), (0.0, 2.0, -1.0), 0.25),
}


@pytest.mark.parametrize('case', POSES)
@pytest.mark.parametrize('kind', ['pose', 'transform'])
def test_markers_of_a_screw_motion(make_rig, case, kind):  # noqa: F811
    q, b, scale = POSES[case]
    q, b = np.array(q) / np.linalg.norm(q), np.array(b)
    rig = make_rig(marker_scale=scale)  # noqa: F811
    build = pose_stamped if kind == 'pose' else transform_stamped
    stamp = rig.send(kind, build(q, b, frame='odom'))
    m = check_array(rig.output_of('markers', stamp), stamp, 'odom')
    R, u, c, theta, d = expected_screw(q, b)
    check_triad(m, R, b, scale)
    size = 1 + np.linalg.norm(c) + abs(d)
    # The path: a LINE_STRIP from the origin to b on the constant-screw motion.
    path = m[PATH]
    assert (path.type, path.action) == (Marker.LINE_STRIP, Marker.ADD) and path.scale.x > 0
    points = np.array([xyz(p) for p in path.points])
    assert theta / (len(points) - 1) <= math.radians(3.0) + 1e-15  # steps of at most 3°
    np.testing.assert_array_equal(points[0], np.zeros(3))
    np.testing.assert_allclose(points[-1], b, rtol=0, atol=1e-12 * size)
    np.testing.assert_allclose(points, helix(u, c, theta, d, np.zeros(3), len(points) - 1),
                               rtol=0, atol=1e-12 * size)
    # The axis: an ARROW whose ends lie on the line through c along +l̂, at least
    # marker_scale beyond the origin's and b's feet on it.
    axis = m[AXIS]
    assert (axis.type, axis.action) == (Marker.ARROW, Marker.ADD)
    start, end = xyz(axis.points[0]), xyz(axis.points[1])
    for e in (start, end):
        assert np.linalg.norm(np.cross(e - c, u)) <= 1e-12 * size
    np.testing.assert_allclose((end - start) / np.linalg.norm(end - start), u, atol=1e-12)
    assert (start - c) @ u <= min(0.0, d) - scale + 1e-12
    assert (end - c) @ u >= max(0.0, d) + scale - 1e-12
    label = m[LABEL]
    assert (label.type, label.action) == (Marker.TEXT_VIEW_FACING, Marker.ADD)
    assert label.scale.z > 0
    assert label.text == (f'theta = {theta:.4g} rad, d = {d + 0.0:.4g}, '
                          f'screw pitch = {d / theta + 0.0:.4g} /rad\npath: origin')
    # ~/screw_axis of the same input: the arrow from c along l̂, marker_scale long.
    arrow = rig.output_of('screw_axis', stamp)
    assert (arrow.ns, arrow.id, arrow.action) == ('screw_axis', 0, Marker.ADD)
    np.testing.assert_allclose(xyz(arrow.points[0]), c, rtol=0, atol=1e-12 * size)
    np.testing.assert_allclose(xyz(arrow.points[1]) - c, scale * u, rtol=0, atol=1e-12 * size)


def test_pure_rotation_draws_the_arc_of_the_x_tip(make_rig):  # noqa: F811
    rig = make_rig(angle_unit='deg', marker_scale=2.0)  # noqa: F811
    stamp = rig.send('euler', euler_stamped((90.0, 0.0, 0.0)))  # ZYX: 90° about z
    m = check_array(rig.output_of('markers', stamp), stamp, 'map')
    R = Rotation.from_rotvec([0.0, 0.0, math.pi / 2]).as_matrix()
    check_triad(m, R, np.zeros(3), 2.0)
    arc = np.array([xyz(p) for p in m[PATH].points])
    np.testing.assert_allclose(arc, helix(np.array([0.0, 0, 1]), np.zeros(3), math.pi / 2, 0.0,
                                          np.array([2.0, 0, 0]), len(arc) - 1),
                               rtol=0, atol=1e-12)
    start, end = xyz(m[AXIS].points[0]), xyz(m[AXIS].points[1])
    np.testing.assert_allclose([start[:2], end[:2]], 0.0, atol=1e-15)
    assert end[2] - start[2] >= 4.0  # marker_scale beyond both ends of the drawing
    assert m[LABEL].text == 'theta = 90 deg, d = 0, screw pitch = 0 /rad\npath: x-axis tip'


def test_identity_deletes_what_was_drawn_on_both_topics(rig):  # noqa: F811
    before = rig.send('pose', pose_stamped((0, 0, 1, 0), (1, 0, 0)))
    rig.output_of('markers', before)
    rig.output_of('screw_axis', before)
    stamp = rig.send('pose', pose_stamped((0, 0, 0, 1)))
    m = check_array(rig.output_of('markers', stamp), stamp, 'map')
    assert [m[i].action for i in range(6)] == [Marker.DELETE] * 6
    arrow = rig.output_of('screw_axis', stamp)
    assert (arrow.ns, arrow.id, arrow.action) == ('screw_axis', 0, Marker.DELETE)
    assert quat(arrow.pose.orientation).tolist() == [0.0, 0.0, 0.0, 1.0]
    # Drawing again after the identity: ADD on both.
    after = rig.send('euler', euler_stamped((0.5, 0.0, 0.0)))
    assert all(x.action == Marker.ADD for x in rig.output_of('markers', after).markers)
    assert rig.output_of('screw_axis', after).action == Marker.ADD


def test_pure_translation_deletes_the_axis_and_draws_a_straight_path(rig):  # noqa: F811
    before = rig.send('pose', pose_stamped((0.6, 0, 0, 0.8), (0, 1, 0)))
    rig.output_of('markers', before)
    b = np.array([1.0, -2.0, 2.0])
    stamp = rig.send('transform', transform_stamped((0, 0, 0, 1), b))
    m = check_array(rig.output_of('markers', stamp), stamp, 'map')
    assert m[AXIS].action == Marker.DELETE
    check_triad(m, np.eye(3), b, 1.0)
    assert [xyz(p).tolist() for p in m[PATH].points] == [[0, 0, 0], b.tolist()]
    assert m[LABEL].text == 'theta = 0 rad, d = 3, screw pitch = inf\npath: origin'


def actions(rig):  # noqa: F811
    """[(stamp, frame, actions)] of every ~/markers array and ~/screw_axis Marker received."""
    def of(markers):
        return (markers[0].header.stamp.sec, markers[0].header.frame_id,
                [m.action for m in markers])
    return ([of(a.markers) for a in rig.received('markers')],
            [of([m]) for m in rig.received('screw_axis')])


def test_publish_markers_false_silences_both(make_rig):  # noqa: F811
    rig = make_rig(publish_markers=False)  # noqa: F811
    for msg in (pose_stamped((0, 0, 1, 0), (1, 0, 0)), pose_stamped((0, 0, 0, 1))):
        rig.roundtrip('pose', msg, marker=False)
    assert set_one(rig.node, 'publish_markers', True).successful
    stamp = rig.send('pose', pose_stamped((0, 1, 0, 0), (0, 0, 1), frame='odom'))
    rig.output_of('markers', stamp)
    rig.output_of('screw_axis', stamp)
    assert set_one(rig.node, 'publish_markers', False).successful
    rig.roundtrip('pose', pose_stamped((0, 0, 0, 1)), marker=False)
    rig.roundtrip('pose', pose_stamped((1, 0, 0, 0), (1, 1, 1)), marker=False)
    rig.tester.spin_for(3.0 / MARKER_RATE)  # a throttled picture would have come by now
    # The picture drawn, then its DELETEs (switched off) in its frame, once; nothing more.
    assert actions(rig) == ([(stamp, 'odom', [Marker.ADD] * 6),
                             (stamp, 'odom', [Marker.DELETE] * 6)],
                            [(stamp, 'odom', [Marker.ADD]), (stamp, 'odom', [Marker.DELETE])])


def test_the_picture_timer_exists_only_while_markers_are_published(make_rig):  # noqa: F811
    # Without pictures the node has no timer of theirs for its executor to wait on (its
    # other timer is /diagnostics', once a second).
    rig = make_rig(publish_markers=False)  # noqa: F811

    def picture_timers():
        return [t for t in rig.node.timers if t.timer_period_ns != PERIOD * 1e9]

    assert len(list(rig.node.timers)) == 1 and picture_timers() == []
    assert set_one(rig.node, 'publish_markers', True).successful
    assert len(picture_timers()) == 1
    stamp = rig.send('pose', pose_stamped((0, 0, 1, 0), (1, 0, 0)))
    rig.output_of('markers', stamp)
    assert set_one(rig.node, 'publish_markers', False).successful
    assert picture_timers() == []


def test_switching_markers_off_deletes_the_picture_and_drops_the_one_waiting(
        make_rig, monkeypatch):  # noqa: F811
    """Switching markers off deletes the picture shown, once; the one waiting is never drawn."""
    monkeypatch.setattr(pictures, 'MARKER_RATE', 0.5)
    rig = make_rig()  # noqa: F811
    shown = rig.send('pose', pose_stamped((0, 0, 1, 0), (1, 0, 0), frame='odom'))
    rig.output_of('markers', shown)
    rig.output_of('screw_axis', shown)
    waiting = rig.roundtrip('euler', euler_stamped((0.5, 0.0, 0.0), frame='base_link'),
                            marker=False)['screw'].header.stamp.sec
    drawn = ([(shown, 'odom', [Marker.ADD] * 6)], [(shown, 'odom', [Marker.ADD])])
    assert actions(rig) == drawn  # the second input's picture waits for its turn
    assert set_one(rig.node, 'publish_markers', False).successful
    deleted = ([(shown, 'odom', [Marker.ADD] * 6), (shown, 'odom', [Marker.DELETE] * 6)],
               [(shown, 'odom', [Marker.ADD]), (shown, 'odom', [Marker.DELETE])])
    rig.tester.spin_until(lambda: actions(rig) == deleted, what='the DELETEs')
    for name, value in (('publish_markers', False), ('marker_scale', 2.0),
                        ('publish_markers', True)):
        assert set_one(rig.node, name, value).successful
    rig.tester.spin_for(2.5)  # the throttle's turn (2 s) has come and gone
    assert actions(rig) == deleted, f'the picture of input {waiting} was drawn'
    # Switched on again, the next input is drawn; off after an identity: nothing to delete.
    after = rig.send('pose', pose_stamped((0, 0, 0, 1)))
    rig.output_of('markers', after)
    assert set_one(rig.node, 'publish_markers', False).successful
    rig.tester.spin_for(0.5)
    assert [a[1:] for a in actions(rig)[0][2:]] == [('map', [Marker.DELETE] * 6)]
    assert [m[1:] for m in actions(rig)[1][2:]] == [('map', [Marker.DELETE])]


def test_markers_are_throttled_and_the_last_input_is_drawn(rig):  # noqa: F811
    n = 60
    start = time.monotonic()
    for k in range(n):
        angle = 0.02 * (k + 1)
        last = rig.send('pose', pose_stamped((0, 0, math.sin(angle), math.cos(angle)),
                                             (0.01 * k, 0, 0)))
    rig.output_of('markers', last)  # the last input is always drawn
    rig.output_of('screw_axis', last)
    elapsed = time.monotonic() - start
    rig.tester.spin_for(2.0 / MARKER_RATE)
    arrays = rig.received('markers')
    # At most one picture per 1/MARKER_RATE s of the node's clock, inside this window.
    assert len(arrays) <= 1 + elapsed * MARKER_RATE
    assert len(rig.received('screw_axis')) == len(arrays)
    stamps = [a.markers[0].header.stamp.sec for a in arrays]
    assert stamps == sorted(stamps) and stamps[-1] == last
    assert len(rig.received('screw')) > len(arrays)  # the other outputs are not throttled


def test_a_picture_too_large_for_float64_deletes_and_warns(make_rig):  # noqa: F811
    rig = make_rig(marker_scale=1e308)  # noqa: F811
    stamp = rig.send('pose', pose_stamped((0, 0, 0.6, 0.8), (1, 0, 0)))
    m = check_array(rig.output_of('markers', stamp), stamp, 'map')
    assert [m[i].action for i in range(6)] == [Marker.DELETE] * 6
    assert rig.output_of('screw_axis', stamp).action == Marker.DELETE
    rig.tester.spin_until(lambda: rig.node_logs(Log.WARN), what='the warning on /rosout')
    (warning,) = rig.node_logs(Log.WARN)
    assert 'no picture: the picture of this motion overflows float64' in warning.msg
    assert set_one(rig.node, 'marker_scale', 1.0).successful  # and the node keeps drawing
    stamp = rig.send('pose', pose_stamped((0, 0, 1, 0), (1, 0, 0)))
    assert all(x.action == Marker.ADD for x in rig.output_of('markers', stamp).markers)


def test_markers_qos(rig):  # noqa: F811
    (info,) = rig.tester.node.get_publishers_info_by_topic(rig.topic('markers'))
    assert info.qos_profile.reliability == ReliabilityPolicy.RELIABLE
    assert info.qos_profile.durability == DurabilityPolicy.VOLATILE
    assert info.topic_type == 'visualization_msgs/msg/MarkerArray'
