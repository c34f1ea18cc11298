"""Importing the math half of rot_tools pulls in no ROS."""

import os
import pathlib
import subprocess
import sys

ROS_AWARE = {'messages', 'rotation_node', 'rotation_client', 'executor', 'service_host',
             'tf_input'}

# Runs in a fresh interpreter: a meta-path finder records (and refuses) every attempt to
# import a ROS package, so even a guarded `try: import rclpy` is caught; then every math
# module of the package is imported and sys.modules is checked as well.
PROBE = r"""
import importlib
import pkgutil
import sys

ROS_PREFIXES = ('rclpy', 'rosidl', 'rcl_interfaces', 'builtin_interfaces', 'geometry_msgs',
                'std_msgs', 'nav_msgs', 'sensor_msgs', 'std_srvs', 'visualization_msgs',
                'ament_index', 'tf2_msgs')
attempts = []


class RefuseRos:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0].startswith(ROS_PREFIXES):
            attempts.append(name)
            raise ImportError('ROS import refused by test_no_ros: ' + name)
        return None


sys.meta_path.insert(0, RefuseRos())
import rot_tools
modules = ['rot_tools'] + ['rot_tools.' + m.name for m in pkgutil.iter_modules(rot_tools.__path__)
                           if m.name not in {ros_aware}]
for name in modules:
    importlib.import_module(name)
loaded = sorted(m for m in sys.modules if m.split('.')[0].startswith(ROS_PREFIXES))
print('modules', ' '.join(modules))
print('attempts', ' '.join(attempts))
print('loaded', ' '.join(loaded))
""".replace('{ros_aware}', repr(ROS_AWARE))


def run_probe():
    root = pathlib.Path(__file__).resolve().parents[1]
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(root), env.get('PYTHONPATH')]))
    done = subprocess.run([sys.executable, '-c', PROBE], capture_output=True, text=True,
                          env=env, cwd=root, timeout=60)
    assert done.returncode == 0, done.stderr
    return dict(line.partition(' ')[::2] for line in done.stdout.splitlines())


def test_math_modules_import_no_ros():
    out = run_probe()
    modules = out['modules'].split()
    for core in ('errors', 'so3', 'euler', 'axis_angle', 'screw'):
        assert 'rot_tools.' + core in modules
    assert out['attempts'] == '', 'math modules tried to import ' + out['attempts']
    assert out['loaded'] == '', 'math modules loaded ' + out['loaded']
    for name in ('rclpy', 'rosidl', 'geometry_msgs'):
        assert name not in out['loaded']
