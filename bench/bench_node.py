"""
Node benchmark: rotation_node against the same job written the usual way and a bare relay.

Processes (all started here, all on the loopback of one DDS domain of their own):

- ``rotation_node`` by its console script, as a user starts it, with
  ``publish_markers:=false`` (``--markers`` adds a second one with the markers on);
- ``bench/usual_node.py``: the same job written the usual way — message objects, scipy's
  ``Rotation`` per message, fresh messages for the six per-input outputs;
- ``bench/relay_node.py``: the same six outputs with constant content made once, no math —
  rclpy's own ceiling;
- ``bench/pose_flooder.py``: publishes PoseStamped on ``~/pose`` of one of them at a set
  rate, stamping each message with the wall clock just before publishing;
- this process: subscribes ``~/screw`` (TwistStamped) of each and records, per message,
  the receive time minus the header stamp (the latency through the node).

All three are plain rclpy nodes on rclpy's SingleThreadedExecutor, started with
``--ros-args -r __node:=NAME`` and flooded the same way. All run all the time; the trials go
round them, rate by rate (500 to 20000 msg/s offered, 3 s each by default), in three rounds,
the order rotating. Delivered msg/s is the best round's (what the process can do; a round
disturbed by other work on the machine is left out), latency and CPU the median; a p99
ratio is the median of each round's ratio (the trials of a round at one rate run one after
the other, so a disturbance falls on both sides). Before measuring, every output of each
node is seen to arrive (discovery is awaited by messages flowing, never by sleeping);
during the trials only ``~/screw`` is subscribed, while each node still publishes all of its
outputs for every input.

Per trial: delivered msg/s (screw messages received / flood duration), the fraction lost,
latency p50 / p99, and the node process's CPU time per delivered message (from
/proc/PID/stat). The goals: rotation_node's sustained throughput (the most it delivered at
any offered rate) ≥ 0.9 × the usual way's (the relay's is shown beside it); its p99 ≤ 2 × the
relay's at every rate both sustain (≤ 1 % lost) unsaturated (each process using at most
UNSATURATED of a core: nearer its ceiling a p99 measures a queue's length); and the slowest
of its first 10,000 messages ≤ 20 ms, measured first, before the flood, by
bench_first_calls.py's node path (the ``~/pose`` callback of a fresh node called on 10,000
different poses, each timed alone). Not a test: it prints ratios and asserts nothing.

Run: ``.venv/bin/python bench/bench_node.py`` (options: --help). The domain is
$BENCH_ROS_DOMAIN_ID or one derived from the pid; ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST.
"""

import argparse
import json
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from typing import NamedTuple

import benchlib

BENCH = Path(__file__).resolve().parent
RATES = (500, 1000, 1500, 2000, 5000, 10000, 20000)
USUAL_GOAL = 0.9
"""rotation_node's sustained msg/s ≥ this × the usual way's."""
LATENCY_GOAL = 2.0
"""rotation_node's p99 ≤ this × the relay's."""
FIRST_MESSAGES = 10_000
FIRST_GOAL_MS = 20.0
"""The slowest of rotation_node's first FIRST_MESSAGES messages."""
LOSS_OK = 0.01
"""A rate is sustained when at most 1 % of the inputs are lost."""
UNSATURATED = 0.8
"""Latency is compared where both processes use at most this many CPU seconds a second."""
OUTPUTS = ('rotation_matrix', 'quaternion', 'axis_angle', 'euler_angles', 'rpy', 'screw')
"""The six outputs every target publishes for every input."""
MARKER_OUTPUTS = ('screw_axis', 'markers')
"""What rotation_node publishes besides, with publish_markers (at a limited rate)."""


class Target(NamedTuple):
    """A process under test: its node name, table label, program, ROS arguments, outputs."""

    node: str
    label: str
    program: str
    """'node' (rotation_node by its console script) or a script of bench/."""
    params: tuple
    """After --ros-args, besides the node's name."""
    outputs: tuple


TARGETS = {
    'rot_tools': Target('bench_rot_tools', 'rot_tools', 'node',
                        ('-p', 'publish_markers:=false'), OUTPUTS),
    'usual': Target('bench_usual', 'usual way', 'usual_node.py', (), OUTPUTS),
    'relay': Target('bench_relay', 'relay', 'relay_node.py', (), OUTPUTS),
}
"""The processes measured, in table order."""

MARKERS = Target('bench_rot_tools_markers', 'rot_tools, markers on', 'node', (),
                 OUTPUTS + MARKER_OUTPUTS)
"""rotation_node with its pictures (--markers)."""


def console_script(python, name):
    """Return the console script ``name`` next to ``python``, else on PATH."""
    script = Path(python).parent / name
    if script.exists():
        return str(script)
    found = shutil.which(name)
    if not found:
        raise SystemExit(f'bench_node: no {name} console script (pip install -e .)')
    return found


def target_command(python, target):
    ros_args = ['--ros-args', '-r', f'__node:={target.node}', *target.params]
    if target.program == 'node':
        return [console_script(python, 'rotation_node'), *ros_args]
    return [python, str(BENCH / target.program), *ros_args]


def cpu_seconds(pid):
    """User + system CPU time of a process, from /proc (Linux)."""
    with open(f'/proc/{pid}/stat', encoding='ascii') as f:
        fields = f.read().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def _own_cpu():
    t = os.times()
    return t.user + t.system


def percentile(sorted_values, q):
    if not sorted_values:
        return float('nan')
    k = min(len(sorted_values) - 1, max(0, int(round(q * (len(sorted_values) - 1)))))
    return sorted_values[k]


OUTPUT_TYPES = {}
"""{output: message class}, filled by Measurer (rclpy's message packages load there)."""


class Measurer:
    """The subscribing side: an rclpy node in this process, spun in a thread."""

    def __init__(self):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import QoSProfile
        from rclpy.signals import SignalHandlerOptions
        from geometry_msgs.msg import QuaternionStamped, TwistStamped, Vector3Stamped
        from std_msgs.msg import Float64MultiArray
        from visualization_msgs.msg import Marker, MarkerArray

        self._rclpy = rclpy
        # No rclpy signal handlers here: Ctrl-C must raise KeyboardInterrupt in the main
        # thread, so that the harness stops the processes it started.
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node('bench_node_measurer')
        OUTPUT_TYPES.update(
            rotation_matrix=Float64MultiArray, quaternion=QuaternionStamped,
            axis_angle=Vector3Stamped, euler_angles=Vector3Stamped, rpy=Vector3Stamped,
            screw=TwistStamped, screw_axis=Marker, markers=MarkerArray)
        qos = QoSProfile(depth=10)  # the outputs' QoS: reliable, keep last 10
        self.records = {t: [] for t in TARGETS}
        self.seen = {(t, o): 0 for t, target in TARGETS.items() for o in target.outputs}
        self._extra = []
        for name, target in TARGETS.items():
            for output in target.outputs:
                topic = f'/{target.node}/{output}'
                if output == 'screw':
                    callback = self._recorder(name)
                else:
                    callback = self._counter(name, output)
                sub = self.node.create_subscription(OUTPUT_TYPES[output], topic, callback, qos)
                if output != 'screw':
                    self._extra.append(sub)
        # (The same executor for every target: its cost falls on all trials alike.)
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self._thread = benchlib.spin_in_thread(rclpy, self.executor)

    def _recorder(self, target):
        records = self.records[target]
        seen = self.seen
        now = time.time_ns

        def on_screw(msg):
            stamp = msg.header.stamp
            records.append((now(), stamp.sec * 1_000_000_000 + stamp.nanosec))
            seen[(target, 'screw')] += 1
        return on_screw

    def _counter(self, target, output):
        seen = self.seen

        def on_output(msg):
            seen[(target, output)] += 1
        return on_output

    def drop_extra_subscriptions(self):
        """Keep only ~/screw subscribed, so this process stays light during the trials."""
        for sub in self._extra:
            self.node.destroy_subscription(sub)
        self._extra = []

    def close(self):
        self._rclpy.try_shutdown()
        self._thread.join(timeout=2.0)


class Harness:
    """The target processes, the flooder, the measurer; trials; clean shutdown."""

    def __init__(self, logdir):
        self.logdir = logdir
        self.procs = {}
        self.logs = []
        self.flooder = None
        self.measurer = None

    def _log(self, name):
        log = open(os.path.join(self.logdir, f'{name}.log'), 'w')
        self.logs.append(log)
        return log

    def start(self):
        for name, target in TARGETS.items():
            self.procs[name] = subprocess.Popen(target_command(sys.executable, target),
                                                stdout=self._log(name),
                                                stderr=subprocess.STDOUT)
        self.measurer = Measurer()
        topics = [f'/{t.node}/pose' for t in TARGETS.values()]
        self.flooder = subprocess.Popen(
            [sys.executable, str(BENCH / 'pose_flooder.py')] + topics,
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=self._log('flooder'),
            text=True)
        line = self.flooder.stdout.readline().strip()
        if line != 'ready':
            self.fail(f'pose_flooder did not get ready: {line!r}')

    def fail(self, why):
        for name, proc in self.procs.items():
            if proc.poll() is not None:
                why += f'\n{name} exited with {proc.returncode}; its log:\n'
                why += Path(self.logdir, f'{name}.log').read_text()[-2000:]
        raise RuntimeError(why)

    def command(self, line):
        self.flooder.stdin.write(line + '\n')
        self.flooder.stdin.flush()
        reply = self.flooder.stdout.readline().split()
        if not reply or reply[0] != 'done':
            self.fail(f'pose_flooder answered {reply!r} to {line!r}')
        return int(reply[1]), float(reply[2])

    def warm_up(self, timeout=60.0):
        """Flood slowly until every output of every target has arrived here."""
        deadline = time.monotonic() + timeout
        for name, target in TARGETS.items():
            while not all(self.measurer.seen[(name, o)] for o in target.outputs):
                if time.monotonic() > deadline:
                    missing = [o for o in target.outputs if not self.measurer.seen[(name, o)]]
                    self.fail(f'{name}: no message on {", ".join(missing)} after '
                              f'{timeout:.0f} s')
                self.command(f'flood /{target.node}/pose 100 0.2')
                time.sleep(0.1)
        self.measurer.drop_extra_subscriptions()
        time.sleep(0.2)

    def trial(self, name, rate, seconds):
        records = self.measurer.records[name]
        records.clear()
        pid = self.procs[name].pid
        cpu0, fl0, me0 = cpu_seconds(pid), cpu_seconds(self.flooder.pid), _own_cpu()
        sent, elapsed = self.command(f'flood /{TARGETS[name].node}/pose {rate} {seconds}')
        # Drain: wait until nothing new has arrived for 0.15 s (at most 2 s).
        end = time.monotonic() + 2.0
        last = -1
        while len(records) != last and time.monotonic() < end:
            last = len(records)
            time.sleep(0.15)
        cpu = cpu_seconds(pid) - cpu0
        flooder_cpu, own_cpu = cpu_seconds(self.flooder.pid) - fl0, _own_cpu() - me0
        got = list(records)
        lat = sorted((recv - stamp) / 1e6 for recv, stamp in got)
        return {'target': name, 'rate': rate, 'sent': sent, 'sent_rate': sent / elapsed,
                'received': len(got), 'delivered': len(got) / elapsed,
                'loss': 1.0 - len(got) / sent, 'p50': percentile(lat, 0.5),
                'p99': percentile(lat, 0.99), 'cpu_us': cpu / max(1, len(got)) * 1e6,
                'node_load': cpu / elapsed, 'flooder_load': flooder_cpu / elapsed,
                'measurer_load': own_cpu / elapsed}

    def stop(self):
        if self.flooder is not None and self.flooder.poll() is None:
            try:
                self.flooder.stdin.write('quit\n')
                self.flooder.stdin.flush()
            except OSError:
                pass
        for proc in self.procs.values():
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
        for proc in list(self.procs.values()) + [p for p in [self.flooder] if p]:
            try:
                proc.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        if self.measurer is not None:
            self.measurer.close()
        for log in self.logs:
            log.close()


def first_messages(messages):
    """rotation_node's first ``messages`` ~/pose callbacks, in a fresh process (markers off)."""
    out = subprocess.run([sys.executable, str(BENCH / 'bench_first_calls.py'), '--node', 'off',
                          '--messages', str(messages)],
                         capture_output=True, text=True, timeout=600)
    if out.returncode != 0:
        raise RuntimeError(f'bench_first_calls --node off: {out.stderr.strip()[-2000:]}')
    return json.loads(out.stdout.strip().splitlines()[-1])[0]


def summarise(trials, rates):
    """
    Per (target, rate): the best round's delivery, the median of the other figures.

    Delivered msg/s and loss are the best of the rounds (most delivered): what a process
    can do, with a round disturbed by other work on the machine left out. Latency and CPU
    per message are the medians.
    """
    keys = ('sent_rate', 'p50', 'p99', 'cpu_us', 'node_load', 'flooder_load',
            'measurer_load')
    out = {}
    for target in TARGETS:
        for rate in rates:
            runs = [t for t in trials if t['target'] == target and t['rate'] == rate]
            best = max(runs, key=lambda t: t['delivered'])
            out[(target, rate)] = {k: benchlib.median([t[k] for t in runs]) for k in keys}
            out[(target, rate)].update(delivered=best['delivered'], loss=best['loss'])
    return out


def round_ratio(trials, node, other, rate, key):
    """Median over the rounds of node's ``key`` / other's in the same round, at ``rate``."""
    rounds = {}
    for t in trials:
        if t['rate'] == rate and t['target'] in (node, other):
            rounds.setdefault(t['round'], {})[t['target']] = t[key]
    return benchlib.median([r[node] / r[other] for r in rounds.values() if len(r) == 2])


def compare(summary, trials, rates, node, other):
    """
    Node against another: sustained throughput ratio, p99 ratios where both sustain, CPU.

    A p99 ratio is the median of each round's: the two trials of a round run one after the
    other, so a round disturbed by other work on the machine disturbs both.
    """
    best = {t: max(summary[(t, r)]['delivered'] for r in rates) for t in (node, other)}
    # Latency is compared at the rates both sustain (≤ 1 % lost) without being saturated
    # (≤ UNSATURATED of a core): nearer their ceiling a p99 is the length of a queue that
    # grows without bound as the load nears 1, and the shortfall is the throughput figure's
    # to show.
    both = [r for r in rates if all(summary[(t, r)]['loss'] <= LOSS_OK
                                    and summary[(t, r)]['node_load'] <= UNSATURATED
                                    for t in (node, other))]
    p99 = {r: round_ratio(trials, node, other, r, 'p99') for r in both}
    cpu = [summary[(node, r)]['cpu_us'] / summary[(other, r)]['cpu_us'] for r in rates]
    return {'node_msgs': best[node], 'other_msgs': best[other],
            'throughput_ratio': best[node] / best[other], 'p99_ratios': p99,
            'p99_ratio_worst': max(p99.values()) if p99 else float('nan'),
            'cpu_ratio': benchlib.median(cpu)}


def evaluate(summary, trials, rates):
    """Every comparison, keyed 'node vs other', and each target's highest sustained rate."""
    pairs = [('rot_tools', 'usual'), ('rot_tools', 'relay'), ('usual', 'relay'),
             ('rot_tools_markers', 'rot_tools')]
    ev = {f'{a} vs {b}': compare(summary, trials, rates, a, b) for a, b in pairs
          if a in TARGETS and b in TARGETS}
    ev['sustained_rate'] = {
        t: max([r for r in rates if summary[(t, r)]['loss'] <= LOSS_OK], default=0)
        for t in TARGETS}
    return ev


def goal_rows(ev, first):
    """(figure, measured, goal, met?) of the node goals; the first messages' in ms of CPU."""
    usual, relay = ev['rot_tools vs usual'], ev['rot_tools vs relay']
    return [
        ('node throughput / usual way', usual['throughput_ratio'], f'>= {USUAL_GOAL:g}',
         usual['throughput_ratio'] >= USUAL_GOAL),
        ("node p99 latency / relay's", relay['p99_ratio_worst'], f'<= {LATENCY_GOAL:g}',
         relay['p99_ratio_worst'] <= LATENCY_GOAL),
        (f"slowest of the first {first['calls']:,} messages, ms of CPU",
         first['worst_cpu_ms'], f'<= {FIRST_GOAL_MS:g}', first['worst_cpu_ms'] <= FIRST_GOAL_MS),
    ]


def print_results(summary, ev, first, rates, seconds, repeats):
    names = list(TARGETS)
    labels = [TARGETS[t].label for t in names]
    rows = [[f'{r}'] + [f"{summary[(t, r)]['delivered']:.0f} ({summary[(t, r)]['loss']:.0%})"
                        for t in names] for r in rates]
    benchlib.print_table(
        f'Delivered msg/s (lost) under a PoseStamped flood (>= {seconds:g} s per trial, '
        f'best of {repeats} interleaved rounds)', ['offered msg/s'] + labels, rows)
    rows = [[f'{r}'] + [f"{summary[(t, r)]['p50']:.2f} / {summary[(t, r)]['p99']:.2f}"
                        for t in names] for r in rates]
    benchlib.print_table('Latency p50 / p99 ms (receive time of ~/screw - input header stamp)',
                         ['offered msg/s'] + labels, rows)
    rows = []
    for r in rates:
        cpu = [f"{summary[(t, r)]['cpu_us']:.0f} ({summary[(t, r)]['node_load']:.2f})"
               for t in names]
        rows.append([f'{r}', *cpu, f"{summary[(names[-1], r)]['flooder_load']:.2f}",
                     f"{summary[(names[-1], r)]['measurer_load']:.2f}"])
    benchlib.print_table(
        'CPU us per delivered message (node process CPU s/s); flooder and measurer CPU s/s '
        f'during the {TARGETS[names[-1]].label} trial',
        ['offered msg/s'] + labels + ['flooder', 'measurer'], rows)
    rows = []
    for key, c in ev.items():
        if key == 'sustained_rate':
            continue
        p99 = ', '.join(f'{r}: {v:.2f}' for r, v in c['p99_ratios'].items()) or 'none'
        rows.append([key, f"{c['node_msgs']:.0f} / {c['other_msgs']:.0f}",
                     f"{c['throughput_ratio']:.2f}", f"{c['p99_ratio_worst']:.2f}", p99,
                     f"{c['cpu_ratio']:.2f}"])
    benchlib.print_table(
        'Comparisons (sustained throughput = most msg/s delivered at any offered rate; p99 '
        'ratios at the offered rates both sustain with <= 1 % lost, each using at most '
        f"{UNSATURATED:g} CPU s/s, the median of each round's)",
        ['a vs b', 'msg/s', 'throughput ratio', 'worst p99 ratio', 'p99 ratio by rate',
         'CPU/msg ratio'], rows)
    sustained = ', '.join(f'{TARGETS[t].label} {r}' for t, r in ev['sustained_rate'].items())
    print(f'  highest offered rate sustained (<= {LOSS_OK:.0%} lost): {sustained}')
    print(f"  first {first['calls']:,} messages of a fresh rotation_node (~/pose callback, "
          f"markers off): first {first['first_ms']:.2f} ms, median "
          f"{first['median_ms'] * 1e3:.0f} us, worst {first['worst_ms']:.2f} ms wall "
          f"(#{first['worst_at'] + 1}), {first['worst_cpu_ms']:.2f} ms CPU "
          f"(#{first['worst_cpu_at'] + 1})")
    benchlib.print_table('Node goals', ['figure', 'measured', 'goal', 'met?'],
                         [[f, f'{v:.2f}', g, 'yes' if ok else 'NO'] for f, v, g, ok in
                          goal_rows(ev, first)])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--rates', type=lambda s: tuple(int(x) for x in s.split(',')),
                        default=RATES, help='offered rates, msg/s (1000,2000,5000,10000,'
                        '20000)')
    parser.add_argument('--seconds', type=float, default=3.0,
                        help='per trial, at least (3); longer where needed for --min-messages')
    parser.add_argument('--min-messages', type=int, default=1000,
                        help='messages per trial at least, so p99 rests on 10+ samples (1000)')
    parser.add_argument('--repeats', type=int, default=3,
                        help='interleaved rounds of every (node, rate) trial (3); delivery is '
                        "the best round's, latency and CPU the median")
    parser.add_argument('--first', type=int, default=FIRST_MESSAGES,
                        help=f"rotation_node's first messages timed ({FIRST_MESSAGES})")
    parser.add_argument('--markers', action='store_true',
                        help='also measure rotation_node with publish_markers on')
    parser.add_argument('--json', metavar='PATH', help='also write the figures as JSON')
    args = parser.parse_args(argv)
    if args.markers:
        TARGETS['rot_tools_markers'] = MARKERS

    domain = os.environ.get('BENCH_ROS_DOMAIN_ID') or str(1 + (os.getpid() * 7 + 13) % 101)
    os.environ['ROS_DOMAIN_ID'] = domain
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_STATIC_PEERS', None)
    print(f'bench_node: {benchlib.machine_line()}, {time.strftime("%Y-%m-%d %H:%M %Z")}; '
          f'ROS_DOMAIN_ID={domain}, discovery LOCALHOST', flush=True)
    first = first_messages(args.first)
    print(f"  first {args.first:,} messages timed (worst {first['worst_cpu_ms']:.2f} ms CPU)",
          flush=True)

    # SIGINT and SIGTERM end this script through the finally that stops the processes
    # (SIGINT explicitly: a shell may start a background job with it ignored).
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    trials = []
    with tempfile.TemporaryDirectory(prefix='rot_tools_bench_') as logdir:
        harness = Harness(logdir)
        try:
            t0 = time.monotonic()
            harness.start()
            harness.warm_up()
            print(f'  processes up, every output of every target seen '
                  f'({time.monotonic() - t0:.1f} s)', flush=True)
            order = list(TARGETS)
            for rep in range(args.repeats):
                for i, rate in enumerate(args.rates):
                    shift = (rep + i) % len(order)
                    for target in order[shift:] + order[:shift]:
                        seconds = max(args.seconds, args.min_messages / rate)
                        trials.append(dict(harness.trial(target, rate, seconds), round=rep))
                print(f'  repetition {rep + 1}/{args.repeats} done', flush=True)
        finally:
            harness.stop()
    summary = summarise(trials, args.rates)
    ev = evaluate(summary, trials, args.rates)
    print_results(summary, ev, first, args.rates, args.seconds, args.repeats)
    goals = [{'figure': f, 'measured': v, 'goal': g, 'met': ok}
             for f, v, g, ok in goal_rows(ev, first)]
    evaluation = {k: {**v, 'p99_ratios': {str(r): x for r, x in v['p99_ratios'].items()}}
                  if k != 'sustained_rate' else v for k, v in ev.items()}
    benchlib.write_json(args.json, {
        'trials': trials, 'goals': goals, 'evaluation': evaluation, 'first': first,
        'summary': {f'{t}@{r}': v for (t, r), v in summary.items()}})


if __name__ == '__main__':
    try:
        main()
    except KeyboardInterrupt:
        print('bench_node: interrupted; the processes it started are stopped', file=sys.stderr)
        sys.exit(130)
