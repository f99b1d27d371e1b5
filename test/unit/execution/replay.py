"""Replay a timed joint trajectory and list every limit it breaks (issue 36, item 2)."""

import numpy as np

from ftplan_ros.core.model.motion_limits import MotionLimits
from ftplan_ros.execution.motion import progress_along

TOLERANCE = 1e-6  # relative to each limit: numerical slack only
ON_PATH = 1e-9    # [rad] a point this close to the certified polyline is on it


def limit_violations(positions, velocities, accelerations, times, limits: MotionLimits,
                     position_limits, certified=None, max_step=0.05) -> list[str]:
    """Say what breaks the limits: the points (k, n) sent and what a controller derives.

    Checks the published rates and their finite differences (Δq/Δt, Δv/Δt, Δa/Δt for
    jerk where bounded), positions within `position_limits` (n, 2), steps <= `max_step`,
    strictly increasing times from 0, rest at both ends, every point on the `certified`
    polyline (m, n), if given, and every vertex of it sent (so linear interpolation stays on it).
    """
    problems = []
    dt = np.diff(times)
    if times[0] != 0.0 or not np.all(dt > 0.0):
        problems.append('times not strictly increasing from 0')
        return problems
    slack = 1.0 + TOLERANCE
    checks = [('velocity', velocities, limits.velocity),
              ('finite-difference velocity', np.diff(positions, axis=0) / dt[:, None],
               limits.velocity),
              ('acceleration', accelerations, limits.acceleration),
              ('finite-difference acceleration', np.diff(velocities, axis=0) / dt[:, None],
               limits.acceleration),
              ('finite-difference jerk', np.diff(accelerations, axis=0) / dt[:, None],
               limits.jerk)]
    for name, values, bound in checks:
        worst = float(np.max(np.abs(values) / bound)) if len(values) else 0.0
        if worst > slack:
            problems.append(f'{name} {worst:.6f} x its limit')
    low, high = np.asarray(position_limits).T
    if np.any(positions < low - 1e-12) or np.any(positions > high + 1e-12):
        problems.append('a position outside the joint limits')
    step = float(np.max(np.abs(np.diff(positions, axis=0)), initial=0.0))
    if step > max_step + 1e-12:
        problems.append(f'a step of {step} rad')
    if np.any(velocities[[0, -1]] != 0.0) or np.any(accelerations[-1] != 0.0):
        problems.append('not at rest at the start and the end')
    if certified is None:
        return problems
    off = max(progress_along(certified, q)[1] for q in positions)
    if off > ON_PATH:
        problems.append(f'a point {off} rad off the certified path')
    sent = {tuple(np.round(q, 12)) for q in positions}
    missing = [q for q in certified if tuple(np.round(q, 12)) not in sent]
    if missing:
        problems.append(f'{len(missing)} vertices of the certified path not sent')
    return problems
