"""The executor's logic without ROS: run the held plan, recover from a locked joint.

`Executor` has a verb per input: `hold` (a plan from the planner), `start` (a call of
/ftplan/execute), `on_joint_state`, `on_lock`, `on_obstacles`, `tick` (the status
timer), `reset` (the locked joints repaired), `use_robot` (a new robot) and `abort` (an
internal error of the node). Each takes the `Moment` of the call and returns the
actions for the node (actions.py): it reads no clock and publishes nothing. A run:

1. approaching: moves the arm to θ_s by the planner's approach when it starts where the
   arm stands, else by one the core plans now (core/planning/approach.py): along the
   obstacle-free arc of M_s through the arm when the end effector is at x_s, else by a
   straight or an RRT-Connect joint move, each certified collision-free;
2. nominal: follows the nominal path to M_g^F;
3. recovering: when a joint locks during 2, it commands a stop, waits until the joint
   states show the arm standing still, asks the core's `recover` for the path in
   S_F ∩ H_i from that configuration to M_g^F and commands it (recovery.py). A lock
   during 1 (not failure-tolerant) is handled alike, with a path to the goal planned
   from where the arm stopped with the joints left (`path_to_goal`), when there is one;
4. done (at the goal, judged by the core's task errors) or failed (with the reason).

A lock stamped ahead of where the arm is on its command (a drill's scheduled failure)
takes effect when the joint states show the arm at the point the command puts it at
that moment, not on arrival; any other takes effect at once. `lock_progress` is where
the arm stood locked, as a fraction of the nominal path's length (motion.py). A lock of
a joint the plan does not tolerate is handled the same way: a recovery path the core
finds in S_F is safe and is followed; without one the run fails with "joint X is not
tolerated by this plan".

Locked joints are remembered in one place (locks.py) whatever the executor is doing,
idle included, until `reset`; no command that would move one is ever given, and a run
is refused while one is locked. A run is also refused when the plan was made for
another robot (their digests differ) or timed within other motion limits (the robot's
or joint_limits_file's, scaled: their digests differ), when obstacle updates were lost,
and when the current obstacles touch a vertex of the plan's S_F. Obstacles that arrive during a run
are checked against the rest of the commanded motion (certified) and against S_F: on
the approach the arm stops and a new approach is planned from where it stands; on the
nominal or recovery path it stops there and the run fails. Lost obstacle updates, a
second lock, a tracking error and the timeouts (watchdog.py) stop the arm and fail the
run too.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ftplan_ros.core import Robot
from ftplan_ros.core.model.motion_limits import (
    MotionLimits,
    motion_limits_digest,
    robot_motion_limits,
)
from ftplan_ros.core.model.robot import robot_digest

from .actions import Action, Answer, Moment, Rejected, Status
from .locks import JointLocks, lock_angle_problem
from .options import ExecutorOptions, Interfaces, Obstacles
from .run import Run, surface_meets_obstacle
from .state import ACTIVE, Execution, HeldPlan, ScheduledLock, State
from .watchdog import JointStates, overdue

_IDLE_REPORT_PERIOD = 1.0  # [s] between status reports while no run is under way


class Executor:
    """Run held plans and recover from locked joints; every verb returns the node's actions."""

    def __init__(self, obstacles: Obstacles, options: ExecutorOptions, interfaces: Interfaces):
        self.obstacles = obstacles
        self.options = options
        self.interfaces = interfaces
        self.robot: Robot | None = None
        self.motion_limits: MotionLimits | None = None  # the robot's, unscaled
        self.names: tuple[str, ...] = ()
        self.plan: HeldPlan | None = None
        self.run: Run | None = None  # the latest run, under way or ended
        self.executions = 0
        self.locks = JointLocks([])  # locked, not yet repaired: the one place (locks.py)
        self.arm = JointStates()
        self._approach: tuple[str, np.ndarray] | None = None  # the planner's, and its plan
        self._last_status = 0.0  # monotonic [s] of the last status report
        self._actions: list[Action] = []

    @property
    def state(self) -> State:
        """What the executor is doing: the latest run's phase, else idle."""
        return self.run.state if self.run is not None else State.IDLE

    @property
    def active(self) -> bool:
        """Whether a run is under way."""
        return self.state in ACTIVE

    @property
    def execution(self) -> Execution | None:
        """The record of the latest run, if any."""
        return self.run.record if self.run is not None else None

    # The robot and the plan ---------------------------------------------------------

    def use_robot(self, robot: Robot, now: Moment, limits: MotionLimits | None = None,
                  ) -> list[Action]:
        """Execute with `robot` (its motion `limits`; None: its own) from now on.

        A run under way stops and fails. A robot with other joints starts afresh: the
        plan, the run, the locks and the joint states of the old one are dropped.
        """
        if self.active:
            self.run.fail(f'{self.interfaces.robot_source} changed during the execution: '
                          'stopped', now)
        names = tuple(robot.joint_names)
        if names != self.names:
            self.plan = self.run = None
            self.locks = JointLocks(list(names))
            self.arm.forget()
        self.robot, self.names = robot, names
        self.motion_limits = robot_motion_limits(robot) if limits is None else limits
        return self.flush()

    def commanded_limits(self) -> MotionLimits:
        """Return the limits commands are timed within: the robot's, scaled, speed capped."""
        return self.options.commanded(self.motion_limits)

    def hold(self, plan: HeldPlan, now: Moment) -> list[Action]:
        """Hold `plan` for the next run."""
        self.plan = plan
        self.report(f'holding plan {plan.key}', now)
        return self.flush()

    def take_approach(self, key: str, path: np.ndarray | None) -> None:
        """Keep the planner's approach (k, n) [rad] to θ_s of plan `key` (None: it sent none)."""
        self._approach = None if path is None or not len(path) else (key, path)

    def given_approach(self, key: str) -> np.ndarray | None:
        """Return (a copy of) the planner's approach (k, n) of plan `key`, if it sent one."""
        if self._approach is None or self._approach[0] != key:
            return None
        return self._approach[1].copy()

    # Requests -----------------------------------------------------------------------

    def start(self, now: Moment) -> Answer:
        """Start a run of the held plan: approach θ_s from the next joint state, then follow it."""
        problem = self._refusal()
        if problem:
            return Answer(False, problem)
        self.executions += 1
        self.run = Run(Execution(self.executions, self.plan, self.plan.surface, now.monotonic,
                                 requested_ns=now.ros_ns), self)
        # The move starts from the first joint state stamped after the request: the ones
        # received so far may predate it (e.g. a reset of the arm just before it).
        self.run.set_state(State.APPROACHING, 'starting from the next joint state', now)
        return Answer(True, f'execution {self.executions}: plan {self.plan.key} accepted',
                      self.flush())

    def _refusal(self) -> str:
        """Say why no run may start now ('' when one may)."""
        if self.active:
            return f'execution {self.execution.number} is still {self.state.value}'
        if self.plan is None:
            return 'no plan yet: call the plan service (/ftplan/plan) first'
        if self.locks:
            locked = [self.names[j] for j in self.locks.joints]
            return (f'{locked} locked ({self.locks.describe()}) and would be commanded: '
                    f'call {self.interfaces.reset_service} once repaired')
        if self.obstacles.lost:
            return f'{self.obstacles.lost}: {self.interfaces.obstacles_fix}, then execute again'
        digest = robot_digest(self.robot)
        if self.plan.robot_digest != digest:
            return (f'plan {self.plan.key} was made for robot {self.plan.robot_digest}, but the '
                    f'robot is now {digest} (from {self.interfaces.robot_source}): plan again')
        limits = motion_limits_digest(self.options.scaled(self.motion_limits))
        if self.plan.motion_limits_digest != limits:
            return (f'plan {self.plan.key} was timed within motion limits '
                    f'{self.plan.motion_limits_digest}, but the executor\'s are {limits} '
                    '(joint_limits_file, max_velocity_scaling_factor, '
                    'max_acceleration_scaling_factor): give the planner the same, plan again')
        if surface_meets_obstacle(self.obstacles, self.plan.surface):
            return (f'the obstacles changed since plan {self.plan.key}: its failure surface now '
                    'meets one; plan again')
        return ''

    def reset(self, now: Moment) -> Answer:
        """Declare the locked joints repaired, so that runs may start again (not during one)."""
        if self.active:
            return Answer(False, f'execution {self.execution.number} is {self.state.value}')
        repaired = self.locks.clear()
        message = f'repaired: {repaired}' if repaired else 'no joint was locked'
        self.report(f'reset: {message}', now, log=True)
        return Answer(True, message, self.flush())

    def abort(self, reason: str, now: Moment) -> list[Action]:
        """Stop and fail the run under way for `reason`; return the actions still pending.

        For an error inside a verb: the actions it decided before it raised go out too.
        """
        if self.active:
            self.run.fail(reason, now)
        return self.flush()

    # Inputs -------------------------------------------------------------------------

    def on_joint_state(self, q: np.ndarray, stamp_ns: int, now: Moment) -> list[Action]:
        """Track the arm at q (n,) [rad], stamped `stamp_ns` [ns]; move the run on."""
        self.arm.take(q, now.monotonic, self.options.stopped_tolerance)
        if self.active:
            due = self.run.track(q, stamp_ns, now)
            if due is not None:
                self._take_lock(due.joint, due.angle, now)
        return self.flush()

    def on_lock(self, joint: int, angle: float | None, stamp_ns: int, now: Moment,
                ) -> list[Action]:
        """Take a lock of `joint` (at `angle` [rad], None: where it is), stamped `stamp_ns` [ns].

        It takes effect at once, or, for an event stamped ahead of where the arm is on its
        command (a drill's scheduled failure), when the arm gets there (`on_joint_state`).
        """
        if self.active and self.execution.scheduled_lock is None and \
                not self.run.lock_due(stamp_ns, self.arm.q):
            self.run.schedule(ScheduledLock(joint, angle, stamp_ns), now)
        else:
            self._take_lock(joint, angle, now)
        return self.flush()

    def _take_lock(self, joint: int, angle: float | None, now: Moment) -> None:
        """Take the lock of `joint`: remember it; during a run, stop the arm to recover."""
        name = self.names[joint]
        current = None if self.arm.q is None else float(self.arm.q[joint])
        problem = lock_angle_problem(name, angle, current, bool(self.robot.periodic[joint]),
                                     self.options.lock_angle_tolerance)
        if problem:
            self.emit(Rejected(f'ignored locked-joint event: {problem}', name))
            return
        if not self.locks.lock(joint, current, self.execution.number if self.active else None):
            return  # the same failure reported again
        if self.active:
            self.run.lock(joint, now)
        else:
            self.report(f'{name} locked while no execution is running: remembered; executions '
                        f'are refused until {self.interfaces.reset_service} declares it '
                        'repaired', now, 'WARN', log=True)

    def on_obstacles(self, now: Moment) -> list[Action]:
        """Check a run under way against the obstacles, which changed (run.py)."""
        if self.active:
            self.run.obstacles_changed(now)
        return self.flush()

    def tick(self, now: Moment) -> list[Action]:
        """Fail a run that waited too long (watchdog.py); report progress, 1 Hz when idle."""
        late = overdue(self.state, self.execution, self.arm, now.monotonic, self.options)
        if late is not None:
            self.run.fail(late.reason, now, stop=late.stop)
        elif self.active or now.monotonic - self._last_status >= _IDLE_REPORT_PERIOD:
            self.report(self.state.value, now)
        return self.flush()

    # Reports ------------------------------------------------------------------------

    def emit(self, action: Action) -> None:
        """Add an action for the node."""
        self._actions.append(action)

    def report(self, message: str, now: Moment, level: str = 'OK', log: bool = False) -> None:
        """Add a status report: state, plan, the run (a copy), locks, tolerated joints."""
        self._last_status = now.monotonic
        ex = self.execution
        plan = ex.plan if ex is not None else self.plan
        self.emit(Status(message, level, log, self.state, self.plan.key if self.plan else '',
                         self.names, None if ex is None else replace(ex),
                         tuple(self.names[j] for j in self.locks.joints),
                         None if plan is None else plan.tolerated))

    def flush(self) -> list[Action]:
        """Return the actions decided since the last call, in order (after `report`)."""
        actions, self._actions = self._actions, []
        return actions
