"""
rotation_node's /diagnostics: an IMU's conventions over the last 10 s, and its inputs.

Once a second the node publishes a ``diagnostic_msgs/DiagnosticArray`` on ``/diagnostics`` (the
convention rqt_robot_monitor and diagnostic_aggregator read): ``<node name>: imu conventions``
(imu_status) and ``<node name>: inputs`` (rates and refusals of each input).
"""

from collections import deque
import math
import time

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.qos import QoSProfile
from rot_tools.core.errors import RotationError
from rot_tools.core.imu import check_imu, faults, ImuChecks

TOPIC = '/diagnostics'
PERIOD = 1.0
"""Seconds between two DiagnosticArrays."""
WINDOW = 10.0
"""Seconds of input the checks and the rates are computed over."""
STALE_BELOW = 5.0
"""Seconds of IMU input in the window below which the conventions are STALE."""
CAPACITY = 10_000
"""IMU samples kept at most: WINDOW seconds at 1 kHz."""
CHECKED = 2_000
"""IMU samples checked at most (every k-th of the window beyond): 10 s at 200 Hz, every
other sample of a 400 Hz IMU. The checks' cost grows faster than their samples."""

CHECKS = ImuChecks._fields


def _number(x):
    """Write a number as ``:.4g`` text, a list or matrix of them in brackets, a bool as a word."""
    if isinstance(x, (list, tuple, np.ndarray)):
        return '[' + ', '.join(_number(v) for v in x) + ']'
    if isinstance(x, (bool, np.bool_)):
        return 'true' if x else 'false'
    if isinstance(x, str):
        return f"'{x}'"
    if isinstance(x, (int, np.integer)):
        return str(int(x))
    return f'{float(x):.4g}'


def check_value(check):
    """
    ``<status> <name>=<value> ...``: one check's KeyValue value.

    Its numbers, flags and words (a quaternion's reading); None and the mounting's warning (a
    sentence, in the check's message's place) left out.
    """
    numbers = [f'{name}={_number(value)}' for name, value in zip(check._fields[2:], check[2:])
               if value is not None and name != 'warning']
    return ' '.join([check.status, *numbers])


class ImuWindow:
    """The ~/imu samples of the last WINDOW seconds, as received: a bounded ring."""

    def __init__(self, capacity=CAPACITY):
        self._samples = deque(maxlen=capacity)
        self.frame = ''
        self.skipped = 0
        """Messages left out since the start: angular velocity or acceleration not finite."""

    def add(self, msg, now):
        """Keep one Imu message received at ``now`` (time.monotonic())."""
        w, a, q = msg.angular_velocity, msg.linear_acceleration, msg.orientation
        numbers = (w.x, w.y, w.z, a.x, a.y, a.z)
        if not all(map(math.isfinite, numbers)):
            self.skipped += 1
            return
        stamp = msg.header.stamp
        oriented = msg.orientation_covariance[0] != -1.0  # ROS: -1, no orientation
        self._samples.append((now, stamp.sec + 1e-9 * stamp.nanosec,
                              *((q.x, q.y, q.z, q.w) if oriented else (0.0,) * 4), *numbers))
        self.frame = msg.header.frame_id

    def recent(self, now):
        """Return the samples received in the last WINDOW seconds, an (n, 12) array."""
        while self._samples and self._samples[0][0] < now - WINDOW:
            self._samples.popleft()
        return np.array(self._samples, dtype=np.float64).reshape(-1, 12)


def steady(whole, halves):
    """
    Return the check of a whole window where its halves bear it out, else unknown.

    whole: one check of check_imu over the window; halves: the same check over its first and
    second halves. A half that says otherwise (ok against a fault, fault against ok, another
    axis map or reading of the quaternion) makes the check unknown: the window does not fix
    it. A half that cannot tell (unknown) leaves the whole window's verdict.
    """
    if whole.status == 'unknown':
        return whole
    told = [half for half in halves if half.status != 'unknown']
    same = all(half.status == whole.status and all(
        getattr(half, name) == getattr(whole, name) for name in ('matrix', 'reading')
        if name in whole._fields) for half in told)
    if same:
        return whole
    said = '; '.join(f'{which} half {half.status}: {half.message.rstrip(".")}'
                     for which, half in zip(('first', 'second'), halves))
    return type(whole)(**{**dict.fromkeys(whole._fields), 'status': 'unknown', 'message': (
        f'{whole.status} over the window, but not over both its halves ({said}).'),
        **({'warning': ''} if 'warning' in whole._fields else {})})


def steady_checks(stamps, quaternions, angular_velocity, linear_acceleration):
    """Return the ImuChecks of a window whose halves bear each check out (steady)."""
    whole = check_imu(stamps, quaternions, angular_velocity, linear_acceleration)
    middle = len(stamps) // 2
    halves = []
    for part in (slice(None, middle), slice(middle, None)):
        try:
            halves.append(check_imu(stamps[part], None if quaternions is None else
                                    quaternions[part], angular_velocity[part],
                                    linear_acceleration[part]))
        except RotationError:  # too few samples in a half: it cannot tell
            return ImuChecks(*(steady(check, ()) for check in whole))
    return ImuChecks(*(steady(check, [half[k] for half in halves])
                       for k, check in enumerate(whole)))


def imu_status(name, window, now):
    """
    Return the DiagnosticStatus ``<name>: imu conventions`` of ``window`` at ``now``.

    steady_checks over the ~/imu messages received in the last WINDOW seconds (at most
    CHECKED of them, every k-th of a faster stream). ``hardware_id`` is the IMU's frame;
    the level is OK (no fault), WARN (a fault: the message names the checks; or the checks
    cannot run on these samples, and the message says why) or STALE (under STALE_BELOW
    seconds of input in the window); one KeyValue per check, its name and ``<status>
    <numbers>`` (``ok scale=0.9987``; radians, rad/s, seconds). An Imu without orientation
    has its orientation checks unknown.
    """
    status = DiagnosticStatus(name=f'{name}: imu conventions', hardware_id=window.frame)
    samples = window.recent(now)
    seconds = float(samples[-1, 0] - samples[0, 0]) if len(samples) else 0.0
    values = dict.fromkeys(CHECKS, 'unknown')
    if seconds < STALE_BELOW:
        status.level = DiagnosticStatus.STALE
        status.message = (f'{seconds:.1f} s of ~/imu in the last {WINDOW:g} s ({len(samples)} '
                          f'messages): the checks need {STALE_BELOW:g} s')
    else:
        step = -(-len(samples) // CHECKED)  # every k-th: at most CHECKED samples
        x = samples[::step]
        q = x[:, 2:6] if x[:, 2:6].any(axis=1).all() else None  # (any without: none)
        of = f'{seconds:.1f} s, {len(x)} messages' + (
            f' (every {step})' if step > 1 else '') + (
            f', {window.skipped} left out since the start' if window.skipped else '')
        try:
            checks = steady_checks(x[:, 1], q, x[:, 6:9], x[:, 9:12])
        except RotationError as exc:
            status.level = DiagnosticStatus.WARN
            status.message = f'the checks cannot run on the last {of}: {exc}'
        else:
            values = {key: check_value(check) for key, check in zip(CHECKS, checks)}
            at_fault = faults(checks)
            if at_fault:
                status.level = DiagnosticStatus.WARN
                status.message = (f'{", ".join(at_fault)} at fault ({of}): ' + ' '.join(
                    getattr(checks, key).message for key in at_fault))
            else:
                status.level = DiagnosticStatus.OK
                status.message = f'no fault ({of})'
    status.values = [KeyValue(key=key, value=value) for key, value in values.items()]
    return status


class Diagnostics:
    """The /diagnostics of one node: its timer, the IMU's window, the inputs' counts."""

    def __init__(self, node):
        """Publish on ``node``'s /diagnostics once a PERIOD (a steady-clock timer)."""
        self._node = node
        self._name = node.get_name()
        self.tf = None
        """The node's rot_tools.ros.tf_input.TfFollower: its /tf messages are counted while
        it follows frames."""
        self.imu = ImuWindow()
        self._received = {}  # topic: messages received since the start
        self._refused = {}  # topic: {reason: refusals since the start}
        self._history = deque()  # (time.monotonic(), received copy, refused totals copy)
        self._publisher = node.create_publisher(DiagnosticArray, TOPIC, QoSProfile(depth=10))
        self._timer = node.create_timer(PERIOD, self.publish,
                                        clock=Clock(clock_type=ClockType.STEADY_TIME))

    def counted(self, topic, callback, imu=False):
        """
        Return ``callback`` counting the messages of input ``topic`` (``imu``: and keeping them).

        The IMU's are kept as received, before the node converts (or refuses) them.
        """
        received = self._received
        received[topic] = 0
        if not imu:
            def counting(msg):
                received[topic] += 1
                callback(msg)
            return counting
        window = self.imu

        def keeping(msg):
            received[topic] += 1
            window.add(msg, time.monotonic())
            callback(msg)
        return keeping

    def refused(self, topic, reason):
        """Count a refusal of the node (its _refuse) under its topic."""
        reasons = self._refused.setdefault(topic, {})
        reasons[reason] = reasons.get(reason, 0) + 1

    def statuses(self, now=None):
        """Return [the imu conventions' status, the inputs' status] at ``now`` (monotonic)."""
        now = time.monotonic() if now is None else now
        return [imu_status(self._name, self.imu, now), self._inputs_status(now)]

    def publish(self):
        """Publish the DiagnosticArray of now (the timer's callback)."""
        array = DiagnosticArray(status=self.statuses())
        array.header.stamp = self._node.get_clock().now().to_msg()
        self._publisher.publish(array)

    def _inputs_status(self, now):
        received = dict(self._received)
        if self.tf is not None and self.tf.following:
            received[self.tf.topic] = self.tf.messages
        refused = {topic: sum(reasons.values()) for topic, reasons in self._refused.items()}
        history = self._history
        history.append((now, received, refused))
        while len(history) > 1 and history[1][0] <= now - WINDOW:
            history.popleft()
        then, received_then, refused_then = history[0]
        span = now - then
        recent = sum(n - refused_then.get(topic, 0) for topic, n in refused.items())
        status = DiagnosticStatus(
            name=f'{self._name}: inputs', hardware_id=self._node.get_fully_qualified_name(),
            level=DiagnosticStatus.WARN if recent else DiagnosticStatus.OK,
            message=(f'{recent} input(s) refused in the last {span:.0f} s' if recent
                     else f'no input refused in the last {span:.0f} s'))
        for topic in [*received, *(t for t in self._refused if t not in received)]:
            parts = []
            if topic in received:
                count = received[topic] - received_then.get(topic, received[topic])
                parts.append(f'{count / span if span > 0 else 0.0:.3g} msg/s')
            reasons = self._refused.get(topic, {})
            parts.append(f'{sum(reasons.values())} refused' + (
                ' (' + ', '.join(f'{r} {n}' for r, n in reasons.items()) + ')'
                if reasons else ''))
            status.values.append(KeyValue(key=topic, value=', '.join(parts)))
        return status
