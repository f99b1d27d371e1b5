"""Timing a certified joint path within the robot's motion limits, on the path itself.

The path (k, n) [rad] is a polyline the planner certified. It is cut into points at most
`max_step` [rad] apart in every joint (every vertex kept), so a controller that
interpolates between consecutive points linearly never leaves the polyline, and one
that takes continuous joints the short way round takes the certified way.

Timing is TOPP-RA's (Pham & Pham, IEEE T-RO 2018; the `toppra` library): time-optimal
along a GIVEN path under per-joint velocity and acceleration bounds, so the geometry
stays the certified one. TOPP-RA runs on a cubic spline through the points (it needs a
path with two derivatives) and is sampled at the points only: the positions sent are the
polyline's, the velocities and accelerations the spline's tangent times the path speed.
TOPP-RA bounds neither jerk nor the rates between its grid points; so the result is
checked at the points sent (the published rates and the finite differences a
controller sees: Δq/Δt, Δv/Δt, Δa/Δt), and slowed down uniformly (time × k scales
velocity by 1/k, acceleration by 1/k², jerk by 1/k³) until every check holds. The
trajectory starts at rest at the path's first point and ends at rest at its last, and
it stops where the path turns back (two segments more than 90° apart, as a recovery's
last steps may): each stretch between such turns is timed on its own. A spline through
such a turn loops, and TOPP-RA crawled over it (a 0.03 rad end of a recovery on
crowded_sheets_100 took 190 s).

`braking_speed_scaling` says how much slower a timing must run for every lock on it to
brake inside a certified box (collision/braking.py): the planner reports it as
stats['max_safe_speed'], the executor slows the nominal path's command by it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ..collision.braking import max_safe_speed, segment_speeds
from ..collision.checker import CollisionChecker
from ..model.motion_limits import MotionLimits
from ..model.paths import densify

DEFAULT_MAX_STEP = 0.05      # [rad] farthest any joint moves between two points
_RELATIVE_SLACK = 1e-6       # the checks' numerical tolerance, relative to each limit
_SHORTEST = 1e-9             # [rad] points closer than this are one point (as _SAME)
_SAME = 1e-9                 # [rad] a cut point this close to a vertex is the vertex
_FEWEST_STEPS = 8            # grid intervals of the shortest path
_MOST_SPLITS = 8             # cuts of a crawling stretch, before it stops at every vertex

logging.getLogger('toppra').setLevel(logging.WARNING)


@dataclass(frozen=True, eq=False)
class TimedPath:
    """Points (k, n) at `times` (k,) [s] from 0.

    `positions` [rad], `velocities` [rad/s], `accelerations` [rad/s²].
    """

    positions: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    times: np.ndarray


def time_within_limits(path: np.ndarray, limits: MotionLimits, max_step: float = DEFAULT_MAX_STEP,
              ) -> TimedPath:
    """Time the polyline `path` (k, n) [rad] within `limits` (see the module docstring)."""
    stretches = _split_where_it_turns_back(np.asarray(path, dtype=float))
    return _one_after_another([_time_without_crawling(stretch, limits, max_step, _MOST_SPLITS)
                               for stretch in stretches], limits)


def _one_after_another(timed: list[TimedPath], limits: MotionLimits) -> TimedPath:
    """Join timings, each from rest to rest, that end where the next starts."""
    if len(timed) == 1:
        return timed[0]
    ends = np.cumsum([0.0] + [part.times[-1] for part in timed[:-1]])
    joined = TimedPath(*(np.concatenate([getattr(timed[0], name)[:1]] + [
        getattr(part, name)[1:] for part in timed]) for name in ('positions', 'velocities',
                                                                 'accelerations')),
        np.concatenate([timed[0].times[:1]] + [part.times[1:] + end
                                               for part, end in zip(timed, ends, strict=True)]))
    return _slowed_to_limits(joined, limits)  # the joints' jerk across each stop


def _time_without_crawling(stretch: np.ndarray, limits: MotionLimits, max_step: float,
                           splits: int) -> TimedPath:
    """TOPP-RA's timing of a stretch (k, n) that does not turn back, unless stopping is faster.

    Where the stretch turns sharply at vertices close together, the spline through them
    bends so much that TOPP-RA may crawl (the last 0.003 rad of a crowded_sheets_100
    recovery took 36 s). A timing slower than the least time of stopping at every vertex
    crawls somewhere: the stretch is then also timed as two, stopping at the vertex
    nearest the slowest step (each part checked again, `splits` more times at most;
    then stopping at every vertex), and the faster timing is kept.
    """
    timed = _time_stretch(stretch, limits, max_step)
    vertices = _distinct(stretch)
    if len(vertices) <= 2 or timed.times[-1] <= _least_time_stopping_at_vertices(vertices,
                                                                                  limits):
        return timed
    if splits == 0:
        parts = [vertices[i:i + 2] for i in range(len(vertices) - 1)]
    else:
        slowest = int(np.argmax(np.diff(timed.times)))
        crawl = 0.5 * (timed.positions[slowest] + timed.positions[slowest + 1])
        at = 1 + int(np.argmin(np.max(np.abs(vertices[1:-1] - crawl), axis=1)))
        parts = [vertices[:at + 1], vertices[at:]]
    split = _one_after_another([_time_without_crawling(part, limits, max_step, splits - 1)
                                for part in parts], limits)
    return split if split.times[-1] < timed.times[-1] else timed


def _least_time_stopping_at_vertices(vertices: np.ndarray, limits: MotionLimits) -> float:
    """Least time [s] of the polyline (k, n) moving from rest to rest along each segment.

    A straight segment's fastest rest-to-rest motion under velocity and acceleration
    bounds is a trapezoid of the path speed (jerk would only make it slower).
    """
    total = 0.0
    for step in np.abs(np.diff(vertices, axis=0)):
        moving = step > 0.0
        speed = float(np.min(limits.velocity[moving] / step[moving]))      # [1/s] of the segment
        rate = float(np.min(limits.acceleration[moving] / step[moving]))  # [1/s²]
        total += 2.0 * np.sqrt(1.0 / rate) if speed * speed >= rate else 1.0 / speed + speed / rate
    return total


def _split_where_it_turns_back(path: np.ndarray) -> list[np.ndarray]:
    """Cut the polyline (k, n) at each vertex where it turns by more than 90 degrees."""
    points = _distinct(path) if len(path) > 1 else path
    steps = np.diff(points, axis=0)
    turns = np.flatnonzero(np.sum(steps[:-1] * steps[1:], axis=1) < 0.0) + 1
    cuts = np.concatenate([[0], turns, [len(points) - 1]])
    return [points[a:b + 1] for a, b in zip(cuts[:-1], cuts[1:], strict=True)] \
        if len(turns) else [path]


def _time_stretch(path: np.ndarray, limits: MotionLimits, max_step: float) -> TimedPath:
    """`time_within_limits` for a path (k, n) that does not turn back."""
    # TOPP-RA starts and ends at rest on grid points: a path of one step would get no
    # speed at all, so every path gets at least _FEWEST_STEPS.
    span = float(np.sum(np.max(np.abs(np.diff(path, axis=0)), axis=1))) if len(path) > 1 else 0.0
    # Not below 2 _SHORTEST: cut points closer than that would be merged, end and all.
    step = min(max_step, max(span / _FEWEST_STEPS, 2.0 * _SHORTEST)) if span > 0.0 else max_step
    points = _distinct(densify(path, step))
    n = points.shape[1]
    if len(points) < 2:
        zero = np.zeros((1, n))
        return TimedPath(points[:1].copy(), zero, zero.copy(), np.zeros(1))
    ss = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])
    spline, (sdd, sd) = _parameterize(ss, points, limits)
    if sd is None:
        raise RuntimeError('TOPP-RA found no timing of the path within the limits')
    sd = np.maximum(np.asarray(sd, dtype=float), 0.0)
    if not np.all(sd[1:-1] > 0.0):
        raise RuntimeError('TOPP-RA stops the path between its ends')
    sdd = np.append(np.asarray(sdd, dtype=float), 0.0)
    steps = 2.0 * np.diff(ss) / np.maximum(sd[:-1] + sd[1:], 1e-300)
    times = np.concatenate([[0.0], np.cumsum(steps)])
    tangent, curvature = spline(ss, 1), spline(ss, 2)
    velocities = tangent * sd[:, None]
    accelerations = tangent * sdd[:, None] + curvature * (sd ** 2)[:, None]
    velocities[[0, -1]] = 0.0
    accelerations[-1] = 0.0
    return _slowed_to_limits(TimedPath(points, velocities, accelerations, times), limits)


def _parameterize(ss: np.ndarray, points: np.ndarray, limits: MotionLimits):
    """Return TOPP-RA's spline of `points` at path positions `ss`, and (s'', s') on them."""
    # Imported here: toppra imports matplotlib.pyplot, which the core must not load.
    import toppra
    import toppra.algorithm
    import toppra.constraint
    spline = toppra.SplineInterpolator(ss, points)
    constraints = [
        toppra.constraint.JointVelocityConstraint(np.column_stack([-limits.velocity,
                                                                   limits.velocity])),
        toppra.constraint.JointAccelerationConstraint(np.column_stack([-limits.acceleration,
                                                                       limits.acceleration])),
    ]
    solver = toppra.algorithm.TOPPRA(constraints, spline, gridpoints=ss)
    sdd, sd, _, _ = solver.compute_parameterization(0.0, 0.0, return_data=True)
    return spline, (sdd, sd)


def limit_ratios(timed: TimedPath, limits: MotionLimits) -> tuple[float, float, float]:
    """Return the largest |velocity|, |acceleration|, |jerk| over their limits of the points.

    Each counts the published rates and the finite differences between points (Δq/Δt,
    and Δv/Δt, Δa/Δt of the published rates); jerk 0 where no joint has a jerk limit.
    """
    dt = np.diff(timed.times)[:, None]
    velocity = max(_ratio(timed.velocities, limits.velocity),
                   _ratio(np.diff(timed.positions, axis=0) / dt, limits.velocity))
    acceleration = max(_ratio(timed.accelerations, limits.acceleration),
                       _ratio(np.diff(timed.velocities, axis=0) / dt, limits.acceleration))
    jerk = _ratio(np.diff(timed.accelerations, axis=0) / dt, limits.jerk)
    return velocity, acceleration, jerk


def slowed(timed: TimedPath, factor: float) -> TimedPath:
    """Return the same points `factor` (>= 1) times slower: v / factor, a / factor²."""
    return TimedPath(timed.positions, timed.velocities / factor,
                     timed.accelerations / factor ** 2, timed.times * factor)


def at_speed(timed: TimedPath, speed: float) -> TimedPath:
    """Return `timed` run at `speed` (0, 1] of its own speed (a braking_speed_scaling)."""
    if not 0.0 < speed <= 1.0:
        raise ValueError(f'speed must be in (0, 1], got {speed}')
    return slowed(timed, 1.0 / speed) if speed < 1.0 else timed


def at_vertices(timed: TimedPath, path: np.ndarray) -> TimedPath:
    """Return the points of `timed`, a timing of `path` (k, n) [rad], at `path`'s vertices.

    The positions are `path`'s own numbers (the timing's cut points may differ from them
    in the last bit). A vertex that repeats the one before keeps its time: the times
    are then not strictly increasing. The finite differences between vertices are means
    of the timing's own, so they keep its limits; the steps between them do not.
    """
    path = np.asarray(path, dtype=float)
    indices, start = [], 0
    for vertex in path:
        at = np.flatnonzero(np.max(np.abs(timed.positions[start:] - vertex), axis=1) <= _SAME)
        if not len(at):
            raise ValueError(f'vertex {vertex.tolist()} is not among the timed points')
        start += int(at[0])
        indices.append(start)
    return TimedPath(path.copy(), timed.velocities[indices], timed.accelerations[indices],
                     timed.times[indices])


def braking_speed_scaling(checker: CollisionChecker, timed: TimedPath,
                          deceleration: np.ndarray, margin: float = 0.0) -> float:
    """Return the largest speed scaling (at most 1) whose braking boxes certify on `timed`.

    A lock anywhere on it then brakes, at `deceleration` (n,) [rad/s²], inside a
    certified box (collision/braking.py). 0 when no speed is certified; 1 when the
    timing's own speeds are.
    """
    speeds = segment_speeds(timed.positions, timed.velocities, timed.times) \
        if len(timed.times) > 1 else np.zeros((0, timed.positions.shape[1]))
    return min(1.0, max_safe_speed(checker, timed.positions, speeds, deceleration, margin,
                                   cap=1.0))


def _slowed_to_limits(timed: TimedPath, limits: MotionLimits) -> TimedPath:
    """Stretch time uniformly by the least factor k >= 1 after which every ratio is <= 1."""
    velocity, acceleration, jerk = limit_ratios(timed, limits)
    k = max(velocity, float(np.sqrt(acceleration)), float(np.cbrt(jerk)))
    return timed if k <= 1.0 else slowed(timed, k * (1.0 + _RELATIVE_SLACK))


def _ratio(values: np.ndarray, limit: np.ndarray) -> float:
    if values.size == 0:
        return 0.0
    return float(np.max(np.abs(values) / limit))


def _distinct(points: np.ndarray) -> np.ndarray:
    """Drop points that repeat the one before (TOPP-RA needs a strictly increasing grid)."""
    keep = np.concatenate([[True], np.linalg.norm(np.diff(points, axis=0), axis=1) > _SHORTEST])
    return points[keep]
