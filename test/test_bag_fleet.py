"""rot-tools bag over many bags: --jobs, --parquet, --engine dask, bags that fail."""

import contextlib
import csv
import http.server
import io
import json
import os
from pathlib import Path
import shutil
import socket
import subprocess
import sys
import threading

import bag_helpers as bh
from conftest import console_script, one_error, run_cli, script_env
from doc_blocks import assert_doc_output, console_steps, doc_block
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
pa = pytest.importorskip('pyarrow', reason="the 'bag' extra (pyarrow) is not installed")
pq = pytest.importorskip('pyarrow.parquet')
from rot_tools.cli import bag_parquet, fleet, output_file  # noqa: E402

REAL_MESSAGES = 3061 + 3060
"""Messages of the real recording (Imu and Odometry), every one accepted."""

N = 60
"""Messages of each topic of a small bag (Imu and Odometry): 2·N a bag, every one accepted."""


def small_messages(n=N, seed=0):
    """[(topic, type, record time ns, message)]: n Imu and n Odometry, random orientations."""
    b = bh.Builder()
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    messages = []
    for k in range(n):
        stamp = 100.0 + 0.02 * k
        ns = int(round(stamp * 1e9))
        messages.append(('/imu', 'sensor_msgs/msg/Imu', ns,
                         b.imu(stamp, q[k], gyro=(0.1, 0.0, 0.2), cov0=1e-4)))
        messages.append(('/odom', 'nav_msgs/msg/Odometry', ns + 1,
                         b.odometry(stamp, (0.01 * k, 0.0, 0.0), q[k])))
    return messages


def strings_bag(path):
    """Write a ROS 1 bag of one std_msgs/String topic: nothing rot-tools bag reads."""
    b = bh.Builder()
    return bh.write_ros1_bag(path, [('/chatter', 'std_msgs/msg/String', 10**9 + k,
                                     b.string(f'hello {k}')) for k in range(3)])


@pytest.fixture(scope='module')
def small(tmp_path_factory):
    """Return a directory holding fleet/: the small bag as ROS 1, sqlite3 and MCAP; its paths."""
    root = tmp_path_factory.mktemp('small')
    messages = small_messages()
    (root / 'fleet' / 'ros1').mkdir(parents=True)
    bh.write_ros1_bag(root / 'fleet' / 'ros1' / 'run.bag', messages)
    for storage in ('sqlite3', 'mcap'):
        bh.write_bag(root / 'fleet' / storage, messages, storage)
    return root, ['fleet/ros1/run.bag', 'fleet/sqlite3', 'fleet/mcap']


@pytest.fixture(scope='module')
def bags(tmp_path_factory):
    """Return the docs' fleet: the real recording as a ROS 1 bag, sqlite3 and MCAP."""
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


def manifest(directory):
    """Return the manifest of the run that wrote ``directory``."""
    return json.loads((Path(directory) / '_manifest.json').read_text())


def test_serial_processes_and_dask_give_the_same_output(small, capsys, monkeypatch):
    root, paths = small
    monkeypatch.chdir(root)
    runs = {}
    # a local Dask cluster of one worker process (two: the cluster at an address, below)
    for name, options in (('serial', ['--jobs', '1']), ('processes', ['--jobs', '2']),
                          ('dask', ['--engine', 'dask', '--jobs', '1'])):
        common = [*paths, *options, '--parquet', f'pq-{name}', '--csv', f'{name}.csv']
        if name == 'serial':  # here; the others in processes of their own
            status, out, err = run_cli(capsys, 'bag', *common)
        else:
            with dask_port_held():  # another cluster's dashboard (or run's): not a word
                status, out, err = rot_tools_bag(root, *common)
        assert (status, err) == (0, ''), (name, err)
        runs[name] = (out, (root / f'{name}.csv').read_bytes(), tables(root / f'pq-{name}'),
                      manifest(root / f'pq-{name}'))
    serial = runs.pop('serial')
    for name, run in runs.items():
        assert run[0] == serial[0], name  # the summary, byte for byte
        assert run[1] == serial[1], name  # the CSV
        assert list(run[2]) == list(serial[2]), name
        for file_name, table in run[2].items():
            assert table.equals(serial[2][file_name], check_metadata=True), (name, file_name)
        assert run[3] == serial[3], name
    files = ['fleet_ros1_run.bag.parquet', 'fleet_sqlite3.parquet', 'fleet_mcap.parquet']
    assert sorted(serial[2]) == sorted(files)
    assert serial[3] == {'bags': [{'path': p, 'status': 'ok', 'file': f}
                                  for p, f in zip(paths, files)], 'files': files}
    assert (root / 'pq-serial' / '_SUCCESS').read_bytes() == b''
    # each bag's entry is the summary the bag gives alone (minus its `bag` key)
    monkeypatch.chdir(root)
    status, out, err = run_cli(capsys, 'bag', *paths, '--jobs', '1', '--json')
    data = json.loads(out)
    assert [e['path'] for e in data['bags']] == paths
    assert data['fleet'] == {'bags': 3, 'failed': 0, 'skipped': 0, 'messages': 3 * 2 * N}
    for entry, path in zip(data['bags'], paths):
        alone = json.loads(run_cli(capsys, 'bag', path, '--json')[1])
        assert entry == {'path': path, 'status': 'ok',
                         **{k: v for k, v in alone.items() if k != 'bag'}}
    rows = list(csv.reader(io.StringIO(serial[1].decode())))
    assert rows[0][:3] == ['bag', 'topic', 'stamp'] and len(rows) == 1 + 3 * 2 * N
    assert [r[0] for r in rows[1::2 * N]] == paths


def test_the_csv_on_stdout_is_the_same_whatever_jobs_is(small, capsys, monkeypatch):
    """--csv -: the header once, then the rows, with --jobs 2 as with --jobs 1."""
    root, paths = small
    monkeypatch.chdir(root)
    serial = run_cli(capsys, 'bag', *paths, '--jobs', '1', '--csv', '-')
    assert rot_tools_bag(root, *paths, '--jobs', '2', '--csv', '-') == serial
    assert serial[0] == 0 and serial[1].count('bag,topic,stamp') == 1


def test_an_existing_dask_cluster_by_its_address(small, capsys, monkeypatch):
    """--scheduler ADDRESS: the jobs run on the workers of a cluster started here."""
    distributed = pytest.importorskip('distributed')
    root, paths = small
    monkeypatch.chdir(root)
    want = run_cli(capsys, 'bag', *paths, '--jobs', '1', '--parquet', 'pq-want')
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol='tcp', dashboard_address=':0') as cluster:
        got = run_cli(capsys, 'bag', *paths, '--engine', 'dask', '--scheduler',
                      cluster.scheduler_address, '--parquet', 'pq-got')
    assert got == want and want[0] == 0
    assert tables('pq-got').keys() == tables('pq-want').keys()
    for name, table in tables('pq-got').items():
        assert table.equals(tables('pq-want')[name])
    assert manifest('pq-got') == manifest('pq-want')


class Silent:
    """A TCP port that takes connections and never says a word (as a hung server)."""

    def __enter__(self):
        self.socket = socket.create_server(('127.0.0.1', 0))
        return f'tcp://127.0.0.1:{self.socket.getsockname()[1]}'

    def __exit__(self, *exc):
        self.socket.close()


class Quiet(http.server.BaseHTTPRequestHandler):
    """An HTTP server's handler that logs nothing (on stderr)."""

    def log_message(self, *args):
        pass


class Dashboard:
    """An HTTP server (as a Dask dashboard's port is), in a thread of this process."""

    def __enter__(self):
        self.server = http.server.HTTPServer(('127.0.0.1', 0), Quiet)
        threading.Thread(target=self.server.serve_forever, daemon=True).start()
        return f'tcp://127.0.0.1:{self.server.server_address[1]}'

    def __exit__(self, *exc):
        self.server.shutdown()
        self.server.server_close()


def test_a_scheduler_that_cannot_be_reached_is_one_line(small, capsys, monkeypatch):
    """Each address is one line and status 2, within the connect bound (set to 0.3 s)."""
    root, paths = small
    monkeypatch.chdir(root)
    one_error(capsys, 'bag', *paths, '--scheduler', 'tcp://127.0.0.1:8786',
              contains='--engine dask')
    status, out, err = run_cli(capsys, 'bag', *paths, '--engine', 'dask', '--scheduler', '')
    assert (status, out, err) == (2, '', "rot-tools: error: --scheduler '': no address (a "
                                  "Dask scheduler's, such as tcp://HOST:8786)\n")
    pytest.importorskip('distributed')
    monkeypatch.setattr(fleet, 'CONNECT_TIMEOUT', 0.3)
    said = {}
    with Silent() as silent, Dashboard() as dashboard:
        for name, address in (('silent', silent), ('dashboard', dashboard),
                              ('refused', 'tcp://127.0.0.1:9'), ('tls', 'tls://127.0.0.1:9'),
                              ('ucx', 'ucx://127.0.0.1:9'), ('http', 'http://127.0.0.1:9')):
            status, out, err = run_cli(capsys, 'bag', *paths, '--engine', 'dask', '--scheduler',
                                       address, '--parquet', 'pq-unreached')
            assert (status, out) == (2, '') and err.count('\n') == 1, (name, err)
            prefix = f'rot-tools: error: --scheduler {address}: cannot connect: '
            assert err.startswith(prefix), (name, err)
            said[name] = err[len(prefix):-1]
    for name in ('silent', 'dashboard', 'refused'):
        assert said[name] == ("no Dask scheduler answered within 0.3 s (the dashboard's HTTP "
                              "port is not the scheduler's)"), name
    assert said['tls'].startswith("tls:// needs Dask's TLS settings")
    assert said['ucx'].startswith("ucx:// needs Dask's UCX support")
    assert said['http'].startswith("unknown address scheme 'http'")
    assert not (root / 'pq-unreached' / '_manifest.json').exists()


def test_an_in_process_scheduler_address_is_one_line(small, capsys, monkeypatch):
    root, paths = small
    monkeypatch.chdir(root)
    status, out, err = run_cli(capsys, 'bag', *paths, '--engine', 'dask', '--scheduler',
                               'inproc://x')
    assert (status, out, err) == (
        2, '', 'rot-tools: error: --scheduler inproc://x: an inproc:// address is reachable only '
        "inside the Python process that made it; give the scheduler's tcp://HOST:PORT\n")


def test_a_local_dask_cluster_has_no_more_workers_than_bags(small, capsys, monkeypatch):
    distributed = pytest.importorskip('dask.distributed')
    root, paths = small
    made = []

    class Cluster:

        def __init__(self, **kwargs):
            made.append(kwargs['n_workers'])
            raise RuntimeError('no cluster in this test')

    monkeypatch.setattr(distributed, 'LocalCluster', Cluster)
    monkeypatch.chdir(root)
    for given, jobs in ((paths[:2], 6), (paths, 2)):
        with pytest.raises(RuntimeError, match='no cluster'):
            run_cli(capsys, 'bag', *given, '--engine', 'dask', '--jobs', jobs)
    assert made == [2, 2]


def test_a_bag_that_fails_or_is_skipped_among_good_ones(small, tmp_path, capsys, monkeypatch):
    """A corrupt bag, an error of rot-tools on one bag, a bag of nothing asked: one line each."""
    root, paths = small
    monkeypatch.chdir(tmp_path)
    (tmp_path / 'corrupt.bag').write_bytes(bh.REAL.read_bytes()[:50_000])
    strings_bag(tmp_path / 'strings.bag')
    good = [str(root / p) for p in paths[:2]]
    analyse = fleet.bag_analysis.analyse

    def overflowing(path, *args, **kwargs):
        if str(path) == good[1]:
            raise OverflowError('int too large to convert to float')
        return analyse(path, *args, **kwargs)

    monkeypatch.setattr(fleet.bag_analysis, 'analyse', overflowing)
    given = [good[0], 'corrupt.bag', good[1], 'strings.bag']
    status, out, err = run_cli(capsys, 'bag', *given, '--jobs', '1', '--json', '--parquet', 'pq')
    assert status == 1
    data = json.loads(out)
    assert [(e['path'], e['status']) for e in data['bags']] == [
        (good[0], 'ok'), ('corrupt.bag', 'failed'), (good[1], 'failed'),
        ('strings.bag', 'skipped')]
    corrupt, overflow, skipped = data['bags'][1:]
    assert set(corrupt) == set(overflow) == {'path', 'status', 'error'}
    assert set(skipped) == {'path', 'status', 'reason'}
    assert corrupt['error'].startswith('corrupt.bag: ')
    assert overflow['error'] == (f'{good[1]}: unexpected OverflowError: int too large to '
                                 'convert to float (a fault of rot-tools on this bag: please '
                                 'report it)')
    assert skipped['reason'].startswith('strings.bag: no topic of a type read')
    assert err == (f'rot-tools: error: bag: {corrupt["error"]}\n'
                   f'rot-tools: error: bag: {overflow["error"]}\n'
                   f'rot-tools: bag: skipped: {skipped["reason"]}\n')
    assert data['fleet'] == {'bags': 4, 'failed': 2, 'skipped': 1, 'messages': 2 * N}
    assert list(tables('pq')) == [bag_parquet.file_names(given)[0]]
    # skipped is no failure: without the failed bags, the status is 0
    monkeypatch.undo()
    monkeypatch.chdir(tmp_path)
    status, out, err = run_cli(capsys, 'bag', good[0], 'strings.bag', '--jobs', '1', '--json')
    assert (status, err) == (0, f'rot-tools: bag: skipped: {skipped["reason"]}\n')
    assert json.loads(out)['fleet'] == {'bags': 2, 'failed': 0, 'skipped': 1,
                                        'messages': 2 * N}


CRASHING = r"""
import os, signal, sys
from pathlib import Path
from rot_tools.cli import bag_analysis, main

analyse = bag_analysis.analyse


def crashing(path, *args, **kwargs):
    '''Die as the OOM killer kills: reading b.bag always, a.bag the first time.'''
    name = Path(path).name
    if name == 'b.bag' or (name == 'a.bag' and not os.path.exists('a.died')):
        with open(name.replace('.bag', '.died'), 'a') as deaths:
            deaths.write('x')
        os.kill(os.getpid(), signal.SIGKILL)
    return analyse(path, *args, **kwargs)


bag_analysis.analyse = crashing
sys.exit(main.main(sys.argv[1:]))
"""


def test_a_worker_killed_is_tried_again_once_and_a_rerun_owns_its_files(small, tmp_path):
    """--jobs 2: a.bag's worker killed once is read again, b.bag's killed every time fails."""
    duckdb = pytest.importorskip('duckdb')
    root, paths = small
    for name in ('a', 'b', 'c'):
        shutil.copy(root / paths[0], tmp_path / f'{name}.bag')
    (tmp_path / 'corrupt.bag').write_bytes(bh.REAL.read_bytes()[:50_000])
    strings_bag(tmp_path / 'strings.bag')
    table = tmp_path / 'table'
    table.mkdir()
    earlier = pa.table({'bag': ['an earlier run']})
    for stale in ('b.bag.parquet', 'corrupt.bag.parquet', 'other.bag.parquet'):
        pq.write_table(earlier, table / stale)
    (table / '_SUCCESS').write_text('')
    (table / '_manifest.json').write_text('{"files": ["b.bag.parquet"]}')
    given = ['a.bag', 'b.bag', 'c.bag', 'corrupt.bag', 'strings.bag']
    done = subprocess.run([sys.executable, '-c', CRASHING, 'bag', *given, '--jobs', '2',
                           '--json', '--parquet', 'table', '--csv', 'all.csv'],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300,
                          env=script_env([sys.executable]))
    assert done.returncode == 1, done.stderr
    # a.bag died in the pool, then was read alone; b.bag died alone (and in the pool, if
    # its worker had begun it before a.bag's died)
    assert (tmp_path / 'a.died').read_text() == 'x'
    assert (tmp_path / 'b.died').read_text() in ('x', 'xx')
    data = json.loads(done.stdout)
    assert [e['status'] for e in data['bags']] == ['ok', 'failed', 'ok', 'failed', 'skipped']
    assert data['bags'][1]['error'] == (
        'b.bag: the process reading this bag, alone, died before it was done; out of memory?')
    assert data['fleet'] == {'bags': 5, 'failed': 2, 'skipped': 1, 'messages': 2 * 2 * N}
    lines = done.stderr.splitlines()
    assert [line.split(':')[:3] for line in lines] == [
        ['rot-tools', ' error', ' bag'], ['rot-tools', ' error', ' bag'],
        ['rot-tools', ' bag', ' skipped']]
    assert sorted(p.name for p in table.iterdir()) == [
        '_manifest.json', 'a.bag.parquet', 'c.bag.parquet', 'other.bag.parquet']
    assert manifest(table) == {'bags': [
        {'path': 'a.bag', 'status': 'ok', 'file': 'a.bag.parquet'},
        {'path': 'b.bag', 'status': 'failed', 'file': None},
        {'path': 'c.bag', 'status': 'ok', 'file': 'c.bag.parquet'},
        {'path': 'corrupt.bag', 'status': 'failed', 'file': None},
        {'path': 'strings.bag', 'status': 'skipped', 'file': None}],
        'files': ['a.bag.parquet', 'c.bag.parquet']}
    # the whole of a.bag, read again, in the table and the CSV
    files = [str(table / name) for name in manifest(table)['files']]
    counts = duckdb.sql(f'SELECT bag, count(*) FROM read_parquet({files}) GROUP BY bag '
                        'ORDER BY bag').fetchall()
    assert counts == [('a.bag', 2 * N), ('c.bag', 2 * N)]
    rows = list(csv.reader(io.StringIO((tmp_path / 'all.csv').read_text())))
    assert [r[0] for r in rows[1:]] == ['a.bag'] * 2 * N + ['c.bag'] * 2 * N


def test_one_bag_alone_keeps_its_rules(small, capsys, monkeypatch):
    root, paths = small
    monkeypatch.chdir(root)
    Path('alone.bag').write_bytes(b'not a bag at all')
    err = one_error(capsys, 'bag', 'alone.bag', '--jobs', '2')
    assert err.startswith('rot-tools: error: bag: alone.bag: ')
    alone = run_cli(capsys, 'bag', paths[0])
    assert run_cli(capsys, 'bag', paths[0], '--jobs', '2', '--engine', 'processes') == alone
    assert alone[1].startswith(f'bag: {paths[0]}\nstorage: rosbag1\ntopics:\n')


def test_options_that_take_one_bag_or_a_count(small, capsys, monkeypatch):
    root, paths = small
    monkeypatch.chdir(root)
    one_error(capsys, 'bag', *paths, '--plot', 'rpy.png', contains='--plot draws one bag')
    assert not (root / 'rpy.png').exists()
    for jobs in ('0', '-1', 'two'):
        one_error(capsys, 'bag', paths[0], '--jobs', jobs, contains='must be a whole number >= 1')


def test_directories_are_searched_for_bags_in_path_order(small, tmp_path, capsys,
                                                         monkeypatch):
    """rosbag2 directories, .bag files, and .db3 / .mcap files alone (no metadata.yaml)."""
    root, paths = small
    tree = tmp_path / 'tree'
    shutil.copytree(root / 'fleet', tree / 'b')
    shutil.copy(root / paths[0], tree / 'a.bag')
    (tree / 'c').mkdir()
    (tree / 'c' / 'notes.txt').write_text('no bag here')
    (tree / 'd').mkdir()
    for storage in ('sqlite3', 'mcap'):  # the storage file alone, out of its directory
        (stored,) = (root / 'fleet' / storage).glob('*.db3' if storage == 'sqlite3'
                                                    else '*.mcap')
        shutil.copy(stored, tree / 'd' / stored.name)
    found, searched = fleet.find_bags([str(tree), str(tree / 'a.bag')])
    assert searched
    bare = sorted(str(p) for p in (tree / 'd').iterdir())
    assert found == [str(tree / 'a.bag'), str(tree / 'b' / 'mcap'),
                     str(tree / 'b' / 'ros1' / 'run.bag'), str(tree / 'b' / 'sqlite3'),
                     *bare, str(tree / 'a.bag')]
    assert fleet.find_bags([str(tree / 'b' / 'mcap')]) == ([str(tree / 'b' / 'mcap')], False)
    monkeypatch.chdir(tmp_path)
    one_error(capsys, 'bag', 'tree/c', contains='no bag')
    status, out, err = run_cli(capsys, 'bag', 'tree', '--jobs', '1', '--json')
    assert (status, err) == (0, '')
    data = json.loads(out)
    assert [e['status'] for e in data['bags']] == ['ok'] * 6
    assert data['fleet']['messages'] == 6 * 2 * N


def test_parquet_schema_column_by_column(small, capsys, monkeypatch):
    root, paths = small
    monkeypatch.chdir(root)
    status, out, err = run_cli(capsys, 'bag', paths[0], paths[2], '--seq', 'ZYX', '--deg',
                               '--precision', '17', '--parquet', 'pq-schema', '--csv',
                               'schema.csv', '--jobs', '1')
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
        assert table.num_rows == len(mine) == 2 * N
        data = table.to_pydict()
        assert data['bag'] == [path] * 2 * N
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


def test_parquet_file_names_are_unique_and_short():
    assert bag_parquet.file_names(['runs/a_b.bag', 'runs/a/b.bag', '/data/x y/ü.bag',
                                   '../up/.hidden', 'RUNS_A_B.bag']) == [
        'runs_a_b.bag.parquet', 'runs_a_b.bag-2.parquet', 'data_x_y__.bag.parquet',
        'up_.hidden.parquet', 'RUNS_A_B.bag-3.parquet']
    deep = 'd' * 150 + '/' + 'e' * 150
    names = bag_parquet.file_names([f'{deep}/one.bag', f'{deep}/two.bag', f'{deep}/one.bag'])
    assert len(set(names)) == 3
    assert all(len(n.encode()) <= bag_parquet.STEM_BYTES + len('-2.parquet') for n in names)
    assert [n[:bag_parquet.STEM_BYTES - 17] for n in names] == [f'{"d" * 150}_{"e" * 12}'] * 3
    assert names[2] == names[0].replace('.parquet', '-2.parquet')


def test_bags_of_long_paths_get_their_parquet_files(small, tmp_path, capsys, monkeypatch):
    """Paths whose joined names pass 255 bytes (each part within it): shortened, unique."""
    root, paths = small
    deep = tmp_path / ('d' * 200) / ('e' * 200)
    deep.mkdir(parents=True)
    for name in ('one.bag', 'two.bag'):
        shutil.copy(root / paths[0], deep / name)
    monkeypatch.chdir(tmp_path)
    status, out, err = run_cli(capsys, 'bag', deep.relative_to(tmp_path), '--jobs', '1',
                               '--parquet', 'pq')
    assert (status, err) == (0, '')
    written = tables('pq')
    assert len(written) == 2 and all(len(n.encode()) < 255 for n in written)
    assert sorted(t['bag'][0].as_py() for t in written.values()) == [
        str(deep.relative_to(tmp_path) / name) for name in ('one.bag', 'two.bag')]
    assert sorted(manifest('pq')['files']) == sorted(written)


def test_a_rerun_in_which_a_bag_fails_removes_its_earlier_file(small, tmp_path, capsys,
                                                               monkeypatch):
    root, paths = small
    monkeypatch.chdir(tmp_path)
    for name in ('a.bag', 'b.bag'):
        shutil.copy(root / paths[0], name)
    assert run_cli(capsys, 'bag', 'a.bag', 'b.bag', '--jobs', '1', '--parquet', 'pq')[0] == 0
    assert sorted(p.name for p in Path('pq').iterdir()) == [
        '_SUCCESS', '_manifest.json', 'a.bag.parquet', 'b.bag.parquet']
    Path('b.bag').write_bytes(b'\0' * 100)  # damaged since
    status, _, err = run_cli(capsys, 'bag', 'a.bag', 'b.bag', '--jobs', '1', '--parquet', 'pq')
    assert status == 1 and err.startswith('rot-tools: error: bag: b.bag: ')
    assert sorted(p.name for p in Path('pq').iterdir()) == ['_manifest.json', 'a.bag.parquet']
    assert manifest('pq')['files'] == ['a.bag.parquet']


def test_a_run_of_one_bag_keeps_its_parquet_directory_as_a_fleet_does(
        small, capsys, monkeypatch):
    """One bag alone, and the same bag as a fleet (its directory searched): same files."""
    root, paths = small
    monkeypatch.chdir(root)
    assert run_cli(capsys, 'bag', paths[0], '--parquet', 'pq-alone')[0] == 0
    assert run_cli(capsys, 'bag', str(Path(paths[0]).parent), '--parquet', 'pq-fleet')[0] == 0
    name = 'fleet_ros1_run.bag.parquet'
    for directory in ('pq-alone', 'pq-fleet'):
        assert sorted(p.name for p in Path(directory).iterdir()) == [
            '_SUCCESS', '_manifest.json', name]
        assert manifest(directory) == {
            'bags': [{'path': paths[0], 'status': 'ok', 'file': name}], 'files': [name]}
    assert tables('pq-alone')[name].equals(tables('pq-fleet')[name], check_metadata=True)


def test_a_failed_run_of_one_bag_leaves_no_directory_that_reads_as_ok(
        small, tmp_path, capsys, monkeypatch):
    root, paths = small
    monkeypatch.chdir(tmp_path)
    shutil.copy(root / paths[0], 'x.bag')
    assert run_cli(capsys, 'bag', 'x.bag', '--parquet', 'pq')[0] == 0
    Path('x.bag').write_bytes(b'\0' * 100)  # damaged since
    err = one_error(capsys, 'bag', 'x.bag', '--parquet', 'pq')
    assert err.startswith('rot-tools: error: bag: x.bag: ')
    assert sorted(p.name for p in Path('pq').iterdir()) == ['_manifest.json']
    assert manifest('pq') == {'bags': [{'path': 'x.bag', 'status': 'failed', 'file': None}],
                              'files': []}


def test_a_file_has_a_temporary_name_until_complete(tmp_path):
    target = tmp_path / 'out.csv'
    target.write_text('before\n')
    with output_file.complete_or_nothing(target) as out:
        out.write('whole\n')
        out.flush()
        (partial,) = [p for p in tmp_path.iterdir() if p != target]
        assert partial.name.startswith('.out.csv.') and partial.name.endswith('.partial')
        assert target.read_text() == 'before\n'
    assert list(tmp_path.iterdir()) == [target] and target.read_text() == 'whole\n'
    assert oct(target.stat().st_mode & 0o777) == oct(0o666 & ~current_umask())


@pytest.mark.parametrize('stop', [ZeroDivisionError, KeyboardInterrupt])
def test_an_error_or_ctrl_c_removes_the_temporary_file(tmp_path, stop):
    target = tmp_path / 'out.csv'
    target.write_text('before\n')
    with pytest.raises(stop):
        with output_file.complete_or_nothing(target) as out:
            out.write('half')
            raise stop()
    assert list(tmp_path.iterdir()) == [target] and target.read_text() == 'before\n'


def current_umask():
    umask = os.umask(0)
    os.umask(umask)
    return umask


KILLER = r"""
import os, signal, sys
from rot_tools.cli import main

replace, renames = os.replace, [0]


def dying_replace(source, target):
    # the second file is complete under its temporary name: the process is killed
    renames[0] += 1
    if renames[0] == 2:
        os.kill(os.getpid(), signal.SIGKILL)
    return replace(source, target)


os.replace = dying_replace
sys.exit(main.main(sys.argv[1:]))
"""


def test_a_run_killed_while_writing_a_parquet_file_leaves_nothing_that_looks_whole(small):
    """SIGKILL as the second bag's file is complete, not yet renamed: a hidden name only."""
    root, paths = small
    out = root / 'pq-killed'
    done = subprocess.run([sys.executable, '-c', KILLER, 'bag', *paths, '--jobs', '1',
                           '--parquet', str(out)], cwd=root, capture_output=True,
                          timeout=300, env=script_env([sys.executable]))
    assert done.returncode == -9, done.stderr
    partial, whole = sorted(p.name for p in out.iterdir())
    assert whole == 'fleet_ros1_run.bag.parquet'
    assert partial.startswith('.fleet_sqlite3.parquet.') and partial.endswith('.partial')
    assert list(tables(out)) == [whole]  # DIR/*.parquet: the whole file only
    assert tables(out)[whole].num_rows == 2 * N


def test_duckdb_reads_the_files_of_the_manifest_as_one_table(bags, capsys, monkeypatch):
    """The doc's query over the doc's command's Parquet directory, its output in the doc."""
    duckdb = pytest.importorskip('duckdb')
    root, paths = bags
    (line, _), = console_steps(doc_block('bag-fleet-command'))
    command = line.split()
    assert command[:3] == ['rot-tools', 'bag', 'fleet/']
    monkeypatch.chdir(root)
    # here, one bag after the other (the same output whatever --jobs is): no fork of pytest
    status, out, err = run_cli(capsys, 'bag', *command[2:], '--jobs', '1')
    assert (status, err) == (0, '')
    assert_doc_output('bag-fleet-command', f'$ {line}\n{out}')
    pq.write_table(pq.read_table(root / 'table' / 'fleet_mcap.parquet'),
                   root / 'table' / 'stale.parquet')  # not the run's: the query leaves it out
    shown = subprocess.run([sys.executable, '-c', doc_block('bag-fleet-query')], cwd=root,
                           capture_output=True, text=True, timeout=120)
    assert shown.stderr == ''
    assert_doc_output('bag-fleet-table', shown.stdout)
    counts = duckdb.sql(f"SELECT bag, count(*) FROM '{root}/table/*.parquet' GROUP BY bag "
                        'ORDER BY bag').fetchall()
    assert counts == [(p, REAL_MESSAGES * (2 if p == 'fleet/mcap' else 1))
                      for p in sorted(paths)]


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
