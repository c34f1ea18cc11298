"""
A message's fields by their paths: read and written.

A path names a field from the message down, dot-separated ('pose.pose.orientation',
'header.stamp'); its last field may be indexed ('orientation_covariance[0]', 'data[3]'). The
paths are those of the interface table (rot_tools.io.interface). Any object with the
message's attribute names will do — rclpy's message objects (rotation_node,
rotation_client) and rosbags' (``rot-tools bag``) alike: this module imports no ROS.
"""

from operator import attrgetter


def field_getter(path):
    """
    Return get(msg): the field at ``path`` of a message ('pose.position', 'data[3]').

    The path names fields from the message down, dot-separated; only its last field may be
    indexed (an element of an array or a sequence).
    """
    name, indexed, index = path.partition('[')
    get = attrgetter(name)
    if not indexed:
        return get
    k = int(index.rstrip(']'))
    return lambda msg: get(msg)[k]


def field_value(msg, path):
    """Return the field at ``path`` of a message: 'pose.position', 'data[3]'."""
    return field_getter(path)(msg)


def fields_reader(paths):
    """Return read(msg): the tuple of the fields at ``paths`` of a message, in order."""
    getters = tuple(map(field_getter, paths))
    return lambda msg: tuple([get(msg) for get in getters])


def field_setter(path):
    """
    Return put(msg, value): ``value`` written into the field at ``path`` of a message.

    As :func:`field_getter`'s paths; an indexed element must exist already (a fixed-size
    array, or a sequence given its length once).
    """
    name, indexed, index = path.partition('[')
    if indexed:
        get, k = attrgetter(name), int(index.rstrip(']'))

        def put(msg, value):
            get(msg)[k] = value
        return put
    parent, _, leaf = name.rpartition('.')
    get = attrgetter(parent) if parent else (lambda msg: msg)

    def put(msg, value):
        setattr(get(msg), leaf, value)
    return put


def fields_writer(paths):
    """Return write(msg, values): values[k] written into the field at paths[k], in order."""
    setters = tuple(map(field_setter, paths))

    def write(msg, values):
        for put, value in zip(setters, values):
            put(msg, value)
    return write
