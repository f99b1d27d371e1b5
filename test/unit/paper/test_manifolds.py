"""Steps 1-2: traced self-motion manifolds against exact inverse kinematics."""

import numpy as np
import pytest
from ftplan_testing import jacobian, robot_config

from ftplan_ros.core.collision.checker import CollisionChecker
from ftplan_ros.core.model.angles import configuration_difference
from ftplan_ros.core.model.robot import PlanarChain, task_errors
from ftplan_ros.core.model.scene import Obstacle
from ftplan_ros.core.paper.manifolds import (
    ManifoldCache,
    ManifoldOptions,
    mark_obstacle_free,
    project_many,
    project_to_preimage,
    self_motion_path,
    trace_self_motion_manifolds,
)

ARM = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'))


def exact_ik(x, theta1):
    """Every (θ2, θ3) of the 3R arm with θ1 fixed that reaches x: 2R inverse kinematics."""
    elbow = np.array([np.cos(theta1), np.sin(theta1)])
    d = x - elbow
    r = np.linalg.norm(d)
    if r > 2.0 or r < 1e-9:
        return []
    bend = np.arccos(np.clip(r * r / 2.0 - 1.0, -1.0, 1.0))  # links of 1 m
    out = []
    for sign in (1.0, -1.0):
        a2 = np.arctan2(d[1], d[0]) - sign * np.arctan2(np.sin(bend), 1.0 + np.cos(bend))
        out.append(np.array([theta1, a2 - theta1, sign * bend]))
    return out


def distance_to_branches(theta, branches):
    return min(np.min(np.linalg.norm(configuration_difference(b.points, theta, ARM.periodic),
                                     axis=1)) for b in branches)


@pytest.mark.parametrize('x, loops', [([2.0, 0.0], 1), ([2.5, 0.0], 1), ([0.3, 1.9], 1)])
def test_regular_positions_give_closed_loops_on_the_preimage(rng, x, loops):
    x = np.array(x)
    branches = trace_self_motion_manifolds(ARM, x, rng)
    assert len(branches) == loops
    for branch in branches:
        assert branch.closed
        assert np.abs(ARM.forward_kinematics(branch.points) - x).max() < 1e-9
        closing = branch.points[0] + branch.period - branch.points[-1]
        loop = np.vstack([branch.points, branch.points[:1] + branch.period])
        steps = np.linalg.norm(np.diff(loop, axis=0), axis=1)
        assert steps.max() <= ManifoldOptions().step_max * 1.5 + 1e-9
        assert np.linalg.norm(closing) <= ManifoldOptions().step_max


@pytest.mark.parametrize('x', [[2.0, 0.0], [2.5, 0.0], [1.0, 0.0], [0.3, 1.9]])
def test_every_exact_ik_solution_lies_on_a_traced_branch(rng, x):
    """Brute force: θ1 on a dense grid, exact 2R IK for the rest; nothing may be missed."""
    x = np.array(x)
    branches = trace_self_motion_manifolds(ARM, x, rng)
    step = ManifoldOptions().step_max
    checked = 0
    for theta1 in np.linspace(-np.pi, np.pi, 721):
        for theta in exact_ik(x, theta1):
            assert distance_to_branches(theta, branches) < step, np.degrees(theta)
            checked += 1
    assert checked > 300  # hundreds of solutions were compared (394 to 1440 here)


def test_the_papers_goal_is_a_critical_value_with_three_crossing_branches(rng):
    """x_g = [1, 0] is reached by folded, singular configurations: three loops cross there."""
    branches = trace_self_motion_manifolds(ARM, np.array([1.0, 0.0]), rng)
    assert len(branches) == 3
    assert all(b.closed for b in branches)
    # Link 2 folded back onto link 1 (θ2 = π) is a whole loop: link 3 points at the goal.
    folded = [b for b in branches if np.allclose(np.cos(b.points[:, 1]), -1.0)]
    assert len(folded) == 1
    assert np.allclose(np.abs(folded[0].period), [2 * np.pi, 0.0, 2 * np.pi])
    for singular in ([0.0, 0.0, np.pi], [0.0, np.pi, np.pi], [np.pi, np.pi, 0.0]):
        assert np.linalg.matrix_rank(jacobian(ARM, singular), tol=1e-9) == 1
        assert distance_to_branches(np.array(singular), branches) < 0.05


def test_free_arcs_follow_the_clearance(rng):
    branch = trace_self_motion_manifolds(ARM, np.array([2.0, 0.0]), rng)[0]
    checker = CollisionChecker(ARM, [Obstacle('sphere', (1.0, 1.0, 0.0), radius=0.3)])
    marked = mark_obstacle_free(branch, checker)
    free = marked.free()
    assert 0 < free.sum() < len(free)
    for first, count in marked.free_arcs():
        run = marked.arc_points(first, count)
        assert np.all(checker.min_clearance(run) > 0)
    assert sum(count for _, count in marked.free_arcs()) == free.sum()


def test_joint_limits_cut_loops_open(rng):
    arm = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'),
                      joint_limits=(None, (-2.0, 2.0), (-2.0, 2.0)))
    branches = trace_self_motion_manifolds(arm, np.array([1.0, 0.0]), rng)
    assert branches and not any(b.closed for b in branches)
    for b in branches:
        assert np.all(np.abs(b.points[:, 1:]) <= 2.0)


def test_projection_into_a_failure_plane_keeps_the_locked_joint(rng):
    solved_count = 0
    for theta in rng.uniform(-np.pi, np.pi, (20, 3)):
        solved = project_to_preimage(ARM, np.array([1.2, 0.4]), theta, fixed_joint=1)
        if solved is not None:
            assert solved[1] == theta[1]
            assert np.linalg.norm(ARM.forward_kinematics(solved) - [1.2, 0.4]) < 1e-10
            solved_count += 1
    # With θ2 fixed the point is out of reach only for θ2 within ~15° of π (links 1 and 2
    # then fold to less than |x| - 1 = 0.26 m): most starts must converge.
    assert solved_count >= 15


def test_seeds_that_are_not_finite_do_not_converge_and_leave_the_others_alone(rng):
    seeds = np.vstack([rng.uniform(-np.pi, np.pi, (6, 3)),
                       [[np.nan, 0.0, 0.0], [0.0, np.inf, 0.0], [0.0, 0.0, -np.inf]]])
    x = np.array([1.2, 0.4])
    solved, converged = project_many(ARM, x, seeds)
    alone, alone_converged = project_many(ARM, x, seeds[:6])
    assert not converged[6:].any()
    assert np.array_equal(converged[:6], alone_converged) and alone_converged.sum() >= 4
    assert np.array_equal(solved[:6], alone)
    assert project_many(ARM, x, np.empty((0, 3)))[1].shape == (0,)


def test_self_motion_path_joins_two_configurations(rng):
    x = np.array([2.0, 0.0])
    a = project_to_preimage(ARM, x, np.radians([10.0, -40.0, 50.0]))
    b = project_to_preimage(ARM, x, np.radians([-70.0, 110.0, -20.0]))
    path = self_motion_path(ARM, x, a, b)
    assert np.allclose(path[0], a) and np.allclose(path[-1], b)
    assert np.abs(ARM.forward_kinematics(path) - x).max() < 1e-9
    assert np.max(np.linalg.norm(np.diff(path, axis=0), axis=1)) <= ManifoldOptions().step_max * 1.5
    other = project_to_preimage(ARM, np.array([2.5, 0.0]), b)
    assert self_motion_path(ARM, x, a, other) is None  # not on the same manifold


def test_cache_returns_the_same_branches(rng):
    cache = ManifoldCache(size=1)
    first = cache.trace(ARM, np.array([2.0, 0.0]), rng)
    assert cache.trace(ARM, np.array([2.0, 0.0]), rng) is first
    cache.trace(ARM, np.array([1.0, 0.0]), rng)
    assert cache.trace(ARM, np.array([2.0, 0.0]), rng) is not first  # evicted


def test_a_pose_whose_first_seeds_all_miss_is_still_traced():
    """The goal of `ftplan bench --robot panda --seed 1`, task 8: a pose with a narrow preimage.

    Its first round of 48 random seeds (rng 13) converges nowhere; the rounds that follow
    find it. The search used to stop after a round without a branch, and the bench
    aborted with 'no configuration reaches it'.
    """
    robot = robot_config('panda', 'pose')
    x = np.array([-0.29639890554141124, 0.7541883054822759, 0.8004986419621284,
                  -0.032209690856453956, 0.4455253581950194, 0.8494597103693099,
                  -0.28086988353937015])
    one_round = ManifoldOptions(seed_rounds=1)
    assert not trace_self_motion_manifolds(robot, x, np.random.default_rng(13), one_round)
    branches = trace_self_motion_manifolds(robot, x, np.random.default_rng(13))
    assert branches
    assert np.max(task_errors(robot, x, branches[0].points)) < 1e-6
