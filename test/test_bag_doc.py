"""doc/bags.md shows real output: its examples are run here and compared, the plot redrawn."""

import os
from pathlib import Path
import subprocess
import sys

from doc_blocks import console_steps, doc_block, matches
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")

REPO = Path(__file__).resolve().parents[1]


def _shell(command):
    env = dict(os.environ)
    env['PATH'] = os.pathsep.join([str(Path(sys.executable).parent), env.get('PATH', '')])
    return subprocess.run(['bash', '-c', f'set -o pipefail; {command}'], capture_output=True,
                          text=True, cwd=REPO, env=env, timeout=120)


@pytest.mark.parametrize('tag', ['bag-summary', 'bag-csv'])
def test_doc_example_is_real_output(tag):
    for command, want in console_steps(doc_block(tag)):
        done = _shell(command)
        assert done.returncode in (0, 141) and done.stderr == '', done.stderr  # 141: head
        assert matches(want, done.stdout), (
            f'doc/bags.md block {tag!r} no longer matches:\n--- doc\n{want}--- real\n'
            f'{done.stdout}')


def test_doc_plot_is_what_the_command_draws(tmp_path):
    """Check that the picture in the doc is what the command draws (pixels compared)."""
    matplotlib = pytest.importorskip('matplotlib')
    from matplotlib.image import imread
    doc = (REPO / 'doc' / 'bags.md').read_text()
    command = next(line for line in doc.splitlines()
                   if line.startswith('rot-tools bag') and '--plot doc/bags.png' in line)
    done = _shell(command.replace('doc/bags.png', str(tmp_path / 'bags.png')))
    assert done.returncode == 0, done.stderr
    said = next(line for line in doc.splitlines()  # the line on stderr, shown in the doc
                if line.startswith('rot-tools bag: --plot doc/bags.png'))
    assert done.stderr == said.replace('doc/bags.png', str(tmp_path / 'bags.png')) + '\n'
    assert '](bags.png)' in doc
    new, old = imread(tmp_path / 'bags.png'), imread(REPO / 'doc' / 'bags.png')
    assert new.shape == old.shape
    if matplotlib.__version__ != '3.11.2':  # the pinned one drew the doc's picture
        pytest.skip(f'matplotlib {matplotlib.__version__} draws text differently')
    assert np.mean(np.abs(new - old)) < 1e-3
