"""
Overload: rotation_node flooded on ~/pose or /tf, as fast as one publisher sends or at a rate.

Processes (all started here, in a DDS domain of their own on the loopback):

- ``rotation_node`` by its console script (next to this Python; defaults, markers on); with
  ``--tf SCENARIO`` it follows base_link in odom (``tf_reference_frame``,
  ``tf_body_frame``);
- ``bench/pose_flooder.py``: publishes PoseStamped on the node's ``~/pose`` back to back,
  as fast as it can (``--rate max``, the default: ``flood TOPIC max SECONDS``), or at
  ``--rate`` msg/s (10000 for the service-latency goal); with ``--tf SCENARIO``, TFMessages
  on ``/tf`` instead (and ``map → odom`` on ``/tf_static``): ``steady`` (the followed edge
  stamped now), ``large`` (steady, and one TFMessage of 100,000 transforms a second, ten in
  all), ``reparent`` (base_link's parent changing at every message, odom ↔ map) or ``jump``
  (the stream's clock going back 30 s every second, every 100th message stamped 10⁶ s
  ahead): pose_flooder.TF_SCENARIOS;
- a listener (this script with ``--listen NODE``): subscribes every output of the node
  (reliable, depth 10, as a user's RViz or recorder would), counts ``~/screw``;
- with ``--tf``, a bare rclpy /tf subscriber (this script with ``--bare-tf``): tf2_ros's
  QoS, a callback that only counts — what any /tf listener costs, the middleware's buffers
  and rclpy's message objects included; its resident set is sampled beside the node's;
- this process: calls ``~/describe``, ``~/get_parameters`` and ``~/set_parameters``
  (``angle_unit`` rad ↔ deg) in turn, one call outstanding at a time, each abandoned after
  ``--call-timeout`` seconds (an *unanswered* call), and samples the resident sets
  (/proc/PID/status VmRSS) every second.

Timeline: warm-up (a slow flood until the outputs reach the listener, one answered call of
each service), RSS at the start, the flood for ``--seconds`` (60), RSS at its end, then the
calls stop and the RSS is sampled for ``--after`` (10) seconds more; then the same flood
again, and SIGINT to the node 2 s into it. Printed: RSS at the start, at the end, at most
and ``--after`` s after; for each service the latency p50, p99 and max during the flood,
how many calls took over 1 s and how many went unanswered; the refusals the node counted
(~/describe); how the node ended on SIGINT. The goals: flooded at 10,000 msg/s, every
service answers with p99 <= 100 ms (an unanswered call counts as infinitely late); flooded
as fast as one publisher sends, every call is answered within 5 s (the call timeout) and
the node keeps publishing; under ``--tf large``, the node's RSS grows (at most during the
flood, and ``--after`` s after it) by at most 20 MB more than the bare /tf subscriber's,
measured with the steady stream at a rate the node keeps up with (``--tf large --rate
100``: under a faster one its /tf queue drops the large messages before it takes them, and
the goal is then not met for want of evidence); at
any rate, SIGINT during the flood ends the node within 1 s with status 0 and no traceback
in its log. The RSS growth under a ~/pose flood is printed against its older goals (50 MB,
back within 20 MB; under a /tf flood the middleware's buffers make most of it, and the bare
subscriber's is the measure). Not a test: a script that prints what it measured.

With ``--fastdds-profile`` the node runs on the opt-in Fast DDS profile shipped in
config/ (its process only, set as doc/node.md says).

Run: ``.venv/bin/python bench/bench_overload.py [--rate max|MSG_PER_S] [--seconds 60]
[--after 10] [--tf steady|large|reparent|jump] [--fastdds-profile] [--json PATH]``.
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
TF_GROWTH_GOAL_MB = 20.0
"""Under --tf large: the node's RSS growth at most this more than the bare subscriber's."""
BARE_TF = 'bench_overload_bare_tf'


def node_command(tf=None):
    """rotation_node by its console script, following base_link in odom with ``tf``."""
    ros_args = ['--ros-args', '-r', f'__node:={NODE}']
    if tf:
        ros_args += ['-p', f'tf_reference_frame:={TF_FRAMES[0]}',
                     '-p', f'tf_body_frame:={TF_FRAMES[1]}']
    script = Path(sys.executable).parent / 'rotation_node'
    if not script.exists():
        found = shutil.which('rotation_node')
        if not found:
            raise SystemExit('bench_overload: no rotation_node console script (pip install -e .)')
        script = Path(found)
    return [str(script), *ros_args]


def _count_until_shutdown(node, count):
    """Spin ``node``, printing count[0] every 0.2 s, until a signal shuts rclpy down."""
    import rclpy
    from rclpy.executors import ExternalShutdownException
    last = time.monotonic()
    try:
        while rclpy.ok():
            rclpy.spin_once(node, timeout_sec=0.05)
            if time.monotonic() - last >= 0.2:
                last = time.monotonic()
                print(count[0], flush=True)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


def listen(node):
    """Run the listener process: every output of ``node`` subscribed; print ~/screw counts."""
    import rclpy
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
        def on_output(msg, screw=name == 'screw'):
            if screw:
                count[0] += 1
        listener.create_subscription(msg_type, f'/{node}/{name}', on_output,
                                     QoSProfile(depth=10))
    return _count_until_shutdown(listener, count)


def bare_tf():
    """Run the bare /tf subscriber: tf2_ros's QoS, a callback that counts; print the count."""
    import rclpy
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from tf2_msgs.msg import TFMessage
    rclpy.init()
    node = rclpy.create_node(BARE_TF)
    count = [0]

    def on_tf(msg):
        count[0] += 1
    # tf2_ros.TransformListener's QoS for /tf
    qos = QoSProfile(depth=100, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE)
    node.create_subscription(TFMessage, '/tf', on_tf, qos)
    return _count_until_shutdown(node, count)


class Caller:
    """This process's service client of the node: one call at a time, bounded waits."""

    def __init__(self, node, timeout):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.signals import SignalHandlerOptions
        from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
        from rcl_interfaces.srv import GetParameters, SetParameters
        from std_srvs.srv import Trigger
        self._rclpy = rclpy
        rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
        self.node = rclpy.create_node('bench_overload_caller')
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


class Counter:
    """A process of this script that prints a count every 0.2 s; the latest count."""

    def __init__(self, logdir, name, *args):
        self.log = open(os.path.join(logdir, f'{name}.log'), 'w')
        self.process = subprocess.Popen(
            [sys.executable, str(Path(__file__).resolve()), *args],
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


def _rss(processes):
    """Return {name: RSS MB} of the running ``processes`` {name: Popen}."""
    return {name: benchlib.rss_mb(p.pid) for name, p in processes.items()}


def _stop(process, timeout=10.0):
    if process.poll() is None:
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


PROFILE = BENCH.parent / 'config' / 'fastdds_profile.xml'
"""The opt-in Fast DDS profile shipped for the node (doc/node.md), for --fastdds-profile."""


def measure(seconds, after, call_timeout, logdir, rate='max', tf=None, profile=False):
    node_log = open(os.path.join(logdir, 'node.log'), 'w')
    env = dict(os.environ)
    if profile:  # the node's process only, as doc/node.md turns it on
        env.update(FASTRTPS_DEFAULT_PROFILES_FILE=str(PROFILE),
                   RMW_FASTRTPS_USE_QOS_FROM_XML='1')
    node = subprocess.Popen(node_command(tf), stdout=node_log, stderr=subprocess.STDOUT,
                            env=env)
    topic = '/tf' if tf else f'/{NODE}/pose'

    def flood(duration, flood_rate=rate, scenario=tf):
        return f'flood {topic} {flood_rate} {duration} {scenario or ""}'.rstrip()
    listener = bare = flooder = caller = None
    try:
        caller = Caller(NODE, call_timeout)
        listener = Counter(logdir, 'listener', '--listen', NODE)
        watched = {'node': node}
        if tf:
            bare = Counter(logdir, 'bare_tf', '--bare-tf')
            watched['bare'] = bare.process
        flooder = subprocess.Popen([sys.executable, str(BENCH / 'pose_flooder.py'), topic],
                                   stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        if flooder.stdout.readline().strip() != 'ready':
            raise RuntimeError('pose_flooder did not get ready')
        deadline = time.monotonic() + 60.0
        caller.wait_ready(deadline)
        # Outputs flow to the listener, /tf to the bare subscriber (discovery both ways).
        while listener.poll() == 0 or (bare is not None and bare.poll() == 0):
            if time.monotonic() > deadline or node.poll() is not None:
                raise RuntimeError('rotation_node never answered; see its log')
            flood_command(flooder, flood(0.5, 100, tf and 'steady'))
            flood_reply(flooder)
        for name in SERVICES:  # each client has had an answer (Fast DDS may drop a first)
            while not caller.call(name, timeout=2.0)[1]:
                if time.monotonic() > deadline:
                    raise RuntimeError(f'{name} never answered before the flood')
        time.sleep(1.0)
        rss_start = _rss(watched)
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
                samples.append((next_sample - start, _rss(watched)))
                next_sample += 1.0
            time.sleep(0.05)
        sent, elapsed = flood_reply(flooder)
        end = time.monotonic()
        rss_end = _rss(watched)
        samples.append((end - start, rss_end))
        answered = listener.poll() - count0
        after_samples = []
        while time.monotonic() - end < after:
            time.sleep(min(1.0, max(0.0, after - (time.monotonic() - end))))
            after_samples.append((time.monotonic() - end, _rss(watched)))
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
        _stop(node)
        for counter in (listener, bare):
            if counter is not None:
                counter.stop()
        if caller is not None:
            caller.close()
        node_log.close()
    latency = {}
    for name in SERVICES:
        lat = calls[name]
        finite = [t for t in lat if math.isfinite(t)]
        latency[name] = {'calls': len(lat), 'unanswered': len(lat) - len(finite),
                         'slow': sum(t > SLOW_S for t in lat),
                         'wrong': wrong[name], 'p50': percentile(lat, 0.5),
                         'p99': percentile(lat, 0.99), 'max': max(lat) if lat else math.nan}
    # RSS growth of each watched process: at most during the flood, and --after s after it
    growth = {w: max(mb[w] for _, mb in samples) - rss_start[w] for w in watched}
    kept = {w: after_samples[-1][1][w] - rss_start[w] for w in watched}
    goals = {'alive': alive and answered > 0,
             'sigint': stop is not None and stop['status'] == 0 and stop['clean']
             and stop['seconds'] <= SIGINT_GOAL_S}
    if not tf:  # (under /tf floods the bare subscriber beside the node is the measure)
        goals.update(growth=growth['node'] <= GROWTH_GOAL_MB,
                     returned=kept['node'] <= RETURN_GOAL_MB)
    if rate == 'max' or tf:
        # (the 10 kHz p99 goal is ~/pose's; under a /tf flood a call may wait behind one
        # huge TFMessage, which rclpy takes seconds to convert: answered within 5 s)
        goals['answered'] = all(v['max'] <= ANSWER_GOAL_S for v in latency.values())
    else:
        goals['latency'] = all(v['p99'] <= LATENCY_GOAL_S for v in latency.values())
    beside_bare = None
    if tf:
        beside_bare = {'growth_mb': growth['node'] - growth['bare'],
                       'kept_mb': kept['node'] - kept['bare'],
                       'bare_growth_mb': growth['bare'], 'bare_kept_mb': kept['bare']}
        if tf == 'large':
            # Only a run in which the node took large messages says anything of their cost:
            # under a fast steady stream its queue drops them before they are taken.
            from rot_tools.ros.tf_input import TF_TOO_MANY_TRANSFORMS
            beside_bare['large_taken'] = refused.get(TF_TOO_MANY_TRANSFORMS, 0)
            goals['tf_memory'] = beside_bare['large_taken'] > 0 and max(
                beside_bare['growth_mb'], beside_bare['kept_mb']) <= TF_GROWTH_GOAL_MB
    node_rss = [(t, mb['node']) for t, mb in samples]
    node_after = [(t, mb['node']) for t, mb in after_samples]
    return {'rate': rate, 'flood': (f'/tf {tf}' if tf else '~/pose')
            + (', the node on the opt-in Fast DDS profile' if profile else ''),
            'seconds': seconds,
            'after': after, 'sent': sent, 'sent_rate': sent / elapsed, 'answered': answered,
            'answered_rate': answered / elapsed, 'rss_start_mb': rss_start['node'],
            'rss_end_mb': rss_end['node'],
            'rss_max_mb': max(mb for _, mb in node_rss + node_after),
            'rss_after_mb': node_after[-1][1], 'growth_mb': growth['node'],
            'latency': latency, 'samples': node_rss, 'after_samples': node_after,
            'all_samples': samples + after_samples, 'beside_bare_tf': beside_bare,
            'final_describe_s': final_call[0], 'alive': alive, 'refused': refused,
            'sigint': stop, 'goals': goals}


def print_results(m):
    step = max(1, len(m['samples']) // 12)
    rows = [[f'{t:.0f}', f'{mb:.1f}'] for t, mb in m['samples'][::step]]
    rows.append([f"{m['samples'][-1][0]:.0f} (end)", f"{m['rss_end_mb']:.1f}"])
    rows += [[f'+{t:.0f} after', f'{mb:.1f}'] for t, mb in m['after_samples']]
    benchlib.print_table(
        f"rotation_node RSS (MB): {m['flood']} flooded "
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

    def met(key):
        return '-' if key not in g else 'yes' if g[key] else 'NO'
    rows = [
        ['RSS growth during the flood', f"{m['growth_mb']:+.1f} MB",
         f'<= {GROWTH_GOAL_MB:g} MB' if 'growth' in g else 'no goal', met('growth')],
        [f"RSS {m['after']:.0f} s after - start",
         f"{m['rss_after_mb'] - m['rss_start_mb']:+.1f} MB",
         f'<= {RETURN_GOAL_MB:g} MB' if 'returned' in g else 'no goal', met('returned')],
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
    bare = m['beside_bare_tf']
    if bare is not None:
        taken = (f", {bare['large_taken']} large messages taken by the node"
                 if 'large_taken' in bare else '')
        rows.append(['RSS growth beside a bare /tf subscriber (max during; after)',
                     f"{bare['growth_mb']:+.1f} MB; {bare['kept_mb']:+.1f} MB (bare: "
                     f"{bare['bare_growth_mb']:+.1f}; {bare['bare_kept_mb']:+.1f}){taken}",
                     f'<= {TF_GROWTH_GOAL_MB:g} MB' if 'tf_memory' in g else 'no goal',
                     ('yes' if g['tf_memory'] else 'NO') if 'tf_memory' in g else '-'])
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
    parser.add_argument('--fastdds-profile', action='store_true',
                        help='run the node on the opt-in Fast DDS profile, config/'
                        'fastdds_profile.xml (doc/node.md)')
    parser.add_argument('--listen', metavar='NODE', help=argparse.SUPPRESS)
    parser.add_argument('--bare-tf', action='store_true', help=argparse.SUPPRESS)
    parser.add_argument('--json', metavar='PATH', help='also write the figures as JSON')
    args = parser.parse_args(argv)
    if args.listen:
        return listen(args.listen)
    if args.bare_tf:
        return bare_tf()
    domain = os.environ.get('BENCH_ROS_DOMAIN_ID') or str(1 + (os.getpid() * 11 + 5) % 101)
    os.environ['ROS_DOMAIN_ID'] = domain
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_STATIC_PEERS', None)
    print(f'bench_overload: {benchlib.machine_line()}, {time.strftime("%Y-%m-%d %H:%M %Z")}; '
          f'ROS_DOMAIN_ID={domain}', flush=True)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    with tempfile.TemporaryDirectory(prefix='rot_tools_bench_') as logdir:
        m = measure(args.seconds, args.after, args.call_timeout, logdir, args.rate, args.tf,
                    args.fastdds_profile)
    print_results(m)
    benchlib.write_json(args.json, m)
    return 0


if __name__ == '__main__':
    sys.exit(main())
