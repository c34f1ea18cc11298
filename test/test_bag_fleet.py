"""
rot-tools bag over many bags: --jobs, --parquet, --engine dask, a failed bag among good ones.

The fleet is the real recording (../shared/data) as a ROS 1 bag and, converted by rosbags, as
rosbag2 sqlite3 and MCAP. Whatever runs the per-bag jobs (one after the other, two
processes, a two-worker Dask cluster), the summary is the same byte for byte and the
Parquet tables are equal; each bag's entry is the summary the bag gives alone.
"""

import contextlib
import csv
import io
import json
from pathlib import Path
import shutil
import signal
import socket
import subprocess
import sys

import bag_helpers as bh
from conftest import console_script, script_env
from doc_blocks import assert_doc_output, console_steps, doc_block
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
pa = pytest.importorskip('pyarrow', reason="the 'bag' extra (pyarrow) is not installed")
pq = pytest.importorskip('pyarrow.parquet')
from rot_tools.cli import bag_parquet, fleet, main as cli  # noqa: E402

MESSAGES = 3061 + 3060
"""Messages of the real recording (Imu and Odometry), every one accepted."""


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    """Return the fleet's directory and its three bags, relative to it: ROS 1, sqlite3, MCAP."""
    root = tmp_path_factory.mktemp('fleet')
    (root / 'fleet' / 'ros1').mkdir(parents=True)
    shutil.copy(bh.REAL, root / 'fleet' / 'ros1' / 'jackal.bag')
    for storage in ('sqlite3', 'mcap'):
        bh.convert_real(root / 'fleet' / storage, storage)
    return root, ['fleet/ros1/jackal.bag', 'fleet/sqlite3', 'fleet/mcap']


def rot_tools_bag(cwd, *args, env=None):
    """Run the rot-tools console script: (status, stdout, stderr)."""
    script = console_script('rot-tools', 'rot_tools.cli.main')
    done = subprocess.run(script + ['bag'] + [str(a) for a in args], cwd=cwd,
                          capture_output=True, text=True, timeout=300,
                          env=env or script_env(script))
    return done.returncode, done.stdout, done.stderr


def tables(directory):
    """{file name: pyarrow Table} of every *.parquet in ``directory``."""
    return {p.name: pq.read_table(p) for p in sorted(Path(directory).glob('*.parquet'))}


def dask_port_held():
    """Hold Dask's default dashboard port 8787 (nothing to hold where something has it)."""
    held = socket.socket()
    try:
        held.bind(('127.0.0.1', 8787))
    except OSError:
        held.close()
        return contextlib.nullcontext()
    held.listen()
    return held


def test_serial_processes_and_dask_give_the_same_output(bags, capsys, monkeypatch):
    root, paths = bags
    runs = {}
    for name, options in (('serial', ['--jobs', '1']), ('processes', ['--jobs', '2']),
                          ('dask', ['--engine', 'dask', '--jobs', '2'])):
        with dask_port_held():  # another cluster's dashboard (or run's): not a word on stderr
            status, out, err = rot_tools_bag(root, *paths, *options, '--parquet',
                                             f'pq-{name}', '--csv', f'{name}.csv')
        assert (status, err) == (0, ''), (name, err)
        runs[name] = (out, (root / f'{name}.csv').read_bytes(), tables(root / f'pq-{name}'))
    serial = runs.pop('serial')
    for name, run in runs.items():
        assert run[0] == serial[0], name  # the summary, byte for byte
        assert run[1] == serial[1], name  # the CSV
        assert list(run[2]) == list(serial[2]), name
        for file_name, table in run[2].items():
            assert table.equals(serial[2][file_name], check_metadata=True), (name, file_name)
    assert list(serial[2]) == ['fleet_mcap.parquet', 'fleet_ros1_jackal.bag.parquet',
                               'fleet_sqlite3.parquet']
    # each bag's entry is the summary the bag gives alone (minus its `bag` key)
    monkeypatch.chdir(root)
    data = json.loads(rot_tools_bag(root, *paths, '--jobs', '1', '--json')[1])
    assert [e['path'] for e in data['bags']] == paths
    assert data['fleet'] == {'bags': 3, 'failed': 0, 'messages': 3 * MESSAGES}
    for entry, path in zip(data['bags'], paths):
        assert cli.main(['bag', path, '--json']) == 0
        alone = json.loads(capsys.readouterr().out)
        assert entry == {'path': path, 'status': 'ok',
                         **{k: v for k, v in alone.items() if k != 'bag'}}
    rows = list(csv.reader(io.StringIO(serial[1].decode())))
    assert rows[0][:3] == ['bag', 'topic', 'stamp'] and len(rows) == 1 + 3 * MESSAGES
    assert [r[0] for r in rows[1::MESSAGES]] == paths


def test_an_existing_dask_cluster_by_its_address(bags):
    """--scheduler ADDRESS: the jobs run on the workers of a cluster started here."""
    distributed = pytest.importorskip('distributed')
    root, paths = bags
    paths = [root / p for p in paths]  # the workers, threads of this process, run elsewhere
    want = rot_tools_bag(root, *paths, '--jobs', '1', '--parquet', root / 'pq-want')
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol='tcp', dashboard_address=':0') as cluster:
        got = rot_tools_bag(root, *paths, '--engine', 'dask', '--scheduler',
                            cluster.scheduler_address, '--parquet', root / 'pq-got')
    assert got == want and want[0] == 0
    assert tables(root / 'pq-got').keys() == tables(root / 'pq-want').keys()
    for name, table in tables(root / 'pq-got').items():
        assert table.equals(tables(root / 'pq-want')[name])


def test_scheduler_needs_the_dask_engine_and_a_scheduler(bags):
    root, paths = bags
    status, out, err = rot_tools_bag(root, *paths, '--scheduler', 'tcp://127.0.0.1:8786')
    assert (status, out) == (2, '') and err.count('\n') == 1 and '--engine dask' in err
    pytest.importorskip('distributed')
    script = console_script('rot-tools', 'rot_tools.cli.main')
    env = dict(script_env(script), DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT='1s')
    status, out, err = rot_tools_bag(root, *paths, '--engine', 'dask', '--scheduler',
                                     'tcp://127.0.0.1:9', env=env)  # the discard port
    assert (status, out) == (2, '') and err.count('\n') == 1
    assert err.startswith('rot-tools: error: --scheduler tcp://127.0.0.1:9: cannot connect')


@pytest.mark.parametrize('jobs', ['1', '2'])
def test_a_corrupt_bag_fails_alone(bags, jobs):
    root, paths = bags
    (root / 'corrupt.bag').write_bytes(bh.REAL.read_bytes()[:50_000])
    given = [paths[0], 'corrupt.bag', paths[1]]
    status, out, err = rot_tools_bag(root, *given, '--jobs', jobs, '--json',
                                     '--parquet', f'pq-corrupt-{jobs}')
    assert status == 1
    assert err.count('\n') == 1 and err.startswith('rot-tools: error: bag: corrupt.bag: ')
    data = json.loads(out)
    assert [(e['path'], e['status']) for e in data['bags']] == [
        (paths[0], 'ok'), ('corrupt.bag', 'failed'), (paths[1], 'ok')]
    failed = data['bags'][1]
    assert set(failed) == {'path', 'status', 'error'}
    assert err == f'rot-tools: error: bag: {failed["error"]}\n'
    assert data['fleet'] == {'bags': 3, 'failed': 1, 'messages': 2 * MESSAGES}
    assert sorted(tables(root / f'pq-corrupt-{jobs}')) == [
        'fleet_ros1_jackal.bag.parquet', 'fleet_sqlite3.parquet']


def test_one_bag_alone_keeps_its_rules(bags, capsys):
    root, paths = bags
    (root / 'alone.bag').write_bytes(b'not a bag at all')
    status, out, err = rot_tools_bag(root, 'alone.bag', '--jobs', '2')
    assert (status, out) == (2, '') and err.count('\n') == 1
    assert err.startswith('rot-tools: error: bag: alone.bag: ')
    assert cli.main(['bag', str(bh.REAL)]) == 0
    alone = capsys.readouterr()
    assert cli.main(['bag', str(bh.REAL), '--jobs', '2', '--engine', 'processes']) == 0
    assert capsys.readouterr() == alone
    assert alone.out.startswith(f'bag: {bh.REAL}\nstorage: rosbag1\ntopics:\n')


def test_options_that_take_one_bag_or_a_count(bags, capsys):
    root, paths = bags
    status, out, err = rot_tools_bag(root, *paths, '--plot', 'rpy.png')
    assert (status, out) == (2, '') and err.count('\n') == 1 and '--plot draws one bag' in err
    assert not (root / 'rpy.png').exists()
    for jobs in ('0', '-1', 'two'):
        assert cli.main(['bag', str(bh.REAL), '--jobs', jobs]) == 2
        captured = capsys.readouterr()
        assert captured.out == '' and 'must be a whole number >= 1' in captured.err


def test_directories_are_searched_for_bags_in_path_order(bags, tmp_path):
    root, paths = bags
    tree = tmp_path / 'tree'
    shutil.copytree(root / 'fleet', tree / 'b')
    shutil.copy(bh.REAL, tree / 'a.bag')
    (tree / 'c').mkdir()
    (tree / 'c' / 'notes.txt').write_text('no bag here')
    found, searched = fleet.find_bags([str(tree), str(bh.REAL)])
    assert searched
    assert found == [str(tree / 'a.bag'), str(tree / 'b' / 'mcap'),
                     str(tree / 'b' / 'ros1' / 'jackal.bag'), str(tree / 'b' / 'sqlite3'),
                     str(bh.REAL)]
    assert fleet.find_bags([str(tree / 'b' / 'mcap')]) == ([str(tree / 'b' / 'mcap')], False)
    status, out, err = rot_tools_bag(tmp_path, 'tree/c')
    assert (status, out) == (2, '') and err.count('\n') == 1 and 'no bag' in err
    status, out, err = rot_tools_bag(tmp_path, 'tree/b', '--jobs', '2')
    assert (status, err) == (0, '')
    assert out.count('- path: ') == 3


def test_parquet_schema_column_by_column(bags):
    root, paths = bags
    status, out, err = rot_tools_bag(root, paths[0], paths[2], '--seq', 'ZYX', '--deg',
                                     '--precision', '17', '--parquet', 'pq-schema',
                                     '--csv', 'schema.csv')
    assert (status, err) == (0, '')
    floats = ['x', 'y', 'z', 'qx', 'qy', 'qz', 'qw', 'roll', 'pitch', 'yaw', 'ZYX_1', 'ZYX_2',
              'ZYX_3', 'rx', 'ry', 'rz', 'angle', 'wx', 'wy', 'wz', 'roll_std', 'pitch_std',
              'yaw_std']
    want = [('bag', pa.string()), ('topic', pa.string()), ('stamp', pa.int64()),
            ('frame_id', pa.string())] + [(name, pa.float64()) for name in floats]
    rows = list(csv.DictReader(io.StringIO((root / 'schema.csv').read_text())))
    for path in (paths[0], paths[2]):
        table = pq.read_table(root / 'pq-schema' / bag_parquet.file_names([path])[0])
        assert [(f.name, f.type) for f in table.schema] == want
        assert table.schema.metadata[b'angles'] == b'deg'
        mine = [r for r in rows if r['bag'] == path]
        assert table.num_rows == len(mine) == MESSAGES
        data = table.to_pydict()
        assert data['bag'] == [path] * MESSAGES
        assert data['topic'] == [r['topic'] for r in mine]
        assert data['frame_id'] == [r['frame_id'] for r in mine]
        assert data['stamp'] == [int(r['stamp'].replace('.', '')) for r in mine]
        for name in floats:
            column = np.array([np.nan if v is None else v for v in data[name]])
            text = np.array([float(r[name]) if r[name] else np.nan for r in mine])
            # the CSV's 17 digits and 17 decimal places, rounded as numbers: within one unit
            # of the last digit (1e-17, or 1e-16 relative)
            np.testing.assert_allclose(column, text, rtol=1.1e-16, atol=1.1e-17, err_msg=name)
        first = [k for k, t in enumerate(data['topic']) if data['topic'].index(t) == k]
        assert [data['wx'][k] for k in first] == [None, None]  # empty in the CSV: null


def test_parquet_file_names_are_unique():
    assert bag_parquet.file_names(['runs/a_b.bag', 'runs/a/b.bag', '/data/x y/ü.bag',
                                   '../up/.hidden', 'RUNS_A_B.bag']) == [
        'runs_a_b.bag.parquet', 'runs_a_b.bag-2.parquet', 'data_x_y__.bag.parquet',
        'up_.hidden.parquet', 'RUNS_A_B.bag-3.parquet']


KILLER = r"""
import os, signal, sys
import pyarrow.parquet as pq
from rot_tools.cli import main

write_table, writes = pq.write_table, [0]


class Dying:
    '''A file that takes the first half of what is written, then the process is killed.'''

    def __init__(self, out):
        self.out, self.closed = out, False

    def write(self, data):
        self.out.write(bytes(data)[:len(data) // 2])
        self.out.flush()
        os.kill(os.getpid(), signal.SIGKILL)


def dying_write(table, where, **options):
    writes[0] += 1
    if writes[0] < int(os.environ['KILL_AT_WRITE']):
        return write_table(table, where, **options)
    return write_table(table, Dying(where), **options)


pq.write_table = dying_write
sys.exit(main.main(sys.argv[1:]))
"""


@pytest.mark.parametrize('kill_at', [1, 2])
def test_a_killed_run_leaves_no_parquet_file_that_looks_whole(bags, kill_at):
    """SIGKILL while the Parquet file of bag number ``kill_at`` is half written."""
    root, paths = bags
    out = root / f'pq-killed-{kill_at}'
    env = dict(script_env([sys.executable]), KILL_AT_WRITE=str(kill_at))
    done = subprocess.run([sys.executable, '-c', KILLER, 'bag', *paths, '--jobs', '1',
                           '--parquet', str(out)], cwd=root, capture_output=True,
                          timeout=300, env=env)
    assert done.returncode == -signal.SIGKILL, done.stderr
    partial = [p.name for p in out.iterdir() if not p.name.endswith('.parquet')]
    assert len(partial) == 1 and partial[0].startswith('.') and partial[0].endswith('.partial')
    assert (out / partial[0]).stat().st_size > 0  # killed in the middle of writing it
    whole = tables(out)  # every file that looks whole is: it reads, every row there
    assert list(whole) == ['fleet_ros1_jackal.bag.parquet'][:kill_at - 1]
    assert all(t.num_rows == MESSAGES for t in whole.values())


def test_duckdb_reads_the_directory_as_one_table(bags):
    """The doc's query over the doc's command's Parquet directory, its output in the doc."""
    duckdb = pytest.importorskip('duckdb')
    root, paths = bags
    (line, _), = console_steps(doc_block('bag-fleet-command'))
    command = line.split()
    assert command[:3] == ['rot-tools', 'bag', 'fleet/']
    status, out, err = rot_tools_bag(root, *command[2:])
    assert (status, err) == (0, '')
    assert_doc_output('bag-fleet-command', f'$ {line}\n{out}')
    shown = subprocess.run([sys.executable, '-c', doc_block('bag-fleet-query')], cwd=root,
                           capture_output=True, text=True, timeout=120)
    assert shown.stderr == ''
    assert_doc_output('bag-fleet-table', shown.stdout)
    counts = duckdb.sql(f"SELECT bag, count(*) FROM '{root}/table/*.parquet' GROUP BY bag "
                        'ORDER BY bag').fetchall()
    assert counts == [(p, MESSAGES) for p in sorted(paths)]


def test_progress_on_a_terminal_only():
    class Terminal(io.StringIO):

        def isatty(self):
            return True

    for stream, shown in ((Terminal(), True), (io.StringIO(), False)):
        progress = fleet.FleetProgress(2, stream)
        progress.add(fleet.Outcome('a.bag', accepted=1000))
        progress.add(fleet.Outcome('b.bag', error='b.bag: broken'))
        progress.done()
        text = stream.getvalue()
        assert ('2/2 bags' in text and 'messages/s' in text and '1/2 bags' in text) == shown
        assert (text == '') == (not shown)
