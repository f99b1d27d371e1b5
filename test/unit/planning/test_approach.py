"""Approaches from where the arm stands (core/planning/approach.py): M_s^F, certified cells,
RRT-Connect, locks."""

from dataclasses import replace

import numpy as np
import pytest
from ftplan_testing import REPO, SCENES, paper_scene

from ftplan_ros.core import CollisionChecker, PlannerOptions, load_scene, plan, task_errors
from ftplan_ros.core.grid.free_components import (
    FreeComponents,
    proof_grids,
    tolerant_start_out_of_reach,
)
from ftplan_ros.core.grid.tolerant_set import preimage_samples
from ftplan_ros.core.model.paths import densify
from ftplan_ros.core.model.scene import Obstacle
from ftplan_ros.core.paper.manifolds import project_to_preimage, trace_self_motion_manifolds
from ftplan_ros.core.paper.verification import VerificationOptions
from ftplan_ros.core.planning import approach as approach_module
from ftplan_ros.core.planning.approach import (
    ApproachOptions,
    ApproachPlanner,
    Route,
    plan_from,
    straight_move_ends,
)

X_S = np.array([2.0, 0.0])
# A disk that cuts M_s in two arcs, each holding failure-tolerant starts; the planner's
# favourite lies on the other arc than this configuration.
SPLIT = paper_scene(obstacles=[((0.811, -0.159), 0.144)])
ON_THE_OTHER_ARC = [-1.1223, 1.2014, 0.8857]
SCENES_OF_TESTS = REPO / 'test' / 'ros' / 'scenes'


def planner_for(scene, **options):
    return ApproachPlanner(CollisionChecker(scene.robot, scene.obstacles),
                           ApproachOptions(**options))


def clearest_start(scene):
    """The sim's default start: the clearest point of M_s."""
    checker = CollisionChecker(scene.robot, scene.obstacles)
    points = np.vstack([b.points for b in trace_self_motion_manifolds(
        scene.robot, np.array(scene.task.start), np.random.default_rng(0))])
    return points[int(np.argmax(checker.min_clearance(points)))]


def test_the_plan_prefers_a_start_the_arm_reaches_along_its_arc_of_M_s_free():
    q = project_to_preimage(SPLIT.robot, X_S, np.array(ON_THE_OTHER_ARC))
    approaches = planner_for(SPLIT)
    arc = approaches.reachable_arc(X_S, q)
    on_arc = approaches.prefer_reachable(arc)
    plain = plan(SPLIT)
    assert plain.feasible and not on_arc(plain.theta_s[None])[0]
    preferred = plan(SPLIT, prefer_starts=on_arc)
    assert preferred.feasible and preferred.stats['start_preferred']
    assert on_arc(preferred.theta_s[None])[0]
    found = approaches.approach(q, preferred.theta_s, arc=arc)
    assert found.route is Route.ALONG_ARC and np.array_equal(found.path[0], q)
    assert np.allclose(found.path[-1], preferred.theta_s, atol=1e-9)
    # The tool stays at x_s at every point, and the chords between them are certified.
    assert task_errors(SPLIT.robot, X_S, found.path)[:, 0].max() < 1e-6
    assert approaches.certify(found.path)
    assert CollisionChecker(SPLIT.robot, SPLIT.obstacles).min_clearance(
        densify(found.path, 0.005)).min() > 0.0


def test_a_hook_that_prefers_nothing_leaves_the_plan_as_it_was():
    plain = plan(SPLIT)
    nothing = plan(SPLIT, prefer_starts=lambda candidates: np.zeros(len(candidates), bool))
    assert np.array_equal(nothing.theta_s, plain.theta_s)
    assert nothing.stats['start_preferred'] is False


def test_an_arc_holds_only_free_configurations_of_M_s_through_q():
    scene = load_scene(SCENES / 'fig3a.yaml')
    q = clearest_start(scene)
    approaches = planner_for(scene)
    arc = approaches.reachable_arc(np.array(scene.task.start), q)
    assert np.min(np.abs(arc - q).max(axis=1)) == 0.0          # q is one of its points
    assert task_errors(scene.robot, np.array(scene.task.start), arc)[:, 0].max() < 1e-9
    assert CollisionChecker(scene.robot, scene.obstacles).min_clearance(arc).min() > 0.0
    away = q.copy()
    away[0] += 0.5
    assert approaches.reachable_arc(np.array(scene.task.start), away) is None   # off M_s


def test_a_joint_move_goes_round_the_disks_either_way_and_is_certified():
    """Through the 64^3 grid's certified cells among disks; where the grid does not apply
    (a box far away), by RRT-Connect."""
    scene = load_scene(SCENES / 'fig3a.yaml')
    boxed = replace(scene, obstacles=scene.obstacles + (
        Obstacle('box', (-2.9, -2.9, 0.0), size=(0.1, 0.1, 0.1)),))
    q, target = np.zeros(3), np.array([2.867, -1.356, 0.933])
    straight = [np.stack([q, end]) for end in straight_move_ends(q, target, scene.robot.periodic)]
    for where, route in ((scene, Route.THROUGH_CELLS), (boxed, Route.RRT_CONNECT)):
        approaches = planner_for(where)
        assert not any(approaches.certify(move) for move in straight)
        found = approaches.joint_move(q, target)
        assert found.route is route and np.array_equal(found.path[0], q)
        turns = (found.path[-1] - target) / (2 * np.pi)
        assert np.allclose(turns, np.round(turns), atol=1e-9)      # the target, whole turns apart
        checker = CollisionChecker(where.robot, where.obstacles)
        assert checker.min_clearance(densify(found.path, 0.002)).min() > 0.0


def test_the_certificate_refuses_a_sweep_through_a_disk_and_non_finite_paths():
    scene = load_scene(SCENES / 'fig3a.yaml')
    approaches = planner_for(scene)
    through = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])     # both ends are clear
    assert CollisionChecker(scene.robot, scene.obstacles).min_clearance(through).min() > 0.0
    assert not approaches.certify(through)
    assert not approaches.certify(np.array([[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]]))


def test_a_pocket_the_arm_cannot_leave_gives_no_approach_and_says_why():
    scene = load_scene(SCENES / 'fig3a.yaml')
    approaches = planner_for(scene, rrt_time=0.2, rrt_attempts=1)
    found = approaches.joint_move(np.zeros(3), np.array([1.0, 0.0, 0.0]))
    assert not found.ok and found.route is Route.NONE
    assert 'no collision-free joint move exists (proved on a 64^3 joint grid' in found.reason
    # Where the grid does not apply (a box), RRT-Connect searches and gives up.
    boxed = replace(scene, obstacles=scene.obstacles + (
        Obstacle('box', (-2.5, -2.5, 0.0), size=(0.1, 0.1, 0.1)),))
    approaches = planner_for(boxed, rrt_time=0.2, rrt_attempts=1)
    assert approaches.free_components is None
    found = approaches.joint_move(np.zeros(3), np.array([1.0, 0.0, 0.0]))
    assert not found.ok and 'no collision-free joint move found' in found.reason


def test_with_a_joint_locked_the_path_to_the_goal_holds_it_exactly():
    scene = load_scene(SCENES / 'fig3a.yaml')
    approaches = planner_for(scene)
    q = clearest_start(scene)
    for joint in range(3):
        found = approaches.path_to_goal(q, np.array(scene.task.goal), joint)
        assert found.ok, found.reason
        assert np.all(found.path[:, joint] == q[joint])
        assert task_errors(scene.robot, np.array(scene.task.goal), found.path[-1])[0] < 1e-9
        assert approaches.certify(found.path)


def test_where_no_plan_starts_within_reach_the_approach_says_so_and_why():
    """In out_of_reach every start that may be failure-tolerant lies in another free
    component than the sim's default start. plan_from's approach says that a grid proved
    it; each start of M_s^F in the arm's component (by the 64^3 free components) indeed
    fails as a start of its own, and from the plan's θ_s nothing is proved."""
    scene = load_scene(SCENES_OF_TESTS / 'out_of_reach.yaml')
    q = clearest_start(scene)
    reachable = plan_from(scene, q)
    assert reachable.result.feasible and not reachable.approach.ok
    assert reachable.approach.reason.startswith(
        'no failure-tolerant plan starts where the arm can get to from here (proved on a '
        '64^3 joint grid')
    assert 'no collision-free joint move exists' in reachable.approach.reason
    checker = CollisionChecker(scene.robot, scene.obstacles)
    starts = preimage_samples(np.asarray(scene.robot.link_lengths, dtype=float),
                              np.asarray(scene.task.start, dtype=float), 200)
    starts = starts[checker.min_clearance(starts) > 0.0]
    walls = FreeComponents.over(scene)
    within_reach = [theta for theta in starts if not walls.separated(q, theta)]
    assert len(within_reach) >= 5
    for theta in within_reach[::len(within_reach) // 5][:5]:
        assert not plan(scene, start_configuration=theta).feasible
    assert tolerant_start_out_of_reach(scene, reachable.result.theta_s) is None
    assert tolerant_start_out_of_reach(scene, q, grids=(256,)) == 256
    # Nothing is claimed for an arm in collision, lost turns away or not finite.
    inside_a_disk = np.array([-0.4087, 2.9794, 2.4987])
    assert checker.min_clearance(inside_a_disk[None])[0] < 0.0
    for nowhere in (inside_a_disk, q + 2e15 * np.pi, np.full(3, np.nan)):
        assert tolerant_start_out_of_reach(scene, nowhere) is None
    with pytest.raises(ValueError, match='margin must be a finite clearance'):
        tolerant_start_out_of_reach(scene, q, margin=-0.1)
    # Under a margin the proof says so.
    options = PlannerOptions(verification=VerificationOptions(margin=0.01))
    assert 'clear by more than 0.01 m' in plan_from(scene, q, options).approach.reason


def test_the_proof_comes_before_the_other_arcs_are_searched(monkeypatch):
    """Once a grid proves that no plan starts within reach, joint moves to the other arcs
    of M_s^F (RRT-Connect, seconds) cannot succeed: they are not tried."""
    scene = load_scene(SCENES_OF_TESTS / 'out_of_reach.yaml')

    def searched(*args, **kwargs):
        raise AssertionError('the other arcs were searched after the proof')

    monkeypatch.setattr(approach_module, '_joint_move_arcs', searched)
    reason = plan_from(scene, clearest_start(scene)).approach.reason
    assert reason.startswith('no failure-tolerant plan starts where the arm can get to')


def test_a_narrow_gap_is_proved_on_the_finest_grid_the_options_allow():
    """In out_of_reach_narrow the default grids (up to 128^3) cannot separate the arm from
    the starts that may be failure-tolerant; `proof_cells=384` does."""
    scene = load_scene(SCENES_OF_TESTS / 'out_of_reach_narrow.yaml')
    q = clearest_start(scene)
    found = {cells: plan_from(scene, q, approach_options=ApproachOptions(
        rrt_time=0.2, proof_cells=cells)) for cells in (128, 384)}
    assert all(r.result.feasible and not r.approach.ok for r in found.values())
    assert found[128].approach.reason.startswith('no collision-free joint move found')
    assert found[384].approach.reason.startswith(
        'no failure-tolerant plan starts where the arm can get to from here (proved on a '
        '384^3 joint grid')
    assert tolerant_start_out_of_reach(scene, q, grids=(256,)) is None
    assert proof_grids(256) == (64, 128, 256)
    with pytest.raises(ValueError, match='one of'):
        proof_grids(100)
    with pytest.raises(ValueError, match='one of'):
        ApproachOptions(proof_cells=100)  # when the options are made, not when a proof runs


@pytest.mark.parametrize('name, route, preferred', [
    ('detour', Route.RRT_CONNECT, False), ('split_arcs', Route.ALONG_ARC, True),
    ('crowded_6', Route.ALONG_ARC, True)])
def test_plans_from_the_default_start_come_with_an_approach(name, route, preferred):
    """In detour and split_arcs the planner's favourite θ_s lies on another arc of M_s than
    the sim's default start, and neither M_s nor a straight joint move joins them."""
    scene = load_scene(SCENES_OF_TESTS / f'{name}.yaml')
    q = clearest_start(scene)
    reachable = plan_from(scene, q)
    assert reachable.result.feasible and reachable.approach.ok
    assert reachable.approach.route is route
    assert reachable.result.stats['start_preferred'] is preferred
    assert np.array_equal(reachable.approach.path[0], q)

