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
/ftplan/plan/trajectory (the nominal joint path timed within the robot's motion
limits: plan_results.py; stamped likewise), /ftplan/plan/failure_surface (S_F) and
/ftplan/plan/approach, and 50 ms later on /ftplan/plan/markers for RViz; match them to
a response by stamp (PlanClient does).
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

The node is the service's adapter: a request is read by plan_request.py, planned by
plan_jobs.py (here) or plan_pool.py (in workers), ended by plan_service.py (the reason of
a refusal, the status of a plan found) and published by plan_results.py (the latched
topics, then plan_markers.py's markers).

Planning runs in its own callback group (as many callbacks at once as there are workers),
so joint states and obstacles keep flowing while it works on a MultiThreadedExecutor.
"""

from __future__ import annotations

import os
import threading
import traceback

import numpy as np
from nav_msgs.msg import Path
from nav_msgs.srv import GetPlan
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_msgs.msg import Header

from ftplan_msgs_py import DEFAULT_JOINT_SPACE_FRAME, create_path
from ftplan_ros.core import InputError, ManifoldCache, PlanResult, Robot, Scene, load_kernels
from ftplan_ros.core.grid.free_components import PROOF_GRIDS, START_GRIDS
from ftplan_ros.core.io.scene_file import parse_tolerated
from ftplan_ros.core.model.motion_limits import MotionLimits, robot_motion_limits
from ftplan_ros.core.model.robot import robot_digest
from ftplan_ros.core.planning.reachable import ReachablePlan

from .inputs import read_arm_state
from .motion_limit_parameters import (
    SCALING_FACTORS,
    declare_motion_limit_parameters,
    file_motion_limits,
)
from .obstacle_topic import FULL_SET_FIX, ObstacleTopic
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
from .plan_info import plan_info_values
from .plan_jobs import PlanJob, PlanSettings, run_job
from .plan_pool import PlanPool
from .plan_request import RequestSettings, StaleInputError, check_settings, read_request
from .plan_results import PlanResults
from .plan_service import found_values, refusal
from .qos import EVENT_QOS_DEPTH, SERVICE_QOS
from .reporting import Diagnostics, format_vector, stamp_key
from .scene_source import SceneSource
from .spinning import BoundedCallbackGroup, run_node
from .tasks import bind_task_kind, check_task_kind, end_effector_poses
from .topics import JOINT_STATES, PLAN_SERVICE, PLANNER_NODE, ROBOT_DESCRIPTION

# Plan in the node's process (README, "Plans side by side": workers pay little on shared cores).
DEFAULT_PLAN_WORKERS = 0


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
            self.source = SceneSource(self, self.diagnostics, self._scene_changed)
            self._declare_parameters()
            workers = self.get_parameter('plan_workers').value
            self.pool = PlanPool(workers) if workers else None
            if self.source.scene is not None:
                check_settings(self.source.scene, self._settings())  # a bad one stops the start
                self._motion_limits(self.source.scene.robot)  # so does a bad joint_limits_file
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
                'Cap [rad/s] on every joint\'s speed in /ftplan/plan/trajectory and '
                '/ftplan/plan/approach, below the robot\'s velocity limits.')
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
        validators = declare_motion_limit_parameters(self) | {
                      'max_joint_speed': positive, 'margin': non_negative,
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
        self.results = PlanResults(self, self.diagnostics, self._lock)
        # Planning is slow: its own group keeps the subscriptions flowing meanwhile.
        self.plan_group = BoundedCallbackGroup(self.pool.size if self.pool else 1)
        self.plan_service = self.create_service(
            GetPlan, PLAN_SERVICE, self.plan_callback, qos_profile=SERVICE_QOS,
            callback_group=self.plan_group)

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

    def _settings(self) -> RequestSettings:
        """Return the parameters that shape a request's task."""
        return RequestSettings(self.get_parameter('task_kind').value,
                               float(self.get_parameter('orientation_tolerance').value),
                               tuple(array_parameter(self, 'tolerate')))

    def _motion_limits(self, robot: Robot) -> MotionLimits:
        """Return the limits plans for `robot` are timed within: its own or the file's, scaled.

        Raises InputError naming joint_limits_file when the file does not fit the robot.
        """
        limits = file_motion_limits(self, robot) or robot_motion_limits(robot)
        return limits.scaled(*(float(self.get_parameter(name).value)
                               for name in SCALING_FACTORS))

    def _use_scene(self, scene: Scene) -> None:
        """Plan with `scene` from now on (its robot is new: forget the old joint state).

        Whoever plans (the workers, else this process) loads the robot's kernels first.
        """
        try:
            robot = self._settings().robot(scene)
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
            check_settings(scene, self._settings())
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
            scene, result, reachable, limits = self._answer(request, values, timeout)
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            reason, level = refusal(error, timeout)
            if level == 'ERROR':
                self.get_logger().error(traceback.format_exc())
            self._report_failure(reason, values, level)
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
        approach = None if reachable is None else reachable.approach
        values.update(found_values(scene, result, approach))
        # The response first: the results and the report follow it (plan_results.py).
        self.results.publish(scene, result, approach, stamp, values, limits)
        positions, orientations = end_effector_poses(scene.robot, result.nominal_path)
        response.plan = create_path(positions, scene.frame_id, stamp, orientations)
        return response

    def _answer(self, request: GetPlan.Request, values: dict, timeout: float,
                ) -> tuple[Scene, PlanResult, ReachablePlan | None, MotionLimits]:
        """Read the request, plan it, check the robot stayed; raise on the way (refusal).

        `values` get the plan status's description of the request (plan_info.py). Returns
        the motion limits the plan is timed within too.
        """
        scene, q = self._request_scene(request)
        limits = self._motion_limits(scene.robot)
        values.update(plan_info_values(scene.robot, limits, scene.obstacles, scene.task, [
            scene.robot.joint_names[i] for i in scene.tolerated_joints]))
        result, reachable = self._plan(scene, q, timeout, limits)
        self._check_robot_kept(values['robot'])
        return scene, result, reachable, limits

    def _plan(self, scene: Scene, q: np.ndarray | None, timeout: float, limits: MotionLimits,
              ) -> tuple[PlanResult, ReachablePlan | None]:
        """Plan the request's scene within motion `limits`; with q, for the arm standing there.

        In a plan worker when there are any, else here. Raises PlanTimeout at the first
        stage of the search that starts `timeout` [s] after the planning did,
        PlanWorkerError when the worker failed.
        """
        job = PlanJob(scene, q, PlanSettings(
            margin=float(self.get_parameter('margin').value),
            seed=int(self.get_parameter('seed').value),
            approach=bool(self.get_parameter('approach').value),
            approach_time=float(self.get_parameter('approach_time').value),
            proof_cells=int(self.get_parameter('approach_proof_cells').value),
            motion_limits=limits), timeout)
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
        return read_request(request, scene, self._settings(), q, joint_state_problem), q

    def _check_robot_kept(self, planned: str) -> None:
        """Raise StaleInputError when the robot is no longer the one of digest `planned`."""
        now = robot_digest(self.scene.robot)
        if now != planned:
            raise StaleInputError(f'{ROBOT_DESCRIPTION} replaced the robot while it was '
                                  f'planned for: the plan is for robot {planned}, the robot '
                                  f'is now {now}; plan again')

    def _report_failure(self, reason: str, values: dict, level: str = 'WARN') -> None:
        values['reason'] = reason
        self.diagnostics.report('plan', level, reason, values, log=True)


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


def main(args=None) -> int:
    """Run the planner node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(PlannerNode, PLANNER_NODE, args)
