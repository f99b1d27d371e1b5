"""The executor node: runs the last plan and recovers from a locked joint.

    ros2 run ftplan_ros executor --ros-args -p scene_file:=fig3a.yaml

It keeps the last plan from the planner's latched topics (θ_s, the nominal trajectory,
the S_F web; the nominal path is the web path equal to the trajectory). A call of
/ftplan/execute (std_srvs/Trigger):

1. approaching: moves the arm to θ_s, along the start self-motion manifold M_s when the
   end effector is already at x_s, else by the shortest collision-free straight joint
   move (a joint without limits may turn either way);
2. nominal: follows the nominal path to M_g^F;
3. recovering: when a joint locks (/ftplan/locked_joint) during 2, it commands a stop,
   waits until /joint_states shows the arm standing still, asks the core's `recover`
   for the path in S_F ∩ H_i from that configuration to M_g^F and commands it;
4. done (at the goal) or failed (with the reason).

A lock of a joint the plan does not tolerate (the planner names the tolerated joints in
its 'plan' status, plan_info.py) is handled the same way: a recovery path the core
finds in S_F is safe and is followed; without one the arm stays stopped and the
execution fails with "joint X is not tolerated by this plan". Arrival is judged with
the core's task errors against the plan's goal (position [m] and, for axis and pose
tasks, orientation [rad]). A scene file without a robot takes it from
/robot_description (scene_source.py); until then executions are refused.

An execution is refused while a joint that locked in an earlier one has not been
declared repaired (`~/reset`, std_srvs/Trigger: the approach would command it), and when
the current obstacles (scene and /ftplan/obstacles) touch a vertex of the plan's S_F:
the obstacles changed since the plan, so plan again.

Commands go out on /ftplan/joint_command as JointTrajectory (strictly increasing times,
the first point one step ahead of where the arm is), so a ros2_control
joint_trajectory_controller can take them (remap the topic); an empty trajectory asks
for a stop. Every state change, and the progress along the nominal path, is reported on
/diagnostics as 'ftplan_executor: execution'. A lock before or after the nominal phase,
a lock of an unknown joint and any malformed input are logged and reported, never
fatal.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, replace
from enum import StrEnum

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from rclpy.time import Time
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from ftplan_msgs_py import (
    create_joint_trajectory,
    read_diagnostic_status,
    read_failure_surface,
    read_joint_state,
    read_joint_trajectory,
    read_locked_joint,
)
from ftplan_ros.core import (
    FailureSurface,
    InputError,
    Robot,
    Scene,
    load_kernels,
    recover,
    self_motion_path,
    task_errors,
)

from .motion import path_clearance, progress_along, straight_moves, time_path
from .obstacles import ObstacleSet
from .params import (
    add_validators,
    check_startup_parameters,
    declare,
    positive,
)
from .plan_info import PLANNER_STATUS, PlanInfos, join_names, read_plan_info
from .qos import EVENT_QOS_DEPTH, LATCHED_QOS
from .reporting import Diagnostics, format_vector, stamp_key
from .scene_source import SceneSource
from .spinning import run_node
from .tasks import bind_task_kind
from .topics import (
    DIAGNOSTICS,
    EXECUTE_SERVICE,
    EXECUTOR_NODE,
    FAILURE_SURFACE,
    JOINT_COMMAND,
    JOINT_STATES,
    LOCKED_JOINT,
    OBSTACLES,
    RESET_SERVICE,
    ROBOT_DESCRIPTION,
    START_CONFIGURATION,
    TRAJECTORY,
)

_DIAGNOSTICS_DEPTH = 50
COLLISION_CHECK_STEP = 0.01  # [rad] between the clearance samples of an approach move
ON_MANIFOLD_TOLERANCE = 1e-6  # [m, rad] the end effector counts as at x_s within this


class State(StrEnum):
    """What the executor is doing; reported as the 'state' value of its status."""

    IDLE = 'idle'
    APPROACHING = 'approaching'
    NOMINAL = 'nominal'
    RECOVERING = 'recovering'
    DONE = 'done'
    FAILED = 'failed'


ACTIVE = (State.APPROACHING, State.NOMINAL, State.RECOVERING)


@dataclass(frozen=True, eq=False)
class HeldPlan:
    """A plan assembled from the latched topics (angles [rad])."""

    key: str                  # the plan's stamp as 'sec.nanosec'
    theta_s: np.ndarray       # (n,)
    surface: FailureSurface   # S_F; surface.nominal is the path the arm follows


@dataclass(eq=False)
class Execution:
    """One run of a plan: its lifted copy, the current command and the failure, if any."""

    number: int
    plan: HeldPlan
    surface: FailureSurface          # the plan's S_F shifted by whole turns to the arm's lift
    started: float                   # monotonic [s]
    command: np.ndarray | None = None     # (k, n) path being commanded, from where it began
    progress: float = 0.0            # fraction of the nominal path's length done
    locked_joint: int | None = None
    lock_received: float | None = None
    lock_progress: float | None = None
    lock_configuration: np.ndarray | None = None
    recovery_length: float | None = None
    stop_requested: float | None = None
    finished: float | None = None
    goal_error: float | None = None              # [m]
    goal_orientation_error: float | None = None  # [rad]
    reason: str = ''
    approach: str = ''
    requested_ns: int = 0            # ROS time [ns] of the request; older joint states are stale

    @property
    def nominal(self) -> np.ndarray:
        """The nominal path (k, n) [rad] in the arm's lift."""
        return self.surface.nominal_path


class ExecutorNode(Node):
    """Execute plans on /ftplan/execute and recover from locked joints."""

    def __init__(self, **kwargs):
        super().__init__(EXECUTOR_NODE, **kwargs)
        self.diagnostics = Diagnostics(self)
        self.source = SceneSource(self, self.diagnostics, self._scene_changed)
        self._declare_parameters()
        self.scene: Scene | None = None
        self.names: list[str] = []
        self.state = State.IDLE
        self.plan: HeldPlan | None = None
        self.plan_infos = PlanInfos()
        self.execution: Execution | None = None
        self.executions = 0
        self.locked_joints: set[int] = set()  # locked in an execution, not yet repaired
        self.q: np.ndarray | None = None
        self._previous_q: np.ndarray | None = None
        self._obstacles = ObstacleSet(None)
        self._start_msg: JointState | None = None
        self._trajectory_msg: JointTrajectory | None = None
        self._surface_msg: Float64MultiArray | None = None
        self._last_status = 0.0
        if self.source.scene is not None:
            self._use_scene(self.source.scene)
        self._create_interfaces()
        self.report_status('waiting for a plan')

    def _declare_parameters(self) -> None:
        declare(self, 'max_joint_speed', 1.0,
                'Fastest joint speed [rad/s] of the commanded trajectories.')
        declare(self, 'arrival_tolerance', 1e-6,
                'Largest joint error [rad] at which a command counts as completed. The sim '
                'lands exactly; raise it (with max_path_offset) for a real arm.')
        declare(self, 'max_path_offset', 1e-6,
                'Largest distance [rad] of the stopped arm from the nominal path that '
                'recovery accepts (the core recover()\'s max_offset).')
        declare(self, 'path_tolerance', 0.1,
                'Largest distance [rad] of the arm from the commanded path before the '
                'execution fails with a tracking error.')
        declare(self, 'stopped_tolerance', 1e-9,
                'Two consecutive joint states closer than this [rad] mean the arm stands still.')
        declare(self, 'stop_timeout', 5.0,
                'Seconds to wait for the arm to stop after a lock before failing.')
        declare(self, 'start_timeout', 5.0,
                'Seconds an execution waits for a joint state stamped after its request.')
        declare(self, 'status_rate', 10.0,
                'Rate [Hz] of the progress reports on /diagnostics while executing (1 Hz when '
                'idle).', read_only=True)
        declare(self, 'planner_status', PLANNER_STATUS,
                'Name of the planner\'s plan status on /diagnostics (task, tolerances and '
                'tolerated joints of each plan).')
        validators = {name: positive for name in (
            'max_joint_speed', 'arrival_tolerance', 'max_path_offset', 'path_tolerance',
            'stopped_tolerance', 'stop_timeout', 'start_timeout', 'status_rate')}
        check_startup_parameters(self, validators)
        add_validators(self, validators)

    def _create_interfaces(self) -> None:
        self.command_publisher = self.create_publisher(
            JointTrajectory, JOINT_COMMAND, EVENT_QOS_DEPTH)
        self.joint_state_subscription = self.create_subscription(
            JointState, JOINT_STATES, self.joint_state_callback, EVENT_QOS_DEPTH)
        self.locked_joint_subscription = self.create_subscription(
            JointState, LOCKED_JOINT, self.locked_joint_callback, EVENT_QOS_DEPTH)
        self.obstacle_subscription = self.create_subscription(
            MarkerArray, OBSTACLES, self.obstacles_callback, LATCHED_QOS)
        self.start_subscription = self.create_subscription(
            JointState, START_CONFIGURATION, self.start_configuration_callback, LATCHED_QOS)
        self.trajectory_subscription = self.create_subscription(
            JointTrajectory, TRAJECTORY, self.trajectory_callback, LATCHED_QOS)
        self.surface_subscription = self.create_subscription(
            Float64MultiArray, FAILURE_SURFACE, self.failure_surface_callback, LATCHED_QOS)
        self.diagnostics_subscription = self.create_subscription(
            DiagnosticArray, DIAGNOSTICS, self.diagnostics_callback, _DIAGNOSTICS_DEPTH)
        self.execute_service = self.create_service(
            Trigger, EXECUTE_SERVICE, self.execute_callback)
        self.reset_service = self.create_service(Trigger, RESET_SERVICE, self.reset_callback)
        rate = float(self.get_parameter('status_rate').value)
        self.status_timer = self.create_timer(1.0 / rate, self.status_callback)

    # The robot ----------------------------------------------------------------------

    def _use_scene(self, scene: Scene) -> None:
        """Execute with `scene`'s robot from now on; a plan for other joints is dropped."""
        load_kernels(scene.robot)  # approaches along M_s trace with it
        problems = self._obstacles.rebase(scene)
        names = list(scene.robot.joint_names)
        if names != self.names:  # another arm: nothing of the old one applies
            self.plan = self.execution = None
            self.locked_joints.clear()
            self.q = self._previous_q = None
        self.scene, self.names = scene, names
        for problem in problems:
            self.diagnostics.rejected('input', f'ignored obstacle markers: {problem}')

    def _scene_changed(self, scene: Scene) -> None:
        """Take a new robot from /robot_description (stopping an execution under way)."""
        if self.state in ACTIVE:
            self._stop()
            self._fail(f'{ROBOT_DESCRIPTION} changed during the execution: stopped')
        self._use_scene(scene)
        self._assemble_plan()
        self.report_status(f'robot from {ROBOT_DESCRIPTION}: {len(self.names)} joints', log=True)

    def _plan_robot(self, plan: HeldPlan) -> Robot:
        """Return the robot bound to the plan's task kind (the scene's when unknown)."""
        info = self.plan_infos.get(plan.key)
        robot = self.scene.robot
        if info is None:
            return robot
        try:
            return bind_task_kind(robot, info.task_kind)
        except InputError:
            return robot

    def _tolerated(self, plan: HeldPlan) -> tuple[str, ...] | None:
        """Return the joints the plan tolerates (None: its plan status did not arrive)."""
        info = self.plan_infos.get(plan.key)
        return None if info is None else info.tolerated_joints

    # The plan -----------------------------------------------------------------------

    def start_configuration_callback(self, msg: JointState) -> None:
        """Keep θ_s of the latest plan."""
        self._start_msg = msg
        self._assemble_plan()

    def trajectory_callback(self, msg: JointTrajectory) -> None:
        """Keep the nominal trajectory of the latest plan."""
        self._trajectory_msg = msg
        self._assemble_plan()

    def failure_surface_callback(self, msg: Float64MultiArray) -> None:
        """Keep S_F of the latest plan."""
        self._surface_msg = msg
        self._assemble_plan()

    def _assemble_plan(self) -> None:
        """Hold a new plan once θ_s, trajectory and S_F of one plan have all arrived."""
        start, trajectory, surface = self._start_msg, self._trajectory_msg, self._surface_msg
        if start is None or trajectory is None or surface is None or self.scene is None:
            return
        key = stamp_key(start.header.stamp)
        if stamp_key(trajectory.header.stamp) != key:
            return  # the other topic of this plan is still on its way
        if self.plan is not None and self.plan.key == key:
            return
        try:
            theta_s = read_joint_state(start, self.names)
            nominal = read_joint_trajectory(trajectory, self.names).positions
            paths = read_failure_surface(surface)
        except ValueError as error:
            self.diagnostics.rejected('plan', f'ignored plan {key}: {error}', {'plan': key})
            return
        if paths.shape[2] != len(self.names) or paths.shape[1] != len(nominal):
            return  # S_F of another plan; its own is on its way
        matches = np.flatnonzero(np.all(paths == nominal[None], axis=(1, 2)))
        if len(matches) == 0 or not np.array_equal(nominal[0], theta_s):
            return
        self.plan = HeldPlan(key, theta_s, FailureSurface(paths, int(matches[0]), (), ()))
        self.get_logger().info(f'holding plan {key}: {len(nominal)} waypoints, S_F of '
                               f'{paths.shape[0]} paths')
        self.report_status(f'holding plan {key}')

    def diagnostics_callback(self, msg: DiagnosticArray) -> None:
        """Keep what the planner's plan statuses say about each plan (plan_info.py)."""
        name = self.get_parameter('planner_status').value
        for status in msg.status:
            if status.name != name:
                continue
            try:
                reading = read_diagnostic_status(status)
            except ValueError:
                continue
            info = read_plan_info(reading.values) if reading.level == 'OK' else None
            if info is not None:
                self.plan_infos.add(info)

    def obstacles_callback(self, msg: MarkerArray) -> None:
        """Keep the obstacle topic, for checking approach moves and the held plan's S_F."""
        try:
            self._obstacles.update(msg)
        except ValueError as error:
            self.diagnostics.rejected('input', f'ignored obstacle markers: {error}; keeping '
                                      f'the {len(self._obstacles)} previous')

    # Execution ----------------------------------------------------------------------

    def execute_callback(self, request: Trigger.Request, response: Trigger.Response,
                         ) -> Trigger.Response:
        """Start executing the held plan: approach θ_s, then the nominal path."""
        try:
            response.success, response.message = self._start_execution()
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            self.get_logger().error(traceback.format_exc())
            response.success, response.message = False, f'internal executor error: {error!r}'
        if not response.success:
            self.diagnostics.rejected('input', f'execute refused: {response.message}')
        return response

    def reset_callback(self, request: Trigger.Request, response: Trigger.Response,
                       ) -> Trigger.Response:
        """Declare the locked joints repaired, so that executions may start again."""
        if self.state in ACTIVE:
            response.success = False
            response.message = f'execution {self.execution.number} is {self.state.value}'
            self.diagnostics.rejected('input', f'reset refused: {response.message}')
            return response
        repaired = [self.names[j] for j in sorted(self.locked_joints)]
        self.locked_joints.clear()
        response.success = True
        response.message = f'repaired: {repaired}' if repaired else 'no joint was locked'
        self.report_status(f'reset: {response.message}', log=True)
        return response

    def _start_execution(self) -> tuple[bool, str]:
        if self.state in ACTIVE:
            return False, f'execution {self.execution.number} is still {self.state.value}'
        if self.scene is None:
            return False, self.source.waiting
        if self.plan is None:
            return False, 'no plan yet: call the plan service (/ftplan/plan) first'
        if self.locked_joints:
            locked = [self.names[j] for j in sorted(self.locked_joints)]
            return False, (f'{locked} locked in execution {self.execution.number} and would be '
                           f'commanded: call {self.get_name()}/reset once repaired')
        if self._obstacles.checker.min_clearance(self.plan.surface.vertices,
                                                 needed=0.0).min() <= 0.0:
            return False, (f'the obstacles changed since plan {self.plan.key}: its failure '
                           'surface now meets one; plan again')
        self.executions += 1
        self.execution = Execution(self.executions, self.plan, self.plan.surface,
                                   time.monotonic(),
                                   requested_ns=self.get_clock().now().nanoseconds)
        # The move starts from the first joint state stamped after the request: the ones
        # received so far may predate it (e.g. a reset of the arm just before it).
        self._set_state(State.APPROACHING, 'starting from the next joint state')
        return True, f'execution {self.executions}: plan {self.plan.key} accepted'

    def _start_motion(self, q: np.ndarray) -> None:
        """Command the approach to θ_s from q (or the nominal path if the arm is there)."""
        ex = self.execution
        plan = ex.plan
        approach, how = self._approach(q, plan.theta_s)
        ex.approach = how
        if approach is None:
            self._fail(how)
            return
        # The approach may end whole turns away from θ_s: shift S_F to the arm's lift.
        turns = np.where(self.scene.robot.periodic,
                         np.round((approach[-1] - plan.theta_s) / (2.0 * np.pi)), 0.0)
        offset = 2.0 * np.pi * turns
        approach[-1] = plan.theta_s + offset
        if np.any(offset):
            ex.surface = replace(plan.surface, paths=plan.surface.paths + offset)
        self.get_logger().info(f'execution {ex.number} of plan {plan.key}: {how}')
        if len(approach) < 2:
            self._begin_nominal()
        else:
            self._command(approach)
            self._set_state(State.APPROACHING, how)

    def _approach(self, q: np.ndarray, theta_s: np.ndarray) -> tuple[np.ndarray | None, str]:
        """Find a collision-free path (k, n) from q to θ_s plus whole turns; say how it goes.

        A single point (1, n) means the arm is at θ_s already. Along M_s only with one
        degree of redundancy (M_s is then a curve).
        """
        robot = self._plan_robot(self.execution.plan)
        moves = straight_moves(q, theta_s, robot.periodic)
        if np.max(np.abs(moves[0][-1] - q)) <= \
                float(self.get_parameter('arrival_tolerance').value):
            return moves[0][-1:].copy(), 'already at theta_s'
        x_s = robot.forward_kinematics(theta_s)
        if robot.n_joints - robot.task_dim == 1 and \
                np.all(task_errors(robot, x_s, q) <= ON_MANIFOLD_TOLERANCE):
            path = self_motion_path(robot, x_s, q, theta_s)
            if path is not None and \
                    path_clearance(self._obstacles.checker, path, COLLISION_CHECK_STEP) > 0.0:
                return path.copy(), f'approaching theta_s along M_s ({len(path)} points)'
        for move in moves:
            if path_clearance(self._obstacles.checker, move, COLLISION_CHECK_STEP) > 0.0:
                return move, 'approaching theta_s by a straight joint move'
        return None, ('no collision-free approach to theta_s: neither along M_s nor by a '
                      'straight joint move')

    def _begin_nominal(self) -> None:
        ex = self.execution
        self._command(ex.nominal)
        self._set_state(State.NOMINAL, 'following the nominal path')

    def _command(self, path: np.ndarray) -> None:
        """Command `path` (k, n), whose first point is where the arm is."""
        speed = float(self.get_parameter('max_joint_speed').value)
        times = time_path(path, speed)
        self.execution.command = path
        self.command_publisher.publish(
            create_joint_trajectory(self.names, path[1:], times[1:]))

    def _stop(self) -> None:
        """Ask the controller to stop: an empty trajectory."""
        self.command_publisher.publish(JointTrajectory(joint_names=self.names))

    def _fail(self, reason: str) -> None:
        ex = self.execution
        ex.reason = reason
        ex.finished = time.monotonic()
        self._set_state(State.FAILED, reason, level='ERROR')

    def joint_state_callback(self, msg: JointState) -> None:
        """Track the arm and move the execution on from phase to phase.

        Messages that name none of the arm's joints (a gripper's, another arm's) are not
        the arm's; extra joints in the arm's message (fingers) are ignored.
        """
        if not self.names or not set(msg.name) & set(self.names):
            return
        try:
            q = read_joint_state(msg, self.names)
        except ValueError as error:
            self.get_logger().warning(f'rejected joint state: {error}', throttle_duration_sec=5.0)
            return
        self._previous_q, self.q = self.q, q
        if self.state not in ACTIVE:
            return
        try:
            self._track(q, Time.from_msg(msg.header.stamp).nanoseconds)
        except Exception as error:  # noqa: BLE001
            self.get_logger().error(traceback.format_exc())
            self._stop()
            self._fail(f'internal executor error: {error!r}')

    def _track(self, q: np.ndarray, stamp_ns: int) -> None:
        ex = self.execution
        arrival = float(self.get_parameter('arrival_tolerance').value)
        if self.state == State.NOMINAL:
            ex.progress, _ = progress_along(ex.nominal, q)
        if ex.command is None:
            if ex.locked_joint is not None:
                self._wait_for_stop(q)
            elif self.state == State.APPROACHING and (stamp_ns == 0 or
                                                      stamp_ns >= ex.requested_ns):
                self._start_motion(q)
            return
        _, deviation = progress_along(ex.command, q)
        if deviation > float(self.get_parameter('path_tolerance').value):
            self._stop()
            self._fail(f'tracking error: the arm is {deviation:.3f} rad from the commanded '
                       f'path while {self.state.value}')
            return
        if np.max(np.abs(q - ex.command[-1])) > arrival:
            return
        if self.state == State.APPROACHING:
            self._begin_nominal()
        else:
            self._finish(q)

    def _finish(self, q: np.ndarray) -> None:
        """Done: report the task errors [m, rad] from the plan's goal (its end, if unknown)."""
        ex = self.execution
        robot = self._plan_robot(ex.plan)
        info = self.plan_infos.get(ex.plan.key)
        goal = info.goal if info is not None and len(info.goal) == len(
            robot.forward_kinematics(q)) else robot.forward_kinematics(ex.nominal[-1])
        ex.finished = time.monotonic()
        ex.goal_error, ex.goal_orientation_error = (
            float(v) for v in task_errors(robot, goal, q))
        how = 'recovered' if ex.locked_joint is not None else 'nominal path'
        error = f'{ex.goal_error:.2e} m' + (f', {ex.goal_orientation_error:.2e} rad' if
                                            robot.task_kind in ('axis', 'pose') else '')
        self._set_state(State.DONE, f'reached the goal ({how}), error {error}')

    def locked_joint_callback(self, msg: JointState) -> None:
        """Handle a failure: during the nominal phase, stop and prepare the recovery."""
        try:
            event = read_locked_joint(msg)
        except ValueError as error:
            self.diagnostics.rejected('input', f'ignored locked-joint event: {error}')
            return
        if self.scene is None:
            self.diagnostics.rejected('input', f'ignored lock of {event.name}: '
                                      f'{self.source.waiting}', {'joint': event.name})
            return
        if event.name not in self.names:
            self.diagnostics.rejected('input', f'ignored lock of unknown joint {event.name!r}; '
                                      f'the arm has {self.names}', {'joint': event.name})
            return
        joint = self.names.index(event.name)
        ex = self.execution
        if self.state not in ACTIVE:
            what = 'no execution is running' if self.state == State.IDLE else \
                f'execution {ex.number} is {self.state.value}'
            self.diagnostics.rejected('input', f'ignored lock of {event.name}: {what}',
                                      {'joint': event.name, 'state': self.state.value})
            return
        self.locked_joints.add(joint)
        if self.state == State.APPROACHING:
            self._stop()
            ex.locked_joint, ex.lock_received = joint, time.monotonic()
            self._fail(f'{event.name} locked while approaching theta_s, before the '
                       'failure-tolerant nominal path began: no recovery is guaranteed')
            return
        if self.state == State.RECOVERING:
            if joint == ex.locked_joint:
                return  # the same failure reported again
            self._stop()
            self._fail(f'{event.name} locked after {self.names[ex.locked_joint]}: a second '
                       'failure is beyond the single-failure guarantee')
            return
        self._stop()
        ex.locked_joint, ex.lock_received = joint, time.monotonic()
        ex.stop_requested = ex.lock_received
        ex.command = None
        self._set_state(State.RECOVERING, f'{event.name} locked at about {ex.progress:.1%} '
                        'of the nominal path: stopping')

    def _wait_for_stop(self, q: np.ndarray) -> None:
        previous = self._previous_q
        if previous is None or np.max(np.abs(q - previous)) > \
                float(self.get_parameter('stopped_tolerance').value):
            return
        ex = self.execution
        joint = ex.locked_joint
        ex.lock_progress, _ = progress_along(ex.nominal, q)
        ex.progress = ex.lock_progress
        ex.lock_configuration = q.copy()
        name = self.names[joint]
        tolerated = self._tolerated(ex.plan)
        untolerated = tolerated is not None and name not in tolerated
        problem = ''
        try:
            rescue = recover(ex.surface, q, joint,
                             float(self.get_parameter('max_path_offset').value))
        except InputError as error:
            rescue, problem = None, str(error)
        if rescue is None:
            self._stop()  # the arm stands still: keep it so
            self._fail(self._no_recovery(name, tolerated, untolerated, problem))
            return
        ex.recovery_length = rescue.length
        self._command(rescue.path)
        note = ' (not tolerated by this plan, but S_F holds a recovery path)' if untolerated \
            else ''
        self._set_state(State.RECOVERING, f'{name} locked at {ex.lock_progress:.1%} of the '
                        f'nominal path{note}: following the recovery path ({len(rescue.path)} '
                        f'points, {rescue.length:.3f} rad)')

    def _no_recovery(self, name: str, tolerated: tuple[str, ...] | None, untolerated: bool,
                     problem: str) -> str:
        """Say why there is no recovery path for the lock of joint `name`."""
        progress = f'{self.execution.lock_progress:.1%} of the nominal path'
        where = f'locked at {progress}'
        if untolerated:
            return (f'joint {name} is not tolerated by this plan (it tolerates '
                    f'{", ".join(tolerated)}): S_F holds no recovery path from where it '
                    f'locked, at {progress}; the arm is stopped there')
        if problem:
            return f'cannot recover from {name} {where}: {problem}; the arm is stopped there'
        if tolerated is None:
            return (f'S_F holds no recovery path for {name} {where}: the plan may not tolerate '
                    'it (its plan status, which names the tolerated joints, did not arrive); '
                    'the arm is stopped there')
        return (f'S_F holds no recovery path for {name} {where}: the plan\'s guarantee is '
                'broken, please report')

    # Status -------------------------------------------------------------------------

    def status_callback(self) -> None:
        """Report progress while executing, 1 Hz otherwise; watch for a stop that hangs."""
        ex = self.execution
        if self.state == State.APPROACHING and ex.command is None and \
                time.monotonic() - ex.started > \
                float(self.get_parameter('start_timeout').value):
            self._fail('no joint state on /joint_states since the request (start_timeout)')
            return
        if self.state == State.RECOVERING and ex.command is None and \
                time.monotonic() - ex.stop_requested > \
                float(self.get_parameter('stop_timeout').value):
            self._stop()  # once more: the first request may have been lost
            self._fail('the arm did not stop after the lock (no two equal joint states within '
                       'stop_timeout)')
            return
        if self.state in ACTIVE or time.monotonic() - self._last_status >= 1.0:
            self.report_status(self.state.value)

    def _set_state(self, state: State, message: str, level: str = 'OK') -> None:
        self.state = state
        self.report_status(message, level, log=True)

    def report_status(self, message: str, level: str = 'OK', log: bool = False) -> None:
        """Publish the 'execution' status: state, plan, progress, failure, outcome."""
        self._last_status = time.monotonic()
        ex = self.execution
        values: dict[str, object] = {'state': self.state.value,
                                     'plan': self.plan.key if self.plan else ''}
        if ex is not None:
            values.update(execution=ex.number, execution_plan=ex.plan.key,
                          progress=ex.progress, approach=ex.approach)
            if ex.locked_joint is not None:
                values['locked_joint'] = self.names[ex.locked_joint]
            if ex.lock_progress is not None:
                values.update(lock_progress=ex.lock_progress,
                              lock_configuration=format_vector(ex.lock_configuration),
                              recovery_length_rad=ex.recovery_length)
            if ex.finished is not None:
                values['duration_s'] = ex.finished - ex.started
                if ex.lock_received is not None and self.state == State.DONE:
                    values['recovery_time_s'] = ex.finished - ex.lock_received  # to the goal
            if ex.goal_error is not None:
                values.update(goal_error_m=ex.goal_error,
                              goal_orientation_error_rad=ex.goal_orientation_error)
            if ex.reason:
                values['reason'] = ex.reason
        if self.locked_joints:
            values['locked_joints'] = join_names([self.names[j]
                                                  for j in sorted(self.locked_joints)])
        plan = ex.plan if ex is not None else self.plan
        tolerated = None if plan is None else self._tolerated(plan)
        if tolerated is not None:
            values['tolerated_joints'] = join_names(tolerated)  # of the execution's plan
        self.diagnostics.report('execution', level, message, values, log=log)


def main(args=None) -> int:
    """Run the executor node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(ExecutorNode, EXECUTOR_NODE, args)
