"""The planner end to end: a trivial, the paper's, and impossible cases; bad input; brute force."""

import numpy as np
import pytest
from ftplan_testing import SCENES, paper_scene

from ftplan_ros.core import (
    CollisionChecker,
    InputError,
    ManifoldCache,
    PlannerOptions,
    load_scene,
    parse_scene,
    plan,
    recover,
    task_errors,
)
from ftplan_ros.core.grid.exhaustive import recoverable_in_plane
from ftplan_ros.core.model.paths import densify, point_at_fraction
from ftplan_ros.core.model.scene import Obstacle, Task
from ftplan_ros.core.planning.surface_search import SurfaceSearch, straight_fans

X_GOAL = np.array([1.0, 0.0])


@pytest.fixture(scope='module')
def fig3a():
    scene = load_scene(SCENES / 'fig3a.yaml')
    return scene, plan(scene)


def test_obstacle_free_paper_task_is_feasible_and_reported():
    scene = paper_scene()
    result = plan(scene)
    assert result.feasible and result.reason == ''
    data = result.to_json()
    for key in ('feasible', 'joint_names', 'theta_s', 'nominal_path', 'failure_surface',
                'failure_plane_hits', 'hypercube', 'stats'):
        assert key in data
    assert 'reason' not in data
    assert np.allclose(scene.robot.forward_kinematics(result.theta_s), [2.0, 0.0], atol=1e-9)
    assert np.allclose(scene.robot.forward_kinematics(result.nominal_path[-1]), X_GOAL,
                       atol=1e-9)
    for joint, hit in enumerate(result.failure_plane_hits):
        assert np.cos(hit[joint] - result.theta_s[joint]) == pytest.approx(1.0)
        assert np.linalg.norm(scene.robot.forward_kinematics(hit) - X_GOAL) < 1e-9
    lower, upper = result.hypercube
    assert np.all(lower <= result.nominal_path.min(axis=0) + 1e-12)
    assert np.all(upper >= result.nominal_path.max(axis=0) - 1e-12)
    stats = result.stats
    # Every clearance the planner computed is counted: at least the points of the traced
    # self-motion manifolds (Step 2) and the self-check's samples of S_F.
    traced = sum(len(b.points) for b in result.start_manifolds + result.goal_manifolds)
    assert traced > 0 and stats['clearance_samples'] > 0
    assert stats['collision_checks'] >= traced + stats['clearance_samples']
    assert stats['plan_time_s'] > 0
    assert stats['criterion'] and stats['theta_S'] <= stats['start_candidates']


@pytest.mark.parametrize('name', ['fig3a', 'fig3b', 'fig3c'])
def test_paper_like_scenes_are_feasible_with_clearance(name):
    scene = load_scene(SCENES / f'{name}.yaml')
    result = plan(scene)
    assert result.feasible, result.reason
    assert result.stats['min_clearance_m'] > 0
    checker = CollisionChecker(scene.robot, scene.obstacles)
    assert checker.min_clearance(result.nominal_path).min() > 0


def test_same_seed_same_plan():
    scene = load_scene(SCENES / 'fig3b.yaml')
    first = plan(scene, rng=np.random.default_rng(4))
    second = plan(scene, rng=np.random.default_rng(4))
    assert np.array_equal(first.theta_s, second.theta_s)
    assert np.array_equal(first.surface.paths, second.surface.paths)


def test_chosen_start_beats_the_others_on_the_criterion(fig3a):
    """θ_s is the start whose coarse surface keeps the largest vertex clearance."""
    scene, result = fig3a
    assert result.stats['criterion_value_m'] > 0
    others = [plan(scene, start_configuration=theta) for theta in result.proposed_starts[::6]]
    scores = [r.stats.get('criterion_value_m', -np.inf) for r in others]
    assert result.stats['criterion_value_m'] >= max(scores) - 1e-12


def test_a_given_start_is_checked_not_replaced(fig3a):
    scene, result = fig3a
    again = plan(scene, start_configuration=result.theta_s)
    assert again.feasible and np.allclose(again.theta_s, result.theta_s, atol=1e-9)
    with pytest.raises(InputError, match='start_configuration: does not put'):
        plan(scene, start_configuration=np.zeros(3))
    blocked = scene.with_obstacles([Obstacle('sphere', (*scene.robot.joint_positions(
        result.theta_s)[1], 0.0), radius=0.05)])
    assert not plan(blocked, start_configuration=result.theta_s).feasible


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


def test_infeasible_scene_says_why():
    result = plan(load_scene(SCENES / 'infeasible.yaml'))
    assert not result.feasible
    assert 'necessary condition' in result.reason
    assert result.surface is None and result.theta_s is None
    assert result.to_json()['reason'] == result.reason


def test_blocked_start_and_goal_say_why():
    blocked_goal = paper_scene(obstacles=[((1.0, 0.0), 0.15)])
    assert 'M_g^F is empty' in plan(blocked_goal).reason
    blocked_start = paper_scene(obstacles=[((2.0, 0.0), 0.15)])
    assert 'M_s^F is empty' in plan(blocked_start).reason


def test_every_nominal_lock_may_recover_by_brute_force(fig3a):
    """A flood fill in each failure plane (over-approximating, 1 deg cells) never refutes."""
    scene, result = fig3a
    checker = CollisionChecker(scene.robot, scene.obstacles)
    for fraction in np.linspace(0.0, 1.0, 7):
        theta = point_at_fraction(result.nominal_path, fraction)
        for joint in range(3):
            assert recoverable_in_plane(checker, theta, joint, X_GOAL, 360)


def test_the_referee_can_refute():
    """The brute-force check is not vacuous.

    With joint 3 locked straight (θ3 = 0) the arm is a 2R arm of links 1 m and 2 m, which
    reaches [1, 0] only fully folded, link 1 pointing to [-1, 0]. A disk on that link
    leaves no goal in the failure plane (a big one: the check over-approximates).
    """
    theta = np.zeros(3)
    free = paper_scene()
    assert recoverable_in_plane(CollisionChecker(free.robot, free.obstacles), theta, 2,
                                X_GOAL, 180)
    blocked = paper_scene(obstacles=[((-0.5, 0.0), 0.4)])
    checker = CollisionChecker(blocked.robot, blocked.obstacles)
    assert checker.min_clearance(theta[None])[0] > 0
    assert not recoverable_in_plane(checker, theta, 2, X_GOAL, 180)
    assert recoverable_in_plane(checker, theta, 0, X_GOAL, 180)


@pytest.mark.parametrize('change, field', [
    (lambda s: s.with_task(None), 'task: is missing'),
    (lambda s: s.with_task(Task((3.2, 0.0), (1.0, 0.0))), 'task.start: .* out of the arm'),
    (lambda s: s.with_task(Task((2.0, 0.0), (0.0, 3.5))), 'task.goal: .* out of the arm'),
    (lambda s: s.with_task(Task((2.0, 0.0), (2.0, 0.005))), 'task.goal: equals task.start'),
    (lambda s: s.with_obstacles([Obstacle('sphere', (0.05, 0.0, 0.0), radius=0.1)]),
     r'obstacles\[0\]: covers the robot base'),
    (lambda s: s.with_obstacles([Obstacle('sphere', (0.0, 0.0, 0.0), radius=0.2)]),
     r'obstacles\[0\]: covers the robot base'),
    (lambda s: s.with_obstacles([Obstacle('box', (0.0, 0.0, 0.0), size=(0.3, 0.3, 0.3))]),
     r'obstacles\[0\]: covers the robot base'),
])
def test_unplannable_scenes_raise_naming_the_field(change, field):
    with pytest.raises(InputError, match=field):
        plan(change(paper_scene()))


def test_redundancy_is_checked():
    scene = parse_scene({'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0]},
                         'task': {'start': [1.5, 0.0], 'goal': [0.5, 0.5]}})
    with pytest.raises(InputError, match='robot.link_lengths: .*no redundancy'):
        plan(scene)


@pytest.mark.parametrize('seed', range(4))
def test_a_narrow_band_of_starts_is_found_whatever_the_sampling(seed):
    """fig3c leaves few feasible starts (the paper's among them); any seed finds a sound one.

    (Goal loops free all round are searched across the point where their tracing began.)
    """
    scene = load_scene(SCENES / 'fig3c.yaml')
    result = plan(scene, rng=np.random.default_rng(seed))
    assert result.feasible, result.reason
    # Whichever start of the band it is, a lock on the way still gets to the goal: each
    # recovery sampled every milliradian is collision-free and arrives.
    checker = CollisionChecker(scene.robot, scene.obstacles)
    for progress in np.linspace(0.0, 1.0, 11):
        theta = point_at_fraction(result.nominal_path, progress)
        for joint in range(3):
            rescue = recover(result.surface, theta, joint)
            assert rescue is not None
            assert checker.min_clearance(densify(rescue.path, 1e-3), 1e-3).min() > 0.0
            assert scene.task.reached(task_errors(scene.robot, X_GOAL, rescue.path[-1]))


@pytest.mark.parametrize('n', [3, 7])
def test_ranking_fans_are_the_points_along_each_straight_path(n):
    """straight_fans (P, W, G, n) against start + w/W (goal - start), written with arrays."""
    rng = np.random.default_rng(2)
    starts, goals = rng.normal(size=(40, n)), rng.normal(size=(40, 6, n))
    steps = np.arange(1, 9)[None, :, None, None] / 8
    expected = starts[:, None, None, :] + steps * (goals[:, None] - starts[:, None, None, :])
    assert np.array_equal(straight_fans(starts, goals, 8), expected)
