"""The executor's watch over the arm: its last joint states, and the timeouts of a run.

A run fails when the arm does not start (no joint state since the request within
`start_timeout`), does not stop after a lock (`stop_timeout`), goes silent while
commanded (`joint_state_timeout`: the watchdog) or stands still short of the end of its
command (`stall_timeout`). Times are monotonic seconds, angles radians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .options import ExecutorOptions
from .state import ACTIVE, Execution, State


@dataclass
class JointStates:
    """The arm as its last two joint states show it, and when it was last heard and moved."""

    q: np.ndarray | None = None          # (n,) the latest configuration
    previous: np.ndarray | None = None   # (n,) the one before
    received: float = 0.0                # monotonic [s] of the last good joint state
    moved: float = 0.0                   # monotonic [s] of the last joint state that moved

    def take(self, q: np.ndarray, now: float, stopped_tolerance: float) -> None:
        """Take a joint state q (n,) received at `now` [s]."""
        self.previous, self.q = self.q, q
        self.received = now
        if not self.standing(stopped_tolerance):
            self.moved = now

    def standing(self, stopped_tolerance: float) -> bool:
        """Whether the last two joint states lie within `stopped_tolerance` [rad]: standing."""
        return self.previous is not None and \
            float(np.max(np.abs(self.q - self.previous))) <= stopped_tolerance

    def forget(self) -> None:
        """Forget the configurations (another arm)."""
        self.q = self.previous = None


@dataclass(frozen=True)
class Overdue:
    """Why a run fails now, and whether to command a stop first."""

    reason: str
    stop: bool = True


def overdue(state: State, ex: Execution | None, arm: JointStates, now: float,
            options: ExecutorOptions) -> Overdue | None:
    """Return why the run `ex` in `state` has waited too long at `now` [s], or None."""
    if state == State.APPROACHING and ex.command is None and \
            now - ex.started > options.start_timeout:
        return Overdue('no joint state on /joint_states since the request (start_timeout)',
                       stop=False)
    if state == State.RECOVERING and ex.command is None and \
            now - ex.stop_requested > options.stop_timeout:
        # A stop again: the first request may have been lost.
        return Overdue('the arm did not stop after the lock (no two equal joint states within '
                       'stop_timeout)')
    if _joint_states_stopped(state, ex, arm, now, options):
        return Overdue(f'watchdog: no joint state for more than {options.joint_state_timeout} '
                       's (joint_state_timeout) while the arm was commanded: stop commanded')
    if state in ACTIVE and ex.command is not None and \
            now - max(ex.commanded, arm.moved) > options.stall_timeout:
        return Overdue(f'the arm stands still short of the end of the command while '
                       f'{state.value} (stall_timeout): stopped there')
    return None


def _joint_states_stopped(state: State, ex: Execution | None, arm: JointStates, now: float,
                          options: ExecutorOptions) -> bool:
    """Whether /joint_states went quiet during a run that has started moving."""
    if state not in ACTIVE or (state == State.APPROACHING and ex.command is None and
                               not ex.reapproach):
        return False  # not moving yet: start_timeout's case
    # From the last command too: planning it (an RRT-Connect approach) may take longer
    # than the timeout, with the joint states waiting behind it.
    quiet = now - max(arm.received, ex.started, ex.commanded)
    return quiet > options.joint_state_timeout
