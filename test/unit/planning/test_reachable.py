"""Plans for an arm standing at q (core/planning/reachable.py): each of the three outcomes,
the scene of issue 36, and brute-force checks of the answers on small random cases."""

from dataclasses import replace

import numpy as np
import pytest
from ftplan_testing import SCENES, TEST_SCENES, clearest_start

from ftplan_ros.bench.reach import approach_checks, independent_reach
from ftplan_ros.bench.scenes import random_scene
from ftplan_ros.core import (
    CollisionChecker,
    ManifoldCache,
    PlannerOptions,
    load_scene,
    task_errors,
)
from ftplan_ros.core.paper.verification import VerificationOptions
from ftplan_ros.core.planning import reachable as reachable_module
from ftplan_ros.core.planning.approach import ApproachOptions, ApproachPlanner, Route
from ftplan_ros.core.planning.reachable import Outcome, plan_from

QUICK_RRT = ApproachOptions(rrt_time=0.2, rrt_attempts=1)


def test_the_scene_of_the_issue_has_no_plan_within_reach_and_says_what_exists_elsewhere():
    """Issue 36: in out_of_reach the planner answered "plan found" from the sim's default
    start, with an approach proved impossible. Now the answer is "none reachable
    (proved)", naming the grid and the plan that starts out of reach."""
    scene = load_scene(TEST_SCENES / 'out_of_reach.yaml')
    q = clearest_start(scene)
    answer = plan_from(scene, q)
    assert answer.outcome is Outcome.NONE_REACHABLE and not answer.ok
    assert answer.result.feasible and not answer.approach.ok   # a plan exists elsewhere
    assert answer.reason.startswith('no failure-tolerant plan starts where the arm can get to '
                                    'from here (proved on a 64^3 joint grid')
    assert 'one starts at theta_s = [' in answer.reason and 'out of the arm\'s reach' in \
        answer.reason
    assert 'joint grids up to 64^3 cells' in answer.searched
    options = PlannerOptions(verification=VerificationOptions(margin=0.01))
    assert 'clear by more than 0.01 m' in plan_from(scene, q, options).reason


def test_after_the_proof_neither_rrt_connect_nor_the_other_arcs_are_searched(monkeypatch):
    """Once a grid proves that no plan starts within reach, the joint moves to θ_s and to
    the other arcs of M_s (seconds of RRT-Connect) cannot succeed: they are not tried."""
    scene = load_scene(TEST_SCENES / 'out_of_reach.yaml')

    def searched(*args, **kwargs):
        raise AssertionError('searched after the proof')

    monkeypatch.setattr(reachable_module, '_joint_move_arcs', searched)
    monkeypatch.setattr(ApproachPlanner, '_rrt_move', searched)
    assert plan_from(scene, clearest_start(scene)).outcome is Outcome.NONE_REACHABLE


@pytest.mark.parametrize('name, route', [('split_arcs', Route.ALONG_ARC),
                                         ('crowded_6', Route.ALONG_ARC)])
def test_a_start_on_the_arms_arc_of_M_s_free_is_planned_first(name, route):
    scene = load_scene(TEST_SCENES / f'{name}.yaml')
    q = clearest_start(scene)
    answer = plan_from(scene, q)
    assert answer.ok and answer.approach.route is route and answer.reason == ''
    assert answer.result.stats['start_preferred'] is True
    assert approach_checks(scene, q, answer)
    assert answer.searched == 'a plan preferring the starts on the arm\'s arc of M_s^F'


def test_where_the_first_plan_starts_out_of_reach_a_start_within_reach_is_planned_from():
    """detour: the planner's favourite θ_s lies on another arc of M_s than the sim's start
    (RRT-Connect went round the disks to it). The grid puts starts within reach; the first
    one planned from is failure-tolerant and next to the arm."""
    scene = load_scene(TEST_SCENES / 'detour.yaml')
    q = clearest_start(scene)
    answer = plan_from(scene, q)
    assert answer.ok and answer.approach.route is not Route.RRT_CONNECT
    assert 'a 64^3 joint grid: not proved that no start within reach is failure-tolerant; ' \
        '1 start within reach planned from so far' in answer.searched
    assert approach_checks(scene, q, answer) and answer.approach.length < 0.1
    assert task_errors(scene.robot, np.array(scene.task.start),
                       answer.result.theta_s[None])[0, 0] < 1e-9
    # Without starts from the grid, RRT-Connect goes round the disks to the first θ_s.
    rrt = plan_from(scene, q, approach_options=ApproachOptions(reach_starts=0))
    assert rrt.ok and rrt.approach.route is Route.RRT_CONNECT
    assert 'RRT-Connect to its theta_s (3 x 1 s)' in rrt.searched
    assert approach_checks(scene, q, rrt) and rrt.approach.length > 1.0
    with pytest.raises(ValueError, match='reach_starts must be an integer >= 0'):
        ApproachOptions(reach_starts=-1)


def test_a_narrow_gap_leaves_none_found_within_the_default_grids_and_384_proves_it():
    """out_of_reach_narrow: up to 128^3 the grids neither prove that no start within reach
    may be failure-tolerant nor put one within reach; RRT-Connect and the other arcs find
    nothing. The answer says how far it looked. 384^3 proves it."""
    scene = load_scene(TEST_SCENES / 'out_of_reach_narrow.yaml')
    q = clearest_start(scene)
    found = plan_from(scene, q, approach_options=QUICK_RRT)
    assert found.outcome is Outcome.NONE_FOUND and found.result.feasible
    assert found.reason.startswith('no failure-tolerant plan found that starts where the arm '
                                   'can get to; one starts at theta_s = [')
    for looked in ('a 64^3 joint grid: not proved', 'a 128^3 joint grid: not proved',
                   'RRT-Connect to its theta_s (1 x 0.2 s)', 'other free arcs of M_s'):
        assert looked in found.searched
    proved = plan_from(scene, q, approach_options=replace(QUICK_RRT, proof_cells=384))
    assert proved.outcome is Outcome.NONE_REACHABLE
    assert 'proved on a 384^3 joint grid' in proved.reason


def test_without_any_plan_the_outcome_says_whether_none_exists_at_all():
    scene = load_scene(SCENES / 'infeasible.yaml')
    q = clearest_start(scene)
    proved = plan_from(scene, q)
    assert proved.outcome is Outcome.NONE_REACHABLE and proved.approach is None
    assert proved.result.proved_infeasible and proved.reason == proved.result.reason
    paper_only = PlannerOptions(methods=('paper_surface',))
    unproved = plan_from(scene, q, paper_only)
    assert unproved.outcome is Outcome.NONE_FOUND and not unproved.result.proved_infeasible


def test_answers_on_small_random_cases_agree_with_brute_force():
    """Random scenes, the arm at random clear configurations. A plan's approach joins q to
    θ_s and is clear at samples 0.002 rad apart; where the planner proves that no start
    within reach may be failure-tolerant although a plan exists elsewhere, a flood fill of
    joint space from q (96^3 cells) and of each failure plane of every start of M_s in its
    component (120^2) finds none that may be."""
    rng = np.random.default_rng(3)
    counts = dict.fromkeys(Outcome, 0)
    proofs_checked = 0
    for _ in range(12):
        scene = random_scene(rng, int(rng.integers(8, 14)))
        checker = CollisionChecker(scene.robot, scene.obstacles)
        qs = rng.uniform(-np.pi, np.pi, (40, 3))
        cache = ManifoldCache()
        for q in qs[checker.min_clearance(qs) > 0.02][:4]:
            answer = plan_from(scene, q, cache=cache, approach_options=QUICK_RRT)
            counts[answer.outcome] += 1
            if answer.ok:
                assert answer.result.feasible and approach_checks(scene, q, answer)
            elif answer.outcome is Outcome.NONE_REACHABLE and answer.result.feasible:
                proofs_checked += 1
                assert independent_reach(scene, q, answer.result.theta_s[None], cells=96,
                                         plane_cells=120, samples=360).none
    assert counts[Outcome.PLANNED] >= 10 and proofs_checked >= 3, counts
