"""A plan's results, latched, after its response: status, S_F, approach, trajectory, θ_s, markers.

The planner answers a request first, then publishes what it found: right after the
response (RESULTS_DELAY) its plan status on /ftplan/plan/info (plan_info.py), S_F on
/ftplan/plan/failure_surface, the approach on /ftplan/plan/approach (no points: none),
the nominal trajectory on /ftplan/plan/trajectory and θ_s on
/ftplan/plan/start_configuration, all stamped like the plan, in that order; then it
reports the plan on /diagnostics; MARKERS_DELAY later its RViz markers (plan_markers.py,
the biggest message: building it before the response would delay it). Plans answered
side by side go out in the order they were answered.

Both trajectories are timed as the executor times its commands (core/planning/timing.py:
TOPP-RA within the plan's motion limits, the robot's or joint_limits_file's, scaled:
motion_limit_parameters.py; velocities capped by `max_joint_speed`), and
the nominal one slowed to the plan's stats['max_safe_speed'] as the executor slows its
command: the fraction of the time-optimal speed at which a lock anywhere on the path
brakes inside certified boxes. The planner finds it within the plan's limits; a speed
cap only lowers the path speed everywhere, so the braking stays certified. Their points
are the planned paths' vertices (the trajectory is one path of S_F, which the executor
and PlanClient find by its numbers), with the positions, velocities, accelerations and
times of the timing there: a record of the plan, not a command (the executor cuts its
commands into small steps).
"""

from __future__ import annotations

import threading
import traceback
from collections import deque

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from ftplan_msgs_py import (
    create_diagnostic_array,
    create_diagnostic_status,
    create_failure_surface,
    create_joint_state,
    create_joint_trajectory,
)
from ftplan_ros.core import PlanResult, Scene
from ftplan_ros.core.model.motion_limits import MotionLimits
from ftplan_ros.core.planning.approach import Approach
from ftplan_ros.core.planning.timing import at_speed, at_vertices, time_within_limits

from .plan_markers import plan_markers
from .qos import LATCHED_QOS
from .reporting import Diagnostics, format_vector, stamp_key
from .topics import (
    APPROACH,
    FAILURE_SURFACE,
    PLAN_INFO,
    PLAN_MARKERS,
    START_CONFIGURATION,
    TRAJECTORY,
)

# [s] after a plan's response, its latched results go out, then its markers (the biggest
# message, ~10 ms of Python to build); before it, they would delay the response.
RESULTS_DELAY = 0.002
MARKERS_DELAY = 0.05


class PlanResults:
    """The planner's latched result topics; plans queued by `publish` go out in order."""

    def __init__(self, node: Node, diagnostics: Diagnostics, lock: threading.Lock):
        self._node = node
        self._diagnostics = diagnostics
        self._lock = lock  # the node's, held while the queues change
        self._pending: deque[tuple] = deque()  # plans whose results go out next
        self._pending_markers: tuple | None = None
        self.info_publisher = node.create_publisher(DiagnosticArray, PLAN_INFO, LATCHED_QOS)
        self.start_publisher = node.create_publisher(JointState, START_CONFIGURATION,
                                                     LATCHED_QOS)
        self.trajectory_publisher = node.create_publisher(JointTrajectory, TRAJECTORY,
                                                          LATCHED_QOS)
        self.surface_publisher = node.create_publisher(Float64MultiArray, FAILURE_SURFACE,
                                                       LATCHED_QOS)
        self.approach_publisher = node.create_publisher(JointTrajectory, APPROACH, LATCHED_QOS)
        self.markers_publisher = node.create_publisher(MarkerArray, PLAN_MARKERS, LATCHED_QOS)
        # One-shot timers: the results go out right after the response, the markers (the
        # biggest message) a moment later; building them before would delay the answer.
        group = MutuallyExclusiveCallbackGroup()
        self.results_timer = node.create_timer(RESULTS_DELAY, self.results_callback,
                                               callback_group=group, autostart=False)
        self.markers_timer = node.create_timer(MARKERS_DELAY, self.markers_callback,
                                               callback_group=group, autostart=False)

    def publish(self, scene: Scene, result: PlanResult, approach: Approach | None, stamp,
                values: dict, limits: MotionLimits) -> None:
        """Queue a plan's results (its status `values`): they go out after its response.

        Its trajectories are timed within motion `limits` (capped by max_joint_speed).
        """
        with self._lock:
            self._pending.append((scene, result, approach, stamp, values, limits))
        self.results_timer.reset()

    def results_callback(self) -> None:
        """Publish the results of the plans answered since the last call, in order."""
        self.results_timer.cancel()  # before taking them: a plan queued later re-arms it
        with self._lock:
            pending = list(self._pending)
            self._pending.clear()
        for plan_results in pending:
            self._publish_results(*plan_results)

    def _publish_results(self, scene: Scene, result: PlanResult, approach: Approach | None,
                         stamp, values: dict, limits: MotionLimits) -> None:
        """Publish θ_s, the nominal trajectory and S_F of a plan, latched; report it."""
        values.update(theta_s=format_vector(result.theta_s),
                      waypoints=len(result.nominal_path),
                      surface_paths=result.surface.paths.shape[0],
                      min_clearance_m=result.stats.get('min_clearance_m', float('nan')))
        message = (f'plan found in {values["plan_time_s"]:.3f} s: theta_s = '
                   f'{values["theta_s"]} rad, {len(result.nominal_path)} waypoints; approach: '
                   f'{values["approach"]}')
        try:
            self._publish_topics(scene, result, approach, stamp, message, values, limits)
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            if not self._node.context.ok():  # Ctrl-C came while publishing: nobody to tell
                return
            self._node.get_logger().error(traceback.format_exc())
            self._diagnostics.report('plan', 'ERROR', f'could not publish plan '
                                     f'{stamp_key(stamp)}: {error!r}', log=True)
            return
        self._diagnostics.report('plan', 'OK', message, values, log=True)
        with self._lock:
            self._pending_markers = (scene, result, stamp)
        self.markers_timer.reset()

    def _publish_topics(self, scene: Scene, result: PlanResult, approach: Approach | None,
                        stamp, message: str, values: dict, limits: MotionLimits) -> None:
        names = list(scene.robot.joint_names)
        nominal = result.nominal_path
        speed = float(self._node.get_parameter('max_joint_speed').value)
        self.info_publisher.publish(create_diagnostic_array(
            [create_diagnostic_status(self._diagnostics.status_name('plan'), 'OK', message,
                                      values)], stamp))
        self.surface_publisher.publish(create_failure_surface(result.surface.paths))
        moves = approach.path if approach is not None and approach.ok else \
            np.zeros((0, len(names)))
        limits = limits.capped(speed)
        self.approach_publisher.publish(_timed_trajectory(names, moves, limits, 1.0, stamp))
        # No speed certified: the executor refuses to run the plan; this shows its timing.
        braking = result.stats['max_safe_speed'] or 1.0
        self.trajectory_publisher.publish(_timed_trajectory(names, nominal, limits, braking,
                                                            stamp))
        self.start_publisher.publish(create_joint_state(names, result.theta_s, stamp=stamp))

    def markers_callback(self) -> None:
        """Publish the RViz markers of the last plan (after its response went out)."""
        self.markers_timer.cancel()
        with self._lock:
            pending, self._pending_markers = self._pending_markers, None
        if pending is None:
            return
        scene, result, stamp = pending
        try:
            self.markers_publisher.publish(plan_markers(
                scene, result, stamp, self._node.get_parameter('joint_space_frame').value))
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            if not self._node.context.ok():  # Ctrl-C came while publishing: nobody to tell
                return
            self._diagnostics.report('markers', 'ERROR', f'could not publish markers: '
                                     f'{error!r}', log=True)


def _timed_trajectory(names: list[str], path: np.ndarray, limits: MotionLimits, speed: float,
                      stamp) -> JointTrajectory:
    """Return `path` (k, n) as a JointTrajectory at its vertices, timed within `limits`.

    At `speed` (0, 1] of the time-optimal timing (timing.py at_speed).
    No points for an empty path (no approach).
    """
    path = np.asarray(path, dtype=float)
    if not len(path):
        return create_joint_trajectory(names, path, [], stamp)
    timed = at_vertices(at_speed(time_within_limits(path, limits), speed), path)
    return create_joint_trajectory(names, timed.positions, timed.times, stamp,
                                   velocities=timed.velocities,
                                   accelerations=timed.accelerations)
