"""
rot_tools.io.interface: one row per input and output, read by everything that lists them.

The node's graph (rclpy's introspection of its publishers and subscriptions) against the
table, the client's verbs and answers, and the bag reader's types, against the same rows.
The client matches answers to outputs by name: reordered or fewer rows change nothing else.
"""

from builtin_interfaces.msg import Time
import numpy as np
import pytest
from rot_tools.io import bag_read, interface
from rot_tools.io.fields import field_value
from rot_tools.ros.client import message_data, session
from rot_tools.ros.client.arguments import parse_args
from rot_tools.ros.messages import message_class
from rot_tools.ros.rotation_node import RotationNode

PARAMETERS = {'euler_sequence': 'ZYX', 'angle_unit': 'rad', 'publish_markers': True}
"""The node's parameters as the client reads them (defaults)."""


@pytest.fixture(scope='module')
def graph(ros_context):
    """Return ({topic: [types]} subscribed, {topic: [types]} published) of a RotationNode."""
    node = RotationNode('interface_check', context=ros_context, namespace='/interface')
    try:
        name, namespace = node.get_name(), node.get_namespace()
        subscribed = dict(node.get_subscriber_names_and_types_by_node(name, namespace))
        published = dict(node.get_publisher_names_and_types_by_node(name, namespace))
    finally:
        node.destroy_node()
    return subscribed, published


def test_the_node_subscribes_every_input_row(graph):
    subscribed, _ = graph
    for row in interface.INPUTS:
        assert subscribed[f'/interface/interface_check/{row.name}'] == [row.type_name]


def test_the_node_publishes_every_output_row(graph):
    _, published = graph
    for row in interface.OUTPUTS:
        assert published[f'/interface/interface_check/{row.name}'] == [row.type_name]


def test_the_node_subscribes_and_publishes_nothing_else(graph):
    subscribed, published = graph
    ours = {topic for topic in {**subscribed, **published}
            if topic.startswith('/interface/interface_check/')}
    rows = {f'/interface/interface_check/{row.name}'
            for row in interface.INPUTS + interface.OUTPUTS}
    assert ours == rows


def numbers_of(args):
    return [str(0.1 * (k + 1)) for k in range(args)]


@pytest.mark.parametrize('row', interface.INPUTS, ids=lambda row: row.name)
def test_every_input_is_a_client_verb_that_fills_the_rows_fields(row):
    """Parse ``VERB numbers``, build the message: each field of the row holds its number."""
    count = sum(len(interface.MEMBERS[role]) for role in row.fields
                if role in ('position', 'orientation', 'angles'))
    given = [float(n) for n in numbers_of(count)]
    sequence = ['ZYX'] if 'angles' in row.fields else []
    args = parse_args([row.name, *sequence, *numbers_of(count), '--child-frame', 'body']
                      if 'child_frame_id' in row.fields else
                      [row.name, *sequence, *numbers_of(count)])
    assert args.row is row
    msg, sent = message_data.input_message(args, PARAMETERS)
    assert isinstance(msg, message_class(row.type_name))
    written = [field_value(msg, path) for path in row.floats()
               if not path.endswith('[0]')]  # an Imu's covariance is not given: 0
    assert written == pytest.approx(given, abs=1e-15)
    for path in row.strings():
        assert field_value(msg, path) == sent[path] == 'body'


def test_the_bag_reader_reads_every_input_with_an_orientation():
    from rosbags.typesys import get_typestore, Stores
    typestore = get_typestore(Stores.ROS2_JAZZY)
    oriented = {row.type_name for row in interface.INPUTS if 'orientation' in row.fields}
    assert set(bag_read.SUPPORTED) == oriented
    assert 'geometry_msgs/msg/Vector3Stamped' not in bag_read.SUPPORTED  # Euler: no sequence
    for row in interface.INPUTS:
        if row.type_name in oriented:  # every field the bag reader reads is the message's
            assert bag_read.SUPPORTED[row.type_name] == {**row.fields, **row.bag_fields}
            assert row.type_name in typestore.types


# ---------------------------------------------------------------------------------------
# The client's answers, by output name


def answer_messages():
    """Return {output name: a message of its type}, each with distinct numbers, stamped 7."""
    messages = {}
    for k, row in enumerate(interface.OUTPUTS):
        msg = message_class(row.type_name)()
        if row.name == 'markers':
            msg.markers = [message_class('visualization_msgs/msg/Marker')()]
            header = msg.markers[0].header
        else:
            header = getattr(msg, 'header', None)
        if header is not None:
            header.stamp, header.frame_id = Time(sec=7, nanosec=8), 'map'
        if row.name == 'rotation_matrix':
            msg.data = np.eye(3).ravel().tolist()
        for j, path in enumerate(row.fields):
            parent, _, member = path.rpartition('.')
            name, _, index = member.partition('[')
            if not parent or row.name == 'rotation_matrix':
                continue
            if index:  # an element of an array: pose.covariance[3]
                getattr(field_value(msg, parent), name)[int(index[:-1])] = 10.0 * k + j
            else:
                setattr(field_value(msg, parent), member, 10.0 * k + j)
        if row.name == 'quaternion':
            msg.quaternion.x = msg.quaternion.y = msg.quaternion.z = 0.0
            msg.quaternion.w = 1.0  # the identity, as the matrix
        messages[row.name] = msg
    return messages


def collect(messages):
    """Feed an Answers the messages as the subscriptions would; return the complete answer."""
    answers = session.Answers('map')
    answers.sent.add((7, 8))
    for row in interface.OUTPUTS:  # the table as it is now (reordered or not)
        if row.stamped:
            answers.collector(row.name)(messages[row.name])
        else:
            answers.matrices.append(messages[row.name])
    stamp = answers.complete()
    assert stamp == (7, 8)
    answer = dict(answers.by_stamp[stamp])
    answer[session.MATRIX] = answers.matrix(np.eye(3))
    return answer


def test_the_client_prints_each_answer_under_its_output_name(monkeypatch):
    messages = answer_messages()
    expected = message_data.answer_data(collect(messages), PARAMETERS)
    assert list(expected) == [row.name for row in interface.OUTPUTS]
    assert expected['axis_angle'] == [20.0, 21.0, 22.0]
    assert expected['screw'] == {'angular': [50.0, 51.0, 52.0], 'linear': [53.0, 54.0, 55.0]}
    assert expected['rpy'] == {'roll': 40.0, 'pitch': 41.0, 'yaw': 42.0, 'unit': 'rad'}
    k = [row.name for row in interface.OUTPUTS].index('rpy_covariance')
    assert expected['rpy_covariance'] == {
        'position': [10.0 * k, 10.0 * k + 1, 10.0 * k + 2],
        'orientation': {'x': 10.0 * k + 3, 'y': 10.0 * k + 4, 'z': 10.0 * k + 5,
                        'w': 10.0 * k + 6},
        'covariance': (10.0 * k + 7 + np.arange(36).reshape(6, 6)).tolist()}
    monkeypatch.setattr(interface, 'OUTPUTS', interface.OUTPUTS[::-1])
    reordered = message_data.answer_data(collect(messages), PARAMETERS)
    assert reordered == expected and list(reordered) == list(expected)[::-1]
    dropped = tuple(row for row in interface.OUTPUTS if row.name != 'euler_angles')
    monkeypatch.setattr(interface, 'OUTPUTS', dropped)
    fewer = message_data.answer_data(collect(messages), PARAMETERS)
    assert fewer == {name: value for name, value in reordered.items() if name != 'euler_angles'}


def test_a_new_output_row_is_printed_by_its_fields(monkeypatch):
    row = interface.Output('rotvec_again', 'geometry_msgs/msg/Vector3Stamped',
                           interface.members('vector', 'xyz'), 'rotvec')
    monkeypatch.setattr(interface, 'OUTPUTS', interface.OUTPUTS + (row,))
    messages = answer_messages()
    answer = message_data.answer_data(collect(messages), PARAMETERS)
    k = len(interface.OUTPUTS) - 1
    assert answer['rotvec_again'] == {'vector': {'x': 10.0 * k, 'y': 10.0 * k + 1,
                                                 'z': 10.0 * k + 2}}
    assert session.stamped_outputs()[-1] == 'rotvec_again'  # awaited like the others


def test_every_output_names_what_it_publishes():
    """Each per-input output holds a field of the Decomposition by name, the matrix or a pose."""
    from rot_tools.core.decomposition import Decomposition
    for row in interface.OUTPUTS:
        if row.value is None:  # a picture
            continue
        assert row.value in Decomposition._fields or row.value in (
            interface.MATRIX, interface.POSE_COVARIANCE), row.name
