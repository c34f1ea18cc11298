"""What the package imports, and what the tests need of the machine."""

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


PUBLIC_UNDERSCORED = {(None, '_replace'), (None, '_asdict'),
                      (None, '_fields'), (None, '_make'), (None, '_field_defaults')}
"""Documented names that start with ``_``: (the object's name or None for any, attribute)."""

PRIVATE_MODULES = ('rclpy.impl',)
"""Modules private though no part of their name starts with ``_``."""


def _private(name):
    return name.startswith('_') and not (name.startswith('__') and name.endswith('__'))


def _own_names(trees):
    """Return every underscored name rot_tools defines itself."""
    own = set()
    for tree in trees:
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                own.add(node.name)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                own.add(node.id)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                own.add(node.attr)
            elif isinstance(node, ast.alias) and node.asname:
                own.add(node.asname)
            elif isinstance(node, ast.arg):
                own.add(node.arg)
    return {name for name in own if _private(name)}


def _foreign_module(module):
    return module is not None and module.split('.')[0] != 'rot_tools'


def _private_module(module):
    return (any(_private(part) for part in module.split('.'))
            or any(module == p or module.startswith(p + '.') for p in PRIVATE_MODULES))


def private_uses(tree, own):
    """Return (line, what) for each use of another library's private name in ``tree``."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if _foreign_module(alias.name) and _private_module(alias.name):
                    found.append((node.lineno, f'import {alias.name}'))
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            if not _foreign_module(node.module):
                continue
            if _private_module(node.module):
                found.append((node.lineno, f'from {node.module} import ...'))
                continue
            for alias in node.names:
                if _private(alias.name) or _private_module(f'{node.module}.{alias.name}'):
                    found.append((node.lineno, f'from {node.module} import {alias.name}'))
        elif isinstance(node, ast.Attribute):
            owner = node.value.id if isinstance(node.value, ast.Name) else None
            if (_private(node.attr) and node.attr not in own
                    and (owner, node.attr) not in PUBLIC_UNDERSCORED
                    and (None, node.attr) not in PUBLIC_UNDERSCORED):
                found.append((node.lineno, f'{owner or "..."}.{node.attr}'))
            if node.attr == 'impl' and owner == 'rclpy':
                found.append((node.lineno, 'rclpy.impl'))
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
              and node.func.id in ('getattr', 'hasattr', 'setattr', 'delattr')
              and len(node.args) >= 2 and isinstance(node.args[1], ast.Constant)
              and isinstance(node.args[1].value, str) and _private(node.args[1].value)
              and node.args[1].value not in own):
            found.append((node.lineno, f'{node.func.id}(..., {node.args[1].value!r})'))
    return found


def _trees():
    return {path: ast.parse(path.read_text(encoding='utf-8'), str(path))
            for path in sorted(PACKAGE.rglob('*.py'))}


def test_rot_tools_uses_no_private_name_of_another_library():
    trees = _trees()
    own = _own_names(trees.values())
    found = [f'{path.relative_to(PACKAGE.parent)}:{line}: {what}'
             for path, tree in trees.items() for line, what in private_uses(tree, own)]
    assert not found, 'private names of other libraries:\n' + '\n'.join(found)


@pytest.mark.parametrize('source, what', [
    ('import rclpy._rclpy_pybind11', 'import rclpy._rclpy_pybind11'),
    ('from rclpy import _rclpy_pybind11', 'from rclpy import _rclpy_pybind11'),
    ('import rclpy.impl.rcutils_logger', 'import rclpy.impl.rcutils_logger'),
    ('from rclpy import impl', 'from rclpy import impl'),
    ('import rclpy\nrclpy.impl.x', 'rclpy.impl'),
    ('from rpyutils import _x', 'from rpyutils import _x'),
    ('node._parameter_overrides', 'node._parameter_overrides'),
    ('hasattr(node, "_guard")', "hasattr(..., '_guard')"),
])
def test_the_check_catches_each_form(source, what):
    tree = ast.parse(source)
    assert what in {found for _, found in private_uses(tree, _own_names([tree]))}


def test_the_check_passes_own_and_documented_names():
    source = ('import os\nclass A:\n    def __init__(self):\n        self._x = 1\n'
              '    def _f(self):\n        return self._x, self._f, self.__dict__\n'
              'p = point._replace(x=1)\n'
              'from rot_tools.core._arrays import apart\n')
    tree = ast.parse(source)
    assert private_uses(tree, _own_names([tree])) == []


REFUSE_PLUGIN = r"""
import sys

REFUSED = set(sys.argv[-1].split(','))


class Refuse:
    def find_spec(self, name, path=None, target=None):
        if name.split('.')[0] in REFUSED:
            raise ModuleNotFoundError(f'No module named {name!r}', name=name)


sys.meta_path.insert(0, Refuse())
"""


def collect_without(tmp_path, refused, *test_files):
    """Collect ``test_files`` in a pytest whose imports of ``refused`` fail; return its run."""
    (tmp_path / 'refuse_imports.py').write_text(REFUSE_PLUGIN.replace(
        'sys.argv[-1]', repr(','.join(refused))))
    root = PACKAGE.parent
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        filter(None, [str(tmp_path), str(root), os.environ.get('PYTHONPATH')])))
    return subprocess.run(
        [sys.executable, '-m', 'pytest', '-p', 'no:cacheprovider', '-p', 'refuse_imports',
         '--collect-only', '-q', '-rs', *(f'test/{name}' for name in test_files)],
        capture_output=True, text=True, env=env, cwd=root, timeout=120)


def test_test_modules_that_need_ros_or_scipy_are_skipped_without_them(tmp_path):
    done = collect_without(tmp_path, ['rclpy', 'geometry_msgs', 'scipy'],
                           'test_messages.py', 'test_client_tools.py', 'test_fitting.py',
                           'test_euler.py')
    assert done.returncode == 0, done.stdout + done.stderr
    assert 'needs geometry_msgs, not installed' in done.stdout
    assert 'needs scipy, not installed' in done.stdout
    assert 'test_euler.py::' in done.stdout and 'test_fitting.py::' not in done.stdout


def test_a_missing_required_package_is_an_error_not_a_skip(tmp_path):
    done = collect_without(tmp_path, ['hypothesis'], 'test_euler.py')
    assert done.returncode != 0
    assert "No module named 'hypothesis'" in done.stdout, done.stdout
