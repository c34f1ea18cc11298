"""rot-tools bag against what a careless or hostile user gives it, each made here."""

import csv
import errno
import io
import json
import os
from pathlib import Path
import shutil
import subprocess
import xml.etree.ElementTree as ElementTree

import bag_helpers as bh
from conftest import console_script, one_error, run_cli, script_env
from math_helpers import unit
import numpy as np
import pytest

pytest.importorskip('rosbags', reason="the 'bag' extra (rosbags) is not installed")
from rot_tools.cli import bag_analysis, bag_output  # noqa: E402
from rot_tools.core.euler import RPY_SEQUENCE  # noqa: E402
from rot_tools.io import bag_read  # noqa: E402
import yaml  # noqa: E402,I100


def pose_bag(path, stamps, frames=('map',), topic='/pose', storage='sqlite3'):
    """Return a rosbag2 bag of PoseStamped at ``stamps`` (seconds), frames in turn."""
    b = bh.Builder()
    rng = np.random.default_rng(5)
    messages = [(topic, 'geometry_msgs/msg/PoseStamped', 1_000_000 * (k + 1),
                 b.pose_stamped(s, -rng.random(3), unit(rng.normal(size=4)),
                                frames[k % len(frames)]))
                for k, s in enumerate(stamps)]
    return bh.write_bag(path, messages, storage)


@pytest.fixture(scope='module')
def small_bag(tmp_path_factory):
    return pose_bag(tmp_path_factory.mktemp('small') / 'bag', [1.0 + 0.1 * k for k in range(50)])


# Nothing lost


def test_an_output_that_is_the_bag_is_refused(capsys, tmp_path, small_bag):
    ros1 = tmp_path / 'run.bag'
    shutil.copy(bh.REAL, ros1)
    before = ros1.read_bytes()
    (tmp_path / 'link.bag').symlink_to(ros1)
    (tmp_path / 'link.png').symlink_to(ros1)
    for args in (('--csv', ros1), ('--plot', tmp_path / 'link.png'),
                 ('--csv', tmp_path / '.' / 'run.bag')):
        one_error(capsys, 'bag', ros1, *args, contains='would overwrite the bag being read')
    one_error(capsys, 'bag', tmp_path / 'link.bag', '--csv', ros1, contains='overwrite')
    assert ros1.read_bytes() == before
    folder = tmp_path / 'copy'
    shutil.copytree(small_bag, folder)
    db3 = next(folder.glob('*.db3'))
    files = {p: p.read_bytes() for p in folder.iterdir()}
    for given in (folder, db3):
        for option, output in (('--csv', db3), ('--csv', folder / 'metadata.yaml'),
                               ('--plot', folder / 'new.png')):
            one_error(capsys, 'bag', given, option, output, contains=f'{option} {output} would')
    assert {p: p.read_bytes() for p in folder.iterdir()} == files
    bare = tmp_path / 'alone.db3'
    shutil.copy(db3, bare)
    one_error(capsys, 'bag', bare, '--csv', bare, contains='would overwrite the bag being read')
    assert bare.read_bytes() == files[db3]
    png = tmp_path / 'both.svg'
    one_error(capsys, 'bag', bare, '--csv', png, '--plot', png, contains='the same file')
    assert not png.exists()


def test_a_failed_csv_write_leaves_the_old_file(capsys, tmp_path, monkeypatch):
    out = tmp_path / 'imu.csv'
    out.write_text('the old table\n')
    monkeypatch.setattr(bag_output, 'ROWS_PER_CHUNK', 100)
    real_stamp_text = bag_output.stamp_text
    calls = []

    def stamp_then_full(ns):
        calls.append(1)
        if len(calls) == 500:  # the disk fills up in the middle of the table
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real_stamp_text(ns)
    monkeypatch.setattr(bag_output, 'stamp_text', stamp_then_full)
    one_error(capsys, 'bag', bh.REAL, '--topic', '/imu/data', '--csv', out,
              contains=f'--csv: cannot write {out}: No space left on device')
    assert out.read_text() == 'the old table\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['imu.csv']  # nothing left over
    monkeypatch.setattr(bag_output, 'stamp_text', real_stamp_text)
    assert run_cli(capsys, 'bag', bh.REAL, '--csv', out)[0] == 0  # the real one, complete
    assert len(out.read_text().splitlines()) == 1 + 3061 + 3060
    assert sorted(p.name for p in tmp_path.iterdir()) == ['imu.csv']


def test_a_failed_plot_write_leaves_nothing(capsys, tmp_path, savefig_fills_the_disk,
                                            small_bag):
    png = tmp_path / 'rpy.png'
    one_error(capsys, 'bag', small_bag, '--plot', png,
              contains=f'--plot: cannot write {png}: No space left on device')
    assert list(tmp_path.iterdir()) == []


def test_an_unexpected_error_on_the_bag_is_one_line(capsys, tmp_path, small_bag, monkeypatch):
    """Any exception of rot-tools on one bag is that bag's one line, never a traceback."""
    out = tmp_path / 'rows.csv'
    out.write_text('the old table\n')

    def overflows(values, precision):
        raise OverflowError('int too large to convert to float')
    monkeypatch.setattr(bag_output, 'rounded', overflows)
    one_error(capsys, 'bag', small_bag, '--csv', out,
              contains=f'bag: {small_bag}: unexpected OverflowError: int too large to convert '
              'to float (a fault of rot-tools on this bag: please report it)')
    assert out.read_text() == 'the old table\n' and len(list(tmp_path.iterdir())) == 1
    assert bag_analysis.failure('b.bag', ValueError()) == (
        'b.bag: unexpected ValueError (a fault of rot-tools on this bag: please report it)')
    assert bag_analysis.failure('b.bag', bag_read.BagError('b.bag: the file is empty')) == (
        'b.bag: the file is empty')


def interrupted(capsys, *args):
    """Return the exit status of rot-tools ARGS stopped by Ctrl-C (130)."""
    try:
        status = run_cli(capsys, *args)[0]
    except KeyboardInterrupt:  # main lets it through, or says it in one line
        status = 130
    capsys.readouterr()
    return status


def test_ctrl_c_while_writing_leaves_every_output_as_it_was(
        capsys, tmp_path, small_bag, monkeypatch):
    """Each writer removes its partial file in ``finally``: the old file stays, nothing else."""
    pytest.importorskip('pyarrow')
    from matplotlib.figure import Figure
    import pyarrow.parquet as pq
    out, table = tmp_path / 'rows.csv', tmp_path / 'table'
    out.write_text('the old table\n')
    real_stamp_text = bag_output.stamp_text
    written = []

    def stamp_then_stop(ns):
        written.append(ns)
        if len(written) == 20:  # half the table written
            raise KeyboardInterrupt
        return real_stamp_text(ns)
    monkeypatch.setattr(bag_output, 'stamp_text', stamp_then_stop)
    assert interrupted(capsys, 'bag', small_bag, '--csv', out) == 130

    def half_then_stop(self, target, **kwargs):
        target.write(b'half a picture')
        raise KeyboardInterrupt
    monkeypatch.setattr(Figure, 'savefig', half_then_stop)
    assert interrupted(capsys, 'bag', small_bag, '--plot', tmp_path / 'rpy.png') == 130

    def half_a_table(data, where, **options):
        where.write(b'PAR1 half a table')
        raise KeyboardInterrupt
    monkeypatch.setattr(pq, 'write_table', half_a_table)
    assert interrupted(capsys, 'bag', small_bag, '--parquet', table) == 130
    assert sorted(p.name for p in tmp_path.iterdir()) == ['rows.csv', 'table']
    assert out.read_text() == 'the old table\n' and list(table.iterdir()) == []


# Stamps


def test_negative_stamps_are_exact(capsys, tmp_path):
    path = pose_bag(tmp_path / 'bag', [-12345.0, -2.0, -1.5, -0.5, -1e-9, 0.25])
    status, out, err = run_cli(capsys, 'bag', path, '--csv', '-')
    assert (status, err) == (0, '')
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [r['stamp'] for r in rows] == ['-12345.000000000', '-2.000000000', '-1.500000000',
                                          '-0.500000000', '-0.000000001', '0.250000000']
    assert float(rows[2]['wx'] or 0) != 0 or rows[2]['wx'] != ''  # Δt > 0: ω given
    s = json.loads(run_cli(capsys, 'bag', path, '--json')[1])['topics']['/pose']
    assert (s['start'], s['end'], s['duration']) == (-12345.0, 0.25, 12345.25)
    bag = next(iter(bag_analysis.analyse(path)[1]))
    assert bag.ns.tolist() == [-12345 * 10**9, -2 * 10**9, -15 * 10**8, -5 * 10**8, -1,
                               25 * 10**7]


def test_start_and_end_keep_every_digit_whatever_the_precision(capsys, tmp_path):
    """--precision rounds the summary's numbers, never its stamps (1503000000.0 it printed)."""
    stamps = [1503000000.123456789, 1503000000.987654321, 1503000061.5]
    path = pose_bag(tmp_path / 'bag', stamps)
    ns = [1503000000_123456789, 1503000000_987654321, 1503000061_500000000]
    for extra in ((), ('--json',)):
        status, out, err = run_cli(capsys, 'bag', path, '--precision', '4', *extra)
        assert (status, err) == (0, '')
        s = (json.loads(out) if extra else yaml.safe_load(out))['topics']['/pose']
        assert (s['start'], s['end']) == (ns[0] / 1e9, ns[-1] / 1e9)
        assert (s['duration'], s['rate']) == (61.38, 0.0326)  # the others rounded


def test_a_start_beyond_any_time_reads_nothing(capsys, small_bag):
    status, out, err = run_cli(capsys, 'bag', small_bag, '--start', '1e300', '--json')
    assert (status, err) == (0, '')
    assert json.loads(out)['topics']['/pose']['messages'] == 0


# Files that are not bags


def test_files_that_are_not_bags(capsys, tmp_path):
    for name in ('notes.txt', 'x.bag.active', 'README.md'):
        (tmp_path / name).write_text('not a bag\n')
        one_error(capsys, 'bag', tmp_path / name, contains=f'{name}: not a bag')
    one_error(capsys, 'bag', Path(__file__).parents[1] / 'README.md', contains='not a bag')


@pytest.mark.parametrize('storage', ['sqlite3', 'mcap'])
def test_a_bare_storage_file_is_read_as_a_bag(capsys, tmp_path, storage):
    """A .db3 or .mcap without its metadata.yaml (NotADirectoryError, with a traceback)."""
    folder = pose_bag(tmp_path / 'folder', [1.0 + 0.1 * k for k in range(30)], storage=storage)
    (inner,) = [p for p in folder.iterdir() if p.name != 'metadata.yaml']
    bare = tmp_path / f'alone{inner.suffix}'
    shutil.copy(inner, bare)
    assert bag_read.is_bag(bare) and bag_read.is_bag(folder) and bag_read.is_bag(inner)
    assert not bag_read.is_bag(tmp_path) and not bag_read.is_bag(tmp_path / 'notes.txt')
    of_folder, of_bare = (json.loads(run_cli(capsys, 'bag', path, '--json')[1])
                          for path in (folder, bare))
    assert of_bare == {**of_folder, 'bag': str(bare)}
    assert of_bare['storage'] == f'rosbag2 {storage}'
    assert of_bare['topics']['/pose']['accepted'] == 30
    rows = run_cli(capsys, 'bag', bare, '--csv', '-')[1]
    assert rows == run_cli(capsys, 'bag', folder, '--csv', '-')[1] and rows.count('\n') == 31


def test_files_named_as_bags_that_are_not(capsys, tmp_path):
    """Each is one line and exit status 2: rosbags' own word on what is wrong."""
    import sqlite3
    (tmp_path / 'text.mcap').write_text('not a bag\n')
    (tmp_path / 'text.db3').write_text('not a bag\n')
    with sqlite3.connect(tmp_path / 'other.db3') as db:
        db.execute('CREATE TABLE t (x)')
    folder = pose_bag(tmp_path / 'folder', [1.0, 2.0], storage='mcap')
    cut = next(folder.glob('*.mcap')).read_bytes()
    (tmp_path / 'cut.mcap').write_bytes(cut[:len(cut) // 2])
    (tmp_path / 'empty.db3').write_bytes(b'')
    for name in ('text.mcap', 'text.db3', 'other.db3', 'cut.mcap'):
        one_error(capsys, 'bag', tmp_path / name, contains=f'{name}: cannot read the bag: ')
    one_error(capsys, 'bag', tmp_path / 'empty.db3', contains='empty.db3: the file is empty')


def test_a_fifo_in_a_rosbag2_folder_is_refused_before_opening(capsys, tmp_path, small_bag):
    """Refuse it by its stat: rosbags would open it and wait for a writer for ever."""
    db3 = next(small_bag.glob('*.db3')).name
    for name in ('metadata.yaml', db3):
        folder = tmp_path / name.replace('.', '_')
        shutil.copytree(small_bag, folder)
        (folder / name).unlink()
        os.mkfifo(folder / name)
        with pytest.raises(bag_read.BagError, match='not a regular file'):
            bag_read.bag_paths(folder)  # nothing opened: the command below cannot hang
        for given in (folder, folder / db3) if name != db3 else (folder,):
            one_error(capsys, 'bag', given, contains=f'bag: {folder}: its {name} is not a '
                      'regular file (a FIFO, socket or device): refused')


def test_a_fifo_is_refused_before_opening(tmp_path):
    fifo = tmp_path / 'run.bag'
    os.mkfifo(fifo)
    script = console_script('rot-tools', 'rot_tools.cli.main')
    proc = subprocess.run(script + ['bag', str(fifo)], capture_output=True, text=True,
                          timeout=60, env=script_env(script))  # it hung for ever
    assert (proc.returncode, proc.stdout) == (2, '')
    assert proc.stderr == f'rot-tools: error: bag: {fifo}: not a regular file or a directory\n'


# What a spreadsheet would run


def test_text_cells_a_spreadsheet_would_run_are_escaped(capsys, tmp_path):
    frames = ('=HYPERLINK("x")', '+1', '-cmd', '@SUM(A1)', '\tx', '\rx', 'map', "'q", 'a,b\nc')
    path = pose_bag(tmp_path / 'bag', [1.0 + k for k in range(len(frames))], frames)
    out = run_cli(capsys, 'bag', path, '--csv', '-')[1]
    rows = list(csv.DictReader(io.StringIO(out)))
    assert [r['frame_id'] for r in rows] == ["'" + f for f in frames[:6]] + list(frames[6:])
    assert out.count('"\'=HYPERLINK(""x"")"') == 1  # quoted where CSV needs it
    numbers = [r[c] for r in rows for c in ('x', 'y', 'z')]
    assert all(n.startswith('-') and float(n) < 0 for n in numbers)  # never numbers
    assert bag_output.text_cell('=1+2') == "'=1+2" and bag_output.text_cell('map') == 'map'


# The plot: bounded, and tilt beside a spinning yaw


def spinning_bag(path, topics):
    """Topics of QuaternionStamped: yaw through 2,000°, roll and pitch within ±10°."""
    from scipy.spatial.transform import Rotation
    b = bh.Builder()
    t = np.linspace(0, 10, 200)
    rpy = np.stack([np.radians(10) * np.sin(t), np.radians(8) * np.cos(2 * t),
                    np.radians(200) * t], axis=1)
    q = Rotation.from_euler(RPY_SEQUENCE, rpy).as_quat()
    messages = [(topic, 'geometry_msgs/msg/QuaternionStamped', int(1e9 * (1 + s)) + k,
                 b.quaternion_stamped(1 + s, qk))
                for s, qk in zip(t, q) for k, topic in enumerate(topics)]
    return bh.write_bag(path, messages)


def axes_of(svg, gid):
    """Return the id of the matplotlib Axes group that holds the element ``gid``."""
    root = ElementTree.parse(svg).getroot()
    parent = {child: node for node in root.iter() for child in node}
    node = next(e for e in root.iter() if e.get('id') == gid)
    while not (node.get('id') or '').startswith('axes_'):
        node = parent[node]
    return node.get('id')


def test_the_plot_is_bounded_and_says_what_it_draws(capsys, tmp_path):
    pytest.importorskip('matplotlib')
    topics = [f'/t{k:02d}' for k in range(bag_output.MAX_PLOTTED_TOPICS + 3)]
    path = spinning_bag(tmp_path / 'bag', topics)
    svg = tmp_path / 'rpy.svg'
    status, _, err = run_cli(capsys, 'bag', path, '--plot', svg, '--deg')
    drawn, left = topics[:bag_output.MAX_PLOTTED_TOPICS], topics[bag_output.MAX_PLOTTED_TOPICS:]
    assert status == 0 and err == (
        f'rot-tools bag: --plot {svg}: roll, pitch, yaw of {", ".join(drawn)}; left out, 3 '
        f'(at most {len(drawn)} topics are drawn; choose them with --topic): '
        f'{", ".join(left)}\n')
    text = svg.read_text()
    assert all(f'id="{t}:yaw"' in text for t in drawn)
    assert not any(f'id="{t}:yaw"' in text for t in left)
    # roll and pitch share an axis of their own; yaw (2,000°) has another
    assert axes_of(svg, '/t00:roll') == axes_of(svg, '/t00:pitch') != axes_of(svg, '/t00:yaw')
    status, _, err = run_cli(capsys, 'bag', path, '--plot', svg, '--topic', left[0])
    assert status == 0 and err == f'rot-tools bag: --plot {svg}: roll, pitch, yaw of {left[0]}\n'
    assert f'id="{left[0]}:roll"' in svg.read_text()
