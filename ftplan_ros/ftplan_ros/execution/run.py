"""One run of a held plan: the approach, the nominal path, a lock's recovery, the end.

A `Run` moves its record (state.py `Execution`) from phase to phase as the executor
(executor.py) passes it the joint states, locks and obstacle changes; it commands the
arm, stops it and reports through its host, the executor. Angles [rad], monotonic
times [s], ROS times [ns].
"""

from __future__ import annotations

from dataclasses import replace
from typing import Protocol

import numpy as np

from ftplan_ros.core import FailureSurface, Robot, task_errors
from ftplan_ros.core.collision.braking import lock_point, point_at_level, segment_speeds
from ftplan_ros.core.model.angles import configuration_difference, whole_turns
from ftplan_ros.core.model.motion_limits import MotionLimits
from ftplan_ros.core.planning.approach import Approach, ApproachOptions, ApproachPlanner, Route
from ftplan_ros.core.planning.timing import at_speed, braking_speed_scaling, time_within_limits

from .actions import Action, Moment, Stop
from .command import Command
from .locks import JointLocks
from .motion import progress_along
from .options import ExecutorOptions, Interfaces, Obstacles
from .recovery import lock_message, with_joints_left, within_surface
from .state import Execution, ScheduledLock, State
from .watchdog import JointStates


class Host(Protocol):
    """What a run uses of the executor that holds it."""

    robot: Robot
    names: tuple[str, ...]
    obstacles: Obstacles
    options: ExecutorOptions
    interfaces: Interfaces
    locks: JointLocks
    arm: JointStates

    def commanded_limits(self) -> MotionLimits:
        """Return the motion limits the commands are timed within (scaled)."""

    def given_approach(self, key: str) -> np.ndarray | None:
        """Return the planner's approach (k, n) of plan `key`, if it sent one."""

    def emit(self, action: Action) -> None:
        """Add an action for the node."""

    def report(self, message: str, now: Moment, level: str = 'OK', log: bool = False) -> None:
        """Add a status report."""


def surface_meets_obstacle(obstacles: Obstacles, surface: FailureSurface) -> bool:
    """Whether a vertex of S_F touches the current obstacles (or measures NaN)."""
    return not obstacles.checker.min_clearance(surface.vertices, needed=0.0).min() > 0.0


class Run:
    """One run of a plan, from the request to done or failed (see executor.py)."""

    def __init__(self, record: Execution, host: Host):
        self.record = record
        self.host = host
        self.state = State.APPROACHING

    def set_state(self, state: State, message: str, now: Moment, level: str = 'OK') -> None:
        """Enter `state` and report it with `message` (logged)."""
        self.state = state
        self.host.report(message, now, level, log=True)

    def fail(self, reason: str, now: Moment, stop: bool = True) -> None:
        """End the run for `reason`; with `stop`, ask the arm to stop first."""
        if stop:
            self.host.emit(Stop())
        self.record.reason = reason
        self.record.finished = now.monotonic
        self.set_state(State.FAILED, reason, now, level='ERROR')

    # The arm ------------------------------------------------------------------------

    def track(self, q: np.ndarray, stamp_ns: int, now: Moment) -> ScheduledLock | None:
        """Move on with the arm at q (n,), stamped `stamp_ns` [ns]; return a lock come due.

        A lock scheduled on the command that the arm has now reached is returned for the
        executor to take; the run does nothing else with this joint state.
        """
        ex = self.record
        if self.state == State.NOMINAL:
            ex.progress, _ = progress_along(ex.nominal, q)
        lock = ex.scheduled_lock
        if lock is not None and self.lock_due(lock.stamp_ns, q):
            ex.scheduled_lock = None
            return lock
        if ex.command is None:
            self._between_commands(q, stamp_ns, now)
            return None
        deviation = ex.command.deviation(q)
        if deviation > self.host.options.path_tolerance:
            self.fail(f'tracking error: the arm is {deviation:.3f} rad from the commanded path '
                      f'while {self.state.value}', now)
        elif ex.command.ends_at(q, self.host.options.arrival_tolerance):
            if self.state == State.APPROACHING:
                self._begin_nominal(now)
            else:
                self._finish(q, now)
        return None

    def _between_commands(self, q: np.ndarray, stamp_ns: int, now: Moment) -> None:
        """With no command under way: wait for the stop after a lock, or start moving."""
        ex = self.record
        if ex.locked_joint is not None:
            # Joint states sent before the lock may still be queued (the node takes
            # another topic's messages in no set order with the lock's): a stop judged
            # on them would recover from where the arm no longer is.
            if _sent_since(stamp_ns, ex.lock_received_ns):
                self._wait_for_stop(q, now)
        elif ex.reapproach:
            if self.host.arm.standing(self.host.options.stopped_tolerance):
                self._start_motion(q, now)
        elif self.state == State.APPROACHING and _sent_since(stamp_ns, ex.requested_ns):
            self._start_motion(q, now)

    def _start_motion(self, q: np.ndarray, now: Moment) -> None:
        """Command the approach to θ_s from q (or the nominal path if the arm is there)."""
        ex = self.record
        plan = ex.plan
        ex.reapproach = False
        found = self._approach(q, plan.theta_s)
        ex.approach = found.describe()
        if not found.ok:
            self.fail(f'no collision-free approach to theta_s from where the arm stands: '
                      f'{found.reason}', now, stop=False)
            return
        approach = found.path.copy()
        # The approach may end whole turns away from θ_s: shift S_F to the arm's lift.
        offset = whole_turns(approach[-1], plan.theta_s, self.host.robot.periodic)
        approach[-1] = plan.theta_s + offset
        if np.any(offset):
            ex.surface = replace(plan.surface, paths=plan.surface.paths + offset)
        if len(approach) < 2:
            self._begin_nominal(now)
        elif self._command(approach, now):
            self.set_state(State.APPROACHING, f'approaching theta_s {ex.approach}', now)

    def _approach(self, q: np.ndarray, theta_s: np.ndarray) -> Approach:
        """Find a certified path (k, n) from q to θ_s plus whole turns (core/approach.py).

        The planner's approach of this plan is taken when it starts where the arm stands,
        ends at θ_s (whole turns apart on periodic joints) and is still clear of the
        obstacles; else one is planned now. A single point (1, n) means the arm is at θ_s.
        """
        arrival = self.host.options.arrival_tolerance
        planner = self._planner()
        given = self.host.given_approach(self.record.plan.key)
        if given is not None and np.max(np.abs(given[0] - q)) <= arrival and np.max(np.abs(
                configuration_difference(given[-1], theta_s, self.host.robot.periodic))) <= arrival:
            given[0] = q
            if planner.certify(given):
                return Approach(given, Route.GIVEN)
        return planner.approach(q, theta_s, arrival)

    def _begin_nominal(self, now: Moment) -> None:
        """Command the nominal path, slowed so that a lock anywhere on it brakes certified."""
        speed = self._command(self.record.nominal, now, self.host.options.nominal_lead,
                              braking=True)
        if speed:
            slower = '' if speed == 1.0 else \
                f' at {speed:.0%} of its time-optimal speed (the braking after a lock certified)'
            self.set_state(State.NOMINAL, f'following the nominal path{slower}', now)

    def _finish(self, q: np.ndarray, now: Moment) -> None:
        """Done: report the task errors [m, rad] from the plan's goal."""
        ex = self.record
        robot = ex.plan.robot
        ex.finished = now.monotonic
        ex.goal_error, ex.goal_orientation_error = (
            float(v) for v in task_errors(robot, ex.plan.goal, q))
        how = 'recovered' if ex.locked_joint is not None else 'nominal path'
        error = f'{ex.goal_error:.2e} m' + (f', {ex.goal_orientation_error:.2e} rad' if
                                            robot.task_kind in ('axis', 'pose') else '')
        self.set_state(State.DONE, f'reached the goal ({how}), error {error}', now)

    def _command(self, path: np.ndarray, now: Moment, lead: float = 0.0,
                 braking: bool = False) -> float:
        """Command `path` (k, n), whose first point is where the arm is; 0 if refused.

        Returns the fraction (0, 1] of the time-optimal speed commanded: with `braking`,
        the largest at which a lock anywhere on the path brakes, within the commanded
        accelerations, inside a box certified free (core/planning/timing.py); none
        certified fails the run.

        The command starts `lead` [s] after now: its stamp; it is timed within the
        host's commanded limits, in steps of at most `max_step` (timing.py). A path that
        would move a locked joint is never commanded: the arm is stopped and the run fails
        instead (that would be a bug of the executor).
        """
        moved = self.host.locks.moved(path)
        if moved:
            self.fail(f'refused to command a path that moves locked joint {moved}: the arm is '
                      'stopped (please report)', now)
            return 0.0
        ex = self.record
        limits = self.host.commanded_limits()
        timed = time_within_limits(path, limits, self.host.options.max_step)
        speed = braking_speed_scaling(self.host.obstacles.checker, timed,
                                      limits.acceleration) if braking else 1.0
        if speed <= 0.0:
            self.fail('no speed of the nominal path is certified to brake clear of the '
                      'obstacles after a lock: stopped; plan again (with a margin)', now)
            return 0.0
        timed = at_speed(timed, speed)
        ex.command = Command(timed.positions, timed.times, now.ros_ns + round(lead * 1e9),
                             timed.velocities, timed.accelerations)
        ex.commanded = now.monotonic
        if braking:
            ex.nominal_command, ex.braking = ex.command, limits.acceleration
        self.host.emit(ex.command)
        return speed

    # Locks --------------------------------------------------------------------------

    def lock_due(self, stamp_ns: int, q: np.ndarray | None) -> bool:
        """Whether a lock stamped `stamp_ns` [ns] has taken effect with the arm at q (n,).

        It has once the arm is where its command puts it at that moment (command.py), and
        at once without a command under way (or a joint state).
        """
        command = self.record.command
        return command is None or q is None or command.reached(stamp_ns, q)

    def schedule(self, lock: ScheduledLock, now: Moment) -> None:
        """Wait with `lock` until the arm gets to its moment of the command (`track`)."""
        ex = self.record
        ex.scheduled_lock = lock
        self.host.report(f'{self.host.names[lock.joint]} locks at '
                         f'{ex.command.fraction_at(lock.stamp_ns):.1%} of the command under way '
                         f'({self.state.value}): scheduled', now, log=True)

    def lock(self, joint: int, now: Moment) -> None:
        """Joint `joint` locked (remembered by the executor): stop the arm to go on from there."""
        ex = self.record
        names = self.host.names
        if ex.locked_joint is not None:
            self.fail(f'{names[joint]} locked after {names[ex.locked_joint]}: a second failure '
                      'is beyond the single-failure guarantee; the arm is stopped safely where '
                      'it is', now)
            return
        self.host.emit(Stop())
        ex.locked_joint, ex.lock_received, ex.lock_received_ns = joint, now.monotonic, now.ros_ns
        ex.stop_requested = ex.lock_received
        ex.lock_phase = self.state
        ex.command = None
        approaching = self.state == State.APPROACHING
        self.set_state(State.RECOVERING, lock_message(names[joint], approaching, ex.progress),
                       now, level='WARN' if approaching else 'OK')

    def _wait_for_stop(self, q: np.ndarray, now: Moment) -> None:
        """Once the arm stands still at q (n,) after the lock, and has settled: on to the goal."""
        ex = self.record
        options = self.host.options
        if not self.host.arm.standing(options.stopped_tolerance) or \
                now.monotonic - ex.stop_requested < options.stop_settle_time:
            return
        self.host.locks.settle(q)
        ex.lock_configuration = q.copy()
        name = self.host.names[ex.locked_joint]
        if ex.lock_phase == State.APPROACHING:
            way = with_joints_left(self._planner(), ex, q, name)
        else:
            start = ex.lock_point = self._lock_point(q)
            ex.lock_progress, _ = progress_along(ex.nominal, start)
            ex.progress = ex.lock_progress
            way = within_surface(ex, q, start, name, options.max_path_offset,
                                 self._planner(), options.path_tolerance)
        if way.path is None:
            self.fail(way.message, now)  # the arm stands still: keep it so
            return
        ex.recovery_length = way.length
        if self._command(way.path, now):
            self.set_state(State.RECOVERING, way.message, now, level=way.level)

    def _lock_point(self, q: np.ndarray) -> np.ndarray:
        """Return where on the nominal path the arm, stopped at q (n,), braked from.

        The point of the locked joint's angle (within `max_path_offset`) whose certified
        braking box holds q (core/collision/braking.py). An arm under physics may stop
        outside every box: its locked joint lags its command, and where that joint hardly
        moves along the path, the point of its angle lies far back. The point of the angle
        nearest along the path to where the arm was when the joint locked (`progress`, not
        updated since: the arm braked on) is then taken, among those within
        `path_tolerance` (the tracking error the executor accepts), if the straight move
        back to it is certified now. Else q itself (the arm stopped on the path, or
        recovery refuses it).
        """
        ex = self.record
        sent = ex.nominal_command
        if sent is None or len(sent.path) < 2:
            return q
        speeds = segment_speeds(sent.path, sent.velocities, sent.times)
        offset = self.host.options.max_path_offset
        p = lock_point(sent.path, speeds, ex.braking, q, ex.locked_joint, offset)
        if p is None:
            p = point_at_level(sent.path, q, ex.locked_joint, offset,
                               self.host.options.path_tolerance, ex.progress)
            if p is None or not self._planner().certify(np.stack([q, p])):
                return q
        return p

    # Obstacles ----------------------------------------------------------------------

    def obstacles_changed(self, now: Moment) -> None:
        """Stop when updates were lost or new obstacles meet the rest of the motion or S_F.

        On the approach the arm then approaches θ_s again from where it stops (unless S_F
        is hit); on the nominal or recovery path it stays stopped and the run fails.
        """
        lost = self.host.obstacles.lost
        if lost:
            self.fail(f'{lost} while {self.state.value}: an obstacle may be in the way unseen, '
                      'so the arm is stopped where it is; '
                      f'{self.host.interfaces.obstacles_fix}, then plan again', now)
            return
        problem = self._obstacle_problem()
        if not problem:
            return
        ex = self.record
        if self.state == State.APPROACHING and \
                not surface_meets_obstacle(self.host.obstacles, ex.surface):
            self.host.emit(Stop())
            ex.command, ex.reapproach = None, True
            self.set_state(State.APPROACHING, f'{problem} while approaching theta_s: stopped; '
                           'approaching again from where the arm stands', now, level='WARN')
            return
        self.fail(f'{problem} ({self.state.value}, {ex.progress:.1%} of the nominal path): '
                  'stopped there; plan again', now)

    def _obstacle_problem(self) -> str:
        """Say how the current obstacles meet the rest of the command or S_F ('' if not)."""
        ex = self.record
        q = self.host.arm.q
        rest = None if ex.command is None or q is None else ex.command.rest(q)
        if rest is not None and not self._planner().certify(rest):
            return 'an obstacle that arrived meets the rest of the motion'
        if self.state != State.RECOVERING and surface_meets_obstacle(self.host.obstacles,
                                                                     ex.surface):
            return ('an obstacle that arrived meets the failure surface S_F: the rest of the '
                    'motion would not be failure-tolerant')
        return ''

    def _planner(self) -> ApproachPlanner:
        """Return the core's approach planner over the current obstacles, for the run's plan."""
        return ApproachPlanner(self.host.obstacles.checker,
                               ApproachOptions(rrt_time=self.host.options.approach_time,
                                               margin=self.host.options.margin),
                               robot=self.record.plan.robot)


def _sent_since(stamp_ns: int, since_ns: int) -> bool:
    """Whether a message stamped `stamp_ns` [ns, ROS time] was sent at `since_ns` or later.

    An unstamped message (0) counts as sent now: older ones may still be queued.
    """
    return stamp_ns == 0 or stamp_ns >= since_ns
