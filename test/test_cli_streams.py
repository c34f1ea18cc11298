"""
rot-tools' outputs and streams: the one output guard, a full or closed stdout, signals.

Every command checks all its output paths against all its input paths and each other before
writing (rot_tools.cli.output_file.check_outputs). What the process does — its exit status
on a full disk, a closed pipe, Ctrl-C or SIGTERM, what Python prints at exit — is tested on
the console script, one process per behaviour; the rest in this process.
"""

import os
from pathlib import Path

import bag_helpers as bh
import numpy as np
import pytest
import rot_tools as rt
from rot_tools.cli import main as cli
from rot_tools.cli import output_file


def run(capsys, *args):
    """(status, stdout, stderr) of rot-tools with these words, in this process."""
    status = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return status, out, err


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


# ---------------------------------------------------------------------------------------
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
        status, out, err = run(capsys, 'compare', est, 'ref.tum', option, output)
        assert (status, out) == (2, ''), err
        assert err == (f'rot-tools: error: {option} {output} would overwrite the bag being read '
                       f'({est}): refused\n')
    assert {p: p.read_bytes() for p in victim.iterdir()} == before
    # the same bag written to beside it: compare runs, the bag is untouched
    status, _, err = run(capsys, 'compare', storage, 'ref.tum', '--csv', tmp_path / 'e.csv')
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
