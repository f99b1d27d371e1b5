"""The injector node: failure drills as locked-joint events on /ftplan/locked_joint.

    ros2 run ftplan_ros injector --ros-args -p drills:="['joint2@0.4', 'joint1@2.5s']"
    ros2 param set /ftplan_injector lock_now joint3        # one event, right now

Each execution of a plan (the executor's 'execution' status on /diagnostics numbers them)
gets at most one drill, taken in order from:

- `drills`: scheduled drills, one per execution. 'JOINT@F' locks JOINT when the arm has
  done the fraction F (0..1) of the nominal path's length (execution/motion.py): once the
  executor commands the nominal path (/ftplan/joint_command, equal to
  /ftplan/plan/trajectory, stamped with its start), the injector publishes the lock event
  stamped with the moment that command reaches F, and the sim and the executor make it
  take effect then, exactly there, however late the event arrived (as long as it arrived
  before). 'JOINT@Ts' locks it T seconds after the execution started (which may fall in
  the approach to θ_s, where no recovery is guaranteed). A drill not sent when the
  injector learns that the execution ended (reached the goal, failed) is dropped with a
  warning: a lock after the goal would test no recovery, and the executor would refuse
  executions until reset.
- `random_drills`: then this many executions (-1: all of them) get a Monte Carlo drill,
  a uniformly random joint among those the plan tolerates (the executor's status names
  them, plan_info.py; every joint when it does not) at a uniformly random fraction of
  the nominal path, drawn from a generator seeded with `seed` (setting either parameter
  restarts the sequence).

Drills name joints, for any number of joints; a scheduled drill may lock a joint the
plan does not tolerate (the executor then recovers if S_F allows it, else stops the arm
and reports it). A scene file without a robot takes it from /robot_description
(scene_source.py): drills are checked against its joints when it arrives.

Setting `lock_now` to a joint name publishes one event at once and clears the parameter.
Every event is logged and reported on /diagnostics ('ftplan_injector: drills').
"""

from __future__ import annotations

import re
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.time import Time
from sensor_msgs.msg import JointState
from trajectory_msgs.msg import JointTrajectory

from ftplan_msgs_py import (
    create_locked_joint,
    read_diagnostic_status,
    read_joint_trajectory,
    time_to_nanoseconds,
)
from ftplan_ros.core.model.angles import configuration_difference
from ftplan_ros.execution.motion import time_at_fraction

from .params import (
    add_validators,
    array_parameter,
    check_startup_parameters,
    declare,
    declare_array,
    destroyed_if_start_fails,
    non_negative,
)
from .plan_info import split_names
from .qos import EVENT_QOS_DEPTH, LATCHED_QOS
from .reporting import Diagnostics
from .scene_source import SceneSource
from .spinning import run_node
from .topics import (
    DIAGNOSTICS,
    EXECUTOR_NODE,
    INJECTOR_NODE,
    JOINT_COMMAND,
    LOCKED_JOINT,
    TRAJECTORY,
)

# [rad] How far a command may be from the nominal path and still be it (the executor sends
# the very numbers of /ftplan/plan/trajectory, shifted by whole turns at most).
_SAME_PATH = 1e-9
_DRILL = re.compile(r'^\s*([^@\s]+)\s*@\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*(s?)\s*$')
_RUNNING = ('approaching', 'nominal')
# How far from its fraction of the nominal path a drill's lock may land and count as drilled.
DRILL_TOLERANCE = 0.02


@dataclass(frozen=True)
class Drill:
    """Lock `joint` at `fraction` (0..1) of the nominal path, or `seconds` after the start."""

    joint: str
    fraction: float | None = None
    seconds: float | None = None

    def __str__(self) -> str:
        return f'{self.joint}@{self.seconds:.3g}s' if self.seconds is not None else \
            f'{self.joint}@{self.fraction:.3g}'

    def missed(self, locked_joint: str, lock_phase: str, landed: float) -> str:
        """Say how a run's lock missed this drill ('' when it was drilled as asked).

        The arguments are the executor's report of the run: the joint that locked ('' for
        none), the phase it locked in, and `landed`, the fraction of the nominal path
        where the arm stood locked (NaN if not reported). A fraction drill must lock its
        joint on the nominal path within DRILL_TOLERANCE of its fraction; a drill in
        seconds must lock its joint during the execution.
        """
        if not locked_joint:
            return 'no lock during the execution'
        if locked_joint != self.joint:
            return f'{locked_joint} locked, not {self.joint}'
        if self.fraction is None:
            return ''
        if lock_phase != 'nominal':
            return f'the lock landed while {lock_phase or "in an unknown phase"}, not on ' \
                'the nominal path'
        if not np.isfinite(landed):
            return 'the executor did not report where the lock landed'
        if abs(landed - self.fraction) <= DRILL_TOLERANCE:
            return ''
        after = ': after the motion' if landed >= 1.0 else ''
        return f'lock landed at {landed:.1%}{after}, asked {self.fraction:.1%}'


def parse_drill(text: str, joint_names: Sequence[str] | None) -> Drill:
    """Parse 'JOINT@FRACTION' (0..1) or 'JOINT@SECONDSs'; ValueError says what is wrong.

    With `joint_names` None (the robot is not known yet) any joint name passes.
    """
    match = _DRILL.match(text) if isinstance(text, str) else None
    if match is None:
        raise ValueError(f'drill {text!r} is not JOINT@FRACTION (e.g. joint2@0.4) or '
                         'JOINT@SECONDSs (e.g. joint1@2.5s)')
    joint, number, seconds = match.group(1), float(match.group(2)), match.group(3)
    if joint_names is not None and joint not in joint_names:
        raise ValueError(f'drill {text!r}: unknown joint {joint!r}; the arm has '
                         f'{list(joint_names)}')
    if seconds:
        return Drill(joint, seconds=number)
    if not 0.0 <= number <= 1.0:
        raise ValueError(f'drill {text!r}: the fraction of the path must be in [0, 1]; '
                         'add "s" for seconds')
    return Drill(joint, fraction=number)


def lock_moment(nominal: np.ndarray, positions: np.ndarray, times: np.ndarray,
                stamp_ns: int, fraction: float, periodic: np.ndarray) -> int | None:
    """Return when [ns, ROS time] a command reaches `fraction` of the nominal path (k, n).

    The command holds positions (k - 1, n) [rad] at times (k - 1,) [s] from `stamp_ns`:
    the executor commands the nominal path from its first point, where the arm stands, so
    it sends the points after it (whole turns of `periodic` joints apart, in the arm's
    lift). None when the command is not the nominal path.
    """
    if len(positions) == 0 or positions.shape != (len(nominal) - 1, nominal.shape[1]) or \
            np.max(np.abs(configuration_difference(positions, nominal[1:], periodic))) > \
            _SAME_PATH:
        return None
    seconds = time_at_fraction(nominal, np.concatenate([[0.0], times]), fraction)
    return stamp_ns + round(seconds * 1e9)


def random_drill(rng: np.random.Generator, joint_names: Sequence[str]) -> Drill:
    """Draw a Monte Carlo drill: a random joint of `joint_names` at a random fraction.

    Both are uniform; the fraction is of the nominal path's length.
    """
    joint = joint_names[int(rng.integers(len(joint_names)))]
    return Drill(joint, fraction=float(rng.uniform(0.0, 1.0)))


class InjectorNode(Node):
    """Publish locked-joint failure events: scheduled, random or manual."""

    def __init__(self, **kwargs):
        with destroyed_if_start_fails(self):
            super().__init__(INJECTOR_NODE, **kwargs)
            self.diagnostics = Diagnostics(self)
            self.source = SceneSource(self, self.diagnostics, self._scene_changed)
            self.scene = self.source.scene
            self.names = None if self.scene is None else list(self.scene.robot.joint_names)
            declare_array(self, 'drills', Parameter.Type.STRING_ARRAY,
                          'Scheduled drills, one per execution: JOINT@FRACTION of the nominal '
                          'path (0..1) or JOINT@SECONDSs after the execution starts.')
            declare(self, 'random_drills', 0,
                    'Executions (after the scheduled ones) that get a random drill; -1: all.')
            declare(self, 'seed', 0, 'Seed of the random drills.')
            declare(self, 'lock_now', '',
                    'Set to a joint name to publish one lock event at once (then cleared).')
            declare(self, 'executor_status', f'{EXECUTOR_NODE}: execution',
                    'Name of the executor\'s execution status on /diagnostics.')
            validators = {
                'drills': self._check_drills,
                'random_drills': lambda v: None if v >= -1 else f'must be >= -1, got {v}',
                'seed': non_negative,
                'lock_now': self._check_lock_now,
            }
            check_startup_parameters(self, validators)
            add_validators(self, validators)
            self.add_post_set_parameters_callback(self.parameters_callback)

            self.queue = [parse_drill(text, self.names) for text in array_parameter(self, 'drills')]
            self._restart_random()
            self.execution: int | None = None
            self.state = ''
            self.drill: Drill | None = None
            self.pending = False
            self.nominal: np.ndarray | None = None
            self.tolerated: tuple[str, ...] = ()  # of the execution's plan, from its status
            self._trajectory_msg: JointTrajectory | None = None
            self._command_msg: JointTrajectory | None = None  # the last, since arming
            self._drill_timer = None
            self._lock_now_clearer = self.create_timer(0.0, self._clear_lock_now)
            self._lock_now_clearer.cancel()

            self.lock_publisher = self.create_publisher(JointState, LOCKED_JOINT, EVENT_QOS_DEPTH)
            self.status_subscription = self.create_subscription(
                DiagnosticArray, DIAGNOSTICS, self.diagnostics_callback, EVENT_QOS_DEPTH)
            self.command_subscription = self.create_subscription(
                JointTrajectory, JOINT_COMMAND, self.command_callback, EVENT_QOS_DEPTH)
            self.trajectory_subscription = self.create_subscription(
                JointTrajectory, TRAJECTORY, self.trajectory_callback, LATCHED_QOS)
            if self.queue or self.random_left:
                self.get_logger().info(f'drills: {[str(d) for d in self.queue]}, then '
                                       f'{self.random_left} random (seed {self._seed})')

    # Parameters ---------------------------------------------------------------------

    def _check_lock_now(self, value) -> str | None:
        if value == '' or self.names is None or value in self.names:  # None: robot to come
            return None
        return f'unknown joint {value!r}; the arm has {self.names}'

    def _scene_changed(self, scene) -> None:
        """Take the joints of a robot from /robot_description; drop drills of others."""
        self.scene = scene
        self.names = list(scene.robot.joint_names)
        kept = [drill for drill in self.queue if drill.joint in self.names]
        for drill in self.queue:
            if drill.joint not in self.names:
                self.diagnostics.report('drills', 'WARN', f'dropped drill {drill}: unknown '
                                        f'joint {drill.joint!r}; the arm has {self.names}',
                                        {'drill': str(drill)}, log=True)
        self.queue = kept
        if self._trajectory_msg is not None:
            self.trajectory_callback(self._trajectory_msg)

    def _check_drills(self, value) -> str | None:
        try:
            for text in value:
                parse_drill(text, self.names)
        except ValueError as error:
            return str(error)
        return None

    def _restart_random(self) -> None:
        self._seed = int(self.get_parameter('seed').value)
        self.rng = np.random.default_rng(self._seed)
        self.random_left = int(self.get_parameter('random_drills').value)

    def parameters_callback(self, parameters: list[Parameter]) -> None:
        """Apply accepted changes: new schedule, new random sequence, manual lock."""
        names = {p.name for p in parameters}
        if 'drills' in names:
            self.queue = [parse_drill(t, self.names) for t in array_parameter(self, 'drills')]
        if names & {'random_drills', 'seed'}:
            self._restart_random()
        lock = self.get_parameter('lock_now').value
        if 'lock_now' in names and lock:
            self.publish_lock(lock, 'manual lock_now')
            # Clear it outside this callback: parameters cannot be set from in here.
            self._lock_now_clearer.reset()

    def _clear_lock_now(self) -> None:
        self._lock_now_clearer.cancel()
        self.set_parameters([Parameter('lock_now', value='')])

    # Inputs -------------------------------------------------------------------------

    def trajectory_callback(self, msg: JointTrajectory) -> None:
        """Keep the nominal path, to measure the progress of an execution."""
        self._trajectory_msg = msg
        if self.names is None:
            return
        try:
            self.nominal = read_joint_trajectory(msg, self.names).positions
        except ValueError as error:
            self.diagnostics.rejected('drills', f'ignored trajectory: {error}')

    def diagnostics_callback(self, msg: DiagnosticArray) -> None:
        """Follow the executor's execution status: arm a drill for each new execution."""
        name = self.get_parameter('executor_status').value
        for status in msg.status:
            if status.name != name:
                continue
            try:
                values = read_diagnostic_status(status).values
                state = values['state']
                execution = int(values['execution']) if 'execution' in values else None
            except (ValueError, KeyError):
                continue
            self._follow(execution, state, split_names(values.get('tolerated_joints', '')))

    def _follow(self, execution: int | None, state: str, tolerated: tuple[str, ...]) -> None:
        if execution is not None and execution != self.execution and state in _RUNNING:
            self.execution = execution
            self.tolerated = tolerated
            self._arm()
        if execution != self.execution:
            return
        previous, self.state = self.state, state
        if self.pending and state != previous and state not in _RUNNING:
            self._disarm(f'execution {execution} became {state} first')

    def _arm(self) -> None:
        self._disarm()
        self._command_msg = None  # commands so far were for earlier executions
        if self.queue:
            self.drill = self.queue.pop(0)
        elif self.random_left != 0 and self.names is not None:
            joints = [name for name in self.names if name in self.tolerated] or self.names
            self.drill = random_drill(self.rng, joints)
            self.random_left -= 1 if self.random_left > 0 else 0
        else:
            self.drill = None
            return
        self.pending = True
        self.diagnostics.report('drills', 'OK', f'execution {self.execution}: armed '
                                f'{self.drill}', {'execution': self.execution,
                                                  'drill': str(self.drill)}, log=True)
        if self.drill.seconds is not None:
            self._drill_started = time.monotonic()
            self._drill_timer = self.create_timer(self.drill.seconds, self._timed_fire)

    def _disarm(self, why: str = '') -> None:
        if self._drill_timer is not None:
            self.destroy_timer(self._drill_timer)
            self._drill_timer = None
        if self.pending and why:
            self.diagnostics.report('drills', 'WARN', f'dropped drill {self.drill}: {why}',
                                    {'execution': self.execution, 'drill': str(self.drill)},
                                    log=True)
        self.pending = False

    def _timed_fire(self) -> None:
        self.destroy_timer(self._drill_timer)
        self._drill_timer = None
        if self.pending and self.state in _RUNNING:
            self._fire(f'{time.monotonic() - self._drill_started:.2f} s after the start')

    def command_callback(self, msg: JointTrajectory) -> None:
        """Schedule a fraction drill on the executor's command of the nominal path."""
        self._command_msg = msg
        self._schedule()

    def _schedule(self) -> None:
        """Once the nominal path is commanded, send the lock stamped with its moment."""
        msg = self._command_msg
        if not self.pending or self.drill.fraction is None or msg is None or \
                self.nominal is None or self.names is None:
            return
        try:
            positions, times = read_joint_trajectory(msg, self.names)
            stamp_ns = time_to_nanoseconds(msg.header.stamp) or \
                self.get_clock().now().nanoseconds  # unstamped: it starts on arrival
        except ValueError:
            return  # not a command of this arm; the executor reports bad ones
        moment = lock_moment(self.nominal, positions, times, stamp_ns, self.drill.fraction,
                             self.scene.robot.periodic)
        if moment is not None:
            self._fire(f'at {self.drill.fraction:.1%} of the nominal path, '
                       f'{(moment - stamp_ns) * 1e-9:.3f} s after its start',
                       Time(nanoseconds=moment, clock_type=self.get_clock().clock_type))

    # Output -------------------------------------------------------------------------

    def _fire(self, when: str, at: Time | None = None) -> None:
        self.pending = False
        self.publish_lock(self.drill.joint, f'execution {self.execution}: drill {self.drill} '
                          f'{when}', {'execution': self.execution, 'drill': str(self.drill)},
                          at)

    def publish_lock(self, joint: str, why: str, values: dict | None = None,
                     at: Time | None = None) -> None:
        """Publish the event that locks `joint` where it is, now or `at` (ROS time); report it."""
        at = at or self.get_clock().now()
        self.lock_publisher.publish(create_locked_joint(joint, stamp=at.to_msg()))
        self.diagnostics.report('drills', 'OK', f'locked {joint}: {why}',
                                {'joint': joint, **(values or {})}, log=True)


def main(args=None) -> int:
    """Run the injector node until Ctrl-C; exit code 2 for a bad scene or parameter."""
    return run_node(InjectorNode, INJECTOR_NODE, args)
