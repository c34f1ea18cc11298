"""The console-script entries stop cleanly on a signal even during start-up."""

import subprocess
import sys

import pytest

LIGHT = """
import sys
import rot_tools.entry
heavy = sorted(m for m in ('numpy', 'rclpy') if m in sys.modules)
print(','.join(heavy) or 'light')
"""

# Delivers the signal exactly while the entry imports the node (NumPy + rclpy), the window in
# which Python's default handling would exit with -15 or a KeyboardInterrupt traceback.
SIGNAL_DURING_IMPORT = """
import builtins, os, signal, sys
import rot_tools.entry as entry
real_import = builtins.__import__
def import_and_signal(name, *args, **kwargs):
    if name == 'rot_tools.{script}':
        os.kill(os.getpid(), signal.{sig})
    return real_import(name, *args, **kwargs)
builtins.__import__ = import_and_signal
sys.argv = ['{script}', 'describe']
sys.exit(entry.{script}())
print('not reached')
"""


def test_entry_module_imports_nothing_heavy():
    out = subprocess.run([sys.executable, '-c', LIGHT], capture_output=True, text=True,
                         timeout=60, check=True)
    assert out.stdout.strip() == 'light'


@pytest.mark.parametrize('script, sig, status', [
    ('rotation_node', 'SIGTERM', 0), ('rotation_node', 'SIGINT', 0),
    ('rotation_client', 'SIGINT', 130)])
def test_signal_during_start_up_exits_cleanly(script, sig, status):
    code = SIGNAL_DURING_IMPORT.format(script=script, sig=sig)
    proc = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == status, proc.stderr
    assert 'Traceback' not in proc.stderr
    assert 'not reached' not in proc.stdout


def test_console_script_uses_the_light_entry():
    from importlib.metadata import entry_points
    scripts = {ep.name: ep.value for ep in entry_points(group='console_scripts')}
    assert scripts['rotation_node'] == 'rot_tools.entry:rotation_node'
    assert scripts['rotation_client'] == 'rot_tools.entry:rotation_client'
