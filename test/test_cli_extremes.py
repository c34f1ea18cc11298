"""rot-tools on float64's edges: a report or one error line, never a warning."""

import itertools
from pathlib import Path
import shutil
import subprocess
import sys
import warnings

from conftest import run_cli
import numpy as np
import pytest

EDGES = ['1e308', '-1e308', '1.7976931348623157e308', '-1.7976931348623157e308', '1e300',
         '1e154', '1e200', '5e-324', '-5e-324', '2.2e-308', '1e-300', '0', '-0', '1', '-1',
         '0.5', '3.14159', 'nan', 'inf', '-inf', '1e400', '-1e400', '1e-400']

ARITY = {
    'euler ZYX': 3, 'euler zxz': 3, 'matrix': 9, 'axis-angle': 4, 'rotvec': 3,
    'quaternion': 4, 'frame': 9,
}
SCREW_ROTATIONS = {'--rotation': 9, '--quaternion': 4, '--frame': 9, '--euler XYZ': 3,
                   '--axis-angle': 4, '--rotvec': 3, '': 0}
OPTIONS = [[], ['--deg'], ['--json'], ['--all-sequences'], ['--seq', 'xyx'],
           ['--precision', '3'], ['--precision', '17'], ['--tol', '1e308'], ['--tol', '0'],
           ['--tol', '5e-324'], ['--point', '1e308', '1e308', '-1e308'],
           ['--point', '5e-324', '0', '1e300'], ['--wxyz']]


def _argument_lists(rng, per_command):
    """Seeded random command lines: every command, its numbers drawn from EDGES."""
    lists = []
    for command, n in ARITY.items():
        for _ in range(per_command):
            numbers = list(rng.choice(EDGES, n))
            lists.append(command.split() + numbers + list(OPTIONS[rng.integers(len(OPTIONS))]))
    for (rot, n), _ in itertools.product(SCREW_ROTATIONS.items(), range(per_command)):
        numbers = list(rng.choice(EDGES, n))
        lists.append(['screw'] + (rot.split() + numbers if rot else []) + ['--translation']
                     + list(rng.choice(EDGES, 3)) + list(OPTIONS[rng.integers(len(OPTIONS))]))
    # a homogeneous 4×4: rotation block and translation from EDGES, last row exact or not
    for _ in range(per_command):
        m = rng.choice(EDGES, 16)
        if rng.random() < 0.7:
            m[12:] = ['0', '0', '0', '1']
        lists.append(['matrix'] + list(m))
    # diagonal matrices of one size (the reported case) and exact rotations scaled up
    for size in EDGES:
        lists.append(['matrix', size, '0', '0', '0', size, '0', '0', '0', size])
        lists.append(['screw', '--rotation', '0', '-1', '0', '1', '0', '0', '0', '0', '1',
                      '--translation', size, size, size])
        lists.append(['screw', '--axis-angle', '0', '0', '1', size, '--translation', size,
                      '0', '0'])
    return lists


ARGUMENT_LISTS = _argument_lists(np.random.default_rng(2026), 60)


def _run_in_process(argv, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        # NumPy's defaults (underflow is silent): overflow, division and invalid warn
        with np.errstate(over='warn', divide='warn', invalid='warn', under='ignore'):
            return run_cli(capsys, *argv)


def test_the_reported_matrix_gives_one_line(capsys):
    status, out, err = _run_in_process(
        ['matrix', '1e308', '0', '0', '0', '1e308', '0', '0', '0', '1e308'], capsys)
    assert status == 2 and out == ''
    assert len(err.splitlines()) == 1 and err.startswith('rot-tools: error: matrix: ')


@pytest.mark.parametrize('chunk', range(8))
def test_extreme_numbers_give_a_report_or_one_error_line(chunk, capsys):
    for argv in ARGUMENT_LISTS[chunk::8]:
        status, out, err = _run_in_process(argv, capsys)
        lines = err.splitlines()
        if status == 0:
            assert out and all(line.startswith('rot-tools: hint: ') for line in lines), argv
            assert 'nan' not in out.lower(), (argv, out)
        else:
            assert status == 2 and out == '', argv
            assert len(lines) == 1 and lines[0].startswith('rot-tools: error: '), (argv, err)


def _script():
    found = shutil.which('rot-tools', path=str(Path(sys.executable).parent))
    return [found] if found else [sys.executable, '-m', 'rot_tools.cli.main']


@pytest.mark.parametrize('argv', ARGUMENT_LISTS[::485] + [  # the process adds nothing
    ['matrix', '1e308', '0', '0', '0', '1e308', '0', '0', '0', '1e308']])
def test_the_script_prints_one_line_on_stderr(argv):
    done = subprocess.run(_script() + argv, capture_output=True, text=True, timeout=60)
    lines = done.stderr.splitlines()
    if done.returncode == 0:
        assert all(line.startswith('rot-tools: hint: ') for line in lines), done.stderr
    else:
        assert done.returncode == 2 and len(lines) == 1, done.stderr
