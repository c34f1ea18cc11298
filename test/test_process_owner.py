"""rot_tools leaves the process and the wire to their owners (read from its syntax trees)."""

import ast
import io
from pathlib import Path
import re
import tokenize

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / 'rot_tools'

ROSBAGS_MODULES = ('rosbags.highlevel', 'rosbags.rosbag1', 'rosbags.rosbag2',
                   'rosbags.typesys', 'rosbags.typesys.stores', 'rosbags.serde',
                   'rosbags.interfaces')
"""The rosbags modules its documentation describes (readers, writers, type stores, serde)."""


def _rosbags_internal(module):
    return module.split('.')[0] == 'rosbags' and module not in ROSBAGS_MODULES


ENVIRON_METHODS = {'setdefault', 'update', 'pop', 'popitem', 'clear', '__setitem__',
                   '__delitem__'}

FIGURE = re.compile(r'\d(?:[\d,.]*\d)?\s?(?:µs|us|ns|MB|kB|KB|GB|MiB|KiB|GiB)\b')
"""A measured figure: a number with a unit of time below a millisecond or of memory."""


def _sources():
    return sorted(PACKAGE.rglob('*.py'))


def _name(node):
    """'os.environ' for the expression os.environ, 'environ' for environ; '' otherwise."""
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        owner = _name(node.value)
        return f'{owner}.{node.attr}' if owner else ''
    return ''


def _is_environ(node):
    return _name(node) in ('os.environ', 'environ')


def _constant_name(node):
    return _name(node).rsplit('.', 1)[-1]


def _disposition(call):
    """Whether a call signal.signal(SIG, X) gives SIG its default or ignores it (no handler)."""
    return len(call.args) == 2 and _constant_name(call.args[1]) in ('SIG_DFL', 'SIG_IGN')


def takeovers(tree):
    """(line, what) of every use the module docstring refuses, in one module's tree."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                root = alias.name.split('.')[0]
                if root in ('struct', 'ctypes', '_ctypes'):
                    found.append((node.lineno, f'import {alias.name}'))
                if _rosbags_internal(alias.name):
                    found.append((node.lineno, f'import {alias.name}'))
        elif isinstance(node, ast.ImportFrom) and node.module:
            root = node.module.split('.')[0]
            if root in ('struct', 'ctypes', '_ctypes'):
                found.append((node.lineno, f'from {node.module} import ...'))
            if _rosbags_internal(node.module):
                found.append((node.lineno, f'from {node.module} import ...'))
            takeover = ('_exit', 'freeze', 'disable', 'putenv', 'unsetenv', 'environ')
            if root in ('os', 'gc') and any(a.name in takeover for a in node.names):
                found.append((node.lineno, f'from {node.module} import ...'))
        elif isinstance(node, ast.Attribute):
            name = _name(node)
            if name in ('os._exit', 'gc.freeze', 'gc.disable', 'os.putenv', 'os.unsetenv'):
                found.append((node.lineno, name))
            if node.attr in ('fielddefs', 'readers', 'mallopt'):
                found.append((node.lineno, f'.{node.attr}'))
            if node.attr == 'callback' and isinstance(node.ctx, ast.Store):
                found.append((node.lineno, f'{_name(node.value) or "..."}.callback = ...'))
            if (node.attr in ENVIRON_METHODS and _is_environ(node.value)):
                found.append((node.lineno, f'{_name(node.value)}.{node.attr}'))
            if name in ('signal.pthread_sigmask', 'signal.sigwait', 'signal.set_wakeup_fd'):
                found.append((node.lineno, name))
        elif isinstance(node, ast.Subscript) and _is_environ(node.value) and isinstance(
                node.ctx, (ast.Store, ast.Del)):
            found.append((node.lineno, f'{_name(node.value)}[...] set'))
        elif isinstance(node, ast.Call):
            if any(k.arg == 'raw' and isinstance(k.value, ast.Constant) and k.value.value
                   for k in node.keywords):
                found.append((node.lineno, 'raw=True'))
            if _name(node.func) in ('signal.signal', 'signal') and not _disposition(node):
                found.append((node.lineno, 'a signal handler'))
    return found


SIGNAL_OWNER = PACKAGE / 'cli' / 'main.py'
"""The one module that sets a signal handler: rot-tools' main (SIGTERM)."""

PARAMETER_GUARD = PACKAGE / 'ros' / 'node' / 'rotation_node.py'
"""The one module that wraps a callback of rclpy's: the node's parameter services, whose
requests of an unknown value type rclpy raises on instead of refusing."""


def test_rot_tools_leaves_the_process_and_the_wire_to_its_libraries():
    found = [f'{path.relative_to(PACKAGE.parent)}:{line}: {what}'
             for path in _sources()
             for line, what in takeovers(ast.parse(path.read_text(encoding='utf-8')))
             if not (path == SIGNAL_OWNER and what == 'a signal handler')
             and not (path == PARAMETER_GUARD and what == 'service.callback = ...')]
    assert found == []


def test_at_most_one_signal_handler():
    """One call site at most in the whole package, in rot-tools' main."""
    calls = [(path, node.lineno) for path in _sources()
             for node in ast.walk(ast.parse(path.read_text(encoding='utf-8')))
             if isinstance(node, ast.Call) and _name(node.func) == 'signal.signal'
             and not _disposition(node)]
    assert len(calls) <= 1, calls
    assert all(path == SIGNAL_OWNER for path, _ in calls), calls


BAD_SAMPLES = {
    'raw=True': "node.create_subscription(Imu, '~/imu', cb, 10, raw=True)",
    'import struct': 'import struct',
    'from struct import ...': 'from struct import pack',
    'import ctypes': 'import ctypes',
    'os._exit': 'os._exit(0)',
    'gc.freeze': 'gc.freeze()',
    'gc.disable': 'gc.disable()',
    'os.environ[...] set': "os.environ['RMW_FASTRTPS_USE_QOS_FROM_XML'] = '1'",
    'os.environ.setdefault': "os.environ.setdefault('A', 'b')",
    'environ[...] set': "environ['A'] = 'b'",
    'os.putenv': "os.putenv('A', 'b')",
    'a signal handler': 'signal.signal(signal.SIGINT, handler)',
    'sub.callback = ...': 'sub.callback = wrapped',
    '.fielddefs': 'typestore.fielddefs[name]',
    '.readers': 'reader.readers[0]',
    'from rosbags.convert import ...': 'from rosbags.convert import x',
    'import rosbags.rosbag2.storage_sqlite3': 'import rosbags.rosbag2.storage_sqlite3',
}


@pytest.mark.parametrize('what', sorted(BAD_SAMPLES))
def test_each_takeover_is_caught(what):
    """The check can fail: each refused use, written as code, is found (and named)."""
    assert (1, what) in takeovers(ast.parse(BAD_SAMPLES[what]))


@pytest.mark.parametrize('code', [
    'signal.signal(signal.SIGPIPE, signal.SIG_DFL)',
    'signal.signal(signal.SIGINT, signal.SIG_IGN)',
    "env = dict(os.environ, ROS_DOMAIN_ID='7')",
    "value = os.environ.get('HOME')",
    'from rosbags.highlevel import AnyReader',
    'from rosbags.typesys import Stores, get_typestore',
    "sub = node.create_subscription(Imu, '~/imu', cb, 10)",
])
def test_plain_uses_pass(code):
    assert takeovers(ast.parse(code)) == []


def _texts(path):
    """(line, text) of every docstring and comment of a module."""
    source = path.read_text(encoding='utf-8')
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            doc = ast.get_docstring(node, clean=False)
            if doc:
                yield node.body[0].lineno, doc
        elif isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant) and isinstance(
                node.value.value, str):
            yield node.lineno, node.value.value  # an attribute's docstring
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT:
            yield token.start[0], token.string


def test_no_measured_figure_in_docstrings_or_comments():
    found = sorted({f'{path.relative_to(PACKAGE.parent)}:{line}: {match.group(0)}'
                    for path in _sources() for line, text in _texts(path)
                    for match in FIGURE.finditer(text)})
    assert found == []


@pytest.mark.parametrize('text,figure', [
    ('costs ~18 µs a message', True), ('+160 MB for good', True), ('a 9 MB TFMessage', True),
    ('~60 µs for a picture', True), ('1,000 transforms', False), ('at most 1 ms each', False),
])
def test_figure_pattern(text, figure):
    assert bool(FIGURE.search(text)) is figure
