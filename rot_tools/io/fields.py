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
    """
    Return write(msg, values): values[k] written into the field at paths[k], in order.

    Consecutive paths under one parent ('vector.x', 'vector.y', 'vector.z'; 'data[0]' to
    'data[8]') are written together, the parent looked up once; each leaf gets what
    :func:`field_setter` would write into it.
    """
    groups = []  # (parent, indexed, leaves) of consecutive paths under one parent
    for path in paths:
        parent, indexed, leaf = _parent_and_leaf(path)
        if groups and groups[-1][:2] == (parent, indexed):
            groups[-1][2].append(leaf)
        else:
            groups.append((parent, indexed, [leaf]))
    puts, start = [], 0
    for parent, indexed, leaves in groups:
        puts.append((_children_setter(parent, indexed, tuple(leaves)),
                     slice(start, start + len(leaves))))
        start += len(leaves)

    def write(msg, values):
        for put, part in puts:
            put(msg, values[part])
    return write


def _parent_and_leaf(path):
    """
    Return (parent, indexed, leaf) of a path.

    ('vector', False, 'x') of 'vector.x', ('data', True, 3) of 'data[3]', ('', False, 'x')
    of 'x'.
    """
    name, indexed, index = path.partition('[')
    if indexed:
        return name, True, int(index.rstrip(']'))
    parent, _, leaf = name.rpartition('.')
    return parent, False, leaf


def _children_setter(parent, indexed, leaves):
    """
    Return put(msg, values): values written into the leaves of the field at ``parent``.

    leaves: the names of its members, or (``indexed``) the indices of its elements, which
    must exist already.
    """
    get = attrgetter(parent) if parent else (lambda msg: msg)
    if indexed:
        def put(msg, values):
            field = get(msg)
            for k, value in zip(leaves, values):
                field[k] = value
    else:
        def put(msg, values):
            field = get(msg)
            for name, value in zip(leaves, values):
                setattr(field, name, value)
    return put
