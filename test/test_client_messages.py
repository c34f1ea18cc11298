"""rotation_client's messages without DDS: the input each verb fills, field by field."""

from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, PoseWithCovarianceStamped, QuaternionStamped
from geometry_msgs.msg import TwistStamped, Vector3Stamped
import numpy as np
import pytest
from rot_tools.io import interface
from rot_tools.ros.client import arguments, message_data, session
from rot_tools.ros.message_types import message_class, type_name
from scipy.spatial.transform import Rotation
from std_msgs.msg import Float64MultiArray, Header
from visualization_msgs.msg import Marker, MarkerArray

PARAMETERS = {'euler_sequence': 'ZYX', 'angle_unit': 'rad', 'publish_markers': True}
"""The node's parameters as the client reads them (the defaults)."""


# The input each verb fills


def xyz(v):
    return [v.x, v.y, v.z]


def xyzw(q):
    return [q.x, q.y, q.z, q.w]


FILLED = {
    'pose': lambda msg: xyz(msg.pose.position) + xyzw(msg.pose.orientation),
    'euler': lambda msg: xyz(msg.vector),
    'transform': lambda msg: xyz(msg.transform.translation) + xyzw(msg.transform.rotation),
    'pose_with_covariance': lambda msg: (xyz(msg.pose.pose.position)
                                         + xyzw(msg.pose.pose.orientation)),
    'odometry': lambda msg: xyz(msg.pose.pose.position) + xyzw(msg.pose.pose.orientation),
    'imu': lambda msg: xyzw(msg.orientation),
    'orientation': lambda msg: xyzw(msg.quaternion),
}
"""Each input's message fields that must hold the numbers typed, in the order typed."""

WITH_CHILD_FRAME = ('transform', 'odometry')
"""The inputs whose message has a child_frame_id: the body, --child-frame."""

COVARIANCE = {
    'imu': lambda msg: list(msg.orientation_covariance),
    'pose_with_covariance': lambda msg: list(msg.pose.covariance),
    'odometry': lambda msg: list(msg.pose.covariance),
}
"""Each input's message field that must hold --cov."""

ROTATION_BLOCK = (21, 22, 23, 27, 28, 29, 33, 34, 35)
"""Where the rotation's 3×3 goes in a pose's 6×6 covariance (x, y, z, roll, pitch, yaw),
row-major."""


def sent(name, count, *options):
    """Return (message, what was sent, numbers typed) of ``name`` with ``count`` numbers."""
    typed = [k + 0.25 for k in range(count)]
    sequence = ['ZYX'] if name == 'euler' else []
    args = arguments.parse_args([name, *sequence, *map(str, typed), *options])
    assert args.row is interface.input_named(name)
    msg, data = message_data.input_message(args, PARAMETERS)
    assert type(msg) is message_class(args.row.type_name)
    return msg, data, typed


def test_every_node_input_is_a_client_verb():
    assert set(arguments.INPUTS) == {row.name for row in interface.INPUTS}
    for row in interface.INPUTS:
        assert arguments.commands()[row.name].row is row


@pytest.mark.parametrize('row', interface.INPUTS, ids=lambda row: row.name)
def test_a_verb_puts_each_number_in_its_field(row):
    """The numbers typed, as many as the fields, each in its field in the order typed."""
    filled = FILLED[row.name]
    count = len(filled(message_class(row.type_name)()))
    msg, _, typed = sent(row.name, count)
    assert filled(msg) == typed


@pytest.mark.parametrize('name', WITH_CHILD_FRAME)
def test_a_verb_names_the_body_in_child_frame_id(name):
    msg, data, _ = sent(name, 7, '--child-frame', 'wheel_2')
    assert msg.child_frame_id == data['child_frame_id'] == 'wheel_2'


def test_only_the_messages_with_child_frame_id_take_child_frame():
    for row in interface.INPUTS:
        has_field = hasattr(message_class(row.type_name)(), 'child_frame_id')
        assert has_field == (row.name in WITH_CHILD_FRAME), row.name


@pytest.mark.parametrize('name', COVARIANCE)
def test_cov_is_the_rotations_covariance_of_the_message(name):
    """--cov C11 … C33 is an Imu's orientation_covariance, a pose's roll-pitch-yaw block."""
    cov = [k + 1.5 for k in range(9)]
    count = len(FILLED[name](message_class(interface.input_named(name).type_name)()))
    msg, _, _ = sent(name, count, '--cov', *map(str, cov))
    if name == 'imu':
        expected = cov
    else:
        expected = [0.0] * 36
        for index, value in zip(ROTATION_BLOCK, cov):
            expected[index] = value
    assert COVARIANCE[name](msg) == expected


# The answer, by output name

ANSWER_PARAMETERS = {'euler_sequence': 'xyz', 'angle_unit': 'deg', 'publish_markers': True}
"""Parameters other than the defaults: the printed sequence and unit are the node's."""

STAMP = Time(sec=7, nanosec=8)
Q = (0.18, 0.26, 0.54, 0.78)
"""The answer's quaternion (x, y, z, w): a unit one, of distinct numbers."""
R = Rotation.from_quat(Q).as_matrix()
"""Its rotation matrix: the content of the answer's ~/rotation_matrix."""


def header(msg):
    """Stamp ``msg`` as the answer to the message sent (STAMP, frame map); return it."""
    msg.header.stamp, msg.header.frame_id = STAMP, 'map'
    return msg


def vector(x, y, z):
    msg = header(Vector3Stamped())
    msg.vector.x, msg.vector.y, msg.vector.z = x, y, z
    return msg


def answer_messages():
    """Return {output name: a message of its type}, each holding numbers of its own."""
    quaternion = header(QuaternionStamped())
    quaternion.quaternion.x, quaternion.quaternion.y = Q[:2]
    quaternion.quaternion.z, quaternion.quaternion.w = Q[2:]
    screw = header(TwistStamped())
    screw.twist.angular.x, screw.twist.angular.y, screw.twist.angular.z = 13.0, 14.0, 15.0
    screw.twist.linear.x, screw.twist.linear.y, screw.twist.linear.z = 16.0, 17.0, 18.0
    pose = header(PoseWithCovarianceStamped())
    pose.pose.pose.position.x, pose.pose.pose.position.y = 19.0, 20.0
    pose.pose.pose.position.z = 21.0
    pose.pose.pose.orientation.x, pose.pose.pose.orientation.y = 22.0, 23.0
    pose.pose.pose.orientation.z, pose.pose.pose.orientation.w = 24.0, 25.0
    pose.pose.covariance = [26.0 + k for k in range(36)]
    axis = header(Marker(id=1, action=Marker.ADD, type=Marker.ARROW))
    axis.points = [Point(x=62.0, y=63.0, z=64.0), Point(x=65.0, y=66.0, z=67.0)]
    markers = MarkerArray(markers=[
        header(Marker(id=2, action=Marker.ADD, type=Marker.LINE_STRIP)),
        header(Marker(id=3, action=Marker.DELETE))])
    return {
        'rotation_matrix': Float64MultiArray(data=R.ravel().tolist()),
        'quaternion': quaternion,
        'axis_angle': vector(1.0, 2.0, 3.0),
        'rodrigues': vector(4.0, 5.0, 6.0),
        'euler_angles': vector(7.0, 8.0, 9.0),
        'rpy': vector(10.0, 11.0, 12.0),
        'screw': screw,
        'rpy_covariance': pose,
        'screw_axis': axis,
        'markers': markers,
    }


PRINTED = {
    'rotation_matrix': R.tolist(),
    'quaternion': {'x': 0.18, 'y': 0.26, 'z': 0.54, 'w': 0.78},
    'axis_angle': [1.0, 2.0, 3.0],
    'rodrigues': {'vector': {'x': 4.0, 'y': 5.0, 'z': 6.0}},
    'euler_angles': {'sequence': 'xyz', 'unit': 'deg', 'angles': [7.0, 8.0, 9.0]},
    'rpy': {'roll': 10.0, 'pitch': 11.0, 'yaw': 12.0, 'unit': 'deg'},
    'screw': {'angular': [13.0, 14.0, 15.0], 'linear': [16.0, 17.0, 18.0]},
    'rpy_covariance': {'position': [19.0, 20.0, 21.0],
                       'orientation': {'x': 22.0, 'y': 23.0, 'z': 24.0, 'w': 25.0},
                       'covariance': [[26.0 + 6 * i + j for j in range(6)] for i in range(6)]},
    'screw_axis': {'id': 1, 'action': 'ADD', 'type': 'ARROW',
                   'points': [[62.0, 63.0, 64.0], [65.0, 66.0, 67.0]]},
    'markers': [{'id': 2, 'action': 'ADD', 'type': 'LINE_STRIP'}, {'id': 3, 'action': 'DELETE'}],
}
"""How the client prints each of answer_messages(), by output name."""


def collected(messages):
    """Feed session.Answers the table's outputs; return (whether complete, the answer)."""
    answers = session.Answers(Header(frame_id='map', stamp=STAMP))
    for row in interface.OUTPUTS:  # the table as it is now
        if row.name == session.MATRIX:
            answers.matrices.append(messages[row.name])
        elif row.name in messages:
            answers.collector(row.name)(messages[row.name])
    answer = dict(answers.outputs)
    answer[session.MATRIX] = answers.matrix(R)
    return answers.complete(), answer


def printed(messages):
    """Return the client's printed answer to ``messages``, after checking it is complete."""
    complete, answer = collected(messages)
    assert complete
    return message_data.answer_data(answer, ANSWER_PARAMETERS)


def test_the_answer_messages_are_of_each_outputs_type():
    messages = answer_messages()
    assert list(messages) == [row.name for row in interface.OUTPUTS]
    for row in interface.OUTPUTS:
        assert type(messages[row.name]) is message_class(row.type_name), row.name


def test_the_client_prints_each_answer_under_its_output_name():
    answer = printed(answer_messages())
    assert answer == PRINTED
    assert list(answer) == [row.name for row in interface.OUTPUTS]


@pytest.mark.parametrize('order', ['reversed', 'shuffled'])
def test_the_answer_follows_the_tables_order(monkeypatch, order):
    if order == 'reversed':
        rows = interface.OUTPUTS[::-1]
    else:
        indices = np.random.default_rng(5).permutation(len(interface.OUTPUTS))
        rows = tuple(interface.OUTPUTS[i] for i in indices)
    monkeypatch.setattr(interface, 'OUTPUTS', rows)
    answer = printed(answer_messages())
    assert answer == PRINTED
    assert list(answer) == [row.name for row in rows]


@pytest.mark.parametrize('dropped', ['axis_angle', 'euler_angles', 'rpy', 'screw'])
def test_an_output_dropped_from_the_table_is_neither_awaited_nor_printed(monkeypatch, dropped):
    monkeypatch.setattr(interface, 'OUTPUTS',
                        tuple(row for row in interface.OUTPUTS if row.name != dropped))
    messages = answer_messages()
    del messages[dropped]
    answer = printed(messages)
    assert answer == {name: value for name, value in PRINTED.items() if name != dropped}


def test_a_new_output_is_awaited_and_printed_by_its_fields(monkeypatch):
    row = interface.Topic('gibbs', 'geometry_msgs/msg/Vector3Stamped', 'tan(θ/2)·l̂ again')
    monkeypatch.setattr(interface, 'OUTPUTS', interface.OUTPUTS + (row,))
    messages = answer_messages()
    complete, _ = collected(messages)
    assert not complete  # awaited: no answer is complete without it
    messages['gibbs'] = vector(31.0, 32.0, 33.0)
    answer = printed(messages)
    assert answer == {**PRINTED, 'gibbs': {'vector': {'x': 31.0, 'y': 32.0, 'z': 33.0}}}


def test_an_answer_without_rodrigues_is_complete():
    """At θ = π the node withholds ~/rodrigues: the answer is complete without it."""
    messages = answer_messages()
    del messages['rodrigues']
    answer = printed(messages)
    assert answer == {name: value for name, value in PRINTED.items() if name != 'rodrigues'}


AWAITED = ('quaternion', 'axis_angle', 'euler_angles', 'rpy', 'screw')
"""The outputs published with a header for every input: an answer is complete with them."""


def test_an_answer_without_an_output_of_every_input_is_not_complete():
    for name in AWAITED:
        messages = answer_messages()
        del messages[name]
        complete, _ = collected(messages)
        assert not complete, name


# echo


def test_echo_prints_a_message_of_the_outputs_type_under_its_name():
    msg = answer_messages()['rpy']
    assert message_data.echo_data(msg, interface.output_named('rpy'), ANSWER_PARAMETERS) == {
        'stamp': {'sec': 7, 'nanosec': 8}, 'frame_id': 'map', 'rpy': PRINTED['rpy']}


def test_echo_prints_a_message_of_another_type_whole():
    """A Vector3Stamped on ~/quaternion (echo --topic elsewhere): every field, as it is."""
    msg = answer_messages()['axis_angle']
    row = interface.output_named('quaternion')
    assert message_data.echo_data(msg, row, ANSWER_PARAMETERS) == {
        'header': {'stamp': {'sec': 7, 'nanosec': 8}, 'frame_id': 'map'},
        'vector': {'x': 1.0, 'y': 2.0, 'z': 3.0}}


def test_the_type_name_of_each_rows_message_class_is_the_rows():
    for row in interface.INPUTS + interface.OUTPUTS:
        assert type_name(message_class(row.type_name)) == row.type_name
