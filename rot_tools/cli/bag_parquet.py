"""
``rot-tools bag --parquet DIR``: one Parquet file per bag, the ``--csv`` columns plus ``bag``.

The columns are typed (:func:`schema`); a run of one bag or of many writes its bags' files,
then DIR's manifest and ``_SUCCESS`` (:func:`begin`, :func:`keep`, :func:`finish`). pyarrow,
the ``bag`` extra, is imported only when a table is made.
"""

from contextlib import contextmanager, suppress
import hashlib
import io
import json
import os
from pathlib import Path
import re

import numpy as np
from rot_tools.cli import output_file
from rot_tools.cli.bag_output import csv_header, row_values
from rot_tools.io.bag_read import BagSkipped


TEXT_COLUMNS = ('bag', 'topic', 'frame_id')
"""The columns of strings; ``stamp`` is int64 nanoseconds, every other column float64."""


def schema(seq, degrees):
    """Return the pyarrow schema of a bag's table (``--seq SEQ`` adds SEQ_1..3)."""
    import pyarrow as pa
    fields = [pa.field(name, pa.string() if name in TEXT_COLUMNS
                       else pa.int64() if name == 'stamp' else pa.float64())
              for name in ['bag'] + csv_header(seq)]
    return pa.schema(fields, metadata={'stamp': 'int64 nanoseconds (sec * 10^9 + nanosec)',
                                       'angles': 'deg' if degrees else 'rad'})


def table(topics, bag, degrees, seq):
    """Return the pyarrow Table of every accepted message of ``topics``, ``bag`` on each row."""
    import pyarrow as pa
    rows = [t for t in topics if len(t.R)]
    names = schema(seq, degrees).names
    width = len(names) - 4  # the numbers after bag, topic, stamp, frame_id
    values = np.vstack([row_values(t, degrees) for t in rows] or [np.zeros((0, width))])
    frames = [np.asarray(t.columns.frame_ids, object)[t.frame] for t in rows]
    columns = {
        'bag': pa.array([bag] * len(values), pa.string()),
        'topic': pa.array([t.topic for t in rows for _ in range(len(t.R))], pa.string()),
        'stamp': pa.array(np.concatenate([t.ns for t in rows] or [np.zeros(0, np.int64)]),
                          pa.int64()),
        'frame_id': pa.array(np.concatenate(frames or [np.zeros(0, object)]), pa.string()),
    }
    for k, name in enumerate(names[4:]):
        column = np.ascontiguousarray(values[:, k])
        columns[name] = pa.array(column, pa.float64(), mask=np.isnan(column))
    return pa.table(columns, schema=schema(seq, degrees))


def to_bytes(data):
    """Return the Table ``data`` as the bytes of a Parquet file."""
    import pyarrow.parquet as pq
    out = io.BytesIO()
    pq.write_table(data, out)
    return out.getvalue()


# ---------------------------------------------------------------------------------------
# The files of a run


STEM_BYTES = 180
"""The longest name made before ``.parquet`` and a ``-2`` (file systems allow 255 bytes)."""


def _short(stem):
    """``stem``, or within STEM_BYTES: its start, ``~`` and 16 hex digits of its SHA-256."""
    if len(stem) <= STEM_BYTES:  # ASCII only: characters are bytes
        return stem
    return f'{stem[:STEM_BYTES - 17]}~{hashlib.sha256(stem.encode()).hexdigest()[:16]}'


def file_names(paths):
    """
    Return a Parquet file name for each bag path: its parts joined by ``_``, unique.

    ``runs/day1/robot.bag`` is ``runs_day1_robot.bag.parquet``; ``.``, ``..`` and the root
    are dropped, characters other than letters, digits, ``.``, ``-`` and ``_`` become ``_``,
    a name longer than STEM_BYTES keeps its start and a hash of the whole (``~`` and 16 hex
    digits: two paths that differ only past the cut keep different names), and a name
    already taken (letter case aside) gets ``-2``, ``-3``, ... before its suffix.
    """
    names, taken = [], set()
    for path in paths:
        parts = [p for p in Path(path).parts if p not in ('.', '..', '/')]
        stem = _short(re.sub(r'[^\w.-]', '_', '_'.join(parts), flags=re.ASCII).lstrip('.')
                      or 'bag')
        name, k = stem, 1
        while name.lower() in taken:
            k += 1
            name = f'{stem}-{k}'
        taken.add(name.lower())
        names.append(name + '.parquet')
    return names


MANIFEST = '_manifest.json'
"""The file that says what a run wrote: each bag's path, status and file, and the files."""

SUCCESS = '_SUCCESS'
"""An empty file, written after the manifest when no bag failed (as Spark's writers do)."""


def begin(directory, error):
    """
    Start a run in DIR: create it if needed, and remove its manifest and _SUCCESS.

    While a run writes DIR, DIR has neither. ``error(text)`` (one line, exit 2) when DIR
    cannot be made or written.
    """
    try:
        os.makedirs(directory, exist_ok=True)
        for name in (SUCCESS, MANIFEST):
            with suppress(FileNotFoundError):
                os.unlink(os.path.join(directory, name))
    except OSError as exc:
        error(f'--parquet: cannot write in {directory}: {exc.strerror or exc}')
    if not os.access(directory, os.W_OK | os.X_OK):
        error(f'--parquet: cannot write in {directory}: permission denied')


def keep(path, data):
    """
    Write a bag's Parquet bytes ``data`` to ``path`` whole (output_file.complete_or_nothing).

    ``data`` None (the bag failed or was skipped): remove an earlier run's file at ``path``.
    """
    if data is None:
        with suppress(FileNotFoundError):
            os.unlink(path)
        return
    with output_file.complete_or_nothing(path, 'wb') as out:
        out.write(data)


def finish(directory, bags):
    """
    Write DIR's manifest, then _SUCCESS if no bag failed: the last files of a run.

    bags: [(path, status, file name)] in the run's order, status ``ok``, ``skipped`` or
    ``failed``; the manifest lists every bag, and under ``files`` the files of the ``ok``
    ones: the run's table, whatever else DIR holds.
    """
    data = {'bags': [{'path': path, 'status': status, 'file': name if status == 'ok' else None}
                     for path, status, name in bags],
            'files': [name for _, status, name in bags if status == 'ok']}
    manifest = os.path.join(directory, MANIFEST)
    with output_file.complete_or_nothing(manifest, 'w', encoding='utf-8') as out:
        json.dump(data, out, indent=2, ensure_ascii=False)
        out.write('\n')
    if all(status != 'failed' for _, status, _ in bags):
        with output_file.complete_or_nothing(os.path.join(directory, SUCCESS), 'w'):
            pass


@contextmanager
def run_of_one(directory, bag, error):
    """
    Keep --parquet DIR (None: not asked) for a run of the one bag ``bag`` as a fleet's run.

    Yield the bag's file in DIR, which the block writes. When the block raises an Exception
    (the bag failed, or holds nothing asked), the bag's earlier file goes and the manifest
    says so; a run stopped otherwise (an error line, Ctrl-C) leaves DIR without a manifest.
    """
    if directory is None:
        yield None
        return
    begin(directory, error)
    name = file_names([bag])[0]
    target = os.path.join(directory, name)
    try:
        yield target
    except Exception as exc:
        with suppress(OSError):  # the bag's own line says what went wrong
            keep(target, None)
            finish(directory, [(str(bag), 'skipped' if isinstance(exc, BagSkipped)
                                else 'failed', name)])
        raise
    try:
        finish(directory, [(str(bag), 'ok', name)])
    except OSError as exc:
        error(f'--parquet: cannot write the manifest in {directory}: {exc.strerror or exc}')
