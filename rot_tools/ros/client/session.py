"""
rotation_client's conversation with a node: a short-lived rclpy node, every wait bounded.

It publishes one input until the node answers and collects the answer output by output, by
the output's name; it calls the node's services and reads ~/describe's refusal counts.
"""

from collections import deque
import os
import time

import numpy as np
from rot_tools.core.so3 import quaternion_to_matrix
from rot_tools.io import interface
import yaml

RESEND = 0.5
"""Seconds to wait for an answer before an input is sent again or a call repeated."""

PICTURE_WAIT = 1.0
"""Seconds to wait for the pictures of an answer (when the node drew that input)."""

MATRIX_MATCH = 1e-9
"""Largest |entry difference| between ~/rotation_matrix and R of the answer's quaternion."""


class Unreachable(Exception):
    """The node, a topic, a service or an answer could not be reached in time (exit 1)."""


class Refused(Exception):
    """The node refused the input (exit 2)."""


class BadInput(Exception):
    """What was given cannot be used (exit 2): a value not of its parameter's type, a bag."""


MATRIX = 'rotation_matrix'
"""The output without a header, matched by its content."""

PICTURES = ('screw_axis', 'markers')
"""The pictures: drawn at a limited rate, the latest input winning."""

COVARIANCES = ('rpy_covariance',)
"""The outputs published only for an input that carries a covariance."""

WITHHELD = ('rodrigues',)
"""The outputs the node withholds for some inputs (the Rodrigues vector at θ = π, where it is
infinite): kept in the answer when they come with the others."""


def stamped_outputs():
    """Return the names of the outputs published for every input, with its header."""
    return tuple(row.name for row in interface.OUTPUTS
                 if row.name not in (MATRIX, *PICTURES, *COVARIANCES, *WITHHELD))


def describe_data(response):
    """
    Return ~/describe's YAML document as data: at least ``refused`` {total, reason: n}.

    The node writes one even before it has accepted an input (then ``success`` is false and
    ``note`` says so). Anything else is not a rotation_node's report: Unreachable.
    """
    try:
        data = yaml.safe_load(response.message)
    except yaml.YAMLError:
        data = None
    if not (isinstance(data, dict) and isinstance(data.get('refused'), dict)):
        text = ' '.join(response.message.split())
        raise Unreachable(f'~/describe did not answer with a rotation_node report: '
                          f'{text[:200]!r}')
    return data


def _counts(data):
    """{reason: n} of describe_data's refusal counts (without the total)."""
    return {reason: n for reason, n in data['refused'].items() if reason != 'total'}


def refusal_text(data, before, source, stamps=None):
    """
    Why the node refused what the client sent to ``source``, or '' if it did not.

    ``data`` is describe_data now, ``before`` the counts before sending. For each reason
    counted since, the node's sentence (what and by how much) from ``last_refusals`` when
    that refusal is of ``source`` — and of one of ``stamps`` (sent header stamps, (sec,
    nanosec)), when given and the refusal has one — else the reason's name alone.
    """
    last = data.get('last_refusals') or {}
    texts = []
    for reason, n in _counts(data).items():
        if n <= before.get(reason, 0):
            continue
        refusal = last.get(reason) or {}
        stamp = refusal.get('stamp')
        ours = refusal.get('source') == source and (
            stamps is None or stamp is None or (stamp['sec'], stamp['nanosec']) in stamps)
        texts.append(f"{refusal['message']} ({reason})" if ours and refusal.get('message')
                     else reason)
    return '; '.join(texts)


def _ignore(msg):
    """Drop a message: the callback of a subscription that no command listens to now."""


class Client:
    """
    A short-lived rclpy node that talks to one rotation_node, every wait bounded.

    Its endpoints — service clients, publishers, subscriptions — are made when first needed
    and kept: a command calls ~/describe several times, and a program that runs several
    commands with one Client (:meth:`aim` at each) has each endpoint discovered by the node
    once, not once a command.
    """

    def __init__(self, target, timeout, context=None):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.target = target
        self.timeout = timeout
        self.node = rclpy.create_node(f'rotation_client_{os.getpid()}', context=context,
                                      start_parameter_services=False)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self.service_clients = {}
        """The clients of the services called so far, by service name."""
        self.publishers = {}
        """The publishers made so far, by (topic, message class)."""
        self.subscriptions = {}
        """(subscription, [its callback now]) of the topics listened to, by (topic, class)."""

    def aim(self, target, timeout):
        """Talk to node ``target`` with waits of ``timeout`` seconds from now on."""
        self.target, self.timeout = target, timeout

    def release(self):
        """Stop handing messages to the callbacks of the command that ended."""
        for _, callback in self.subscriptions.values():
            callback[0] = _ignore

    def close(self):
        self.executor.shutdown(timeout_sec=1.0)
        self.node.destroy_node()

    def publisher(self, msg_type, topic, qos=10):
        """Return the publisher of ``msg_type`` on ``topic``, made at the first call."""
        key = topic, msg_type
        if key not in self.publishers:
            self.publishers[key] = self.node.create_publisher(msg_type, topic, qos)
        return self.publishers[key]

    def subscribe(self, msg_type, topic, callback, qos):
        """
        Hand the messages of ``topic`` to ``callback`` from now on; return the subscription.

        The subscription is made at the first call and kept; a later call replaces its
        callback (``qos``, that of the first, stays).
        """
        key = topic, msg_type
        if key not in self.subscriptions:
            current = [callback]
            sub = self.node.create_subscription(msg_type, topic,
                                                lambda msg: current[0](msg), qos)
            self.subscriptions[key] = sub, current
        sub, current = self.subscriptions[key]
        current[0] = callback
        return sub

    def unsubscribe(self, sub):
        """Destroy a subscription of :meth:`subscribe` (a topic is one type in a node)."""
        for key, (kept, _) in list(self.subscriptions.items()):
            if kept is sub:
                del self.subscriptions[key]
        self.node.destroy_subscription(sub)

    def topic(self, name):
        return f'{self.target}/{name}'

    def spin_until(self, done, seconds):
        """Spin until done() or ``seconds`` have passed; return done()."""
        deadline = time.monotonic() + seconds
        while not done() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)
        return done()

    def found(self):
        """
        Whether the node is there: a service of it answered, or the graph has it.

        A node's name reaches the graph by its participant's own announcements, which can
        come seconds after its topics and services (each discovered for itself) do; the graph
        may also hear of its services after a client of ours has matched them.
        """
        if any(client.service_is_ready() for service, client in self.service_clients.items()
               if service.startswith(self.target + '/')):
            return True
        names = {f"{namespace.rstrip('/')}/{name}"
                 for name, namespace in self.node.get_node_names_and_namespaces()}
        return self.target in names or self.node.count_services(self.topic('describe')) > 0

    def missing(self, what):
        """One line for a ``what`` (topic, service) that did not appear in time."""
        if not self.found():
            domain = os.environ.get('ROS_DOMAIN_ID') or '0'
            return (f'cannot reach node {self.target}: not found within {self.timeout:g} s '
                    f'(is rotation_node running, with ROS_DOMAIN_ID {domain}?)')
        return f'node {self.target} has no {what} (waited {self.timeout:g} s)'

    def call(self, srv_type, name, request):
        """
        Call the node's service ``name``; the response, or Unreachable.

        The service's client is made at the first call and kept for the next ones (a command
        may call ~/describe several times): a new one is discovered by the node anew.
        """
        service = self.topic(name)
        client = self.service_clients.get(service)
        if client is None:
            client = self.service_clients[service] = self.node.create_client(srv_type, service)
        if not self.spin_until(client.service_is_ready, self.timeout):
            raise Unreachable(self.missing(f'service {service}'))
        deadline = time.monotonic() + self.timeout
        while time.monotonic() < deadline:
            future = client.call_async(request)
            if self.spin_until(future.done, min(RESEND, deadline - time.monotonic())):
                return future.result()
            client.remove_pending_request(future)  # the reply may have been dropped
        raise Unreachable(f'no reply from service {service} within {self.timeout:g} s')

    def describe(self):
        from std_srvs.srv import Trigger
        return self.call(Trigger, 'describe', Trigger.Request())

    def parameters(self, names):
        """Return {name: value} of the node's parameters, from its ~/get_parameters service."""
        from rcl_interfaces.srv import GetParameters
        from rclpy.parameter import parameter_value_to_python
        response = self.call(GetParameters, 'get_parameters', GetParameters.Request(names=names))
        return dict(zip(names, map(parameter_value_to_python, response.values)))

    def parameter_values(self, names):
        """Return the node's rcl_interfaces/ParameterValue of each of ``names`` (NOT_SET: none)."""
        from rcl_interfaces.srv import GetParameters
        return list(self.call(GetParameters, 'get_parameters',
                              GetParameters.Request(names=names)).values)

    def parameter_names(self):
        """Return the names of the node's parameters (its ~/list_parameters)."""
        from rcl_interfaces.srv import ListParameters
        return list(self.call(ListParameters, 'list_parameters',
                              ListParameters.Request()).result.names)

    def parameter_types(self, names):
        """
        Return {name: the type the node declares for it (ParameterType)} of ``names``.

        The descriptors come in the order asked, none when one of the names is not declared.
        """
        from rcl_interfaces.srv import DescribeParameters
        descriptors = self.call(DescribeParameters, 'describe_parameters',
                                DescribeParameters.Request(names=names)).descriptors
        return {name: d.type for name, d in zip(names, descriptors)}

    def parameter_type(self, name):
        """Return the type the node declares for parameter ``name`` (ParameterType), or None."""
        return self.parameter_types([name]).get(name)

    def set_parameter(self, parameter):
        """Set one parameter (rcl_interfaces/Parameter); return the node's SetParametersResult."""
        from rcl_interfaces.srv import SetParameters
        request = SetParameters.Request(parameters=[parameter])
        (result,) = self.call(SetParameters, 'set_parameters', request).results
        return result

    def refusal_counts(self):
        """{reason: n} of the refusals the node has counted so far."""
        return _counts(describe_data(self.describe()))

    def refused(self, before, source, stamps=None):
        """Why the node refused what was sent to ``source`` since ``before``, or ''."""
        return refusal_text(describe_data(self.describe()), before, source, stamps)

    def wait_for_match(self, pub, subs):
        """Wait until the node subscribes to ``pub`` and publishes on every one of ``subs``."""
        if not self.spin_until(lambda: pub.get_subscription_count() > 0, self.timeout):
            raise Unreachable(self.missing(f'subscription on {pub.topic_name}'))
        for sub in subs:
            if not self.spin_until(lambda sub=sub: sub.get_publisher_count() > 0,
                                   self.timeout):
                raise Unreachable(self.missing(f'publisher on {sub.topic_name}'))

    def send(self, name, msg, pictures, topic=None, covariance=False):
        """
        Publish ``msg`` on the node's ~/name until it answers; return (topic, stamp, answer).

        ``topic``: where the node reads ~/name when it is remapped (default NODE/name); the
        topic returned is the one really used, after the client's own remappings.

        The answer is {output: message}: the outputs stamped as one sent message, the
        ~/rotation_matrix whose content matches, and, when ``pictures``, the pictures of that
        message if the node draws them within PICTURE_WAIT. Refused when the node's refusal
        counts rise instead. With ``covariance`` (a covariance was sent) the answer has the
        covariance outputs too: their message, or why the node published none
        (:meth:`covariance_answer`).
        """
        from rclpy.qos import QoSProfile
        from rot_tools.ros.message_types import message_class
        msg.header.stamp = self.node.get_clock().now().to_msg()  # one stamp for every resend
        answers = Answers(msg.header)
        matrix = MATRIX
        qos = QoSProfile(depth=100)
        covariances = COVARIANCES if covariance else ()
        wanted = (stamped_outputs() + WITHHELD + covariances
                  + (PICTURES if pictures else ()))
        subs = [self.subscribe(message_class(interface.output_named(name).type_name),
                               self.topic(name), answers.collector(name), qos)
                for name in wanted]
        subs.append(self.subscribe(message_class(interface.output_named(matrix).type_name),
                                   self.topic(matrix), answers.matrices.append, qos))
        pub = self.publisher(type(msg), topic or self.topic(name))
        topic = pub.topic_name
        self.wait_for_match(pub, subs)
        before = self.refusal_counts()
        deadline = time.monotonic() + self.timeout
        while True:
            pub.publish(msg)
            if self.spin_until(answers.complete, min(RESEND, deadline - time.monotonic())):
                break
            refused = self.refused(before, topic, {answers.stamp})
            if refused:
                raise Refused(f'node {self.target} refused the input on {topic}: {refused}')
            if time.monotonic() >= deadline:
                raise Unreachable(f'no answer from node {self.target} to the input on {topic} '
                                  f'within {self.timeout:g} s')
        answer = answers.outputs
        q = answer['quaternion'].quaternion
        R = quaternion_to_matrix([q.x, q.y, q.z, q.w])
        if not self.spin_until(lambda: answers.matrix(R), self.timeout):
            raise Unreachable(f'no matching message on {self.topic(matrix)} '
                              f'within {self.timeout:g} s')
        # Kept now: while the pictures are awaited, another publisher's inputs may push it
        # out of the latest matrices.
        matrix_msg = answers.matrix(R)
        self.spin_until(lambda: set(WITHHELD) <= set(answer), min(PICTURE_WAIT, self.timeout))
        if covariances:
            self.covariance_answer(answer, covariances, before, topic, {answers.stamp})
        if pictures:
            self.spin_until(lambda: set(PICTURES) <= set(answer),
                            min(PICTURE_WAIT, self.timeout))
        return topic, answers.stamp, {**answer, matrix: matrix_msg}

    def covariance_answer(self, answer, names, before, topic, stamps):
        """
        Wait for the covariance outputs ``names`` of ``answer``, or put why there are none.

        ~/describe is served after the input's callback, so it tells what the node did with
        the covariance: published (then awaited), refused (Refused, with the node's reason),
        or neither, unknown or at gimbal lock (the answer holds describe's phrase instead).
        """
        data = describe_data(self.describe())
        refused = refusal_text(data, before, topic, stamps)
        if refused:
            raise Refused(f'node {self.target} refused the covariance sent to {topic}: '
                          f'{refused}')
        phrase = data.get('rpy_stddev')
        if isinstance(phrase, str):
            answer.update(dict.fromkeys(names, phrase))
        elif not self.spin_until(lambda: set(names) <= set(answer), self.timeout):
            raise Unreachable(f'no message on {", ".join(map(self.topic, names))} '
                              f'within {self.timeout:g} s')


def _key(stamp):
    return stamp.sec, stamp.nanosec


class Answers:
    """What the node published for the message sent: its stamped outputs, the matrices."""

    def __init__(self, header):
        self.frame_id = header.frame_id
        self.stamp = _key(header.stamp)
        """(sec, nanosec) of the message sent (and sent again, unchanged, until answered)."""
        self.outputs = {}
        """{output: message} of the stamped outputs of that message."""
        self.matrices = deque(maxlen=100)
        """The latest ~/rotation_matrix messages (they carry no header)."""

    def collector(self, output):
        """Subscription callback keeping the ``output`` messages stamped as the sent one."""
        def collect(msg):
            if hasattr(msg, 'header'):
                header = msg.header
            elif msg.markers:  # a MarkerArray has no header: its markers carry it
                header = msg.markers[0].header
            else:
                return
            if _key(header.stamp) == self.stamp and header.frame_id == self.frame_id:
                self.outputs[output] = msg
        return collect

    def complete(self):
        """Return whether every one of stamped_outputs() has come."""
        return set(stamped_outputs()) <= set(self.outputs)

    def matrix(self, R):
        """Return the latest ~/rotation_matrix equal to R (within MATRIX_MATCH), or None."""
        for m in reversed(self.matrices):
            if np.max(np.abs(np.reshape(m.data, (3, 3)) - R)) <= MATRIX_MATCH:
                return m
        return None
