"""
``rot-tools bag PATH...``: many bags in one command, each read once by one job.

A fleet's bags are found (:func:`find_bags`: the paths as given, directories searched for
bags in path order) and each is the job :func:`read_bag` — the whole of ``rot-tools bag`` on
one bag: its summary, its CSV rows, its Parquet file. The jobs run here one after the other
(``--jobs 1``), in ``--jobs N`` processes (concurrent.futures), or on a Dask cluster
(``--engine dask``: an existing one at ``--scheduler ADDRESS``, else a local one of N
workers); whichever runs them, their results are taken in the order of the bags, so the
output is the same byte for byte. A bag that cannot be read is one line on stderr and an
entry ``status: failed`` in the summary; the others go on, and the exit status is 1.
"""

import io
import multiprocessing
import os
from pathlib import Path
import sys
import time
from typing import NamedTuple

from rot_tools.cli import bag_analysis, bag_parquet, output_file
from rot_tools.cli.bag_output import csv_header, write_csv
from rot_tools.io import bag_read
from rot_tools.io.boundary import QUATERNION_TOLERANCE


def _bags_under(directory):
    """Every bag under ``directory``, sorted by path: .bag files and rosbag2 directories."""
    found = []
    for root, dirs, files in os.walk(directory):
        if 'metadata.yaml' in files:
            found.append(Path(root))
            dirs.clear()  # a rosbag2 directory is one bag
            continue
        found += [Path(root, name) for name in files if name.endswith('.bag')]
    return sorted(found)


class Found(NamedTuple):
    """The bags of PATH... (strings, in order), and whether a directory was searched."""

    bags: list
    searched: bool


def find_bags(paths):
    """
    Return Found: the bags of PATH..., and whether a directory was searched.

    The bags are in the order given, each as given or as found (strings).

    A directory with metadata.yaml is a rosbag2 bag; any other directory is searched
    recursively for bags (BagError when it holds none); anything else is a bag as given
    (what it is, the job says).
    """
    bags, searched = [], False
    for path in paths:
        if os.path.isdir(path) and not os.path.exists(os.path.join(path, 'metadata.yaml')):
            found = _bags_under(path)
            if not found:
                raise bag_read.BagError(f'{path}: no bag in this directory (a ROS 1 .bag file '
                                        'or a rosbag2 directory with metadata.yaml)')
            bags += [str(p) for p in found]
            searched = True
        else:
            bags.append(path)
    return Found(bags, searched)


class Outcome:
    """What one bag's job gives back: its summary and accepted count, or the line of its error."""

    def __init__(self, path, summary=None, accepted=0, rows=None, error=None):
        self.path, self.summary, self.accepted = str(path), summary, accepted
        self.rows, self.error = rows, error


def _csv_rows(topics, path, options):
    """Return the CSV rows of one bag (text, a ``bag`` column first, no header)."""
    text = io.StringIO(newline='')
    write_csv(text, topics, options.deg, options.precision, bag=str(path), header=False)
    return text.getvalue()


def read_bag(path, options, parquet=None):
    """
    One bag's job, wherever it runs: analyse it, and keep what the command asked for.

    options: the command's parsed arguments (their bag options). parquet: the file to write
    the bag's table to, or None. Returns an Outcome; a bag that cannot be read is one with
    the error's line (beginning with the bag's path).
    """
    quiet = io.StringIO()  # not a terminal: no bar per bag, the fleet's line says how far
    try:
        storage, topics = bag_analysis.analyse(
            path, options.topic or (), options.start, options.end,
            QUATERNION_TOLERANCE if options.tol is None else options.tol, options.seq,
            options.wrap, progress_stream=quiet, tf=options.tf,
            reading=options.input_covariance)
    except bag_read.BagError as exc:
        text = str(exc)
        return Outcome(path, error=text if text.startswith(f'{path}:') else f'{path}: {text}')
    summary = bag_analysis.summary(path, storage, topics, options.deg)
    accepted = sum(t['accepted'] for t in summary['topics'].values())
    rows = _csv_rows(topics, path, options) if options.csv is not None else None
    if parquet is not None:
        try:
            bag_parquet.write(parquet, bag_parquet.table(topics, str(path), options.deg,
                                                         options.seq))
        except OSError as exc:
            return Outcome(path, error=f'--parquet: cannot write {parquet}: '
                           f'{exc.strerror or exc}')
    return Outcome(path, summary, accepted, rows)


# ---------------------------------------------------------------------------------------
# Running the jobs


def _processes(items, jobs):
    """
    Yield read_bag(*item) for each item, in order, from ``jobs`` processes.

    The processes are forked from this one (the command's own process) once the bag reader
    is imported, so each starts with it loaded: on a fleet of small bags, importing it again
    in every process costs as much as the reading.
    """
    from concurrent.futures import ProcessPoolExecutor
    import rosbags.highlevel  # noqa: F401 - imported once, here, for every process
    context = multiprocessing.get_context('fork')
    with ProcessPoolExecutor(min(jobs, len(items)), mp_context=context) as pool:
        yield from pool.map(read_bag, *zip(*items))


class EngineError(Exception):
    """The engine cannot run the jobs (a Dask scheduler that does not answer)."""


def _dask(items, jobs, scheduler):
    """
    Yield read_bag(*item) for each item, in order, from a Dask cluster's workers.

    scheduler: the address of a running cluster's scheduler; None starts a local cluster of
    ``jobs`` worker processes of one thread each, closed at the end.
    """
    from dask.distributed import Client, LocalCluster
    # dashboard_address ':0': the scheduler's HTTP server on a free port (with None it still
    # tries 8787, and warns on stderr when another cluster, or another run, holds it)
    cluster = None if scheduler else LocalCluster(
        n_workers=jobs, threads_per_worker=1, dashboard_address=':0')
    try:
        try:
            client = Client(scheduler or cluster)  # waits distributed.comm.timeouts.connect
        except (OSError, ValueError) as exc:  # no scheduler there, or not an address
            raise EngineError(f'--scheduler {scheduler}: cannot connect: {exc}') from None
        with client:
            futures = client.map(read_bag, *zip(*items), pure=False)
            for future in futures:
                yield future.result()
    finally:
        if cluster is not None:
            cluster.close()


def outcomes(items, jobs, engine, scheduler):
    """Yield read_bag(*item) for each item, in the items' order, by the engine chosen."""
    if engine == 'dask':
        yield from _dask(items, jobs, scheduler)
    elif jobs == 1 or len(items) == 1:
        for item in items:
            yield read_bag(*item)
    else:
        yield from _processes(items, jobs)


class FleetProgress(bag_analysis.Progress):
    """Bags done and messages (accepted) per second, on stderr when it is a terminal."""

    def __init__(self, total, stream=None):
        super().__init__(total, stream)
        self.done_bags, self.messages, self.start = 0, 0, time.monotonic()

    def add(self, outcome):
        """Count one more bag done."""
        self.done_bags += 1
        self.messages += outcome.accepted
        if self.active:
            rate = self.messages / max(time.monotonic() - self.start, 1e-9)
            self.stream.write(f'\rrot-tools bag: {self.done_bags}/{self.total} bags, '
                              f'{rate:,.0f} messages/s')
            self.stream.flush()


# ---------------------------------------------------------------------------------------
# The command


def check_extras(args, error):
    """Call ``error`` when --parquet lacks pyarrow (the bag extra) or --engine dask, Dask."""
    if args.parquet is not None:
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            error("--parquet needs pyarrow, the 'bag' extra: pip install 'rot_tools[bag]'")
    if args.engine == 'dask':
        try:
            import dask.distributed  # noqa: F401
        except ImportError:
            error("--engine dask needs dask.distributed, the 'fleet' extra: "
                  "pip install 'rot_tools[fleet]'")


def _collect(items, args, out):
    """Run the jobs; write each bag's rows to ``out`` (or None) and its failure on stderr."""
    progress = FleetProgress(len(items))
    done = []
    if out is not None:
        out.write(','.join(['bag'] + csv_header(args.seq)) + '\n')
    try:
        for outcome in outcomes(items, args.jobs, args.engine, args.scheduler):
            progress.add(outcome)
            if outcome.error is not None:
                progress.done()
                sys.stderr.write(f'rot-tools: error: bag: {outcome.error}\n')
            elif out is not None:
                out.write(outcome.rows)
            outcome.rows = None
            done.append(outcome)
    finally:
        progress.done()
    return done


def fleet_summary(done):
    """Return the summary of many bags: ``bags`` (one entry each, in order), then ``fleet``."""
    entries = []
    for outcome in done:
        if outcome.error is not None:
            entries.append({'path': outcome.path, 'status': 'failed', 'error': outcome.error})
        else:
            usual = {k: v for k, v in outcome.summary.items() if k != 'bag'}
            entries.append({'path': outcome.path, 'status': 'ok', **usual})
    failed = sum(o.error is not None for o in done)
    return {'bags': entries, 'fleet': {'bags': len(done), 'failed': failed,
                                       'messages': sum(o.accepted for o in done)}}


def run(args, bags, error):
    """rot-tools bag over many bags; returns the exit status (1 when a bag failed)."""
    if args.plot:
        error('--plot draws one bag: give one bag, or leave --plot out')
    check_extras(args, error)
    if args.jobs is None:
        args.jobs = len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') \
            else os.cpu_count() or 1
    output_file.check_outputs([('--csv', args.csv), ('--parquet', args.parquet)], bags, error)
    names = [None] * len(bags)
    if args.parquet is not None:
        bag_parquet.directory(args.parquet, error)
        names = [os.path.join(args.parquet, n) for n in bag_parquet.file_names(bags)]
    items = [(path, args, name) for path, name in zip(bags, names)]
    try:
        return _write(items, args, error)
    except EngineError as exc:
        error(str(exc))


def _write(items, args, error):
    """Run the jobs, write the CSV and the summary; return the exit status."""
    from rot_tools.io.report import to_json, to_yaml

    if args.csv == '-':
        found = []
        output_file.to_stdout(lambda out: found.extend(_collect(items, args, out)))
        return 1 if any(o.error is not None for o in found) else 0
    if args.csv is not None:
        try:
            with output_file.complete_or_nothing(args.csv, 'w', encoding='utf-8',
                                                 newline='') as out:
                done = _collect(items, args, out)
        except OSError as exc:
            error(f'--csv: cannot write {args.csv}: {exc.strerror or exc}')
    else:
        done = _collect(items, args, None)
    text = to_json if args.json else to_yaml
    data = fleet_summary(done)
    output_file.to_stdout(lambda out: out.write(text(data, precision=args.precision)))
    return 1 if data['fleet']['failed'] else 0
