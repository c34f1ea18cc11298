"""
rotation_node's topics as rclpy takes them.

Each row of rot_tools.io.interface bound to its message class and to the reader or writer
of its bytes (rot_tools.io.cdr).

The node subscribes raw (``create_subscription(..., raw=True)``: the callback gets the
message's bytes) and publishes bytes (``publish(bytes)``), both public rclpy API; the bytes
are read and written from the rows' fields, and test_cdr checks them against
rclpy.serialization for every row.
"""

from typing import Callable, NamedTuple

from rot_tools.io import cdr, interface
from rot_tools.ros.messages import message_class


class Subscribed(NamedTuple):
    """An input row with its message class and read(data) -> (header, values)."""

    row: interface.Input
    msg_type: type
    read: Callable

    @property
    def topic(self):
        """Return the topic of the row, e.g. '~/pose'."""
        return self.row.topic


class Published(NamedTuple):
    """An output row with its message class and encode(head, values) -> bytes (or None)."""

    row: interface.Output
    msg_type: type
    encode: Callable

    @property
    def topic(self):
        """Return the topic of the row, e.g. '~/quaternion'."""
        return self.row.topic


def subscribed(row):
    """Return an input row bound to its message class and the reader of its fields."""
    return Subscribed(row, message_class(row.type_name), cdr.input_reader(row))


def published(row):
    """Return an output row bound to its message class and the writer of its fields."""
    encode = cdr.output_writer(row) if row.value is not None else None
    return Published(row, message_class(row.type_name), encode)


INPUTS = tuple(map(subscribed, interface.INPUTS))
"""Every input of the node, as it subscribes them."""

OUTPUTS = tuple(map(published, interface.OUTPUTS))
"""Every output of the node, as it publishes them (a picture has no ``encode``)."""
