"""rotation_node: the node program, its messages, pictures, services and /tf input."""
