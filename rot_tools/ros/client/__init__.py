"""rotation_client: the command line that talks to a running rotation_node."""
