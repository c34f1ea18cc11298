"""~/screw_path against a hostile caller: failures counted, replies bounded in bytes."""

import math

from nav_msgs.srv import GetPlan
import pytest
from rcl_interfaces.msg import Log
from rclpy.serialization import serialize_message
from rot_tools.ros.node import rotation_node
from rot_tools.ros.node.screw_path import MAX_PATH_STEPS, MAX_REPLY_BYTES, reply_bytes
from test_node import pose_stamped


def request(start, goal, tolerance=0.0):
    return GetPlan.Request(start=start, goal=goal, tolerance=float(tolerance))


class Service:
    """A RotationNode under test and the tester that calls it and reads its /rosout."""

    def __init__(self, tester, node):
        self.tester = tester
        self.node = node
        self.name = f'{node.get_fully_qualified_name()}/screw_path'
        tester.add_node(node)
        tester.subscribe_rosout()

    def call(self, start, goal, tolerance=0.0):
        """Return the path of a request, waiting up to 30 s an attempt."""
        return self.tester.call(GetPlan, self.name, request(start, goal, tolerance),
                                timeout=30.0, attempts=3).plan

    def errors(self, count):
        """Wait until the node has logged ``count`` errors on /rosout; return their texts."""
        logger = self.node.get_logger().name

        def errors():
            return [log.msg for log in self.tester.logs
                    if log.name == logger and log.level == Log.ERROR]
        self.tester.spin_until(lambda: len(errors()) >= count,
                               what=f'{count} error(s) of the node on /rosout')
        return errors()


@pytest.fixture
def service(ros_context, tester, namespace):
    node = rotation_node.RotationNode(context=ros_context, namespace=namespace)
    yield Service(tester, node)
    tester.remove_node(node)
    node.destroy_node()


def refused(node):
    return {k: v for k, v in node.refused_counts().items() if v}


# Every failure is a counted refusal with its reason


@pytest.mark.parametrize('tolerance', [0.0, 0.5])
def test_huge_positions_are_a_counted_refusal(service, tolerance):
    """±1e308: b1 − b0 overflows float64, no screw between them: a counted refusal."""
    start = pose_stamped(p=(-1e308, 0, 0))
    start.header.stamp.sec, start.header.stamp.nanosec = 42, 7
    goal = pose_stamped(p=(1e308, 0, 0))
    assert service.call(start, goal, tolerance).poses == []
    (error,) = service.errors(1)
    assert error.endswith('(not_decomposable): start and goal are too far apart: '
                          'goal.position − start.position overflows float64 '
                          '(beyond ±1.8e308)'), error
    assert refused(service.node) == {'total': 1, 'not_decomposable': 1}
    # ~/describe's data names the request (service, start's stamp) and says why.
    assert service.node.last_refusals() == {'not_decomposable': {
        'source': service.name, 'stamp': {'sec': 42, 'nanosec': 7},
        'message': error.partition('(not_decomposable): ')[2]}}
    # The node keeps serving.
    path = service.call(pose_stamped(), pose_stamped(p=(1, 0, 0)), 0.5)
    assert [p.pose.position.x for p in path.poses] == [0.0, 0.5, 1.0]


# A reply is bounded in bytes


def test_reply_size_estimate_bounds_the_serialised_reply():
    """The estimate is never below what rclpy serialises, and at most 12 B a pose above."""
    for frame in ('', 'm', 'map', 'é' * 5, '😀' * 3, 'x' * 1000):
        for n in (2, 3, 21, 200):
            start, goal = pose_stamped(frame=frame), pose_stamped(p=(1, 0, 0), frame=frame)
            response = GetPlan.Response()
            response.plan.header = start.header
            response.plan.poses = [start] + [pose_stamped(frame=frame)] * (n - 2) + [goal]
            size = len(serialize_message(response))
            estimate = reply_bytes(frame, n)
            assert size <= estimate <= size + 12 * n + 60, (frame, n, size, estimate)


def test_reply_bytes_bound_the_default_path(service):
    """The longest frame_id that fits is served in MAX_REPLY_BYTES; one byte more is refused."""
    longest = MAX_REPLY_BYTES // 22 - reply_bytes('', 21) // 22
    while reply_bytes('x' * (longest + 1), 21) <= MAX_REPLY_BYTES:
        longest += 1
    while reply_bytes('x' * longest, 21) > MAX_REPLY_BYTES:
        longest -= 1
    for length, fits in ((longest, True), (longest + 1, False)):
        frame = 'x' * length
        start, goal = pose_stamped(frame=frame), pose_stamped((0, 0, 1, 0), (1, 2, 3), frame)
        response = service.node._on_screw_path(request(start, goal), GetPlan.Response())
        if fits:
            assert len(response.plan.poses) == 21
            assert len(serialize_message(response)) <= MAX_REPLY_BYTES
        else:
            assert response.plan.poses == []
    assert refused(service.node) == {'total': 1, 'path_too_long': 1}


def test_long_frame_id_times_many_poses_is_refused(service):
    """Check that a 2 kB frame_id × 10,001 poses (10,000 steps over 1 m) is 20.8 MB."""
    frame = 'f' * 2000
    tolerance = 1.0 / (MAX_PATH_STEPS - 0.5)
    start, goal = pose_stamped(frame=frame), pose_stamped(p=(1, 0, 0), frame=frame)
    assert service.call(start, goal, tolerance).poses == []
    (error,) = service.errors(1)
    assert error.endswith(f'(path_too_long): a reply of {MAX_PATH_STEPS + 1} poses with a '
                          'frame_id of 2000 bytes would take 20.8 MB, more than 16 MB'), error
    assert refused(service.node) == {'total': 1, 'path_too_long': 1}
    # The same path in a short frame_id is served: it is the bytes that were refused.
    short = service.call(pose_stamped(), pose_stamped(p=(1, 0, 0)), tolerance)
    assert len(short.poses) == MAX_PATH_STEPS + 1


# Error logs throttled per reason


def test_errors_are_throttled_per_reason(service, monkeypatch):
    """Refusals for different reasons each log; the same reason again at once does not."""
    monkeypatch.setattr(rotation_node, 'REFUSAL_WARNING_PERIOD', 1e9)
    zero = pose_stamped((0, 0, 0, 0))
    cases = [  # (start, goal, tolerance): reason
        ((pose_stamped(frame='map'), pose_stamped(frame='odom'), 0.0), 'frame_mismatch'),
        ((zero, pose_stamped(), 0.0), 'zero_quaternion'),
        ((zero, pose_stamped(), 0.0), 'zero_quaternion'),
        ((pose_stamped(), pose_stamped(), math.nan), 'bad_tolerance'),
        ((pose_stamped(), pose_stamped(p=(1, 0, 0)), 1e-9), 'path_too_long'),
    ]
    for args, _ in cases:
        assert service.call(*args).poses == []
    errors = service.errors(4)
    # The node's /rosout is one reliable, ordered stream: the last error has come, so have
    # all before it.
    assert [e[e.index('(') + 1:e.index(')')] for e in errors] == [
        'frame_mismatch', 'zero_quaternion', 'bad_tolerance', 'path_too_long']
    assert refused(service.node) == {'total': 5, 'frame_mismatch': 1, 'zero_quaternion': 2,
                                     'bad_tolerance': 1, 'path_too_long': 1}
