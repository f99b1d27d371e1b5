"""Joints held still (core/paper/held_joints.py): which joints, and eq. 6 for them."""

import numpy as np

from ftplan_ros.core.paper.held_joints import HELD_TOLERANCE, held_joints, same_angle
from ftplan_ros.core.paper.manifolds import SelfMotionManifold


def _branch(rng, constant: dict[int, float]) -> SelfMotionManifold:
    """A branch of 50 random points (3 joints) with the given joints at fixed angles."""
    points = rng.uniform(-2.0, 2.0, (50, 3))
    for joint, value in constant.items():
        points[:, joint] = value + rng.uniform(-0.1, 0.1, 50) * HELD_TOLERANCE
    return SelfMotionManifold((0.0, 0.0), points, False, np.zeros(3))


def test_a_joint_is_held_only_when_constant_on_every_branch_of_both_manifolds(rng):
    start = (_branch(rng, {1: 0.7}), _branch(rng, {1: -0.7}))
    goal = (_branch(rng, {1: 0.7, 2: 0.1}),)
    assert held_joints(start, goal, (0, 1, 2)) == (1,)  # joint 2 moves on M_s
    assert held_joints(start, goal, (0, 2)) == ()       # joint 1 is not tolerated
    moving = (_branch(rng, {}),)
    assert held_joints(start, goal + moving, (0, 1, 2)) == ()
    assert held_joints((), (), (0, 1, 2)) == ()


def test_a_held_joint_passes_eq_6_only_at_the_arcs_angle(rng):
    arc = _branch(rng, {1: 0.7}).points
    candidates = np.zeros((5, 3))
    candidates[:, 1] = [0.7, 0.7 + 0.5 * HELD_TOLERANCE, 0.7 + 2 * HELD_TOLERANCE, -0.7, np.nan]
    assert same_angle(candidates, arc, 1, periodic=False).tolist() == [
        True, True, False, False, False]


def test_a_periodic_held_joint_compares_angles_round_the_circle(rng):
    arc = _branch(rng, {0: np.pi - 1e-8}).points
    candidates = np.array([[-np.pi + 1e-8, 0.0, 0.0], [np.pi - 1e-8 - 2 * np.pi, 0.0, 0.0],
                           [0.0, 0.0, 0.0]])
    assert same_angle(candidates, arc, 0, periodic=True).tolist() == [True, True, False]
    assert same_angle(candidates, arc, 0, periodic=False).tolist() == [False, False, False]
