"""doc/bags.md shows real output: its examples are run here and compared, the plot redrawn."""

import os
from pathlib import Path
import subprocess
import sys

from doc_blocks import assert_doc_output, console_steps, doc_block
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")

REPO = Path(__file__).resolve().parents[1]


def _shell(command, cwd=REPO):
    env = dict(os.environ)
    env['PATH'] = os.pathsep.join([str(Path(sys.executable).parent), env.get('PATH', '')])
    return subprocess.run(['bash', '-c', f'set -o pipefail; {command}'], capture_output=True,
                          text=True, cwd=cwd, env=env, timeout=120)


@pytest.mark.parametrize('tag', ['bag-summary', 'bag-csv', 'bag-covariance'])
def test_doc_example_is_real_output(tag):
    shown = ''
    for command, _ in console_steps(doc_block(tag)):
        done = _shell(command)
        assert done.returncode in (0, 141) and done.stderr == '', done.stderr  # 141: head
        shown += f'$ {command}\n{done.stdout}'
    assert_doc_output(tag, shown)  # ROT_TOOLS_UPDATE_DOCS=1 rewrites a block that drifted


def test_doc_conversion_to_rosbag2_is_real_output(tmp_path):
    """Check the doc's rosbags-convert line, run in an empty directory on the recording."""
    import bag_helpers as bh
    shown = ''
    for command, _ in console_steps(doc_block('bag-convert')):
        done = _shell(command.replace('../shared/data/jackal_imu_odometry.bag', str(bh.REAL)),
                      tmp_path)
        assert done.returncode == 0 and done.stderr == '', done.stderr
        shown += f'$ {command}\n{done.stdout}'
    assert_doc_output('bag-convert', shown)


def test_doc_plot_is_what_the_command_draws(tmp_path):
    """Check that the picture in the doc is what the command draws (pixels compared)."""
    matplotlib = pytest.importorskip('matplotlib')
    from matplotlib.image import imread
    doc = (REPO / 'doc' / 'bags.md').read_text()
    command = next(line for line in doc.splitlines()
                   if line.startswith('rot-tools bag') and '--plot doc/bags.png' in line)
    done = _shell(command.replace('doc/bags.png', str(tmp_path / 'bags.png')))
    assert done.returncode == 0, done.stderr
    said = doc_block('bag-plot-note').rstrip('\n')  # the line on stderr, shown in the doc
    assert done.stderr == said.replace('doc/bags.png', str(tmp_path / 'bags.png')) + '\n'
    assert '](bags.png)' in doc
    new, old = imread(tmp_path / 'bags.png'), imread(REPO / 'doc' / 'bags.png')
    assert new.shape == old.shape
    if matplotlib.__version__ != '3.11.2':  # the pinned one drew the doc's picture
        pytest.skip(f'matplotlib {matplotlib.__version__} draws text differently')
    assert np.mean(np.abs(new - old)) < 1e-3


def test_make_run_installs_what_the_readme_bag_example_needs():
    """`make run` then the README's bag example: the bag and plot extras come with run."""
    import shutil
    if shutil.which('make') is None:
        pytest.skip('make is not installed')
    done = subprocess.run(['make', '-n', '-B', 'run'], capture_output=True, text=True,
                          cwd=REPO, timeout=60)
    assert done.returncode == 0, done.stderr
    installs = [line for line in done.stdout.splitlines() if ' install ' in line]
    assert any('-c requirements-test.txt' in line and 'matplotlib' in line.split()
               and 'rosbags' in line.split() for line in installs), installs
    pins = (REPO / 'requirements-test.txt').read_text().splitlines()
    assert {'matplotlib', 'rosbags'} <= {p.split('==')[0] for p in pins if '==' in p}
    readme = (REPO / 'README.md').read_text()
    assert '`make run` installs them' in readme.split('## Recorded bags')[1].split('```')[0]
