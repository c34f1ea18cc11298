"""
rotation_node's topics as rclpy takes them.

Each row of rot_tools.io.interface bound to its message class, and to the reader or the
writer of its fields by their paths (rot_tools.io.fields.fields_reader, fields_writer):
the node takes and publishes message objects, and reads or writes in them exactly the
fields its rows name.
"""

import math
from typing import Callable, NamedTuple

from rot_tools.io import interface
from rot_tools.io.fields import fields_reader, fields_writer
from rot_tools.ros.messages import message_class


class Subscribed(NamedTuple):
    """An input row with its message class and read(msg) -> the numbers of row.floats()."""

    row: interface.Input
    msg_type: type
    read: Callable

    @property
    def topic(self):
        """Return the topic of the row, e.g. '~/pose'."""
        return self.row.topic


class Published(NamedTuple):
    """An output row with its message class, write(msg, numbers) of row.fields, numbers()."""

    row: interface.Output
    msg_type: type
    write: Callable

    @property
    def topic(self):
        """Return the topic of the row, e.g. '~/quaternion'."""
        return self.row.topic

    def message(self):
        """
        Return a message of the row's type, ready to be written by ``write``.

        A MultiArray gets its layout (the row's, constant) and its data sized.
        """
        msg = self.msg_type()
        if self.row.layout:
            dimension = message_class('std_msgs/msg/MultiArrayDimension')
            msg.layout.dim = [dimension(label=label, size=size, stride=stride)
                              for label, size, stride in self.row.layout]
            msg.data = [0.0] * self.row.layout[0][2]
        return msg

    def numbers(self, R, decomposition, degrees):
        """
        Return the numbers of one input that this output publishes, as write takes them.

        R row-major (interface.MATRIX), or the row's field of the input's decomposition as
        Python numbers (rot_tools.core.decomposition.decompose_one); angles in degrees when
        ``degrees`` (the decomposition's are in radians).
        """
        if self.row.value == interface.MATRIX:
            return R.ravel().tolist()
        value = getattr(decomposition, self.row.value)
        if self.row.angles and degrees:
            return [math.degrees(angle) for angle in value]
        return value


def subscribed(row):
    """Return an input row bound to its message class and the reader of its fields."""
    return Subscribed(row, message_class(row.type_name), fields_reader(row.floats()))


def published(row):
    """Return an output row bound to its message class and the writer of its fields."""
    return Published(row, message_class(row.type_name), fields_writer(row.fields))


INPUTS = tuple(map(subscribed, interface.INPUTS))
"""Every input of the node, as it subscribes them."""

OUTPUTS = tuple(map(published, interface.OUTPUTS))
"""Every output of the node, as it publishes them (a picture has no fields to write)."""
