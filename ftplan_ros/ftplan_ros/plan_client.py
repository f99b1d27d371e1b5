"""PlanClient: plan and execute failure-tolerant motions from Python, without futures.

In the spirit of nav2_simple_commander's BasicNavigator: a Node that owns its spinning
(its own executor, spun only inside its verbs), so a script or a test just calls

    rclpy.init()
    client = PlanClient()
    client.wait_until_ready()
    motion = client.plan(goal=(1.0, 0.0))          # from where the arm is now
    # a spatial arm: goal=(x, y, z) or (x, y, z, qx, qy, qz, qw), as the planner's task_kind
    if motion.result is Outcome.SUCCEEDED:
        report = client.execute(motion)
        print(report.result, report.message)
    client.destroy_node()

`plan` returns θ_s, the nominal trajectory and the failure surface as one PlannedMotion
(gathered from the service response and the planner's latched topics, as the executor
gathers them: nodes/plan_assembly.py); when there is no plan its message carries the
planner's reason from /diagnostics. `execute` calls
/ftplan/execute and follows the executor's status until the arm is at the goal or the
execution failed. Never use a PlanClient from inside another node's callback: its verbs
block while they spin.

While a verb waits for a node, it watches the ROS graph: once the service it called has
no server (the node stopped, or its process died), it ends with Outcome.FAILED saying
which service left, instead of waiting for its timeout. A node that stops cleanly leaves
the graph at once; one that dies (SIGKILL, a crash) leaves it when DDS declares it lost:
Fast DDS's default participant lease is 20 s.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import Enum

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseStamped
from nav_msgs.srv import GetPlan
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, Header
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from ftplan_msgs_py import DiagnosticReading, create_pose, read_diagnostic_status, read_path_poses

from .nodes.plan_assembly import LatchedPlan, PlanTopics
from .nodes.qos import LATCHED_QOS
from .nodes.reporting import parse_number, stamp_key
from .nodes.tasks import pose_of_task_point
from .nodes.topics import (
    DIAGNOSTICS,
    EXECUTE_SERVICE,
    EXECUTOR_NODE,
    FAILURE_SURFACE,
    PLAN_INFO,
    PLAN_SERVICE,
    PLANNER_NODE,
    START_CONFIGURATION,
    TRAJECTORY,
)

_POLL = 0.02  # [s] longest single wait of the client's executor
_STATUS_LOG_SIZE = 500  # recent /diagnostics statuses kept
_STATUS_WAIT = 1.0  # [s] longest wait for the planner's status of a plan once it answered
# The planner's latched results of this many recent plans are kept: plans answered side by
# side (plan workers) publish theirs back to back, and the client's own may not be the last.
_PLAN_HISTORY = 20
_GONE_AFTER = 0.5  # [s] a service without a server this long has left, not flickered


class Outcome(Enum):
    """How a verb ended (like nav2's TaskResult)."""

    SUCCEEDED = 'succeeded'
    FAILED = 'failed'           # the node answered: no plan, or the execution failed
    TIMED_OUT = 'timed out'     # no (complete) answer within the timeout
    UNAVAILABLE = 'unavailable'  # the service is not there


@dataclass(frozen=True, eq=False)
class PlannedMotion:
    """The outcome of a plan request; the arrays are set when `result` is SUCCEEDED.

    Angles [rad], positions [m], times [s].
    """

    result: Outcome
    message: str
    stamp: str = ''                          # the plan's stamp 'sec.nanosec'
    joint_names: tuple[str, ...] = ()
    path: np.ndarray | None = None           # (k, 3) end-effector path
    orientations: np.ndarray | None = None   # (k, 4) its quaternions (x, y, z, w)
    theta_s: np.ndarray | None = None        # (n,) start configuration
    trajectory: np.ndarray | None = None     # (k, n) nominal joint path
    times: np.ndarray | None = None          # (k,) its times from start
    surface: np.ndarray | None = None        # (K, W, n) failure surface S_F
    nominal_index: int | None = None         # which path of S_F is the nominal one
    round_trip_s: float = float('nan')       # request sent -> response received
    plan_time_s: float = float('nan')        # the core's plan time, from the planner's status
    task_kind: str = ''                      # planar, position, axis or pose (planner's status)
    tolerated_joints: tuple[str, ...] = ()   # whose lock the plan survives (planner's status)
    approach: str = ''                       # how the arm gets to θ_s, or why not (status)

    @property
    def succeeded(self) -> bool:
        """Whether there is a failure-tolerant plan."""
        return self.result is Outcome.SUCCEEDED


@dataclass(frozen=True)
class ExecutionReport:
    """The outcome of an execution, from the executor's final status."""

    result: Outcome
    message: str
    execution: int | None = None
    values: dict = field(default_factory=dict)   # the status values, as text

    def number(self, key: str, default: float = float('nan')) -> float:
        """Return a numeric status value (e.g. 'recovery_time_s', 'lock_progress')."""
        try:
            return float(self.values[key])
        except (KeyError, ValueError):
            return default


class PlanClient(Node):
    """Call the ftplan planner and executor with blocking verbs; see the module docstring."""

    def __init__(self, node_name: str = 'ftplan_plan_client', *,
                 planner_name: str = PLANNER_NODE, executor_name: str = EXECUTOR_NODE,
                 interrupted: threading.Event | None = None, **kwargs):
        """Make the client node; see the class docstring.

        `interrupted`, once set (e.g. by a signal handler), makes every wait raise
        KeyboardInterrupt, between two turns of the executor, where it is safe.
        """
        super().__init__(node_name, **kwargs)
        self._interrupted = interrupted
        self._planner_status = f'{planner_name}: plan'
        self._executor_status = f'{executor_name}: execution'
        self.plan_client = self.create_client(GetPlan, PLAN_SERVICE)
        self.execute_client = self.create_client(Trigger, EXECUTE_SERVICE)
        self._trigger_clients: dict[str, object] = {}
        self._statuses: dict[str, DiagnosticReading] = {}
        self._status_log: list[tuple[int, DiagnosticReading]] = []
        self._status_seq = 0
        self._status_listeners: list[Callable[[DiagnosticReading], None]] = []
        self._plans = PlanTopics(kept=_PLAN_HISTORY)  # the latched results of recent plans
        self.create_subscription(DiagnosticArray, DIAGNOSTICS, self._diagnostics_callback, 50)
        results_qos = QoSProfile(depth=_PLAN_HISTORY, durability=LATCHED_QOS.durability,
                                 reliability=LATCHED_QOS.reliability)
        for msg_type, topic, kept in ((JointState, START_CONFIGURATION, self._plans.starts),
                                      (JointTrajectory, TRAJECTORY, self._plans.trajectories),
                                      (Float64MultiArray, FAILURE_SURFACE, self._plans.surfaces)):
            self.create_subscription(msg_type, topic, lambda msg, kept=kept: kept.append(msg),
                                     results_qos)
        # The statuses that describe no plan are left aside: the client waits for its own.
        self.create_subscription(DiagnosticArray, PLAN_INFO, self._plans.add_info, results_qos)
        self._executor = SingleThreadedExecutor(context=self.context)
        self._executor.add_node(self)

    def destroy_node(self) -> None:
        """Stop the client's executor and destroy the node."""
        self._executor.remove_node(self)
        self._executor.shutdown()
        super().destroy_node()

    # Spinning -----------------------------------------------------------------------

    def spin_until(self, done: Callable[[], bool], timeout: float) -> bool:
        """Spin this client until `done()` or `timeout` [s]; return whether it is done."""
        deadline = time.monotonic() + timeout
        while not done():
            if self._interrupted is not None and self._interrupted.is_set():
                raise KeyboardInterrupt
            left = deadline - time.monotonic()
            if left <= 0.0:
                return False
            self._executor.spin_once(timeout_sec=min(_POLL, left))
        return True

    def _call(self, client, request, timeout: float):
        """Call a service; return (response or None, round trip [s], whether its server left).

        Gives up early when the service has no server any more (`_ServerWatch`).
        """
        sent = time.perf_counter()
        future = client.call_async(request)
        left = _ServerWatch(client)
        self.spin_until(lambda: future.done() or left(), timeout)
        elapsed = time.perf_counter() - sent
        if not future.done():
            client.remove_pending_request(future)
            return None, elapsed, left.gone
        return future.result(), elapsed, False

    def _diagnostics_callback(self, msg: DiagnosticArray) -> None:
        for status in msg.status:
            try:
                reading = read_diagnostic_status(status)
            except ValueError:
                continue
            self._statuses[reading.name] = reading
            self._status_seq += 1
            self._status_log.append((self._status_seq, reading))
            for listener in self._status_listeners:
                listener(reading)
        del self._status_log[:-_STATUS_LOG_SIZE]

    def add_status_listener(self, listener: Callable[[DiagnosticReading], None]) -> None:
        """Call `listener` with every status read from /diagnostics, as it comes.

        For what must outlast the bounded log of recent statuses (`statuses`).
        """
        self._status_listeners.append(listener)

    def status(self, name: str) -> DiagnosticReading | None:
        """Return the latest status `name` seen on /diagnostics (e.g. 'ftplan_sim: arm')."""
        return self._statuses.get(name)

    @property
    def status_mark(self) -> int:
        """A mark in the status log: pass it as `since` to look only at later statuses."""
        return self._status_seq

    def statuses(self, name: str, since: int = 0) -> list[DiagnosticReading]:
        """Return the recent statuses `name` (after the mark `since`), oldest first."""
        return [reading for seq, reading in self._status_log
                if reading.name == name and seq > since]

    def wait_for_status(self, name: str, accept: Callable[[dict], bool], timeout: float,
                        since: int = 0, give_up: Callable[[], bool] = lambda: False,
                        ) -> DiagnosticReading | None:
        """Spin until a status `name` after `since` has values that `accept`.

        Returns None after `timeout` [s], or as soon as `give_up()` is true.
        """
        found: list[DiagnosticReading] = []

        def seen() -> bool:
            for seq, reading in self._status_log:
                if seq > since and reading.name == name and accept(reading.values):
                    found.append(reading)
                    return True
            return give_up()

        self.spin_until(seen, timeout)
        return found[0] if found else None

    # Verbs --------------------------------------------------------------------------

    def wait_until_ready(self, timeout: float = 10.0) -> bool:
        """Wait until the plan and execute services are available."""
        deadline = time.monotonic() + timeout
        for client in (self.plan_client, self.execute_client):
            if not self.spin_until(client.service_is_ready, max(0.0, deadline -
                                                                time.monotonic())):
                self.get_logger().warning(f'{client.srv_name} is not available')
                return False
        return True

    def plan(self, goal: Sequence[float] | PoseStamped | None = None,
             start: Sequence[float] | PoseStamped | None = None,
             tolerance: float = 0.0, frame_id: str = 'base_link',
             timeout: float = 30.0) -> PlannedMotion:
        """Ask for a failure-tolerant plan from `start` (None: where the arm is) to `goal`.

        :param goal: a task point in `frame_id` [m] (task_space.py: (x, y), (x, y, z),
            (x, y, z, ax, ay, az) or (x, y, z, qx, qy, qz, qw)) or a PoseStamped; None: the
            scene's goal. What the planner takes from it is its `task_kind`.
        :param start: likewise; None: the arm's current position.
        :param tolerance: goal tolerance [m]; 0 keeps the scene's. GetPlan carries it as a
            float32, so it must be 0 or between 1.2e-38 and 3.4e38 (ValueError otherwise).
        :param timeout: seconds to wait for the answer and the latched plan topics.
        """
        tolerance = _float32_tolerance(tolerance)
        if not self.spin_until(self.plan_client.service_is_ready, min(timeout, 5.0)):
            return PlannedMotion(Outcome.UNAVAILABLE, f'{PLAN_SERVICE} is not available')
        request = GetPlan.Request(start=_pose(start, frame_id), goal=_pose(goal, frame_id),
                                  tolerance=float(tolerance))
        deadline = time.monotonic() + timeout
        mark = self.status_mark
        response, round_trip, left = self._call(self.plan_client, request, timeout)
        if left:
            return PlannedMotion(Outcome.FAILED, _left(PLAN_SERVICE, 'planner'),
                                 round_trip_s=round_trip)
        if response is None:
            return PlannedMotion(Outcome.TIMED_OUT, f'no answer from {PLAN_SERVICE} within '
                                 f'{timeout} s', round_trip_s=round_trip)
        key = stamp_key(response.plan.header.stamp)
        if not response.plan.poses:
            status = self._plan_status(key, mark, _STATUS_WAIT)
            reason = status.message if status else \
                'no failure-tolerant plan (the planner\'s reason did not arrive)'
            return PlannedMotion(Outcome.FAILED, reason, key, round_trip_s=round_trip,
                                 plan_time_s=_plan_time(status))
        gathered = self._gather_plan(key, max(0.0, deadline - time.monotonic()))
        # The planner reports a plan once it has published the plan's topics: after them.
        status = self._plan_status(key, mark, min(_STATUS_WAIT,
                                                  max(0.0, deadline - time.monotonic())))
        plan_time = _plan_time(status)
        if gathered is None:
            return PlannedMotion(Outcome.TIMED_OUT, f'plan {key} answered, but its latched '
                                 'topics did not all arrive', key, round_trip_s=round_trip,
                                 plan_time_s=plan_time)
        if isinstance(gathered, str):
            return PlannedMotion(Outcome.FAILED, f'plan {key}: {gathered}', key,
                                 round_trip_s=round_trip, plan_time_s=plan_time)
        try:
            path, orientations = read_path_poses(response.plan)
        except ValueError as error:
            return PlannedMotion(Outcome.FAILED, f'plan {key}: unreadable Path: {error}', key,
                                 round_trip_s=round_trip, plan_time_s=plan_time)
        return PlannedMotion(Outcome.SUCCEEDED, status.message if status else 'plan found',
                             key, gathered.joint_names, path, orientations, gathered.theta_s,
                             gathered.trajectory, gathered.times, gathered.paths,
                             gathered.nominal, round_trip, plan_time, gathered.info.task_kind,
                             gathered.info.tolerated_joints,
                             status.values.get('approach', '') if status else '')

    def _plan_status(self, key: str, mark: int, timeout: float) -> DiagnosticReading | None:
        """Wait for the planner's status of plan `key` after `mark`; None after `timeout` [s]."""
        return self.wait_for_status(self._planner_status, lambda v: v.get('stamp') == key,
                                    timeout, mark)

    def _gather_plan(self, key: str, timeout: float) -> LatchedPlan | str | None:
        """θ_s, trajectory, S_F and plan status of plan `key` from the latched topics.

        Returns None on timeout, and the reason as a string when they cannot be read (S_F
        carries no stamp: an unreadable one may be another publisher's, so the plan's own is
        waited for until the timeout).
        """
        found: list[LatchedPlan] = []
        problems: list[str] = []

        def complete() -> bool:
            try:
                plan = self._plans.assemble(key)
            except ValueError as error:
                problems[:] = [f'unreadable plan topics: {error}']
                return False
            found.extend([plan] if plan is not None else [])
            return plan is not None

        if self.spin_until(complete, timeout):
            return found[0]
        return problems[0] if problems else None

    def execute(self, motion: PlannedMotion | None = None, timeout: float = 120.0,
                ) -> ExecutionReport:
        """Execute the executor's plan (`motion`'s, once the executor holds it) to the end.

        Returns when the executor reports done (SUCCEEDED) or failed (FAILED), leaves the
        ROS graph (FAILED), or after `timeout` [s] (TIMED_OUT).
        """
        if not self.spin_until(self.execute_client.service_is_ready, min(timeout, 5.0)):
            return ExecutionReport(Outcome.UNAVAILABLE, f'{EXECUTE_SERVICE} is not available')
        deadline = time.monotonic() + timeout
        if motion is not None and motion.stamp:
            held = self.wait_for_status(self._executor_status,
                                         lambda v: v.get('plan') == motion.stamp,
                                         min(timeout, 5.0))
            if held is None:
                return ExecutionReport(Outcome.TIMED_OUT,
                                       f'the executor did not receive plan {motion.stamp}')
        mark = self.status_mark
        response, _, left = self._call(self.execute_client, Trigger.Request(),
                                       max(0.0, deadline - time.monotonic()))
        if left:
            return ExecutionReport(Outcome.FAILED, _left(EXECUTE_SERVICE, 'executor'))
        if response is None:
            return ExecutionReport(Outcome.TIMED_OUT, f'no answer from {EXECUTE_SERVICE}')
        if not response.success:
            return ExecutionReport(Outcome.FAILED, response.message)
        number = _execution_number(response.message)
        gone = _ServerWatch(self.execute_client)
        final = self.wait_for_status(
            self._executor_status,
            lambda v: v.get('execution') == str(number) and v.get('state') in ('done', 'failed'),
            max(0.0, deadline - time.monotonic()), mark, gone)
        if final is None and gone.gone:
            return ExecutionReport(Outcome.FAILED, f'execution {number}: the executor left '
                                   f'the ROS graph ({EXECUTE_SERVICE} has no server) before it '
                                   'finished', number)
        if final is None:
            return ExecutionReport(Outcome.TIMED_OUT, f'execution {number} did not finish '
                                   f'within {timeout} s', number)
        result = Outcome.SUCCEEDED if final.values['state'] == 'done' else Outcome.FAILED
        return ExecutionReport(result, final.message, number, dict(final.values))

    def trigger(self, service: str, timeout: float = 5.0) -> tuple[bool, str]:
        """Call a std_srvs/Trigger service (e.g. '/ftplan_sim/reset'); (success, message)."""
        client = self._trigger_clients.get(service)
        if client is None:
            client = self._trigger_clients[service] = self.create_client(Trigger, service)
        if not self.spin_until(client.service_is_ready, timeout):
            return False, f'{service} is not available'
        response, _, left = self._call(client, Trigger.Request(), timeout)
        if left:
            return False, _left(service, 'node serving it')
        if response is None:
            return False, f'no answer from {service} within {timeout} s'
        return response.success, response.message


class _ServerWatch:
    """Whether a client's service lost its server: called while waiting on the client.

    True (and `gone` too) once the service has had no server for `_GONE_AFTER` [s] on end:
    the server left the ROS graph.
    """

    def __init__(self, client):
        self._client = client
        self._missing_since: float | None = None
        self.gone = False

    def __call__(self) -> bool:
        if self._client.service_is_ready():
            self._missing_since = None
            return False
        now = time.monotonic()
        if self._missing_since is None:
            self._missing_since = now
        self.gone = now - self._missing_since >= _GONE_AFTER
        return self.gone


def _left(service: str, server: str) -> str:
    """Say that `service` lost its server (the `server`, e.g. 'planner') before answering."""
    return (f'{service} left the ROS graph before answering: the {server} is gone (stopped, '
            'or its process died)')


def _plan_time(status: DiagnosticReading | None) -> float:
    """Return the core's plan time [s] a planner status carries; NaN without one."""
    return parse_number(status.values.get('plan_time_s')) if status else float('nan')


def _float32_tolerance(tolerance: float) -> float:
    """Return a goal tolerance [m] that GetPlan's float32 carries; ValueError naming it if not.

    A positive value below float32's smallest normal number would arrive as 0 (the
    scene's tolerance) or stripped of its digits, without a word.
    """
    value = float(tolerance)
    tiny, huge = float(np.finfo(np.float32).tiny), float(np.finfo(np.float32).max)
    if not np.isfinite(value) or value < 0.0 or value > huge:
        raise ValueError(f'tolerance must be a finite number >= 0 [m] that fits a float32 '
                         f'(0: the scene\'s), got {tolerance!r}')
    if 0.0 < value < tiny:
        raise ValueError(f'tolerance {value:g} m is below the smallest normal float32 '
                         f'({tiny:g}), the type of GetPlan.tolerance: it would arrive as 0 or '
                         'without its digits')
    return value


def _pose(point: Sequence[float] | PoseStamped | None, frame_id: str) -> PoseStamped:
    """Make a PoseStamped of a task point in `frame_id`; None gives an empty frame.

    An axis becomes an orientation whose z axis is the axis; a PoseStamped is kept.
    """
    if point is None:
        return PoseStamped()
    if isinstance(point, PoseStamped):
        return point
    position, quaternion = pose_of_task_point([float(v) for v in point])
    return PoseStamped(header=Header(frame_id=frame_id), pose=create_pose(position, quaternion))


def _execution_number(message: str) -> int | None:
    """Read the execution number in the executor's 'execution N: ...' answer."""
    head = message.split(':', 1)[0].split()
    return int(head[1]) if len(head) == 2 and head[0] == 'execution' and head[1].isdigit() \
        else None
