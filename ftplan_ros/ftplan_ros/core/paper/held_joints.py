"""Joints held still: a tolerated joint whose angle is one value all along M_s and M_g.

On an arm with a spherical shoulder and wrist (S-R-S: the iiwa) the shoulder-wrist
distance fixes the elbow's angle, so for a 6-D pose the elbow keeps one value along each
branch of the self-motion. Its failure plane H_i(θ_s) then either holds a whole goal
branch (the same angle: a task that keeps the shoulder-wrist distance) or misses M_g
(paper eq. 6 fails), and the sign-change test of Step 3 cannot tell them apart: the
differences it compares are rounding noise.

Where the angles agree, the plan holds the joint at θ_s,i over the whole web: every web
path runs straight between points with θ_i = θ_s,i, so it keeps that value exactly, and
the nominal path serves as the joint's hit path (`FailureSurface.hit_paths`). A lock of
the joint anywhere on the nominal path then needs no recovery but the rest of the
nominal path, which the self-check proves like any other lock (verification.py: the hit
path keeps θ_i = θ_s,i exactly; it is certified collision-free and ends on the goal row).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..model.angles import wrap_angle
from .manifolds import SelfMotionManifold

# [rad] an angle varying less than this along a branch is one value (Newton's residuals
# of 1e-10 m move an elbow by about 1e-9 rad); two such values this close are the same.
HELD_TOLERANCE = 1e-6


def held_joints(start_branches: Sequence[SelfMotionManifold],
                goal_branches: Sequence[SelfMotionManifold],
                joints: Sequence[int]) -> tuple[int, ...]:
    """Find the joints of `joints` whose angle is constant along every branch of M_s and M_g."""
    branches = list(start_branches) + list(goal_branches)
    if not branches:
        return ()
    return tuple(j for j in joints
                 if all(np.ptp(branch.points[:, j]) <= HELD_TOLERANCE for branch in branches))


def same_angle(candidates: np.ndarray, arc_points: np.ndarray, joint: int,
               periodic: bool) -> np.ndarray:
    """Test eq. 6 for a held joint: (C,) bool, θ_s,joint of candidates (C, n) [rad] is the arc's.

    The arc (a, n) keeps the joint at one angle (`held_joints`); H_joint(θ_s) holds the
    arc exactly when θ_s has that angle too.
    """
    difference = candidates[:, joint] - np.median(arc_points[:, joint])
    if periodic:
        difference = wrap_angle(difference)
    return np.abs(difference) <= HELD_TOLERANCE
