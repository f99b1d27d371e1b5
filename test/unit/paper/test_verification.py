"""The self-check: its certificates against brute force, and its refusals."""

import math
from dataclasses import replace

import numpy as np
import pytest
from ftplan_testing import paper_scene

from ftplan_ros.core import CollisionChecker, plan
from ftplan_ros.core.model.robot import PlanarChain
from ftplan_ros.core.model.scene import Obstacle, Task
from ftplan_ros.core.paper.failure_surface import FailureSurface
from ftplan_ros.core.paper.verification import (
    VerificationOptions,
    certify_surface,
    goal_row_error,
    structure_problem,
    verify_surface,
)

ARM = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'))
X_GOAL = np.array([1.0, 0.0])
GOAL_TASK = Task((2.0, 0.0), (1.0, 0.0), 0.01)


def test_a_web_of_one_path_is_certified_along_its_segments():
    """No triangle: S_F is the path itself, and a disk across it fails the certificate."""
    path = np.array([0.0, 0.5, 0.5]) + np.linspace(0.0, 1.0, 8)[:, None] * [0.0, 0.5, 0.7]
    surface = FailureSurface(path[None], 0, (0,), (0,))
    middle = ARM.joint_positions(path[4])[2]
    task = Task(tuple(ARM.joint_positions(path[0])[-1]), tuple(ARM.joint_positions(path[-1])[-1]))
    blocked = CollisionChecker(ARM, [Obstacle('sphere', (middle[0], middle[1], 0.0), radius=0.3)])
    assert not certify_surface(surface, blocked, task).ok
    assert certify_surface(surface, CollisionChecker(ARM, []), task).ok


def test_goal_row_bound_holds_against_dense_sampling():
    # The branches for [1, 0] are straight lines in joint space; the one for [2, 0] curves.
    from ftplan_ros.core.paper.manifolds import trace_self_motion_manifolds
    curved = 0
    for x in (X_GOAL, np.array([2.0, 0.0])):
        for branch in trace_self_motion_manifolds(ARM, x, np.random.default_rng(1)):
            for stride in (1, 5, 20):
                points = branch.points[::stride]
                bound = goal_row_error(ARM, Task(tuple(x), tuple(x)), points, samples=4)[0]
                t = np.linspace(0, 1, 200)[None, :, None]
                chords = points[:-1, None] + t * (points[1:, None] - points[:-1, None])
                true = np.linalg.norm(ARM.forward_kinematics(chords) - x, axis=-1).max()
                assert true <= bound
                if true > 1e-4:  # a curved branch: the bound is not uselessly loose
                    curved += 1
                    assert bound < 3 * true
    assert curved >= 2


def test_a_goal_row_of_several_sheets_leaves_the_chords_between_them_out():
    """Chords given: the bound over them is the largest of each sheet's own, a point on
    no chord counts alone, the chord between two sheets does not count, and a point
    that is not finite makes the bound NaN (the check then fails)."""
    x = np.asarray(X_GOAL, dtype=float)
    task = Task(tuple(x), tuple(x))
    rng = np.random.default_rng(4)
    for _ in range(50):
        points = rng.uniform(-np.pi, np.pi, (7, 3))
        sheets = [(0, 2), (3, 3), (4, 6)]
        chords = np.array([0, 1, 4, 5])
        each = max(goal_row_error(ARM, task, points[first:last + 1], 4)[0]
                   for first, last in sheets)
        assert goal_row_error(ARM, task, points, 4, chords)[0] == each
        # With the chords between the sheets too, the bound is no smaller.
        assert goal_row_error(ARM, task, points, 4)[0] >= each
    points[3, 1] = np.nan
    assert np.isnan(goal_row_error(ARM, task, points, 4, chords)[0])


@pytest.fixture(scope='module')
def free_plan():
    scene = paper_scene()
    return scene, plan(scene)


def test_structure_problems_are_named(free_plan):
    _, result = free_plan
    surface = result.surface
    assert structure_problem(surface) == ''
    bent = surface.paths.copy()
    bent[surface.nominal, 5, 0] += 0.5
    assert 'not monotonic' in structure_problem(replace(surface, paths=bent))
    off_plane = surface.paths.copy()
    k = surface.hit_paths[2]
    off_plane[k, 3, 2] += 1e-9
    assert 'H_3 hit leaves the failure plane' in structure_problem(replace(surface,
                                                                             paths=off_plane))
    moved = surface.paths.copy()
    moved[4, 0, 1] += 1e-12
    assert 'start at θ_s' in structure_problem(replace(surface, paths=moved))


def test_an_obstacle_across_the_surface_fails_the_check(free_plan):
    scene, result = free_plan
    surface = result.surface
    middle = surface.paths[len(surface.paths) // 2, surface.paths.shape[1] // 2]
    elbow = ARM.joint_positions(middle)[2]
    checker = CollisionChecker(ARM, [Obstacle('sphere', (elbow[0], elbow[1], 0.0), radius=0.05)])
    verdict = verify_surface(surface, checker, GOAL_TASK)
    assert not verdict.ok and 'not collision-free' in verdict.reason
    assert verify_surface(surface, CollisionChecker(ARM, []), GOAL_TASK).ok


def test_a_goal_row_off_the_goal_fails_the_check(free_plan):
    _, result = free_plan
    verdict = certify_surface(result.surface, CollisionChecker(ARM, []),
                              Task((2.0, 0.0), tuple(X_GOAL + [0.05, 0.0]), 0.01))
    assert not verdict.ok and 'goal row strays' in verdict.reason


@pytest.mark.parametrize('options', [
    {'margin': -0.3}, {'margin': math.nan}, {'chord_samples': 0}, {'recovery_moments': 0},
    {'max_depth': -1}])
def test_options_that_would_weaken_the_check_are_refused(options):
    with pytest.raises(ValueError):
        VerificationOptions(**options)
