"""The predictor-corrector that traces one self-motion curve, compiled with numba.

Tracing is most of a cold plan: thousands of steps, each a few Newton iterations on an
n x n system, where numpy's per-call overhead dominates in plain Python. The kernel gets
the robot's task map from `kinematics.task_residual(Robot.kernel_kind,
Robot.kernel_parameters, x, θ)`, so it serves any chain and task with one degree of
redundancy (n = m + 1). The machine code is cached next to this file (numba's cache), so
only the first run on a machine compiles. Angles [rad], positions [m].
"""

from __future__ import annotations

import numba
import numpy as np

from ..model.angles import wrap_steps
from ..model.kinematics import solve_in_place, task_residual

# How a trace ended (the `status` of `trace_curve`).
OPEN = 0        # a joint limit, a dead end or the target
CLOSED = 1      # back at the seed: a loop, `period` says by how many turns
STALLED = 2     # the step shrank below step_min
TOO_LONG = 3    # max_points reached

_NEWTON_ITERATIONS = 8


@numba.njit(cache=True)
def _correct(kind, parameters, x, predicted, tangent, tolerance):
    """Newton on f(θ) = x in the hyperplane through `predicted` orthogonal to `tangent`.

    `x` is a task point and `kind`, `parameters` the robot's task map (model/kinematics.py).

    Returns (converged, θ, unit self-motion direction oriented like `tangent`); both come
    from the bordered matrix [J; tangent], whose solve against the last unit vector is a
    null vector of J.
    """
    n = predicted.shape[0]
    m = n - 1
    theta = predicted.copy()
    bordered = np.empty((n, n))
    rhs = np.zeros((n, 2))
    rhs[n - 1, 1] = 1.0
    for _ in range(_NEWTON_ITERATIONS + 1):
        residual, jac = task_residual(kind, parameters, x, theta)
        bordered[:m] = jac
        bordered[m] = tangent
        rhs[:m, 0] = residual
        solution = rhs.copy()
        if not solve_in_place(bordered, solution):  # exactly singular: a crossing point
            return False, theta, tangent
        if residual @ residual < tolerance * tolerance:
            direction = np.ascontiguousarray(solution[:, 1])
            return True, theta, direction / np.linalg.norm(direction)
        theta = theta + solution[:, 0]
    return False, theta, tangent


@numba.njit(cache=True)
def trace_curve(kind, parameters, x, seed, tangent, periodic, lower, upper, step_max,
                step_min, max_turn, tolerance, max_points, target, use_target):
    """Continue from `seed` (n,) along `tangent` until the loop closes, a limit or a dead end.

    With `use_target`, it also stops as soon as a point comes within a step of `target`.
    Returns (points (k, n), status, period (n,)); see OPEN, CLOSED, STALLED, TOO_LONG.
    """
    n = seed.shape[0]
    points = np.empty((max_points, n))
    points[0] = seed
    count = 1
    theta = seed.copy()
    seed_tangent = tangent.copy()
    step = step_max
    travelled = 0.0
    min_turn = np.cos(max_turn)
    no_period = np.zeros(n)
    while count < max_points:
        ok, corrected, new_tangent = _correct(kind, parameters, x,
                                              theta + step * tangent, tangent, tolerance)
        moved = 0.0
        if ok:
            moved = np.linalg.norm(corrected - theta)
            if new_tangent @ tangent < min_turn or moved > 1.5 * step:
                ok = False
        if not ok:
            step *= 0.5
            if step < step_min:
                return points[:count].copy(), STALLED, no_period
            continue
        for k in range(n):
            if not periodic[k] and (corrected[k] < lower[k] or corrected[k] > upper[k]):
                return points[:count].copy(), OPEN, no_period
        travelled += moved
        theta, tangent = corrected, new_tangent
        points[count] = theta
        count += 1
        if use_target and np.linalg.norm(
                wrap_steps(target - theta, periodic)) <= step_max:
            return points[:count].copy(), OPEN, no_period
        gap = wrap_steps(theta - seed, periodic)
        if (travelled > 3.0 * step_max and np.linalg.norm(gap) < step_max
                and tangent @ seed_tangent > min_turn):
            # Back at the seed: the closing chord to seed + period is shorter than a step.
            period = np.zeros(n)
            for k in range(n):
                if periodic[k]:
                    turns = (theta[k] - gap[k] - seed[k]) / (2.0 * np.pi)
                    period[k] = 2.0 * np.pi * np.round(turns)
            return points[:count].copy(), CLOSED, period
        step = min(step * 1.5, step_max)
    return points[:count].copy(), TOO_LONG, no_period
