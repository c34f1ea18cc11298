"""rot_tools.cdr: the node's per-input outputs as bytes, checked against rclpy's own CDR."""

from geometry_msgs.msg import QuaternionStamped, TwistStamped, Vector3Stamped
from hypothesis import example, given, settings, strategies as st
from math_helpers import HYPOTHESIS_SETTINGS
import pytest
from rclpy.serialization import deserialize_message, serialize_message
from rot_tools import cdr
from rot_tools.messages import MATRIX_DIMS
from rot_tools.rotation_node import OUTPUTS
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
    twist = (0.0, 1.0, 2.0, 3.0, 4.0, 5.0)  # screw_log's order: (θ·l̂, θ·v)
    msg = deserialize_message(screw.encode(cdr.header(5, 6, 'map'), twist), TwistStamped)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id) == (
        5, 6, 'map')
    t = msg.twist
    assert (t.angular.x, t.angular.y, t.angular.z) == (0.0, 1.0, 2.0)
    assert (t.linear.x, t.linear.y, t.linear.z) == (3.0, 4.0, 5.0)


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
                                   for label, size, stride in MATRIX_DIMS])
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


def test_every_output_row_encodes_its_type():
    head = cdr.header(3, 4, 'odom')
    values = (0.5, -0.25, 0.125, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0)
    sizes = {Float64MultiArray: 9, QuaternionStamped: 4, Vector3Stamped: 3, TwistStamped: 6}
    for kind in OUTPUTS:
        ours = kind.encode(head, values[:sizes[kind.msg_type]])
        msg = deserialize_message(ours, kind.msg_type)
        assert isinstance(msg, kind.msg_type)
        assert_same_message(ours, msg)  # the message read back is written as ours
        if kind.msg_type is not Float64MultiArray:
            assert (msg.header.stamp.sec, msg.header.frame_id) == (3, 'odom')
