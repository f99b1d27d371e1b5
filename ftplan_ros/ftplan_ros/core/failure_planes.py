"""Steps 3 and 4 of the paper: failure hyperplanes, the necessary condition and the hypercube.

A joint i locked at θ_s confines the arm to the failure hyperplane H_i(θ_s) = {θ | θ_i =
θ_s,i} (paper eq. 2). θ_s is feasible when every H_i meets the obstacle-free goal manifold
M_g^F (eq. 6). On a traced branch, H_i crosses the curve where the wrapped difference
θ_i - θ_s,i changes sign between neighbouring points; the exact intersection then comes
from Newton in H_i, which for r = 1 is the square inverse kinematics of the arm with
joint i fixed (for a planar 3R arm, exact 2R inverse kinematics in the plane).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .angles import wrap_angle
from .manifolds import SelfMotionManifold, project_to_preimage
from .robot import Robot


@dataclass(frozen=True)
class FreeArc:
    """A run of obstacle-free points of a goal branch: `count` points from index `first`."""

    branch: int
    first: int
    count: int


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
    """Every maximal obstacle-free run of every goal branch (M_g^F in pieces)."""
    return [FreeArc(b, first, count)
            for b, branch in enumerate(goal_branches)
            for first, count in branch.free_arcs(margin) if count >= 2]


def crossing_segments(values: np.ndarray, levels: np.ndarray, periodic: bool) -> np.ndarray:
    """Where levels (C,) cross the sampled curve values (K,) [rad]: bool (C, K-1).

    Segment k joins samples k and k+1. For a periodic joint the difference is wrapped, and
    a jump across ±π between neighbours is not a crossing (neighbours are close).
    """
    diff = values[None, :] - levels[:, None]
    if periodic:
        diff = wrap_angle(diff)
    below = diff < 0.0
    change = below[:, :-1] != below[:, 1:]
    if periodic:
        change &= np.abs(diff[:, 1:] - diff[:, :-1]) < np.pi
    return change


def necessary_condition(robot: Robot, candidates: np.ndarray, arc_points: np.ndarray,
                        ) -> np.ndarray:
    """Step 3 for many θ_s at once: (C, n) bool, H_i(θ_s) crosses the free arc (a, n)."""
    periodic = robot.periodic
    return np.stack([crossing_segments(arc_points[:, i], candidates[:, i], periodic[i]).any(axis=1)
                     for i in range(robot.n_joints)], axis=1)


def failure_plane_hits(robot: Robot, x_goal: np.ndarray, theta_s: np.ndarray,
                       arc_points: np.ndarray, refine: bool = True, tolerance: float = 1e-10,
                       ) -> list[list[FailurePlaneHit]]:
    """Step 3 for one θ_s: for each joint i, the points of H_i(θ_s) on the arc (a, n).

    Each crossing segment of the arc gives the point of its chord with θ_i = θ_s,i; with
    `refine` that point is moved onto M_g exactly by Newton in H_i, and a refinement that
    leaves the segment's neighbourhood is dropped.
    """
    periodic = robot.periodic
    hits: list[list[FailurePlaneHit]] = []
    for i in range(robot.n_joints):
        found = []
        level = np.array([theta_s[i]])
        for k in np.flatnonzero(crossing_segments(arc_points[:, i], level, periodic[i])[0]):
            a, b = arc_points[k], arc_points[k + 1]
            da = wrap_angle(a[i] - theta_s[i]) if periodic[i] else a[i] - theta_s[i]
            db = da + (b[i] - a[i])
            fraction = da / (da - db) if da != db else 0.0
            guess = a + fraction * (b - a)
            guess[i] = a[i] - da  # exactly θ_s,i, lifted like the arc
            theta = guess
            if refine:
                theta = project_to_preimage(robot, x_goal, guess, tolerance, fixed_joint=i)
                if theta is None or np.linalg.norm(theta - guess) > np.linalg.norm(b - a):
                    continue
            found.append(FailurePlaneHit(i, theta, k + float(np.clip(fraction, 0.0, 1.0))))
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
