"""A fleet ended by a signal: no worker left, no file half written, the caller sees EOF."""

from pathlib import Path
import shutil
import signal
import subprocess
import sys
import time

import bag_helpers as bh
from conftest import console_script, live_pids, script_env
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
pq = pytest.importorskip('pyarrow.parquet', reason="the 'bag' extra (pyarrow) is not installed")

BAGS = 6
"""Copies of the real recording: enough work for the fleet to be stopped in the middle."""

BOUND = 10.0
"""Seconds the command and its workers have to end after the signal (a generous bound)."""


def alive(pid):
    """Whether process ``pid`` runs (a zombie, dead but not yet reaped, does not)."""
    try:
        return Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0] != 'Z'
    except OSError:
        return False


def signalled(tmp_path, command, signum, ready):
    """Run ``command`` over bags/, ``signum`` once ``ready(pid)``; return it and children left."""
    bags = tmp_path / 'bags'
    bags.mkdir()
    for k in range(BAGS):
        shutil.copy(bh.REAL, bags / f'run{k}.bag')
    with subprocess.Popen(command, cwd=tmp_path, stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, env=script_env(command)) as child:
        try:
            deadline = time.monotonic() + 120
            while not ready(child.pid):
                assert child.poll() is None and time.monotonic() < deadline, \
                    'the fleet ended before it was at work'
                time.sleep(0.01)
            workers = live_pids(parent=child.pid)
            child.send_signal(signum)
            end = time.monotonic() + BOUND
            stdout, stderr = child.communicate(timeout=BOUND)  # EOF: no worker holds them
            while [pid for pid in workers if alive(pid)] and time.monotonic() < end:
                time.sleep(0.01)  # one closed them as it ended, and is ending
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
    return child.returncode, stdout, stderr, [pid for pid in workers if alive(pid)]


def two_workers(pid):
    return len(live_pids(parent=pid)) >= 2


@pytest.mark.parametrize('signum', [signal.SIGTERM, signal.SIGKILL])
def test_a_fleet_ended_by_a_signal_leaves_nothing(tmp_path, signum):
    script = console_script('rot-tools', 'rot_tools.cli.main')
    status, stdout, stderr, left_alive = signalled(
        tmp_path, [*script, 'bag', 'bags', '--jobs', '2', '--csv', 'all.csv', '--parquet',
                   'table'], signum, two_workers)
    assert (status, stdout, stderr) == (
        (-signal.SIGKILL, '', '') if signum == signal.SIGKILL
        else (128 + signal.SIGTERM, '', 'rot-tools: terminated\n'))
    assert left_alive == []
    left = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob('*')
                  if p.parent.name != 'bags' and p.name != 'bags')
    if signum == signal.SIGKILL:  # nothing can remove a temporary file then
        left = [name for name in left if not Path(name).name.endswith('.partial')]
    done = [name for name in left if name.endswith('.parquet')]
    assert left == ['table'] + done  # no CSV, no temporary file, no manifest
    for name in done:  # a bag done before the signal: whole
        assert pq.read_table(tmp_path / name).num_rows == 3061 + 3060


STARTED = r"""
import sys
from pathlib import Path
from rot_tools.cli import bag_analysis, main

analyse = bag_analysis.analyse


def started(path, *args, **kwargs):
    # a bag's job has begun here (a cluster of threads): the test may send its signal
    Path('started').touch()
    return analyse(path, *args, **kwargs)


bag_analysis.analyse = started
sys.exit(main.main(sys.argv[1:]))
"""


def test_a_local_dask_fleet_killed_leaves_no_process_and_says_nothing(tmp_path):
    """SIGKILL while its bags are read: nothing left, nothing said (no leak warning)."""
    pytest.importorskip('distributed')
    status, stdout, stderr, left_alive = signalled(
        tmp_path, [sys.executable, '-c', STARTED, 'bag', 'bags', '--engine', 'dask', '--jobs',
                   '2'], signal.SIGKILL,
        lambda pid: (tmp_path / 'started').exists() or two_workers(pid))
    assert (status, stdout, stderr, left_alive) == (-signal.SIGKILL, '', '', [])
