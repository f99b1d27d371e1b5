"""What the executor holds: the plan it runs, one run of it, and the phase it is in.

Angles [rad], monotonic times [s], ROS times [ns]. The executor (executor.py) changes
them; its status reports (actions.py) carry copies.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ftplan_ros.core import FailureSurface, Robot

from .command import Command


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
    """A plan from the planner's latched topics and what its plan status says it is for."""

    key: str                        # the plan's stamp as 'sec.nanosec'
    theta_s: np.ndarray             # (n,)
    surface: FailureSurface         # S_F; surface.nominal is the path the arm follows
    robot: Robot                    # the arm, bound to the plan's task kind
    goal: np.ndarray                # the task point the plan reaches
    tolerated: tuple[str, ...]      # the joints whose lock it survives
    robot_digest: str               # of the robot it was planned for (core robot_digest)
    motion_limits_digest: str       # of the (scaled) limits it was timed within


@dataclass(frozen=True)
class ScheduledLock:
    """A lock event stamped ahead of the arm on its command (a drill): it waits for then."""

    joint: int
    angle: float | None   # [rad] where it locks; None: where it stands
    stamp_ns: int         # ROS time [ns] on the command's timeline


@dataclass(eq=False)
class Execution:
    """One run of a plan: its lifted copy, the current command and the failure, if any."""

    number: int
    plan: HeldPlan
    surface: FailureSurface          # the plan's S_F shifted by whole turns to the arm's lift
    started: float                   # monotonic [s]
    command: Command | None = None   # the command under way
    nominal_command: Command | None = None   # the nominal path's, as sent: its braking boxes
    braking: np.ndarray | None = None        # [rad/s²] (n,) the deceleration they assume
    scheduled_lock: ScheduledLock | None = None
    progress: float = 0.0            # fraction of the nominal path's length done
    locked_joint: int | None = None
    lock_received: float | None = None
    lock_progress: float | None = None
    lock_configuration: np.ndarray | None = None
    lock_point: np.ndarray | None = None   # where on the nominal path it braked from
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
    def braking_deviation(self) -> float | None:
        """[rad] how far (∞-norm) the arm braked from its lock point; None without one."""
        if self.lock_point is None or self.lock_configuration is None:
            return None
        return float(np.max(np.abs(self.lock_configuration - self.lock_point)))

    @property
    def nominal(self) -> np.ndarray:
        """The nominal path (k, n) [rad] in the arm's lift."""
        return self.surface.nominal_path
