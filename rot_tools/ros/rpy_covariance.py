"""
rotation_node's ~/rpy_covariance: an input's covariance as that of roll, pitch and yaw.

Only the inputs that carry a covariance (rows of rot_tools.io.interface with a
``covariance``: ~/imu, ~/pose_with_covariance, ~/odometry) come here, once the input is
accepted and its other outputs are published; the others (~/pose's flood) pay nothing for it.
The covariance array is read from the same bytes (rot_tools.io.cdr.covariance_reader) and
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
a covariance (:meth:`RpyCovariances.describe`).
"""

from typing import NamedTuple

import numpy as np
from rot_tools.io import cdr, interface
from rot_tools.io.message_covariance import BAD, LOCK, OK, UNKNOWN
from rot_tools.io.message_covariance import fault, READINGS, rpy_covariances, stddev_correlation

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
    return f'input_covariance {value!r} is not ' + ' or '.join(map(repr, READINGS))


class Reader(NamedTuple):
    """How one input row's covariance is read from its bytes."""

    read: object
    """read(data) -> (header, the row's covariance_floats())."""
    position: slice
    """Where the position is among the floats (None: an input without one, position 0)."""
    orientation: slice
    covariance: slice
    path: str
    """The covariance's field, named in a refusal."""


def covariance_reader(row):
    """Return the Reader of an input row that carries a covariance."""
    at, slots = 0, {}
    for role in row.fields:
        names = interface.MEMBERS[role]
        if names is not None:
            slots[role] = slice(at, at + len(names))
            at += len(names)
    path, size = row.covariance
    count = len(row.covariance_floats())
    return Reader(cdr.covariance_reader(row), slots.get('position'), slots['orientation'],
                  slice(count - size, count), path)


class Latest(NamedTuple):
    """The latest input that carried a covariance, for ~/describe."""

    topic: str
    header: object
    status: int
    C: np.ndarray
    """The 3×3 covariance of roll, pitch, yaw (rad²); NaN unless status is OK."""
    degrees: bool


class RpyCovariances:
    """~/rpy_covariance of the inputs that carry a covariance, and its part of ~/describe."""

    def __init__(self, publishers, outputs, refuse):
        """
        Publish with ``publishers`` {output name: publisher} the covariance rows of ``outputs``.

        ``outputs``: rot_tools.ros.topics.OUTPUTS (the rows, bound to their writers);
        ``refuse(topic, reason, text, header=...)``: the node's counted, throttled refusal.
        """
        self._outputs = tuple((publishers[kind.row.name].publish, kind.encode, kind.row.value)
                              for kind in outputs if kind.row.covariance)
        self._refuse = refuse
        self._latest = None

    def on_input(self, take, topic, reader, data):
        """
        Serve one message of a covariance input: ``take(data)`` (the node's), then its covariance.

        ``take`` returns (header, R, settings) of an accepted input, None for a refused one.
        """
        accepted = take(data)
        if accepted is None:
            return
        header, R, settings = accepted
        _, floats = reader.read(data)
        cov = floats[reader.covariance]
        if any(cov):  # (NaN is true: refused below)
            (C,), (status,) = rpy_covariances(R[None], np.array(cov)[None],
                                              settings.input_covariance)
        else:  # all zeros, unknown: rpy_covariances' verdict, without its ~0.2 ms
            C, status = np.full((3, 3), np.nan), UNKNOWN
        self._latest = Latest(topic, header, int(status), C[-3:, -3:], settings.degrees)
        if status == OK:
            self._publish(header, reader, floats, C)
        elif status == BAD:
            text = fault(np.array(cov))
            if text.startswith('covariance '):
                text = reader.path + text[len('covariance'):]
            self._refuse(topic, BAD_COVARIANCE, text, header=header)

    def _publish(self, header, reader, floats, C):
        """Publish the pose of the input (its floats) with C, 3×3 (an Imu's) or 6×6."""
        if C.shape[-1] == 3:
            C6 = np.zeros((6, 6))
            C6[3:, 3:] = C
            C = C6
        position = floats[reader.position] if reader.position is not None else (0.0,) * 3
        values = interface.PoseCovariance(position, floats[reader.orientation],
                                          tuple(C.ravel().tolist()))
        stamp = header.stamp
        head = cdr.header(stamp.sec, stamp.nanosec, header.frame_id)
        for publish, encode, value_of in self._outputs:
            publish(encode(head, value_of(values)))

    def describe(self):
        """
        Return ~/describe's part: {} before any input with a covariance, else its data.

        ``rpy_covariance_of`` (the input's topic and stamp), ``rpy_stddev`` {roll, pitch, yaw,
        unit} in that input's angle_unit and ``rpy_correlation`` (3 rows); when nothing was
        published, both say why (NOT_PUBLISHED).
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
        if latest.degrees:
            s = np.degrees(s)
        data['rpy_stddev'] = {**dict(zip(NAMES, s.tolist())),
                              'unit': 'deg' if latest.degrees else 'rad'}
        data['rpy_correlation'] = rho.tolist()
        return data
