"""Message classes by their type names ('nav_msgs/msg/Odometry'), for the node and the client."""

import importlib


def type_name(msg_type):
    """'nav_msgs/msg/Odometry' for the message class nav_msgs.msg.Odometry."""
    return f"{msg_type.__module__.split('.')[0]}/msg/{msg_type.__name__}"


def message_class(name):
    """Return the message class nav_msgs.msg.Odometry of 'nav_msgs/msg/Odometry' (imported)."""
    package, interface_kind, class_name = name.split('/')
    return getattr(importlib.import_module(f'{package}.{interface_kind}'), class_name)
