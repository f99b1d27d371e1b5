"""The planner node: serves failure-tolerant plans on /ftplan/plan (nav_msgs/srv/GetPlan).

    ros2 run ftplan_ros planner --ros-args -p scene_file:=fig3a.yaml

A request asks for a motion of the end effector from `start` to `goal` in the scene's
base frame. An empty `start.header.frame_id` means "from where the arm is now": x_s is
the forward kinematics of the latest /joint_states. An empty `goal.header.frame_id`
means the scene's task goal. `tolerance` > 0 overrides the goal tolerance [m].

The response Path is the end-effector path of the nominal motion; an empty Path means
there is no failure-tolerant plan, and the reason is logged and reported on
/diagnostics. A plan found is also published, latched, right after the response on
/ftplan/plan/start_configuration (θ_s, stamped like the Path), /ftplan/plan/trajectory
(the nominal joint path, timed by `max_joint_speed`, stamped likewise) and
/ftplan/plan/failure_surface (S_F), and 50 ms later on /ftplan/plan/markers for RViz;
match them to a response by stamp (PlanClient does). A failed request leaves the last
good plan's topics as they were.

Planning runs in its own callback group, so joint states and obstacles keep flowing
while it works on a MultiThreadedExecutor.
"""

from __future__ import annotations

import threading
import traceback

import numpy as np
from geometry_msgs.msg import PoseStamped
from nav_msgs.msg import Path
from nav_msgs.srv import GetPlan
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, Header
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from ftplan_msgs_py import (
    DEFAULT_JOINT_SPACE_FRAME,
    create_failure_surface,
    create_joint_state,
    create_joint_trajectory,
    create_obstacle_markers,
    create_path,
    create_plan_markers,
    read_joint_state,
)
from ftplan_ros.core import (
    InputError,
    ManifoldCache,
    PlannerOptions,
    PlanResult,
    Scene,
    Task,
    VerificationOptions,
    load_kernels,
    plan,
)

from .motion import time_path
from .obstacles import ObstacleSet, shape_from_obstacle
from .params import (
    add_validators,
    check_startup_parameters,
    declare,
    declare_scene,
    non_negative,
    positive,
)
from .qos import EVENT_QOS_DEPTH, LATCHED_QOS
from .reporting import Diagnostics, format_vector, stamp_key
from .spinning import run_node
from .topics import (
    FAILURE_SURFACE,
    JOINT_STATES,
    OBSTACLES,
    PLAN_MARKERS,
    PLAN_SERVICE,
    PLANNER_NODE,
    START_CONFIGURATION,
    TRAJECTORY,
)

_PLANAR_Z_TOLERANCE = 1e-9  # [m] a planar arm's task lies in z = 0
# [s] after a plan's response, its latched results go out, then its markers (the biggest
# message, ~10 ms of Python to build); before it, they would delay the response.
RESULTS_DELAY = 0.002
MARKERS_DELAY = 0.05
MARKER_WEB_SIZE = 40  # paths and waypoints of S_F drawn at most (~6000 marker points)


class PlannerNode(Node):
    """Serve GetPlan with the core planner over the scene plus the obstacle topic."""

    def __init__(self, **kwargs):
        super().__init__(PLANNER_NODE, **kwargs)
        self.scene = declare_scene(self)
        declare(self, 'max_joint_speed', 1.0,
                'Fastest joint speed [rad/s] used to time /ftplan/plan/trajectory.')
        declare(self, 'margin', 0.0,
                'Clearance [m] the guarantee keeps from every obstacle.')
        declare(self, 'seed', 0,
                'Seed of the inverse-kinematics samples: the same request gives the same '
                'plan (a new seed clears the cache of traced manifolds).')
        declare(self, 'joint_space_frame', DEFAULT_JOINT_SPACE_FRAME,
                'Frame of the joint-space markers (x, y, z = joint 1, 2, 3 angles [rad]).')
        validators = {'max_joint_speed': positive, 'margin': non_negative,
                      'seed': non_negative,
                      'joint_space_frame': lambda v: None if v else 'must not be empty'}
        check_startup_parameters(self, validators)
        add_validators(self, validators)
        self.add_post_set_parameters_callback(self._parameters_set)

        self.cache = ManifoldCache()
        load_kernels(self.scene.robot)
        self.diagnostics = Diagnostics(self)
        self._lock = threading.Lock()
        self._joint_state: np.ndarray | None = None
        self._joint_state_problem = 'no joint state received yet on /joint_states'
        self._obstacles = ObstacleSet(self.scene)
        self._pending_results: tuple | None = None
        self._pending_markers: tuple | None = None

        self.joint_state_subscription = self.create_subscription(
            JointState, JOINT_STATES, self.joint_state_callback, EVENT_QOS_DEPTH)
        self.obstacle_subscription = self.create_subscription(
            MarkerArray, OBSTACLES, self.obstacles_callback, LATCHED_QOS)
        self.start_publisher = self.create_publisher(
            JointState, START_CONFIGURATION, LATCHED_QOS)
        self.trajectory_publisher = self.create_publisher(
            JointTrajectory, TRAJECTORY, LATCHED_QOS)
        self.surface_publisher = self.create_publisher(
            Float64MultiArray, FAILURE_SURFACE, LATCHED_QOS)
        self.markers_publisher = self.create_publisher(MarkerArray, PLAN_MARKERS, LATCHED_QOS)
        # Planning is slow: its own group keeps the subscriptions flowing meanwhile.
        self.plan_group = MutuallyExclusiveCallbackGroup()
        self.plan_service = self.create_service(
            GetPlan, PLAN_SERVICE, self.plan_callback, callback_group=self.plan_group)
        # One-shot timers: the results go out right after the response, the markers (the
        # biggest message) a moment later; building them before would delay the answer.
        results_group = MutuallyExclusiveCallbackGroup()
        self.results_timer = self.create_timer(
            RESULTS_DELAY, self.results_callback, callback_group=results_group,
            autostart=False)
        self.markers_timer = self.create_timer(
            MARKERS_DELAY, self.markers_callback, callback_group=results_group,
            autostart=False)
        self.get_logger().info(f'serving {PLAN_SERVICE}')

    # Inputs -------------------------------------------------------------------------

    def _parameters_set(self, parameters: list[Parameter]) -> None:
        """Start a new cache on a new seed: the cached manifolds were traced with the old one."""
        if any(p.name == 'seed' for p in parameters):
            self.cache = ManifoldCache()

    def joint_state_callback(self, msg: JointState) -> None:
        """Keep the latest joint configuration; a bad one makes the start unknown.

        Messages that name none of the arm's joints (a gripper's, say) are not the arm's.
        """
        if not set(msg.name) & set(self.scene.robot.joint_names):
            return
        try:
            q = read_joint_state(msg, self.scene.robot.joint_names)
        except ValueError as error:
            with self._lock:
                was_good = self._joint_state is not None
                self._joint_state = None
                self._joint_state_problem = f'the latest joint state was rejected: {error}'
            if was_good:
                self.diagnostics.rejected('joint_states', f'rejected joint state: {error}')
            else:
                self.get_logger().warning(f'rejected joint state: {error}',
                                          throttle_duration_sec=5.0)
            return
        with self._lock:
            was_bad = self._joint_state is None
            self._joint_state = q
        if was_bad:
            self.diagnostics.report('joint_states', 'OK', 'receiving joint states',
                                    {'configuration': format_vector(q)})

    def obstacles_callback(self, msg: MarkerArray) -> None:
        """Apply obstacle markers; malformed ones are reported and the old set kept."""
        with self._lock:
            try:
                self._obstacles.update(msg)
            except ValueError as error:
                kept = len(self._obstacles)
                problem = f'ignored obstacle markers: {error}; keeping the {kept} previous'
                error_seen = True
            else:
                kept = len(self._obstacles)
                error_seen = False
        if error_seen:
            self.diagnostics.rejected('obstacles', problem, {'obstacles': kept})
        else:
            self.diagnostics.report('obstacles', 'OK', f'{kept} obstacles from {OBSTACLES}',
                                    {'obstacles': kept}, log=True)

    # The service --------------------------------------------------------------------

    def plan_callback(self, request: GetPlan.Request, response: GetPlan.Response,
                      ) -> GetPlan.Response:
        """Plan from request.start to request.goal; an empty Path says there is no plan."""
        stamp = self.get_clock().now().to_msg()
        frame = self.scene.frame_id
        response.plan = Path(header=Header(stamp=stamp, frame_id=frame))
        values: dict[str, object] = {'stamp': stamp_key(stamp)}
        try:
            scene = self._request_scene(request)
            task = scene.task
            values.update(start=format_vector(task.start), goal=format_vector(task.goal),
                          tolerance=task.goal_tolerance, obstacles=len(scene.obstacles))
            options = PlannerOptions(verification=VerificationOptions(
                margin=float(self.get_parameter('margin').value)))
            rng = np.random.default_rng(int(self.get_parameter('seed').value))
            result = plan(scene, options, rng, cache=self.cache)
        except InputError as error:
            self._report_failure(f'bad plan request: {error}', values)
            return response
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            self.get_logger().error(traceback.format_exc())
            self._report_failure(f'internal planner error: {error!r}', values, 'ERROR')
            return response
        values['plan_time_s'] = result.stats.get('plan_time_s', float('nan'))
        if not result.feasible:
            self._report_failure(f'no failure-tolerant plan: {result.reason}', values)
            return response
        response.plan = self._publish_plan(scene, result, stamp, values)
        return response

    def _request_scene(self, request: GetPlan.Request) -> Scene:
        """Build the scene (static + topic obstacles) with the request's task, or raise."""
        robot = self.scene.robot
        with self._lock:
            q = self._joint_state
            joint_state_problem = self._joint_state_problem
            scene = self._obstacles.scene()
        if request.start.header.frame_id == '':
            if q is None:
                raise InputError('start', f'empty frame_id asks for the current position, but '
                                 f'{joint_state_problem}')
            x_s = robot.forward_kinematics(q)
        else:
            x_s = self._position(request.start, 'start')
        if request.goal.header.frame_id == '':
            if self.scene.task is None:
                raise InputError('goal.header.frame_id', f'is empty and scene {self.scene.name} '
                                 f'has no task goal; give the goal in {self.scene.frame_id!r}')
            x_g = np.asarray(self.scene.task.goal, dtype=float)
        else:
            x_g = self._position(request.goal, 'goal')
        tolerance = float(request.tolerance)
        if not np.isfinite(tolerance) or tolerance < 0.0:
            raise InputError('tolerance', f'must be >= 0 [m] (0: the scene\'s), got {tolerance}')
        if tolerance == 0.0:
            tolerance = self.scene.task.goal_tolerance if self.scene.task else 0.01
        return scene.with_task(Task(tuple(x_s.tolist()), tuple(x_g.tolist()), tolerance))

    def _position(self, pose: PoseStamped, field: str) -> np.ndarray:
        """Return the (m,) task position [m] of a pose in the base frame, or raise."""
        if pose.header.frame_id != self.scene.frame_id:
            raise InputError(f'{field}.header.frame_id',
                             f'unknown frame {pose.header.frame_id!r}: poses must be in the '
                             f'base frame {self.scene.frame_id!r} (no tf lookups here)')
        p = pose.pose.position
        xyz = np.array([p.x, p.y, p.z])
        if not np.all(np.isfinite(xyz)):
            raise InputError(f'{field}.pose.position', f'must be finite, got {xyz.tolist()}')
        m = self.scene.robot.task_dim
        if m == 2 and abs(xyz[2]) > _PLANAR_Z_TOLERANCE:
            raise InputError(f'{field}.pose.position.z',
                             f'is {xyz[2]} but the planar arm works in z = 0')
        return xyz[:m]

    def _report_failure(self, reason: str, values: dict, level: str = 'WARN') -> None:
        values['reason'] = reason
        self.diagnostics.report('plan', level, reason, values, log=True)

    # Results ------------------------------------------------------------------------

    def _publish_plan(self, scene: Scene, result: PlanResult, stamp, values: dict) -> Path:
        """Return the end-effector Path; the results and report follow the response."""
        path = create_path(scene.robot.forward_kinematics(result.nominal_path),
                           scene.frame_id, stamp)
        with self._lock:
            self._pending_results = (scene, result, stamp, values)
        self.results_timer.reset()
        return path

    def results_callback(self) -> None:
        """Publish θ_s, the nominal trajectory and S_F of the last plan, latched; report it."""
        self.results_timer.cancel()
        with self._lock:
            pending, self._pending_results = self._pending_results, None
        if pending is None:
            return
        scene, result, stamp, values = pending
        try:
            names = list(scene.robot.joint_names)
            nominal = result.nominal_path
            speed = float(self.get_parameter('max_joint_speed').value)
            self.surface_publisher.publish(create_failure_surface(result.surface.paths))
            self.trajectory_publisher.publish(create_joint_trajectory(
                names, nominal, time_path(nominal, speed), stamp))
            self.start_publisher.publish(create_joint_state(names, result.theta_s, stamp=stamp))
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            if not self.context.ok():  # Ctrl-C came while publishing: nothing to report to
                return
            self.get_logger().error(traceback.format_exc())
            self.diagnostics.report('plan', 'ERROR', f'could not publish plan '
                                    f'{stamp_key(stamp)}: {error!r}', log=True)
            return
        values.update(theta_s=format_vector(result.theta_s),
                      waypoints=len(result.nominal_path),
                      surface_paths=result.surface.paths.shape[0],
                      min_clearance_m=result.stats.get('min_clearance_m', float('nan')))
        self.diagnostics.report(
            'plan', 'OK', f'plan found in {values["plan_time_s"]:.3f} s: theta_s = '
            f'{values["theta_s"]} rad, {len(result.nominal_path)} waypoints', values, log=True)
        with self._lock:
            self._pending_markers = (scene, result, stamp)
        self.markers_timer.reset()

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
                scene, result, stamp, self.get_parameter('joint_space_frame').value))
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            if not self.context.ok():  # Ctrl-C came while publishing: nothing to report to
                return
            self.diagnostics.report('markers', 'ERROR', f'could not publish markers: {error!r}',
                                    log=True)


def display_web(paths: np.ndarray, most: int = MARKER_WEB_SIZE) -> np.ndarray:
    """Thin the S_F web (K, W, n) to at most `most` paths of `most` waypoints for RViz.

    The first and last path and waypoint are kept; the full web is on
    /ftplan/plan/failure_surface.
    """
    rows = np.unique(np.linspace(0, paths.shape[0] - 1, min(most, paths.shape[0])).round())
    columns = np.unique(np.linspace(0, paths.shape[1] - 1, min(most, paths.shape[1])).round())
    return paths[rows.astype(int)][:, columns.astype(int)]


def plan_markers(scene: Scene, result: PlanResult, stamp, joint_space_frame: str,
                 ) -> MarkerArray:
    """Draw a plan for RViz: arm at θ_s, end-effector path, M_s, M_g, S_F (thinned), obstacles."""
    robot = scene.robot
    markers = create_plan_markers(
        scene.frame_id, stamp,
        arm_polylines={'arm_theta_s': robot.joint_positions(result.theta_s)},
        end_effector_path=robot.forward_kinematics(result.nominal_path),
        joint_space_frame=joint_space_frame,
        joint_space_curves={
            'start_manifold': [b.points for b in result.start_manifolds if len(b) > 1],
            'goal_manifold': [b.points for b in result.goal_manifolds if len(b) > 1],
            'nominal_path': [result.nominal_path],
        },
        joint_space_points={'theta_s': result.theta_s[None, :],
                            'failure_plane_hits': result.failure_plane_hits},
        surface_paths=display_web(result.surface.paths))
    if scene.obstacles:
        shapes = [shape_from_obstacle(('obstacles', k), obstacle)
                  for k, obstacle in enumerate(scene.obstacles)]
        markers.markers.extend(
            create_obstacle_markers(shapes, scene.frame_id, stamp, clear_first=False).markers)
    return markers


def main(args=None) -> int:
    """Run the planner node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(PlannerNode, PLANNER_NODE, args)
