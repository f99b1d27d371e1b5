"""Executor helpers: an executor without rclpy 7's busy loops, a clean stop, a bounded group.

`BoundedCallbackGroup` runs up to N callbacks of a group at once (the planner's plans).

Two busy loops of rclpy 7 (Jazzy) with Fast DDS make a MultiThreadedExecutor spin at
full speed while holding the GIL, so that a node with a 100 Hz timer next to a few
subscriptions drops, at random, to a few callbacks per second:

- The QoS event handlers that rclpy attaches to every publisher and subscription (the
  default "incompatible QoS" and "incompatible type" warnings) wake the wait set over and
  over with nothing ready once a worker thread runs callbacks beside it. This executor
  leaves them out of its wait set: those warnings are not delivered (ftplan registers
  no event callback of its own). Without them it was never seen to spin.
- rclpy re-yields every handler task that has been handed to the thread pool but has not
  started yet, so `spin()` loops without waiting while the workers cannot even start
  (ros2/rclpy#1452, fixed upstream by ros2/rclpy#1547). Our callbacks are plain functions
  that finish in one go, so their handler tasks never need a second yield: this
  executor drops them from the re-yield list as it makes them. (Coroutine callbacks,
  which await, need the re-yield: use rclpy's own executor for those.)
"""

from __future__ import annotations

import os
import signal
import threading
import traceback
from collections.abc import Callable, Sequence

import rclpy
from rclpy.callback_groups import CallbackGroup
from rclpy.context import Context
from rclpy.event_handler import EventHandler
from rclpy.executors import ExternalShutdownException
from rclpy.executors import MultiThreadedExecutor as _RclpyMultiThreadedExecutor
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from .params import STARTUP_ERRORS

MIN_THREADS = 4
_log = rclpy.logging.get_logger('ftplan_spin')
_STOP_POLL = 0.1  # [s] longest wait of a spin loop before it looks for a stop
# What rclpy.init raises when rcl cannot start: `--ros-args` it cannot parse, a
# ROS_DOMAIN_ID that is not a number. rclpy gives it no public name.
RclError = _rclpy.RCLError


class MultiThreadedExecutor(_RclpyMultiThreadedExecutor):
    """rclpy's MultiThreadedExecutor for plain (non-coroutine) callbacks, minus its busy loop.

    It runs one thread per core, for the plans that wait on plan workers side by side (at
    most one per core), and `MIN_THREADS` more, so that slow plans never leave the other
    callbacks of a process without one.
    """

    def __init__(self, num_threads: int | None = None, *, context=None):
        super().__init__(num_threads or MIN_THREADS + (os.cpu_count() or 1), context=context)

    def can_execute(self, entity) -> bool:
        """Leave QoS event handlers out of the wait set (the first busy loop above)."""
        return not isinstance(entity, EventHandler) and super().can_execute(entity)

    def spin_once(self, timeout_sec: float | None = None) -> None:
        """Run one callback, like rclpy; one that raised is logged and spinning goes on.

        rclpy re-raises a callback's exception from `spin_once`, which ends `spin()` and
        with it every node of the process: one bad message must not do that.
        """
        try:
            super().spin_once(timeout_sec)
        except Exception:  # noqa: BLE001 - any callback's failure, logged in full
            _log.error(f'a callback raised; the nodes keep spinning:\n{traceback.format_exc()}')

    def shutdown(self, timeout_sec: float | None = None) -> bool:
        """Shut down after `spin` has returned: first run every handler already handed out.

        rclpy 7 destroys its guard condition without waiting for the handlers queued in
        its thread pool (it tests its shutdown flag right after setting it); each of them
        then fails on that guard, and the failure is printed as "exception was never
        retrieved" when the handler is collected. Failures of the handlers that ran since
        the last `spin_once` are logged here rather than lost.
        """
        self._executor.shutdown(wait=True)
        for handler in self._futures:
            if handler.done() and handler.exception() is not None:
                _log.error(f'a callback raised: {handler.exception()!r}')
        self._futures.clear()
        return super().shutdown(timeout_sec)

    def spin_until(self, stop: threading.Event) -> None:
        """Spin until `stop` is set (looked at every `_STOP_POLL` [s]) or the context ends."""
        try:
            while not stop.is_set() and self.context.ok():
                self.spin_once(timeout_sec=_STOP_POLL)
        except ExternalShutdownException:
            pass

    def _make_handler(self, entity, node, take_from_wait_list):
        task = super()._make_handler(entity, node, take_from_wait_list)
        with self._tasks_lock:
            self._tasks = [entry for entry in self._tasks if entry[0] is not task]
        return task


class BoundedCallbackGroup(CallbackGroup):
    """Run at most `limit` callbacks of the group at once (1: mutually exclusive).

    The callbacks past the limit wait where they are (a service's requests in its queue)
    rather than in executor threads.
    """

    def __init__(self, limit: int):
        super().__init__()
        if limit < 1:
            raise ValueError(f'a callback group runs at least 1 callback at once, got {limit}')
        self.limit = limit
        self._running = 0
        self._lock = threading.Lock()

    def can_execute(self, entity) -> bool:
        """Whether a callback may start now."""
        with self._lock:
            return self._running < self.limit

    def beginning_execution(self, entity) -> bool:
        """Count a callback in, if there is room."""
        with self._lock:
            if self._running >= self.limit:
                return False
            self._running += 1
            return True

    def ending_execution(self, entity) -> None:
        """Count a callback out."""
        with self._lock:
            self._running -= 1


class BackgroundSpin:
    """Nodes spinning on our MultiThreadedExecutor in a daemon thread, and a clean stop."""

    def __init__(self, nodes: Sequence[Node] = (), *, context: Context | None = None,
                 name: str = 'ftplan-spin'):
        self.executor = MultiThreadedExecutor(context=context)
        self.nodes: list[Node] = []
        for node in nodes:
            self.add(node)
        self._stopping = threading.Event()
        self.thread = threading.Thread(target=self.executor.spin_until, args=(self._stopping,),
                                       name=name, daemon=True)
        self.thread.start()

    def add(self, node: Node) -> Node:
        """Spin `node` too; return it."""
        self.nodes.append(node)
        self.executor.add_node(node)
        return node

    def stop(self, timeout: float = 5.0) -> None:
        """Stop spinning, let the callbacks handed out finish and destroy every node."""
        for node in self.nodes:
            self.executor.remove_node(node)
        self._stopping.set()
        self.thread.join(timeout=timeout)
        self.executor.shutdown()
        for node in self.nodes:
            node.destroy_node()


def run_node(make_node: Callable[[], Node], name: str, args: list[str] | None = None) -> int:
    """Init rclpy, build the node and spin it until Ctrl-C or SIGTERM (every node's main).

    Returns 0, or 2 when the node cannot start (rcl refuses `--ros-args` or the
    environment, a bad scene file or parameter), after one fatal log line.

    The signals only set a flag, which `MultiThreadedExecutor.spin_until` reads at least
    every `_STOP_POLL` [s]. rclpy's own handlers are not installed: its signal thread triggers every
    executor's guard condition while KeyboardInterrupt, raised in this thread, already
    shuts the executor down and destroys its guard condition; the planner died in
    rcl_trigger_guard_condition (SIGSEGV) about once in 30 stops under load.
    """
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except RclError as error:
        rclpy.logging.get_logger(name).fatal(f'cannot start: {error}')
        return 2
    stop = threading.Event()
    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, lambda signum, frame: stop.set())
    executor = MultiThreadedExecutor()
    node = None
    try:
        node = make_node()
        executor.add_node(node)
        executor.spin_until(stop)
    except STARTUP_ERRORS as error:
        rclpy.logging.get_logger(name).fatal(f'cannot start: {error}')
        return 2
    finally:
        executor.shutdown()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
