"""
Console-script entries of rotation_node and rotation_client (setup.py's console_scripts).

Each names its program's module and hands it to rot_tools.runtime, which installs the signal
handlers before the module (NumPy, rclpy) loads: see rot_tools.runtime.start. This module and
rot_tools.runtime import nothing heavy, and neither imports the programs' modules by name.
"""

from rot_tools import runtime


def rotation_node(args=None):
    """Run rot_tools.rotation_node.main as this process (rot_tools.runtime.start)."""
    runtime.start('rot_tools.rotation_node', args)


def rotation_client(args=None):
    """Run rot_tools.rotation_client.main; Ctrl-C at any moment ends it with status 130."""
    return runtime.start_command('rot_tools.rotation_client', args)
