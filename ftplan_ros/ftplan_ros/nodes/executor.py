"""The executor node: runs the last plan and recovers from a locked joint.

    ros2 run ftplan_ros executor --ros-args -p scene_file:=fig3a.yaml

An adapter: what a run does (approach θ_s, follow the nominal path, recover from a
lock), and when an execution is refused or fails, is the executor's logic
(execution/executor.py, without ROS). This node reads its parameters into the logic's
options, turns messages into the logic's verbs and carries out the actions they return.

In:
- the plan: θ_s, the nominal trajectory and S_F from the planner's latched topics, and
  its plan status from /ftplan/plan/info (what it is for: the task, the tolerated joints,
  the robot's digest), held once all four of one plan have arrived (plan_assembly.py);
  the planner's approach to θ_s from /ftplan/plan/approach, taken when it starts where
  the arm stands;
- /ftplan/execute (std_srvs/Trigger) starts a run; `~/reset` (std_srvs/Trigger)
  declares the locked joints repaired;
- /joint_states (messages that name none of the arm's joints are not the arm's),
  /ftplan/locked_joint (lock_events.py), /ftplan/obstacles (obstacle_topic.py), and
  /robot_description when the scene file has no robot (scene_source.py; until then
  executions are refused).

Out:
- /ftplan/joint_command: JointTrajectory commands, stamped with the moment they start,
  strictly increasing times, the first point one step ahead of where the arm is, so a
  ros2_control joint_trajectory_controller can take them (remap the topic); an empty
  trajectory asks for a stop;
- /diagnostics 'ftplan_executor: execution': every state change and, at `status_rate`
  while executing (1 Hz when idle), the progress along the nominal path (values:
  `status_values`); 'ftplan_executor: input' and 'ftplan_executor: plan' for refused
  input. A malformed message (a joint state stamped before the epoch, a lock of an
  unknown joint, a lock angle away from where the joint is) is logged and reported,
  never fatal; an error inside the logic stops the arm and fails the run.
"""

from __future__ import annotations

import time
import traceback
from collections.abc import Callable
from dataclasses import fields

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.time import Time
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from ftplan_msgs_py import create_joint_trajectory, read_joint_trajectory
from ftplan_ros.core import InputError, Robot, Scene, load_kernels
from ftplan_ros.execution.actions import Action, Answer, Moment, Rejected, Status, Stop
from ftplan_ros.execution.command import Command
from ftplan_ros.execution.executor import Executor
from ftplan_ros.execution.options import LONGEST_LEAD, ExecutorOptions, Interfaces
from ftplan_ros.execution.state import HeldPlan, State

from .inputs import read_arm_state
from .lock_events import read_lock_event
from .motion_limit_parameters import declare_motion_limit_parameters, file_motion_limits
from .obstacle_topic import FULL_SET_FIX, ObstacleTopic
from .params import (
    add_validators,
    check_startup_parameters,
    declare,
    destroyed_if_start_fails,
    non_negative,
    options_from_parameters,
    positive,
)
from .plan_assembly import LatchedPlan, PlanTopics
from .plan_info import join_names
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
_DEFAULTS = ExecutorOptions()


class ExecutorNode(Node):
    """Execute plans on /ftplan/execute and recover from locked joints (execution/executor.py)."""

    def __init__(self, **kwargs):
        with destroyed_if_start_fails(self):
            super().__init__(EXECUTOR_NODE, **kwargs)
            self.diagnostics = Diagnostics(self)
            self.source = SceneSource(self, self.diagnostics, self._scene_changed)
            self._declare_parameters()
            self.scene: Scene | None = None
            self.names: list[str] = []
            self.obstacle_topic = ObstacleTopic(self, self.diagnostics,
                                                on_update=self._obstacles_updated)
            self._obstacles = self.obstacle_topic.obstacles
            self.logic = Executor(self._obstacles, self._options(), Interfaces(
                f'{self.get_name()}/reset', ROBOT_DESCRIPTION, FULL_SET_FIX))
            self.topics = PlanTopics()
            self._approach_msg: JointTrajectory | None = None
            self._last_rejection_report = 0.0
            if self.source.scene is not None:
                self._use_scene(self.source.scene)
            self._create_interfaces()
            self._report('waiting for a plan')

    @property
    def plan(self) -> HeldPlan | None:
        """The plan held for the next execution."""
        return self.logic.plan

    def _declare_parameters(self) -> None:
        declare(self, 'max_joint_speed', _DEFAULTS.max_joint_speed,
                'Cap [rad/s] on every joint\'s speed in the commanded trajectories, below '
                'the robot\'s velocity limits.')
        declare(self, 'max_step', _DEFAULTS.max_step,
                'Farthest [rad] any joint moves between two commanded points.')
        declare(self, 'arrival_tolerance', _DEFAULTS.arrival_tolerance,
                'Largest joint error [rad] at which a command counts as completed. The sim '
                'lands exactly; raise it (with max_path_offset) for a real arm.')
        declare(self, 'max_path_offset', _DEFAULTS.max_path_offset,
                'Largest distance [rad] of the stopped arm from the nominal path that '
                'recovery accepts (the core recover()\'s max_offset).')
        declare(self, 'path_tolerance', _DEFAULTS.path_tolerance,
                'Largest distance [rad] of the arm from the commanded path before the '
                'execution fails with a tracking error.')
        declare(self, 'stopped_tolerance', _DEFAULTS.stopped_tolerance,
                'Two consecutive joint states closer than this [rad] mean the arm stands still.')
        declare(self, 'stop_timeout', _DEFAULTS.stop_timeout,
                'Seconds to wait for the arm to stop after a lock before failing.')
        declare(self, 'stop_settle_time', _DEFAULTS.stop_settle_time,
                'Seconds after a lock before the arm standing still counts as stopped: a '
                'controller that had not yet taken up the last command may still start it '
                'and move before it takes up the stop.')
        declare(self, 'start_timeout', _DEFAULTS.start_timeout,
                'Seconds an execution waits for a joint state stamped after its request.')
        declare(self, 'joint_state_timeout', _DEFAULTS.joint_state_timeout,
                'Seconds without a joint state during an execution after which the watchdog '
                'commands a stop and fails the execution.')
        declare(self, 'stall_timeout', _DEFAULTS.stall_timeout,
                'Seconds the arm may stand still short of the end of a command before the '
                'execution fails (the controller dropped it, or the arm was reset).')
        declare(self, 'lock_angle_tolerance', _DEFAULTS.lock_angle_tolerance,
                'Farthest a lock event\'s angle may be from where the joint is [rad]; events '
                'beyond it are refused (a joint locks where it stands).')
        declare(self, 'approach_time', _DEFAULTS.approach_time,
                'Budget [s] of each of the three RRT-Connect attempts of an approach (or, '
                'after a lock during it, of a path to the goal with the joints left).')
        declare(self, 'margin', _DEFAULTS.margin,
                'Clearance [m] the executor\'s own certifications keep: the approach, a move '
                'back to the nominal path after a lock, a recovery path moved to where a brake '
                'holds. Give it the planner\'s margin.')
        declare(self, 'nominal_lead', _DEFAULTS.nominal_lead,
                'Seconds from sending the command of the nominal path to its start (its '
                'stamp): time for a drill\'s lock, scheduled on that command (injector), to '
                'reach the arm before it moves. At most 1 s.')
        declare(self, 'status_rate', 10.0,
                'Rate [Hz] of the progress reports on /diagnostics while executing (1 Hz when '
                'idle).', read_only=True)
        validators = {field.name: positive for field in fields(ExecutorOptions)}
        validators['status_rate'] = positive
        validators['margin'] = non_negative
        validators.update(declare_motion_limit_parameters(
            self, _DEFAULTS.max_velocity_scaling_factor,
            _DEFAULTS.max_acceleration_scaling_factor))
        validators['nominal_lead'] = lambda value: non_negative(value) or (
            None if value <= LONGEST_LEAD else f'must be at most {LONGEST_LEAD} s, got {value}')
        check_startup_parameters(self, validators)
        add_validators(self, validators)
        self.add_post_set_parameters_callback(self._parameters_set)

    def _options(self) -> ExecutorOptions:
        """Return the logic's options from the parameters of the same names."""
        return options_from_parameters(self, ExecutorOptions)

    def _parameters_set(self, parameters: list[Parameter]) -> None:
        self.logic.options = self._options()

    def _create_interfaces(self) -> None:
        self.command_publisher = self.create_publisher(
            JointTrajectory, JOINT_COMMAND, EVENT_QOS_DEPTH)
        self.joint_state_subscription = self.create_subscription(
            JointState, JOINT_STATES, self.joint_state_callback, EVENT_QOS_DEPTH)
        self.locked_joint_subscription = self.create_subscription(
            JointState, LOCKED_JOINT, self.locked_joint_callback, EVENT_QOS_DEPTH)
        self.info_subscription = self.create_subscription(
            DiagnosticArray, PLAN_INFO, self.plan_info_callback, LATCHED_QOS)
        for msg_type, topic, kept in (
                (JointState, START_CONFIGURATION, self.topics.starts),
                (JointTrajectory, TRAJECTORY, self.topics.trajectories),
                (Float64MultiArray, FAILURE_SURFACE, self.topics.surfaces)):
            self.create_subscription(msg_type, topic, lambda msg, kept=kept: self._keep(
                kept, msg), LATCHED_QOS)
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
        """Execute with `scene`'s robot from now on (a run under way stops and fails).

        Raises InputError, with nothing changed, when joint_limits_file does not fit it.
        """
        limits = file_motion_limits(self, scene.robot)
        self._perform(self.logic.use_robot(scene.robot, self._now(), limits))
        load_kernels(scene.robot)  # approaches along M_s trace with it
        problems = self._obstacles.rebase(scene)
        self.scene, self.names = scene, list(scene.robot.joint_names)
        self._pass_approach()
        self.obstacle_topic.report_rebase(problems)

    def _scene_changed(self, scene: Scene) -> None:
        """Take a new robot from /robot_description (stopping an execution under way)."""
        try:
            self._use_scene(scene)
        except InputError as error:
            self._report(f'robot from {ROBOT_DESCRIPTION} refused: {error}', 'ERROR', log=True)
            return
        self._assemble_plan()
        self._report(f'robot from {ROBOT_DESCRIPTION}: {len(self.names)} joints', log=True)

    # The plan -----------------------------------------------------------------------

    def _keep(self, kept, msg) -> None:
        """Keep a message of one of the plan's latched topics; hold the plan if complete."""
        kept.append(msg)
        self._assemble_plan()

    def plan_info_callback(self, msg: DiagnosticArray) -> None:
        """Keep what the planner's plan status says about a plan (plan_info.py)."""
        for problem in self.topics.add_info(msg):
            self.diagnostics.rejected('plan', problem)
        self._assemble_plan()

    def approach_callback(self, msg: JointTrajectory) -> None:
        """Keep the planner's approach to θ_s of the latest plan (used if it starts here)."""
        self._approach_msg = msg
        self._pass_approach()

    def _pass_approach(self) -> None:
        """Give the logic the planner's latest approach, read for the arm's joints."""
        msg = self._approach_msg
        if msg is None or not self.names:
            return
        try:
            path = read_joint_trajectory(msg, self.names).positions if msg.points else None
        except ValueError:
            path = None
        self.logic.take_approach(stamp_key(msg.header.stamp), path)

    def _assemble_plan(self) -> None:
        """Hold a new plan once θ_s, trajectory, S_F and plan status of one have all arrived."""
        key = self.topics.newest_key()
        held = self.logic.plan
        if key is None or self.scene is None or (held is not None and held.key == key):
            return
        try:
            latched = self.topics.assemble(key, self.names)
        except ValueError as error:
            self.diagnostics.rejected('plan', f'ignored plan {key}: {error}', {'plan': key})
            return
        if latched is None:
            return  # a topic of this plan is still on its way
        self.get_logger().info(f'holding plan {key}: {len(latched.trajectory)} waypoints, S_F '
                               f'of {latched.paths.shape[0]} paths')
        self._perform(self.logic.hold(held_plan(latched, self.scene.robot), self._now()))

    # Requests -----------------------------------------------------------------------

    def execute_callback(self, request: Trigger.Request, response: Trigger.Response,
                         ) -> Trigger.Response:
        """Start executing the held plan: approach θ_s, then the nominal path."""
        now = self._now()
        try:
            answer = self.logic.start(now) if self.scene is not None else \
                Answer(False, self.source.waiting)
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            self.get_logger().error(traceback.format_exc())
            reason = f'internal executor error: {error!r}'
            answer = Answer(False, reason, self.logic.abort(reason, now))
        self._perform(answer.actions)
        response.success, response.message = answer.success, answer.message
        if not response.success:
            self.diagnostics.rejected('input', f'execute refused: {response.message}')
        return response

    def reset_callback(self, request: Trigger.Request, response: Trigger.Response,
                       ) -> Trigger.Response:
        """Declare the locked joints repaired, so that executions may start again."""
        answer = self.logic.reset(self._now())
        self._perform(answer.actions)
        response.success, response.message = answer.success, answer.message
        if not response.success:
            self.diagnostics.rejected('input', f'reset refused: {response.message}')
        return response

    # Inputs -------------------------------------------------------------------------

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
        self._call(lambda now: self.logic.on_joint_state(q, stamp_ns, now))

    def _reject_joint_state(self, problem: str) -> None:
        """Log a rejected joint state and report it, at most once per second."""
        self.get_logger().warning(f'rejected joint state: {problem}', throttle_duration_sec=5.0)
        now = time.monotonic()
        if now - self._last_rejection_report >= _REJECTION_REPORT_PERIOD:
            self._last_rejection_report = now
            self.diagnostics.report('input', 'WARN', f'rejected joint state: {problem}')

    def locked_joint_callback(self, msg: JointState) -> None:
        """Hand a failure event to the logic: it stops the arm and recovers when it takes effect."""
        found = read_lock_event(
            msg, None if self.scene is None else self.names, self.source.waiting,
            lambda why, name: self.diagnostics.rejected(
                'input', why, None if name is None else {'joint': name}))
        if found is not None:
            event, joint, stamp_ns = found
            self._call(lambda now: self.logic.on_lock(joint, event.angle, stamp_ns, now))

    def _obstacles_updated(self) -> None:
        """Have the logic check a run under way against the obstacles, which changed."""
        self._call(self.logic.on_obstacles)

    def status_callback(self) -> None:
        """Report progress while executing, 1 Hz otherwise; the logic watches the timeouts."""
        self._call(self.logic.tick)

    # Actions ------------------------------------------------------------------------

    def _now(self) -> Moment:
        return Moment(time.monotonic(), self.get_clock().now().nanoseconds)

    def _call(self, verb: Callable[[Moment], list[Action]]) -> None:
        """Call a verb of the logic at this moment and carry out its actions.

        An error inside the logic stops the arm and fails the run under way.
        """
        now = self._now()
        try:
            actions = verb(now)
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            self.get_logger().error(traceback.format_exc())
            actions = self.logic.abort(f'internal executor error: {error!r}', now)
        self._perform(actions)

    def _report(self, message: str, level: str = 'OK', log: bool = False) -> None:
        self.logic.report(message, self._now(), level, log)
        self._perform(self.logic.flush())

    def _perform(self, actions: list[Action]) -> None:
        """Carry out the logic's actions, in order: publish commands, report statuses."""
        for action in actions:
            if isinstance(action, Command):
                self.command_publisher.publish(create_joint_trajectory(
                    self.names, action.path[1:], action.times[1:],
                    Time(nanoseconds=action.stamp_ns).to_msg(),
                    velocities=None if action.velocities is None else action.velocities[1:],
                    accelerations=None if action.accelerations is None else
                    action.accelerations[1:]))
            elif isinstance(action, Stop):
                self.command_publisher.publish(JointTrajectory(joint_names=self.names))
            elif isinstance(action, Status):
                self.diagnostics.report('execution', action.level, action.message,
                                        status_values(action), log=action.log)
            elif isinstance(action, Rejected):
                self.diagnostics.rejected('input', action.message,
                                          {'joint': action.joint} if action.joint else None)


def held_plan(latched: LatchedPlan, robot: Robot) -> HeldPlan:
    """Return the plan the logic holds: the robot bound to the plan's task kind, its goal.

    The goal is the plan status's, else (a task point of another size) the nominal
    path's end.
    """
    info = latched.info
    try:
        robot = bind_task_kind(robot, info.task_kind)
    except InputError:
        pass  # the scene's robot
    end = robot.forward_kinematics(latched.trajectory[-1])
    goal = info.goal if len(info.goal) == len(end) else end
    return HeldPlan(latched.key, latched.theta_s, latched.surface, robot, goal,
                    info.tolerated_joints, info.robot, info.motion_limits)


def status_values(status: Status) -> dict[str, object]:
    """Return the values of an execution status (README: the executor's status)."""
    values: dict[str, object] = {'state': status.state.value, 'plan': status.plan}
    ex = status.execution
    if ex is not None:
        values.update(execution=ex.number, execution_plan=ex.plan.key, progress=ex.progress,
                      approach=ex.approach)
        if ex.locked_joint is not None:
            values['locked_joint'] = status.names[ex.locked_joint]
        if ex.lock_progress is not None:
            values['lock_progress'] = ex.lock_progress
        if ex.lock_configuration is not None:
            values.update(lock_configuration=format_vector(ex.lock_configuration),
                          recovery_length_rad=ex.recovery_length)
        if ex.braking_deviation is not None:
            values['braking_deviation_rad'] = ex.braking_deviation
        if ex.lock_phase is not None:
            values['lock_phase'] = ex.lock_phase.value
        if ex.finished is not None:
            values['duration_s'] = ex.finished - ex.started
            if ex.lock_received is not None and status.state == State.DONE:
                values['recovery_time_s'] = ex.finished - ex.lock_received  # to the goal
        if ex.goal_error is not None:
            values.update(goal_error_m=ex.goal_error,
                          goal_orientation_error_rad=ex.goal_orientation_error)
        if ex.reason:
            values['reason'] = ex.reason
    if status.locked_joints:
        values['locked_joints'] = join_names(status.locked_joints)
    if status.tolerated_joints is not None:
        values['tolerated_joints'] = join_names(status.tolerated_joints)  # of the run's plan
    return values


def main(args=None) -> int:
    """Run the executor node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(ExecutorNode, EXECUTOR_NODE, args)

