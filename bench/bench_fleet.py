"""
``rot-tools bag`` over a fleet: --jobs 2 against --jobs 1, and one bag against a bare read.

The fleet is --copies copies (default 32) of the real recording
(../shared/data/jackal_imu_odometry.bag: 3,061 Imu and 3,060 Odometry messages, a ROS 1 bag)
in one directory. Each command runs as a user runs it (the console script, a subprocess,
its summary discarded), --repeat times, the repetitions interleaved (the order rotating from
one to the next), and the median of each taken:

- ``rot-tools bag FLEET --jobs 1`` and ``rot-tools bag FLEET --jobs 2``: goal, the second
  ≥ 1.6 × as fast on 2 cores. Start-up (Python, NumPy, rosbags: about 0.3 s) is paid once
  for the whole fleet and one bag takes about 0.08 s, so the ratio nears the number of
  cores as the bags get more: with 8 copies start-up bounds it near 1.5, with 32 not;
- ``rot-tools bag ONE`` against reading the same bag with rosbags alone, deserialising every
  message (its AnyReader, the loop users write): goal, ≤ 1.5 × the bare read's time. Both
  are whole commands, Python's start-up included. Messages per second are printed for each.

Both goals are ratios of wall times measured side by side; on a machine shared with other
work they move with its load (printed at the start). So the same run also times a plain CPU
loop, the same work in 1 and in 2 forked processes: the speed-up the machine offers at that
moment, the ceiling of --jobs 2's.

    .venv/bin/python bench/bench_fleet.py [--copies 32] [--repeat 5] [--json FILE]
"""

import argparse
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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--copies', type=int, default=32)
    parser.add_argument('--repeat', type=int, default=5)
    parser.add_argument('--json', help='write the figures here (for run_all.py)')
    args = parser.parse_args()
    rot_tools = str(Path(sys.executable).parent / 'rot-tools')
    print(f'bench_fleet: {benchlib.machine_line()}')
    with tempfile.TemporaryDirectory(prefix='rot_tools_fleet_') as tmp:
        fleet = Path(tmp, 'fleet')
        fleet.mkdir()
        for k in range(args.copies):
            shutil.copy(REAL, fleet / f'jackal_{k:03d}.bag')
        one = fleet / 'jackal_000.bag'
        times = benchlib.interleaved({
            'jobs 1': command([rot_tools, 'bag', str(fleet), '--jobs', '1']),
            'jobs 2': command([rot_tools, 'bag', str(fleet), '--jobs', '2']),
            'one bag': command([rot_tools, 'bag', str(one)]),
            'bare read': command([sys.executable, '-c', BARE_READ, str(one)]),
            'cpu loop 1': command([sys.executable, '-c', CPU_LOOP, '1']),
            'cpu loop 2': command([sys.executable, '-c', CPU_LOOP, '2']),
        }, args.repeat)
    seconds = {name: benchlib.median(values) for name, values in times.items()}
    speedup = seconds['jobs 1'] / seconds['jobs 2']
    read_ratio = seconds['one bag'] / seconds['bare read']
    ceiling = seconds['cpu loop 1'] / seconds['cpu loop 2']
    counts = {'jobs 1': args.copies * MESSAGES, 'jobs 2': args.copies * MESSAGES,
              'one bag': MESSAGES, 'bare read': MESSAGES, 'cpu loop 1': 0, 'cpu loop 2': 0}
    benchlib.print_table(
        f'{args.copies} copies of the recording, {MESSAGES} messages each; median of '
        f'{args.repeat}', ['command', 'seconds', 'messages/s'],
        [[name, f'{s:.3f}', f'{counts[name] / s:,.0f}' if counts[name] else '-']
         for name, s in seconds.items()])
    rows = [['--jobs 2 speed-up over --jobs 1', f'{speedup:.2f}', f'>= {SPEEDUP_GOAL:g}',
             'yes' if speedup >= SPEEDUP_GOAL else 'NO'],
            ['one bag / bare rosbags read (time)', f'{read_ratio:.2f}', f'<= {READ_GOAL:g}',
             benchlib.verdict(read_ratio, READ_GOAL)],
            ['(the machine now: a CPU loop in 2 processes / 1)', f'{ceiling:.2f}', '-', '-']]
    benchlib.print_table('Goals', ['figure', 'measured', 'goal', 'met?'], rows)
    benchlib.write_json(args.json, {
        'copies': args.copies, 'repeat': args.repeat, 'seconds': seconds,
        'speedup': speedup, 'speedup_goal': SPEEDUP_GOAL, 'read_ratio': read_ratio,
        'read_goal': READ_GOAL, 'ceiling': ceiling,
        'messages_per_second': {name: counts[name] / s for name, s in seconds.items()}})
    return 0


if __name__ == '__main__':
    sys.exit(main())
