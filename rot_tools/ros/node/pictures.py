"""
rotation_node's pictures of its inputs: ~/markers (MarkerArray) and ~/screw_axis (Marker).

A picture (rot_tools.io.drawing) costs more than the rest of an input's work, so it is
throttled: at most MARKER_RATE a second, the latest input wins, and the last input is always
drawn, by a timer that exists only while publish_markers is true (start, stop).
"""

import math
import time

from rclpy.clock import Clock, ClockType
from rot_tools.core.errors import RotationError
from rot_tools.io import drawing
from rot_tools.ros.node import messages

MARKER_RATE = 30.0
"""Most pictures (~/markers with ~/screw_axis) a second: RViz draws 30 frames a second."""


class Pictures:
    """The pictures of one node: drawn by its timer, published on its two publishers."""

    def __init__(self, node, markers_publisher, screw_axis_publisher, publish_markers):
        """Start when ``publish_markers`` is true (the timer is made on ``node`` by start)."""
        self._node = node
        self._markers_pub = markers_publisher
        self._marker_pub = screw_axis_publisher
        self._timer = None  # while publish_markers is true: fires when a picture is due
        self._waiting = None  # (header, R, b, settings) of the input to draw next
        self._on_show = None  # the header of the picture on show (ADDs), or None
        self._published_at = -math.inf  # time.monotonic() of the last one published
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
        self._waiting = (header, R, b, settings)
        if not self._timer.is_canceled():
            return
        # Due a MARKER_RATE period after the last picture, or at once when that has passed.
        wait = self._published_at + 1.0 / MARKER_RATE - time.monotonic()
        self._timer.timer_period_ns = round(max(wait, 0.0) * 1e9)
        self._timer.reset()

    def publish(self):
        """~/markers and ~/screw_axis of the input waiting (DELETEs for the identity)."""
        waiting, self._waiting = self._waiting, None
        if waiting is None:  # dropped: publish_markers was switched off (stop)
            return
        self._timer.cancel()
        header, R, b, settings = waiting
        self._published_at = time.monotonic()
        try:
            picture = drawing.picture(R, b, settings.marker_scale, settings.degrees)
        except RotationError as exc:  # e.g. a huge marker_scale: the old picture goes
            self._node.get_logger().warning(f'no picture: {exc}', throttle_duration_sec=1.0)
            picture = None
        if picture is None or picture.kind == drawing.IDENTITY:
            self._delete(header)
            return
        self._on_show = header
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
        self._waiting = None
        if self._on_show is not None:
            self._delete(self._on_show)

    def _delete(self, header):
        """DELETE every marker of ~/markers and ~/screw_axis, in ``header``'s frame."""
        self._on_show = None
        self._markers_pub.publish(messages.delete_picture_markers(header))
        self._marker_pub.publish(messages.delete_marker(header, messages.SCREW_AXIS_NS, 0))
