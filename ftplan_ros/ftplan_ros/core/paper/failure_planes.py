"""Steps 3 and 4 of the paper: failure hyperplanes, the necessary condition and the hypercube.

A joint i locked at θ_s confines the arm to the failure hyperplane H_i(θ_s) = {θ | θ_i =
θ_s,i} (paper eq. 2). θ_s is feasible when every H_i meets the obstacle-free goal manifold
M_g^F (eq. 6). On a traced branch, H_i crosses the curve where the wrapped difference
θ_i - θ_s,i changes sign between neighbouring points; the exact intersection then comes
from Newton in H_i, which for r = 1 is the square inverse kinematics of the arm with
joint i fixed (for a planar 3R arm, exact 2R inverse kinematics in the plane).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numba
import numpy as np

from ..model.angles import wrap_angle, wrap_one
from ..model.robot import Robot
from .manifolds import SelfMotionManifold, project_to_preimage


@dataclass(frozen=True)
class FreeArc:
    """A run of obstacle-free points of a goal branch: `count` points from index `first`.

    A window of the arc must start within its first `lap` points (less than `count` only
    for a free loop given as two laps, whose windows past one lap repeat).
    """

    branch: int
    first: int
    count: int
    lap: int


@dataclass(frozen=True, eq=False)
class FailurePlaneHit:
    """A configuration of H_i(θ_s) ∩ M_g^F.

    `theta` (n,) [rad] is lifted like the arc's points; `position` is its place along the
    arc in units of arc points (k + fraction: between arc points k and k+1).
    """

    joint: int
    theta: np.ndarray
    position: float


def goal_free_arcs(goal_branches: tuple[SelfMotionManifold, ...], margin: float,
                   ) -> list[FreeArc]:
    """Every maximal obstacle-free run of every goal branch (M_g^F in pieces).

    A closed branch free all round has no ends: it comes as two laps from wherever its
    tracing began, so that a window of hits may straddle that arbitrary point.
    """
    arcs = []
    for b, branch in enumerate(goal_branches):
        for first, count in branch.free_arcs(margin):
            if branch.closed and count == len(branch):
                arcs.append(FreeArc(b, first, 2 * count, count))
            elif count >= 2:
                arcs.append(FreeArc(b, first, count, count))
    return arcs


def crossing_segments(values: np.ndarray, levels: np.ndarray, periodic: bool,
                      first_only: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Where levels (C,) cross the sampled curve values (K,) [rad]: pairs (level, segment).

    Segment k joins samples k and k+1; the pairs (H,) each come level by level, segments in
    order, and with `first_only` only each level's first crossing. For a periodic joint the
    difference is wrapped, and a jump across ±π between neighbours is not a crossing
    (neighbours are close).
    """
    return _crossings(np.ascontiguousarray(values, dtype=float),
                      np.ascontiguousarray(levels, dtype=float), bool(periodic), first_only)


# Beyond this size [rad] of an angle, or of a step between neighbours, a segment's levels
# are not looked up among the sorted ones but all tested: the lookup's slack
# (_LOOKUP_SLACK [rad]) bounds the rounding of the wrap only for angles this small.
_LOOKUP_RANGE = 1e6
_LOOKUP_SLACK = 1e-6


@numba.njit(cache=True, inline='always')
def _crosses(value_before, value_after, level, periodic):
    """Whether the level lies between two neighbouring samples (the definition, exactly)."""
    before, after = value_before - level, value_after - level
    if periodic:
        before, after = wrap_one(before), wrap_one(after)
    return (before < 0.0) != (after < 0.0) and (not periodic or abs(after - before) < np.pi)


@numba.njit(cache=True)
def _crossings(values, levels, periodic, first_only):
    """`crossing_segments` in one compiled pass over the segments.

    Each segment tests only the levels that may lie between its ends: those whose
    (wrapped) value falls within its range, widened by a slack that covers the rounding
    of the wrap, found in the sorted levels. Levels, segments and angles too large for
    that bound are tested against everything, so the pairs are those of the definition.
    """
    count, n_levels = values.shape[0], levels.shape[0]
    keys = np.empty(n_levels)
    for c in range(n_levels):
        keys[c] = wrap_one(levels[c]) if periodic else levels[c]
    wild = np.flatnonzero(~(np.abs(levels) <= _LOOKUP_RANGE))  # NaN too
    keys[wild] = np.inf
    order = np.argsort(keys)
    tame = n_levels - wild.shape[0]
    keys = keys[order[:tame]]
    pairs = []
    for k in range(count - 1):
        a, b = values[k], values[k + 1]
        low, high = min(a, b) - _LOOKUP_SLACK, max(a, b) + _LOOKUP_SLACK
        if not (abs(a) <= _LOOKUP_RANGE and abs(b) <= _LOOKUP_RANGE) or \
                (periodic and high - low >= np.pi):
            for c in range(n_levels):
                if _crosses(a, b, levels[c], periodic):
                    pairs.append(c * count + k)
            continue
        # A wrapped level w in (-π, π] stands for w + 2πm: the m that reach the range,
        # and one more turn each side for a w rounded just past ±π.
        turns_low, turns_high = 0, 0
        if periodic:
            turns_low = int(np.floor((low - np.pi) / (2.0 * np.pi))) - 1
            turns_high = int(np.ceil((high + np.pi) / (2.0 * np.pi))) + 1
        for m in range(turns_low, turns_high + 1):
            shift = 2.0 * np.pi * m
            first = np.searchsorted(keys, low - shift)
            last = np.searchsorted(keys, high - shift, side='right')
            for j in range(first, last):
                c = order[j]
                if _crosses(a, b, levels[c], periodic):
                    pairs.append(c * count + k)
        for c in wild:
            if _crosses(a, b, levels[c], periodic):
                pairs.append(c * count + k)
    codes = np.sort(np.array(pairs, dtype=np.int64))
    which, segment = codes // max(count, 1), codes % max(count, 1)
    if first_only and codes.shape[0]:
        first = np.ones(codes.shape[0], dtype=np.bool_)
        first[1:] = which[1:] != which[:-1]
        which, segment = which[first], segment[first]
    return which, segment


def necessary_condition(robot: Robot, candidates: np.ndarray, arc_points: np.ndarray,
                        joints: Sequence[int]) -> np.ndarray:
    """Step 3 for many θ_s at once: (C, J) bool, H_i(θ_s) crosses the free arc (a, n).

    Column k is joint `joints[k]` (the tolerated joints).
    """
    periodic = robot.periodic
    out = np.zeros((len(candidates), len(joints)), dtype=bool)
    for k, i in enumerate(joints):
        which, _ = crossing_segments(arc_points[:, i], candidates[:, i], periodic[i],
                                     first_only=True)
        out[which, k] = True
    return out


def chord_crossings(robot: Robot, candidates: np.ndarray, arc_points: np.ndarray, joint: int,
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where H_joint(θ_s) of many θ_s (C, n) crosses the arc's chords, all at once.

    Returns, per crossing, the candidate index (H,), its position along the arc (H,) in
    units of arc points, and the chord point (H, n) [rad] with θ_joint = θ_s,joint exactly
    (lifted like the arc).
    """
    periodic = bool(robot.periodic[joint])
    values = arc_points[:, joint]
    which, segment = crossing_segments(values, candidates[:, joint], periodic)
    before = values[segment] - candidates[which, joint]
    if periodic:
        before = wrap_angle(before)
    rise = values[segment + 1] - values[segment]
    fraction = np.clip(np.divide(-before, rise, out=np.zeros_like(rise), where=rise != 0.0),
                       0.0, 1.0)
    a, b = arc_points[segment], arc_points[segment + 1]
    points = a + fraction[:, None] * (b - a)
    points[:, joint] = values[segment] - before
    return which, segment + fraction, points


def failure_plane_hits(robot: Robot, x_goal: np.ndarray, theta_s: np.ndarray,
                       arc_points: np.ndarray, joints: Sequence[int],
                       tolerance: float = 1e-10) -> list[list[FailurePlaneHit]]:
    """Step 3 for one θ_s: for each joint i of `joints`, the points of H_i(θ_s) ∩ M_g on the arc.

    Each chord crossing (`chord_crossings`) is moved onto M_g by Newton in H_i; a
    refinement that leaves the chord's neighbourhood is dropped.
    """
    hits: list[list[FailurePlaneHit]] = []
    for i in joints:
        found = []
        _, positions, guesses = chord_crossings(robot, theta_s[None, :], arc_points, i)
        for position, guess in zip(positions, guesses, strict=True):
            k = min(int(position), len(arc_points) - 2)
            theta = project_to_preimage(robot, x_goal, guess, tolerance, fixed_joint=i)
            if theta is None or (np.linalg.norm(theta - guess)
                                 > np.linalg.norm(arc_points[k + 1] - arc_points[k])):
                continue
            found.append(FailurePlaneHit(i, theta, float(position)))
        hits.append(found)
    return hits


def failure_hypercube(theta_s: np.ndarray, goal_points: np.ndarray,
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Step 4: bounds (lower, upper) (n,) [rad] of V_sg around θ_s and the goal arc used.

    The bounding hyperplanes are the extremal points of the arc of M_g^F and the failure
    planes of θ_s (paper eqs. 3-5); both come out as the coordinate-wise extremes.
    """
    points = np.vstack([theta_s[None, :], goal_points])
    return points.min(axis=0), points.max(axis=0)
