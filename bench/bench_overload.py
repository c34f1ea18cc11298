"""
Overload: rotation_node flooded 60 s on ~/pose or /tf, as fast as one publisher sends or at a rate.

Processes (all started here, in a DDS domain of their own on the loopback):

- ``rotation_node`` by its console script (next to this Python; defaults, markers on), or,
  with ``--executor NAME``, the same node on another executor (bench/node_on_executor.py);
  with ``--tf SCENARIO`` it follows base_link in odom (``tf_reference_frame``,
  ``tf_body_frame``);
- ``bench/pose_flooder.py``: publishes PoseStamped on the node's ``~/pose`` back to back,
  as fast as it can (``--rate max``, the default: ``flood TOPIC max SECONDS``), or at
  ``--rate`` msg/s (10000 for the service-latency goal); with ``--tf SCENARIO``, TFMessages
  on ``/tf`` instead (and ``map → odom`` on ``/tf_static``): ``steady`` (the followed edge
  stamped now), ``large`` (steady, and every 5 s three TFMessages of 100,000 transforms),
  ``reparent`` (base_link's parent changing at every message, odom ↔ map) or ``jump`` (the
  stream's clock going back 30 s every second, every 100th message stamped 10⁶ s ahead):
  pose_flooder.TF_SCENARIOS;
- a listener (this script with ``--listen``): subscribes every output of the node
  (reliable, depth 10, as a user's RViz or recorder would), counts ``~/screw``;
- this process: calls ``~/describe``, ``~/get_parameters`` and ``~/set_parameters``
  (``angle_unit`` rad ↔ deg) in turn, one call outstanding at a time, each abandoned after
  ``--call-timeout`` seconds (an *unanswered* call), and samples the node's resident set
  (/proc/PID/status VmRSS) every second.

Timeline: warm-up (a slow flood until the outputs reach the listener, one answered call of
each service), RSS at the start, the flood for ``--seconds`` (60), RSS at its end, then the
calls stop and the RSS is sampled for ``--after`` (10) seconds more; then the same flood
again, and SIGINT to the node 2 s into it. Printed: RSS at the start, at the end, at most
and ``--after`` s after; for each service the latency p50, p99 and max during the flood,
how many calls took over 1 s (their request was lost and sent again at the client's next
DDS heartbeat) and how many went unanswered; the refusals the node counted (~/describe);
how the node ended on SIGINT. The goals, flooded as fast as one publisher sends: RSS grows
by at most 50 MB and is back within 20 MB of the start 10 s after the flood, every call is
answered within 5 s (the call timeout), the node keeps publishing; flooded at 10,000
msg/s: every service answers with p99 <= 100 ms (an unanswered call counts as infinitely
late); at either rate, SIGINT during the flood ends the node within 1 s with status 0 and
no traceback in its log. Not a test: a script that prints what it measured.

The node runs with its own Fast DDS profile (rot_tools.ros.runtime.use_fast_dds_profile);
``FASTDDS_BUILTIN_TRANSPORTS=DEFAULT`` in the environment runs it, and every other process
here, on Fast DDS's defaults instead (the user's own setting keeps the node's profile out).

Run: ``.venv/bin/python bench/bench_overload.py [--rate max|MSG_PER_S] [--seconds 60]
[--after 10] [--tf steady|large|reparent|jump] [--executor events|single|multi]
[--caller-heartbeat SECONDS] [--json PATH]``.
"""

import argparse
import math
import os
from pathlib import Path
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import benchlib
from pose_flooder import TF_SCENARIOS

BENCH = Path(__file__).resolve().parent
NODE = 'bench_overload_rot_tools'
GROWTH_GOAL_MB = 50.0
RETURN_GOAL_MB = 20.0
LATENCY_GOAL_S = 0.1
"""Services' p99 under a flood at a set rate (--rate 10000)."""
ANSWER_GOAL_S = 5.0
"""Every call answered within this under the fastest flood (--rate max)."""
SLOW_S = 1.0
"""A call slower than this waited for its client's DDS to send the request again."""
SIGINT_GOAL_S = 1.0
"""SIGINT during the flood ends the node within this, with status 0."""
SIGINT_AFTER_S = 2.0
"""Seconds into the last flood at which the node gets SIGINT."""
TF_FRAMES = ('odom', 'base_link')
"""The frames the node follows with --tf (reference, body): pose_flooder's /tf stream."""
SERVICES = ('describe', 'get_parameters', 'set_parameters')
HEARTBEAT_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <data_writer profile_name="bench_overload_caller" is_default_profile="true">
    <times><heartbeatPeriod><sec>{sec}</sec><nanosec>{nanosec}</nanosec></heartbeatPeriod>
    </times>
  </data_writer>
</profiles>
"""
"""Fast DDS profile of the caller with --caller-heartbeat (the default period is 3 s)."""


def node_command(executor, tf=None):
    """rotation_node by its console script, or on another executor (node_on_executor.py)."""
    ros_args = ['--ros-args', '-r', f'__node:={NODE}']
    if tf:
        ros_args += ['-p', f'tf_reference_frame:={TF_FRAMES[0]}',
                     '-p', f'tf_body_frame:={TF_FRAMES[1]}']
    if executor:
        return [sys.executable, str(BENCH / 'node_on_executor.py'), '--executor', executor,
                *ros_args]
    script = Path(sys.executable).parent / 'rotation_node'
    if not script.exists():
        found = shutil.which('rotation_node')
        if not found:
            raise SystemExit('bench_overload: no rotation_node console script (pip install -e .)')
        script = Path(found)
    return [str(script), *ros_args]


def listen(node):
    """Run the listener process: every output of ``node`` subscribed; print ~/screw counts."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile
    from geometry_msgs.msg import QuaternionStamped, TwistStamped, Vector3Stamped
    from std_msgs.msg import Float64MultiArray
    from visualization_msgs.msg import Marker, MarkerArray
    rclpy.init()
    listener = rclpy.create_node('bench_overload_listener')
    count = [0]
    outputs = {'rotation_matrix': Float64MultiArray, 'quaternion': QuaternionStamped,
               'axis_angle': Vector3Stamped, 'euler_angles': Vector3Stamped, 'rpy': Vector3Stamped,
               'screw': TwistStamped, 'screw_axis': Marker, 'markers': MarkerArray}
    for name, msg_type in outputs.items():
        def on_output(data, screw=name == 'screw'):
            if screw:
                count[0] += 1
        listener.create_subscription(msg_type, f'/{node}/{name}', on_output,
                                     QoSProfile(depth=10), raw=True)
    executor = SingleThreadedExecutor()
    executor.add_node(listener)
    last = time.monotonic()
    try:
        while rclpy.ok():
            executor.spin_once(timeout_sec=0.05)
            if time.monotonic() - last >= 0.2:
                last = time.monotonic()
                print(count[0], flush=True)
    except Exception:  # noqa: BLE001 - shut down by a signal while spinning: the end
        pass
    return 0


class Caller:
    """This process's service client of the node: one call at a time, bounded waits."""

    def __init__(self, node, timeout, heartbeat=None, logdir=None):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions
        from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
        from rcl_interfaces.srv import GetParameters, SetParameters
        from std_srvs.srv import Trigger
        self._rclpy = rclpy
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        if heartbeat:  # this process's DDS writers (the requests) heartbeat more often
            profile = Path(logdir, 'caller_profile.xml')
            profile.write_text(HEARTBEAT_PROFILE.format(
                sec=int(heartbeat), nanosec=int(round(heartbeat % 1 * 1e9))))
            os.environ['FASTRTPS_DEFAULT_PROFILES_FILE'] = str(profile)
        self.node = rclpy.create_node('bench_overload_caller')
        os.environ.pop('FASTRTPS_DEFAULT_PROFILES_FILE', None)  # (not for the others)
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.timeout = timeout
        self.clients = {
            'describe': self.node.create_client(Trigger, f'/{node}/describe'),
            'get_parameters': self.node.create_client(GetParameters,
                                                      f'/{node}/get_parameters'),
            'set_parameters': self.node.create_client(SetParameters,
                                                      f'/{node}/set_parameters'),
        }
        self._units = 0
        self.answers = {}

        def set_request():
            self._units += 1
            value = ParameterValue(type=ParameterType.PARAMETER_STRING,
                                   string_value='deg' if self._units % 2 else 'rad')
            return SetParameters.Request(parameters=[Parameter(name='angle_unit',
                                                               value=value)])
        self.requests = {
            'describe': Trigger.Request,
            'get_parameters': lambda: GetParameters.Request(names=['angle_unit',
                                                                   'euler_sequence']),
            'set_parameters': set_request,
        }

    def wait_ready(self, deadline):
        for name, client in self.clients.items():
            while not client.service_is_ready():
                if time.monotonic() > deadline:
                    raise RuntimeError(f'service {name} of {NODE} never appeared')
                self.executor.spin_once(timeout_sec=0.05)

    def call(self, name, timeout=None):
        """Return (seconds to the answer, or inf when abandoned after the timeout, ok?)."""
        client = self.clients[name]
        begin = time.monotonic()
        future = client.call_async(self.requests[name]())
        deadline = begin + (timeout or self.timeout)
        while not future.done():
            left = deadline - time.monotonic()
            if left <= 0:
                client.remove_pending_request(future)
                return math.inf, False
            self.executor.spin_once(timeout_sec=min(left, 0.05))
        took = time.monotonic() - begin
        result = self.answers[name] = future.result()
        ok = {'describe': lambda r: True,  # (success False is fine before any input)
              'get_parameters': lambda r: len(r.values) == 2,
              'set_parameters': lambda r: r.results and r.results[0].successful}[name](result)
        return took, bool(ok)

    def close(self):
        self.node.destroy_node()
        self._rclpy.try_shutdown()


def percentile(values, q):
    """Return the q-quantile (nearest rank) of values; inf counts as the largest."""
    values = sorted(values)
    if not values:
        return math.nan
    return values[min(len(values) - 1, max(0, math.ceil(q * len(values)) - 1))]


def flood_command(flooder, line):
    flooder.stdin.write(line + '\n')
    flooder.stdin.flush()


def flood_reply(flooder):
    reply = flooder.stdout.readline().split()
    if not reply or reply[0] != 'done':
        raise RuntimeError(f'pose_flooder answered {reply!r}')
    return int(reply[1]), float(reply[2])


class Listener:
    """The listener process and the latest ~/screw count it printed."""

    def __init__(self, logdir):
        self.log = open(os.path.join(logdir, 'listener.log'), 'w')
        self.process = subprocess.Popen(
            [sys.executable, str(Path(__file__).resolve()), '--listen', NODE],
            stdout=subprocess.PIPE, stderr=self.log)
        self._fd = self.process.stdout.fileno()
        os.set_blocking(self._fd, False)
        self.count = 0
        self._buffer = ''

    def poll(self):
        try:
            chunk = os.read(self._fd, 65536).decode('ascii')
        except BlockingIOError:
            chunk = ''
        if chunk:
            self._buffer += chunk
            lines = self._buffer.split('\n')
            self._buffer = lines[-1]
            if len(lines) > 1 and lines[-2].strip():
                self.count = int(lines[-2])
        return self.count

    def stop(self):
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self.log.close()


def stop_during_a_flood(node, flooder, flood, node_log):
    """
    Flood as before, SIGINT the node SIGINT_AFTER_S into it; return {status, seconds, clean}.

    seconds: from the signal to the node's exit (inf if it did not end within 10 s: then it
    is killed); clean: no traceback in its log.
    """
    flood_command(flooder, flood(SIGINT_AFTER_S + 2.0))
    time.sleep(SIGINT_AFTER_S)
    begin = time.monotonic()
    node.send_signal(signal.SIGINT)
    try:
        status = node.wait(timeout=10.0)
        took = time.monotonic() - begin
    except subprocess.TimeoutExpired:
        node.kill()
        status, took = node.wait(), math.inf
    flood_reply(flooder)
    node_log.flush()
    with open(node_log.name, encoding='utf-8', errors='replace') as f:
        clean = 'Traceback' not in f.read()
    return {'status': status, 'seconds': took, 'clean': clean}


def refusals(answer):
    """Return the node's refusal counts {reason: n > 0} from a ~/describe answer."""
    import yaml
    try:
        refused = yaml.safe_load(answer.message).get('refused') or {}
    except (AttributeError, yaml.YAMLError):
        return {}
    return {reason: n for reason, n in refused.items() if n and reason != 'total'}


def measure(seconds, after, executor, call_timeout, logdir, heartbeat=None, rate='max',
            tf=None):
    node_log = open(os.path.join(logdir, 'node.log'), 'w')
    node = subprocess.Popen(node_command(executor, tf), stdout=node_log,
                            stderr=subprocess.STDOUT)
    topic = '/tf' if tf else f'/{NODE}/pose'

    def flood(duration, flood_rate=rate, scenario=tf):
        return f'flood {topic} {flood_rate} {duration} {scenario or ""}'.rstrip()
    listener = flooder = caller = None
    try:
        caller = Caller(NODE, call_timeout, heartbeat, logdir)
        listener = Listener(logdir)
        flooder = subprocess.Popen([sys.executable, str(BENCH / 'pose_flooder.py'), topic],
                                   stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        if flooder.stdout.readline().strip() != 'ready':
            raise RuntimeError('pose_flooder did not get ready')
        deadline = time.monotonic() + 60.0
        caller.wait_ready(deadline)
        while listener.poll() == 0:  # outputs flow to the listener (discovery both ways)
            if time.monotonic() > deadline or node.poll() is not None:
                raise RuntimeError('rotation_node never answered; see its log')
            flood_command(flooder, flood(0.5, 100, tf and 'steady'))
            flood_reply(flooder)
        for name in SERVICES:  # each client has had an answer (Fast DDS may drop a first)
            while not caller.call(name, timeout=2.0)[1]:
                if time.monotonic() > deadline:
                    raise RuntimeError(f'{name} never answered before the flood')
        time.sleep(1.0)
        rss_start = benchlib.rss_mb(node.pid)
        samples = [(0.0, rss_start)]
        calls = {name: [] for name in SERVICES}
        wrong = {name: 0 for name in SERVICES}
        count0 = listener.poll()
        start = time.monotonic()
        flood_command(flooder, flood(seconds))
        k = 0
        next_sample = start + 1.0
        while time.monotonic() - start < seconds:
            name = SERVICES[k % len(SERVICES)]
            k += 1
            took, ok = caller.call(name)
            if time.monotonic() - start < seconds:  # (a call the flood's end cut short: out)
                calls[name].append(took)
                wrong[name] += math.isfinite(took) and not ok
            while time.monotonic() >= next_sample:
                samples.append((next_sample - start, benchlib.rss_mb(node.pid)))
                next_sample += 1.0
            time.sleep(0.05)
        sent, elapsed = flood_reply(flooder)
        end = time.monotonic()
        rss_end = benchlib.rss_mb(node.pid)
        samples.append((end - start, rss_end))
        answered = listener.poll() - count0
        after_samples = []
        while time.monotonic() - end < after:
            time.sleep(min(1.0, max(0.0, after - (time.monotonic() - end))))
            after_samples.append((time.monotonic() - end, benchlib.rss_mb(node.pid)))
        final_call = caller.call('describe')
        refused = refusals(caller.answers.get('describe'))
        alive = node.poll() is None
        stop = stop_during_a_flood(node, flooder, flood, node_log) if alive else None
    finally:
        if flooder is not None and flooder.poll() is None:
            try:
                flood_command(flooder, 'quit')
                flooder.wait(timeout=10.0)
            except (OSError, subprocess.TimeoutExpired):
                flooder.kill()
                flooder.wait()
        if node.poll() is None:
            node.send_signal(signal.SIGINT)
            try:
                node.wait(timeout=10.0)
            except subprocess.TimeoutExpired:
                node.kill()
                node.wait()
        if listener is not None:
            listener.stop()
        if caller is not None:
            caller.close()
        node_log.close()
    rss_after = after_samples[-1][1]
    latency = {}
    for name in SERVICES:
        lat = calls[name]
        finite = [t for t in lat if math.isfinite(t)]
        latency[name] = {'calls': len(lat), 'unanswered': len(lat) - len(finite),
                         'slow': sum(t > SLOW_S for t in lat),
                         'wrong': wrong[name], 'p50': percentile(lat, 0.5),
                         'p99': percentile(lat, 0.99), 'max': max(lat) if lat else math.nan}
    growth = max(mb for _, mb in samples) - rss_start
    goals = {'growth': growth <= GROWTH_GOAL_MB, 'alive': alive and answered > 0,
             'returned': rss_after - rss_start <= RETURN_GOAL_MB,
             'sigint': stop is not None and stop['status'] == 0 and stop['clean']
             and stop['seconds'] <= SIGINT_GOAL_S}
    if rate == 'max':
        goals['answered'] = all(v['max'] <= ANSWER_GOAL_S for v in latency.values())
    else:
        goals['latency'] = all(v['p99'] <= LATENCY_GOAL_S for v in latency.values())
    return {'executor': executor or 'node (console script)', 'rate': rate,
            'flood': f'/tf {tf}' if tf else '~/pose', 'seconds': seconds, 'after': after,
            'sent': sent, 'sent_rate': sent / elapsed, 'answered': answered,
            'answered_rate': answered / elapsed, 'rss_start_mb': rss_start, 'rss_end_mb': rss_end,
            'rss_max_mb': max(mb for _, mb in samples + after_samples), 'rss_after_mb': rss_after,
            'growth_mb': growth, 'latency': latency, 'samples': samples,
            'after_samples': after_samples, 'final_describe_s': final_call[0], 'alive': alive,
            'refused': refused, 'sigint': stop, 'goals': goals}


def print_results(m):
    step = max(1, len(m['samples']) // 12)
    rows = [[f'{t:.0f}', f'{mb:.1f}'] for t, mb in m['samples'][::step]]
    rows.append([f"{m['samples'][-1][0]:.0f} (end)", f"{m['rss_end_mb']:.1f}"])
    rows += [[f'+{t:.0f} after', f'{mb:.1f}'] for t, mb in m['after_samples']]
    benchlib.print_table(
        f"rotation_node ({m['executor']}) RSS (MB): {m['flood']} flooded "
        f"{'back to back' if m['rate'] == 'max' else 'at ' + m['rate'] + ' msg/s'}, "
        f"{m['sent_rate']:.0f} msg/s sent for {m['seconds']:.0f} s, {m['answered_rate']:.0f} "
        'answered per s (a subscriber on every output)', ['s', 'RSS MB'], rows)
    print(f"  RSS start {m['rss_start_mb']:.1f} MB, end {m['rss_end_mb']:.1f} MB, max "
          f"{m['rss_max_mb']:.1f} MB, {m['after']:.0f} s after {m['rss_after_mb']:.1f} MB")
    rows = []
    for name, v in m['latency'].items():
        rows.append([f'~/{name}', f"{v['calls']}", f"{v['p50'] * 1e3:.1f}",
                     f"{v['p99'] * 1e3:.1f}", f"{v['max'] * 1e3:.1f}", f"{v['slow']}",
                     f"{v['unanswered']}", f"{v['wrong']}"])
    benchlib.print_table(
        'Service latency during the flood, ms (one call at a time; unanswered = no reply '
        f'within the call timeout, counted as infinitely late; > {SLOW_S:g} s: the request was '
        'sent again)',
        ['service', 'calls', 'p50', 'p99', 'max', f'> {SLOW_S:g} s', 'unanswered',
         'wrong answers'], rows)
    if m['refused']:
        print('  refused (~/describe after the flood): ' + ', '.join(
            f'{reason} {n:,}' for reason, n in sorted(m['refused'].items())))
    g, stop = m['goals'], m['sigint']
    rows = [
        ['RSS growth during the flood', f"{m['growth_mb']:+.1f} MB", f'<= {GROWTH_GOAL_MB:g} MB',
         'yes' if g['growth'] else 'NO'],
        [f"RSS {m['after']:.0f} s after - start",
         f"{m['rss_after_mb'] - m['rss_start_mb']:+.1f} MB", f'<= {RETURN_GOAL_MB:g} MB',
         'yes' if g['returned'] else 'NO'],
        ['node publishing during the flood, alive after it',
         f"{m['answered']} outputs, {'alive' if m['alive'] else 'dead'}", '> 0, alive',
         'yes' if g['alive'] else 'NO'],
    ]
    if 'latency' in g:
        rows.append(['worst service p99', f"{max(v['p99'] for v in m['latency'].values()):.3f} s",
                     f'<= {LATENCY_GOAL_S:g} s', 'yes' if g['latency'] else 'NO'])
    else:
        rows.append(['slowest call', f"{max(v['max'] for v in m['latency'].values()):.3f} s",
                     f'<= {ANSWER_GOAL_S:g} s (none unanswered)',
                     'yes' if g['answered'] else 'NO'])
    rows.append([f'SIGINT {SIGINT_AFTER_S:g} s into a flood',
                 'node dead before' if stop is None else
                 f"status {stop['status']} after {stop['seconds']:.2f} s"
                 f"{'' if stop['clean'] else ', a traceback in its log'}",
                 f'status 0 within {SIGINT_GOAL_S:g} s, no traceback',
                 'yes' if g['sigint'] else 'NO'])
    benchlib.print_table(f"Overload goals ({m['flood']})",
                         ['figure', 'measured', 'goal', 'met?'], rows)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=60.0, help='flood length (60)')
    parser.add_argument('--after', type=float, default=10.0,
                        help='seconds of RSS samples after the flood (10)')
    parser.add_argument('--call-timeout', type=float, default=5.0,
                        help='seconds before a call counts as unanswered (5)')
    parser.add_argument('--rate', default='max',
                        help="flood rate, msg/s, or 'max': back to back (max)")
    parser.add_argument('--tf', choices=sorted(TF_SCENARIOS),
                        help='flood /tf instead of ~/pose, the node following base_link in '
                        'odom: ' + '; '.join(f'{k}: {v}' for k, v in TF_SCENARIOS.items()))
    parser.add_argument('--executor', choices=('events', 'single', 'multi'),
                        help='run rotation_node on this executor (bench/node_on_executor.py) '
                        'instead of by its console script; single is the one it uses')
    parser.add_argument('--caller-heartbeat', type=float, metavar='SECONDS',
                        help="the calling process's DDS writers heartbeat this often (Fast DDS: "
                        '3 s): a request the flooded node lost is sent again sooner')
    parser.add_argument('--listen', metavar='NODE', help=argparse.SUPPRESS)
    parser.add_argument('--json', metavar='PATH', help='also write the figures as JSON')
    args = parser.parse_args(argv)
    if args.listen:
        return listen(args.listen)
    domain = os.environ.get('BENCH_ROS_DOMAIN_ID') or str(1 + (os.getpid() * 11 + 5) % 101)
    os.environ['ROS_DOMAIN_ID'] = domain
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_STATIC_PEERS', None)
    print(f'bench_overload: {benchlib.machine_line()}; ROS_DOMAIN_ID={domain}', flush=True)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    with tempfile.TemporaryDirectory(prefix='rot_tools_bench_') as logdir:
        m = measure(args.seconds, args.after, args.executor, args.call_timeout, logdir,
                    args.caller_heartbeat, args.rate, args.tf)
    print_results(m)
    benchlib.write_json(args.json, m)
    return 0


if __name__ == '__main__':
    sys.exit(main())
