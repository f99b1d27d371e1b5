"""The planner node: serves failure-tolerant plans on /ftplan/plan (nav_msgs/srv/GetPlan).

    ros2 run ftplan_ros planner --ros-args -p scene_file:=fig3a.yaml

A request asks for a motion of the end effector from `start` to `goal`, poses in the
scene's base frame. What part of a pose is the task comes from the `task_kind`
parameter ('' = the scene's task kind, else 'pose' for a spatial arm): `position` (x,
y, z), `axis` (the position and the z axis of the pose's orientation: the tool points
along it, free to turn about it) or `pose` (position and orientation, a unit quaternion
within 1e-3); planar arms take (x, y) with z = 0. An empty `start.header.frame_id`
means "from where the arm is now": x_s is the forward kinematics of the latest
/joint_states. An empty `goal.header.frame_id` means the scene's task goal.
`tolerance` > 0 overrides the goal tolerance [m]; the `orientation_tolerance` parameter
[rad] (0: the scene's) bounds the orientation error of axis and pose tasks, and the
`tolerate` parameter names the joints whose lock the plan must survive (empty: the
scene's `tolerate`, else every joint).

The response Path holds the tool poses along the nominal motion (orientations too for
spatial arms); an empty Path means there is no failure-tolerant plan, and the reason is
logged and reported on /diagnostics. A plan found is also published, latched, right
after the response on /ftplan/plan/start_configuration (θ_s, stamped like the Path),
/ftplan/plan/trajectory (the nominal joint path, timed by `max_joint_speed`, stamped
likewise), /ftplan/plan/failure_surface (S_F) and /ftplan/plan/approach, and 50 ms later
on /ftplan/plan/markers for RViz; match them to a response by stamp (PlanClient does).
Its robot (a digest of the model), obstacle set (a digest), task, tolerances, tolerated
joints and approach are values of the 'ftplan_planner: plan' status (plan_info.py), which
also goes out latched, stamped like the plan, on /ftplan/plan/info. A failed request
leaves the last good plan's topics as they were.

Obstacle updates are applied one by one, in order (obstacle_topic.py); while some were
lost, every request is refused with the reason until a full set (a MarkerArray whose
first marker is DELETEALL) arrives. A plan is made for the obstacles of the moment its
planning starts, and its status names them (`obstacle_set`); when /robot_description
replaces the robot while it plans, the request is refused: the plan would be for a
robot that is gone.

The arm where it stands (`approach`, default on): with a joint state, the planner serves
only a plan whose θ_s the arm gets to (core/planning/reachable.py): preferably along
M_s^F (the end effector staying at x_s), else by a certified joint move. It publishes that
approach, timed and stamped like the plan, on /ftplan/plan/approach (no points: no joint
state); the status says how it goes (`approach`). The approach is not failure-tolerant.
Otherwise the Path is empty and the reason says "none reachable (proved)" or "none found
within the search", and what plan exists elsewhere; the status says which (`reach`) and
how far the search looked (`reach_search`).

Requests wait in a queue of SERVICE_QUEUE_DEPTH (qos.py). With `plan_workers` = 0 they
are planned one at a time in the node's process; with N >= 1, N at a time in N worker
processes (plan_pool.py), a worker that crashes failing its request only. `plan_timeout`
[s] bounds each: the search stops at its next stage past it (a worker still busy
OVERRUN_GRACE later is stopped) and the request is answered with an empty Path and the
reason.

A scene file without a robot takes it from /robot_description (scene_source.py); until
then every request is refused with "waiting for /robot_description".

Planning runs in its own callback group (as many callbacks at once as there are workers),
so joint states and obstacles keep flowing while it works on a MultiThreadedExecutor.
"""

from __future__ import annotations

import os
import threading
import traceback
from collections import deque

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
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
    create_diagnostic_array,
    create_diagnostic_status,
    create_failure_surface,
    create_joint_state,
    create_joint_trajectory,
    create_obstacle_markers,
    create_path,
    create_plan_markers,
    read_point,
    read_quaternion,
)
from ftplan_ros.core import (
    InputError,
    ManifoldCache,
    PlanResult,
    Robot,
    Scene,
    Task,
    load_kernels,
)
from ftplan_ros.core.grid.free_components import PROOF_GRIDS, START_GRIDS
from ftplan_ros.core.io.scene_file import parse_tolerated
from ftplan_ros.core.model.robot import robot_digest
from ftplan_ros.core.model.scene import DEFAULT_GOAL_TOLERANCE, DEFAULT_ORIENTATION_TOLERANCE
from ftplan_ros.core.planning.approach import Approach
from ftplan_ros.core.planning.planner import check_plannable
from ftplan_ros.core.planning.reachable import ReachablePlan

from .inputs import read_arm_state
from .motion import time_path
from .obstacle_topic import FULL_SET_FIX, ObstacleTopic
from .obstacles import shape_from_obstacle
from .params import (
    add_validators,
    array_parameter,
    check_startup_parameters,
    declare,
    declare_array,
    destroyed_if_start_fails,
    non_negative,
    positive,
)
from .plan_info import join_names, plan_info_values
from .plan_jobs import PlanJob, PlanSettings, PlanTimeout, run_job
from .plan_pool import PlanPool, PlanWorkerError
from .qos import EVENT_QOS_DEPTH, LATCHED_QOS, SERVICE_QOS
from .reporting import Diagnostics, format_vector, stamp_key
from .scene_source import SceneSource
from .spinning import BoundedCallbackGroup, run_node
from .tasks import (
    bind_task_kind,
    check_task_kind,
    convert_task_point,
    end_effector_poses,
    task_point,
)
from .topics import (
    APPROACH,
    FAILURE_SURFACE,
    JOINT_STATES,
    PLAN_INFO,
    PLAN_MARKERS,
    PLAN_SERVICE,
    PLANNER_NODE,
    ROBOT_DESCRIPTION,
    START_CONFIGURATION,
    TRAJECTORY,
)

_PLANAR_Z_TOLERANCE = 1e-9  # [m] a planar arm's task lies in z = 0
# [s] after a plan's response, its latched results go out, then its markers (the biggest
# message, ~10 ms of Python to build); before it, they would delay the response.
RESULTS_DELAY = 0.002
MARKERS_DELAY = 0.05
MARKER_WEB_SIZE = 40  # paths and waypoints of S_F drawn at most (~6000 marker points)
# [m] GetPlan.tolerance is a float32: below its smallest normal number a tolerance has
# lost its digits on the way (and one below 1.4e-45 arrives as 0, the scene's).
SMALLEST_TOLERANCE = float(np.finfo(np.float32).tiny)
# Plan in the node's process (README, "Plans side by side": workers pay little on shared cores).
DEFAULT_PLAN_WORKERS = 0


class RequestError(ValueError):
    """A request field the planner cannot use; the message names it."""


class StaleInputError(Exception):
    """The obstacles or the robot are not those published (updates lost, robot replaced)."""


class PlannerNode(Node):
    """Serve GetPlan with the core planner over the scene plus the obstacle topic."""

    def __init__(self, **kwargs):
        self.pool: PlanPool | None = None  # before anything that may fail: destroy_node ends it
        with destroyed_if_start_fails(self):
            super().__init__(PLANNER_NODE, **kwargs)
            self.diagnostics = Diagnostics(self)
            self._lock = threading.Lock()
            self.cache = ManifoldCache()
            self.scene: Scene | None = None
            self.obstacle_topic = ObstacleTopic(self, self.diagnostics, lock=self._lock,
                                                log=True)
            self._obstacles = self.obstacle_topic.obstacles
            self._joint_state: np.ndarray | None = None
            self._joint_state_problem = 'no joint state received yet on /joint_states'
            self._early_joint_state: JointState | None = None  # arrived before the robot
            self._pending_results: deque[tuple] = deque()  # plans whose results go out next
            self._pending_markers: tuple | None = None
            self.source = SceneSource(self, self.diagnostics, self._scene_changed)
            self._declare_parameters()
            workers = self.get_parameter('plan_workers').value
            self.pool = PlanPool(workers) if workers else None
            if self.source.scene is not None:
                self._check_scene_parameters(self.source.scene)  # a bad one stops the start
                self._use_scene(self.source.scene)
            self._create_interfaces()
            self.get_logger().info(f'serving {PLAN_SERVICE}' + (
                f' with {workers} plan workers' if workers else ''))

    def destroy_node(self) -> None:
        """End the plan workers, then the node."""
        if self.pool is not None:
            self.pool.close()
        super().destroy_node()

    def _declare_parameters(self) -> None:
        declare(self, 'max_joint_speed', 1.0,
                'Fastest joint speed [rad/s] used to time /ftplan/plan/trajectory.')
        declare(self, 'margin', 0.0,
                'Clearance [m] the guarantee keeps from every obstacle.')
        declare(self, 'seed', 0,
                'Seed of the inverse-kinematics samples: the same request gives the same '
                'plan (a new seed clears the cache of traced manifolds).')
        declare(self, 'joint_space_frame', DEFAULT_JOINT_SPACE_FRAME,
                'Frame of the joint-space markers (x, y, z = joint 1, 2, 3 angles [rad]).')
        declare(self, 'task_kind', '',
                'What part of the request poses is the task: position, axis (position and '
                'the pose\'s z axis) or pose; "" = the scene\'s task kind (pose without a '
                'task). Planar arms: planar.')
        declare(self, 'orientation_tolerance', 0.0,
                'Orientation error [rad] allowed at the goal of axis and pose tasks (0.0: '
                'the scene task\'s).')
        declare_array(self, 'tolerate', Parameter.Type.STRING_ARRAY,
                      'Joints whose lock the plan must survive (empty: the scene\'s '
                      '`tolerate`, else every joint).')
        declare(self, 'plan_timeout', 30.0,
                'Longest a request may plan [s]; past it the search stops at its next stage '
                'and the request is refused with the reason.')
        declare(self, 'plan_workers', DEFAULT_PLAN_WORKERS,
                'Worker processes that plan requests side by side (read-only), at most one '
                'per core; 0: one request at a time in the node\'s process. Requests past '
                'them wait in a queue.', read_only=True)
        declare(self, 'approach', True,
                'Plan for the arm where it stands: serve only a plan whose theta_s the '
                'latest joint state reaches (along M_s^F preferably, else by a certified '
                'joint move) and publish the approach on /ftplan/plan/approach; else an '
                'empty Path: none reachable (proved), or none found within the search.')
        declare(self, 'approach_time', 1.0,
                'Budget [s] of each of the three RRT-Connect attempts of an approach.')
        declare(self, 'approach_proof_cells', START_GRIDS[-1],
                'Cells per joint of the finest grid that searches the failure-tolerant starts '
                'within the arm\'s reach, or proves there are none, when no approach is found '
                f'(planar 3R arms among disks): one of {", ".join(map(str, PROOF_GRIDS))}; '
                'finer decides narrower gaps but takes longer and more memory (384: about '
                '1 s and 0.4 GB).')
        validators = {'max_joint_speed': positive, 'margin': non_negative,
                      'seed': non_negative, 'plan_timeout': positive,
                      'plan_workers': _check_plan_workers,
                      'approach_time': positive,
                      'approach_proof_cells': _check_proof_cells,
                      'joint_space_frame': lambda v: None if v else 'must not be empty',
                      'task_kind': self._check_task_kind,
                      'orientation_tolerance': non_negative,
                      'tolerate': self._check_tolerate}
        check_startup_parameters(self, validators)
        add_validators(self, validators)
        self.add_post_set_parameters_callback(self._parameters_set)

    def _create_interfaces(self) -> None:
        self.joint_state_subscription = self.create_subscription(
            JointState, JOINT_STATES, self.joint_state_callback, EVENT_QOS_DEPTH)
        self.info_publisher = self.create_publisher(DiagnosticArray, PLAN_INFO, LATCHED_QOS)
        self.start_publisher = self.create_publisher(
            JointState, START_CONFIGURATION, LATCHED_QOS)
        self.trajectory_publisher = self.create_publisher(
            JointTrajectory, TRAJECTORY, LATCHED_QOS)
        self.surface_publisher = self.create_publisher(
            Float64MultiArray, FAILURE_SURFACE, LATCHED_QOS)
        self.approach_publisher = self.create_publisher(JointTrajectory, APPROACH, LATCHED_QOS)
        self.markers_publisher = self.create_publisher(MarkerArray, PLAN_MARKERS, LATCHED_QOS)
        # Planning is slow: its own group keeps the subscriptions flowing meanwhile.
        self.plan_group = BoundedCallbackGroup(self.pool.size if self.pool else 1)
        self.plan_service = self.create_service(
            GetPlan, PLAN_SERVICE, self.plan_callback, qos_profile=SERVICE_QOS,
            callback_group=self.plan_group)
        # One-shot timers: the results go out right after the response, the markers (the
        # biggest message) a moment later; building them before would delay the answer.
        results_group = MutuallyExclusiveCallbackGroup()
        self.results_timer = self.create_timer(
            RESULTS_DELAY, self.results_callback, callback_group=results_group,
            autostart=False)
        self.markers_timer = self.create_timer(
            MARKERS_DELAY, self.markers_callback, callback_group=results_group,
            autostart=False)

    # The robot and the parameters ---------------------------------------------------

    def _check_task_kind(self, value) -> str | None:
        problem = check_task_kind(value)
        if problem is None and self.scene is not None:
            try:
                bind_task_kind(self.scene.robot, value)
            except InputError as error:
                problem = error.problem
        return problem

    def _check_tolerate(self, value) -> str | None:
        if self.scene is None:
            return None if len(set(value)) == len(value) else 'names a joint twice'
        try:
            parse_tolerated(list(value) or None, self.scene.robot.joint_names)
        except InputError as error:
            return str(error)
        return None

    def _check_scene_parameters(self, scene: Scene) -> None:
        """Raise InputError when the parameters do not fit the scene, or nothing can plan.

        task_kind and tolerate must fit the robot; a robot without redundancy for the task
        kind, a static obstacle over the base or a scene task that cannot be planned would
        make every request fail, so they stop the start.
        """
        robot = bind_task_kind(scene.robot, self.get_parameter('task_kind').value)
        parse_tolerated(array_parameter(self, 'tolerate') or None, scene.robot.joint_names)
        if robot.n_joints - robot.task_dim < 1:
            raise InputError('robot', f'{robot.n_joints} joints give no redundancy for a '
                             f'{robot.task_dim}-D {robot.task_kind} task: every plan request '
                             'would fail')
        task = scene.task
        if task is not None and convert_task_point(task.start, robot.task_kind) is not None \
                and convert_task_point(task.goal, robot.task_kind) is not None:
            check_plannable(scene.with_task(Task(
                tuple(convert_task_point(task.start, robot.task_kind)),
                tuple(convert_task_point(task.goal, robot.task_kind)), task.goal_tolerance,
                task.orientation_tolerance)))

    def _task_robot(self, scene: Scene) -> Robot:
        """Return the scene's robot bound to the requests' task kind (InputError if it cannot)."""
        return bind_task_kind(scene.robot, self.get_parameter('task_kind').value)

    def _use_scene(self, scene: Scene) -> None:
        """Plan with `scene` from now on (its robot is new: forget the old joint state).

        Whoever plans (the workers, else this process) loads the robot's kernels first.
        """
        try:
            robot = self._task_robot(scene)
        except InputError:
            robot = scene.robot
        if self.pool is not None:
            self.pool.use_robot(robot)
        else:
            load_kernels(robot)
        with self._lock:
            problems = self._obstacles.rebase(scene)
            self.scene = scene
            self.cache = ManifoldCache()
            self._joint_state = None
            early, self._early_joint_state = self._early_joint_state, None
        self.obstacle_topic.report_rebase(problems)
        if early is not None:
            self.joint_state_callback(early)

    def _scene_changed(self, scene: Scene) -> None:
        """Take a robot from /robot_description: check the parameters against it, use it."""
        try:
            self._check_scene_parameters(scene)
        except InputError as error:
            self.diagnostics.report('parameters', 'ERROR', f'parameter {error} for the robot '
                                    'from /robot_description; plan requests will fail until '
                                    'it is fixed', log=True)
        self._use_scene(scene)

    def _parameters_set(self, parameters: list[Parameter]) -> None:
        """Start a new cache on a new seed: the cached manifolds were traced with the old one."""
        if any(p.name == 'seed' for p in parameters):
            self.cache = ManifoldCache()

    # Inputs -------------------------------------------------------------------------

    def joint_state_callback(self, msg: JointState) -> None:
        """Keep the latest joint configuration; a bad one makes the start unknown.

        Messages that name none of the arm's joints (a gripper's, another arm's) are not
        the arm's; extra joints in the arm's message (fingers) are ignored.
        """
        scene = self.scene
        if scene is None:
            self._early_joint_state = msg  # read once the robot is known
            return
        names = scene.robot.joint_names
        if not set(msg.name) & set(names):
            return
        try:
            q, _ = read_arm_state(msg, scene.robot)
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

    # The service --------------------------------------------------------------------

    def plan_callback(self, request: GetPlan.Request, response: GetPlan.Response,
                      ) -> GetPlan.Response:
        """Plan from request.start to request.goal; an empty Path says there is no plan."""
        stamp = self.get_clock().now().to_msg()
        scene = self.scene
        response.plan = Path(header=Header(stamp=stamp,
                                           frame_id=scene.frame_id if scene else ''))
        values: dict[str, object] = {'stamp': stamp_key(stamp)}
        timeout = float(self.get_parameter('plan_timeout').value)
        try:
            scene, q = self._request_scene(request)
            task = scene.task
            values.update(plan_info_values(scene.robot, scene.obstacles, task, [
                scene.robot.joint_names[i] for i in scene.tolerated_joints]))
            result, reachable = self._plan(scene, q, timeout)
            self._check_robot_kept(values['robot'])
        except (InputError, RequestError) as error:
            self._report_failure(f'bad plan request: {error}', values)
            return response
        except StaleInputError as error:
            self._report_failure(str(error), values)
            return response
        except PlanTimeout:
            self._report_failure(f'no answer within plan_timeout = {timeout:g} s: the search '
                                 'was stopped; raise plan_timeout or simplify the request',
                                 values)
            return response
        except PlanWorkerError as error:
            self.get_logger().error(traceback.format_exc())
            self._report_failure(f'internal planner error: {error}', values, 'ERROR')
            return response
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            self.get_logger().error(traceback.format_exc())
            self._report_failure(f'internal planner error: {error!r}', values, 'ERROR')
            return response
        values['plan_time_s'] = result.stats.get('plan_time_s', float('nan'))
        if reachable is not None:
            values.update(reach=reachable.outcome.value, reach_search=reachable.searched)
        if not result.feasible:
            self._report_failure(f'no failure-tolerant plan: {result.reason}', values)
            return response
        if reachable is not None and not reachable.ok:
            self._report_failure(f'{reachable.outcome.value}: {reachable.reason}', values)
            return response
        values['tolerated_joints'] = join_names(result.stats.get('tolerated_joints', []) or [
            scene.robot.joint_names[i] for i in result.tolerated_joints])
        approach = None if reachable is None else reachable.approach
        values['approach'] = 'not planned (no joint state, or the approach parameter is ' \
            'off)' if approach is None else approach.describe()
        response.plan = self._publish_plan(scene, result, approach, stamp, values)
        return response

    def _plan(self, scene: Scene, q: np.ndarray | None, timeout: float,
              ) -> tuple[PlanResult, ReachablePlan | None]:
        """Plan the request's scene; with q, for the arm standing there (plan_from).

        In a plan worker when there are any, else here. Raises PlanTimeout at the first
        stage of the search that starts `timeout` [s] after the planning did,
        PlanWorkerError when the worker failed.
        """
        job = PlanJob(scene, q, PlanSettings(
            margin=float(self.get_parameter('margin').value),
            seed=int(self.get_parameter('seed').value),
            approach=bool(self.get_parameter('approach').value),
            approach_time=float(self.get_parameter('approach_time').value),
            proof_cells=int(self.get_parameter('approach_proof_cells').value)), timeout)
        if self.pool is not None:
            return self.pool.run(job)
        return run_job(job, self.cache)

    def _request_scene(self, request: GetPlan.Request) -> tuple[Scene, np.ndarray | None]:
        """Build the scene (static + topic obstacles) with the request's task, or raise.

        Returns it with the latest joint configuration (None when there is none).
        """
        with self._lock:
            q = self._joint_state
            joint_state_problem = self._joint_state_problem
            scene = self._obstacles.scene()
            lost = self._obstacles.lost
        if scene is None:
            raise InputError('robot', self.source.waiting)
        if lost:
            raise StaleInputError(f'{lost}: {FULL_SET_FIX}, then plan again')
        robot = self._task_robot(scene)
        kind = robot.task_kind
        if request.start.header.frame_id == '':
            if q is None:
                raise InputError('start', f'empty frame_id asks for the current position, but '
                                 f'{joint_state_problem}')
            x_s = robot.forward_kinematics(q)
        else:
            x_s = self._task_point(scene, request.start, 'start', kind)
        if request.goal.header.frame_id == '':
            x_g = self._scene_goal(scene, kind)
        else:
            x_g = self._task_point(scene, request.goal, 'goal', kind)
        tolerance = float(request.tolerance)
        if not np.isfinite(tolerance) or tolerance < 0.0:
            raise InputError('tolerance', f'must be >= 0 [m] (0: the scene\'s), got {tolerance}')
        if 0.0 < tolerance < SMALLEST_TOLERANCE:
            raise InputError('tolerance', f'{tolerance:g} m is below the smallest normal float32 '
                             f'({SMALLEST_TOLERANCE:g}), the type of GetPlan.tolerance: its '
                             'digits were lost on the way')
        if tolerance == 0.0:
            tolerance = scene.task.goal_tolerance if scene.task else DEFAULT_GOAL_TOLERANCE
        angle = float(self.get_parameter('orientation_tolerance').value)
        if angle == 0.0:
            angle = scene.task.orientation_tolerance if scene.task else \
                DEFAULT_ORIENTATION_TOLERANCE
        tolerate = array_parameter(self, 'tolerate') or scene.tolerate
        tolerated = parse_tolerated(None if tolerate is None else list(tolerate),
                                    robot.joint_names)
        task = Task(tuple(x_s.tolist()), tuple(x_g.tolist()), tolerance, angle)
        return scene.with_task(task).with_tolerated(tolerated), q

    def _check_robot_kept(self, planned: str) -> None:
        """Raise StaleInputError when the robot is no longer the one of digest `planned`."""
        now = robot_digest(self.scene.robot)
        if now != planned:
            raise StaleInputError(f'{ROBOT_DESCRIPTION} replaced the robot while it was '
                                  f'planned for: the plan is for robot {planned}, the robot '
                                  f'is now {now}; plan again')

    def _scene_goal(self, scene: Scene, kind: str) -> np.ndarray:
        """Return the scene's task goal as a task point of `kind`, or raise InputError."""
        if scene.task is None:
            raise InputError('goal.header.frame_id', f'is empty and scene {scene.name} '
                             f'has no task goal; give the goal in {scene.frame_id!r}')
        goal = convert_task_point(scene.task.goal, kind)
        if goal is None:
            raise InputError('goal.header.frame_id', f'is empty, but the {scene.task.kind} '
                             f'goal of scene {scene.name} is no {kind} goal (task_kind); give '
                             f'the goal pose in {scene.frame_id!r}')
        return goal

    def _task_point(self, scene: Scene, pose: PoseStamped, field: str, kind: str,
                    ) -> np.ndarray:
        """Return the task point of `kind` of a pose in the base frame, or raise."""
        if pose.header.frame_id != scene.frame_id:
            raise InputError(f'{field}.header.frame_id',
                             f'unknown frame {pose.header.frame_id!r}: poses must be in the '
                             f'base frame {scene.frame_id!r} (no tf lookups here)')
        try:
            position = read_point(pose.pose.position, f'{field}.pose.position')
            quaternion = read_quaternion(pose.pose.orientation, f'{field}.pose.orientation') \
                if kind in ('axis', 'pose') else None
        except ValueError as error:
            raise RequestError(f'{error} ({kind} task)') from None
        if kind == 'planar' and abs(position[2]) > _PLANAR_Z_TOLERANCE:
            raise InputError(f'{field}.pose.position.z',
                             f'is {position[2]} but the planar arm works in z = 0')
        return task_point(kind, position, quaternion)

    def _report_failure(self, reason: str, values: dict, level: str = 'WARN') -> None:
        values['reason'] = reason
        self.diagnostics.report('plan', level, reason, values, log=True)

    # Results ------------------------------------------------------------------------

    def _publish_plan(self, scene: Scene, result: PlanResult, approach: Approach | None,
                      stamp, values: dict) -> Path:
        """Return the end-effector Path; the results and report follow the response."""
        positions, orientations = end_effector_poses(scene.robot, result.nominal_path)
        path = create_path(positions, scene.frame_id, stamp, orientations)
        with self._lock:
            self._pending_results.append((scene, result, approach, stamp, values))
        self.results_timer.reset()
        return path

    def results_callback(self) -> None:
        """Publish the results of the plans answered since the last call, in order."""
        self.results_timer.cancel()  # before taking them: a plan queued later re-arms it
        with self._lock:
            pending = list(self._pending_results)
            self._pending_results.clear()
        for plan_results in pending:
            self._publish_results(*plan_results)

    def _publish_results(self, scene: Scene, result: PlanResult, approach: Approach | None,
                         stamp, values: dict) -> None:
        """Publish θ_s, the nominal trajectory and S_F of a plan, latched; report it."""
        values.update(theta_s=format_vector(result.theta_s),
                      waypoints=len(result.nominal_path),
                      surface_paths=result.surface.paths.shape[0],
                      min_clearance_m=result.stats.get('min_clearance_m', float('nan')))
        message = (f'plan found in {values["plan_time_s"]:.3f} s: theta_s = '
                   f'{values["theta_s"]} rad, {len(result.nominal_path)} waypoints; approach: '
                   f'{values["approach"]}')
        try:
            names = list(scene.robot.joint_names)
            nominal = result.nominal_path
            speed = float(self.get_parameter('max_joint_speed').value)
            self.info_publisher.publish(create_diagnostic_array(
                [create_diagnostic_status(self.diagnostics.status_name('plan'), 'OK', message,
                                          values)], stamp))
            self.surface_publisher.publish(create_failure_surface(result.surface.paths))
            moves = approach.path if approach is not None and approach.ok else \
                np.zeros((0, len(names)))
            self.approach_publisher.publish(create_joint_trajectory(
                names, moves, time_path(moves, speed) if len(moves) else [], stamp))
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
        self.diagnostics.report('plan', 'OK', message, values, log=True)
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


def _check_plan_workers(value) -> str | None:
    """Validate `plan_workers`: 0 (plan in the node) up to one worker per core."""
    cores = os.cpu_count() or 1
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= cores:
        return (f'must be an integer from 0 (plan in the node\'s process) to {cores} (one '
                f'worker per core of this machine), got {value!r}')
    return None


def _check_proof_cells(value) -> str | None:
    """Validate `approach_proof_cells`: one of the grids the proof may take."""
    if isinstance(value, bool) or value not in PROOF_GRIDS:
        return f'must be one of {", ".join(map(str, PROOF_GRIDS))}, got {value!r}'
    return None


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
    """Draw a plan for RViz: arm at θ_s, end-effector path, M_s, M_g, S_F (thinned), obstacles.

    The arm and the tool's path are in 3-D in the base frame; the joint-space objects
    show joints 1-3 as x, y, z.
    """
    robot = scene.robot
    markers = create_plan_markers(
        scene.frame_id, stamp,
        arm_polylines={'arm_theta_s': robot.skeleton(result.theta_s)},
        end_effector_path=end_effector_poses(robot, result.nominal_path)[0],
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
