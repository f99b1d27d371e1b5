"""The paper's surface search (core/planning/surface_search.py): fail-closed screens, fans,
joints held still."""

import numpy as np
import pytest
from ftplan_testing import SCENES

from ftplan_ros.core import (
    CollisionChecker,
    FailureSurface,
    ManifoldCache,
    PlannerOptions,
    load_scene,
    plan,
    task_errors,
)
from ftplan_ros.core.model.paths import densify
from ftplan_ros.core.paper.verification import verify_surface
from ftplan_ros.core.planning.drill import run_drill
from ftplan_ros.core.planning.surface_search import SurfaceSearch, straight_fans


class _NanChecker(CollisionChecker):
    """A checker whose clearances are all NaN, as a broken distance would give."""

    def clearance(self, thetas, needed=np.inf, refine=True):
        return np.full_like(super().clearance(thetas, needed, refine), np.nan)


def test_a_nan_clearance_reads_as_a_collision(fig3a):
    """The search's own screens of θ_s and of the web's vertices fail closed on NaN."""
    scene, result = fig3a
    search = SurfaceSearch(scene, PlannerOptions(), np.random.default_rng(0),
                           lambda line: None, ManifoldCache())
    webs = []
    build = search._fine_surface
    search._fine_surface = lambda *args: webs.append(args) or build(*args)
    assert search.run(result.theta_s).feasible and webs
    assert search._given_start(result.theta_s).shape == (1, 3)
    search.checker = _NanChecker(scene.robot, scene.obstacles)
    assert search._fine_surface(*webs[-1]) is None
    assert search._given_start(result.theta_s).shape == (0, 3)


def test_a_search_whose_webs_all_fail_to_build_says_so(fig3a):
    """When no fine web is clear at its vertices, no surface was checked: the reason says
    that, not that the check failed."""
    scene, _ = fig3a
    search = SurfaceSearch(scene, PlannerOptions(), np.random.default_rng(0),
                           lambda line: None, ManifoldCache())
    search._fine_surface = lambda *args: None
    result = search.run()
    assert not result.feasible
    assert 'best failure surfaces proposed reached the self-check' in result.reason
    assert 'check failed' not in result.reason


@pytest.mark.parametrize('n', [3, 7])
def test_ranking_fans_are_the_points_along_each_straight_path(n):
    """straight_fans (P, W, G, n) against start + w/W (goal - start), written with arrays."""
    rng = np.random.default_rng(2)
    starts, goals = rng.normal(size=(40, n)), rng.normal(size=(40, 6, n))
    steps = np.arange(1, 9)[None, :, None, None] / 8
    expected = starts[:, None, None, :] + steps * (goals[:, None] - starts[:, None, None, :])
    assert np.array_equal(straight_fans(starts, goals, 8), expected)


@pytest.fixture(scope='module')
def held_elbow():
    """The iiwa on a pose task that keeps the shoulder-wrist distance, every joint tolerated."""
    scene = load_scene(SCENES / 'iiwa_free_pose_held.yaml')
    return scene, plan(scene)


def test_an_elbow_with_one_angle_on_both_manifolds_is_held_still(held_elbow):
    scene, result = held_elbow
    assert result.feasible, result.reason
    assert result.tolerated_joints == tuple(range(7))
    assert result.stats['held_joints'] == ['iiwa_joint_4']
    surface = result.surface
    assert np.all(surface.paths[..., 3] == result.theta_s[3])  # the whole web, exactly
    assert surface.hit_paths[surface.tolerated.index(3)] == surface.nominal


def test_the_rest_of_the_nominal_path_recovers_every_lock_of_the_held_joint(held_elbow):
    """Brute force: densely sampled, the nominal path with the elbow fixed is clear and
    ends at the goal, so from every point of it the lock needs nothing more."""
    scene, result = held_elbow
    path = densify(result.nominal_path, 0.002)
    assert np.all(path[:, 3] == result.theta_s[3])
    checker = CollisionChecker(scene.robot, scene.obstacles)
    assert checker.min_clearance(path, 0.0).min() > 0.0
    assert scene.task.reached(task_errors(scene.robot, scene.task.goal, path[-1]))


def test_every_joints_lock_recovers_on_the_held_elbows_plan(held_elbow):
    """The drill, as brute force: locks of every joint at random moments recover."""
    scene, result = held_elbow
    trials = run_drill(scene, result, 300, np.random.default_rng(3))
    assert {t.joint for t in trials} == set(range(7))
    assert all(t.ok for t in trials), [t for t in trials if not t.ok][:1]


def test_a_web_that_moves_the_held_joint_fails_its_check(held_elbow):
    """The certificate covers the held joint as any other: nudge its angle at one nominal
    waypoint and the self-check refuses the web."""
    scene, result = held_elbow
    surface = result.surface
    paths = np.array(surface.paths)
    paths[surface.nominal, paths.shape[1] // 2, 3] += 1e-3
    tampered = FailureSurface(paths, surface.nominal, surface.hit_paths, surface.tolerated)
    checker = CollisionChecker(scene.robot, scene.obstacles)
    verdict = verify_surface(tampered, checker, scene.task)
    assert not verdict.ok
    assert 'θ_4' in verdict.reason or 'joint 4' in verdict.reason, verdict.reason


def test_a_search_for_other_joints_shares_the_traced_manifolds(fig3a):
    """The coverage search (planner.py) plans for fewer joints on the same manifolds."""
    scene, _ = fig3a
    search = SurfaceSearch(scene, PlannerOptions(), np.random.default_rng(0),
                           lambda line: None, ManifoldCache())
    traced = search.manifolds()
    other = search.for_joints([scene.robot.joint_names[2]])
    assert other.manifolds() is traced
    assert other.joints == (2,) and other.checker is search.checker
    assert other.run().tolerated_joints == (2,)


def test_a_six_joint_arms_tool_axis_task_turns_the_last_joint_alone():
    """The tool point on the last joint's axis: the self-motion of a tool axis turns that
    joint alone; it is tolerated, and asking for the others says which keep their angle."""
    scene = load_scene(SCENES / 'jaco2_free_axis.yaml')
    result = plan(scene)
    assert result.feasible, result.reason
    assert result.tolerated_joints == (5,)
    every = plan(scene.with_tolerated(None), PlannerOptions(coverage_attempts=0))
    assert not every.feasible
    assert f'{scene.robot.joint_names[0]} keeps its angle along each branch' in every.reason


def test_a_vertical_tool_holds_the_ur5es_wrist_2_still():
    """Pointing down at start and goal, wrist 2 is at -90 deg on M_s and M_g alike."""
    scene = load_scene(SCENES / 'ur5e_free_axis.yaml')
    result = plan(scene)
    assert result.feasible, result.reason
    assert result.stats['held_joints'] == ['wrist_2_joint']
    assert np.all(result.surface.paths[..., 4] == result.theta_s[4])
    assert np.isclose(result.theta_s[4], -np.pi / 2, atol=1e-6) or \
        np.isclose(result.theta_s[4], np.pi / 2, atol=1e-6)


def test_the_finer_round_is_skipped_only_when_none_of_its_starts_could_pass():
    """Brute force: when a joint's angles along M_s miss every free arc's, the finer
    round's starts are computed anyway and none passes eq. 6 for that joint."""
    from ftplan_ros.bench.spatial import random_task
    from ftplan_ros.core.paper.failure_planes import goal_free_arcs, necessary_condition
    rng = np.random.default_rng(0)
    random_task('iiwa14', rng)
    scene = random_task('iiwa14', rng)  # the spatial benchmark's second task
    search = SurfaceSearch(scene, PlannerOptions(), np.random.default_rng(1),
                           lambda line: None, ManifoldCache())
    result = search.run()
    assert not result.feasible and result.stats['candidate_subdivisions'] == 1
    M_s, M_g = search.manifolds()
    arcs = [M_g[a.branch].arc_points(a.first, a.count) for a in goal_free_arcs(M_g, 0.0)]
    beyond = search._out_of_reach_of_every_arc(M_s, arcs)
    joint = next(j for j in search.moving if scene.robot.joint_names[j] in beyond)
    finer = search._start_candidates(M_s, PlannerOptions().candidate_refinement)
    assert len(finer) > len(search._start_candidates(M_s, 1))
    assert not any(necessary_condition(scene.robot, finer, points, (joint,)).any()
                   for points in arcs)


def test_the_finer_round_is_kept_when_a_joints_angles_reach_an_arc():
    """The screen names a joint only when its range along M_s misses every arc's."""
    scene = load_scene(SCENES / 'iiwa_free_pose.yaml')
    search = SurfaceSearch(scene, PlannerOptions(), np.random.default_rng(0),
                           lambda line: None, ManifoldCache())
    M_s, _ = search.manifolds()
    search._hold_still(M_s, M_s)
    arcs = [branch.points for branch in M_s]
    assert search._out_of_reach_of_every_arc(M_s, arcs) == ''
    shifted = [points.copy() for points in arcs]
    for points in shifted:
        points[:, 2] += 10.0  # iiwa_joint_3's angles out of M_s's range (+-2.97 rad)
    assert 'iiwa_joint_3' in search._out_of_reach_of_every_arc(M_s, shifted)
