"""A plan from the planner's latched topics: θ_s, the nominal trajectory, S_F, the plan status.

The planner publishes each plan on four latched topics (plan_results.py): its plan status on
/ftplan/plan/info (plan_info.py: what the plan is for, the robot's digest among it), S_F,
the nominal trajectory and θ_s, the last two stamped like the plan. They arrive in no set
order, and S_F carries no stamp: it is the plan's when one of its paths is the
trajectory. `PlanTopics` keeps the latest messages of each and assembles a plan once all
four of it are in: the one way the executor and PlanClient read a plan.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray
from trajectory_msgs.msg import JointTrajectory

from ftplan_msgs_py import (
    read_diagnostic_status,
    read_failure_surface,
    read_joint_state,
    read_joint_trajectory,
)
from ftplan_ros.core import FailureSurface

from .plan_info import INFOS_KEPT, PlanInfo, PlanInfos, read_plan_info
from .reporting import stamp_key
from .topics import PLAN_INFO


@dataclass(frozen=True, eq=False)
class LatchedPlan:
    """A plan as its latched topics carry it (angles [rad], times [s])."""

    key: str                        # the plan's stamp 'sec.nanosec'
    joint_names: tuple[str, ...]
    theta_s: np.ndarray             # (n,) start configuration
    trajectory: np.ndarray          # (k, n) nominal joint path
    times: np.ndarray               # (k,) its times from start
    paths: np.ndarray               # (K, k, n) S_F
    nominal: int                    # which path of S_F is the trajectory
    info: PlanInfo                  # what the plan is for

    @property
    def surface(self) -> FailureSurface:
        """S_F as the core's FailureSurface (the nominal path marked)."""
        return FailureSurface(self.paths, self.nominal, (), ())


class PlanTopics:
    """The latest `kept` messages of each latched plan topic, and the plans they make."""

    def __init__(self, kept: int = 1):
        self.starts: deque[JointState] = deque(maxlen=kept)
        self.trajectories: deque[JointTrajectory] = deque(maxlen=kept)
        self.surfaces: deque[Float64MultiArray] = deque(maxlen=kept)
        self.infos = PlanInfos(max(kept, INFOS_KEPT))

    def add_info(self, msg: DiagnosticArray) -> list[str]:
        """Keep the plan statuses of a /ftplan/plan/info message; return why any was ignored."""
        problems = []
        for status in msg.status:
            try:
                reading = read_diagnostic_status(status)
            except ValueError as error:
                problems.append(f'ignored {PLAN_INFO}: {error}')
                continue
            info = read_plan_info(reading.values) if reading.level == 'OK' else None
            if info is None or info.stamp != stamp_key(msg.header.stamp):
                problems.append(f'ignored {PLAN_INFO}: it describes no plan stamped '
                                f'{stamp_key(msg.header.stamp)}')
                continue
            self.infos.add(info)
        return problems

    def newest_key(self) -> str | None:
        """Return the stamp of the newest θ_s received: the latest plan's (None before any)."""
        return stamp_key(self.starts[-1].header.stamp) if self.starts else None

    def assemble(self, key: str, names: Sequence[str] | None = None) -> LatchedPlan | None:
        """Return plan `key` once its four topics are in (None until then).

        `names` orders the joints (default: the trajectory's). Raises ValueError when the
        plan's messages cannot be read, or disagree (θ_s not where the trajectory starts);
        an S_F that cannot be read may be another publisher's: only when none holds the
        trajectory is its error raised.
        """
        start, trajectory = _stamped(self.starts, key), _stamped(self.trajectories, key)
        if start is None or trajectory is None:
            return None
        names = tuple(names or trajectory.joint_names)
        positions, times = read_joint_trajectory(trajectory, names)
        theta_s = read_joint_state(start, names)
        found = self._surface_holding(positions)
        if found is None:
            return None
        if not np.array_equal(positions[0], theta_s):
            raise ValueError(f'theta_s {theta_s.tolist()} is not where the trajectory starts '
                             f'({positions[0].tolist()})')
        info = self.infos.get(key)
        if info is None:
            return None
        paths, nominal = found
        return LatchedPlan(key, names, theta_s, positions, times, paths, nominal, info)

    def _surface_holding(self, trajectory: np.ndarray) -> tuple[np.ndarray, int] | None:
        """Return the newest S_F (K, k, n) with the trajectory (k, n) among its paths, and which.

        None when no S_F holds it; ValueError when none does and one could not be read.
        """
        unreadable = None
        for surface in reversed(self.surfaces):
            try:
                paths = read_failure_surface(surface)
            except ValueError as error:
                unreadable = unreadable or error
                continue
            if paths.shape[1:] != trajectory.shape:
                continue
            matches = np.flatnonzero(np.all(paths == trajectory[None], axis=(1, 2)))
            if len(matches):
                return paths, int(matches[0])
        if unreadable is not None:
            raise unreadable
        return None


def _stamped(messages: deque, key: str):
    """Return the newest message of `messages` stamped `key` ('sec.nanosec'), else None."""
    return next((msg for msg in reversed(messages) if stamp_key(msg.header.stamp) == key),
                None)
