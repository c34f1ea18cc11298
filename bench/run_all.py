"""
Run every benchmark (``make bench``): math, first calls, node, memory, overload, bags, IMU, goals.

Each script runs in its own process with this interpreter and prints its own tables; this
script then collects their figures (JSON) and prints every goal with the figure measured
and whether it is met. The overload runs: ~/pose back to back and at 10,000 msg/s, then /tf
in each of TF_OVERLOADS' scenarios (bench_overload.py --tf; ``large`` at 100 msg/s, beside a
bare rclpy /tf subscriber), each flooded back to back.

Run: ``.venv/bin/python bench/run_all.py [--quick]
[--skip math|first|node|memory|overload|overload-tf|bag|fleet|imu] [--json-dir DIR]``. ``--quick``
is a smoke run (smaller batch, fewer repetitions and rates, a short flood): its figures are
not the ones to quote.
"""

import argparse
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile
import time

import benchlib

BENCH = Path(__file__).resolve().parent
TF_OVERLOADS = ('large', 'reparent', 'jump')
"""bench_overload.py --tf scenarios run (back to back), beside the ~/pose flood."""


def run(script, args, json_path):
    cmd = [sys.executable, str(BENCH / script)] + args + ['--json', str(json_path)]
    print(f'\n$ {" ".join(cmd[1:])}', flush=True)
    start = time.monotonic()
    code = subprocess.call(cmd)
    print(f'({script}: {time.monotonic() - start:.0f} s, exit {code})', flush=True)
    if code != 0 or not json_path.exists():
        return None
    return json.loads(json_path.read_text())


def overload_rows(overload):
    """Goal rows of one bench_overload.py run: RSS, calls, publishing, SIGINT."""
    what = overload.get('flood', '~/pose')
    flood = (f"{what}, {overload['seconds']:.0f} s "
             f"{'back to back' if overload['rate'] == 'max' else 'at ' + overload['rate']}")
    goals, stop = overload['goals'], overload.get('sigint')
    rows = []
    if 'growth' in goals:
        rows += [['overload: node RSS growth', flood, f"{overload['growth_mb']:+.1f} MB",
                  '<= 50 MB', 'yes' if goals['growth'] else 'NO'],
                 [f"overload: RSS {overload['after']:.0f} s after - start", flood,
                  f"{overload['rss_after_mb'] - overload['rss_start_mb']:+.1f} MB",
                  '<= 20 MB', 'yes' if goals['returned'] else 'NO']]
    if 'tf_memory' in goals:
        bare = overload['beside_bare_tf']
        rows.append(['overload: node RSS growth beyond a bare /tf subscriber', flood,
                     f"{bare['growth_mb']:+.1f} MB max, {bare['kept_mb']:+.1f} MB after "
                     f"({bare['large_taken']} large taken)", '<= 20 MB',
                     'yes' if goals['tf_memory'] else 'NO'])
    rows.append(['overload: the node publishes, alive after', flood, f"{overload['answered']}",
                 '> 0', 'yes' if goals['alive'] else 'NO'])
    latency = overload['latency'].values()
    if 'answered' in goals:
        rows.append(['overload: slowest call', flood, f"{max(v['max'] for v in latency):.3f} s",
                     '<= 5 s', 'yes' if goals['answered'] else 'NO'])
    if 'latency' in goals:
        rows.append(['overload: worst service p99', flood,
                     f"{max(v['p99'] for v in latency):.3f} s", '<= 0.1 s',
                     'yes' if goals['latency'] else 'NO'])
    if 'sigint' in goals:
        rows.append(['overload: SIGINT during the flood', flood,
                     'dead before' if stop is None else
                     f"status {stop['status']}, {stop['seconds']:.2f} s",
                     '0, <= 1 s', 'yes' if goals['sigint'] else 'NO'])
    return rows


def goal_rows(math, node, memory, first=None, overload=None, fleet=None, tf_overloads=None,
              bag=None, flood=None, imu=None):
    rows = []
    if math:
        for r in math.get('batch', []):
            rows.append([f"batch {r['operation']}", f"vs {r['reference']}", f"{r['ratio']:.3f}",
                         benchlib.fmt_goal(r['goal']), benchlib.verdict(r['ratio'], r['goal'])])
        for r in math.get('batch', []):
            if 'memory_ratio' in r:
                rows.append([f"memory {r['operation']}", 'peak / (in + out)',
                             f"{r['memory_ratio']:.2f}", '<= 2', benchlib.verdict(
                                 r['memory_ratio'], 2.0)])
        for r in math.get('batch', []):
            ok = r['max_diff'] <= 1e-12
            scipy = r['reference'].startswith('scipy')  # the equality goal is scipy's
            rows.append([f"equal {r['operation']}", f"max |diff| vs {r['reference']}",
                         f"{r['max_diff']:.1e}", '<= 1e-12' if scipy else '- (note)',
                         ('yes' if ok else 'NO') if scipy else '-'])
        for r in math.get('single', []):
            rows.append([f"single {r['operation']}", f"vs {r['reference']}",
                         f"{r['ratio']:.3f}", benchlib.fmt_goal(r['goal']),
                         benchlib.verdict(r['ratio'], r['goal'])])
    if first:
        worst = max(first['functions'], key=lambda r: r['worst_cpu_ms'])
        rows.append(['first 1000 calls, every public function', f"worst: {worst['label']}",
                     f"{worst['worst_cpu_ms']:.3f} ms CPU", f"<= {first['goal_ms']:g} ms",
                     'yes' if first['met'] else 'NO'])
        wall = max(first['functions'], key=lambda r: r['worst_ms'])
        rows.append(['  (the same, wall clock)', f"worst: {wall['label']}",
                     f"{wall['worst_ms']:.3f} ms", '- (note)', '-'])
        for r in first['node']:
            rows.append([f"first {r['calls']} calls: {r['label']}", 'worst call',
                         f"{r['worst_cpu_ms']:.3f} ms CPU, {r['worst_ms']:.2f} wall", '-',
                         '-'])
    if node:
        for g in node['goals']:
            rows.append([g['figure'], 'markers off', f"{g['measured']:.2f}", g['goal'],
                         'yes' if g['met'] else 'NO'])
    if memory:
        rows.append(['node RSS growth under a 5 kHz flood', f"{memory['seconds']:.0f} s",
                     f"{memory['rss_end_mb'] - memory['rss_start_mb']:+.1f} MB",
                     'bounded', 'yes' if memory['bounded'] else 'NO'])
    if overload:
        rows += overload_rows(overload)
        for name, v in overload['latency'].items():
            rows.append([f'overload: ~/{name} p99', f"{v['unanswered']} unanswered",
                         f"{v['p99']:.3f} s", '<= 1 s', 'yes' if v['p99'] <= 1.0 else 'NO'])
    if flood:
        rows += overload_rows(flood)
    for tf in tf_overloads or ():
        rows += overload_rows(tf)
    if bag:
        rows.append(['rot-tools bag --csv, per message', 'the same job the usual way',
                     f"{bag['ratio']:.2f}", f"<= {bag['goal']:g}",
                     benchlib.verdict(bag['ratio'], bag['goal'])])
    if fleet:
        copies = f"{fleet['copies']} copies of the bag"
        rows.append(['rot-tools bag --jobs 2 speed-up over --jobs 1', f'{copies}, the job',
                     f"{fleet['speedup']:.2f}", f">= {fleet['speedup_goal']:g}",
                     'yes' if fleet['speedup'] >= fleet['speedup_goal'] else 'NO'])
        rows.append(['  (the same, whole commands: start-up included)', 'no goal',
                     f"{fleet['speedup_whole']:.2f}", '-', '-'])
        rows.append(['rot-tools bag, one bag', 'bare rosbags read',
                     f"{fleet['read_ratio']:.2f}", benchlib.fmt_goal(fleet['read_goal']),
                     benchlib.verdict(fleet['read_ratio'], fleet['read_goal'])])
        rows.append(['  (the machine then: a CPU loop, 2 processes / 1)', 'no goal',
                     f"{fleet['ceiling']:.2f}", '-', '-'])
    if imu:
        rows.append([f"rot-tools imu-check, {imu['messages']:,} Imu messages",
                     'rot-tools bag on the same', f"{imu['ratio']:.2f}",
                     f"<= {imu['goal']:g}", benchlib.verdict(imu['ratio'], imu['goal'])])
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--quick', action='store_true', help='smoke run, figures not quotable')
    parser.add_argument('--skip', choices=['math', 'first', 'node', 'memory', 'overload',
                                           'overload-tf', 'bag', 'fleet', 'imu'],
                        action='append', default=[])
    parser.add_argument('--json-dir', help='keep the JSON figures here')
    args = parser.parse_args(argv)

    print(f'run_all: {benchlib.machine_line()}, {time.strftime("%Y-%m-%d %H:%M")}')
    math_args = ['--n', '200000', '--repeats', '3', '--single-repeats', '5'] if args.quick \
        else []
    node_args = ['--rates', '500,2000,5000', '--repeats', '1', '--seconds', '1'] if args.quick \
        else []
    memory_args = ['--seconds', '5'] if args.quick else []
    first_args = ['--messages', '2000'] if args.quick else []
    overload_args = ['--seconds', '5', '--after', '3'] if args.quick else []
    fleet_args = ['--repeat', '1'] if args.quick else []
    bag_args = ['--repeat', '1'] if args.quick else []
    imu_args = ['--minutes', '2', '--repeat', '1'] if args.quick else []
    start = time.monotonic()
    with tempfile.TemporaryDirectory(prefix='rot_tools_bench_') as tmp:
        out = Path(args.json_dir or tmp)
        os.makedirs(out, exist_ok=True)
        math = first = node = memory = overload = flood = bag = fleet = imu = None
        if 'math' not in args.skip:
            math = run('bench_math.py', math_args, out / 'bench_math.json')
        if 'first' not in args.skip:
            first = run('bench_first_calls.py', first_args, out / 'bench_first_calls.json')
        if 'node' not in args.skip:
            node = run('bench_node.py', node_args, out / 'bench_node.json')
        if 'memory' not in args.skip:
            memory = run('bench_memory.py', memory_args, out / 'bench_memory.json')
        if 'overload' not in args.skip:
            overload = run('bench_overload.py', overload_args, out / 'bench_overload.json')
            flood = run('bench_overload.py', overload_args + ['--rate', '10000'],
                        out / 'bench_overload_10k.json')
        tf_overloads = []
        if 'overload-tf' not in args.skip:
            for scenario in TF_OVERLOADS:
                rate = ['--rate', '100'] if scenario == 'large' else []
                tf_overloads.append(run('bench_overload.py',
                                        overload_args + ['--tf', scenario] + rate,
                                        out / f'bench_overload_tf_{scenario}.json'))
        if 'bag' not in args.skip:
            bag = run('bench_bag.py', bag_args, out / 'bench_bag.json')
        if 'fleet' not in args.skip:
            fleet = run('bench_fleet.py', fleet_args, out / 'bench_fleet.json')
        if 'imu' not in args.skip:
            imu = run('bench_imu.py', imu_args, out / 'bench_imu.json')
        rows = goal_rows(math, node, memory, first, overload, fleet,
                         [tf for tf in tf_overloads if tf], bag, flood, imu)
    benchlib.print_table(f'Goals (ratios rot_tools / reference, first calls in ms; '
                         f'{time.monotonic() - start:.0f} s in all)',
                         ['figure', 'against', 'measured', 'goal', 'met?'], rows)
    missed = [f'{r[0]} ({r[1]})' for r in rows if r[-1] == 'NO']
    goals = [r for r in rows if r[-1] != '-']
    tail = f'; missed: {", ".join(missed)}' if missed else ''
    print(f'\n{len(goals) - len(missed)} of {len(goals)} goals met{tail}')
    failed = [s for s, res in (('math', math), ('first', first), ('node', node),
                               ('memory', memory), ('overload', overload),
                               ('overload', flood), ('bag', bag), ('fleet', fleet),
                               ('imu', imu))
              if s not in args.skip and res is None]
    failed += [f'overload --tf {scenario}' for scenario, res in zip(TF_OVERLOADS, tf_overloads)
               if res is None]
    if failed:
        print(f'run_all: {", ".join(failed)} benchmark failed (see above)', file=sys.stderr)
        return 1
    return 0


if __name__ == '__main__':
    sys.exit(main())
