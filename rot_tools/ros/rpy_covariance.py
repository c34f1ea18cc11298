"""
rotation_node's ~/rpy_covariance: an input's covariance as that of roll, pitch and yaw.

Only the inputs that carry a covariance (rows of rot_tools.io.interface with a
``covariance``: ~/imu, ~/pose_with_covariance, ~/odometry) come here, once the input is
accepted and its other outputs are published; the others (~/pose's flood) pay nothing for it.
The covariance array is read from the same message, at the row's ``covariance`` path, and
converted by rot_tools.io.message_covariance.rpy_covariances, read as the parameter
``input_covariance`` says (``rotvec``: rotations about the parent's fixed X, Y, Z, as ROS
documents PoseWithCovariance; ``rpy``: already roll, pitch, yaw). What follows:

- converted: ~/rpy_covariance, the input's header and pose (an Imu's position 0) and the 6×6
  covariance of x, y, z, roll, pitch, yaw in rad² (an Imu's position block and cross terms 0);
- all zeros (ROS: unknown): nothing published, ~/describe says ``unknown``;
- not finite, symmetric or PSD: nothing published, a refusal counted under bad_covariance (the
  node's throttled refusals: what and by how much);
- within GIMBAL_LOCK_TOL of pitch ±90°: nothing published (the covariance of roll, pitch, yaw
  does not exist there), ~/describe says so. Not a refusal.

~/describe's ``rpy_stddev`` and ``rpy_correlation`` are those of the latest input that carried
a covariance (:meth:`RpyCovariances.describe`), with ``rpy_note`` near gimbal lock, where they
are large and mean little.
"""

from typing import Callable, NamedTuple

import numpy as np
from rot_tools.core.covariance import gimbal_lock_distance
from rot_tools.core.euler import matrix_to_euler, RPY_SEQUENCE
from rot_tools.core.transform_tree import shown
from rot_tools.io import interface
from rot_tools.io.fields import field_getter
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


class Reader(NamedTuple):
    """How one input row's covariance is read from its message."""

    covariance: Callable
    """covariance(msg) -> the covariance array (9 or 36 float64, row-major)."""
    position: slice
    """Where the position is among the row's numbers (None: an input without one, at 0)."""
    orientation: slice
    path: str
    """The covariance's field, named in a refusal."""


def covariance_reader(row):
    """Return the Reader of an input row that carries a covariance."""
    slots = row.slots()
    path, _ = row.covariance
    return Reader(field_getter(path), slots.get('position'), slots['orientation'], path)


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

    def __init__(self, publishers, outputs, refuse):
        """
        Publish with ``publishers`` {output name: publisher} the covariance rows of ``outputs``.

        ``outputs``: rot_tools.ros.topics.OUTPUTS (the rows, bound to their writers);
        ``refuse(topic, reason, text, header=...)``: the node's counted, throttled refusal.
        """
        self._outputs = tuple((publishers[kind.row.name].publish, kind.message(), kind.write)
                              for kind in outputs if kind.row.covariance)
        self._refuse = refuse
        self._latest = None

    def on_input(self, topic, reader, msg, header, R, values, settings):
        """
        Publish the covariance of one accepted input ``msg``, or say why there is none.

        ``reader``: its row's Reader; ``header``, ``R``: the input's; ``values``: the numbers
        at its row's field paths; ``settings``: the node's, as the input was converted.
        """
        cov = np.asarray(reader.covariance(msg), dtype=np.float64)
        if cov.any():  # (NaN is true: refused below)
            (C,), (status,) = rpy_covariances(R[None], cov[None], settings.input_covariance)
        else:  # all zeros, unknown: rpy_covariances' verdict, without converting anything
            C, status = np.full((3, 3), np.nan), UNKNOWN
        self._latest = Latest(topic, header, int(status), C[-3:, -3:], settings.degrees, R)
        if status == OK:
            self._publish(header, reader, values, C)
        elif status == BAD:
            text = fault(cov)
            if text.startswith('covariance'):  # (' is not …' or ': its …')
                text = reader.path + text[len('covariance'):]
            self._refuse(topic, BAD_COVARIANCE, text, header=header)

    def _publish(self, header, reader, values, C):
        """Publish the pose of the input (its ``values``) with C, 3×3 (an Imu's) or 6×6."""
        if C.shape[-1] == 3:
            C6 = np.zeros((6, 6))
            C6[3:, 3:] = C
            C = C6
        position = values[reader.position] if reader.position is not None else (0.0,) * 3
        pose = interface.PoseCovariance(position, values[reader.orientation],
                                        tuple(C.ravel().tolist()))
        numbers = [*pose.position, *pose.orientation, *pose.covariance]
        for publish, msg, write in self._outputs:
            msg.header = header
            write(msg, numbers)
            publish(msg)

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
