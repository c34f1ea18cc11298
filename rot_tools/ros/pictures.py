"""
rotation_node's pictures of its inputs: ~/markers (MarkerArray) and ~/screw_axis (Marker).

A picture (rot_tools.io.drawing) costs several times the rest of an input's work, so it is
throttled: at most MARKER_RATE a second, the latest input wins, and the last input is
always drawn. A timer callback draws it, never an input's callback; the timer exists only
while publish_markers is true (start, stop), so that a node without pictures has no timer
for its executor to wait on.
"""

import math
import time

import numpy as np
from rclpy.clock import Clock, ClockType
from rot_tools.core.errors import RotationError
from rot_tools.io import drawing
from rot_tools.ros import messages
from std_msgs.msg import Header

MARKER_RATE = 30.0
"""Most pictures (~/markers with ~/screw_axis) a second: RViz draws 30 frames a second."""

WARM_UP_ROTATION = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
WARM_UP_TRANSLATION = np.array([0.0, 0.0, 1.0])
"""The screw motion drawn (and not published) at start-up, a quarter turn about z, 1 m up;
rotation_node decomposes it too."""


class Pictures:
    """The pictures of one node: drawn by its timer, published on its two publishers."""

    def __init__(self, node, markers_publisher, screw_axis_publisher, publish_markers):
        """
        Draw one picture, publishing nothing; start when ``publish_markers`` is true.

        The timer is made on ``node`` by start and destroyed by stop.
        """
        self._node = node
        self._markers_pub = markers_publisher
        self._marker_pub = screw_axis_publisher
        self._timer = None  # while publish_markers is true: fires when a picture is due
        self._due = None  # the arguments of the latest drawing not yet published
        self._shown = None  # the header of the picture on show (ADDs), or None
        self._sent = -math.inf  # time.monotonic() of the last one published
        self._warm_up()
        if publish_markers:
            self.start()

    def start(self):
        """publish_markers is true: make the timer that draws the pictures (stopped)."""
        steady = Clock(clock_type=ClockType.STEADY_TIME)
        self._timer = self._node.create_timer(1.0 / MARKER_RATE, self.publish, clock=steady,
                                              autostart=False)

    def offer(self, header, R, b, settings):
        """
        Have the picture of this input drawn next, as soon as MARKER_RATE allows it.

        An input that arrives while a drawing is due replaces the one waiting: the latest
        wins, and the last input is always drawn.
        """
        self._due = (header, R, b, settings)
        if not self._timer.is_canceled():
            return
        # Due a MARKER_RATE period after the last picture, or at once when that has passed.
        wait = self._sent + 1.0 / MARKER_RATE - time.monotonic()
        self._timer.timer_period_ns = round(max(wait, 0.0) * 1e9)
        self._timer.reset()

    def publish(self):
        """~/markers and ~/screw_axis of the input waiting (DELETEs for the identity)."""
        due, self._due = self._due, None
        if due is None:  # dropped: publish_markers was switched off (stop)
            return
        self._timer.cancel()
        header, R, b, settings = due
        self._sent = time.monotonic()
        try:
            picture = drawing.picture(R, b, settings.marker_scale, settings.degrees)
        except RotationError as exc:  # e.g. a huge marker_scale: the old picture goes
            self._node.get_logger().warning(f'no picture: {exc}', throttle_duration_sec=1.0)
            picture = None
        if picture is None or picture.kind == drawing.IDENTITY:
            self._delete(header)
            return
        self._shown = header
        self._markers_pub.publish(messages.picture_markers(header, picture))
        self._marker_pub.publish(messages.screw_axis_marker(
            header, picture.screw.point, picture.screw.direction, settings.marker_scale))

    def stop(self):
        """
        publish_markers was switched off: drop the picture waiting, delete the one shown.

        The DELETEs go once, in the frame of the last picture drawn; nothing is sent when
        nothing is shown (none drawn yet, or the last input was the identity). The timer is
        destroyed.
        """
        self._node.destroy_timer(self._timer)
        self._timer = None
        self._due = None
        if self._shown is not None:
            self._delete(self._shown)

    def _warm_up(self):
        """
        Draw one picture and build its messages, publishing nothing.

        The first drawing of a process pays for one-off work (NumPy's first calls): a few
        ms, paid here at start-up instead of inside the callback of the first input.
        """
        header = Header()
        picture = drawing.picture(WARM_UP_ROTATION, WARM_UP_TRANSLATION, 1.0, False)
        messages.picture_markers(header, picture)
        messages.screw_axis_marker(header, picture.screw.point, picture.screw.direction, 1.0)
        messages.delete_picture_markers(header)
        messages.delete_marker(header, messages.SCREW_AXIS_NS, 0)

    def _delete(self, header):
        """DELETE every marker of ~/markers and ~/screw_axis, in ``header``'s frame."""
        self._shown = None
        self._markers_pub.publish(messages.delete_picture_markers(header))
        self._marker_pub.publish(messages.delete_marker(header, messages.SCREW_AXIS_NS, 0))
