"""Plan workers: processes that plan jobs side by side, for the planner's `plan_workers`.

A plan is CPU-bound Python and numba under one GIL: in the node's process requests are
planned one at a time, however many cores there are. `PlanPool.run(job)` plans a
PlanJob (plan_jobs.py) in one of its worker processes instead and returns what
`run_job` returns there; callers on as many threads as there are workers plan at once.

- Start method 'forkserver': the node process runs rclpy's and DDS's threads, and a
  process forked from it could inherit a lock one of them held. The fork server is a
  fresh interpreter that imported this module (and the core) once; workers are forked
  from it, so a new one starts in a fraction of a second.
- Robots: every job carries its robot (about 14 kB pickled for a Panda). A worker keeps
  the robots it has seen by the key the pool gave them and plans with its own copy, so
  that its ManifoldCache (one per worker, cleared on a new seed) finds the manifolds it
  traced for the same task before; each worker fills its cache for itself. A worker
  loads the compiled kernels for a robot (`load_kernels`) before it plans with it:
  `use_robot` returns once the idle workers have, a new worker has before it takes a
  job, and a worker busy when the robot changed does so before its next job.
- The timeout travels with the job: the worker stops at the first stage past it, as the
  node does. A worker still busy OVERRUN_GRACE [s] after it (plus WARM_ALLOWANCE when it
  loads a robot's kernels first) is killed and replaced, and the job ends with
  PlanTimeout.
- A worker that dies (a crash in compiled code) fails its job with PlanWorkerError; a
  new worker takes its place in the background, and the caller's process stays up. One
  found dead while idle is replaced before it gets a job.
- `close()` ends every worker. A worker whose node died sees its connection close:
  at once when idle, at the next stage of its search when busy.

The worker's side is plan_worker.py. No rclpy here either: the fork server imports it.
"""

from __future__ import annotations

import itertools
import logging
import multiprocessing
import queue
import signal
import threading
import time
from collections import OrderedDict
from multiprocessing.connection import wait

from ftplan_ros.core import InputError, PlanResult, Robot
from ftplan_ros.core.planning.reachable import ReachablePlan

from .plan_jobs import PlanJob, PlanTimeout
from .plan_worker import ROBOTS_KEPT, serve

OVERRUN_GRACE = 2.0     # [s] a worker's time past the deadline to stop at its next stage
WARM_ALLOWANCE = 120.0  # [s] more for a worker that loads (or compiles) a robot's kernels
CLOSE_WAIT = 5.0        # [s] longest wait for the workers to exit at close
START_ATTEMPTS = 3      # a worker that dies as it starts is started again, this often
_log = logging.getLogger(__name__)


class PlanWorkerError(RuntimeError):
    """A job has no result: its worker died, raised, or the pool is closed."""


class _RemoteTracebackError(Exception):
    """A worker's traceback, shown as the cause of the PlanWorkerError it led to."""

    def __str__(self) -> str:
        return self.args[0]


class _WorkerLost(Exception):  # noqa: N818 - what happened to a worker, not a caller's error
    """The worker died; the message says how."""


class _WorkerHung(_WorkerLost):
    """The worker was still busy past its time: it was killed."""


class _Worker:
    """The pool's end of one worker process: its connection and the robots it holds."""

    def __init__(self, context: multiprocessing.context.BaseContext):
        self.connection, there = context.Pipe()
        self.process = context.Process(target=serve, args=(there,), daemon=True,
                                       name='ftplan-plan-worker')
        self.process.start()
        there.close()  # the worker's end is the worker's: its close is the worker's exit
        self.robots: set[int] = set()
        self.busy = False

    @property
    def pid(self) -> int:
        """The worker's process id."""
        return self.process.pid

    def send(self, message: tuple) -> None:
        """Send `message`; _WorkerLost if the worker is gone."""
        try:
            self.connection.send(message)
        except OSError:
            raise _WorkerLost(self.ended()) from None

    def receive(self, kill_at: float) -> tuple:
        """Return the worker's reply; past `kill_at` (monotonic [s]) kill it: _WorkerLost."""
        ready = wait([self.connection, self.process.sentinel],
                     timeout=max(0.0, kill_at - time.monotonic()))
        if not ready:
            self.stop()
            raise _WorkerHung('was still busy past its time and was killed')
        if self.connection in ready:
            try:
                return self.connection.recv()
            except (EOFError, OSError):
                pass  # it died as it answered
        raise _WorkerLost(self.ended())

    def stop(self) -> None:
        """Kill the worker and reap it."""
        self.process.kill()
        self.process.join(timeout=CLOSE_WAIT)
        self.connection.close()

    def ended(self) -> str:
        """Reap the (dead) worker and say how it ended, e.g. 'died of SIGSEGV'."""
        self.process.join(timeout=CLOSE_WAIT)
        code = self.process.exitcode
        if code is None:
            return 'stopped answering'
        if code < 0:
            return f'died of {signal.Signals(-code).name}'
        return f'exited with code {code}'


class PlanPool:
    """`size` plan worker processes; `run` plans a job in an idle one (module docstring)."""

    def __init__(self, size: int):
        if size < 1:
            raise ValueError(f'a plan pool needs at least 1 worker, got {size}')
        self.size = size
        self._context = multiprocessing.get_context('forkserver')
        self._context.set_forkserver_preload([serve.__module__])
        self._lock = threading.Lock()
        self._idle: queue.SimpleQueue[_Worker] = queue.SimpleQueue()
        self._workers: list[_Worker] = []
        self._robot_keys: OrderedDict[Robot, int] = OrderedDict()
        self._new_keys = itertools.count(1)  # never reused: a worker holds robots by key
        self._robot: tuple[int, Robot] | None = None  # the robot new workers warm up for
        self._closed = False
        for _ in range(size):
            self._idle.put(self._start())

    @property
    def pids(self) -> tuple[int, ...]:
        """The process ids of the workers."""
        with self._lock:
            return tuple(worker.pid for worker in self._workers)

    @property
    def busy(self) -> tuple[int, ...]:
        """The process ids of the workers planning a job now."""
        with self._lock:
            return tuple(worker.pid for worker in self._workers if worker.busy)

    def use_robot(self, robot: Robot) -> None:
        """Plan for `robot` from now on: the idle workers load its kernels (returns then).

        Busy workers load them before their next job; new workers as they start.
        """
        key = self._key(robot)
        with self._lock:
            self._robot = (key, robot)
        idle = []
        while True:
            try:
                idle.append(self._idle.get_nowait())
            except queue.Empty:
                break
        warming = []
        for worker in idle:  # side by side: all are sent their robot before any is waited for
            try:
                worker.send(('warm', key, robot))
                warming.append(worker)
            except _WorkerLost:
                self._replace(worker)
        kill_at = time.monotonic() + WARM_ALLOWANCE
        for worker in warming:
            try:
                worker.receive(kill_at)
            except _WorkerLost:
                self._replace(worker)
                continue
            worker.robots.add(key)
            self._idle.put(worker)

    def run(self, job: PlanJob) -> tuple[PlanResult, ReachablePlan | None]:
        """Plan `job` in a worker; return (result, reachable) as `run_job` does.

        Raises PlanTimeout (past the timeout), InputError (a job the core refuses) or
        PlanWorkerError (the worker died or raised; a dead one is replaced).
        """
        worker = self._take()
        key = self._key(job.scene.robot)
        allowance = 0.0 if key in worker.robots else WARM_ALLOWANCE
        try:
            worker.send(('plan', key, job))
            reply = worker.receive(time.monotonic() + job.timeout + OVERRUN_GRACE + allowance)
        except _WorkerHung:
            self._replace(worker)
            raise PlanTimeout(f'plan worker {worker.pid} was still busy {OVERRUN_GRACE:g} s '
                              'past the timeout; a new worker takes its place') from None
        except _WorkerLost as lost:
            self._replace(worker)
            raise PlanWorkerError(f'plan worker {worker.pid} {lost} while planning; a new '
                                  'worker takes its place') from None
        except BaseException:  # a message that does not (un)pickle: a fresh worker, in doubt
            self._replace(worker)
            raise
        worker.robots.add(key)
        self._give_back(worker)
        kind, *details = reply
        if kind == 'timeout':
            raise PlanTimeout(details[0])
        if kind == 'refused':
            raise InputError(*details)
        if kind == 'error':
            raise PlanWorkerError(f'{details[0]} in plan worker {worker.pid}') \
                from _RemoteTracebackError(details[1])
        return details[0], details[1]

    def close(self) -> None:
        """End every worker: idle ones exit as their connection closes, busy ones are killed."""
        with self._lock:
            self._closed = True
            workers, self._workers = self._workers, []
        for worker in workers:
            if worker.busy:
                worker.process.kill()
            else:
                worker.connection.close()
        deadline = time.monotonic() + CLOSE_WAIT
        for worker in workers:
            worker.process.join(timeout=max(0.0, deadline - time.monotonic()))
            if worker.process.is_alive():
                worker.process.kill()
                worker.process.join(timeout=CLOSE_WAIT)

    # Workers ------------------------------------------------------------------------

    def _start(self) -> _Worker:
        """Start a worker; it loads the current robot's kernels before it is returned."""
        with self._lock:
            if self._closed:
                raise PlanWorkerError('the planner is shutting down')
        worker = _Worker(self._context)
        with self._lock:
            self._workers.append(worker)
            robot = self._robot
        if robot is not None:
            try:
                worker.send(('warm', *robot))
                worker.receive(time.monotonic() + WARM_ALLOWANCE)
            except _WorkerLost:
                worker.stop()
                self._forget(worker)
                raise
            worker.robots.add(robot[0])
        return worker

    def _take(self) -> _Worker:
        """Return an idle live worker (one found dead is replaced now).

        There is one for each caller of `run` up to `size`, or one warming up in its
        place; waiting WARM_ALLOWANCE [s] in vain means the pool lost workers it could
        not replace.
        """
        try:
            worker = self._idle.get(timeout=WARM_ALLOWANCE)
        except queue.Empty:
            raise PlanWorkerError(f'no plan worker was free within {WARM_ALLOWANCE:g} s') \
                from None
        if not worker.process.is_alive():
            _log.warning(f'plan worker {worker.pid} {worker.ended()} while idle; replaced')
            self._forget(worker)
            try:
                worker = self._start()
            except _WorkerLost as lost:
                raise PlanWorkerError(f'a new plan worker {lost} as it started') from None
        with self._lock:
            worker.busy = True
        return worker

    def _give_back(self, worker: _Worker) -> None:
        with self._lock:
            worker.busy = False
        self._idle.put(worker)

    def _replace(self, worker: _Worker) -> None:
        """Stop `worker` and start one in its place in the background (it warms up first)."""
        worker.stop()
        self._forget(worker)
        threading.Thread(target=self._refill, name='ftplan-plan-worker-start',
                         daemon=True).start()

    def _refill(self) -> None:
        for attempt in range(START_ATTEMPTS):
            try:
                self._idle.put(self._start())
                return
            except PlanWorkerError:  # closed
                return
            except _WorkerLost as lost:
                _log.error(f'a new plan worker {lost} as it started (attempt {attempt + 1} '
                           f'of {START_ATTEMPTS})')

    def _forget(self, worker: _Worker) -> None:
        with self._lock:
            if worker in self._workers:
                self._workers.remove(worker)

    def _key(self, robot: Robot) -> int:
        """Return the key of `robot` (equal robots share one), new keys counting up."""
        with self._lock:
            key = self._robot_keys.get(robot)
            if key is None:
                key = self._robot_keys[robot] = next(self._new_keys)
                if len(self._robot_keys) > ROBOTS_KEPT:
                    self._robot_keys.popitem(last=False)
            self._robot_keys.move_to_end(robot)
            return key
