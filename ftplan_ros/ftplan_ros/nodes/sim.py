"""The sim node: a kinematic arm for drills and demos.

    ros2 run ftplan_ros sim --ros-args -p scene_file:=fig3a.yaml -p rate:=100.0

It follows JointTrajectory commands on /ftplan/joint_command like a position-controlled
arm: from where it is through the points at their times (linear in joint space),
slowed down segment by segment when a command asks for more than `max_joint_speed`;
an empty trajectory stops it. A stamped command starts at its stamp.

A failure event on /ftplan/locked_joint locks that joint where it is (or at the angle
given) for good, and the simulated controller brakes the other joints too (the paper
assumes the failure is detected and the arm stops), until a new command arrives; so the
arm stays exactly on the commanded path. Later commands move only the free joints.

The sim keeps its own clock: each tick advances it by 1/`rate`, so an overloaded machine
slows the arm down instead of making it jump past events. It publishes /joint_states
every tick, checks every motion against the scene and the
obstacle topic (sampled at most `collision_check_step` apart) and reports collisions,
the minimum clearance and arrival at the goal on /diagnostics ('ftplan_sim: arm').
`~/reset` (std_srvs/Trigger) puts the arm back at its initial configuration, unlocks
every joint and clears the counters, for repeated drills.
"""

from __future__ import annotations

import time
import traceback

import numpy as np
from rclpy.node import Node
from rclpy.parameter import Parameter
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import MarkerArray

from ftplan_msgs_py import (
    create_joint_state,
    read_joint_trajectory,
    read_locked_joint,
    time_to_seconds,
)
from ftplan_ros.core import CollisionChecker, Scene
from ftplan_ros.core.angles import wrap_configuration
from ftplan_ros.core.manifolds import trace_self_motion_manifolds
from ftplan_ros.core.paths import densify

from .obstacles import ObstacleSet
from .params import (
    add_validators,
    array_parameter,
    check_startup_parameters,
    declare,
    declare_array,
    declare_scene,
    non_negative,
    positive,
)
from .qos import EVENT_QOS_DEPTH, LATCHED_QOS
from .reporting import Diagnostics, format_vector
from .spinning import run_node
from .topics import (
    JOINT_COMMAND,
    JOINT_STATES,
    LOCKED_JOINT,
    OBSTACLES,
    RESET_SERVICE,
    SIM_NODE,
)

_LOCK_SNAP_TOLERANCE = 1e-9  # [rad]


def default_initial_configuration(scene: Scene) -> np.ndarray:
    """Return the clearest configuration (n,) [rad] with the end effector at the task start.

    Without a task, the stretched-out arm (all zeros).
    """
    robot = scene.robot
    if scene.task is None or robot.n_joints - robot.task_dim != 1:
        return np.zeros(robot.n_joints)
    branches = trace_self_motion_manifolds(robot, np.asarray(scene.task.start),
                                           np.random.default_rng(0))
    if not branches:
        return np.zeros(robot.n_joints)
    points = np.vstack([b.points for b in branches])
    clearance = CollisionChecker(robot, scene.obstacles).min_clearance(points)
    best = points[int(np.argmax(clearance))]
    return wrap_configuration(best, robot.periodic)


class Motion:
    """A timed joint path (k, n) [rad], times (k,) [s] from `start`, sampled linearly.

    Times are on the sim's clock [s].
    """

    def __init__(self, positions: np.ndarray, times: np.ndarray, start: float):
        self.positions = positions
        self.times = times
        self.start = start

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


class SimNode(Node):
    """A kinematic arm: follows commands, locks joints, reports collisions and arrival."""

    def __init__(self, **kwargs):
        super().__init__(SIM_NODE, **kwargs)
        self.scene = declare_scene(self)
        robot = self.scene.robot
        self.rate = declare(self, 'rate', 100.0,
                            'Rate [Hz] of the simulation steps and of /joint_states.',
                            read_only=True)
        declare(self, 'max_joint_speed', 2.0,
                'Velocity limit [rad/s] of every joint; faster commands are slowed down.')
        declare(self, 'collision_check_step', 0.01,
                'Largest joint step [rad] between two collision checks along the motion.')
        declare(self, 'goal_tolerance', 0.0,
                'Distance [m] from the goal that counts as reached (0: the scene task\'s).')
        declare(self, 'brake_on_lock', True,
                'Stop every joint when one locks, until the next command.')
        declare_array(self, 'initial_configuration', Parameter.Type.DOUBLE_ARRAY,
                      'Configuration [rad] at start and after ~/reset (default: the clearest '
                      'configuration at the task start).')
        declare_array(self, 'goal', Parameter.Type.DOUBLE_ARRAY,
                      'End-effector goal [m] (default: the scene task goal).')
        validators = {
            'rate': positive, 'max_joint_speed': positive, 'collision_check_step': positive,
            'goal_tolerance': non_negative,
            'initial_configuration': self._check_configuration,
            'goal': self._check_goal,
        }
        check_startup_parameters(self, validators)
        add_validators(self, validators)

        self.names = list(robot.joint_names)
        self.diagnostics = Diagnostics(self)
        self._obstacles = ObstacleSet(self.scene)
        given = array_parameter(self, 'initial_configuration')
        self.initial = np.array(given, dtype=float) if given else \
            default_initial_configuration(self.scene)
        self.q = self.initial.copy()
        self.motion: Motion | None = None
        self.locked: dict[int, float] = {}
        self.resets = 0
        self._clear_counters()

        self.joint_state_publisher = self.create_publisher(
            JointState, JOINT_STATES, EVENT_QOS_DEPTH)
        self.command_subscription = self.create_subscription(
            JointTrajectory, JOINT_COMMAND, self.joint_command_callback, EVENT_QOS_DEPTH)
        self.locked_joint_subscription = self.create_subscription(
            JointState, LOCKED_JOINT, self.locked_joint_callback, EVENT_QOS_DEPTH)
        self.obstacle_subscription = self.create_subscription(
            MarkerArray, OBSTACLES, self.obstacles_callback, LATCHED_QOS)
        self.reset_service = self.create_service(Trigger, RESET_SERVICE,
                                                 self.reset_callback)
        self.timer = self.create_timer(1.0 / self.rate, self.timer_callback)
        self.sim_time = 0.0  # [s] advanced by 1/rate each tick
        self._check_clearance(self.q[None, :])
        self.publish_joint_state(np.zeros(len(self.names)))
        self.report('at the initial configuration', log=True)

    # Parameters ---------------------------------------------------------------------

    def _check_configuration(self, value) -> str | None:
        n = self.scene.robot.n_joints
        if len(value) != n or not np.all(np.isfinite(value)):
            return f'needs {n} finite angles [rad], got {list(value)}'
        return None

    def _check_goal(self, value) -> str | None:
        m = self.scene.robot.task_dim
        if len(value) not in (0, m) or not np.all(np.isfinite(value)):
            return f'needs {m} finite coordinates [m] (or none), got {list(value)}'
        return None

    def goal(self) -> tuple[np.ndarray | None, float]:
        """Return the goal (m,) [m] (None if unknown) and its tolerance [m]."""
        given = array_parameter(self, 'goal')
        task = self.scene.task
        goal = np.array(given, dtype=float) if given else \
            (np.asarray(task.goal, dtype=float) if task else None)
        tolerance = float(self.get_parameter('goal_tolerance').value)
        if tolerance == 0.0:
            tolerance = task.goal_tolerance if task else 0.01
        return goal, tolerance

    # Inputs -------------------------------------------------------------------------

    def joint_command_callback(self, msg: JointTrajectory) -> None:
        """Follow a new command from where the arm is; an empty one stops the arm."""
        try:
            if not msg.points:
                self.motion = None
                return
            positions, times = read_joint_trajectory(msg, self.names)
            start = self._start_time(msg)
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
                             start)

    def _start_time(self, msg: JointTrajectory) -> float:
        """Return the sim time a command starts: now, or its stamp when that lies ahead."""
        stamp = time_to_seconds(msg.header.stamp)
        if stamp == 0.0:
            return self.sim_time
        ahead = stamp - self.get_clock().now().nanoseconds * 1e-9
        return self.sim_time + max(0.0, ahead)

    def locked_joint_callback(self, msg: JointState) -> None:
        """Lock a joint where it is (or at the angle given) and brake the arm."""
        try:
            event = read_locked_joint(msg)
        except ValueError as error:
            self.diagnostics.rejected('input', f'ignored locked-joint event: {error}')
            return
        if event.name not in self.names:
            self.diagnostics.rejected('input', f'ignored lock of unknown joint {event.name!r}; '
                                      f'the arm has {self.names}')
            return
        joint = self.names.index(event.name)
        if joint in self.locked:
            return
        value = float(self.q[joint]) if event.angle is None else event.angle
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

    def obstacles_callback(self, msg: MarkerArray) -> None:
        """Add the obstacle topic to the collision checks."""
        try:
            self._obstacles.update(msg)
        except ValueError as error:
            self.diagnostics.rejected('input', f'ignored obstacle markers: {error}; keeping '
                                      f'the {len(self._obstacles)} previous')

    def reset_callback(self, request: Trigger.Request, response: Trigger.Response,
                       ) -> Trigger.Response:
        """Back to the initial configuration, every joint free, counters cleared."""
        given = array_parameter(self, 'initial_configuration')
        if given:
            self.initial = np.array(given, dtype=float)
        self.q = self.initial.copy()
        self.motion = None
        self.locked = {}
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
        dt = 1.0 / self.rate
        self.sim_time += dt
        previous = self.q
        try:
            if self.motion is not None:
                q, finished = self.motion.sample(self.sim_time)
                for joint, value in self.locked.items():
                    q[joint] = value
                self.q = q
                if finished:
                    self.motion = None
            moved = bool(np.any(self.q != previous))
            if moved:
                self._check_clearance(densify(np.vstack([previous, self.q]),
                                              float(self.get_parameter(
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

    def _check_clearance(self, samples: np.ndarray) -> None:
        clearance = self._obstacles.checker.min_clearance(samples)
        worst = int(np.argmin(clearance))
        self.min_clearance = min(self.min_clearance, float(clearance[worst]))
        colliding = bool(clearance[worst] <= 0.0)
        if colliding and not self._in_collision:
            self.collisions += 1
            self._in_collision = True
            self.report(f'collision at {format_vector(samples[worst])} rad (clearance '
                        f'{clearance[worst]:.4f} m)', 'ERROR', log=True)
        elif not colliding:
            self._in_collision = False

    def _report_stop(self) -> None:
        goal, tolerance = self.goal()
        if goal is None:
            self.report('stopped')
            return
        error = float(np.linalg.norm(self.scene.robot.forward_kinematics(self.q) - goal))
        self.goal_error = error
        self.goal_reached = error <= tolerance
        if self.goal_reached:
            self.report(f'goal reached (error {error:.2e} m)', log=True)
        else:
            self.report(f'stopped {error:.3f} m from the goal')

    def _clear_counters(self) -> None:
        self.collisions = 0
        self.min_clearance = float('inf')
        self.goal_reached = False
        self.goal_error = float('nan')
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
        }
        self.diagnostics.report('arm', level, message, values, log=log)


def main(args=None) -> int:
    """Run the sim node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(SimNode, SIM_NODE, args)
