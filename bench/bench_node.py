"""Node benchmark: rotation_node against a bare rclpy relay, flooded with PoseStamped.

Processes (all started here, all on the loopback of one isolated DDS domain):

- ``rotation_node`` (``python -m rot_tools.rotation_node``, node name ``bench_rot_tools``),
- ``bench/relay_node.py`` (node name ``bench_relay``): the same topics, types and QoS with
  constant content and no math, i.e. rclpy's own messaging limit,
- ``bench/pose_flooder.py``: publishes PoseStamped on ``~/pose`` of one of them at a set
  rate, stamping each message with the wall clock just before publishing,
- this process: subscribes ``~/screw`` (TwistStamped) of both and records, per message,
  the receive time minus the header stamp (the latency through the node).

Both nodes run all the time; the trials alternate between them, rate by rate, and are
repeated; each figure is the median over the repetitions. Before measuring, every one of the
five outputs of each node is seen to arrive (discovery is awaited by subscription counts and
by messages flowing, never by sleeping); during the trials only ``~/screw`` is subscribed,
while each node still publishes all five outputs for every input.

Per trial: delivered msg/s (screw messages received / flood duration), the fraction lost,
latency p50 / p99, and the node process's CPU time per delivered message (from
/proc/PID/stat: the math's cost shows here most plainly).

Run: ``.venv/bin/python bench/bench_node.py`` (options: --help). The domain is
$BENCH_ROS_DOMAIN_ID or one derived from the pid; ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST.
"""

import argparse
import os
from pathlib import Path
import signal
from struct import unpack_from
import subprocess
import sys
import tempfile
import threading
import time

import benchlib

BENCH = Path(__file__).resolve().parent
RATES = (200, 500, 1000, 2000, 3000, 5000)
THROUGHPUT_GOAL = 0.8  # node's sustained msg/s ≥ 0.8 × relay's
LATENCY_GOAL = 1.5  # node's p99 ≤ 1.5 × relay's
LOSS_OK = 0.01  # a rate is sustained when at most 1 % of the inputs are lost
OUTPUTS = ('rotation_matrix', 'axis_angle', 'euler_angles', 'screw', 'screw_axis')
NAMES = {'relay': 'bench_relay', 'rot_tools': 'bench_rot_tools'}
"""Target → node name; main() adds relay_full (bench_relay_full) with --full-relay."""
NO_MARKERS = 'rot_tools_no_markers'
"""Target of --markers-off: rotation_node with publish_markers:=false (bench_rot_tools_nm)."""


def target_command(python, target):
    ros_args = ['--ros-args', '-r', f'__node:={NAMES[target]}']
    if target in ('rot_tools', NO_MARKERS):
        off = ['-p', 'publish_markers:=false'] if target == NO_MARKERS else []
        return [python, '-m', 'rot_tools.rotation_node'] + ros_args + off
    extra = ['--full-interface'] if target == 'relay_full' else []
    return [python, str(BENCH / 'relay_node.py')] + extra + ros_args


def expected_outputs(target):
    """The outputs the warm-up waits for: all but the marker for the no-markers node."""
    return tuple(o for o in OUTPUTS if o != 'screw_axis') if target == NO_MARKERS else OUTPUTS


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


class Measurer:
    """The subscribing side: an rclpy node in this process, spun in a thread."""

    def __init__(self):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import QoSProfile
        from rclpy.signals import SignalHandlerOptions
        from geometry_msgs.msg import TwistStamped, Vector3Stamped
        from std_msgs.msg import Float64MultiArray
        from visualization_msgs.msg import Marker

        self._rclpy = rclpy
        # No rclpy signal handlers here: Ctrl-C must raise KeyboardInterrupt in the main
        # thread, so that the harness stops the processes it started.
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node('bench_node_measurer')
        types = dict(rotation_matrix=Float64MultiArray, axis_angle=Vector3Stamped,
                     euler_angles=Vector3Stamped, screw=TwistStamped, screw_axis=Marker)
        qos = QoSProfile(depth=10)  # the outputs' QoS: reliable, keep last 10
        self.records = {t: [] for t in NAMES}
        self.seen = {(t, o): 0 for t in NAMES for o in OUTPUTS}
        self._extra = []
        for target, name in NAMES.items():
            for output in OUTPUTS:
                topic = f'/{name}/{output}'
                if output == 'screw':
                    cb = self._recorder(target)
                else:
                    cb = self._counter(target, output)
                # raw: the CDR bytes, no deserialisation (the stamp is read from them)
                sub = self.node.create_subscription(types[output], topic, cb, qos, raw=True)
                if output != 'screw':
                    self._extra.append(sub)
        # (rclpy's experimental EventsExecutor would be lighter, but in rclpy 7.1 it hangs
        # here: spun in a thread, its shutdown never returns.)
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        try:
            while self._rclpy.ok():
                self.executor.spin_once(timeout_sec=0.05)
        except Exception:  # shutdown while spinning
            pass

    def _recorder(self, target):
        records = self.records[target]
        now = time.time_ns

        def on_screw(data):
            # CDR: 4-byte encapsulation header, then header.stamp (int32 sec, uint32 nanosec)
            sec, nanosec = unpack_from('<iI' if data[1] else '>iI', data, 4)
            records.append((now(), sec * 1_000_000_000 + nanosec))
            self.seen[(target, 'screw')] += 1
        return on_screw

    def _counter(self, target, output):
        def on_output(msg):
            self.seen[(target, output)] += 1
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

    def start(self):
        for target in NAMES:
            cmd = target_command(sys.executable, target)
            log = open(os.path.join(self.logdir, f'{target}.log'), 'w')
            self.logs.append(log)
            self.procs[target] = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)
        self.measurer = Measurer()
        topics = [f'/{NAMES[t]}/pose' for t in NAMES]
        flog = open(os.path.join(self.logdir, 'flooder.log'), 'w')
        self.logs.append(flog)
        self.flooder = subprocess.Popen(
            [sys.executable, str(BENCH / 'pose_flooder.py')] + topics,
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=flog, text=True)
        line = self.flooder.stdout.readline().strip()
        if line != 'ready':
            self.fail(f'pose_flooder did not get ready: {line!r}')

    def fail(self, why):
        for target, proc in self.procs.items():
            if proc.poll() is not None:
                why += f'\n{target} exited with {proc.returncode}; its log:\n'
                why += Path(self.logdir, f'{target}.log').read_text()[-2000:]
        raise RuntimeError(why)

    def command(self, line):
        self.flooder.stdin.write(line + '\n')
        self.flooder.stdin.flush()
        reply = self.flooder.stdout.readline().split()
        if not reply or reply[0] != 'done':
            self.fail(f'pose_flooder answered {reply!r} to {line!r}')
        return int(reply[1]), float(reply[2])

    def warm_up(self, timeout=30.0):
        """Flood slowly until every output of both nodes has arrived here."""
        deadline = time.monotonic() + timeout
        for target, name in NAMES.items():
            outputs = expected_outputs(target)
            while not all(self.measurer.seen[(target, o)] for o in outputs):
                if time.monotonic() > deadline:
                    missing = [o for o in outputs if not self.measurer.seen[(target, o)]]
                    self.fail(f'{target}: no message on {", ".join(missing)} after '
                              f'{timeout:.0f} s')
                self.command(f'flood /{name}/pose 100 0.2')
                time.sleep(0.1)
        self.measurer.drop_extra_subscriptions()
        time.sleep(0.2)

    def trial(self, target, rate, seconds):
        records = self.measurer.records[target]
        records.clear()
        pid = self.procs[target].pid
        cpu0, fl0, me0 = cpu_seconds(pid), cpu_seconds(self.flooder.pid), _own_cpu()
        sent, elapsed = self.command(f'flood /{NAMES[target]}/pose {rate} {seconds}')
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
        return dict(target=target, rate=rate, sent=sent, sent_rate=sent / elapsed,
                    received=len(got), delivered=len(got) / elapsed,
                    loss=1.0 - len(got) / sent, p50=percentile(lat, 0.5),
                    p99=percentile(lat, 0.99),
                    cpu_us=cpu / max(1, len(got)) * 1e6, node_load=cpu / elapsed,
                    flooder_load=flooder_cpu / elapsed, measurer_load=own_cpu / elapsed)

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


def summarise(trials, rates):
    """Median of each figure over the repetitions, per (target, rate)."""
    keys = ('sent_rate', 'delivered', 'loss', 'p50', 'p99', 'cpu_us', 'node_load',
            'flooder_load', 'measurer_load')
    out = {}
    for target in NAMES:
        for rate in rates:
            runs = [t for t in trials if t['target'] == target and t['rate'] == rate]
            out[(target, rate)] = {k: benchlib.median([t[k] for t in runs]) for k in keys}
    return out


def evaluate(summary, rates):
    """Evaluate the goals: sustained throughput and p99 latency, node against relay."""
    relay_best = max(summary[('relay', r)]['delivered'] for r in rates)
    node_best = max(summary[('rot_tools', r)]['delivered'] for r in rates)
    # Latency is compared at the rates both sustain (≤ 1 % lost): beyond that a latency is
    # queueing in DDS, and the shortfall is the throughput figure's to show.
    unsaturated = [r for r in rates
                   if max(summary[(t, r)]['loss'] for t in ('relay', 'rot_tools')) <= LOSS_OK]
    sustained = {t: max([r for r in rates if summary[(t, r)]['loss'] <= LOSS_OK], default=0)
                 for t in ('relay', 'rot_tools')}
    p99_ratios = {r: summary[('rot_tools', r)]['p99'] / summary[('relay', r)]['p99']
                  for r in unsaturated}
    cpu = [summary[('rot_tools', r)]['cpu_us'] / summary[('relay', r)]['cpu_us']
           for r in rates]
    return dict(relay_msgs=relay_best, node_msgs=node_best,
                throughput_ratio=node_best / relay_best,
                p99_ratios=p99_ratios,
                p99_ratio_worst=max(p99_ratios.values()) if p99_ratios else float('nan'),
                p99_rates=unsaturated, sustained_rate=sustained,
                cpu_ratio=benchlib.median(cpu) if cpu else float('nan'))


def print_results(summary, ev, rates, seconds, repeats):
    rows = []
    for r in rates:
        a, b = summary[('relay', r)], summary[('rot_tools', r)]
        rows.append([f'{r}', f"{a['sent_rate']:.0f}",
                     f"{a['delivered']:.0f} ({a['loss']:.0%})",
                     f"{b['delivered']:.0f} ({b['loss']:.0%})",
                     f"{b['delivered'] / a['delivered']:.2f}",
                     f"{a['p50']:.2f} / {a['p99']:.2f}", f"{b['p50']:.2f} / {b['p99']:.2f}",
                     f"{b['p99'] / a['p99']:.2f}",
                     f"{a['cpu_us']:.0f}", f"{b['cpu_us']:.0f}"])
    benchlib.print_table(
        f'Node under a PoseStamped flood (>= {seconds:g} s per trial, median of {repeats} '
        'interleaved repetitions; latency = receive time of ~/screw - input header stamp)',
        ['offered msg/s', 'sent/s', 'relay delivered/s (lost)',
         'rot_tools delivered/s (lost)', 'ratio', 'relay p50/p99 ms', 'rot_tools p50/p99 ms',
         'p99 ratio', 'relay CPU us/msg', 'rot_tools CPU us/msg'], rows)
    load_rows = []
    for r in rates:
        a, b = summary[('relay', r)], summary[('rot_tools', r)]
        load_rows.append([f'{r}', f"{a['node_load']:.2f} / {b['node_load']:.2f}",
                          f"{a['flooder_load']:.2f} / {b['flooder_load']:.2f}",
                          f"{a['measurer_load']:.2f} / {b['measurer_load']:.2f}"])
    benchlib.print_table(
        'CPU load during the trials (CPU seconds per second; relay trial / rot_tools trial)',
        ['offered msg/s', 'node process', 'flooder', 'measurer (this process)'], load_rows)
    p99_where = ', '.join(f'{r}: {v:.2f}' for r, v in ev['p99_ratios'].items())
    goal_rows = [
        ['sustained throughput', f"{ev['node_msgs']:.0f} msg/s", f"{ev['relay_msgs']:.0f} msg/s",
         f"{ev['throughput_ratio']:.2f}", f'>= {THROUGHPUT_GOAL:g}',
         'yes' if ev['throughput_ratio'] >= THROUGHPUT_GOAL else 'NO'],
        ['highest offered rate with <= 1 % lost', f"{ev['sustained_rate']['rot_tools']} msg/s",
         f"{ev['sustained_rate']['relay']} msg/s", '', '', ''],
        ['p99 latency (worst rate both sustain)', '', '', f"{ev['p99_ratio_worst']:.2f}",
         f'<= {LATENCY_GOAL:g}', benchlib.verdict(ev['p99_ratio_worst'], LATENCY_GOAL)],
        ['node CPU per delivered message (median)', '', '', f"{ev['cpu_ratio']:.2f}", '-', '-'],
    ]
    benchlib.print_table('Node goals (rot_tools node vs bare relay)',
                         ['figure', 'rot_tools', 'relay', 'ratio', 'goal', 'met?'], goal_rows)
    print(f'  p99 ratio at each offered rate both sustain (<= {LOSS_OK:.0%} lost): '
          f'{p99_where or "none"}')
    if 'relay_full' in NAMES:
        rows = []
        for r in rates:
            a, f = summary[('relay', r)], summary[('relay_full', r)]
            rows.append([f'{r}', f"{f['delivered']:.0f} ({f['loss']:.0%})",
                         f"{f['delivered'] / a['delivered']:.2f}",
                         f"{f['p50']:.2f} / {f['p99']:.2f}", f"{f['cpu_us']:.0f}"])
        benchlib.print_table(
            "relay --full-interface (relay plus rotation_node's other idle subscriptions "
            'and services; no math)',
            ['offered msg/s', 'delivered/s (lost)', 'vs relay', 'p50/p99 ms', 'CPU us/msg'],
            rows)
    if NO_MARKERS in NAMES:
        rows = []
        for r in rates:
            on, off = summary[('rot_tools', r)], summary[(NO_MARKERS, r)]
            rows.append([f'{r}', f"{on['delivered']:.0f} ({on['loss']:.0%})",
                         f"{off['delivered']:.0f} ({off['loss']:.0%})",
                         f"{on['delivered'] / off['delivered']:.2f}",
                         f"{on['p99']:.2f} / {off['p99']:.2f}",
                         f"{on['cpu_us']:.0f} / {off['cpu_us']:.0f}"])
        benchlib.print_table(
            'rotation_node with markers (publish_markers true, the default) and without',
            ['offered msg/s', 'markers on: delivered/s (lost)', 'off: delivered/s (lost)',
             'on / off', 'p99 ms on / off', 'CPU us/msg on / off'], rows)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--rates', type=lambda s: tuple(int(x) for x in s.split(',')),
                        default=RATES, help='offered rates, msg/s (200,500,1000,2000,3000,5000)')
    parser.add_argument('--seconds', type=float, default=2.0,
                        help='per trial, at least (2); longer where needed for --min-messages')
    parser.add_argument('--min-messages', type=int, default=1000,
                        help='messages per trial at least, so p99 rests on 10+ samples (1000)')
    parser.add_argument('--repeats', type=int, default=3,
                        help='interleaved repetitions of every (node, rate) trial (3)')
    parser.add_argument('--full-relay', action='store_true',
                        help='also measure relay_node.py --full-interface (the relay with '
                        "rotation_node's other entities, idle)")
    parser.add_argument('--markers-off', action='store_true',
                        help='also measure rotation_node with publish_markers:=false')
    parser.add_argument('--json', metavar='PATH', help='also write the figures as JSON')
    args = parser.parse_args(argv)
    if args.full_relay:
        NAMES['relay_full'] = 'bench_relay_full'
    if args.markers_off:
        NAMES[NO_MARKERS] = 'bench_rot_tools_nm'

    domain = os.environ.get('BENCH_ROS_DOMAIN_ID') or str(1 + (os.getpid() * 7 + 13) % 101)
    os.environ['ROS_DOMAIN_ID'] = domain
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_STATIC_PEERS', None)
    print(f'bench_node: {benchlib.machine_line()}; ROS_DOMAIN_ID={domain}, discovery LOCALHOST')

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
            print(f'  processes up, all five outputs of both nodes seen '
                  f'({time.monotonic() - t0:.1f} s)', flush=True)
            order = list(NAMES)
            for rep in range(args.repeats):
                for i, rate in enumerate(args.rates):
                    shift = (rep + i) % len(order)
                    for target in order[shift:] + order[:shift]:
                        seconds = max(args.seconds, args.min_messages / rate)
                        trials.append(harness.trial(target, rate, seconds))
                print(f'  repetition {rep + 1}/{args.repeats} done', flush=True)
        finally:
            harness.stop()
    summary = summarise(trials, args.rates)
    ev = evaluate(summary, args.rates)
    print_results(summary, ev, args.rates, args.seconds, args.repeats)
    benchlib.write_json(args.json, dict(
        trials=trials, evaluation={k: v for k, v in ev.items() if k != 'p99_ratios'},
        p99_ratios={str(k): v for k, v in ev['p99_ratios'].items()},
        summary={f'{t}@{r}': v for (t, r), v in summary.items()}))


if __name__ == '__main__':
    try:
        main()
    except KeyboardInterrupt:
        print('bench_node: interrupted; the processes it started are stopped', file=sys.stderr)
        sys.exit(130)
