"""
The serialised bytes of rotation_node's messages: its outputs written, its inputs read.

rclpy publishes a message object by converting it field by field to C and serialising it
(~5 µs for a Vector3Stamped); a publisher also takes the serialised bytes themselves
(``Publisher.publish(bytes)``, ~1.5 µs). Every output the node publishes for each input is
a header and a few float64, so the node writes their bytes here: those
``rclpy.serialization.serialize_message`` writes for the message, but for the padding
(zero here, left unwritten there; test_cdr checks it), that is
CDR as rmw_fastrtps writes it (OMG DDS-XTypes 1.3 §7.4.3, XCDR version 1, little endian):

- a 4-byte encapsulation header ``00 01 00 00`` (CDR, little endian), then the payload;
- every primitive aligned to its size (int32/uint32: 4, float64: 8), counted from the
  payload's start, with zero padding;
- a string is a uint32 length that counts a terminating NUL, its UTF-8 bytes, the NUL;
- a sequence is a uint32 count, then its elements.

ROS-free: the encoders take a header's stamp and frame_id, plain floats and NumPy arrays.
:class:`Writer` writes messages of any shape, field by field (the node's Markers).

The other way, taking a message object costs rclpy ~18 µs (a PoseStamped: the C message
turned into six Python objects), taking its bytes (``create_subscription(..., raw=True)``)
~1 µs: :func:`stamped_reader` reads a stamped input's header and the float64 fields the
node uses with one struct.unpack_from, in either byte order (CDR_LE or CDR_BE).
:func:`input_reader` and :func:`output_writer` make them for a row of
rot_tools.io.interface (the fields read or written); :func:`covariance_reader` reads an input's
fields and its covariance array, for the inputs that carry one.
"""

from functools import lru_cache
import struct
from typing import NamedTuple

import numpy as np

ENCAPSULATION = b'\x00\x01\x00\x00'
"""CDR_LE: plain CDR, little endian, no options."""

_STAMP = struct.Struct('<iI')
_LENGTH = struct.Struct('<I')


def _string(text):
    """
    Return a CDR string, aligned to 4: its length with the NUL, its UTF-8 bytes, the NUL.

    The text ends at its first NUL, as rclpy's conversion of a str to a C string does.
    """
    raw = text.encode().partition(b'\0')[0] + b'\0'
    return _LENGTH.pack(len(raw)) + raw


def header(sec, nanosec, frame_id):
    """
    Return the encapsulation and a std_msgs/Header (stamp, frame_id), padded to 8 bytes.

    Every stamped output starts so: header fields, then float64 (aligned to 8).
    """
    return ENCAPSULATION + _STAMP.pack(sec, nanosec) + _frame_id(frame_id)


@lru_cache(maxsize=256)
def _frame_id(frame_id):
    """
    Return a header's frame_id as a CDR string, padded so that the header ends aligned to 8.

    Cached: a stream's frame_id rarely changes, and rotation_node writes it for every input.
    """
    text = _string(frame_id)
    return text + bytes(-(_STAMP.size + len(text)) % 8)


class Stamp(NamedTuple):
    """A builtin_interfaces/Time as read: seconds and nanoseconds."""

    sec: int
    nanosec: int


class Header(NamedTuple):
    """A std_msgs/Header as read (the fields rclpy's Header has)."""

    stamp: Stamp
    frame_id: str


class Malformed(ValueError):
    """Bytes that are not a CDR serialisation of the message type expected."""


_ORDERS = {b'\x00\x01': '<', b'\x00\x00': '>'}
"""Encapsulation identifier → struct byte order: CDR_LE, CDR_BE (XCDR version 1)."""


def stamped_reader(strings, count):
    """
    Return read(data) → (Header, floats) of a message that starts with a std_msgs/Header.

    After the header come ``strings`` strings, skipped (an Odometry's or a
    TransformStamped's child_frame_id), then the ``count`` float64 read (a PoseStamped's
    pose: 7; the rest of the message is not read). The frame_id ends at its first NUL, as
    rclpy's does; its bytes are decoded as UTF-8, an invalid byte replaced. Malformed for
    another encapsulation or bytes that end early.
    """
    structs = {order: (struct.Struct(order + 'iII'), struct.Struct(order + 'I'),
                       struct.Struct(f'{order}{count}d')) for order in _ORDERS.values()}

    def read(data):
        order = _ORDERS.get(data[:2])
        if order is None:
            raise Malformed(f'encapsulation {bytes(data[:4]).hex(" ")} is not CDR '
                            '(00 01 or 00 00, XCDR version 1)')
        head, length, floats = structs[order]
        try:
            sec, nanosec, size = head.unpack_from(data, 4)
            end = 12 + size  # payload offsets: stamp 0-8, frame_id's length 8, its bytes 12-
            if not size or end + 4 > len(data) or data[end + 3]:
                raise Malformed(f'header.frame_id of {size} bytes does not end in a NUL '
                                f'within the {len(data)} bytes')
            frame_id = data[16:end + 3].partition(b'\0')[0].decode('utf-8', 'replace')
            for _ in range(strings):
                end += -end % 4
                end += 4 + length.unpack_from(data, 4 + end)[0]
            return Header(Stamp(sec, nanosec), frame_id), floats.unpack_from(
                data, 4 + end + (-end % 8))
        except struct.error:
            raise Malformed(f'the message ends early: {len(data)} bytes') from None

    return read


def stamped(count):
    """
    Return encode(head, values) of a header (from :func:`header`) and ``count`` float64.

    E.g. Vector3Stamped (3), QuaternionStamped (x, y, z, w: 4), TwistStamped (6).
    """
    pack = struct.Struct(f'<{count}d').pack
    return lambda head, values: head + pack(*values)


def float64_multi_array(dims, data_offset=0):
    """
    Return encode(head, values) of a std_msgs/Float64MultiArray with a constant layout.

    ``dims``: (label, size, stride) of each MultiArrayDimension; the number of values is
    the first dimension's stride. The type has no header: ``head`` is not used.
    """
    w = Writer()
    w.uint32(len(dims))
    for label, size, stride in dims:
        w.string(label)
        w.uint32(size, stride)
    count = dims[0][2]
    w.uint32(data_offset, count)
    w.put(8, b'')  # the values' alignment
    prefix = w.data()
    pack = struct.Struct(f'<{count}d').pack
    return lambda head, values: prefix + pack(*values)


def input_reader(row):
    """
    Return read(data) → (Header, values) of an input row (rot_tools.io.interface.Input).

    Its string fields skipped, its float64 fields read (:func:`stamped_reader`).
    """
    return stamped_reader(len(row.strings()), len(row.floats()))


def covariance_reader(row):
    """
    Return read(data) → (Header, values) of an input row that carries a covariance.

    The values are those of the row's covariance_floats(): its fields, then the whole
    covariance array (rot_tools.io.interface.Input.covariance_floats).
    """
    return stamped_reader(len(row.strings()), len(row.covariance_floats()))


def output_writer(row):
    """
    Return encode(head, values) of an output row (rot_tools.io.interface.Output).

    A MultiArray of the row's layout, or a header and the row's float64 fields.
    """
    if row.layout:
        return float64_multi_array(row.layout)
    return stamped(len(row.fields))


class Writer:
    """
    A CDR payload written field by field, for messages of any shape (the node's Markers).

    Each method appends one field, aligned from the payload's start; :meth:`data` returns
    the encapsulation and the payload.
    """

    def __init__(self):
        self._parts = [ENCAPSULATION]
        self._size = 0  # payload bytes so far

    def put(self, alignment, data):
        """Append bytes already encoded, the first aligned to ``alignment``."""
        pad = -self._size % alignment
        if pad:
            self._parts.append(bytes(pad))
        self._parts.append(data)
        self._size += pad + len(data)

    def int32(self, *values):
        """Append int32 values."""
        self.put(4, struct.pack(f'<{len(values)}i', *values))

    def uint32(self, *values):
        """Append uint32 values (also a sequence's count)."""
        self.put(4, struct.pack(f'<{len(values)}I', *values))

    def float64(self, *values):
        """Append float64 values."""
        self.put(8, struct.pack(f'<{len(values)}d', *values))

    def boolean(self, value):
        """Append a bool (one byte)."""
        self.put(1, b'\x01' if value else b'\x00')

    def string(self, text):
        """Append a string: its length with the NUL, its UTF-8 bytes up to a NUL, the NUL."""
        self.put(4, _string(text))

    def header(self, header):
        """Append a std_msgs/Header (anything with stamp.sec, stamp.nanosec, frame_id)."""
        self.put(4, _STAMP.pack(header.stamp.sec, header.stamp.nanosec))
        self.string(header.frame_id)

    def points(self, points):
        """Append a sequence of geometry_msgs/Point: ``points`` (n, 3) float64."""
        points = np.ascontiguousarray(points, dtype='<f8').reshape(-1, 3)
        self.uint32(len(points))
        if len(points):
            self.put(8, points.tobytes())

    def data(self):
        """Return the message's bytes: the encapsulation, then the payload."""
        return b''.join(self._parts)

    def payload(self):
        """Return the payload's bytes (to be put into another message)."""
        return b''.join(self._parts[1:])
