"""
``rot-tools bag`` over a fleet: --jobs 2 against --jobs 1, and one bag against a bare read.

The fleet is --copies copies of the real recording. Each command runs as a user runs it
(the console script), --repeat times, interleaved; medians are compared. Goals: the job
``--jobs 2`` ≥ 1.6 × ``--jobs 1`` (timed after start-up, in a process that imported the
package already: ``JOB``), and one bag ≤ 1.5 × reading it with rosbags alone (whole
commands). A CPU loop in 1 and 2 processes shows the speed-up the machine offers meanwhile.

    .venv/bin/python bench/bench_fleet.py [--copies 8] [--repeat 5] [--json FILE]
"""

import argparse
import compileall
from pathlib import Path
import shutil
import subprocess
import sys
import tempfile

import benchlib

REPO = Path(__file__).resolve().parents[1]
REAL = REPO.parent / 'shared' / 'data' / 'jackal_imu_odometry.bag'
MESSAGES = 3061 + 3060
SPEEDUP_GOAL = 1.6
READ_GOAL = 1.5

BARE_READ = r"""
import sys
from pathlib import Path
from rosbags.highlevel import AnyReader

with AnyReader([Path(sys.argv[1])]) as reader:
    for conn, t, raw in reader.messages():
        reader.deserialize(raw, conn.msgtype)
"""


JOB = r"""
import contextlib, os, sys, time
from rot_tools.cli import fleet, main  # noqa: F401 (imported before the clock starts)
from rosbags.highlevel import AnyReader  # noqa: F401

with open(os.devnull, 'w') as devnull, contextlib.redirect_stdout(devnull):
    start = time.perf_counter()
    status = main.main(['bag', sys.argv[1], '--jobs', sys.argv[2]])
    seconds = time.perf_counter() - start
sys.exit(status or print(seconds))
"""


CPU_LOOP = r"""
import multiprocessing, sys

def work(_):
    return sum(range(3_000_000))

with multiprocessing.get_context('fork').Pool(int(sys.argv[1])) as pool:
    pool.map(work, range(8), chunksize=1)
"""


def command(args):
    """Return a zero-argument callable running ``args``; it exits on a failure."""
    def run():
        done = subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                              text=True)
        if done.returncode:
            sys.exit(f'{args[:3]} failed: {done.stderr[-2000:]}')
    return run


def job(fleet, jobs, seconds):
    """Return a zero-argument callable running ``JOB``; it appends the job's time to seconds."""
    def run():
        done = subprocess.run([sys.executable, '-c', JOB, str(fleet), str(jobs)],
                              capture_output=True, text=True)
        if done.returncode:
            sys.exit(f'the job --jobs {jobs} failed: {done.stderr[-2000:]}')
        seconds.append(float(done.stdout))
    return run


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--copies', type=int, default=8)
    parser.add_argument('--repeat', type=int, default=5)
    parser.add_argument('--json', help='write the figures here (for run_all.py)')
    args = parser.parse_args()
    rot_tools = str(Path(sys.executable).parent / 'rot-tools')
    print(f'bench_fleet: {benchlib.machine_line()}')
    # The package's bytecode, as an install writes it (the reference's libraries have theirs).
    compileall.compile_dir(REPO / 'rot_tools', quiet=1)
    with tempfile.TemporaryDirectory(prefix='rot_tools_fleet_') as tmp:
        fleet = Path(tmp, 'fleet')
        fleet.mkdir()
        for k in range(args.copies):
            shutil.copy(REAL, fleet / f'jackal_{k:03d}.bag')
        one = fleet / 'jackal_000.bag'
        jobs = {1: [], 2: []}
        times = benchlib.interleaved({
            'job, jobs 1': job(fleet, 1, jobs[1]),
            'job, jobs 2': job(fleet, 2, jobs[2]),
            'jobs 1': command([rot_tools, 'bag', str(fleet), '--jobs', '1']),
            'jobs 2': command([rot_tools, 'bag', str(fleet), '--jobs', '2']),
            'one bag': command([rot_tools, 'bag', str(one)]),
            'bare read': command([sys.executable, '-c', BARE_READ, str(one)]),
            'cpu loop 1': command([sys.executable, '-c', CPU_LOOP, '1']),
            'cpu loop 2': command([sys.executable, '-c', CPU_LOOP, '2']),
        }, args.repeat)
    seconds = {name: benchlib.median(values) for name, values in times.items()}
    seconds.update({f'job, jobs {n}': benchlib.median(values) for n, values in jobs.items()})
    speedup = seconds['job, jobs 1'] / seconds['job, jobs 2']
    whole = seconds['jobs 1'] / seconds['jobs 2']
    read_ratio = seconds['one bag'] / seconds['bare read']
    ceiling = seconds['cpu loop 1'] / seconds['cpu loop 2']
    counts = {'job, jobs 1': args.copies * MESSAGES, 'job, jobs 2': args.copies * MESSAGES,
              'jobs 1': args.copies * MESSAGES, 'jobs 2': args.copies * MESSAGES,
              'one bag': MESSAGES, 'bare read': MESSAGES, 'cpu loop 1': 0, 'cpu loop 2': 0}
    benchlib.print_table(
        f'{args.copies} copies of the recording, {MESSAGES} messages each; median of '
        f'{args.repeat}', ['command', 'seconds', 'messages/s'],
        [[name, f'{s:.3f}', f'{counts[name] / s:,.0f}' if counts[name] else '-']
         for name, s in seconds.items()])
    rows = [['--jobs 2 speed-up over --jobs 1 (the job)', f'{speedup:.2f}',
             f'>= {SPEEDUP_GOAL:g}', 'yes' if speedup >= SPEEDUP_GOAL else 'NO'],
            ['(the same, whole commands: start-up included)', f'{whole:.2f}', '-', '-'],
            ['one bag / bare rosbags read (time)', f'{read_ratio:.2f}', f'<= {READ_GOAL:g}',
             benchlib.verdict(read_ratio, READ_GOAL)],
            ['(the machine now: a CPU loop in 2 processes / 1)', f'{ceiling:.2f}', '-', '-']]
    benchlib.print_table('Goals', ['figure', 'measured', 'goal', 'met?'], rows)
    benchlib.write_json(args.json, {
        'copies': args.copies, 'repeat': args.repeat, 'seconds': seconds,
        'speedup': speedup, 'speedup_whole': whole, 'speedup_goal': SPEEDUP_GOAL,
        'read_ratio': read_ratio,
        'read_goal': READ_GOAL, 'ceiling': ceiling,
        'messages_per_second': {name: counts[name] / s for name, s in seconds.items()}})
    return 0


if __name__ == '__main__':
    sys.exit(main())
