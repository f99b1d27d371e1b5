"""One place that remembers locked joints: the executor asks it before every command.

A joint that locks stays locked until it is declared repaired (the executor's `~/reset`),
whatever the executor was doing when the event came: a lock while idle is remembered as
much as one in an execution. `moved` tells whether a path would move a locked joint, so
the executor never commands one. `lock_angle_problem` is the one bound on a lock event's
angle, which the executor and the sim share.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ftplan_ros.core.model.angles import configuration_difference

LOCKED_TOLERANCE = 1e-9  # [rad] a command may differ this much from a locked joint's angle
# [rad] Farthest a lock event's angle may be from where the joint is: a joint that locks
# stops where it is; the angle only says more precisely where (a jump would teleport it).
DEFAULT_LOCK_ANGLE_TOLERANCE = 0.05


@dataclass
class Lock:
    """A locked joint: its angle [rad] once known, and the execution it locked in."""

    joint: int
    angle: float | None
    execution: int | None  # None: it locked while no execution was running


def lock_angle_problem(name: str, angle: float | None, current: float | None,
                       periodic: bool, tolerance: float) -> str:
    """Say why a lock event's angle [rad] cannot be taken ('' when it can, or is None).

    The angle must lie within `tolerance` [rad] of the joint's current angle (a periodic
    joint's may differ by whole turns).
    """
    if angle is None:
        return ''
    if current is None:
        return f'{name} locks at {angle} rad, but its current angle is not known yet'
    gap = float(configuration_difference(angle, current, periodic)) if abs(angle) < 1e6 \
        else float('inf')
    if abs(gap) > tolerance:
        return (f'{name} would lock at {angle:.6g} rad, {gap:+.3g} rad from where it is '
                f'({current:.6f} rad): a joint locks where it stands (lock_angle_tolerance '
                f'{tolerance:g} rad); send no position to lock it there')
    return ''


class JointLocks:
    """The joints that locked and are not repaired yet, by index into `names`."""

    def __init__(self, names: list[str]):
        self.names = list(names)
        self._locks: dict[int, Lock] = {}

    def __len__(self) -> int:
        return len(self._locks)

    def __contains__(self, joint: int) -> bool:
        return joint in self._locks

    @property
    def joints(self) -> list[int]:
        """Locked joints, in joint order."""
        return sorted(self._locks)

    def lock(self, joint: int, angle: float | None, execution: int | None) -> bool:
        """Remember that `joint` locked (at `angle` [rad], if known); False if it already was."""
        if joint in self._locks:
            return False
        self._locks[joint] = Lock(joint, angle, execution)
        return True

    def settle(self, q: np.ndarray) -> None:
        """Take the angles of the locked joints from q (n,) [rad], where the arm stands still."""
        for joint, lock in self._locks.items():
            lock.angle = float(q[joint])

    def clear(self) -> list[str]:
        """Forget every lock (the joints were repaired); return their names."""
        repaired = [self.names[j] for j in self.joints]
        self._locks.clear()
        return repaired

    def describe(self) -> str:
        """Name the locks, e.g. "joint2 (while idle), joint3 (in execution 4)"."""
        return ', '.join(f'{self.names[j]} ({_when(lock)})'
                         for j, lock in sorted(self._locks.items()))

    def moved(self, path: np.ndarray) -> str:
        """Say which locked joint the path (k, n) [rad] would move, and how far ('' if none).

        A lock whose angle is not known yet counts as moved by any path that changes it.
        """
        for joint, lock in sorted(self._locks.items()):
            reference = lock.angle if lock.angle is not None else float(path[0, joint])
            moved = float(np.max(np.abs(path[:, joint] - reference)))
            if moved > LOCKED_TOLERANCE:
                return f'{self.names[joint]} by {moved:.3g} rad'
        return ''


def _when(lock: Lock) -> str:
    return 'while idle' if lock.execution is None else f'in execution {lock.execution}'
