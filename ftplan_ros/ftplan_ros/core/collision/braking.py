"""How fast a timed path may be run so that braking after a lock stays certified free.

When joint i locks at p while the arm moves at velocities v, every other joint j brakes
at its largest deceleration a_j and stops within d_j = v_j² / (2 a_j) of p_j, moving
monotonically; the straight move back to p keeps within the same reach. So the braking
motion and the return lie in the box p + [-d, d] (d_i = 0 for the locked joint; the box
with every d_j covers every choice of i). If every such box along the path is free, a
lock anywhere on it brakes to a stop without collision, and the arm is back at p, on
the nominal path and in the failure plane H_i, where the planner's recovery starts.

A box is certified by the lever-arm bound of certification.py: channel c's clearance at
a point exceeds Σ_a R[c, a] · (half-width of the box about it)_a. Between two points of
the path (a straight segment, speeds bounded by `speeds`) the boxes of all its points lie
in one box about the segment's middle, of half-width |Δθ|/2 + d. Scaling every speed by
s (times by 1/s) scales d by s², which gives the largest s per segment in closed form.
"""

from __future__ import annotations

import numpy as np

from ..model.paths import cumulative_fractions
from .checker import CollisionChecker

_ROUNDING = 1e-6  # [m] as certification.py: the rounding of a computed clearance


def braking_distances(speeds: np.ndarray, deceleration: np.ndarray) -> np.ndarray:
    """Return d (..., n) [rad]: how far joints at `speeds` [rad/s] go braking at `deceleration`.

    `deceleration` [rad/s²] is each joint's largest; d = v² / (2 a).
    """
    return np.square(speeds) / (2.0 * deceleration)


def segment_speeds(positions: np.ndarray, velocities: np.ndarray, times: np.ndarray,
                   ) -> np.ndarray:
    """Return (k-1, n) [rad/s]: a bound on each joint's speed on each segment of a timed path.

    The larger of the points' velocities and the segment's mean Δθ/Δt (what a controller
    interpolating linearly moves at).
    """
    mean = np.abs(np.diff(positions, axis=0)) / np.diff(times)[:, None]
    ends = np.maximum(np.abs(velocities[:-1]), np.abs(velocities[1:]))
    return np.maximum(mean, ends)


def max_safe_speed(checker: CollisionChecker, positions: np.ndarray, speeds: np.ndarray,
                   deceleration: np.ndarray, margin: float = 0.0, max_depth: int = 6,
                   cap: float = np.inf) -> float:
    """Return the largest speed scaling s >= 0 whose braking boxes certify along the path.

    `positions` (k, n) [rad] is the path, `speeds` (k-1, n) [rad/s] bounds its joints'
    speeds per segment (`segment_speeds`), `deceleration` (n,) [rad/s²] the joints'
    braking. Run at s times its speeds (s < 1: slower), every lock brakes inside a box
    clear by more than `margin` [m]. A segment not clear enough for itself is halved, up
    to `max_depth` times; if it still is not, 0 (no speed is certified). inf when nothing
    moves. Scalings above `cap` need no exact answer: the clearance is measured only as
    far as `cap` needs (checker.py `needed`), and any result >= `cap` stands for all.
    """
    positions = np.asarray(positions, dtype=float)
    if len(positions) < 2:
        return np.inf
    arms = checker.lever_arms()
    low, high = positions[:-1], positions[1:]
    reach = braking_distances(np.asarray(speeds, dtype=float), deceleration)
    best = np.inf
    for depth in range(max_depth + 1):
        centres = 0.5 * (low + high)
        segment = (0.5 * np.abs(high - low)) @ arms.T                                 # (S, C)
        braking = reach @ arms.T                                                      # (S, C)
        needed = margin + _ROUNDING + segment + min(cap, 1e6) ** 2 * braking
        clearance = checker.clearance(centres, needed=needed)
        room = clearance - margin - _ROUNDING - segment
        tight = np.any(~(room > 0.5 * (clearance - margin - _ROUNDING)), axis=1)
        if depth < max_depth and np.any(tight):
            ok = ~tight
            best = min(best, _scaling(room[ok], braking[ok]))
            low, high, reach = (np.concatenate([low[tight], centres[tight]]),
                                np.concatenate([centres[tight], high[tight]]),
                                np.concatenate([reach[tight], reach[tight]]))
            continue
        return min(best, _scaling(room, braking))
    return best


def _scaling(room: np.ndarray, braking: np.ndarray) -> float:
    """Return the largest s with s² · braking < room in every entry (0 where room <= 0)."""
    if room.size == 0:
        return np.inf
    if np.any(~(room > 0.0)):  # NaN clearance too
        return 0.0
    with np.errstate(divide='ignore'):
        squared = np.where(braking > 0.0, room / braking, np.inf)
    return float(np.sqrt(np.min(squared)))


def lock_point(positions: np.ndarray, speeds: np.ndarray, deceleration: np.ndarray,
               q: np.ndarray, joint: int, tolerance: float = 0.0) -> np.ndarray | None:
    """Return where on the path (k, n) the arm braked to q (n,) from, with `joint` locked.

    The point p of the path with p[joint] = q[joint] whose segment's braking box
    (`max_safe_speed`: the segment widened by d of its `speeds` (k-1, n) at
    `deceleration`) holds q, the nearest to q; None if no box holds q. The straight move
    from q back to p lies in that box: certified when the box is. A brake that holds the
    joint up to `tolerance` [rad] beyond a segment's range of it (a real brake slips; a
    physics sim's does) still finds that segment: p is then its nearest end in that joint,
    that far off the path (as `recover`'s `max_offset` allows).
    """
    a, b = positions[:-1], positions[1:]
    reach = braking_distances(np.asarray(speeds, dtype=float), deceleration)
    inside = np.all((q >= np.minimum(a, b) - reach) & (q <= np.maximum(a, b) + reach), axis=1)
    best, nearest = None, np.inf
    for k, _, p in _points_at_level(positions, q, joint, tolerance):
        gap = float(np.max(np.abs(q - p)))
        if inside[k] and gap < nearest:
            best, nearest = p, gap
    return best


def point_at_level(positions: np.ndarray, q: np.ndarray, joint: int, tolerance: float,
                   reach: float, near: float) -> np.ndarray | None:
    """Return the point p of the path (k, n) [rad] with p[joint] = q[joint] nearest `near`.

    Nearest along the path to its fraction `near` (0..1), among the points within
    `reach` [rad] of q (n,) in every joint; None when there is none. A segment reaches
    the level up to `tolerance` [rad] beyond its range, as in `lock_point`. Unlike
    `lock_point`, p need not hold q in a braking box: the move from q to p is then the
    caller's to certify.
    """
    fractions = cumulative_fractions(positions)
    best, nearest = None, np.inf
    for k, share, p in _points_at_level(positions, q, joint, tolerance):
        along = abs(fractions[k] + share * (fractions[k + 1] - fractions[k]) - near)
        if float(np.max(np.abs(q - p))) <= reach and along < nearest:
            best, nearest = p, along
    return best


def _points_at_level(positions: np.ndarray, q: np.ndarray, joint: int, tolerance: float):
    """Yield (segment k, share along it, point (n,)) where the path (k, n) has q's `joint`."""
    a, b = positions[:-1], positions[1:]
    level = q[joint]
    low = np.minimum(a[:, joint], b[:, joint]) - tolerance
    high = np.maximum(a[:, joint], b[:, joint]) + tolerance
    for k in np.flatnonzero((low <= level) & (level <= high)):
        rise = b[k, joint] - a[k, joint]
        share = 0.0 if rise == 0.0 else min(1.0, max(0.0, (level - a[k, joint]) / rise))
        p = a[k] + share * (b[k] - a[k])
        p[joint] = level
        yield int(k), share, p
