"""rot-tools' outputs and streams: the one output guard, a full or closed stdout, signals."""

import io
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

import bag_helpers as bh
from conftest import console_script, live_pids, one_error, run_cli, script_env
import numpy as np
import pytest
import rot_tools as rt
from rot_tools.cli import main as cli
from rot_tools.cli import output_file


def write_tum(path, n=40):
    """Write a TUM file of n poses turning, 10 Hz from t = 1 s."""
    t = 1.0 + 0.1 * np.arange(n)
    R = rt.rotvec_to_matrix(np.outer(0.05 * np.arange(n), [0.2, 0.3, 1.0]))
    np.savetxt(path, np.column_stack([t, np.zeros((n, 3)), rt.matrix_to_quaternion(R)]),
               fmt='%.9f')
    return path


@pytest.fixture(scope='module')
def files(tmp_path_factory):
    """Return a directory: ref.tum, and a rosbag2 bag 'victim' of its poses on /pose."""
    where = tmp_path_factory.mktemp('guard')
    ref = write_tum(where / 'ref.tum')
    rows = np.loadtxt(ref)
    b = bh.Builder()
    bh.write_bag(where / 'victim', [
        ('/pose', 'geometry_msgs/msg/PoseStamped', 1_000_000 * (k + 1),
         b.pose_stamped(row[0], row[1:4], row[4:8])) for k, row in enumerate(rows)])
    return where


# The one output guard


def test_compare_refuses_to_write_into_the_bag_it_reads(capsys, files, tmp_path, monkeypatch):
    """Refuse compare's --csv and --plot in a bag typed as its storage file, through links."""
    monkeypatch.chdir(files)
    victim = Path('victim')
    storage = next(victim.glob('*.db3'))
    before = {p: p.read_bytes() for p in victim.iterdir()}
    (tmp_path / 'link').symlink_to(files / 'victim')
    for est, option, output in (
            (storage, '--csv', victim / 'metadata.yaml'),
            (storage, '--csv', tmp_path / 'link' / 'metadata.yaml'),
            (tmp_path / 'link' / storage.name, '--csv', Path('victim/../victim') / storage.name),
            (storage, '--plot', victim / 'errors.png'),
            (victim, '--csv', victim)):
        status, out, err = run_cli(capsys, 'compare', est, 'ref.tum', option, output)
        assert (status, out) == (2, ''), err
        assert err == (f'rot-tools: error: {option} {output} would overwrite the bag being read '
                       f'({est}): refused\n')
    assert {p: p.read_bytes() for p in victim.iterdir()} == before
    # the same bag written to beside it: compare runs, the bag is untouched
    status, _, err = run_cli(capsys, 'compare', storage, 'ref.tum', '--csv', tmp_path / 'e.csv')
    assert (status, err) == (0, ''), err
    assert (tmp_path / 'e.csv').read_text().startswith('stamp,angle')
    assert {p: p.read_bytes() for p in victim.iterdir()} == before


def test_one_guard_for_every_output_and_input(tmp_path, monkeypatch):
    """Outputs that are an input, lie in an input bag, or are another output; what passes."""
    said = []

    def check(outputs, inputs):
        said.clear()

        def error(text):
            said.append(text)
            raise SystemExit(2)
        try:
            output_file.check_outputs(outputs, inputs, error)
        except SystemExit:
            pass
        return said[0] if said else None

    monkeypatch.chdir(tmp_path)
    Path('est.tum').write_text('1 0 0 0 0 0 0 1\n')
    os.link('est.tum', 'hard.tum')
    Path('run.mcap').write_bytes(b'\x89MCAP0\r\n')  # a bare storage file is a bag
    Path('rec').mkdir()
    Path('rec/metadata.yaml').write_text('rosbag2_bagfile_information: {}\n')
    Path('rec/rec_0.db3').write_bytes(b'SQLite')
    Path('table').mkdir()
    assert check([('--csv', 'est.tum')], ['est.tum']) == (
        '--csv est.tum would overwrite an input (est.tum): refused')
    assert 'an input (est.tum)' in check([('--csv', 'hard.tum')], ['est.tum'])  # a hard link
    assert 'an input (./est.tum)' in check([('--csv', tmp_path / 'est.tum')], ['./est.tum'])
    assert 'the bag being read (run.mcap)' in check([('--csv', 'run.mcap')], ['run.mcap'])
    for typed in ('rec', 'rec/rec_0.db3', 'rec/metadata.yaml'):
        for output in ('rec', 'rec/metadata.yaml', 'rec/rec_0.db3', 'rec/new.csv'):
            assert f'the bag being read ({typed})' in check([('--parquet', output)], [typed])
    assert check([('--csv', 'a.png'), ('--plot', './a.png')], []) == (
        '--plot ./a.png and --csv a.png are the same file: refused')
    assert check([('--csv', 'hard.tum'), ('--plot', 'est.tum')], []) == (
        '--plot est.tum and --csv hard.tum are the same file: refused')
    # what passes: stdout, /dev/null, options not given, outputs beside the inputs
    assert check([('--csv', '-'), ('--plot', None), ('--json', '-')], ['est.tum']) is None
    assert check([('--csv', os.devnull), ('--plot', os.devnull)], ['est.tum']) is None
    assert check([('--csv', 'table/rec.csv'), ('--parquet', 'table'), ('--plot', 'r.png')],
                 ['est.tum', 'rec', 'run.mcap', None]) is None


@pytest.fixture
def recordings(tmp_path):
    """Return a directory of recordings no command reads: a .bag, .mcap, .db3, a rosbag2 one."""
    for name in ('old.bag', 'old.mcap', 'old.db3'):
        (tmp_path / name).write_bytes(b'a recording')
    (tmp_path / 'rec').mkdir()
    (tmp_path / 'rec' / 'metadata.yaml').write_text('rosbag2_bagfile_information: {}\n')
    (tmp_path / 'rec' / 'rec_0.db3').write_bytes(b'SQLite')
    return tmp_path


def test_an_output_over_a_recording_is_refused_without_force(files, recordings, capsys,
                                                             monkeypatch):
    """A compare --csv over a bag it does not read: one line naming it and --force, exit 2."""
    monkeypatch.chdir(files)
    targets = [recordings / name for name in ('old.bag', 'old.mcap', 'old.db3')] + [
        recordings / 'rec' / 'metadata.yaml', recordings / 'rec' / 'rec_0.db3']
    for target in targets:
        before = target.read_bytes()
        status, out, err = run_cli(capsys, 'compare', 'ref.tum', 'ref.tum', '--csv', target)
        assert (status, out, err) == (2, '', f'rot-tools: error: --csv {target} is a recording '
                                      '(a bag): refused; --force writes over it\n')
        assert target.read_bytes() == before


def test_force_writes_over_a_recording(files, recordings, capsys, monkeypatch):
    monkeypatch.chdir(files)
    status, _, err = run_cli(capsys, 'compare', 'ref.tum', 'ref.tum', '--csv',
                             recordings / 'old.bag', '--force')
    assert (status, err) == (0, '')
    assert (recordings / 'old.bag').read_text().startswith('stamp,angle')


def test_force_does_not_let_an_output_overwrite_an_input(files, capsys, monkeypatch):
    monkeypatch.chdir(files)
    storage = next(Path('victim').glob('*.db3'))
    one_error(capsys, 'compare', storage, 'ref.tum', '--csv', storage, '--force',
              contains='would overwrite the bag being read')


def test_bag_refuses_a_parquet_directory_that_is_a_recording(files, recordings, capsys,
                                                             monkeypatch):
    """rot-tools bag's --csv and --parquet get the same guard (a rosbag2 directory as DIR)."""
    pytest.importorskip('pyarrow')
    monkeypatch.chdir(files)
    status, out, err = run_cli(capsys, 'bag', 'victim', '--parquet', recordings / 'rec')
    assert (status, out, err) == (2, '', f'rot-tools: error: --parquet {recordings / "rec"} is '
                                  'a recording (a bag): refused; --force writes over it\n')
    left = sorted(p.name for p in (recordings / 'rec').iterdir())
    assert left == ['metadata.yaml', 'rec_0.db3']


# A standard output that cannot be written: in this process, then as the console script

COMMANDS = {
    'compare': ['compare', 'ref.tum', 'ref.tum'],
    'covariance': ['covariance', 'quaternion', 0, 0, 0, 1, '--cov', 1e-4, 0, 0, 0, 1e-4, 0, 0,
                   0, 1e-4, '--from', 'rotvec', '--to', 'rpy'],
    'one-shot': ['euler', 'ZYX', 30, 20, 10, '--deg', '--all-sequences'],
    'bag': ['bag', 'victim'],
    'bag table': ['bag', 'victim', '--csv', '-'],
}
"""A command line of each kind of command that prints to stdout, run in ``files``."""


def run_with(*words, stdout=io.StringIO):
    """Return (status, stdout, stderr) of rot-tools, ``stdout`` its stream (None: closed)."""
    out = stdout() if stdout is io.StringIO else stdout
    err = io.StringIO()
    real = sys.stdout, sys.stderr
    sys.stdout, sys.stderr = out, err
    try:
        status = cli.main([str(w) for w in words])
    finally:
        sys.stdout, sys.stderr = real
    return status, out.getvalue() if stdout is io.StringIO else None, err.getvalue()


def closed_pipe():
    """Return the writing end of a pipe whose reader is gone (a file descriptor)."""
    read, write = os.pipe()
    os.close(read)
    return write


def test_a_full_a_closed_and_a_broken_stdout_in_every_command(files, monkeypatch):
    """> /dev/full: one line, 1; | true: quiet, 141; >&- (no stdout): one line, 1."""
    monkeypatch.chdir(files)
    for name, words in COMMANDS.items():
        for open_stdout, status, said in (
                (lambda: open('/dev/full', 'w'), 1, 'No space left on device'),
                (lambda: open(closed_pipe(), 'w'), 141, None),
                (lambda: None, 1, 'it is closed')):
            stdout = open_stdout()
            try:
                got = run_with(*words, stdout=stdout)
            finally:
                if stdout is not None:
                    stdout.close()  # what it could not write went to /dev/null: no error
            line = f'rot-tools: error: cannot write to stdout: {said}\n' if said else ''
            assert got[::2] == (status, line), name


@pytest.mark.parametrize('words', [['--version'], ['--help'], ['bag', '--help']])
def test_help_and_version_on_a_full_disk(words):
    """Written a line at a time (as to a terminal), so that the failure comes as they print."""
    with open('/dev/full', 'w', buffering=1) as full:
        status, _, err = run_with(*words, stdout=full)
    assert (status, err) == (1, 'rot-tools: error: cannot write to stdout: No space left on '
                             'device\n')


SCRIPT = console_script('rot-tools', 'rot_tools.cli.main')
"""The console script rot-tools of this Python (or python -m where none is installed)."""


def test_the_console_script_on_a_full_disk_and_a_closed_pipe(files):
    """What Python does at exit adds nothing: no traceback, no 'Exception ignored', no 120."""
    env = script_env(SCRIPT)
    with open('/dev/full', 'w') as full:
        done = subprocess.run([*SCRIPT, *COMMANDS['compare']], stdout=full, cwd=files,
                              stderr=subprocess.PIPE, text=True, timeout=120, env=env)
    assert (done.returncode, done.stderr) == (
        1, 'rot-tools: error: cannot write to stdout: No space left on device\n')
    pipe = closed_pipe()
    try:
        done = subprocess.run([*SCRIPT, *map(str, COMMANDS['covariance'])], stdout=pipe,
                              stderr=subprocess.PIPE, text=True, timeout=120, env=env)
    finally:
        os.close(pipe)
    assert (done.returncode, done.stderr) == (141, '')
    with open('/dev/full', 'w') as full:
        done = subprocess.run([*SCRIPT, '--version'], stdout=full, stderr=subprocess.PIPE,
                              text=True, timeout=120, env=env)
    assert (done.returncode, done.stderr) == (
        1, 'rot-tools: error: cannot write to stdout: No space left on device\n')


# Ctrl-C and SIGTERM


@pytest.mark.parametrize('signum', [signal.SIGINT, signal.SIGTERM], ids=['SIGINT', 'SIGTERM'])
def test_a_signal_while_a_file_is_written_leaves_nothing(files, tmp_path, monkeypatch, signum):
    """The signal lands as --csv's file is complete but not yet renamed: it goes, one line."""
    monkeypatch.chdir(files)
    real_replace, partials = os.replace, []

    def signalled_replace(source, target):
        partials.append(Path(source))
        assert partials[0].exists()
        signal.raise_signal(signum)
        real_replace(source, target)
    before = (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))
    monkeypatch.setattr(os, 'replace', signalled_replace)
    status, out, err = run_with(*COMMANDS['compare'], '--csv', tmp_path / 'errors.csv')
    monkeypatch.undo()
    assert (status, out, err) == (
        (130, '', 'rot-tools: interrupted\n') if signum == signal.SIGINT
        else (143, '', 'rot-tools: terminated\n'))
    assert len(partials) == 1 and list(tmp_path.iterdir()) == []
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before


def test_a_callers_profiler_and_signal_handlers_stay(files, tmp_path, monkeypatch):
    """rot-tools' main in a caller's process: its profiler, SIGTERM handler and SIG_IGN kept."""
    monkeypatch.chdir(files)
    calls = []

    def profiler(frame, event, arg):
        calls.append(event)

    def handler(signum, frame):
        pass

    before = (signal.signal(signal.SIGINT, signal.SIG_IGN),
              signal.signal(signal.SIGTERM, handler))
    sys.setprofile(profiler)
    try:
        status, _, err = run_with(*COMMANDS['compare'], '--csv', tmp_path / 'errors.csv')
        after = (sys.getprofile(), signal.getsignal(signal.SIGINT),
                 signal.getsignal(signal.SIGTERM))
    finally:
        sys.setprofile(None)
        signal.signal(signal.SIGINT, before[0])
        signal.signal(signal.SIGTERM, before[1])
    assert (status, err) == (0, '')
    assert after == (profiler, signal.SIG_IGN, handler) and calls


def wait_for(predicate, what, timeout=60.0):
    """Poll ``predicate()`` until it is true; fail after ``timeout`` seconds."""
    end = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > end:
            pytest.fail(f'waited {timeout:g} s for {what}')
        time.sleep(0.01)


def ignores_sigint(pid):
    """Whether process ``pid`` ignores SIGINT (/proc/PID/status, SigIgn: a mask in hex)."""
    try:
        status = Path(f'/proc/{pid}/status').read_text()
    except OSError:
        return False
    mask = next(line.split()[1] for line in status.splitlines() if line.startswith('SigIgn:'))
    return bool(int(mask, 16) & 1 << (signal.SIGINT - 1))


def test_ctrl_c_on_a_fleet_leaves_no_file_and_no_process(tmp_path):
    """Ctrl-C on a fleet's process group: one line, status 130, no file, no worker left."""
    pytest.importorskip('rosbags')
    pytest.importorskip('pyarrow')
    bags = tmp_path / 'bags'
    bags.mkdir()
    for k in range(6):  # long enough to be stopped in the middle
        (bags / f'run{k}.bag').symlink_to(bh.REAL)
    out = tmp_path / 'out'
    out.mkdir()
    with subprocess.Popen([*SCRIPT, 'bag', bags, '--jobs', '2', '--csv', out / 'all.csv',
                           '--parquet', out / 'table'], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, env=script_env(SCRIPT),
                          start_new_session=True) as child:
        try:
            wait_for(lambda: child.poll() is not None or len(
                [pid for pid in live_pids(session=child.pid) if ignores_sigint(pid)]) == 2,
                'the workers')
            os.killpg(child.pid, signal.SIGINT)
            stdout, stderr = child.communicate(timeout=60)
        finally:
            if child.poll() is None:
                os.killpg(child.pid, signal.SIGKILL)
    assert (child.returncode, stdout, stderr) == (130, '', 'rot-tools: interrupted\n')
    wait_for(lambda: not live_pids(session=child.pid), 'the workers to end', timeout=2.0)
    assert [p.name for p in out.rglob('*') if p.suffix in ('.partial', '.csv')] == []


def test_sigterm_on_compare_reading_a_fifo(tmp_path):
    """SIGTERM while compare reads EST from a pipe (as from ``<(...)``): one line, 143."""
    fifo = tmp_path / 'est.tum'
    os.mkfifo(fifo)
    ref = write_tum(tmp_path / 'ref.tum')
    with subprocess.Popen([*SCRIPT, 'compare', fifo, ref, '--csv', tmp_path / 'e.csv'],
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          env=script_env(SCRIPT)) as child:
        writer = None

        def reading():  # compare opened EST: its writer can open it now
            nonlocal writer
            try:
                writer = os.open(fifo, os.O_WRONLY | os.O_NONBLOCK)
            except OSError:  # ENXIO: no reader yet
                return child.poll() is not None
            return True
        try:
            wait_for(reading, 'compare to open EST')
            assert writer is not None, child.communicate()
            os.write(writer, ref.read_bytes()[:100])  # a line and a half, then nothing
            child.send_signal(signal.SIGTERM)
            stdout, stderr = child.communicate(timeout=60)
        finally:
            if writer is not None:
                os.close(writer)
            if child.poll() is None:
                child.kill()
    assert (child.returncode, stdout, stderr) == (143, '', 'rot-tools: terminated\n')
    assert sorted(p.name for p in tmp_path.iterdir()) == ['est.tum', 'ref.tum']
