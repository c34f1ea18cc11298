"""
``rot-tools bag PATH...``: many bags in one command, each read once by one job.

Each bag is the job :func:`read_bag`, run here one after the other (``--jobs 1``), in a pool
of ``--jobs N`` worker processes (concurrent.futures), or on a Dask cluster (``--engine
dask``); the results are taken in the order of the bags, and only this process writes files.
"""

from collections import deque
from contextlib import closing
import io
import os
from pathlib import Path
import signal
import sys
import threading
import time
from typing import NamedTuple

from rot_tools.cli import bag_analysis, bag_parquet, options, output_file
from rot_tools.cli.bag_output import csv_header, write_csv
from rot_tools.io import arguments, bag_read
from rot_tools.io.boundary import QUATERNION_TOLERANCE


def _bags_under(directory):
    """
    Every bag under ``directory``, sorted by path: rosbag2 directories and bag files.

    A directory holding metadata.yaml is one bag (its storage files are not searched); any
    other file that rot_tools.io.bag_read.is_bag names a bag (.bag, and .db3 or .mcap files
    alone) is one.
    """
    found = []
    for root, dirs, files in os.walk(directory):
        if 'metadata.yaml' in files:
            found.append(Path(root))
            dirs.clear()  # a rosbag2 directory is one bag
            continue
        found += [Path(root, name) for name in files if bag_read.is_bag(Path(root, name))]
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
                raise bag_read.BagError(f'{path}: no bag in this directory (a ROS 1 .bag file, '
                                        'a rosbag2 directory with metadata.yaml, or a .db3 '
                                        'or .mcap file)')
            bags += [str(p) for p in found]
            searched = True
        else:
            bags.append(path)
    return Found(bags, searched)


class Outcome:
    """
    What one bag's job gives back: its summary, CSV rows and Parquet bytes, or why it has none.

    error: the one line of a bag that failed; skipped: the one line of a bag that holds
    nothing of what was asked. Both begin with the bag's path.
    """

    def __init__(self, path, summary=None, accepted=0, rows=None, parquet=None, error=None,
                 skipped=None):
        self.path, self.summary, self.accepted = str(path), summary, accepted
        self.rows, self.parquet, self.error, self.skipped = rows, parquet, error, skipped

    @property
    def status(self):
        """``ok``, ``skipped`` or ``failed``."""
        return 'failed' if self.error is not None else 'skipped' if self.skipped else 'ok'


def read_bag(path, args, parquet):
    """
    One bag's job, wherever it runs: analyse it, and make what the command asked for.

    args: the command's parsed arguments; parquet: whether to make the bag's Parquet bytes.
    Returns an Outcome; a bag on which anything goes wrong is one with the error's line.
    """
    quiet = io.StringIO()  # not a terminal: no bar per bag, the fleet's line says how far
    try:
        storage, topics = bag_analysis.analyse(
            path, args.topic or (), args.start, args.end,
            QUATERNION_TOLERANCE if args.tol is None else args.tol, args.seq,
            args.wrap, progress_stream=quiet, tf=args.tf, reading=args.input_covariance)
        summary = bag_analysis.summary(path, storage, topics, args.deg)
        accepted = sum(t['accepted'] for t in summary['topics'].values())
        rows = None
        if args.csv is not None:
            text = io.StringIO(newline='')
            write_csv(text, topics, args.deg, args.precision, bag=str(path), header=False)
            rows = text.getvalue()
        table = bag_parquet.to_bytes(bag_parquet.table(topics, str(path), args.deg, args.seq)
                                     ) if parquet else None
    except bag_read.BagSkipped as exc:
        return Outcome(path, skipped=bag_analysis.failure(path, exc))
    except Exception as exc:  # one bag's failure, whatever it is, is that bag's line
        return Outcome(path, error=bag_analysis.failure(path, exc))
    return Outcome(path, summary, accepted, rows, table)


# ---------------------------------------------------------------------------------------
# Running the jobs


class FleetError(Exception):
    """What stops the whole fleet (a Dask scheduler that does not answer): one line."""


def _worker_start(command):
    """
    Begin a worker process of the command whose process id is ``command``.

    Ctrl-C is the command's to handle (it stops its workers), SIGTERM ends the worker, and
    the worker ends itself once the command is gone, however it ended (SIGKILL included).
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    threading.Thread(target=_end_with_command, args=(command,), daemon=True).start()


def _end_with_command(command):
    """In a worker: wait until the command is gone, then end at once (a worker writes no file)."""
    while os.getppid() == command:
        time.sleep(0.1)
    os.kill(os.getpid(), signal.SIGKILL)


def _pool(workers):
    """
    Return a pool of ``workers`` processes forked from this one (its modules loaded).

    concurrent.futures and multiprocessing are imported by the functions that use them: a
    command on one bag, or with --jobs 1, never does.
    """
    from concurrent.futures import ProcessPoolExecutor
    import multiprocessing
    return ProcessPoolExecutor(workers, multiprocessing.get_context('fork'),
                               initializer=_worker_start, initargs=(os.getpid(),))


def _stop(pool):
    """Stop ``pool`` at once: its workers killed (this process's only children), no bag begun."""
    import multiprocessing
    for worker in multiprocessing.active_children():
        worker.kill()
    pool.shutdown(cancel_futures=True)


def _alone(item):
    """Return read_bag(*item) from a worker of its own: a bag that a broken pool held."""
    from concurrent.futures.process import BrokenProcessPool
    pool = _pool(1)
    try:
        return pool.submit(read_bag, *item).result()
    except BrokenProcessPool:
        return Outcome(item[0], error=f'{item[0]}: the process reading this bag, alone, died '
                       'before it was done; out of memory?')
    finally:
        _stop(pool)


def _processes(items, jobs):
    """
    Yield read_bag(*item) for each item, in order, from a pool of ``jobs`` processes.

    At most 2 × ``jobs`` bags are handed to the pool at a time. When a worker dies (the OOM
    killer, a crash), the pool breaks: each bag it held is read again alone (:func:`_alone`).
    """
    from concurrent.futures.process import BrokenProcessPool
    import rosbags.highlevel  # noqa: F401 - imported once, here, for every worker
    waiting, queued = deque(items), deque()
    pool = _pool(jobs)
    try:
        while waiting or queued:
            try:
                while waiting and len(queued) < 2 * jobs:
                    queued.append((waiting[0], pool.submit(read_bag, *waiting[0])))
                    waiting.popleft()
                outcome = queued[0][1].result()
            except BrokenProcessPool:
                pool.shutdown()
                for item, future in queued:
                    yield _alone(item) if future.exception() else future.result()
                queued, pool = deque(), _pool(jobs)
                continue
            queued.popleft()
            yield outcome
    except BaseException:  # stopped (Ctrl-C, SIGTERM, the reader gone): no bag waited for
        _stop(pool)
        raise
    pool.shutdown()


CONNECT_TIMEOUT = 5.0
"""Seconds a Dask scheduler has to answer the first connection."""


def _connection_failure(scheduler, exc):
    """Return the line that says why no scheduler answered at ``scheduler``."""
    scheme = scheduler.split('://', 1)[0] if '://' in scheduler else ''
    if isinstance(exc, OSError):  # TimeoutError too; Dask's connect retries until its bound
        said = (f'no Dask scheduler answered within {CONNECT_TIMEOUT:g} s (the '
                "dashboard's HTTP port is not the scheduler's)")
    elif isinstance(exc, TypeError) and scheme == 'tls':
        said = ("tls:// needs Dask's TLS settings (distributed.comm.tls.ca-file, "
                'distributed.comm.tls.client.cert and .key)')
    elif isinstance(exc, TypeError) and scheme == 'ucx':
        said = "ucx:// needs Dask's UCX support (distributed-ucxx), which is not installed"
    else:
        said = ' '.join(str(exc).split()) or type(exc).__name__
    return f'--scheduler {scheduler}: cannot connect: {said}'


def _reach(scheduler):
    """
    Connect once to the Dask scheduler at ``scheduler``, its answer included, or FleetError.

    Dask's client waits for a first answer without a bound (a port that accepts and says
    nothing), and retries a refused connection for Dask's connect timeout (30 s): here
    both get CONNECT_TIMEOUT.
    """
    import asyncio
    from distributed.comm import connect
    from distributed.security import Security

    async def answered():
        comm = await connect(scheduler, timeout=CONNECT_TIMEOUT,
                             **Security().get_connection_args('client'))
        await comm.close()

    try:
        asyncio.run(asyncio.wait_for(answered(), CONNECT_TIMEOUT))
    except (OSError, ValueError, TypeError) as exc:
        raise FleetError(_connection_failure(scheduler, exc)) from None


def _dask(items, jobs, scheduler):
    """
    Yield read_bag(*item) for each item, in order, from a Dask cluster's workers.

    scheduler: the address of a running cluster's scheduler; None starts a local cluster of
    ``jobs`` threads in this process (no more than the items), closed at the end. A task
    whose workers died (Dask tries it on others first) is that item's failed Outcome.
    """
    import logging
    from dask.distributed import Client, LocalCluster
    if scheduler is not None:
        _reach(scheduler)
    # dashboard_address ':0': a free port (the default 8787 may be another cluster's)
    cluster = None if scheduler is not None else LocalCluster(
        n_workers=min(jobs, len(items)), threads_per_worker=1, processes=False,
        dashboard_address=':0')
    try:
        try:
            client = Client(scheduler if cluster is None else cluster, timeout=CONNECT_TIMEOUT)
        except (OSError, ValueError, TypeError) as exc:
            raise FleetError(_connection_failure(scheduler, exc)) from None
        with client:
            futures = client.map(read_bag, *zip(*items), pure=False)
            for item, future in zip(items, futures):
                try:
                    yield future.result()
                except Exception as exc:  # the task's failure (its workers died), not the job's
                    said = ' '.join(str(exc).split())
                    yield Outcome(item[0], error=f'{item[0]}: its Dask task failed: '
                                  f'{type(exc).__name__}{": " if said else ""}{said[:300]}')
    except BaseException:  # stopped (Ctrl-C, SIGTERM, stdout gone): Dask's logs of it dropped
        logging.getLogger('distributed').setLevel(logging.CRITICAL)
        raise
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
    """
    Call ``error`` for what the engine and outputs cannot do here.

    --parquet without pyarrow (the bag extra), --engine dask without Dask (the fleet extra),
    a --scheduler address that is empty or in-process.
    """
    if args.parquet is not None:
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            error("--parquet needs pyarrow, the 'bag' extra: " + arguments.install_hint('bag'))
    if args.scheduler is not None and not args.scheduler.strip():
        error(f"--scheduler {args.scheduler!r}: no address (a Dask scheduler's, such as "
              'tcp://HOST:8786)')
    if args.scheduler is not None and args.scheduler.strip().startswith('inproc://'):
        error(f'--scheduler {args.scheduler}: an inproc:// address is reachable only inside the '
              "Python process that made it; give the scheduler's tcp://HOST:PORT")
    if args.engine == 'dask':
        try:
            import dask.distributed  # noqa: F401
        except ImportError:
            error("--engine dask needs dask.distributed, the 'fleet' extra: "
                  + arguments.install_hint('fleet'))


def _collect(items, names, args, out):
    """
    Run the jobs; write each bag's rows to ``out`` (or None) and its Parquet file.

    names: each bag's Parquet file (None without --parquet). What went wrong on a bag is
    its line on stderr. Returns the Outcomes, in order.
    """
    progress = FleetProgress(len(items))
    done = []
    if out is not None:
        out.write(','.join(['bag'] + csv_header(args.seq)) + '\n')
    try:
        with closing(outcomes(items, args.jobs, args.engine, args.scheduler)) as results:
            for name, outcome in zip(names, results):
                progress.add(outcome)
                if outcome.status != 'ok':
                    progress.done()
                    said = (f'error: bag: {outcome.error}' if outcome.error is not None
                            else f'bag: skipped: {outcome.skipped}')
                    sys.stderr.write(f'{options.PROG}: {said}\n')
                elif out is not None:
                    out.write(outcome.rows)
                if name is not None:
                    try:
                        bag_parquet.keep(name, outcome.parquet)
                    except OSError as exc:
                        raise FleetError(f'--parquet: cannot write {name}: '
                                         f'{exc.strerror or exc}') from None
                outcome.rows = outcome.parquet = None
                done.append(outcome)
    finally:
        progress.done()
    return done


def fleet_summary(done):
    """
    Return the summary of many bags: ``bags`` (one entry each, in order), then ``fleet``.

    An entry is the bag's ``path`` and ``status``, then its usual summary (``ok``), the line
    of its ``error`` (``failed``) or the ``reason`` it was ``skipped``.
    """
    entries = []
    for outcome in done:
        if outcome.status == 'failed':
            entries.append({'path': outcome.path, 'status': 'failed', 'error': outcome.error})
        elif outcome.status == 'skipped':
            entries.append({'path': outcome.path, 'status': 'skipped',
                            'reason': outcome.skipped})
        else:
            usual = {k: v for k, v in outcome.summary.items() if k != 'bag'}
            entries.append({'path': outcome.path, 'status': 'ok', **usual})
    return {'bags': entries, 'fleet': {
        'bags': len(done), 'failed': sum(o.status == 'failed' for o in done),
        'skipped': sum(o.status == 'skipped' for o in done),
        'messages': sum(o.accepted for o in done)}}


def run(args, bags, error):
    """rot-tools bag over many bags; returns the exit status (1 when a bag failed)."""
    if args.plot:
        error('--plot draws one bag: give one bag, or leave --plot out')
    check_extras(args, error)
    if args.jobs is None:
        args.jobs = len(os.sched_getaffinity(0)) if hasattr(os, 'sched_getaffinity') \
            else os.cpu_count() or 1
    output_file.check_outputs([('--csv', args.csv), ('--parquet', args.parquet)], bags, error,
                              args.force)
    names = [None] * len(bags)
    if args.parquet is not None:
        bag_parquet.begin(args.parquet, error)
        names = [os.path.join(args.parquet, n) for n in bag_parquet.file_names(bags)]
    items = [(path, args, args.parquet is not None) for path in bags]
    try:
        return _write(items, names, args, error)
    except FleetError as exc:
        error(str(exc))


def _write(items, names, args, error):
    """Run the jobs, write the CSV, the manifest and the summary; return the exit status."""
    from rot_tools.io.report import to_json, to_yaml

    if args.csv == '-':
        done = []
        output_file.to_stdout(lambda out: done.extend(_collect(items, names, args, out)))
    elif args.csv is not None:
        try:
            with output_file.complete_or_nothing(args.csv, 'w', encoding='utf-8',
                                                 newline='') as out:
                done = _collect(items, names, args, out)
        except OSError as exc:
            error(f'--csv: cannot write {args.csv}: {exc.strerror or exc}')
    else:
        done = _collect(items, names, args, None)
    if args.parquet is not None:
        try:
            bag_parquet.finish(args.parquet, [(o.path, o.status, os.path.basename(name))
                                              for o, name in zip(done, names)])
        except OSError as exc:
            error(f'--parquet: cannot write the manifest in {args.parquet}: '
                  f'{exc.strerror or exc}')
    data = fleet_summary(done)
    if args.csv != '-':
        text = to_json if args.json else to_yaml
        output_file.to_stdout(lambda out: out.write(text(data, precision=args.precision)))
    return 1 if data['fleet']['failed'] else 0
