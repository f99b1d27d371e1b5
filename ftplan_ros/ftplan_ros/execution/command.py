"""A command under way: a timed joint path from where the arm was, and where on it the arm is.

The arm is judged by where it is on the path, never by the clock: an arm that took the
command late gets to each of its moments late. Angles [rad], times [s] from the
command's stamp, stamps ROS time [ns].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ftplan_ros.core.model.paths import cumulative_fractions, point_at_fraction

from .motion import fraction_at_time, progress_along, time_at_fraction

# [s] The sim stops at a scheduled lock's point of the command, read from the command's
# message, whose times are rounded to nanoseconds: the moment of the arm's position may
# differ from the lock's by a few nanoseconds.
DUE_TOLERANCE = 1e-6


@dataclass(frozen=True, eq=False)
class Command:
    """Command `path` (k, n) at `times` (k,) [s] from ROS time `stamp_ns` [ns].

    Its first point is where the arm was when it was given (the message leaves it out).
    """

    path: np.ndarray
    times: np.ndarray
    stamp_ns: int

    def reached(self, stamp_ns: int, q: np.ndarray) -> bool:
        """Whether the arm at q (n,) is where the command puts it at ROS time `stamp_ns` [ns]."""
        progress, _ = progress_along(self.path, q)
        moment = time_at_fraction(self.path, self.times, progress)
        return moment >= (stamp_ns - self.stamp_ns) * 1e-9 - DUE_TOLERANCE

    def fraction_at(self, stamp_ns: int) -> float:
        """Return the fraction (0..1) of the path's length commanded by ROS time `stamp_ns` [ns]."""
        return fraction_at_time(self.path, self.times, (stamp_ns - self.stamp_ns) * 1e-9)

    def deviation(self, q: np.ndarray) -> float:
        """Return the distance [rad] of q (n,) from the path."""
        return progress_along(self.path, q)[1]

    def ends_at(self, q: np.ndarray, tolerance: float) -> bool:
        """Whether q (n,) is within `tolerance` [rad] of the path's end in every joint."""
        return float(np.max(np.abs(q - self.path[-1]))) <= tolerance

    def rest(self, q: np.ndarray) -> np.ndarray | None:
        """Return the part (k, n) of the path still ahead of the arm at q (n,), if any."""
        if len(self.path) < 2:
            return None
        fraction, _ = progress_along(self.path, q)
        ahead = self.path[cumulative_fractions(self.path) > fraction]
        return np.vstack([point_at_fraction(self.path, fraction)[None, :], ahead])
