"""
Node benchmark: rotation_node against bare rclpy relays, flooded with PoseStamped.

Processes (all started here, all on the loopback of one isolated DDS domain):

- ``rotation_node`` by its console script, as a user starts it, twice: ``bench_rot_tools``
  with ``publish_markers:=false`` (the goals are measured on it) and
  ``bench_rot_tools_markers`` with the markers on;
- ``bench/relay_node.py``: the same six message outputs, types and QoS with constant
  content and no math, written the usual way (message objects) — rclpy's own messaging
  limit — ``bench_relay_default`` on rclpy's SingleThreadedExecutor, the executor
  rotation_node runs on (rot_tools.ros.runtime.make_executor); the relay is started, spun
  and stopped as the node is (the node's loop, rot_tools.ros.runtime.serve, and its exit)
  and flooded exactly as the node is;
- ``bench/pose_flooder.py``: publishes PoseStamped on ``~/pose`` of one of them at a set
  rate, stamping each message with the wall clock just before publishing;
- this process: subscribes ``~/screw`` (TwistStamped) of each and records, per message,
  the receive time minus the header stamp (the latency through the node).

All run all the time; the trials go round them, rate by rate (500, 1000, 2000 and 5000
msg/s offered for 3 s each by default), in three rounds, the order rotating. Delivered
msg/s is the best round's (what the process can do; a round disturbed by other work on the
machine is left out), latency and CPU the median (of three rounds, one disturbed round is
left out: with two, the median was their mean, and one round's stall on a shared machine
swung a p99 ratio from 1.0 to 2.0 between runs). Before measuring, every output of each
node is seen to arrive (discovery is awaited by subscription counts and by messages
flowing, never by sleeping); during the trials only ``~/screw`` is subscribed, while each
node still publishes all of its outputs for every input. Options add targets: the relay
with rotation_node's other entities, relay and node on rclpy's EventsExecutor, the node
started by ``python -m`` (the evidence for the executor and for how the node is started).

Per trial: delivered msg/s (screw messages received / flood duration), the fraction lost,
latency p50 / p99, and the node process's CPU time per delivered message (from
/proc/PID/stat: the math's cost shows here most plainly).

Run: ``.venv/bin/python bench/bench_node.py`` (options: --help). The domain is
$BENCH_ROS_DOMAIN_ID or one derived from the pid; ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST.
"""

import argparse
import os
from pathlib import Path
import shutil
import signal
from struct import unpack_from
import subprocess
import sys
import tempfile
import time
from typing import NamedTuple

import benchlib

BENCH = Path(__file__).resolve().parent
RATES = (500, 1000, 2000, 5000)
THROUGHPUT_GOAL = 1.0  # node's sustained msg/s ≥ 1.0 × the relay's
LATENCY_GOAL = 1.5  # node's p99 ≤ 1.5 × the relay's
LOSS_OK = 0.01  # a rate is sustained when at most 1 % of the inputs are lost
OUTPUTS = ('rotation_matrix', 'quaternion', 'axis_angle', 'euler_angles', 'rpy', 'screw')
"""The six message outputs every target publishes for every input."""
MARKER_OUTPUTS = ('screw_axis', 'markers')
"""What rotation_node publishes besides, with publish_markers (at most 30 pictures a second)."""


class Target(NamedTuple):
    """A process under test: node name, table label, program and its arguments, outputs."""

    node: str
    label: str
    program: str
    """'relay' (bench/relay_node.py), 'node' (rotation_node by its console script),
    'node_module' (python -m rot_tools.ros.rotation_node) or 'node_on'
    (bench/node_on_executor.py)."""
    args: tuple
    """Options of the program (before --ros-args)."""
    params: tuple
    """After --ros-args (-p parameters)."""
    outputs: tuple


MARKERS_OFF = ('-p', 'publish_markers:=false')
TARGETS = {
    'relay_default': Target('bench_relay_default', 'relay, default executor', 'relay',
                            ('--executor', 'default'), (), OUTPUTS),
    'rot_tools': Target('bench_rot_tools', 'rot_tools, markers off', 'node', (), MARKERS_OFF,
                        OUTPUTS),
    'rot_tools_markers': Target('bench_rot_tools_markers', 'rot_tools, markers on', 'node',
                                (), (), OUTPUTS + MARKER_OUTPUTS),
}
"""The processes measured, in table order; options add EXTRA targets."""

EXTRA = {
    'relay_full': Target('bench_relay_full', 'relay, full interface', 'relay',
                         ('--executor', 'default', '--full-interface'), (), OUTPUTS),
    'relay_events': Target('bench_relay_events', 'relay, EventsExecutor', 'relay',
                           ('--executor', 'events'), (), OUTPUTS),
    'rot_tools_events': Target('bench_rot_tools_events', 'rot_tools on the EventsExecutor',
                               'node_on', ('--executor', 'events'), MARKERS_OFF, OUTPUTS),
    'rot_tools_module': Target('bench_rot_tools_module', 'rot_tools by python -m',
                               'node_module', (), MARKERS_OFF, OUTPUTS),
}
"""rotation_node's other entities on the relay (--full-relay); relay and node on the
EventsExecutor (--events); the node started by ``python -m`` instead of its console script
(--module)."""


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
    t = TARGETS[target]
    ros_args = ['--ros-args', '-r', f'__node:={t.node}', *t.params]
    if t.program == 'node':
        return [console_script(python, 'rotation_node'), *t.args, *ros_args]
    if t.program == 'node_module':
        return [python, '-m', 'rot_tools.ros.rotation_node', *t.args, *ros_args]
    if t.program == 'node_on':
        return [python, str(BENCH / 'node_on_executor.py'), *t.args, *ros_args]
    return [python, str(BENCH / 'relay_node.py'), *t.args, *ros_args]


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
        from geometry_msgs.msg import QuaternionStamped, TwistStamped, Vector3Stamped
        from std_msgs.msg import Float64MultiArray
        from visualization_msgs.msg import Marker, MarkerArray

        self._rclpy = rclpy
        # No rclpy signal handlers here: Ctrl-C must raise KeyboardInterrupt in the main
        # thread, so that the harness stops the processes it started.
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node('bench_node_measurer')
        types = {'rotation_matrix': Float64MultiArray, 'quaternion': QuaternionStamped,
                 'axis_angle': Vector3Stamped, 'euler_angles': Vector3Stamped,
                 'rpy': Vector3Stamped, 'screw': TwistStamped, 'screw_axis': Marker,
                 'markers': MarkerArray}
        qos = QoSProfile(depth=10)  # the outputs' QoS: reliable, keep last 10
        self.records = {t: [] for t in TARGETS}
        self.seen = {(t, o): 0 for t, target in TARGETS.items() for o in target.outputs}
        self._extra = []
        for target, spec in TARGETS.items():
            for output in spec.outputs:
                topic = f'/{spec.node}/{output}'
                if output == 'screw':
                    cb = self._recorder(target)
                else:
                    cb = self._counter(target, output)
                # raw: the CDR bytes, no deserialisation (the stamp is read from them)
                sub = self.node.create_subscription(types[output], topic, cb, qos, raw=True)
                if output != 'screw':
                    self._extra.append(sub)
        # (The same executor for every target: its cost falls on all trials alike.)
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self._thread = benchlib.spin_in_thread(rclpy, self.executor)

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
        for target in TARGETS:
            cmd = target_command(sys.executable, target)
            log = open(os.path.join(self.logdir, f'{target}.log'), 'w')
            self.logs.append(log)
            self.procs[target] = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)
        self.measurer = Measurer()
        topics = [f'/{t.node}/pose' for t in TARGETS.values()]
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
        for target, spec in TARGETS.items():
            while not all(self.measurer.seen[(target, o)] for o in spec.outputs):
                if time.monotonic() > deadline:
                    missing = [o for o in spec.outputs if not self.measurer.seen[(target, o)]]
                    self.fail(f'{target}: no message on {", ".join(missing)} after '
                              f'{timeout:.0f} s')
                self.command(f'flood /{spec.node}/pose 100 0.2')
                time.sleep(0.1)
        self.measurer.drop_extra_subscriptions()
        time.sleep(0.2)

    def trial(self, target, rate, seconds):
        records = self.measurer.records[target]
        records.clear()
        pid = self.procs[target].pid
        cpu0, fl0, me0 = cpu_seconds(pid), cpu_seconds(self.flooder.pid), _own_cpu()
        sent, elapsed = self.command(f'flood /{TARGETS[target].node}/pose {rate} {seconds}')
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
        return {'target': target, 'rate': rate, 'sent': sent, 'sent_rate': sent / elapsed,
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


def compare(summary, rates, node, relay):
    """Node against relay: sustained throughput ratio, p99 ratios where both sustain, CPU."""
    best = {t: max(summary[(t, r)]['delivered'] for r in rates) for t in (node, relay)}
    # Latency is compared at the rates both sustain (≤ 1 % lost): beyond that a latency is
    # queueing in DDS, and the shortfall is the throughput figure's to show.
    both = [r for r in rates if max(summary[(t, r)]['loss'] for t in (node, relay)) <= LOSS_OK]
    p99 = {r: summary[(node, r)]['p99'] / summary[(relay, r)]['p99'] for r in both}
    cpu = [summary[(node, r)]['cpu_us'] / summary[(relay, r)]['cpu_us'] for r in rates]
    return {'node_msgs': best[node], 'relay_msgs': best[relay],
            'throughput_ratio': best[node] / best[relay], 'p99_ratios': p99,
            'p99_ratio_worst': max(p99.values()) if p99 else float('nan'),
            'cpu_ratio': benchlib.median(cpu)}


def evaluate(summary, rates):
    """Every comparison the goals and the README quote, keyed 'node vs relay'."""
    pairs = [('rot_tools', 'relay_default'), ('rot_tools_markers', 'relay_default'),
             ('relay_full', 'relay_default'), ('rot_tools', 'relay_full'),
             ('rot_tools_events', 'relay_events'), ('relay_default', 'relay_events'),
             ('rot_tools', 'rot_tools_events'), ('rot_tools_module', 'relay_default'),
             ('rot_tools', 'rot_tools_module')]
    ev = {f'{a} vs {b}': compare(summary, rates, a, b) for a, b in pairs
          if a in TARGETS and b in TARGETS}
    ev['sustained_rate'] = {
        t: max([r for r in rates if summary[(t, r)]['loss'] <= LOSS_OK], default=0)
        for t in TARGETS}
    return ev


def goal_rows(ev):
    """(figure, measured, goal, met?) of the node goals (none when a side was left out)."""
    if 'rot_tools vs relay_default' not in ev:
        return []
    vs_relay = ev['rot_tools vs relay_default']
    return [
        ('node throughput / relay', vs_relay['throughput_ratio'], f'>= {THROUGHPUT_GOAL:g}',
         vs_relay['throughput_ratio'] >= THROUGHPUT_GOAL),
        ("node p99 latency / relay's", vs_relay['p99_ratio_worst'], f'<= {LATENCY_GOAL:g}',
         vs_relay['p99_ratio_worst'] <= LATENCY_GOAL),
    ]


def print_results(summary, ev, rates, seconds, repeats):
    names = list(TARGETS)
    rows = []
    for r in rates:
        row = [f'{r}']
        for t in names:
            f = summary[(t, r)]
            row.append(f"{f['delivered']:.0f} ({f['loss']:.0%})")
        rows.append(row)
    benchlib.print_table(
        f'Delivered msg/s (lost) under a PoseStamped flood (>= {seconds:g} s per trial, '
        f'best of {repeats} interleaved rounds)',
        ['offered msg/s'] + [TARGETS[t].label for t in names], rows)
    rows = []
    for r in rates:
        rows.append([f'{r}'] + [f"{summary[(t, r)]['p50']:.2f} / {summary[(t, r)]['p99']:.2f}"
                                for t in names])
    benchlib.print_table('Latency p50 / p99 ms (receive time of ~/screw - input header stamp)',
                         ['offered msg/s'] + [TARGETS[t].label for t in names], rows)
    rows = []
    for r in rates:
        cpu = [f"{summary[(t, r)]['cpu_us']:.0f} ({summary[(t, r)]['node_load']:.2f})"
               for t in names]
        rows.append([f'{r}', *cpu, f"{summary[(names[-1], r)]['flooder_load']:.2f}",
                     f"{summary[(names[-1], r)]['measurer_load']:.2f}"])
    benchlib.print_table(
        'CPU us per delivered message (node process CPU s/s); flooder and measurer CPU s/s '
        f'during the {TARGETS[names[-1]].label} trial',
        ['offered msg/s'] + [TARGETS[t].label for t in names] + ['flooder', 'measurer'], rows)
    rows = []
    for key, c in ev.items():
        if key == 'sustained_rate':
            continue
        p99 = ', '.join(f'{r}: {v:.2f}' for r, v in c['p99_ratios'].items()) or 'none'
        rows.append([key, f"{c['node_msgs']:.0f} / {c['relay_msgs']:.0f}",
                     f"{c['throughput_ratio']:.2f}", f"{c['p99_ratio_worst']:.2f}", p99,
                     f"{c['cpu_ratio']:.2f}"])
    benchlib.print_table(
        'Comparisons (sustained throughput = most msg/s delivered at any offered rate; p99 '
        'ratios at the offered rates both sustain with <= 1 % lost)',
        ['node vs relay', 'msg/s', 'throughput ratio', 'worst p99 ratio', 'p99 ratio by rate',
         'CPU/msg ratio'], rows)
    sustained = ', '.join(f'{TARGETS[t].label} {r}' for t, r in ev['sustained_rate'].items())
    print(f'  highest offered rate sustained (<= {LOSS_OK:.0%} lost): {sustained}')
    benchlib.print_table('Node goals', ['figure', 'measured', 'goal', 'met?'],
                         [[f, f'{v:.2f}', g, 'yes' if ok else 'NO']
                          for f, v, g, ok in goal_rows(ev)])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--rates', type=lambda s: tuple(int(x) for x in s.split(',')),
                        default=RATES, help='offered rates, msg/s (500,1000,2000,5000)')
    parser.add_argument('--seconds', type=float, default=3.0,
                        help='per trial, at least (3); longer where needed for --min-messages')
    parser.add_argument('--min-messages', type=int, default=1000,
                        help='messages per trial at least, so p99 rests on 10+ samples (1000)')
    parser.add_argument('--repeats', type=int, default=3,
                        help='interleaved rounds of every (node, rate) trial (3); delivery is '
                        "the best round's, latency and CPU the median")
    parser.add_argument('--full-relay', action='store_true',
                        help='also measure relay_node.py --full-interface (with '
                        "rotation_node's other entities, idle)")
    parser.add_argument('--events', action='store_true',
                        help="also measure the relay and rotation_node on rclpy's "
                        'EventsExecutor')
    parser.add_argument('--module', action='store_true',
                        help='also measure rotation_node started by python -m '
                        'rot_tools.ros.rotation_node instead of its console script')
    parser.add_argument('--only', metavar='T,T', type=lambda v: v.split(','),
                        help='measure only these targets (a quick look; comparisons need both '
                        'sides): ' + ', '.join(TARGETS))
    parser.add_argument('--json', metavar='PATH', help='also write the figures as JSON')
    args = parser.parse_args(argv)
    if args.only:
        for name in list(TARGETS):
            if name not in args.only:
                del TARGETS[name]
    for option, names in (('full_relay', ['relay_full']),
                          ('events', ['relay_events', 'rot_tools_events']),
                          ('module', ['rot_tools_module'])):
        if getattr(args, option):
            TARGETS.update((name, EXTRA[name]) for name in names)

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
            print(f'  processes up, every output of every target seen '
                  f'({time.monotonic() - t0:.1f} s)', flush=True)
            order = list(TARGETS)
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
    goals = [{'figure': f, 'measured': v, 'goal': g, 'met': ok}
             for f, v, g, ok in goal_rows(ev)]
    evaluation = {k: {**v, 'p99_ratios': {str(r): x for r, x in v['p99_ratios'].items()}}
                  if k != 'sustained_rate' else v for k, v in ev.items()}
    benchlib.write_json(args.json, {
        'trials': trials, 'goals': goals, 'evaluation': evaluation,
        'summary': {f'{t}@{r}': v for (t, r), v in summary.items()}})


if __name__ == '__main__':
    try:
        main()
    except KeyboardInterrupt:
        print('bench_node: interrupted; the processes it started are stopped', file=sys.stderr)
        sys.exit(130)
