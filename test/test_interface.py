"""rot_tools.io.interface: a row per input and output, as the node and bag reader show them."""

import pytest
from rot_tools.io import bag_read, interface
from rot_tools.ros.message_types import message_class
from rot_tools.ros.node.rotation_node import RotationNode, usage


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


def test_help_lists_every_row_with_its_type_and_help():
    text = ' '.join(usage().split())  # (unwrapped)
    for row in interface.INPUTS + interface.OUTPUTS:
        assert f'{row.topic} {row.type_name}: {" ".join(row.help.split())}' in text, row.name


def test_the_bag_reader_reads_every_input_with_an_orientation():
    from rosbags.typesys import get_typestore, Stores
    typestore = get_typestore(Stores.ROS2_JAZZY)
    oriented = {row.type_name for row in interface.INPUTS if row.name != 'euler'}
    assert set(bag_read.SUPPORTED) == oriented  # (a Vector3Stamped holds no Euler sequence)
    for type_name, fields in bag_read.SUPPORTED.items():
        assert type_name in typestore.types
        names = set(message_class(type_name).get_fields_and_field_types())
        assert {path.split('.')[0] for path in fields.values()} <= names, type_name


def test_output_named_finds_a_row_by_name():
    assert interface.output_named('rodrigues').type_name == 'geometry_msgs/msg/Vector3Stamped'
    with pytest.raises(KeyError):
        interface.output_named('no_such_output')
