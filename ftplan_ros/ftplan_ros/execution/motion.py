"""Joint-path helpers of the executor, the sim and the injector: timing, progress along a path.

Paths are (k, n) [rad], lifted (continuous); joints flagged periodic wrap every 2π.
Progress along a path is the fraction of its joint-space length (core/paths.py
`cumulative_fractions`): the one measure of "fraction of the nominal path" that the
injector schedules a drill by, the executor reports a lock at, and ftplan-bringup judges.
"""

from __future__ import annotations

import numpy as np

from ftplan_ros.core.model.angles import configuration_difference
from ftplan_ros.core.model.paths import cumulative_fractions, path_length

MIN_STEP_TIME = 1e-3  # [s] keeps the times of a trajectory strictly increasing


def time_path(path: np.ndarray, max_speed: float, min_step: float = MIN_STEP_TIME,
              ) -> np.ndarray:
    """Return times (k,) [s] from 0 that move no joint faster than `max_speed` [rad/s].

    Each step takes max_j |Δθ_j| / max_speed, and at least `min_step` so the times are
    strictly increasing (a ros2_control joint_trajectory_controller requires it).
    """
    steps = np.max(np.abs(np.diff(path, axis=0)), axis=1) / max_speed if len(path) > 1 \
        else np.zeros(0)
    return np.concatenate([[0.0], np.cumsum(np.maximum(steps, min_step))])


def progress_along(path: np.ndarray, q: np.ndarray, periodic: np.ndarray | None = None,
                   ) -> tuple[float, float]:
    """Project q (n,) onto the polyline `path` (k, n): (fraction of its length, distance [rad]).

    With `periodic`, q may differ from the path by whole turns of those joints.
    """
    periodic = False if periodic is None else periodic
    if len(path) < 2:
        return 1.0, float(np.linalg.norm(configuration_difference(q, path[-1], periodic)))
    a, b = path[:-1], path[1:]
    direction = b - a
    lengths2 = np.einsum('sn,sn->s', direction, direction)
    offset = configuration_difference(q, a, periodic)
    t = np.clip(np.einsum('sn,sn->s', offset, direction) / np.maximum(lengths2, 1e-300), 0, 1)
    gaps = np.linalg.norm(offset - t[:, None] * direction, axis=1)
    best = int(np.argmin(gaps))
    if path_length(path) == 0.0:
        return 1.0, float(gaps[best])
    fractions = cumulative_fractions(path)
    return float(fractions[best] + t[best] * (fractions[best + 1] - fractions[best])), \
        float(gaps[best])


def fraction_at_time(path: np.ndarray, times: np.ndarray, t: float) -> float:
    """Return the fraction (0..1) of the path's length (k, n) that its timing commands by `t`.

    `times` (k,) [s] are strictly increasing from 0; the motion is linear in joint space
    between points, so the fraction is too. Before 0: 0; after the end: 1.
    """
    return float(np.interp(t, times, cumulative_fractions(path)))


def time_at_fraction(path: np.ndarray, times: np.ndarray, fraction: float) -> float:
    """Return the first time [s] at which the timed path (k, n), times (k,), has done `fraction`.

    The inverse of `fraction_at_time`; a fraction outside [0, 1] is clipped.
    """
    fractions = cumulative_fractions(path)
    fraction = float(np.clip(fraction, 0.0, 1.0))
    after = int(np.searchsorted(fractions, fraction, side='left'))
    if after == 0:
        return float(times[0])
    before = after - 1
    share = (fraction - fractions[before]) / (fractions[after] - fractions[before])
    return float(times[before] + share * (times[after] - times[before]))
