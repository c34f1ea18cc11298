"""
The executor rot_tools' node runs on: one wait set, services first, bounded bursts.

rot_tools.ros.runtime.make_executor returns a :class:`WaitSetExecutor`; this module is imported
only then (it needs rclpy, which rot_tools.ros.runtime loads late). Why this executor and not one
of rclpy's: the class docstring, and bench/README.md for the figures.
"""

from contextlib import ExitStack
import time

from rclpy.exceptions import InvalidHandle
from rclpy.executors import Executor, ExternalShutdownException
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.subscription import Subscription
from rclpy.utilities import timeout_sec_to_nsec
from rclpy.waitable import NumberOfEntities

BURST = 10
"""Messages taken from one subscription per wake-up at most (the inputs keep the last 10)."""

EVENT_PERIOD = 0.5
"""Seconds between two looks at the waitables (the QoS events: incompatible QoS or type)."""


class WaitSetExecutor(Executor):
    """
    A lean single-threaded executor: one wait set, services first, bounded bursts.

    Each spin_once waits on the subscriptions, services and timers of its nodes and on its
    own guard conditions (a new entity, a signal), and serves what is ready: timers, every
    waiting service request, then at most BURST messages of each ready subscription —
    taken one at a time from the middleware's queue and handed straight to the callback.
    The waitables (rotation_node's are the QoS events of its 15 publishers and
    subscriptions: "incompatible QoS" warnings) are looked at once every EVENT_PERIOD, in a
    wait set of their own without waiting: with the middleware a wait costs in proportion
    to the entities waited on, and the events would double the node's.

    Why not rclpy's executors (bench/README.md has the figures):

    - ``rclpy.experimental.EventsExecutor`` queues one event per arriving message with no
      bound. Under a flood beyond the node's pace the queue grew by 140–160 MB a minute,
      stayed at its size afterwards, and a service request waited behind the whole queue
      (up to 16 s; some never answered).
    - The default SingleThreadedExecutor is fair and bounded — nothing waits outside the
      middleware's keep-last queues — but wraps every callback in a Task, rebuilds its wait
      set in Python for each message, and waits on every entity: up to 2 × the CPU per
      message.

    This one keeps the middleware's bound (keep-last 10 per input: a flood costs lost
    messages, never memory), answers a service within one burst per subscription, and
    costs 1.0–1.3 × the EventsExecutor's CPU per message (the most at one message per
    wake-up). Single-threaded, plain-function callbacks only (a coroutine callback would
    not run): a node with clients or guard conditions is refused (rotation_node has
    none), and so is create_task.
    """

    def __init__(self, *, context=None, burst=BURST, event_period=EVENT_PERIOD):
        super().__init__(context=context)
        self._burst = burst
        self._event_period = event_period
        self._events_due = 0.0  # time.monotonic() of the next look at the waitables
        self._wait_sets = {}  # sizes: a wait set of those sizes (reused)
        self._entities = None  # (subscriptions, services, timers, waitables), None: stale

    def create_task(self, callback, *args, **kwargs):
        raise NotImplementedError(f'{type(self).__name__} runs no tasks')

    def wake(self):
        """Wake the executor: an entity of one of its nodes was created or destroyed."""
        self._entities = None
        super().wake()

    def add_node(self, node):
        self._entities = None
        return super().add_node(node)

    def remove_node(self, node):
        self._entities = None
        super().remove_node(node)

    def _collect(self):
        """Return the subscriptions, services, timers and waitables of every node."""
        subscriptions, services, timers, waitables = [], [], [], []
        for node in self.get_nodes():
            if list(node.clients) or list(node.guards):
                raise RuntimeError(f'{type(self).__name__} serves no clients or guard '
                                   f'conditions ({node.get_fully_qualified_name()} has some)')
            subscriptions.extend(node.subscriptions)
            services.extend(node.services)
            timers.extend(node.timers)
            waitables.extend(node.waitables)
        return subscriptions, services, timers, waitables

    def spin_once(self, timeout_sec=None):
        """Wait at most ``timeout_sec`` for work; serve everything ready once."""
        if self._is_shutdown:
            return
        if self._entities is None:  # (collected again after a node's entities changed)
            self._entities = self._collect()
        subscriptions, services, timers, waitables = self._entities
        wait = max(0.0, self._events_due - time.monotonic())
        if timeout_sec is not None and timeout_sec >= 0:
            wait = min(wait, timeout_sec)
        held = []  # the handles in use: nothing is destroyed while the wait set holds it
        try:
            subscriptions = _enter(held, subscriptions)
            services = _enter(held, services)
            timers = _enter(held, timers)
            guards = _enter(held, (self._guard, self._sigint_gc))
            self._context.handle.__enter__()
            held.append(self._context.handle)
            wait_set = self._wait_set(len(subscriptions), len(guards), len(timers), 0,
                                      len(services), 0)
            for sub in subscriptions:
                wait_set.add_subscription(sub.handle)
            for srv in services:
                wait_set.add_service(srv.handle)
            for timer in timers:
                wait_set.add_timer(timer.handle)
            for guard in guards:
                wait_set.add_guard_condition(guard.handle)

            wait_set.wait(timeout_sec_to_nsec(wait))
            if self._is_shutdown:
                return
            if not self._context.ok():
                raise ExternalShutdownException()

            ready = wait_set.get_ready_entities('timer')
            if ready:
                ready = set(ready)
                for timer in timers:
                    if timer.handle.pointer in ready and timer.handle.is_timer_ready():
                        timer.handle.call_timer()
                        timer.callback()
            ready = wait_set.get_ready_entities('service')
            if ready:
                ready = set(ready)
                for srv in services:
                    if srv.handle.pointer in ready:
                        _serve_requests(srv)
            ready = set(wait_set.get_ready_entities('subscription'))
            for sub in subscriptions:
                if sub.handle.pointer in ready:
                    self._take_messages(sub)
        finally:
            for handle in reversed(held):
                handle.__exit__(None, None, None)
        if waitables and time.monotonic() >= self._events_due:
            self._events_due = time.monotonic() + self._event_period
            self._serve_waitables(waitables)

    def _wait_set(self, *sizes):
        """Return a wait set of these sizes, cleared (one per set of sizes, reused)."""
        wait_set = self._wait_sets.get(sizes)
        if wait_set is None:
            wait_set = self._wait_sets[sizes] = _rclpy.WaitSet(*sizes, self._context.handle)
        wait_set.clear_entities()
        return wait_set

    def _serve_waitables(self, waitables):
        """Execute every ready waitable, without waiting."""
        with ExitStack() as in_use:
            usable, sizes = [], NumberOfEntities()
            for waitable in waitables:
                try:
                    in_use.enter_context(waitable)
                except InvalidHandle:
                    continue
                usable.append(waitable)
                sizes += waitable.get_num_entities()
            in_use.enter_context(self._context.handle)
            wait_set = self._wait_set(
                sizes.num_subscriptions, sizes.num_guard_conditions, sizes.num_timers,
                sizes.num_clients, sizes.num_services, sizes.num_events)
            for waitable in usable:
                waitable.add_to_wait_set(wait_set)
            wait_set.wait(0)
            for waitable in usable:
                if waitable.is_ready(wait_set):
                    _run_now(waitable.execute(waitable.take_data()))

    def _take_messages(self, sub):
        """Hand at most BURST queued messages of ``sub`` to its callback, one at a time."""
        take, msg_type, raw, callback = (sub.handle.take_message, sub.msg_type, sub.raw,
                                         sub.callback)
        message_only = sub._callback_type is Subscription.CallbackType.MessageOnly
        for _ in range(self._burst):
            taken = take(msg_type, raw)
            if taken is None:
                return
            if message_only:
                callback(taken[0])
            else:
                callback(*taken)


def _enter(held, entities):
    """
    Return the entities whose handle could be entered (not the destroyed ones).

    The handles entered are appended to ``held``: the caller exits them.
    """
    usable = []
    for entity in entities:
        handle = entity.handle
        try:
            handle.__enter__()
        except InvalidHandle:
            continue
        held.append(handle)
        usable.append(entity)
    return usable


def _serve_requests(srv):
    """Answer every request waiting on service ``srv``."""
    while True:
        request, header = srv.handle.service_take_request(srv.srv_type.Request)
        if header is None:
            return
        srv.send_response(srv.callback(request, srv.srv_type.Response()), header)


def _run_now(coroutine):
    """Run a coroutine that never suspends (a waitable's execute of a plain callback)."""
    try:
        coroutine.send(None)
    except StopIteration:
        return
    coroutine.close()
    raise RuntimeError('a waitable awaited something; WaitSetExecutor runs no tasks')
