"""
Console-script entries of rotation_node and rotation_client (setup.py's console_scripts).

Each names its program's module and hands it to rot_tools.ros.runtime, which installs the signal
handlers before the module (NumPy, rclpy) loads: see rot_tools.ros.runtime.start. This module and
rot_tools.ros.runtime import nothing heavy, and neither imports the programs' modules by name.
"""

from rot_tools.ros import runtime


def rotation_node(args=None):
    """Run rot_tools.ros.rotation_node.main as this process (rot_tools.ros.runtime.start)."""
    runtime.start('rot_tools.ros.rotation_node', args)


def rotation_client(args=None):
    """Run rot_tools.ros.rotation_client.main; Ctrl-C at any moment ends it with status 130."""
    return runtime.start_command('rot_tools.ros.rotation_client', args)
