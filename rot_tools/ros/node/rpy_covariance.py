"""
rotation_node's ~/rpy_covariance: an input's covariance as that of roll, pitch and yaw.

For the inputs that carry a covariance (~/imu, ~/pose_with_covariance, ~/odometry), once the
input is accepted and its other outputs are published: the covariance read as the parameter
``input_covariance`` says (rot_tools.io.message_covariance). Converted: published with the
input's header and pose; all zeros (ROS: unknown), or near gimbal lock: nothing published and
~/describe says so; not finite, symmetric or PSD: a refusal counted as bad_covariance.
"""

from typing import NamedTuple

from geometry_msgs.msg import PoseWithCovarianceStamped
import numpy as np
from rot_tools.core.covariance import gimbal_lock_distance
from rot_tools.core.euler import matrix_to_euler, RPY_SEQUENCE
from rot_tools.core.transform_tree import shown
from rot_tools.io.message_covariance import BAD, LOCK, OK, UNKNOWN
from rot_tools.io.message_covariance import fault, near_lock_note, READINGS, rpy_covariances
from rot_tools.io.message_covariance import stddev_correlation

BAD_COVARIANCE = 'bad_covariance'
REFUSAL_REASONS = (BAD_COVARIANCE,)
"""The reason an input's covariance is refused for (the input itself is served)."""

NOT_PUBLISHED = {UNKNOWN: 'unknown', LOCK: 'none at gimbal lock (pitch ±90°)',
                 BAD: f'refused ({BAD_COVARIANCE})'}
"""What ~/describe says, as rpy_stddev and rpy_correlation, when nothing was published."""

NAMES = ('roll', 'pitch', 'yaw')


def check_reading(value):
    """Return why ``value`` is not an input_covariance, or ''."""
    if value in READINGS:
        return ''
    return f'input_covariance {shown(value)} is not ' + ' or '.join(map(repr, READINGS))


class Latest(NamedTuple):
    """The latest input that carried a covariance, for ~/describe."""

    topic: str
    header: object
    status: int
    C: np.ndarray
    """The 3×3 covariance of roll, pitch, yaw (rad²); NaN unless status is OK."""
    degrees: bool
    R: np.ndarray
    """The input's rotation (for the distance to gimbal lock)."""


class RpyCovariances:
    """~/rpy_covariance of the inputs that carry a covariance, and its part of ~/describe."""

    def __init__(self, publisher, refuse):
        """
        Publish ~/rpy_covariance with ``publisher``.

        ``refuse(topic, reason, text, header=...)``: the node's counted, throttled refusal.
        """
        self._publisher = publisher
        self._refuse = refuse
        self._latest = None

    def on_input(self, topic, header, R, position, orientation, covariance, path, settings):
        """
        Publish the covariance of one accepted input, or say why there is none.

        ``header``, ``R``, ``position``, ``orientation``: the input's; ``covariance``: its
        array (9 or 36 numbers, row-major), at field ``path`` (named in a refusal);
        ``settings``: the node's, as the input was converted.
        """
        cov = np.asarray(covariance, dtype=np.float64)
        if cov.any():  # (NaN is true: refused below)
            (C,), (status,) = rpy_covariances(R[None], cov[None], settings.input_covariance)
        else:  # all zeros, unknown: rpy_covariances' verdict, without converting anything
            C, status = np.full((3, 3), np.nan), UNKNOWN
        self._latest = Latest(topic, header, int(status), C[-3:, -3:], settings.degrees, R)
        if status == OK:
            self._publish(header, position, orientation, C)
        elif status == BAD:
            text = fault(cov)
            if text.startswith('covariance'):  # (' is not …' or ': its …')
                text = path + text[len('covariance'):]
            self._refuse(topic, BAD_COVARIANCE, text, header=header)

    def _publish(self, header, position, orientation, C):
        """Publish the pose with C, 3×3 (an Imu's, the rotation block of a 6×6) or 6×6."""
        if C.shape[-1] == 3:
            C6 = np.zeros((6, 6))
            C6[3:, 3:] = C
            C = C6
        msg = PoseWithCovarianceStamped(header=header)
        p, q = msg.pose.pose.position, msg.pose.pose.orientation
        p.x, p.y, p.z = position
        q.x, q.y, q.z, q.w = orientation
        msg.pose.covariance = C.ravel().tolist()
        self._publisher.publish(msg)

    def describe(self):
        """
        Return ~/describe's part: {} before any input with a covariance, else its data.

        ``rpy_covariance_of`` (the input's topic and stamp), ``rpy_stddev`` {roll, pitch, yaw,
        unit} in that input's angle_unit and ``rpy_correlation`` (3 rows); when nothing was
        published, both say why (NOT_PUBLISHED). Near gimbal lock (within NEAR_LOCK_SIGMAS
        standard deviations of pitch), ``rpy_note`` says so
        (rot_tools.io.message_covariance.near_lock_note).
        """
        latest = self._latest
        if latest is None:
            return {}
        stamp = latest.header.stamp
        data = {'rpy_covariance_of': {'source': latest.topic,
                                      'stamp': {'sec': stamp.sec, 'nanosec': stamp.nanosec}}}
        if latest.status != OK:
            data['rpy_stddev'] = data['rpy_correlation'] = NOT_PUBLISHED[latest.status]
            return data
        s, rho = stddev_correlation(latest.C)
        s_rad = s
        if latest.degrees:
            s = np.degrees(s)
        data['rpy_stddev'] = {**dict(zip(NAMES, s.tolist())),
                              'unit': 'deg' if latest.degrees else 'rad'}
        data['rpy_correlation'] = rho.tolist()
        angles = matrix_to_euler(latest.R, RPY_SEQUENCE, check=False).angles
        note = near_lock_note(float(gimbal_lock_distance(angles)), float(s_rad[1]))
        if note:
            data['rpy_note'] = note
        return data
