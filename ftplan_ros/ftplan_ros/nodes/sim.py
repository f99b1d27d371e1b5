"""The sim node: a simulated arm for drills and demos (the arm itself: simulation/).

    ros2 run ftplan_ros sim --ros-args -p scene_file:=fig3a.yaml -p rate:=100.0

An adapter: the arm is a plain class (simulation/kinematic.py, behind the interface of
simulation/arm.py), and so is the watch over its clearance (simulation/clearance.py).
This node feeds them the messages, steps the arm by its own clock and publishes.

The arm follows JointTrajectory commands on /ftplan/joint_command like a
position-controlled arm (a command with an angle beyond a joint's limits, or absurdly far
round, is refused: inputs.py), slowed down where a command asks for more than
`max_joint_speed`; an empty trajectory stops it; a stamped command starts at its stamp. A
failure event on /ftplan/locked_joint locks that joint where it is (or at the angle given,
which must lie within `lock_angle_tolerance` of where it is: a joint cannot jump, so an
event farther off is refused and reported) for good, and the free joints brake
(`brake_on_lock`) within the robot's acceleration limits to a stop, until a new command
arrives. An event stamped ahead of where the arm is
on its command (a drill's scheduled failure, injector.py) locks the joint exactly where
the command puts the arm at that moment.

The sim keeps its own clock: each tick advances it by 1/`rate`, so an overloaded machine
slows the arm down instead of making it jump past events. It publishes /joint_states
every tick, checks every motion against the scene and the obstacle topic (sampled at
most `collision_check_step` apart) and reports collisions, the minimum clearance and
arrival at the goal on /diagnostics ('ftplan_sim: arm'). Obstacle updates are applied
one by one, in order; lost ones are reported as 'ftplan_sim: obstacles' (ERROR,
obstacle_topic.py): until a full set arrives, the collision checks may miss an obstacle.
With `sim_backend: mujoco` the arm is simulated by MuJoCo (simulation/mujoco_arm.py):
position servos with the gains and torque limits of `physics_file` track the commands,
gravity is on, a lock is a brake, /joint_states carries MuJoCo's positions, velocities
and torques, and each contact MuJoCo's own collision detection finds is reported on
/diagnostics with the two bodies and its depth (counted as `contacts`); the arm's
status adds its largest tracking error, how far a joint or the tool stood from its
commanded place then, and its time to standstill after a lock.
`~/reset` (std_srvs/Trigger) puts the arm back at its initial configuration, unlocks
every joint and clears the counters, for repeated drills.

Arrival is judged with the core's task errors: the tool within `goal_tolerance` [m] of
the goal's position and, for axis and pose tasks, within `orientation_tolerance` [rad]
of its orientation; the goal is the scene task's, taken as a task of kind `task_kind`
('' = the scene's; set it like the planner's). A collision is exact; `min_clearance_m`
is measured exactly at the samples found closest since the last stop (clearance.py), and
`braking_clearance_m` likewise from a lock to the stop after it. A
scene file without a robot takes it from /robot_description (scene_source.py); until
then the sim publishes nothing.
"""

from __future__ import annotations

import time
import traceback
from dataclasses import replace

import numpy as np
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from ftplan_msgs_py import create_joint_state, read_joint_trajectory, time_to_nanoseconds
from ftplan_ros.core import InputError, Robot, Scene, Task, task_errors
from ftplan_ros.core.io.files import read_text
from ftplan_ros.core.model.paths import densify
from ftplan_ros.core.model.scene import DEFAULT_GOAL_TOLERANCE, DEFAULT_ORIENTATION_TOLERANCE
from ftplan_ros.core.model.task_space import POINT_SIZE, unit_vector
from ftplan_ros.simulation.arm import Arm, ArmOptions, Locked, LockOutcome, Refused, Scheduled
from ftplan_ros.simulation.clearance import ClearanceMonitor
from ftplan_ros.simulation.initial import default_initial_configuration
from ftplan_ros.simulation.kinematic import KinematicArm
from ftplan_ros.simulation.mujoco_arm import MujocoArm
from ftplan_ros.simulation.mujoco_model import (
    PhysicsOptions,
    find_physics_file,
    read_physics_options,
)

from .inputs import angle_problem
from .lock_events import read_lock_event
from .obstacle_topic import ObstacleTopic
from .params import (
    add_validators,
    array_parameter,
    check_startup_parameters,
    config_path,
    declare,
    declare_array,
    destroyed_if_start_fails,
    non_negative,
    options_from_parameters,
    positive,
)
from .qos import EVENT_QOS_DEPTH, SERVICE_QOS
from .reporting import Diagnostics, format_vector
from .scene_source import SceneSource
from .spinning import run_node
from .tasks import bind_task_kind, check_task_kind, convert_task_point
from .topics import (
    JOINT_COMMAND,
    JOINT_STATES,
    LOCKED_JOINT,
    RESET_SERVICE,
    ROBOT_DESCRIPTION,
    SIM_NODE,
)

_DEFAULTS = ArmOptions()
SIM_BACKENDS = ('kinematic', 'mujoco')


def task_scene(scene: Scene, kind: str) -> Scene:
    """Return the scene with its robot and task as a task of `kind` ('' = as it is).

    A task whose start or goal does not give a point of that kind is dropped.
    """
    robot = bind_task_kind(scene.robot, kind)
    task = scene.task
    if task is not None:
        start, goal = convert_task_point(task.start, robot.task_kind), \
            convert_task_point(task.goal, robot.task_kind)
        task = None if start is None or goal is None else Task(
            tuple(start), tuple(goal), task.goal_tolerance, task.orientation_tolerance)
    return replace(scene, robot=robot, task=task)


def configuration_problem(value, scene: Scene | None) -> str | None:
    """Say what is wrong with an `initial_configuration` for the scene's arm (None: fine)."""
    if not np.all(np.isfinite(value)):
        return f'needs finite angles [rad], got {list(value)}'
    if scene is None or not len(value) or len(value) == scene.robot.n_joints:
        return None
    return f'needs {scene.robot.n_joints} finite angles [rad], got {list(value)}'


def goal_problem(value, scene: Scene | None) -> str | None:
    """Say what is wrong with a `goal` task point for the scene's task kind (None: fine)."""
    if not np.all(np.isfinite(value)):
        return f'needs finite coordinates, got {list(value)}'
    if scene is None or not len(value):
        return None
    kind = scene.robot.task_kind
    if len(value) != POINT_SIZE[kind]:
        return f'needs {POINT_SIZE[kind]} numbers for a {kind} goal (or none), got {list(value)}'
    if kind in ('axis', 'pose'):
        try:
            unit_vector(value[3:], 'its axis' if kind == 'axis' else 'its quaternion')
        except ValueError as error:
            return str(error)
    return None


def arrival_goal(scene: Scene, given: list[float], tolerance: float, angle: float,
                 ) -> tuple[np.ndarray | None, Task | None]:
    """Return the goal task point arrival is judged by (None if unknown), and its task.

    `given` (a task point, [] for none) overrides the scene task's goal, and `tolerance`
    [m] and `angle` [rad] (0: the task's) its tolerances.
    """
    task = scene.task
    goal = np.array(given, dtype=float) if given else \
        (np.asarray(task.goal, dtype=float) if task else None)
    if goal is None:
        return None, None
    tolerance = tolerance or (task.goal_tolerance if task else DEFAULT_GOAL_TOLERANCE)
    angle = angle or (task.orientation_tolerance if task else DEFAULT_ORIENTATION_TOLERANCE)
    return goal, Task(tuple(goal), tuple(goal), tolerance, angle)


class SimNode(Node):
    """A simulated arm: follows commands, locks joints, reports collisions and arrival."""

    def __init__(self, **kwargs):
        with destroyed_if_start_fails(self):
            super().__init__(SIM_NODE, **kwargs)
            self.diagnostics = Diagnostics(self)
            self.source = SceneSource(self, self.diagnostics, self._scene_changed)
            self.rate = declare(self, 'rate', 100.0,
                                'Rate [Hz] of the simulation steps and of /joint_states.',
                                read_only=True)
            self.scene: Scene | None = None   # bound to task_kind (task_scene)
            self._declare_parameters()
            self.names: list[str] = []
            self.obstacle_topic = ObstacleTopic(self, self.diagnostics)
            self._obstacles = self.obstacle_topic.obstacles
            self.monitor = ClearanceMonitor(self._obstacles)
            self.arm: Arm | None = None  # of `sim_backend` (simulation/)
            self.initial = np.zeros(0)
            self.resets = 0
            self._clear_counters()
            self.joint_state_publisher = self.create_publisher(
                JointState, JOINT_STATES, EVENT_QOS_DEPTH)
            if self.source.scene is not None:
                self._use_scene(task_scene(self.source.scene,
                                           self.get_parameter('task_kind').value))
            self.command_subscription = self.create_subscription(
                JointTrajectory, JOINT_COMMAND, self.joint_command_callback, EVENT_QOS_DEPTH)
            self.locked_joint_subscription = self.create_subscription(
                JointState, LOCKED_JOINT, self.locked_joint_callback, EVENT_QOS_DEPTH)
            self.reset_service = self.create_service(Trigger, RESET_SERVICE,
                                                     self.reset_callback, qos_profile=SERVICE_QOS)
            self.timer = self.create_timer(1.0 / self.rate, self.timer_callback)

    def _declare_parameters(self) -> None:
        declare(self, 'max_joint_speed', _DEFAULTS.max_joint_speed,
                'Velocity limit [rad/s] of every joint; faster commands are slowed down.')
        declare(self, 'collision_check_step', 0.01,
                'Largest joint step [rad] between two collision checks along the motion.')
        declare(self, 'goal_tolerance', 0.0,
                'Distance [m] from the goal that counts as reached (0: the scene task\'s).')
        declare(self, 'orientation_tolerance', 0.0,
                'Orientation error [rad] at the goal that counts as reached, for axis and '
                'pose tasks (0: the scene task\'s).')
        declare(self, 'task_kind', '',
                'How the goal is judged: position, axis or pose ("" = the scene\'s task '
                'kind); set it like the planner\'s.', read_only=True)
        declare(self, 'sim_backend', 'kinematic',
                'How the arm moves: kinematic (exactly as commanded) or mujoco (physics: '
                'position servos, gravity, brakes, MuJoCo\'s contacts).', read_only=True)
        declare(self, 'physics_file', '',
                'The mujoco backend\'s gains and torque limits (YAML, see '
                'config/robots/panda_mujoco.yaml; "": the installed *_mujoco.yaml naming '
                'the robot\'s joints, else the defaults).', read_only=True)
        declare(self, 'brake_on_lock', _DEFAULTS.brake_on_lock,
                'When a joint locks, brake the others to a stop at the robot\'s acceleration '
                'limits (the executor certifies that braking), until the next command.')
        declare(self, 'lock_angle_tolerance', _DEFAULTS.lock_angle_tolerance,
                'Farthest a lock event\'s angle may be from where the joint is [rad]; events '
                'beyond it are refused (a joint locks where it stands).')
        declare_array(self, 'initial_configuration', Parameter.Type.DOUBLE_ARRAY,
                      'Configuration [rad] at start and after ~/reset (default: the clearest '
                      'configuration found at the task start).')
        declare_array(self, 'goal', Parameter.Type.DOUBLE_ARRAY,
                      'Goal task point (default: the scene task goal): [x, y] planar, '
                      '[x, y, z] position, [x, y, z, ax, ay, az] axis, [x, y, z, qx, qy, qz, '
                      'qw] pose; [m].')
        validators = {
            'rate': positive, 'max_joint_speed': positive, 'collision_check_step': positive,
            'lock_angle_tolerance': positive,
            'goal_tolerance': non_negative, 'orientation_tolerance': non_negative,
            'task_kind': check_task_kind,
            'sim_backend': lambda value: None if value in SIM_BACKENDS else
            f'must be one of {", ".join(SIM_BACKENDS)}, got {value!r}',
            'initial_configuration': self._check_configuration,
            'goal': self._check_goal,
        }
        check_startup_parameters(self, validators)
        add_validators(self, validators)
        self.add_post_set_parameters_callback(self._parameters_set)

    def _arm_options(self) -> ArmOptions:
        """Return the arm's options from the parameters of the same names."""
        return options_from_parameters(self, ArmOptions)

    def _parameters_set(self, parameters: list[Parameter]) -> None:
        if self.arm is not None:
            self.arm.options = self._arm_options()

    # The robot ----------------------------------------------------------------------

    def _use_scene(self, scene: Scene) -> None:
        """Simulate `scene`'s robot from now on, from its initial configuration."""
        for name, check in (('initial_configuration', configuration_problem),
                            ('goal', goal_problem)):
            problem = check(array_parameter(self, name), scene)
            if problem:
                raise InputError(name, problem)
        problems = self._obstacles.rebase(scene)
        self.scene = scene
        self.names = list(scene.robot.joint_names)
        given = array_parameter(self, 'initial_configuration')
        self.initial = np.array(given, dtype=float) if given else \
            default_initial_configuration(scene)
        self.arm = self._new_arm(scene.robot)
        self._clear_counters()
        self.obstacle_topic.report_rebase(problems)
        self._check_clearance(self.arm.q[None, :])
        self.publish_joint_state(np.zeros(len(self.names)))
        self.report('at the initial configuration', log=True)

    def _new_arm(self, robot: Robot) -> Arm:
        """Return an arm of `sim_backend` at the initial configuration."""
        if self.get_parameter('sim_backend').value == 'kinematic':
            return KinematicArm(robot, self.initial, self._arm_options())
        return MujocoArm(robot, self.initial, self._arm_options(),
                         self._physics_options(robot), self._obstacles)

    def _physics_options(self, robot: Robot) -> PhysicsOptions:
        """Read `physics_file` (or the installed one naming the robot's joints, if any)."""
        given = self.get_parameter('physics_file').value
        path = given or find_physics_file(config_path('robots', 'panda.yaml').parent,
                                                robot.joint_names)
        if not path:
            self.get_logger().warning('no physics file names the robot\'s joints: '
                                      'the default gains (simulation/mujoco_model.py)')
            return PhysicsOptions()
        self.get_logger().info(f'physics from {path}')
        return read_physics_options(read_text(path, 'physics_file'), 'physics_file')

    def _scene_changed(self, scene: Scene) -> None:
        """Take a robot from /robot_description: the arm starts afresh."""
        try:
            self._use_scene(task_scene(scene, self.get_parameter('task_kind').value))
        except InputError as error:
            self.diagnostics.report('robot_description', 'ERROR', f'cannot simulate the robot '
                                    f'from {ROBOT_DESCRIPTION}: {error}', log=True)

    # Parameters ---------------------------------------------------------------------

    def _check_configuration(self, value) -> str | None:
        return configuration_problem(value, self.scene)

    def _check_goal(self, value) -> str | None:
        return goal_problem(value, self.scene)

    def goal(self) -> tuple[np.ndarray | None, Task | None]:
        """Return the goal task point (None if unknown) and the task whose tolerances apply."""
        return arrival_goal(self.scene, array_parameter(self, 'goal'),
                            float(self.get_parameter('goal_tolerance').value),
                            float(self.get_parameter('orientation_tolerance').value))

    @property
    def robot(self) -> Robot:
        """The simulated arm (bound to the kind of task arrival is judged by)."""
        return self.scene.robot

    # Inputs -------------------------------------------------------------------------

    def joint_command_callback(self, msg: JointTrajectory) -> None:
        """Follow a new command from where the arm is; an empty one stops the arm.

        A command starts now, or at its stamp when that lies ahead; an unstamped one is
        stamped now. A command that arrives after its stamp starts late, from its first
        point: its whole timeline (a lock scheduled on it too) shifts with it.
        """
        if self.scene is None:
            self.diagnostics.rejected('input', f'ignored joint command: {self.source.waiting}')
            return
        try:
            if not msg.points:
                self.arm.stop()
                return
            positions, times = read_joint_trajectory(msg, self.names)
            problem = angle_problem(self.robot, positions)
            if problem:
                raise ValueError(f'JointTrajectory: {problem}')
            now_ns = self.get_clock().now().nanoseconds
            stamp_ns = time_to_nanoseconds(msg.header.stamp) or now_ns
        except ValueError as error:
            self.diagnostics.rejected('input', f'ignored joint command: {error}')
            return
        following = self.arm.follow(positions, times, stamp_ns, now_ns)
        for held in following.held:
            self.diagnostics.rejected(
                'input', f'the command moves locked joint {self.names[held.joint]} by up to '
                f'{held.moved:.3f} rad; holding it at {held.angle:.6f} rad')
        if following.slowdown > 1.0:
            self.get_logger().info(f'command exceeds max_joint_speed '
                                   f'{self.arm.options.max_joint_speed} rad/s: slowed down up '
                                   f'to {following.slowdown:.2f}x', throttle_duration_sec=5.0)

    def locked_joint_callback(self, msg: JointState) -> None:
        """Lock a joint where it is (or at the angle given), or when its stamp comes; brake."""
        found = read_lock_event(msg, None if self.scene is None else self.names,
                                self.source.waiting,
                                lambda why, _: self.diagnostics.rejected('input', why))
        if found is not None:
            event, joint, stamp_ns = found
            self._lock_taken(self.arm.lock(joint, event.angle, stamp_ns,
                                           self.get_clock().now().nanoseconds))

    def _lock_taken(self, outcome: LockOutcome | None) -> None:
        """Log and report what came of a lock event; check the sweep of a lock at an angle."""
        if outcome is None:
            return  # locked or scheduled already
        name = self.names[outcome.joint]
        if isinstance(outcome, Scheduled):
            self.get_logger().info(f'{name} locks in {outcome.seconds:.3f} s')
        elif isinstance(outcome, Refused):
            self.diagnostics.rejected('input', f'ignored locked-joint event: {outcome.problem}')
        elif isinstance(outcome, Locked):
            self.monitor.begin_braking()
            if outcome.jump is not None:
                gap = float(np.diff(outcome.jump[:, outcome.joint])[0])
                self.get_logger().warning(f'{name} locks at {outcome.angle:.6f} rad, '
                                          f'{gap:+.6f} rad from where it is')
                self._check_clearance(densify(outcome.jump, self._check_step()))
            self.get_logger().info(f'{name} locked at {outcome.angle:.6f} rad')
            self.report(f'{name} locked at {outcome.angle:.6f} rad', 'WARN')

    def reset_callback(self, request: Trigger.Request, response: Trigger.Response,
                       ) -> Trigger.Response:
        """Back to the initial configuration, every joint free, counters cleared."""
        if self.scene is None:
            response.success, response.message = False, self.source.waiting
            return response
        given = array_parameter(self, 'initial_configuration')
        if given:
            self.initial = np.array(given, dtype=float)
        self.arm.reset(self.initial)
        self.resets += 1
        self._clear_counters()
        self._check_clearance(self.arm.q[None, :])
        self.publish_joint_state(np.zeros(len(self.names)))
        self.report('reset to the initial configuration', log=True)
        response.success = True
        response.message = f'reset {self.resets}: at {format_vector(self.arm.q)} rad'
        return response

    # Simulation ---------------------------------------------------------------------

    def timer_callback(self) -> None:
        """Step the arm, check its sweep for collisions, publish the joint state."""
        if self.scene is None:
            return
        dt = 1.0 / self.rate
        previous = self.arm.q
        try:
            step = self.arm.step(dt)
            for outcome in step.locks:
                self._lock_taken(outcome)
            for contact in step.contacts:
                self.contacts += 1
                self.report(f'contact between {contact.first} and {contact.second}, '
                            f'{contact.depth:.4f} m deep (MuJoCo)', 'ERROR', log=True)
            # From the path, not its end: a command may go out and back within a tick.
            if step.swept is not None and bool(np.any(step.swept != previous)):
                self._check_clearance(densify(step.swept, self._check_step()))
                self._reported_stop = False
                self.goal_reached = False
            self.publish_joint_state((self.arm.q - previous) / dt if step.velocity is None
                                     else step.velocity, step.effort)
            if not self.arm.moving and not self._reported_stop:
                self._reported_stop = True
                self._report_stop()
            elif time.monotonic() - self._last_report >= 1.0:
                if self.arm.moving:
                    self.report('moving')
                else:  # a standing arm may still creep (MuJoCo): judge it again
                    self._report_stop(measure=False)
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            self.get_logger().error(traceback.format_exc())
            self.diagnostics.report('arm', 'ERROR', f'internal sim error: {error!r}')

    def _check_step(self) -> float:
        return float(self.get_parameter('collision_check_step').value)

    def _check_clearance(self, samples: np.ndarray) -> None:
        """Check samples (k, n) [rad] of the motion; report a collision that begins there."""
        collision = self.monitor.check(samples)
        if collision is not None:
            self.report(f'collision at {format_vector(collision.configuration)} rad (clearance '
                        f'{collision.clearance:.4f} m)', 'ERROR', log=True)

    def _report_stop(self, measure: bool = True) -> None:
        """Report the arm standing, judging the goal; `measure` the exact clearance there too.

        The exact measure costs up to 0.6 s on non-convex meshes: once per stop.
        """
        if measure:
            self.monitor.measure_closest()
        goal, task = self.goal()
        if goal is None:
            self.report('stopped')
            return
        position, angle = (float(v) for v in task_errors(self.robot, goal, self.arm.q))
        self.goal_error, self.goal_orientation_error = position, angle
        already = self.goal_reached
        self.goal_reached = bool(task.reached(np.array([position, angle])))
        error = f'{position:.2e} m' + (f', {angle:.2e} rad' if self.robot.task_kind in
                                       ('axis', 'pose') else '')
        if self.goal_reached:
            self.report(f'goal reached (error {error})', log=not already)
        else:
            self.report(f'stopped {error} from the goal')

    def _clear_counters(self) -> None:
        self.monitor.clear()
        self.contacts = 0
        self.goal_reached = False
        self.goal_error = float('nan')
        self.goal_orientation_error = float('nan')
        self._reported_stop = True
        self._last_report = 0.0

    def publish_joint_state(self, velocity: np.ndarray, effort: np.ndarray | None = None,
                            ) -> None:
        """Publish the configuration (lifted, as commanded), velocities [rad/s], torques [Nm]."""
        msg = create_joint_state(self.names, self.arm.q, velocity,
                                 stamp=self.get_clock().now().to_msg())
        if effort is not None:
            msg.effort = [float(value) for value in effort]
        self.joint_state_publisher.publish(msg)

    def report(self, message: str, level: str = 'OK', log: bool = False) -> None:
        """Publish the 'arm' status: motion, locks, collisions, clearance, goal."""
        self._last_report = time.monotonic()
        if level == 'OK' and (self.monitor.collisions or self.contacts):
            level = 'ERROR'
        values = {
            'state': 'moving' if self.arm.moving else 'stopped',
            'resets': self.resets,
            'configuration': format_vector(self.arm.q),
            'locked': ','.join(self.names[j] for j in sorted(self.arm.locked)),
            'collisions': self.monitor.collisions,
            'min_clearance_m': self.monitor.min_clearance,
            'braking_clearance_m': self.monitor.braking_clearance,
            'goal_reached': self.goal_reached,
            'goal_error_m': self.goal_error,
            'goal_orientation_error_rad': self.goal_orientation_error,
        }
        if isinstance(self.arm, MujocoArm):
            values.update(contacts=self.contacts, tracking_error_rad=self.arm.tracking_error,
                          tracking_displacement_m=self.arm.tracking_displacement,
                          standstill_s=self.arm.standstill_time)
        self.diagnostics.report('arm', level, message, values, log=log)


def main(args=None) -> int:
    """Run the sim node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(SimNode, SIM_NODE, args)
