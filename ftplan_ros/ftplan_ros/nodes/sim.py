"""The sim node: a kinematic arm for drills and demos.

    ros2 run ftplan_ros sim --ros-args -p scene_file:=fig3a.yaml -p rate:=100.0

It follows JointTrajectory commands on /ftplan/joint_command like a position-controlled
arm (a command with an angle beyond a joint's limits, or absurdly far round, is refused:
inputs.py): from where it is through the points at their times (linear in joint space),
slowed down segment by segment when a command asks for more than `max_joint_speed`;
an empty trajectory stops it. A stamped command starts at its stamp.

A failure event on /ftplan/locked_joint locks that joint where it is (or at the angle
given, which must lie within `lock_angle_tolerance` of where it is: a joint cannot jump,
so an event farther off is refused and reported) for good, and the simulated controller
brakes the other joints too (the paper assumes the failure is detected and the arm
stops), until a new command arrives; so the arm stays exactly on the commanded path.
Later commands move only the free joints. An event stamped ahead of where the arm is on
its command (a drill's scheduled failure, injector.py) waits for that moment of the
command (its stamp plus time from start; a command that came late started late, and
its moments with it) and locks the joint exactly where the command puts the arm then,
between two ticks too; at the end of the command at the latest.

The sim keeps its own clock: each tick advances it by 1/`rate`, so an overloaded machine
slows the arm down instead of making it jump past events. It publishes /joint_states
every tick, checks every motion against the scene and the
obstacle topic (sampled at most `collision_check_step` apart) and reports collisions,
the minimum clearance and arrival at the goal on /diagnostics ('ftplan_sim: arm').
Obstacle updates are applied one by one, in order; lost ones are reported as
'ftplan_sim: obstacles' (ERROR, obstacle_topic.py): until a full set arrives, the
collision checks may miss an obstacle.
`~/reset` (std_srvs/Trigger) puts the arm back at its initial configuration, unlocks
every joint and clears the counters, for repeated drills.

Arrival is judged with the core's task errors: the tool within `goal_tolerance` [m] of
the goal's position and, for axis and pose tasks, within `orientation_tolerance` [rad]
of its orientation; the goal is the scene task's, taken as a task of kind `task_kind`
('' = the scene's; set it like the planner's). The clearance check screens every sample
cheaply and measures exactly only where the screen sees a contact, so a collision is
exact; `min_clearance_m` is measured exactly at the samples the screen found closest
since the last stop. A scene file without a robot takes it from /robot_description
(scene_source.py); until then the sim publishes nothing.
"""

from __future__ import annotations

import heapq
import time
import traceback
from dataclasses import replace

import numpy as np
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from ftplan_msgs_py import (
    LockedJoint,
    create_joint_state,
    read_joint_trajectory,
    time_to_nanoseconds,
)
from ftplan_ros.core import CollisionChecker, InputError, Robot, Scene, Task, task_errors
from ftplan_ros.core.model.angles import configuration_difference, wrap_configuration
from ftplan_ros.core.model.paths import densify
from ftplan_ros.core.model.scene import DEFAULT_GOAL_TOLERANCE, DEFAULT_ORIENTATION_TOLERANCE
from ftplan_ros.core.model.task_space import POINT_SIZE, unit_vector
from ftplan_ros.core.paper.manifolds import project_many, trace_self_motion_manifolds
from ftplan_ros.execution.locks import DEFAULT_LOCK_ANGLE_TOLERANCE, lock_angle_problem

from .inputs import angle_problem
from .lock_events import read_lock_event
from .obstacle_topic import ObstacleTopic
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

_LOCK_SNAP_TOLERANCE = 1e-9  # [rad]
IK_SEEDS = 64  # random seeds of the inverse kinematics for a default start (r >= 2)
CLOSEST_SAMPLES = 8  # samples measured exactly for min_clearance_m at each stop


def default_initial_configuration(scene: Scene, rng: np.random.Generator | None = None,
                                  ) -> np.ndarray:
    """Return the clearest configuration (n,) [rad] found with the tool at the task start.

    With one degree of redundancy the candidates are the points of the traced start
    manifold M_s; with more, Newton solutions from `IK_SEEDS` random seeds. Both stay
    within the joint limits, and periodic joints are wrapped. Without a task, or when
    nothing reaches the start, the zero configuration moved into the limits.
    """
    robot = scene.robot
    fallback = np.clip(np.zeros(robot.n_joints), robot.limits[:, 0], robot.limits[:, 1])
    redundancy = robot.n_joints - robot.task_dim
    if scene.task is None or redundancy < 1:
        return fallback
    rng = rng if rng is not None else np.random.default_rng(0)
    x_s = np.asarray(scene.task.start, dtype=float)
    if redundancy == 1:
        branches = trace_self_motion_manifolds(robot, x_s, rng)
        points = np.vstack([b.points for b in branches]) if branches else np.zeros((0, 1))
    else:
        seeds = rng.uniform(robot.limits[:, 0], robot.limits[:, 1],
                            size=(IK_SEEDS, robot.n_joints))
        solved, converged = project_many(robot, x_s, seeds)
        points = solved[converged]
    if not len(points):
        return fallback
    return wrap_configuration(_clearest(CollisionChecker(robot, scene.obstacles), points),
                              robot.periodic)


def _clearest(checker: CollisionChecker, points: np.ndarray) -> np.ndarray:
    """Return the clearest of the points (k, n): screened cheaply, the best measured exactly."""
    bounds = checker.min_clearance(points, refine=False)
    best = np.argsort(-bounds)[:CLOSEST_SAMPLES]
    exact = checker.min_clearance(points[best])
    return points[best[int(np.argmax(exact))]].copy()


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


class Motion:
    """A timed joint path (k, n) [rad], times (k,) [s] from `start`, sampled linearly.

    Times are on the sim's clock [s]. `commanded` (k,) [s] are the times the command asked
    for (`times` may be slower: the speed limit), from its stamp `stamp_ns` [ns, ROS time],
    which the sim's `start` stands for.
    """

    def __init__(self, positions: np.ndarray, times: np.ndarray, start: float,
                 commanded: np.ndarray | None = None, stamp_ns: int = 0):
        self.positions = positions
        self.times = times
        self.start = start
        self.commanded = times if commanded is None else commanded
        self.stamp_ns = stamp_ns

    def time_of(self, stamp_ns: int) -> float:
        """Return the sim time [s] at which the arm is where the command puts it at `stamp_ns`.

        `stamp_ns` is ROS time [ns] on the command's timeline (its stamp + time from
        start); before the start: the start; after the end: the end.
        """
        commanded = (stamp_ns - self.stamp_ns) * 1e-9
        return self.start + float(np.interp(commanded, self.commanded, self.times))

    def sample(self, now: float) -> tuple[np.ndarray, bool]:
        """Return the configuration at sim time `now` and whether the motion is over."""
        t = now - self.start
        if t <= 0.0:
            return self.positions[0].copy(), False
        if t >= self.times[-1]:
            return self.positions[-1].copy(), True
        i = int(np.searchsorted(self.times, t, side='right')) - 1
        s = (t - self.times[i]) / (self.times[i + 1] - self.times[i])
        a, b = self.positions[i], self.positions[i + 1]
        return a + s * (b - a), False

    def swept(self, before: float, now: float) -> tuple[np.ndarray, bool]:
        """Return the path (k, n) [rad] followed from sim time `before` to `now`, and if it ended.

        The path holds the ends and every waypoint passed between them: the straight line
        between the ends alone would cut the corners the motion turns.
        """
        passed = self.positions[(self.times > before - self.start) &
                                (self.times < now - self.start)]
        end, finished = self.sample(now)
        return np.vstack([self.sample(before)[0], passed, end]), finished


class SimNode(Node):
    """A kinematic arm: follows commands, locks joints, reports collisions and arrival."""

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
            self.q = np.zeros(0)
            self.initial = np.zeros(0)
            self.motion: Motion | None = None
            self.locked: dict[int, float] = {}
            # Scheduled failures: (event, joint, stamp [ns]), each waiting for its moment.
            self.scheduled: list[tuple[LockedJoint, int, int]] = []
            self.resets = 0
            self.sim_time = 0.0  # [s] advanced by 1/rate each tick
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
        declare(self, 'max_joint_speed', 2.0,
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
        declare(self, 'brake_on_lock', True,
                'Stop every joint when one locks, until the next command.')
        declare(self, 'lock_angle_tolerance', DEFAULT_LOCK_ANGLE_TOLERANCE,
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
            'initial_configuration': self._check_configuration,
            'goal': self._check_goal,
        }
        check_startup_parameters(self, validators)
        add_validators(self, validators)

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
        self.q = self.initial.copy()
        self.motion = None
        self.locked = {}
        self.scheduled = []
        self._clear_counters()
        self.obstacle_topic.report_rebase(problems)
        self._check_clearance(self.q[None, :])
        self.publish_joint_state(np.zeros(len(self.names)))
        self.report('at the initial configuration', log=True)

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
        given = array_parameter(self, 'goal')
        task = self.scene.task
        goal = np.array(given, dtype=float) if given else \
            (np.asarray(task.goal, dtype=float) if task else None)
        tolerance = float(self.get_parameter('goal_tolerance').value) or \
            (task.goal_tolerance if task else DEFAULT_GOAL_TOLERANCE)
        angle = float(self.get_parameter('orientation_tolerance').value) or \
            (task.orientation_tolerance if task else DEFAULT_ORIENTATION_TOLERANCE)
        if goal is None:
            return None, None
        return goal, Task(tuple(goal), tuple(goal), tolerance, angle)

    @property
    def robot(self) -> Robot:
        """The simulated arm (bound to the kind of task arrival is judged by)."""
        return self.scene.robot

    # Inputs -------------------------------------------------------------------------

    def joint_command_callback(self, msg: JointTrajectory) -> None:
        """Follow a new command from where the arm is; an empty one stops the arm."""
        if self.scene is None:
            self.diagnostics.rejected('input', f'ignored joint command: {self.source.waiting}')
            return
        try:
            if not msg.points:
                self.motion = None
                return
            positions, times = read_joint_trajectory(msg, self.names)
            problem = angle_problem(self.robot, positions)
            if problem:
                raise ValueError(f'JointTrajectory: {problem}')
            start, stamp_ns = self._start_time(msg)
        except ValueError as error:
            self.diagnostics.rejected('input', f'ignored joint command: {error}')
            return
        positions = np.vstack([self.q[None, :], positions])
        for joint, value in self.locked.items():
            moved = float(np.max(np.abs(positions[:, joint] - value)))
            if moved > _LOCK_SNAP_TOLERANCE:
                self.diagnostics.rejected(
                    'input', f'the command moves locked joint {self.names[joint]} by up to '
                    f'{moved:.3f} rad; holding it at {value:.6f} rad')
            positions[:, joint] = value
        times = np.concatenate([[0.0], times])
        speed = float(self.get_parameter('max_joint_speed').value)
        needed = np.max(np.abs(np.diff(positions, axis=0)), axis=1) / speed
        given = np.diff(times)
        if np.any(needed > given * (1.0 + 1e-9)):
            factor = float(np.max(needed / np.maximum(given, 1e-12)))
            self.get_logger().info(f'command exceeds max_joint_speed {speed} rad/s: slowed '
                                   f'down up to {factor:.2f}x', throttle_duration_sec=5.0)
        steps = np.maximum(given, needed)
        keep = np.concatenate([[True], steps > 0.0])
        self.motion = Motion(positions[keep], np.concatenate([[0.0], np.cumsum(steps)])[keep],
                             start, times[keep], stamp_ns)

    def _start_time(self, msg: JointTrajectory) -> tuple[float, int]:
        """Return the sim time a command starts, and the ROS time [ns] that start stands for.

        A command starts now, or at its stamp when that lies ahead; an unstamped one is
        stamped now. A command that arrives after its stamp starts late, from its first
        point: its whole timeline (a lock scheduled on it too) shifts with it.
        """
        now_ns = self.get_clock().now().nanoseconds
        stamp_ns = time_to_nanoseconds(msg.header.stamp) or now_ns
        return self.sim_time + max(0.0, (stamp_ns - now_ns) * 1e-9), stamp_ns

    def locked_joint_callback(self, msg: JointState) -> None:
        """Lock a joint where it is (or at the angle given), or when its stamp comes; brake.

        An event stamped ahead of where the arm is on its command is a scheduled failure
        (a drill): it waits in `scheduled` until the command reaches that moment.
        """
        found = read_lock_event(msg, None if self.scene is None else self.names,
                                self.source.waiting,
                                lambda why, _: self.diagnostics.rejected('input', why))
        if found is None:
            return
        event, joint, stamp_ns = found
        if joint in self.locked or any(joint == j for _, j, _ in self.scheduled):
            return
        if stamp_ns and self.motion is not None and self.motion.time_of(stamp_ns) > self.sim_time:
            self.scheduled.append((event, joint, stamp_ns))
            self.get_logger().info(f'{event.name} locks in '
                                   f'{self.motion.time_of(stamp_ns) - self.sim_time:.3f} s')
            return
        self._lock(event, joint)

    def _lock(self, event: LockedJoint, joint: int) -> None:
        """Lock `joint` where it is (or at the event's angle) and brake the arm."""
        problem = lock_angle_problem(event.name, event.angle, float(self.q[joint]),
                                     bool(self.robot.periodic[joint]),
                                     float(self.get_parameter('lock_angle_tolerance').value))
        if problem:
            self.diagnostics.rejected('input', f'ignored locked-joint event: {problem}')
            return
        value = float(self.q[joint]) if event.angle is None else \
            float(self.q[joint]) + float(configuration_difference(
                event.angle, self.q[joint], self.robot.periodic[joint]))
        if abs(value - self.q[joint]) > _LOCK_SNAP_TOLERANCE:
            self.get_logger().warning(f'{event.name} locks at {value:.6f} rad, '
                                      f'{value - self.q[joint]:+.6f} rad from where it is')
            jumped = self.q.copy()
            jumped[joint] = value
            self._check_clearance(densify(np.stack([self.q, jumped]), float(
                self.get_parameter('collision_check_step').value)))
            self.q = jumped
        self.locked[joint] = value
        if self.get_parameter('brake_on_lock').value:
            self.motion = None
        self.get_logger().info(f'{event.name} locked at {value:.6f} rad')
        self.report(f'{event.name} locked at {value:.6f} rad', 'WARN')

    def reset_callback(self, request: Trigger.Request, response: Trigger.Response,
                       ) -> Trigger.Response:
        """Back to the initial configuration, every joint free, counters cleared."""
        if self.scene is None:
            response.success, response.message = False, self.source.waiting
            return response
        given = array_parameter(self, 'initial_configuration')
        if given:
            self.initial = np.array(given, dtype=float)
        self.q = self.initial.copy()
        self.motion = None
        self.locked = {}
        self.scheduled = []
        self.resets += 1
        self._clear_counters()
        self._check_clearance(self.q[None, :])
        self.publish_joint_state(np.zeros(len(self.names)))
        self.report('reset to the initial configuration', log=True)
        response.success = True
        response.message = f'reset {self.resets}: at {format_vector(self.q)} rad'
        return response

    # Simulation ---------------------------------------------------------------------

    def timer_callback(self) -> None:
        """Advance the arm, check its sweep for collisions, publish the joint state."""
        if self.scene is None:
            return
        dt = 1.0 / self.rate
        self.sim_time += dt
        previous = self.q
        try:
            until, due = self._due_locks(self.sim_time - dt, self.sim_time)
            swept = None
            if self.motion is not None:
                swept, finished = self.motion.swept(self.sim_time - dt, until)
                swept[0] = previous
                for joint, value in self.locked.items():
                    swept[:, joint] = value
                self.q = swept[-1].copy()
                if finished:
                    self.motion = None
            for event, joint in due:
                self._lock(event, joint)
            # From the path, not its end: a command may go out and back within a tick.
            moved = swept is not None and bool(np.any(swept != previous))
            if moved:
                self._check_clearance(densify(swept, float(self.get_parameter(
                    'collision_check_step').value)))
                self._reported_stop = False
                self.goal_reached = False
            self.publish_joint_state((self.q - previous) / dt)
            if self.motion is None and not self._reported_stop:
                self._reported_stop = True
                self._report_stop()
            elif time.monotonic() - self._last_report >= 1.0:
                self.report('moving' if self.motion is not None else 'stopped')
        except Exception as error:  # noqa: BLE001 - a callback must never raise
            self.get_logger().error(traceback.format_exc())
            self.diagnostics.report('arm', 'ERROR', f'internal sim error: {error!r}')

    def _due_locks(self, before: float, now: float) -> tuple[float, list[tuple[LockedJoint, int]]]:
        """Take the scheduled locks due by sim time `now` [s]; return when the first is due.

        The arm moves until that moment (within the tick from `before`) and locks there,
        exactly where its command puts it then. Without a command every lock is due.
        """
        moments = [self.motion.time_of(stamp_ns) if self.motion is not None else before
                   for _, _, stamp_ns in self.scheduled]
        due = [lock for lock, moment in zip(self.scheduled, moments, strict=True)
               if moment <= now]
        if not due:
            return now, []
        self.scheduled = [lock for lock in self.scheduled if lock not in due]
        first = max(before, min(moment for moment in moments if moment <= now))
        return first, [(event, joint) for event, joint, _ in due]

    def _check_clearance(self, samples: np.ndarray) -> None:
        """Check samples (k, n) [rad] of the motion; a collision is measured exactly."""
        clearance = self._obstacles.checker.min_clearance(samples, needed=0.0)
        worst = int(np.argmin(clearance))
        colliding = not clearance[worst] > 0.0  # a NaN clearance reads as a collision
        if colliding:
            self.min_clearance = min(self.min_clearance, float(clearance[worst]))
        for bound, q in zip(clearance.tolist(), samples, strict=True):
            self._samples += 1
            entry = (-bound, self._samples, q.copy())
            if len(self._closest) < CLOSEST_SAMPLES:
                heapq.heappush(self._closest, entry)
            elif -bound > self._closest[0][0]:
                heapq.heapreplace(self._closest, entry)
        if colliding and not self._in_collision:
            self.collisions += 1
            self._in_collision = True
            self.report(f'collision at {format_vector(samples[worst])} rad (clearance '
                        f'{clearance[worst]:.4f} m)', 'ERROR', log=True)
        elif not colliding:
            self._in_collision = False

    def _measure_closest(self) -> None:
        """Measure exactly the samples the screen found closest since the last time."""
        if not self._closest:
            return
        samples = np.array([q for _, _, q in self._closest])
        self._closest = []
        exact = self._obstacles.checker.min_clearance(samples)
        self.min_clearance = min(self.min_clearance, float(exact.min()))

    def _report_stop(self) -> None:
        self._measure_closest()
        goal, task = self.goal()
        if goal is None:
            self.report('stopped')
            return
        position, angle = (float(v) for v in task_errors(self.robot, goal, self.q))
        self.goal_error, self.goal_orientation_error = position, angle
        self.goal_reached = bool(task.reached(np.array([position, angle])))
        error = f'{position:.2e} m' + (f', {angle:.2e} rad' if self.robot.task_kind in
                                       ('axis', 'pose') else '')
        if self.goal_reached:
            self.report(f'goal reached (error {error})', log=True)
        else:
            self.report(f'stopped {error} from the goal')

    def _clear_counters(self) -> None:
        self.collisions = 0
        self.min_clearance = float('inf')
        self.goal_reached = False
        self.goal_error = float('nan')
        self.goal_orientation_error = float('nan')
        # The samples with the smallest screened clearance since the last stop, as a heap
        # of (-bound, sample number, configuration).
        self._closest: list[tuple[float, int, np.ndarray]] = []
        self._samples = 0
        self._in_collision = False
        self._reported_stop = True
        self._last_report = 0.0

    def publish_joint_state(self, velocity: np.ndarray) -> None:
        """Publish the configuration (lifted, as commanded) and joint velocities [rad/s]."""
        self.joint_state_publisher.publish(create_joint_state(
            self.names, self.q, velocity, stamp=self.get_clock().now().to_msg()))

    def report(self, message: str, level: str = 'OK', log: bool = False) -> None:
        """Publish the 'arm' status: motion, locks, collisions, clearance, goal."""
        self._last_report = time.monotonic()
        if level == 'OK' and self.collisions:
            level = 'ERROR'
        values = {
            'state': 'moving' if self.motion is not None else 'stopped',
            'resets': self.resets,
            'configuration': format_vector(self.q),
            'locked': ','.join(self.names[j] for j in sorted(self.locked)),
            'collisions': self.collisions,
            'min_clearance_m': self.min_clearance,
            'goal_reached': self.goal_reached,
            'goal_error_m': self.goal_error,
            'goal_orientation_error_rad': self.goal_orientation_error,
        }
        self.diagnostics.report('arm', level, message, values, log=log)


def main(args=None) -> int:
    """Run the sim node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(SimNode, SIM_NODE, args)
