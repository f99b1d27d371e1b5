"""Replay a timed joint trajectory and list every limit it breaks (issue 36, item 2).

Shared by the unit tests (timings and the executor's commands without ROS) and the ROS
tests (every JointTrajectory the nodes publish). No rclpy here: messages are read with
ftplan_msgs_py.
"""

import numpy as np

from ftplan_ros.core.model.motion_limits import MotionLimits
from ftplan_ros.core.planning.timing import DEFAULT_MAX_STEP
from ftplan_ros.execution.motion import progress_along

# Relative to each limit. The timing keeps its own checks within 1e-6 (timing.py
# _RELATIVE_SLACK); a message rounds time_from_start to 1 ns, which moves a finite
# difference over a step of dt >= 1 ms by at most 2 ns / dt = 2e-6 of itself.
TOLERANCE = 1e-5
ON_PATH = 1e-9    # [rad] a point this close to the certified polyline is on it
# How far the finite differences a controller derives may be from the mean of the rates
# sent at both ends of a step, relative to the limit. The rates are TOPP-RA's on a cubic
# spline through the points, the positions the polyline's: at a sharp corner of the path
# the spline's tangent is not the chord's (0.13 of the velocity limit measured on a
# zigzag of right angles), and TOPP-RA switches between full acceleration and full
# deceleration inside a step (Δv/Δt up to the limit where the mean of the two ends is ~0:
# 1.0 measured). So the acceleration check only catches rates of another scale or sign.
VELOCITY_CONSISTENCY = 0.25
ACCELERATION_CONSISTENCY = 1.25


def limit_violations(positions, velocities, accelerations, times, limits: MotionLimits,
                     position_limits=None, certified=None, max_step=DEFAULT_MAX_STEP,
                     from_rest=True, periodic=None) -> list[str]:
    """Say what breaks the limits: the points (k, n) sent and what a controller derives.

    Checks the published rates and their finite differences (Δq/Δt, Δv/Δt, Δa/Δt for
    jerk where bounded) against `limits` and against the rates sent, positions within
    `position_limits` (n, 2) if given, steps <= `max_step` (None: unchecked), strictly
    increasing times, rest at the end, every point on the `certified` polyline (m, n), if
    given, and every vertex of it sent (so linear interpolation stays on it). `from_rest`:
    the first point is the start, at rest at time 0; else (a command without the arm's
    own position, as the executor sends it) the first point is after time 0.
    """
    positions, velocities, accelerations, times = (np.asarray(a, dtype=float) for a in (
        positions, velocities, accelerations, times))
    problems = []
    dt = np.diff(times)
    starts = times[0] == 0.0 if from_rest else times[0] > 0.0
    if not starts or not np.all(dt > 0.0):
        return ['times not strictly increasing from 0']
    slack = 1.0 + TOLERANCE
    velocity = np.diff(positions, axis=0) / dt[:, None]
    acceleration = np.diff(velocities, axis=0) / dt[:, None]
    checks = [('velocity', velocities, limits.velocity, slack),
              ('finite-difference velocity', velocity, limits.velocity, slack),
              ('acceleration', accelerations, limits.acceleration, slack),
              ('finite-difference acceleration', acceleration, limits.acceleration, slack),
              ('finite-difference jerk', np.diff(accelerations, axis=0) / dt[:, None],
               limits.jerk, slack),
              ('finite-difference velocity against the velocities sent',
               velocity - (velocities[1:] + velocities[:-1]) / 2, limits.velocity,
               VELOCITY_CONSISTENCY),
              ('finite-difference acceleration against the accelerations sent',
               acceleration - (accelerations[1:] + accelerations[:-1]) / 2,
               limits.acceleration, ACCELERATION_CONSISTENCY)]
    for name, values, bound, allowed in checks:
        worst = float(np.max(np.abs(values) / bound)) if len(values) else 0.0
        if worst > allowed:
            problems.append(f'{name} {worst:.6f} x its limit')
    if position_limits is not None:
        low, high = np.asarray(position_limits).T
        if np.any(positions < low - 1e-12) or np.any(positions > high + 1e-12):
            problems.append('a position outside the joint limits')
    step = float(np.max(np.abs(np.diff(positions, axis=0)), initial=0.0))
    if max_step is not None and step > max_step + 1e-12:
        problems.append(f'a step of {step} rad')
    if from_rest and np.any(velocities[0] != 0.0):
        problems.append('not at rest at the start')
    if np.any(velocities[-1] != 0.0) or np.any(accelerations[-1] != 0.0):
        problems.append('not at rest at the end')
    if certified is None:
        return problems
    off = max(progress_along(certified, q, periodic)[1] for q in positions)
    if off > ON_PATH:
        problems.append(f'a point {off} rad off the certified path')
    sent = {tuple(np.round(q, 12)) for q in positions}
    vertices = certified if from_rest else certified[1:]  # a command leaves out the start
    missing = [q for q in vertices if tuple(np.round(q, 12)) not in sent]
    if missing:
        problems.append(f'{len(missing)} vertices of the certified path not sent')
    return problems


def trajectory_violations(msg, names, limits: MotionLimits, **checks) -> list[str]:
    """Say what is wrong with a trajectory_msgs/JointTrajectory with points, for joints `names`.

    Joint names as given; every point with positions, velocities and accelerations of one
    value per joint, all finite; then `limit_violations(..., **checks)` on them.
    """
    if list(msg.joint_names) != list(names):
        return [f'joint names {list(msg.joint_names)}, not {list(names)}']
    n = len(names)
    for i, point in enumerate(msg.points):
        for field in ('positions', 'velocities', 'accelerations'):
            values = np.asarray(getattr(point, field), dtype=float)
            if values.shape != (n,) or not np.all(np.isfinite(values)):
                return [f'point {i}: {field} {values.tolist()} are not {n} finite numbers']
    positions, velocities, accelerations = (
        np.array([getattr(point, field) for point in msg.points], dtype=float)
        for field in ('positions', 'velocities', 'accelerations'))
    times = np.array([point.time_from_start.sec + 1e-9 * point.time_from_start.nanosec
                      for point in msg.points])
    return limit_violations(positions, velocities, accelerations, times, limits, **checks)
