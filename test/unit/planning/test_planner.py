"""The planner end to end: a trivial, the paper's, and impossible cases; bad input; brute force."""

import re

import numpy as np
import pytest
from ftplan_testing import SCENES, paper_scene, robot_config, within_limits

from ftplan_ros.core import (
    CollisionChecker,
    InputError,
    PlannerOptions,
    load_scene,
    parse_scene,
    plan,
    recover,
    task_errors,
)
from ftplan_ros.core.grid.exhaustive import recoverable_in_plane
from ftplan_ros.core.grid.recovery_sheets import PAPER_METHOD
from ftplan_ros.core.model.paths import densify, point_at_fraction
from ftplan_ros.core.model.scene import Obstacle, Scene, Task
from ftplan_ros.core.paper.failure_planes import failure_hypercube

X_GOAL = np.array([1.0, 0.0])


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


def test_a_paper_plan_is_named_for_its_method(fig3a):
    _, result = fig3a
    assert result.feasible and result.stats['method'] == PAPER_METHOD
    # Its hypercube is the paper's V_sg: θ_s and the goal points span it.
    box = failure_hypercube(result.surface.theta_s, result.surface.goal_points)
    assert all(np.array_equal(a, b) for a, b in zip(result.hypercube, box, strict=True))


def test_the_papers_second_round_runs_when_the_sheets_decide_nothing():
    """A grid too coarse to plan or to prove: the paper's finer starts are tried after it."""
    result = plan(load_scene(SCENES / 'crowded_sheets_100.yaml'),
                  PlannerOptions(sheet_cells=(32,)))
    assert not result.feasible and not result.stats['proved_infeasible']
    assert result.stats['candidate_subdivisions'] == PlannerOptions().candidate_refinement
    assert result.reason.startswith('no failure-tolerant plan found within the resolution')


def test_a_disk_just_clear_of_the_base_is_not_taken_for_one_covering_it():
    plan(paper_scene(obstacles=[((-0.205, 0.0), 0.2)]))  # no InputError: 5 mm from the base
    with pytest.raises(ValueError, match='covers the robot base'):
        plan(paper_scene(obstacles=[((-0.195, 0.0), 0.2)]))


# Spatial arms ---------------------------------------------------------------------------
# The tasks were found beforehand with a throwaway search (random collision-free
# configurations q1, q2 = q1 + N(0, 0.5), tasks FK(q1) -> FK(q2)) and are written here as
# plain numbers. The tests check each plan on their own terms: dense collision sampling,
# task errors, joint limits.

IIWA_ELBOW = 'iiwa_joint_4'
IIWA_POSE = Task((0.33281, 0.462817, 0.705411, 0.755692, -0.431346, 0.324635, -0.370786),
                 (0.102688, 0.465602, 1.019076, 0.635032, -0.0633, 0.518829, -0.568809),
                 goal_tolerance=0.005, orientation_tolerance=0.01)
IIWA_OBSTACLES = (Obstacle('sphere', (0.586, 0.531, 0.618), radius=0.12),
                  Obstacle('box', (0.178, 0.764, 1.077), size=(0.2, 0.3, 0.15),
                           rpy=(0.3, 0.0, 0.5)),
                  Obstacle('cylinder', (0.18, -0.315, 0.39), radius=0.08, length=0.4,
                           rpy=(0.5, 0.2, 0.0)))
MOMENTS = 9
STEP = 0.001  # [m] most any point of the arm moves between two collision samples


def iiwa_scene(tolerate):
    robot = robot_config('iiwa14', 'pose')
    scene = Scene(robot, IIWA_OBSTACLES).with_task(IIWA_POSE)
    return scene.with_tolerated(tolerate)


@pytest.fixture(scope='module')
def iiwa_pose():
    names = robot_config('iiwa14').joint_names
    scene = iiwa_scene([name for name in names if name != IIWA_ELBOW])
    return scene, plan(scene)


def dense(path, checker):
    """Points of a joint path (k, n) [rad] such that no point of the arm moves > STEP between."""
    arms = checker.lever_arms()
    pieces = [path[:1]]
    for a, b in zip(path[:-1], path[1:], strict=True):
        count = max(1, int(np.ceil(np.max(arms @ np.abs(b - a)) / STEP)))
        pieces.append(a + np.outer(np.arange(1, count + 1) / count, b - a))
    return np.vstack(pieces)


def test_a_pose_plan_tolerating_all_but_the_elbow_is_sound(iiwa_pose):
    """Brute force: at 9 moments, every tolerated joint's lock has a safe way to the goal."""
    scene, result = iiwa_pose
    assert result.feasible, result.reason
    robot = scene.robot
    assert result.tolerated_joints == (0, 1, 2, 4, 5, 6)
    assert result.stats['tolerated_joints'] == [n for n in robot.joint_names if n != IIWA_ELBOW]
    assert_sound(scene, result)


@pytest.mark.parametrize('joint', ['iiwa_joint_1', 'iiwa_joint_3'])
def test_a_plan_tolerating_one_joint_is_found_and_sound(joint):
    """One hit makes no strip of S_F by itself: the web takes its neighbours on M_g^F."""
    scene = iiwa_scene([joint])
    result = plan(scene)
    assert result.feasible, result.reason
    assert result.stats['tolerated_joints'] == [joint]
    assert_sound(scene, result)


def assert_sound(scene, result):
    """Brute force: at 9 moments, every tolerated joint's lock has a safe way to the goal."""
    robot, task = scene.robot, scene.task
    assert task.reached(task_errors(robot, task.start, result.theta_s[None]))[0]
    assert task.reached(task_errors(robot, task.goal, result.nominal_path[-1:]))[0]
    assert within_limits(robot, result.surface.paths)
    checker = CollisionChecker(robot, scene.obstacles)
    assert checker.min_clearance(dense(result.nominal_path, checker), STEP).min() > 0.0
    for progress in np.linspace(0.0, 1.0, MOMENTS):
        theta = point_at_fraction(result.nominal_path, progress)
        for joint in result.tolerated_joints:
            rescue = recover(result.surface, theta, joint)
            where = f'{robot.joint_names[joint]} locked at progress {progress:.3f}'
            assert rescue is not None, where
            path = rescue.path
            assert np.array_equal(path[0], theta) and np.all(path[:, joint] == theta[joint])
            assert within_limits(robot, path), where
            samples = dense(path, checker)
            clearance = checker.min_clearance(samples, STEP)
            assert clearance.min() > 0.0, f'{where}: collides at sample {clearance.argmin()}'
            errors = task_errors(robot, task.goal, path[-1])
            assert task.reached(errors), f'{where}: ends {errors} from the goal'


def test_tolerating_the_elbow_too_is_infeasible_and_says_why():
    """On a spherical shoulder and wrist the elbow keeps its angle along a pose's self-motion."""
    scene = iiwa_scene(None)
    result = plan(scene)
    assert not result.feasible
    assert IIWA_ELBOW in result.reason
    others = [name for name in scene.robot.joint_names if name != IIWA_ELBOW]
    assert result.stats['coverable_joints'] == others
    assert re.search(r'keeps its angle along each branch', result.reason), result.reason


def test_the_answer_alone_goes_on_to_no_coverage_search():
    """`coverage_attempts=0` (the spatial benchmark's setting) answers "no" without
    planning for fewer joints, and the reason says why without a hint."""
    scene = iiwa_scene(None)
    result = plan(scene, PlannerOptions(coverage_attempts=0))
    assert not result.feasible
    assert IIWA_ELBOW in result.reason
    assert 'coverable_joints' not in result.stats
    assert '`tolerate`' not in result.reason
