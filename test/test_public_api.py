"""
rot_tools uses other libraries (rclpy, rpyutils, rcl, ...) through their public names only.

A name starting with ``_`` is a library's own business: an rclpy patch release may rename
or remove it and break the node on a user's install. The check reads every module of
rot_tools/ (its syntax tree, not its text) and refuses:

- an import of a private module or name of another package (``rclpy._rclpy_pybind11``,
  ``from rclpy.executors import _x``) and anything of ``rclpy.impl`` (rclpy's
  implementation, private though its name has no ``_``);
- an attribute ``obj._name`` whose name rot_tools does not define itself (a ``def _name``,
  a class or module variable, an ``x._name = ...`` assignment): rclpy's ``self._context``,
  ``sub._callback_type``, ``node._parameter_overrides`` — through ``self`` too, since a
  subclass of an rclpy class inherits rclpy's private attributes;
- the same names as strings of getattr / hasattr / setattr / delattr.

Dunder names (Python's protocols) and the documented namedtuple methods
(``_replace``, ``_asdict``, ...) are public.
"""

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'rot_tools'

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


OLD_EXECUTOR = """
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.executors import Executor


class WaitSetExecutor(Executor):
    def __init__(self, context=None):
        super().__init__(context=context)
        self._burst = 10

    def spin_once(self, timeout_sec=None):
        if self._is_shutdown:
            return
        guards = (self._guard, self._sigint_gc)
        self._context.handle.__enter__()
        wait_set = _rclpy.WaitSet(1, 2, 0, 0, 0, 0, self._context.handle)

    def _take(self, sub):
        return sub._callback_type, self._burst


def overrides(node):
    return getattr(node, '_parameter_overrides', {})
"""
"""What rot_tools' own executor and node once did (rclpy 7.1's private names)."""


def test_the_check_catches_what_the_node_once_did():
    tree = ast.parse(OLD_EXECUTOR)
    own = _own_names([tree])
    whats = {what for _, what in private_uses(tree, own)}
    assert whats == {
        'from rclpy.impl.implementation_singleton import ...', 'self._is_shutdown',
        'self._guard', 'self._sigint_gc', 'self._context', 'sub._callback_type',
        "getattr(..., '_parameter_overrides')"}


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
