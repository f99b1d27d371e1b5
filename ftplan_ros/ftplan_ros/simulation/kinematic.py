"""The kinematic arm: it follows its commands exactly, as a position-controlled arm does.

From where it is through the points of a command at their times (linear in joint space),
slowed down segment by segment where a command asks for more than `max_joint_speed`; a
stamped command starts at its stamp (one that came late starts late, and all its moments
with it). A lock holds its joint for good and, with `brake_on_lock`, brakes the arm until
the next command: each other joint decelerates from the speed it had, at the robot's
acceleration limit (core/model/motion_limits.py), to a stop v_j² / (2 a_j) further on,
as the executor's braking certificate assumes; later commands move only the free
joints. A lock stamped ahead of where the arm is on its command (a drill) waits for
that moment of the command and locks the joint exactly where the command puts the arm
then, between two steps too; at the end of the command at the latest. See arm.py for
the interface and its units.
"""

from __future__ import annotations

import numpy as np

from ftplan_ros.core import Robot
from ftplan_ros.core.model.angles import configuration_difference
from ftplan_ros.core.model.motion_limits import robot_motion_limits
from ftplan_ros.execution.locks import lock_angle_problem

from .arm import ArmOptions, Following, HeldJoint, Locked, LockOutcome, Refused, Scheduled, Step

_LOCK_SNAP_TOLERANCE = 1e-9  # [rad]
_BRAKING_SAMPLES = 20        # moments of a braking motion (linear between: inside its box)


class Motion:
    """A timed joint path (k, n) [rad], times (k,) [s] from `start`, sampled linearly.

    Times are on the arm's clock [s]. `commanded` (k,) [s] are the times the command asked
    for (`times` may be slower: the speed limit), from its stamp `stamp_ns` [ns, ROS time],
    which the arm's `start` stands for.
    """

    def __init__(self, positions: np.ndarray, times: np.ndarray, start: float,
                 commanded: np.ndarray | None = None, stamp_ns: int = 0):
        self.positions = positions
        self.times = times
        self.start = start
        self.commanded = times if commanded is None else commanded
        self.stamp_ns = stamp_ns

    def time_of(self, stamp_ns: int) -> float:
        """Return the arm's time [s] at which it is where the command puts it at `stamp_ns`.

        `stamp_ns` is ROS time [ns] on the command's timeline (its stamp + time from
        start); before the start: the start; after the end: the end.
        """
        commanded = (stamp_ns - self.stamp_ns) * 1e-9
        return self.start + float(np.interp(commanded, self.commanded, self.times))

    def covers(self, stamp_ns: int) -> bool:
        """Whether ROS time `stamp_ns` [ns] lies on the command's timeline, not after its end."""
        return (stamp_ns - self.stamp_ns) * 1e-9 <= self.commanded[-1]

    def velocity(self, now: float) -> np.ndarray:
        """Return the joint velocities (n,) [rad/s] at the arm's time `now` (0 outside it)."""
        t = now - self.start
        if t < 0.0 or t >= self.times[-1]:
            return np.zeros(self.positions.shape[1])
        i = int(np.searchsorted(self.times, t, side='right')) - 1
        return (self.positions[i + 1] - self.positions[i]) / (self.times[i + 1] - self.times[i])

    def sample(self, now: float) -> tuple[np.ndarray, bool]:
        """Return the configuration at the arm's time `now` and whether the motion is over."""
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
        """Return the path (k, n) [rad] followed from time `before` to `now`, and if it ended.

        The path holds the ends and every waypoint passed between them: the straight line
        between the ends alone would cut the corners the motion turns.
        """
        passed = self.positions[(self.times > before - self.start) &
                                (self.times < now - self.start)]
        end, finished = self.sample(now)
        return np.vstack([self.sample(before)[0], passed, end]), finished


class KinematicArm:
    """An arm that follows its commands exactly (see the module docstring and arm.py)."""

    def __init__(self, robot: Robot, q: np.ndarray, options: ArmOptions):
        self.robot = robot
        self.options = options
        self.q = np.array(q, dtype=float)
        self.time = 0.0
        self.motion: Motion | None = None
        self.locked: dict[int, float] = {}
        # Scheduled failures: (joint, angle, stamp [ns], the arm's time [s] it is due at
        # while no command is under way), each waiting for its moment.
        self._scheduled: list[tuple[int, float | None, int, float]] = []

    @property
    def moving(self) -> bool:
        """Whether a command is under way."""
        return self.motion is not None

    def follow(self, positions: np.ndarray, times: np.ndarray, stamp_ns: int, now_ns: int,
               ) -> Following:
        """Follow positions (k, n) at times (k,) [s] from ROS time `stamp_ns` [ns].

        The command starts at once, or at its stamp when that lies `stamp_ns - now_ns`
        ahead; from where the arm is, the locked joints held where they locked.
        """
        positions = np.vstack([self.q[None, :], positions])
        held = []
        for joint, angle in self.locked.items():
            moved = float(np.max(np.abs(positions[:, joint] - angle)))
            if moved > _LOCK_SNAP_TOLERANCE:
                held.append(HeldJoint(joint, moved, angle))
            positions[:, joint] = angle
        times = np.concatenate([[0.0], times])
        needed = np.max(np.abs(np.diff(positions, axis=0)), axis=1) / self.options.max_joint_speed
        given = np.diff(times)
        slowdown = float(np.max(needed / np.maximum(given, 1e-12))) \
            if np.any(needed > given * (1.0 + 1e-9)) else 1.0
        steps = np.maximum(given, needed)
        keep = np.concatenate([[True], steps > 0.0])
        start = self.time + max(0.0, (stamp_ns - now_ns) * 1e-9)
        self.motion = Motion(positions[keep], np.concatenate([[0.0], np.cumsum(steps)])[keep],
                             start, times[keep], stamp_ns)
        return Following(tuple(held), slowdown)

    def stop(self) -> None:
        """Stop where the arm is; a lock scheduled on the command is due at once."""
        self.motion = None
        self._scheduled = [(joint, angle, stamp_ns, self.time)
                           for joint, angle, stamp_ns, _ in self._scheduled]

    def lock(self, joint: int, angle: float | None, stamp_ns: int, now_ns: int = 0,
             ) -> LockOutcome | None:
        """Lock `joint` (at `angle` [rad], None: where it is) now, or at ROS time `stamp_ns`.

        A stamp ahead of where the arm is on its command schedules the lock for that
        moment (`step` takes it). So does a stamp ahead of the ROS time `now_ns` [ns] (0:
        unknown) with no command under way: a drill's lock, stamped on the command it
        belongs to, may come before that command. A stamp past the end of the command
        under way waits for the later of its ROS time and that end. None when the joint
        is locked or scheduled already.
        """
        if joint in self.locked or any(joint == j for j, _, _, _ in self._scheduled):
            return None
        by_clock = (stamp_ns - now_ns) * 1e-9 if stamp_ns and now_ns else 0.0
        if stamp_ns and self.motion is not None and self.motion.covers(stamp_ns):
            ahead = self.motion.time_of(stamp_ns) - self.time
        elif stamp_ns and self.motion is not None:
            ahead = max(self.motion.start + self.motion.times[-1] - self.time, by_clock)
        else:
            ahead = by_clock
        if ahead > 0.0:
            self._scheduled.append((joint, angle, stamp_ns, self.time + ahead))
            return Scheduled(joint, ahead)
        return self._lock(joint, angle, self._velocity(self.time))

    def _velocity(self, now: float) -> np.ndarray:
        """Return the joint velocities (n,) [rad/s] of the motion under way at time `now` [s]."""
        return np.zeros(len(self.q)) if self.motion is None else self.motion.velocity(now)

    def _lock(self, joint: int, angle: float | None, velocity: np.ndarray) -> Locked | Refused:
        """Lock `joint` where it is (or at `angle`, within tolerance); brake from `velocity`.

        `velocity` (n,) [rad/s] is the arm's at the lock.
        """
        current = float(self.q[joint])
        periodic = bool(self.robot.periodic[joint])
        problem = lock_angle_problem(self.robot.joint_names[joint], angle, current, periodic,
                                     self.options.lock_angle_tolerance)
        if problem:
            return Refused(joint, problem)
        value = current if angle is None else \
            current + float(configuration_difference(angle, current, periodic))
        jump = None
        if abs(value - current) > _LOCK_SNAP_TOLERANCE:
            jumped = self.q.copy()
            jumped[joint] = value
            jump, self.q = np.stack([self.q, jumped]), jumped
        self.locked[joint] = value
        if self.options.brake_on_lock:
            self.motion = self._braking(velocity)
        return Locked(joint, value, jump)

    def _braking(self, velocity: np.ndarray) -> Motion | None:
        """Return the motion of the free joints braking from `velocity` (n,) [rad/s], if any.

        Each decelerates at its acceleration limit a_j: it stops |v_j| / a_j later,
        v_j² / (2 a_j) further on, moving one way (sampled at _BRAKING_SAMPLES moments).
        """
        velocity = velocity.copy()
        velocity[list(self.locked)] = 0.0
        deceleration = robot_motion_limits(self.robot).acceleration
        stops = np.abs(velocity) / deceleration
        if not np.any(stops > 0.0):
            return None
        t = np.linspace(0.0, float(stops.max()), _BRAKING_SAMPLES)[:, None]
        t = np.minimum(t, stops[None, :])
        moved = np.abs(velocity) * t - 0.5 * deceleration * t ** 2
        return Motion(self.q + np.sign(velocity) * moved,
                      np.linspace(0.0, float(stops.max()), _BRAKING_SAMPLES), self.time)

    def step(self, dt: float) -> Step:
        """Move on by `dt` [s]: along the command, up to a scheduled lock due meanwhile."""
        before, self.time = self.time, self.time + dt
        previous = self.q
        until, due = self._due_locks(before, self.time)
        swept = None
        velocity = self._velocity(until) if due else None  # taken before the motion ends
        if self.motion is not None:
            swept, finished = self.motion.swept(before, until)
            swept[0] = previous
            for joint, angle in self.locked.items():
                swept[:, joint] = angle
            self.q = swept[-1].copy()
            if finished:
                self.motion = None
        return Step(swept, [self._lock(joint, angle, velocity) for joint, angle in due])

    def _due_locks(self, before: float, now: float) -> tuple[float, list[tuple[int, float | None]]]:
        """Take the scheduled locks due by time `now` [s]; return when the first is due.

        The arm moves until that moment (within the step from `before`) and locks there,
        exactly where its command puts it then; without a command, or stamped past its end,
        at the moment it was scheduled for.
        """
        moments = [self.motion.time_of(stamp_ns) if self.motion is not None and
                   self.motion.covers(stamp_ns) else moment
                   for _, _, stamp_ns, moment in self._scheduled]
        due = [lock for lock, moment in zip(self._scheduled, moments, strict=True)
               if moment <= now]
        if not due:
            return now, []
        self._scheduled = [lock for lock in self._scheduled if lock not in due]
        first = max(before, min(moment for moment in moments if moment <= now))
        return first, [(joint, angle) for joint, angle, _, _ in due]

    def reset(self, q: np.ndarray) -> None:
        """Stand at q (n,), every joint free, nothing commanded or scheduled."""
        self.q = np.array(q, dtype=float)
        self.motion = None
        self.locked = {}
        self._scheduled = []
