"""Many plan clients at once while the obstacles change (issue 10), against a running planner.

`clients` threads each send `requests` GetPlan requests one after the other (a task drawn
from `tasks`; by default fig3a's arm from (2, 0) to a goal drawn from GOALS) to a
planner that some caller started on the scene, while a publisher replaces the obstacles
on /ftplan/obstacles at `obstacle_rate` [Hz] with 0-3 random disks (planar scenes; 0:
the scene's obstacles stay). Every response is timed (request sent -> response). A plan's
status names its robot (`robot`, a digest of the model) and its obstacle set
(`obstacle_set`, a digest of every number): the robot must be the scene's, and its S_F
(the failure-surface message holding a path equal to its trajectory) must be
collision-free for that set: every path of the web is certified over its segments. An
empty Path must come with a reason (the planner's status). Nothing here needs pytest.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.srv import GetPlan
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSProfile
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from ftplan_msgs_py import (
    ObstacleShape,
    create_obstacle_markers,
    read_diagnostic_status,
    read_failure_surface,
    read_joint_trajectory,
)
from ftplan_ros.core import CollisionChecker, Scene
from ftplan_ros.core.collision.certification import certify_simplices
from ftplan_ros.core.model.robot import robot_digest
from ftplan_ros.nodes.obstacles import obstacle_from_shape, obstacle_set_key
from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.reporting import stamp_key
from ftplan_ros.plan_client import _pose

GOALS = [(1.0, 0.0), (1.2, 0.3), (0.9, -0.4), (1.4, 0.1)]
FIG3A_TASKS = tuple(((2.0, 0.0), goal) for goal in GOALS)
PLAN_STATUS = 'ftplan_planner: plan'


@dataclass
class LoadReport:
    """Latencies and outcomes of a load run."""

    latencies: list[float] = field(default_factory=list)   # [s] answered requests
    plans: int = 0
    refused: dict[str, int] = field(default_factory=dict)   # reason kind -> count
    unanswered: int = 0
    sound: int = 0
    unsound: list[str] = field(default_factory=list)
    unverified: int = 0            # plans whose S_F or obstacle set did not arrive
    obstacle_sets: int = 0
    seconds: float = 0.0

    @property
    def answered(self) -> int:
        """Requests answered (a plan or a refusal)."""
        return len(self.latencies)

    @property
    def throughput(self) -> float:
        """Requests answered per second of the run [1/s]."""
        return self.answered / self.seconds if self.seconds > 0.0 else float('nan')

    def percentile(self, q: float) -> float:
        """Latency percentile [s]."""
        return float(np.percentile(self.latencies, q)) if self.latencies else float('nan')

    def summary(self) -> str:
        """One table row and the details."""
        refused = sum(self.refused.values())
        return (f'{self.answered + self.unanswered} requests in {self.seconds:.1f} s '
                f'({self.throughput:.2f} answered/s): {self.answered} answered ({self.plans} '
                f'plans, {refused} refused: '
                f'{dict(sorted(self.refused.items()))}), {self.unanswered} unanswered; latency '
                f'p50 {self.percentile(50):.2f} s, p95 {self.percentile(95):.2f} s, max '
                f'{max(self.latencies, default=float("nan")):.2f} s; plans sound for their '
                f'obstacle set: {self.sound}, unsound: {len(self.unsound)}, unverified: '
                f'{self.unverified}; {self.obstacle_sets} obstacle sets published')


def _kind(reason: str) -> str:
    for kind in ('plan_timeout', 'no failure-tolerant plan', 'bad plan request',
                 'internal planner error', 'obstacle updates were lost',
                 'replaced the robot'):
        if kind in reason:
            return kind
    return reason[:40]


class LoadRun:
    """Clients, obstacle publisher and checks of one load run, in one rclpy context."""

    def __init__(self, context, scene: Scene, clients: int = 20, requests: int = 10,
                 obstacle_rate: float = 10.0, seed: int = 0, timeout: float = 300.0,
                 tasks: Sequence[tuple[Sequence[float], Sequence[float]]] = FIG3A_TASKS):
        self.scene = scene
        self.clients, self.requests = clients, requests
        self.tasks = tasks
        self.period = 1.0 / obstacle_rate if obstacle_rate > 0.0 else None
        self.g = np.random.default_rng(seed)
        self.timeout = timeout
        self.node = Node('ftplan_load', context=context)
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(self.node)
        self._lock = threading.Lock()
        self.sets: dict[str, tuple] = {obstacle_set_key(scene.obstacles): scene.obstacles}
        # The node publishes each plan's S_F and then its trajectory, in one callback: the
        # k-th S_F received belongs to the k-th trajectory (plans with equal nominal paths
        # are told apart this way).
        self.surfaces: list[np.ndarray | None] = []
        self.trajectories: dict[str, tuple[int, np.ndarray | None]] = {}
        self._trajectory_count = 0
        self.statuses: dict[str, object] = {}
        self.results: list[tuple[float, object]] = []
        # Every plan's results, not only the last: a deep queue on the latched topics.
        qos = QoSProfile(depth=1000, durability=LATCHED_QOS.durability,
                         reliability=LATCHED_QOS.reliability)
        self.node.create_subscription(Float64MultiArray, '/ftplan/plan/failure_surface',
                                      self._surface, qos)
        self.node.create_subscription(JointTrajectory, '/ftplan/plan/trajectory',
                                      self._trajectory, qos)
        self.node.create_subscription(DiagnosticArray, '/diagnostics', self._diagnostics, 1000)
        self.obstacles = self.node.create_publisher(MarkerArray, '/ftplan/obstacles',
                                                    LATCHED_QOS)

    # Inputs -----------------------------------------------------------------------------

    def _surface(self, msg) -> None:
        try:
            web = read_failure_surface(msg)
        except ValueError:
            web = None
        with self._lock:
            self.surfaces.append(web)

    def _trajectory(self, msg) -> None:
        try:
            positions = read_joint_trajectory(msg, list(self.scene.robot.joint_names)).positions
        except ValueError:
            positions = None
        with self._lock:
            self.trajectories[stamp_key(msg.header.stamp)] = (self._trajectory_count,
                                                               positions)
            self._trajectory_count += 1

    def _diagnostics(self, msg) -> None:
        for status in msg.status:
            if status.name == PLAN_STATUS:
                reading = read_diagnostic_status(status)
                with self._lock:
                    self.statuses[reading.values.get('stamp', '')] = reading

    # The run ------------------------------------------------------------------------------

    def run(self) -> LoadReport:
        """Run the clients to the end, publishing obstacles meanwhile; check every plan."""
        report = LoadReport()
        stop = threading.Event()
        spinner = threading.Thread(target=self._spin, args=(stop,), daemon=True)
        publisher = threading.Thread(target=self._publish_obstacles, args=(stop, report),
                                     daemon=True)
        spinner.start()
        if self.period is not None:
            publisher.start()
        started = time.monotonic()
        workers = [threading.Thread(target=self._client, args=(k,), daemon=True)
                   for k in range(self.clients)]
        for worker in workers:
            worker.start()
        for worker in workers:
            worker.join()
        report.seconds = time.monotonic() - started
        time.sleep(1.0)   # the last results and statuses
        stop.set()
        if self.period is not None:
            publisher.join()
        spinner.join()
        self._judge(report)
        self.executor.remove_node(self.node)
        self.executor.shutdown()
        self.node.destroy_node()
        return report

    def _spin(self, stop: threading.Event) -> None:
        while not stop.is_set():
            self.executor.spin_once(timeout_sec=0.01)

    def _publish_obstacles(self, stop: threading.Event, report: LoadReport) -> None:
        k = 0
        while not stop.is_set():
            shapes = []
            for i in range(int(self.g.integers(0, 4))):
                centre = self.g.uniform(-2.5, 2.5, 2)
                if min(np.linalg.norm(centre), np.linalg.norm(centre - (2.0, 0.0))) < 0.5:
                    continue
                shapes.append(ObstacleShape(('load', i), 'sphere', np.array([*centre, 0.0]),
                                            np.full(3, 2 * self.g.uniform(0.05, 0.2)),
                                            np.array([0.0, 0.0, 0.0, 1.0])))
            added = tuple(obstacle_from_shape(shape) for shape in shapes)
            with self._lock:
                self.sets[obstacle_set_key(self.scene.obstacles + added)] = \
                    self.scene.obstacles + added
            self.obstacles.publish(create_obstacle_markers(shapes, self.scene.frame_id))
            k += 1
            stop.wait(self.period)
        report.obstacle_sets = k

    def _client(self, k: int) -> None:
        client = self.node.create_client(GetPlan, '/ftplan/plan')
        client.wait_for_service(timeout_sec=30.0)
        g = np.random.default_rng(k)
        for _ in range(self.requests):
            start, goal = self.tasks[int(g.integers(len(self.tasks)))]
            request = GetPlan.Request(start=_pose(start, self.scene.frame_id),
                                      goal=_pose(goal, self.scene.frame_id))
            done = threading.Event()
            sent = time.monotonic()
            future = client.call_async(request)
            future.add_done_callback(lambda _, event=done: event.set())
            answered = done.wait(self.timeout)
            with self._lock:
                self.results.append((time.monotonic() - sent if answered else float('nan'),
                                     future.result() if answered else None))

    def _judge(self, report: LoadReport) -> None:
        robot = self.scene.robot
        digest = robot_digest(robot)
        for latency, response in self.results:
            if response is None:
                report.unanswered += 1
                continue
            report.latencies.append(latency)
            key = stamp_key(response.plan.header.stamp)
            status = self.statuses.get(key)
            if not response.plan.poses:
                kind = _kind(status.message if status else 'no reason arrived')
                report.refused[kind] = report.refused.get(kind, 0) + 1
                continue
            report.plans += 1
            if status is not None and status.values.get('robot') != digest:
                report.unsound.append(f'plan {key}: made for robot '
                                      f'{status.values.get("robot")}, not the scene\'s {digest}')
                continue
            obstacles = self.sets.get(status.values.get('obstacle_set', '')) if status else None
            index, nominal = self.trajectories.get(key, (len(self.surfaces), None))
            web = self.surfaces[index] if index < len(self.surfaces) else None
            if obstacles is None or web is None or nominal is None:
                report.unverified += 1
                continue
            if web.shape[1:] != nominal.shape or \
                    not np.any(np.all(web == nominal[None], axis=(1, 2))):
                report.unsound.append(f'plan {key}: the S_F published with it does not hold '
                                      'its nominal path')
                continue
            checker = CollisionChecker(robot, obstacles)
            segments = np.stack([web[:, :-1], web[:, 1:]], axis=2).reshape(-1, 2, web.shape[2])
            ok, _, smallest, _ = certify_simplices(checker, segments, 0.0, 10)
            if ok:
                report.sound += 1
            else:
                report.unsound.append(f'plan {key}: S_F meets obstacle set '
                                      f'{status.values["obstacle_set"]} ({smallest:.4f} m)')
