"""
rot_tools.io.cdr: the node's messages as bytes, checked against rclpy's own CDR.

Every row of rot_tools.io.interface is checked, so a new row is checked as it is added.
Outputs: our bytes are rclpy's serialisation of the message they hold, its fields (by the
row's paths) the values written. Inputs: what a row reads from rclpy's serialisation of a
message is that message's fields (by the row's paths), and bytes that are not such a
serialisation are Malformed, never misread.
"""

import math
import struct
from types import SimpleNamespace

from geometry_msgs.msg import PoseWithCovarianceStamped, QuaternionStamped, TwistStamped
from geometry_msgs.msg import Vector3Stamped
from hypothesis import example, given, settings, strategies as st
from math_helpers import HYPOTHESIS_SETTINGS
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rot_tools.io import cdr, interface
from rot_tools.io.interface import MATRIX_LAYOUT
from rot_tools.ros.messages import field_value, message_class, type_name
from rot_tools.ros.topics import INPUTS, OUTPUTS
from std_msgs.msg import Float64MultiArray, Header, MultiArrayDimension, MultiArrayLayout

FLOATS = st.floats(allow_nan=False)  # (NaN != NaN would fail the comparison, not the bytes)
SECONDS = st.integers(-2**31, 2**31 - 1)
NANOSECONDS = st.integers(0, 2**32 - 1)


def header_msg(sec, nanosec, frame_id):
    header = Header(frame_id=frame_id)
    header.stamp.sec, header.stamp.nanosec = sec, nanosec
    return header


def assert_same_message(ours, msg):
    """
    Check our bytes are rclpy's serialisation of ``msg``: same length, same message back.

    Not the same bytes: Fast CDR leaves its padding bytes unwritten (whatever was in the
    buffer), ours are zero.
    """
    theirs = serialize_message(msg)
    assert len(ours) == len(theirs)
    assert ours[:4] == theirs[:4] == cdr.ENCAPSULATION
    assert deserialize_message(ours, type(msg)) == deserialize_message(theirs, type(msg))


@settings(**HYPOTHESIS_SETTINGS)
@given(SECONDS, NANOSECONDS, st.text(max_size=40), st.lists(FLOATS, min_size=4, max_size=4))
@example(0, 0, '', [0.0, 0.0, 0.0, 1.0])
@example(1, 2, 'a' * 7, [1.0, 2.0, 3.0, 4.0])  # the header's end falls on 8: no padding
@example(1, 2, 'odom\u00e9\u4e2d\U0001f600', [1.0, -2.0, float('inf'), -0.0])
def test_stamped_outputs_are_rclpys_bytes(sec, nanosec, frame_id, values):
    header = header_msg(sec, nanosec, frame_id)
    head = cdr.header(sec, nanosec, frame_id)
    assert len(head) % 8 == 4  # the encapsulation, then a payload aligned for float64
    v = Vector3Stamped(header=header)
    v.vector.x, v.vector.y, v.vector.z = values[:3]
    assert_same_message(cdr.stamped(3)(head, values[:3]), v)
    q = QuaternionStamped(header=header)
    q.quaternion.x, q.quaternion.y, q.quaternion.z, q.quaternion.w = values
    assert_same_message(cdr.stamped(4)(head, values), q)


def test_the_screw_twist_is_angular_then_linear():
    (screw,) = [kind for kind in OUTPUTS if kind.topic == '~/screw']
    values = SimpleNamespace(twist=(0.0, 1.0, 2.0, 3.0, 4.0, 5.0))  # screw_log's (θ·l̂, θ·v)
    data = screw.encode(cdr.header(5, 6, 'map'), screw.row.value(values))
    msg = deserialize_message(data, TwistStamped)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id) == (
        5, 6, 'map')
    t = msg.twist
    assert (t.angular.x, t.angular.y, t.angular.z) == (0.0, 1.0, 2.0)
    assert (t.linear.x, t.linear.y, t.linear.z) == (3.0, 4.0, 5.0)


def test_the_rpy_covariance_is_the_pose_then_the_covariance():
    (kind,) = [kind for kind in OUTPUTS if kind.row.covariance]
    values = interface.PoseCovariance((1.0, 2.0, 3.0), (0.0, 0.0, 0.6, 0.8),
                                      tuple(0.5 * k for k in range(36)))
    msg = deserialize_message(kind.encode(cdr.header(5, 6, 'map'), kind.row.value(values)),
                              PoseWithCovarianceStamped)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id) == (
        5, 6, 'map')
    p, q = msg.pose.pose.position, msg.pose.pose.orientation
    assert (p.x, p.y, p.z, q.x, q.y, q.z, q.w) == (1.0, 2.0, 3.0, 0.0, 0.0, 0.6, 0.8)
    assert msg.pose.covariance.tolist() == list(values.covariance)


def test_a_frame_id_ends_at_its_first_nul_as_in_rclpy():
    msg = Vector3Stamped(header=header_msg(1, 2, 'base\0link'))
    ours = cdr.stamped(3)(cdr.header(1, 2, 'base\0link'), (0.0, 0.0, 0.0))
    assert_same_message(ours, msg)
    # The string's length (payload bytes 8-11): what a C++ subscriber's std::string holds.
    assert ours[12:16] == serialize_message(msg)[12:16] == bytes((5, 0, 0, 0))
    assert deserialize_message(ours, Vector3Stamped).header.frame_id == 'base'


@settings(**HYPOTHESIS_SETTINGS)
@given(st.lists(FLOATS, min_size=9, max_size=9))
def test_the_rotation_matrix_is_rclpys_bytes(values):
    (matrix,) = [kind for kind in OUTPUTS if kind.topic == '~/rotation_matrix']
    layout = MultiArrayLayout(dim=[MultiArrayDimension(label=label, size=size, stride=stride)
                                   for label, size, stride in MATRIX_LAYOUT])
    assert_same_message(matrix.encode(None, values),
                        Float64MultiArray(layout=layout, data=values))


@pytest.mark.parametrize('dims, offset', [
    ((('r', 2, 6), ('c', 3, 3)), 0),  # labels of every length modulo 4
    ((('ro', 1, 1),), 7),
    ((('row', 2, 4), ('cols', 2, 2)), 1),
    ((('', 3, 3),), 0),
])
def test_any_float64_multi_array_layout(dims, offset):
    count = dims[0][2]
    values = [float(i) / 3 for i in range(count)]
    layout = MultiArrayLayout(
        dim=[MultiArrayDimension(label=label, size=size, stride=stride)
             for label, size, stride in dims], data_offset=offset)
    assert_same_message(cdr.float64_multi_array(dims, offset)(None, values),
                        Float64MultiArray(layout=layout, data=values))


@pytest.mark.parametrize('kind', [kind for kind in OUTPUTS if kind.encode is not None],
                         ids=lambda kind: kind.topic)
def test_every_output_row_writes_its_fields(kind):
    head = cdr.header(3, 4, 'odom')
    values = tuple(0.5 + k for k in range(len(kind.row.fields)))
    ours = kind.encode(head, values)
    msg = deserialize_message(ours, kind.msg_type)
    assert isinstance(msg, kind.msg_type)
    assert_same_message(ours, msg)  # the message read back is written as ours
    assert [field_value(msg, path) for path in kind.row.fields] == list(values)
    if kind.row.stamped:
        assert (msg.header.stamp.sec, msg.header.frame_id) == (3, 'odom')
    else:
        assert not hasattr(msg, 'header')


# -- inputs ---------------------------------------------------------------------------------


def _message(kind, sec, nanosec, frame_id, child, values, fill):
    """Return a message of the kind's type: header, child frame, every float field filled."""
    msg = kind.msg_type()
    msg.header = header_msg(sec, nanosec, frame_id)
    for path in kind.row.strings():
        setattr(msg, path, child)
    numbers = iter(values)
    _fill(msg, lambda: next(numbers, fill))
    return msg


def _fill(msg, number):
    """Set every float64 field (and array element) of msg, depth first, from number()."""
    for name, kind in msg.get_fields_and_field_types().items():
        value = getattr(msg, name)
        if kind == 'double':
            setattr(msg, name, number())
        elif kind.startswith('double['):
            setattr(msg, name, [number() for _ in value])
        elif hasattr(value, 'get_fields_and_field_types') and name != 'header':
            _fill(value, number)


(POSE,) = [kind for kind in INPUTS if kind.topic == '~/pose']
"""~/pose's row of INPUTS."""


BY_NAME = {kind.row.name: kind for kind in INPUTS}


def test_every_row_names_a_message_type():
    for row in interface.INPUTS + interface.OUTPUTS:
        assert type_name(message_class(row.type_name)) == row.type_name


NUMBERS = st.floats(allow_nan=False) | st.sampled_from([math.inf, -math.inf, -0.0, 5e-324])


@settings(**HYPOTHESIS_SETTINGS)
@given(st.sampled_from(INPUTS), SECONDS, NANOSECONDS, st.text(max_size=20),
       st.text(max_size=20), st.lists(NUMBERS, min_size=60, max_size=60), NUMBERS)
@example(BY_NAME['pose'], 1, 2, 'a' * 4, '', [0.5] * 60, 0.25)  # the header ends on 8
@example(BY_NAME['transform'], 1, 2, 'map', 'b' * 5, [0.5] * 60, 0.25)  # child frame to 8
@example(BY_NAME['odometry'], 1, 2, 'odom\u00e9\u4e2d', 'base\U0001f600', [0.5] * 60, 0.25)
def test_each_input_reads_its_messages_fields(kind, sec, nanosec, frame_id, child, values,
                                              fill):
    msg = _message(kind, sec, nanosec, frame_id, child, values, fill)
    data = serialize_message(msg)
    header, fields = kind.read(data)
    assert (header.stamp.sec, header.stamp.nanosec, header.frame_id) == (
        sec, nanosec, deserialize_message(data, kind.msg_type).header.frame_id)
    assert list(fields) == [field_value(msg, path) for path in kind.row.floats()]


COVARIANCE_INPUTS = [kind for kind in INPUTS if kind.row.covariance]
"""The inputs that carry a covariance (~/imu, ~/pose_with_covariance, ~/odometry)."""


@settings(**HYPOTHESIS_SETTINGS)
@given(st.sampled_from(COVARIANCE_INPUTS), SECONDS, NANOSECONDS, st.text(max_size=20),
       st.text(max_size=20), st.lists(NUMBERS, min_size=60, max_size=60), NUMBERS)
@example(BY_NAME['odometry'], 1, 2, 'odom', 'base' * 3, [0.5] * 60, 0.25)
@example(BY_NAME['imu'], 1, 2, 'imu_link', '', [float(k) for k in range(60)], 0.25)
def test_each_covariance_input_reads_its_fields_then_its_covariance(
        kind, sec, nanosec, frame_id, child, values, fill):
    msg = _message(kind, sec, nanosec, frame_id, child, values, fill)
    data = serialize_message(msg)
    header, read = cdr.covariance_reader(kind.row)(data)
    assert header == kind.read(data)[0]
    path, size = kind.row.covariance
    assert list(read) == [field_value(msg, p) for p in kind.row.covariance_floats()]
    assert list(read[:len(kind.row.floats())]) == list(kind.read(data)[1])
    assert list(read[-size:]) == list(field_value(msg, path))


def test_only_the_inputs_with_a_covariance_read_one():
    assert {kind.row.name for kind in COVARIANCE_INPUTS} == {
        'imu', 'pose_with_covariance', 'odometry'}
    assert all(kind.row.covariance_floats() == () for kind in INPUTS
               if kind not in COVARIANCE_INPUTS)


def test_nan_is_read_as_nan_and_a_frame_id_ends_at_its_first_nul():
    header, fields = POSE.read(serialize_message(
        _message(POSE, 1, 2, 'map\0junk', '', [math.nan], 1.0)))
    assert header.frame_id == 'map'
    assert math.isnan(fields[0]) and fields[1:] == (1.0,) * 6


def test_big_endian_cdr_is_read():
    # PoseStamped written by hand, CDR_BE: stamp, frame_id 'odom' (5 bytes with the NUL,
    # payload 12-17), padding to 24, then position and orientation.
    values = (1.5, -2.0, 3.25, 0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5))
    data = (b'\x00\x00\x00\x00' + struct.pack('>iII', -7, 9, 5) + b'odom\0'
            + bytes(7) + struct.pack('>7d', *values))
    assert POSE.read(data) == (cdr.Header(cdr.Stamp(-7, 9), 'odom'), values)


@pytest.mark.parametrize('kind', INPUTS, ids=lambda kind: kind.topic)
def test_bytes_that_end_early_are_malformed(kind):
    data = serialize_message(_message(kind, 3, 4, 'frame', 'child', [0.5] * 60, 0.25))
    read_all = kind.read(data)
    for end in range(len(data)):
        try:
            got = kind.read(data[:end])
        except cdr.Malformed:
            continue
        assert got == read_all  # only the bytes after the fields read may be missing


@pytest.mark.parametrize('data, why', [
    (b'', 'encapsulation  is not CDR'),
    (b'\x00\x07\x00\x00' + bytes(80), 'encapsulation 00 07 00 00 is not CDR'),  # XCDR2
    (b'\x00\x01\x00\x00' + bytes(8) + struct.pack('<I', 0) + bytes(64),
     'header.frame_id of 0 bytes does not end in a NUL'),
    (b'\x00\x01\x00\x00' + bytes(8) + struct.pack('<I', 2**32 - 1) + bytes(64),
     'header.frame_id of 4294967295 bytes does not end in a NUL within the 80 bytes'),
    (b'\x00\x01\x00\x00' + bytes(8) + struct.pack('<I', 4) + b'odom' + bytes(60),
     'does not end in a NUL'),
    (b'\x00\x01\x00\x00' + bytes(8) + struct.pack('<I', 4) + b'map\0' + bytes(20),
     'the message ends early: 40 bytes'),
])
def test_malformed_bytes_are_refused_with_what_is_wrong(data, why):
    with pytest.raises(cdr.Malformed, match=why.replace('(', r'\(')):
        POSE.read(data)
