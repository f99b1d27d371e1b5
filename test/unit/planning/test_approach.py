"""Approaches from where the arm stands (core/planning/approach.py): M_s^F, certified cells,
RRT-Connect, locks."""

from dataclasses import replace

import numpy as np
from ftplan_testing import SCENES, clearest_start, paper_scene

from ftplan_ros.core import CollisionChecker, load_scene, plan, task_errors
from ftplan_ros.core.model.paths import densify
from ftplan_ros.core.model.scene import Obstacle
from ftplan_ros.core.paper.manifolds import project_to_preimage
from ftplan_ros.core.planning.approach import (
    ApproachOptions,
    ApproachPlanner,
    Route,
    straight_move_ends,
)

X_S = np.array([2.0, 0.0])
# A disk that cuts M_s in two arcs, each holding failure-tolerant starts; the planner's
# favourite lies on the other arc than this configuration.
SPLIT = paper_scene(obstacles=[((0.811, -0.159), 0.144)])
ON_THE_OTHER_ARC = [-1.1223, 1.2014, 0.8857]


def planner_for(scene, **options):
    return ApproachPlanner(CollisionChecker(scene.robot, scene.obstacles),
                           ApproachOptions(**options))


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
    # Without RRT-Connect, where the grid's cells do not join them, the move says so.
    found = planner_for(boxed).joint_move(q, target, rrt=False)
    assert not found.ok and found.reason.endswith('RRT-Connect not tried)')


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
