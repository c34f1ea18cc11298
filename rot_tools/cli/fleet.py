"""
``rot-tools bag PATH...``: many bags in one command, each read once by one job.

A fleet's bags are found (:func:`find_bags`: the paths as given, directories searched for
bags in path order) and each is the job :func:`read_bag` — the whole of ``rot-tools bag`` on
one bag: its summary, its CSV rows, its Parquet file. The jobs run here one after the other
(``--jobs 1``), in at most ``--jobs N`` processes at a time, one forked for each bag
(:func:`_processes`), or on a Dask cluster (``--engine dask``: an existing one at
``--scheduler ADDRESS``, else a local one of N workers); whichever runs them, their results
are taken in the order of the bags, so the output is the same byte for byte.

Every bag ends ``ok``, ``skipped`` (it holds nothing of what was asked: a line on stderr, and
the exit status stays 0) or ``failed`` (one line on stderr; the others go on, and the exit
status is 1) — whatever went wrong on it, its process killed twice included. A worker
process ends with the command, however the command ends; the outputs have no name until they
are complete (rot_tools.cli.output_file.complete_or_nothing), and a ``--parquet`` directory
holds a manifest of the run, written last.
"""

from collections import deque
from contextlib import suppress
import io
import multiprocessing
import os
from pathlib import Path
import signal
import sys
import threading
import time
from typing import NamedTuple

from rot_tools.cli import bag_analysis, bag_parquet, output_file
from rot_tools.cli.bag_output import csv_header, write_csv
from rot_tools.cli.options import PROG
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
    What one bag's job gives back: its summary and accepted count, or why it has none.

    error: the one line of a bag that failed; skipped: the one line of a bag that holds
    nothing of what was asked. Both begin with the bag's path.
    """

    def __init__(self, path, summary=None, accepted=0, rows=None, error=None, skipped=None):
        self.path, self.summary, self.accepted = str(path), summary, accepted
        self.rows, self.error, self.skipped = rows, error, skipped

    @property
    def status(self):
        """``ok``, ``skipped`` or ``failed``."""
        return 'failed' if self.error is not None else 'skipped' if self.skipped else 'ok'


def _csv_rows(topics, path, options):
    """Return the CSV rows of one bag (text, a ``bag`` column first, no header)."""
    text = io.StringIO(newline='')
    write_csv(text, topics, options.deg, options.precision, bag=str(path), header=False)
    return text.getvalue()


def read_bag(path, options, parquet=None):
    """
    One bag's job, wherever it runs: analyse it, and keep what the command asked for.

    options: the command's parsed arguments (their bag options). parquet: the file to write
    the bag's table to, or None. Returns an Outcome; a bag that cannot be read, or on which
    anything else goes wrong, is one with the error's line (beginning with the bag's path).
    """
    quiet = io.StringIO()  # not a terminal: no bar per bag, the fleet's line says how far
    try:
        storage, topics = bag_analysis.analyse(
            path, options.topic or (), options.start, options.end,
            QUATERNION_TOLERANCE if options.tol is None else options.tol, options.seq,
            options.wrap, progress_stream=quiet, tf=options.tf,
            reading=options.input_covariance)
        summary = bag_analysis.summary(path, storage, topics, options.deg)
        accepted = sum(t['accepted'] for t in summary['topics'].values())
        rows = _csv_rows(topics, path, options) if options.csv is not None else None
        if parquet is not None:
            table = bag_parquet.table(topics, str(path), options.deg, options.seq)
            try:
                bag_parquet.write(parquet, table)
            except OSError as exc:
                return Outcome(path, error=f'--parquet: cannot write {parquet}: '
                               f'{exc.strerror or exc}')
    except bag_read.BagSkipped as exc:
        return Outcome(path, skipped=bag_analysis.failure(path, exc))
    except Exception as exc:  # one bag's failure, whatever it is, is that bag's line
        return Outcome(path, error=bag_analysis.failure(path, exc))
    return Outcome(path, summary, accepted, rows)


# ---------------------------------------------------------------------------------------
# Running the jobs


class FleetError(Exception):
    """What stops the whole fleet (a Dask scheduler that does not answer): one line."""


def _end_with_command(lifeline):
    """
    In a worker: wait until the command has ended, then end this worker at once.

    ``lifeline`` is the read end of a pipe whose write end only the command holds: reading it
    returns (end of file) when the command's end is closed — by the command when it is done
    with its workers, or by the kernel when the command dies, SIGKILL included.
    """
    while os.read(lifeline, 1):  # nothing is ever written: only the end of file comes
        pass
    output_file.remove_partials()
    os.kill(os.getpid(), signal.SIGKILL)  # at once, whatever the worker is doing


def _worker(lifeline, held, results, item):
    """Read one bag and send its Outcome to the command: the body of a worker process."""
    os.close(held)  # the command's end of the lifeline: a worker holds none
    sys.stdout = open(os.devnull, 'w')  # what the command had not yet written is its own
    threading.Thread(target=_end_with_command, args=(lifeline,), daemon=True).start()
    outcome = read_bag(*item)
    with suppress(OSError):  # the command is gone: so is this worker, in a moment
        results.send(outcome)


def _ended(path, process):
    """Return the line of a bag whose worker died twice: how the second one ended."""
    code = process.exitcode
    how = (f'was killed by {signal.Signals(-code).name}' if code is not None and code < 0
           and -code in signal.valid_signals() else f'ended with status {code}')
    return (f'{path}: the process reading this bag {how} before it was done, twice (the '
            'second time alone); out of memory?')


class _Running(NamedTuple):
    """A worker at work: the index of its item, whether it is a second try, its process."""

    index: int
    again: bool
    process: multiprocessing.Process


def _processes(items, jobs):
    """
    Yield read_bag(*item) for each item, in order, from at most ``jobs`` processes at a time.

    Each item is read in a process forked from this one (the command's own) for it, once the
    bag reader is imported, so that each starts with it loaded. A worker holds the read end
    of the lifeline and ends itself when the command is gone (:func:`_end_with_command`): it
    never outlives the command, nor holds its standard output and error open after it. A
    worker that dies before its result (the OOM killer, a crash) is forked again for the
    same item, alone; if that one dies too, the item is a failed Outcome.
    """
    from multiprocessing.connection import wait
    import rosbags.highlevel  # noqa: F401 - imported once, here, for every process
    context = multiprocessing.get_context('fork')
    lifeline, held = os.pipe()
    waiting = deque((k, False) for k in range(len(items)))
    running, done, given = {}, {}, 0
    try:
        while given < len(items):
            while (waiting and len(running) < jobs and not any(r.again for r in running.values())
                   and not (waiting[0][1] and running)):  # a second try runs alone
                index, again = waiting.popleft()
                results, sender = context.Pipe(duplex=False)
                process = context.Process(target=_worker, daemon=True,
                                          args=(lifeline, held, sender, items[index]))
                try:
                    process.start()
                except OSError as exc:
                    results.close()
                    raise FleetError(f'cannot start a worker process: {exc.strerror or exc}'
                                     ) from None
                finally:
                    sender.close()
                running[results] = _Running(index, again, process)
            for results in wait(list(running)):
                index, again, process = running.pop(results)
                try:
                    outcome = results.recv()
                except (EOFError, OSError):
                    outcome = None  # it died before it could send its result
                results.close()
                process.join()
                if outcome is None and not again:
                    waiting.appendleft((index, True))
                    continue
                if outcome is None:
                    outcome = Outcome(items[index][0], error=_ended(items[index][0], process))
                done[index] = outcome
            while given in done:
                yield done.pop(given)
                given += 1
    finally:
        os.close(held)  # every worker still at work ends itself
        for worker in running.values():
            worker.process.kill()
        for worker in running.values():
            worker.process.join()
        for results in running:
            results.close()
        os.close(lifeline)


CONNECT = 'distributed.comm.timeouts.connect'
"""Dask's setting of how long a connection may take (30 s unless set): the bound used here."""


def _connection_failure(scheduler, exc, seconds):
    """Return the line that says why no scheduler answered at ``scheduler``."""
    scheme = scheduler.split('://', 1)[0] if '://' in scheduler else ''
    if isinstance(exc, TimeoutError):
        said = (f'no Dask scheduler answered within {seconds:g} s ({CONNECT}; the '
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
    Return the connection bound (s) once a Dask scheduler answered at ``scheduler``.

    Dask's client waits for a scheduler's first answer without a bound (a port that accepts
    and says nothing, a dashboard's HTTP port): here a first connection, answer included,
    is given Dask's own connect bound (:data:`CONNECT`), then closed. FleetError otherwise.
    """
    import asyncio
    import dask
    from dask.utils import parse_timedelta
    from distributed.comm import connect
    from distributed.security import Security

    seconds = parse_timedelta(dask.config.get(CONNECT), default='seconds')

    async def answered():
        comm = await connect(scheduler, timeout=seconds,
                             **Security().get_connection_args('client'))
        await comm.close()

    try:
        # the bound of the whole, answer included; connect, failing, says why first
        asyncio.run(asyncio.wait_for(answered(), seconds + min(seconds, 1)))
    except (OSError, ValueError, TypeError, asyncio.TimeoutError) as exc:
        raise FleetError(_connection_failure(scheduler, exc, seconds)) from None
    return seconds


def _dask(items, jobs, scheduler):
    """
    Yield read_bag(*item) for each item, in order, from a Dask cluster's workers.

    scheduler: the address of a running cluster's scheduler; None starts a local cluster of
    ``jobs`` worker processes (no more than the items) of one thread each, closed at the end.
    A task whose workers died (Dask tries it on others first) is that item's failed Outcome.
    """
    from dask.distributed import Client, LocalCluster
    seconds = _reach(scheduler) if scheduler is not None else None
    # dashboard_address ':0': the scheduler's HTTP server on a free port (with None it still
    # tries 8787, and warns on stderr when another cluster, or another run, holds it)
    cluster = None if scheduler is not None else LocalCluster(
        n_workers=min(jobs, len(items)), threads_per_worker=1, dashboard_address=':0')
    try:
        try:
            client = Client(scheduler, timeout=seconds) if cluster is None else Client(cluster)
        except (OSError, ValueError, TypeError) as exc:
            raise FleetError(_connection_failure(scheduler, exc, seconds)) from None
        with client:
            futures = client.map(read_bag, *zip(*items), pure=False)
            for item, future in zip(items, futures):
                try:
                    yield future.result()
                except Exception as exc:  # the task's failure (its workers died), not the job's
                    said = ' '.join(str(exc).split())
                    yield Outcome(item[0], error=f'{item[0]}: its Dask task failed: '
                                  f'{type(exc).__name__}{": " if said else ""}{said[:300]}')
    except BaseException:  # stopped (Ctrl-C, SIGTERM, stdout gone): no bag is waited for
        if cluster is not None:
            _stop_at_once(cluster)
        raise
    finally:
        if cluster is not None:
            cluster.close()


def _stop_at_once(cluster):
    """
    End a local cluster's workers at once, quietly, in the middle of their bags.

    Closed as usual, a nanny waits for its worker's bag to be done (up to 4 s), then kills it
    and logs how on stderr; its worker logs the tasks it drops. Here the worker processes,
    this process's children, are killed first, and Dask's logging of the ended cluster
    dropped with the run.
    """
    import logging
    logging.getLogger('distributed').setLevel(logging.CRITICAL)
    for worker in multiprocessing.active_children():
        worker.kill()


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
    a --scheduler address that is empty.
    """
    if args.parquet is not None:
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            error("--parquet needs pyarrow, the 'bag' extra: " + arguments.install_hint('bag'))
    if args.scheduler is not None and not args.scheduler.strip():
        error(f"--scheduler {args.scheduler!r}: no address (a Dask scheduler's, such as "
              'tcp://HOST:8786)')
    if args.engine == 'dask':
        try:
            import dask.distributed  # noqa: F401
        except ImportError:
            error("--engine dask needs dask.distributed, the 'fleet' extra: "
                  + arguments.install_hint('fleet'))


def _forget(path):
    """Remove the Parquet file of a bag that has none in this run (an earlier run's)."""
    try:
        os.unlink(path)
    except FileNotFoundError:
        pass
    except OSError as exc:
        raise FleetError(f'--parquet: cannot remove {path}, the file of a bag that has none '
                         f'in this run: {exc.strerror or exc}') from None


def _collect(items, args, out):
    """Run the jobs; write each bag's rows to ``out`` (or None), and what went wrong on stderr."""
    progress = FleetProgress(len(items))
    done = []
    if out is not None:
        out.write(','.join(['bag'] + csv_header(args.seq)) + '\n')
    try:
        for item, outcome in zip(items, outcomes(items, args.jobs, args.engine,
                                                 args.scheduler)):
            progress.add(outcome)
            if outcome.status != 'ok':
                progress.done()
                said = (f'error: bag: {outcome.error}' if outcome.error is not None
                        else f'bag: skipped: {outcome.skipped}')
                sys.stderr.write(f'{PROG}: {said}\n')
                if item[2] is not None:
                    _forget(item[2])
            elif out is not None:
                out.write(outcome.rows)
            outcome.rows = None
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
    output_file.check_outputs([('--csv', args.csv), ('--parquet', args.parquet)], bags, error)
    names = [None] * len(bags)
    if args.parquet is not None:
        bag_parquet.directory(args.parquet, error)
        names = [os.path.join(args.parquet, n) for n in bag_parquet.file_names(bags)]
        try:
            bag_parquet.begin(args.parquet)
        except OSError as exc:
            error(f'--parquet: cannot remove the manifest of an earlier run in {args.parquet}: '
                  f'{exc.strerror or exc}')
    items = [(path, args, name) for path, name in zip(bags, names)]
    try:
        return _write(items, args, error)
    except FleetError as exc:
        error(str(exc))


def _write(items, args, error):
    """Run the jobs, write the CSV, the manifest and the summary; return the exit status."""
    from rot_tools.io.report import to_json, to_yaml

    if args.csv == '-':
        done = []
        output_file.to_stdout(lambda out: done.extend(_collect(items, args, out)))
    elif args.csv is not None:
        try:
            with output_file.complete_or_nothing(args.csv, 'w', encoding='utf-8',
                                                 newline='') as out:
                done = _collect(items, args, out)
        except OSError as exc:
            error(f'--csv: cannot write {args.csv}: {exc.strerror or exc}')
    else:
        done = _collect(items, args, None)
    if args.parquet is not None:
        try:
            bag_parquet.finish(args.parquet, [(o.path, o.status, os.path.basename(name))
                                              for o, (_, _, name) in zip(done, items)])
        except OSError as exc:
            error(f'--parquet: cannot write the manifest in {args.parquet}: '
                  f'{exc.strerror or exc}')
    data = fleet_summary(done)
    if args.csv != '-':
        text = to_json if args.json else to_yaml
        output_file.to_stdout(lambda out: out.write(text(data, precision=args.precision)))
    return 1 if data['fleet']['failed'] else 0
