"""The executor node: runs the last plan and recovers from a locked joint.

    ros2 run ftplan_ros executor --ros-args -p scene_file:=fig3a.yaml

It keeps the last plan from the planner's latched topics (θ_s, the nominal trajectory,
the S_F web; the nominal path is the web path equal to the trajectory) once its plan
status has arrived on /ftplan/plan/info (plan_info.py). A call of /ftplan/execute
(std_srvs/Trigger):

1. approaching: moves the arm to θ_s by the planner's approach (/ftplan/plan/approach)
   when it starts where the arm stands, else by one the core plans now
   (core/approach.py): along the obstacle-free arc of M_s through the arm when the end
   effector is at x_s, else by a straight or an RRT-Connect joint move, each certified
   collision-free;
2. nominal: follows the nominal path to M_g^F;
3. recovering: when a joint locks (/ftplan/locked_joint) during 2, it commands a stop,
   waits until /joint_states shows the arm standing still, asks the core's `recover`
   for the path in S_F ∩ H_i from that configuration to M_g^F and commands it. A lock
   during 1 (not failure-tolerant) is handled alike, with a path to the goal planned
   from where the arm stopped with the joints left (`path_to_goal`), when there is one;
4. done (at the goal) or failed (with the reason).

A lock event stamped ahead of where the arm is on its command (a drill's scheduled
failure, injector.py) takes effect when /joint_states show the arm at the point the
command puts it at that moment (the sim locks it exactly there), not on arrival; any
other takes effect at once. `lock_progress` in the status is where the arm stood locked,
as a fraction of the nominal path's length (motion.py): where the lock landed.

A lock of a joint the plan does not tolerate (the planner names the tolerated joints in
its plan status) is handled the same way: a recovery path the core
finds in S_F is safe and is followed; without one the arm stays stopped and the
execution fails with "joint X is not tolerated by this plan". Arrival is judged with
the core's task errors against the plan's goal (position [m] and, for axis and pose
tasks, orientation [rad]). A scene file without a robot takes it from
/robot_description (scene_source.py); until then executions are refused.

Locked joints are remembered in one place (locks.py) whatever the executor is doing,
idle included, until they are declared repaired (`~/reset`, std_srvs/Trigger); no
command that would move one is ever published, and an execution is refused while one is
locked. An execution is also refused when the plan was made for another robot than the
current one (their digests differ: /robot_description replaced it, with the same joint
names), when obstacle updates were lost (obstacle_topic.py: until a full set arrives),
and when the current obstacles (scene and /ftplan/obstacles) touch a vertex of the
plan's S_F: the obstacles changed since the plan, so plan again. Obstacles that arrive
during an execution are checked against the rest of the commanded motion (certified)
and against S_F: on the approach the arm stops and a new approach is planned from where
it stands; on the nominal or recovery path it stops there safely, and the execution
fails with the reason. Obstacle updates lost during an execution stop the arm too and
fail it: an obstacle may have come into its way unseen. A second lock in one execution
stops the arm safely too. When /joint_states stops for `joint_state_timeout` during an
execution, a watchdog commands a stop and fails it.

Commands go out on /ftplan/joint_command as JointTrajectory (stamped with the moment they
start, strictly increasing times, the first point one step ahead of where the arm is),
so a ros2_control joint_trajectory_controller can take them (remap the topic); an empty
trajectory asks for a stop. Every state change, and the progress along the nominal path,
is reported on /diagnostics as 'ftplan_executor: execution'. A lock before or after the
nominal phase, a lock of an unknown joint and any malformed input (a joint state stamped
before the epoch, a lock angle away from where the joint is) are logged and reported,
never fatal.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, replace
from enum import StrEnum

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.duration import Duration
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from ftplan_msgs_py import (
    LockedJoint,
    create_joint_trajectory,
    read_diagnostic_status,
    read_failure_surface,
    read_joint_state,
    read_joint_trajectory,
)
from ftplan_ros.core import (
    FailureSurface,
    InputError,
    Robot,
    Scene,
    load_kernels,
    recover,
    task_errors,
)
from ftplan_ros.core.model.angles import configuration_difference
from ftplan_ros.core.model.paths import cumulative_fractions, point_at_fraction
from ftplan_ros.core.model.robot import robot_digest
from ftplan_ros.core.planning.approach import Approach, ApproachOptions, ApproachPlanner, Route

from .inputs import read_arm_state
from .locks import (
    DEFAULT_LOCK_ANGLE_TOLERANCE,
    JointLocks,
    lock_angle_problem,
    read_lock_event,
)
from .motion import fraction_at_time, progress_along, time_at_fraction, time_path
from .obstacle_topic import FULL_SET_FIX, ObstacleTopic
from .params import (
    add_validators,
    check_startup_parameters,
    declare,
    destroyed_if_start_fails,
    non_negative,
    positive,
)
from .plan_info import PlanInfos, join_names, read_plan_info
from .qos import EVENT_QOS_DEPTH, LATCHED_QOS, SERVICE_QOS
from .reporting import Diagnostics, format_vector, stamp_key
from .scene_source import SceneSource
from .spinning import run_node
from .tasks import bind_task_kind
from .topics import (
    APPROACH,
    EXECUTE_SERVICE,
    EXECUTOR_NODE,
    FAILURE_SURFACE,
    JOINT_COMMAND,
    JOINT_STATES,
    LOCKED_JOINT,
    PLAN_INFO,
    RESET_SERVICE,
    ROBOT_DESCRIPTION,
    START_CONFIGURATION,
    TRAJECTORY,
)

_REJECTION_REPORT_PERIOD = 1.0  # [s] a stream of bad joint states: one report per period
# [s] The sim stops at a scheduled lock's point of the command, read from the command's
# message, whose times are rounded to nanoseconds: the moment of the arm's position may
# differ from the lock's by a few nanoseconds.
_DUE_TOLERANCE = 1e-6
_LONGEST_LEAD = 1.0  # [s] of the nominal path's command: a longer pause would only stall


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
    command_times: np.ndarray | None = None  # (k,) [s] of the command, from its stamp
    command_stamp_ns: int = 0        # ROS time [ns] the command starts: its stamp
    scheduled_lock: tuple[LockedJoint, int, int] | None = None  # event, joint, stamp [ns]
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
    lock_received_ns: int = 0        # ROS time [ns] of the lock; the stop is judged after it
    lock_phase: State | None = None  # the phase the lock came in
    commanded: float = 0.0           # monotonic [s] of the last command
    reapproach: bool = False         # stopped on the approach (an obstacle): approach again

    @property
    def nominal(self) -> np.ndarray:
        """The nominal path (k, n) [rad] in the arm's lift."""
        return self.surface.nominal_path


class ExecutorNode(Node):
    """Execute plans on /ftplan/execute and recover from locked joints."""

    def __init__(self, **kwargs):
        with destroyed_if_start_fails(self):
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
            self.locks = JointLocks([])  # locked, not yet repaired: the one place (locks.py)
            self.q: np.ndarray | None = None
            self._previous_q: np.ndarray | None = None
            self._last_joint_state = 0.0  # monotonic [s] of the last good joint state
            self._last_motion = 0.0  # monotonic [s] of the last joint state that moved
            self._last_rejection_report = 0.0
            self.obstacle_topic = ObstacleTopic(self, self.diagnostics,
                                                on_update=self._obstacles_updated)
            self._obstacles = self.obstacle_topic.obstacles
            self._start_msg: JointState | None = None
            self._trajectory_msg: JointTrajectory | None = None
            self._surface_msg: Float64MultiArray | None = None
            self._approach_msg: JointTrajectory | None = None
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
        declare(self, 'stop_settle_time', 0.2,
                'Seconds after a lock before the arm standing still counts as stopped: a '
                'controller that had not yet taken up the last command may still start it '
                'and move before it takes up the stop.')
        declare(self, 'start_timeout', 5.0,
                'Seconds an execution waits for a joint state stamped after its request.')
        declare(self, 'joint_state_timeout', 2.0,
                'Seconds without a joint state during an execution after which the watchdog '
                'commands a stop and fails the execution.')
        declare(self, 'stall_timeout', 5.0,
                'Seconds the arm may stand still short of the end of a command before the '
                'execution fails (the controller dropped it, or the arm was reset).')
        declare(self, 'lock_angle_tolerance', DEFAULT_LOCK_ANGLE_TOLERANCE,
                'Farthest a lock event\'s angle may be from where the joint is [rad]; events '
                'beyond it are refused (a joint locks where it stands).')
        declare(self, 'approach_time', 1.0,
                'Budget [s] of each of the three RRT-Connect attempts of an approach (or, '
                'after a lock during it, of a path to the goal with the joints left).')
        declare(self, 'nominal_lead', 0.05,
                'Seconds from sending the command of the nominal path to its start (its '
                'stamp): time for a drill\'s lock, scheduled on that command (injector), to '
                'reach the arm before it moves. At most 1 s.')
        declare(self, 'status_rate', 10.0,
                'Rate [Hz] of the progress reports on /diagnostics while executing (1 Hz when '
                'idle).', read_only=True)
        validators = {name: positive for name in (
            'max_joint_speed', 'arrival_tolerance', 'max_path_offset', 'path_tolerance',
            'stopped_tolerance', 'stop_timeout', 'stop_settle_time', 'start_timeout',
            'status_rate', 'joint_state_timeout', 'stall_timeout', 'lock_angle_tolerance',
            'approach_time')}
        validators['nominal_lead'] = lambda value: non_negative(value) or (
            None if value <= _LONGEST_LEAD else f'must be at most {_LONGEST_LEAD} s, got {value}')
        check_startup_parameters(self, validators)
        add_validators(self, validators)

    def _create_interfaces(self) -> None:
        self.command_publisher = self.create_publisher(
            JointTrajectory, JOINT_COMMAND, EVENT_QOS_DEPTH)
        self.joint_state_subscription = self.create_subscription(
            JointState, JOINT_STATES, self.joint_state_callback, EVENT_QOS_DEPTH)
        self.locked_joint_subscription = self.create_subscription(
            JointState, LOCKED_JOINT, self.locked_joint_callback, EVENT_QOS_DEPTH)
        self.info_subscription = self.create_subscription(
            DiagnosticArray, PLAN_INFO, self.plan_info_callback, LATCHED_QOS)
        self.start_subscription = self.create_subscription(
            JointState, START_CONFIGURATION, self.start_configuration_callback, LATCHED_QOS)
        self.trajectory_subscription = self.create_subscription(
            JointTrajectory, TRAJECTORY, self.trajectory_callback, LATCHED_QOS)
        self.surface_subscription = self.create_subscription(
            Float64MultiArray, FAILURE_SURFACE, self.failure_surface_callback, LATCHED_QOS)
        self.approach_subscription = self.create_subscription(
            JointTrajectory, APPROACH, self.approach_callback, LATCHED_QOS)
        self.execute_service = self.create_service(
            Trigger, EXECUTE_SERVICE, self.execute_callback, qos_profile=SERVICE_QOS)
        self.reset_service = self.create_service(Trigger, RESET_SERVICE, self.reset_callback,
                                                 qos_profile=SERVICE_QOS)
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
            self.locks = JointLocks(names)
            self.q = self._previous_q = None
        self.scene, self.names = scene, names
        self.obstacle_topic.report_rebase(problems)

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

    def approach_callback(self, msg: JointTrajectory) -> None:
        """Keep the planner's approach to θ_s of the latest plan (used if it starts here)."""
        self._approach_msg = msg

    def _assemble_plan(self) -> None:
        """Hold a new plan once θ_s, trajectory, S_F and info of one plan have all arrived."""
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
        if len(matches) == 0 or not np.array_equal(nominal[0], theta_s) or \
                self.plan_infos.get(key) is None:
            return  # its S_F or its plan info is still on its way
        self.plan = HeldPlan(key, theta_s, FailureSurface(paths, int(matches[0]), (), ()))
        self.get_logger().info(f'holding plan {key}: {len(nominal)} waypoints, S_F of '
                               f'{paths.shape[0]} paths')
        self.report_status(f'holding plan {key}')

    def plan_info_callback(self, msg: DiagnosticArray) -> None:
        """Keep what the planner's plan status says about a plan (plan_info.py)."""
        for status in msg.status:
            try:
                reading = read_diagnostic_status(status)
            except ValueError as error:
                self.diagnostics.rejected('plan', f'ignored {PLAN_INFO}: {error}')
                continue
            info = read_plan_info(reading.values) if reading.level == 'OK' else None
            if info is None or info.stamp != stamp_key(msg.header.stamp):
                self.diagnostics.rejected('plan', f'ignored {PLAN_INFO}: it describes no plan '
                                          f'stamped {stamp_key(msg.header.stamp)}')
                continue
            self.plan_infos.add(info)
            self._assemble_plan()

    def _obstacles_updated(self) -> None:
        """During an execution: stop when updates were lost, else check the rest of the motion."""
        if self.state not in ACTIVE:
            return
        try:
            if self._obstacles.lost:
                self._stop()
                self._fail(f'{self._obstacles.lost} while {self.state.value}: an obstacle may '
                           f'be in the way unseen, so the arm is stopped where it is; '
                           f'{FULL_SET_FIX}, then plan again')
                return
            self._check_new_obstacles()
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            self.get_logger().error(traceback.format_exc())
            self._stop()
            self._fail(f'internal executor error: {error!r}')

    def _check_new_obstacles(self) -> None:
        """Stop when new obstacles meet the rest of the motion or (before a lock) S_F.

        On the approach the arm then approaches θ_s again from where it stops; on the
        nominal or recovery path it stays stopped and the execution fails.
        """
        ex = self.execution
        problem = ''
        rest = self._rest_of_command()
        if rest is not None and not self._approach_planner().certify(rest):
            problem = 'an obstacle that arrived meets the rest of the motion'
        elif self.state != State.RECOVERING and self._surface_meets_obstacle(ex.surface):
            problem = 'an obstacle that arrived meets the failure surface S_F: the rest of ' \
                'the motion would not be failure-tolerant'
        if not problem:
            return
        self._stop()
        if self.state == State.APPROACHING and not self._surface_meets_obstacle(ex.surface):
            ex.command, ex.reapproach = None, True
            self._set_state(State.APPROACHING, f'{problem} while approaching theta_s: stopped; '
                            'approaching again from where the arm stands', level='WARN')
            return
        self._fail(f'{problem} ({self.state.value}, {ex.progress:.1%} of the nominal path): '
                   'stopped there; plan again')

    def _rest_of_command(self) -> np.ndarray | None:
        """Return the part (k, n) [rad] of the command still ahead of the arm, if any."""
        ex = self.execution
        if ex.command is None or self.q is None or len(ex.command) < 2:
            return None
        fraction, _ = progress_along(ex.command, self.q)
        ahead = ex.command[cumulative_fractions(ex.command) > fraction]
        return np.vstack([point_at_fraction(ex.command, fraction)[None, :], ahead])

    def _surface_meets_obstacle(self, surface: FailureSurface) -> bool:
        """Whether a vertex of S_F touches the current obstacles (or measures NaN)."""
        return not self._obstacles.checker.min_clearance(surface.vertices,
                                                         needed=0.0).min() > 0.0

    def _approach_planner(self) -> ApproachPlanner:
        """Return the core's approach planner over the scene and the current obstacles."""
        plan = self.execution.plan if self.execution is not None else self.plan
        return ApproachPlanner(
            self._obstacles.checker,
            ApproachOptions(rrt_time=float(self.get_parameter('approach_time').value)),
            robot=self._plan_robot(plan) if plan is not None else None)

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
        repaired = self.locks.clear()
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
        if self.locks:
            locked = [self.names[j] for j in self.locks.joints]
            return False, (f'{locked} locked ({self.locks.describe()}) and would be commanded: '
                           f'call {self.get_name()}/reset once repaired')
        problem = self._stale_plan_problem()
        if problem:
            return False, problem
        if self._surface_meets_obstacle(self.plan.surface):
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

    def _stale_plan_problem(self) -> str:
        """Say why the held plan may not run on the robot and obstacles known now ('' if not)."""
        if self._obstacles.lost:
            return f'{self._obstacles.lost}: {FULL_SET_FIX}, then execute again'
        info = self.plan_infos.get(self.plan.key)
        robot = robot_digest(self.scene.robot)
        if info is not None and info.robot != robot:
            return (f'plan {self.plan.key} was made for robot {info.robot}, but the robot is '
                    f'now {robot} (from {ROBOT_DESCRIPTION}): plan again')
        return ''

    def _start_motion(self, q: np.ndarray) -> None:
        """Command the approach to θ_s from q (or the nominal path if the arm is there)."""
        ex = self.execution
        plan = ex.plan
        ex.reapproach = False
        found = self._approach(q, plan.theta_s)
        ex.approach = found.describe()
        if not found.ok:
            self._fail(f'no collision-free approach to theta_s from where the arm stands: '
                       f'{found.reason}')
            return
        approach = found.path.copy()
        how = f'approaching theta_s {ex.approach}'
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
        elif self._command(approach):
            self._set_state(State.APPROACHING, how)

    def _approach(self, q: np.ndarray, theta_s: np.ndarray) -> Approach:
        """Find a certified path (k, n) from q to θ_s plus whole turns (core/approach.py).

        The planner's approach of this plan is taken when it starts where the arm stands,
        ends at θ_s (whole turns apart on periodic joints) and is still clear of the
        obstacles; else one is planned now. A single point
        (1, n) means the arm is at θ_s already.
        """
        arrival = float(self.get_parameter('arrival_tolerance').value)
        planner = self._approach_planner()
        given = self._planned_approach()
        periodic = self.scene.robot.periodic
        if given is not None and np.max(np.abs(given[0] - q)) <= arrival and np.max(np.abs(
                configuration_difference(given[-1], theta_s, periodic))) <= arrival:
            given[0] = q
            if planner.certify(given):
                return Approach(given, Route.GIVEN)
        return planner.approach(q, theta_s, arrival)

    def _planned_approach(self) -> np.ndarray | None:
        """Return the planner's approach path (k, n) of the executed plan, if it sent one."""
        msg = self._approach_msg
        if msg is None or stamp_key(msg.header.stamp) != self.execution.plan.key or \
                not msg.points:
            return None
        try:
            return read_joint_trajectory(msg, self.names).positions
        except ValueError:
            return None

    def _begin_nominal(self) -> None:
        ex = self.execution
        if self._command(ex.nominal, float(self.get_parameter('nominal_lead').value)):
            self._set_state(State.NOMINAL, 'following the nominal path')

    def _command(self, path: np.ndarray, lead: float = 0.0) -> bool:
        """Command `path` (k, n), whose first point is where the arm is; False if refused.

        The command starts `lead` [s] after now: its stamp. A path that would move a
        locked joint is never published: the arm is stopped and the execution fails
        instead (that would be a bug of the executor).
        """
        moved = self.locks.moved(path)
        if moved:
            self._stop()
            self._fail(f'refused to command a path that moves locked joint {moved}: the arm '
                       'is stopped (please report)')
            return False
        speed = float(self.get_parameter('max_joint_speed').value)
        ex = self.execution
        stamp = self.get_clock().now() + Duration(nanoseconds=round(lead * 1e9))
        ex.command, ex.command_times = path, time_path(path, speed)
        ex.command_stamp_ns = stamp.nanoseconds
        ex.commanded = time.monotonic()
        self.command_publisher.publish(create_joint_trajectory(
            self.names, path[1:], ex.command_times[1:], stamp.to_msg()))
        return True

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
            q, stamp_ns = read_arm_state(msg, self.scene.robot)
        except ValueError as error:
            self._reject_joint_state(str(error))
            return
        self._previous_q, self.q = self.q, q
        self._last_joint_state = time.monotonic()
        if not self._standing(q):
            self._last_motion = self._last_joint_state
        if self.state not in ACTIVE:
            return
        try:
            self._track(q, stamp_ns)
        except Exception as error:  # noqa: BLE001
            self.get_logger().error(traceback.format_exc())
            self._stop()
            self._fail(f'internal executor error: {error!r}')

    def _reject_joint_state(self, problem: str) -> None:
        """Log a rejected joint state and report it, at most once per second."""
        self.get_logger().warning(f'rejected joint state: {problem}', throttle_duration_sec=5.0)
        now = time.monotonic()
        if now - self._last_rejection_report >= _REJECTION_REPORT_PERIOD:
            self._last_rejection_report = now
            self.diagnostics.report('input', 'WARN', f'rejected joint state: {problem}')

    def _track(self, q: np.ndarray, stamp_ns: int) -> None:
        ex = self.execution
        arrival = float(self.get_parameter('arrival_tolerance').value)
        if self.state == State.NOMINAL:
            ex.progress, _ = progress_along(ex.nominal, q)
        if ex.scheduled_lock is not None and self._lock_due(ex.scheduled_lock[2], q):
            event, joint, _ = ex.scheduled_lock
            ex.scheduled_lock = None
            self._take_lock(event, joint)
            return
        if ex.command is None:
            if ex.locked_joint is not None:
                # Joint states sent before the lock may still be queued (the executor takes
                # another topic's messages in no set order with the lock's): a stop judged
                # on them would recover from where the arm no longer is.
                if _sent_since(stamp_ns, ex.lock_received_ns):
                    self._wait_for_stop(q)
            elif ex.reapproach:
                if self._standing(q):
                    self._start_motion(q)
            elif self.state == State.APPROACHING and _sent_since(stamp_ns, ex.requested_ns):
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
        goal = self._plan_goal(ex.plan)
        ex.finished = time.monotonic()
        ex.goal_error, ex.goal_orientation_error = (
            float(v) for v in task_errors(robot, goal, q))
        how = 'recovered' if ex.locked_joint is not None else 'nominal path'
        error = f'{ex.goal_error:.2e} m' + (f', {ex.goal_orientation_error:.2e} rad' if
                                            robot.task_kind in ('axis', 'pose') else '')
        self._set_state(State.DONE, f'reached the goal ({how}), error {error}')

    def locked_joint_callback(self, msg: JointState) -> None:
        """Handle a failure: stop and prepare the recovery, when the lock takes effect.

        That is at once, or, for an event stamped ahead of where the arm is on its command
        (a drill's scheduled failure), when the arm gets there (`_track`).
        """
        found = read_lock_event(
            msg, None if self.scene is None else self.names, self.source.waiting,
            lambda why, name: self.diagnostics.rejected(
                'input', why, None if name is None else {'joint': name}))
        if found is None:
            return
        event, joint, stamp_ns = found
        ex = self.execution
        if self.state in ACTIVE and ex.scheduled_lock is None and \
                not self._lock_due(stamp_ns, self.q):
            ex.scheduled_lock = (event, joint, stamp_ns)
            self.report_status(f'{event.name} locks at {self._fraction_at(stamp_ns):.1%} of '
                               f'the command under way ({self.state.value}): scheduled',
                               log=True)
            return
        self._take_lock(event, joint)

    def _lock_due(self, stamp_ns: int, q: np.ndarray | None) -> bool:
        """Whether a lock stamped `stamp_ns` [ns] has taken effect with the arm at q (n,).

        It has once the arm is where its command puts it at that moment, and at once
        without a command under way (or a joint state). Not by the clock: an arm that
        took the command late gets there late.
        """
        ex = self.execution
        if ex.command is None or q is None:
            return True
        progress, _ = progress_along(ex.command, q)
        reached = time_at_fraction(ex.command, ex.command_times, progress)
        return reached >= (stamp_ns - ex.command_stamp_ns) * 1e-9 - _DUE_TOLERANCE

    def _fraction_at(self, stamp_ns: int) -> float:
        """Return the fraction of the command under way that it commands by `stamp_ns` [ns]."""
        ex = self.execution
        return fraction_at_time(ex.command, ex.command_times,
                                (stamp_ns - ex.command_stamp_ns) * 1e-9)

    def _take_lock(self, event: LockedJoint, joint: int) -> None:
        """Take the lock of `joint`: remember it; during an execution, stop the arm to recover."""
        current = None if self.q is None else float(self.q[joint])
        problem = lock_angle_problem(event.name, event.angle, current,
                                     bool(self.scene.robot.periodic[joint]),
                                     float(self.get_parameter('lock_angle_tolerance').value))
        if problem:
            self.diagnostics.rejected('input', f'ignored locked-joint event: {problem}',
                                      {'joint': event.name})
            return
        ex = self.execution
        active = self.state in ACTIVE
        if not self.locks.lock(joint, current, ex.number if active else None):
            return  # the same failure reported again
        if not active:
            self.report_status(f'{event.name} locked while no execution is running: '
                               'remembered; executions are refused until '
                               f'{self.get_name()}/reset declares it repaired', 'WARN', log=True)
            return
        if ex.locked_joint is not None:
            self._stop()
            self._fail(f'{event.name} locked after {self.names[ex.locked_joint]}: a second '
                       'failure is beyond the single-failure guarantee; the arm is stopped '
                       'safely where it is')
            return
        self._stop()
        ex.locked_joint, ex.lock_received = joint, time.monotonic()
        ex.lock_received_ns = self.get_clock().now().nanoseconds
        ex.stop_requested = ex.lock_received
        ex.lock_phase = self.state
        ex.command = None
        if self.state == State.APPROACHING:
            message = (f'{event.name} locked while approaching theta_s, before the '
                       'failure-tolerant nominal path began: stopping, then planning a path to '
                       'the goal with the joints left (not failure-tolerant)')
        else:
            message = f'{event.name} locked at about {ex.progress:.1%} of the nominal path: ' \
                'stopping'
        self._set_state(State.RECOVERING, message, level='WARN' if ex.lock_phase ==
                        State.APPROACHING else 'OK')

    def _standing(self, q: np.ndarray) -> bool:
        """Whether the last two joint states show the arm standing still."""
        previous = self._previous_q
        return previous is not None and np.max(np.abs(q - previous)) <= \
            float(self.get_parameter('stopped_tolerance').value)

    def _wait_for_stop(self, q: np.ndarray) -> None:
        ex = self.execution
        if not self._standing(q) or time.monotonic() - ex.stop_requested < float(
                self.get_parameter('stop_settle_time').value):
            return
        self.locks.settle(q)
        if ex.lock_phase == State.APPROACHING:
            self._replan_with_joints_left(q)
            return
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
        if not self._command(rescue.path):
            return
        note = ' (not tolerated by this plan, but S_F holds a recovery path)' if untolerated \
            else ''
        self._set_state(State.RECOVERING, f'{name} locked at {ex.lock_progress:.1%} of the '
                        f'nominal path{note}: following the recovery path ({len(rescue.path)} '
                        f'points, {rescue.length:.3f} rad)')

    def _replan_with_joints_left(self, q: np.ndarray) -> None:
        """After a lock on the approach: a path to the goal with the locked joint held."""
        ex = self.execution
        joint = ex.locked_joint
        name = self.names[joint]
        ex.lock_configuration = q.copy()
        found = self._approach_planner().path_to_goal(q, self._plan_goal(ex.plan), joint)
        if not found.ok:
            self._stop()  # the arm stands still: keep it so
            self._fail(f'{name} locked while approaching theta_s (not failure-tolerant) and '
                       f'{found.reason}; the arm is stopped where it is')
            return
        ex.recovery_length = found.length
        if self._command(found.path):
            self._set_state(State.RECOVERING, f'{name} locked while approaching theta_s: '
                            f'following a path to the goal with the joints left, '
                            f'{found.describe()} (not failure-tolerant)', level='WARN')

    def _plan_goal(self, plan: HeldPlan) -> np.ndarray:
        """Return the plan's goal task point: its status's, else its nominal path's end."""
        robot = self._plan_robot(plan)
        info = self.plan_infos.get(plan.key)
        end = robot.forward_kinematics(plan.surface.nominal_path[-1])
        return info.goal if info is not None and len(info.goal) == len(end) else end

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
        if self._joint_states_stopped():
            self._stop()
            self._fail(f'watchdog: no joint state for more than '
                       f'{self.get_parameter("joint_state_timeout").value} s '
                       '(joint_state_timeout) while the arm was commanded: stop commanded')
            return
        if self.state in ACTIVE and ex.command is not None and time.monotonic() - max(
                ex.commanded, self._last_motion) > float(
                    self.get_parameter('stall_timeout').value):
            self._stop()
            self._fail(f'the arm stands still short of the end of the command while '
                       f'{self.state.value} (stall_timeout): stopped there')
            return
        if self.state in ACTIVE or time.monotonic() - self._last_status >= 1.0:
            self.report_status(self.state.value)

    def _joint_states_stopped(self) -> bool:
        """Whether /joint_states went quiet during an execution that has started moving."""
        ex = self.execution
        if self.state not in ACTIVE or (self.state == State.APPROACHING and
                                        ex.command is None and not ex.reapproach):
            return False  # not moving yet: start_timeout's case
        # From the last command too: planning it (an RRT-Connect approach) may take longer
        # than the timeout, with the joint states waiting behind it.
        quiet = time.monotonic() - max(self._last_joint_state, ex.started, ex.commanded)
        return quiet > float(self.get_parameter('joint_state_timeout').value)

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
                values['lock_progress'] = ex.lock_progress
            if ex.lock_configuration is not None:
                values.update(lock_configuration=format_vector(ex.lock_configuration),
                              recovery_length_rad=ex.recovery_length)
            if ex.lock_phase is not None:
                values['lock_phase'] = ex.lock_phase.value
            if ex.finished is not None:
                values['duration_s'] = ex.finished - ex.started
                if ex.lock_received is not None and self.state == State.DONE:
                    values['recovery_time_s'] = ex.finished - ex.lock_received  # to the goal
            if ex.goal_error is not None:
                values.update(goal_error_m=ex.goal_error,
                              goal_orientation_error_rad=ex.goal_orientation_error)
            if ex.reason:
                values['reason'] = ex.reason
        if self.locks:
            values['locked_joints'] = join_names([self.names[j] for j in self.locks.joints])
        plan = ex.plan if ex is not None else self.plan
        tolerated = None if plan is None else self._tolerated(plan)
        if tolerated is not None:
            values['tolerated_joints'] = join_names(tolerated)  # of the execution's plan
        self.diagnostics.report('execution', level, message, values, log=log)


def _sent_since(stamp_ns: int, since_ns: int) -> bool:
    """Whether a message stamped `stamp_ns` [ns, ROS time] was sent at `since_ns` or later.

    An unstamped message (0) counts as sent now: older ones may still be queued.
    """
    return stamp_ns == 0 or stamp_ns >= since_ns


def main(args=None) -> int:
    """Run the executor node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(ExecutorNode, EXECUTOR_NODE, args)
