"""The sub-packages keep their layers: core and io import no ROS, and no import points up."""

import ast
import os
import pathlib
import re
import subprocess
import sys

import pytest

PACKAGE = pathlib.Path(__file__).resolve().parents[1] / 'rot_tools'

LAYERS = {'core': set(), 'io': {'core'}, 'cli': {'io', 'core'}, 'ros': {'io', 'core'}}
"""Each sub-package and the sub-packages it may import (`ros` and `cli` → `io` → `core`)."""

ROS_PREFIXES = ('rclpy', 'rosidl', 'rcl_interfaces', 'builtin_interfaces', 'geometry_msgs',
                'std_msgs', 'nav_msgs', 'sensor_msgs', 'std_srvs', 'visualization_msgs',
                'ament_index', 'tf2_msgs', 'rpyutils', 'rcl')

# Runs in a fresh interpreter: a meta-path finder records (and refuses) every attempt to
# import a ROS package, so even a guarded `try: import rclpy` is caught; then every module of
# the ROS-free sub-packages is imported and sys.modules is checked as well.
PROBE = r"""
import importlib
import pkgutil
import sys

ROS_PREFIXES = {prefixes}
attempts = []


class RefuseRos:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0].startswith(ROS_PREFIXES):
            attempts.append(name)
            raise ImportError('ROS import refused by test_no_ros: ' + name)
        return None


sys.meta_path.insert(0, RefuseRos())
import rot_tools
modules = ['rot_tools']
for sub in ('core', 'io', 'cli'):
    package = importlib.import_module('rot_tools.' + sub)
    modules += [package.__name__ + '.' + m.name for m in pkgutil.iter_modules(package.__path__)]
for name in modules:
    importlib.import_module(name)
getattr(rot_tools, rot_tools.__all__[0])  # every public name
loaded = sorted(m for m in sys.modules if m.split('.')[0].startswith(ROS_PREFIXES))
print('modules', ' '.join(modules))
print('attempts', ' '.join(attempts))
print('loaded', ' '.join(loaded))
""".replace('{prefixes}', repr(ROS_PREFIXES))


def run_probe():
    root = PACKAGE.parent
    env = dict(os.environ)
    env['PYTHONPATH'] = os.pathsep.join(filter(None, [str(root), env.get('PYTHONPATH')]))
    done = subprocess.run([sys.executable, '-c', PROBE], capture_output=True, text=True,
                          env=env, cwd=root, timeout=60)
    assert done.returncode == 0, done.stderr
    return dict(line.partition(' ')[::2] for line in done.stdout.splitlines())


def test_core_io_and_cli_import_no_ros():
    out = run_probe()
    modules = out['modules'].split()
    for module in ('core.errors', 'core.so3', 'core.euler', 'io.boundary', 'cli.main'):
        assert 'rot_tools.' + module in modules
    assert out['attempts'] == '', 'ROS-free modules tried to import ' + out['attempts']
    assert out['loaded'] == '', 'ROS-free modules loaded ' + out['loaded']


def imported_modules(path):
    """Every module name a file imports (absolute names; the package uses no relative ones)."""
    tree = ast.parse(path.read_text(), str(path))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, f'{path}: relative import'
            yield node.module
            yield from (f'{node.module}.{alias.name}' for alias in node.names)


def test_every_module_lives_in_a_sub_package():
    top = sorted(p.name for p in PACKAGE.glob('*.py'))
    assert top == ['__init__.py']
    assert sorted(p.name for p in PACKAGE.iterdir() if p.is_dir() and p.name != '__pycache__') \
        == sorted(LAYERS)


@pytest.mark.parametrize('sub', sorted(LAYERS))
def test_imports_point_down_only(sub):
    allowed = LAYERS[sub] | {sub}
    for path in sorted((PACKAGE / sub).rglob('*.py')):
        for name in imported_modules(path):
            parts = name.split('.')
            if parts[0] != 'rot_tools':
                if sub in ('core', 'io', 'cli'):
                    assert not parts[0].startswith(ROS_PREFIXES), f'{path.name} imports {name}'
                continue
            assert len(parts) == 1 or parts[1] not in LAYERS or parts[1] in allowed, \
                f'{path.relative_to(PACKAGE)} imports {name}: {sub} may import only ' \
                f'{", ".join(sorted(allowed))}'


def test_the_package_root_imports_only_core():
    for name in imported_modules(PACKAGE / '__init__.py'):
        assert not name.startswith(('rot_tools.io', 'rot_tools.cli', 'rot_tools.ros')), name


def test_no_code_is_compiled_or_generated():
    """Nothing in rot_tools/ calls exec or compile, or names generated code."""
    found = [f'{path.relative_to(PACKAGE.parent)}:{number}: {line.strip()}'
             for path in sorted(PACKAGE.rglob('*.py'))
             for number, line in enumerate(path.read_text().splitlines(), 1)
             if re.search(r'exec\(|compile\(|_generated', line)]
    assert found == []


def test_no_module_is_longer_than_700_lines():
    long = {str(path.relative_to(PACKAGE.parent)): count
            for path in sorted(PACKAGE.rglob('*.py'))
            if (count := len(path.read_text().splitlines())) > 700}
    assert long == {}


def test_dir_shows_the_public_names_and_the_sub_packages_only():
    probe = ('import rot_tools as rt\nbefore = set(dir(rt))\nrt.rot_x(0.1)\n'
             'print(" ".join(sorted(before)))\nprint(" ".join(sorted(dir(rt))))')
    done = subprocess.run([sys.executable, '-c', probe], capture_output=True, text=True,
                          cwd=PACKAGE.parent, timeout=60)
    assert done.returncode == 0, done.stderr
    import rot_tools
    for line in done.stdout.splitlines():
        shown = {n for n in line.split() if not n.startswith('_')}
        assert shown <= set(rot_tools.__all__) | set(LAYERS), shown - set(rot_tools.__all__)
    assert set(rot_tools.__all__) <= set(done.stdout.splitlines()[1].split())
