"""Starts within the reach of an arm standing at q (core/grid/start_reach.py): the proof
that none may be failure-tolerant, the starts to plan from, each against brute force."""

import numpy as np
import pytest
from ftplan_testing import SCENES, TEST_SCENES, clearest_start, paper_scene

from ftplan_ros.bench.reach import independent_reach
from ftplan_ros.core import CollisionChecker, load_scene, plan, task_errors
from ftplan_ros.core.grid.start_reach import start_reach, tolerant_start_out_of_reach


def test_in_the_scene_of_the_issue_no_start_within_reach_may_be_failure_tolerant():
    """out_of_reach (issue 36): from the sim's default start the 64^3 grid proves that no
    start that may be failure-tolerant lies within reach. By brute force (a flood fill of
    joint space from q over 160^3 cells, then every lock of each of 720 starts of M_s in
    q's component recovered by a flood fill of its failure plane) none may either."""
    scene = load_scene(TEST_SCENES / 'out_of_reach.yaml')
    q = clearest_start(scene)
    reach = start_reach(scene, q, 0.0, 64)
    assert reach.proved_none and len(reach.starts) == 0
    brute = independent_reach(scene, q)
    assert brute.none and brute.starts_in_reach > 10
    assert tolerant_start_out_of_reach(scene, q) == 64
    assert tolerant_start_out_of_reach(scene, q, grids=(256,)) == 256


def test_the_starts_within_reach_are_on_M_s_joined_to_q_and_likeliest_first():
    """fig3a from the clearest start: every start offered puts the tool at x_s, is certified
    within reach, is in no cell the grid rules out; the first ones are failure-tolerant
    starts of a plan of their own, as the grid's proof says."""
    scene = load_scene(SCENES / 'fig3a.yaml')
    q = clearest_start(scene)
    reach = start_reach(scene, q, 0.0, 64)
    assert not reach.proved_none and reach.in_reach(q[None])[0]
    starts = reach.starts
    assert len(starts) >= 2 and np.all(reach.in_reach(starts))
    assert np.all(reach.grid.liberal_all[tuple(reach.grid.lattice.cell_of(starts).T)])
    assert task_errors(scene.robot, np.array(scene.task.start), starts)[:, 0].max() < 1e-9
    assert plan(scene, start_configuration=starts[0]).feasible
    for theta in starts:
        assert reach.walls.path(q, theta) is not None


def test_nothing_is_claimed_for_an_arm_in_collision_lost_turns_away_or_not_finite():
    scene = load_scene(TEST_SCENES / 'out_of_reach.yaml')
    q = clearest_start(scene)
    inside_a_disk = np.array([-0.4087, 2.9794, 2.4987])
    assert CollisionChecker(scene.robot, scene.obstacles).min_clearance(
        inside_a_disk[None])[0] < 0.0
    for nowhere in (inside_a_disk, q + 2e15 * np.pi, np.full(3, np.nan)):
        assert start_reach(scene, nowhere) is None
        assert tolerant_start_out_of_reach(scene, nowhere) is None
    # Not a planar 3R arm among disks, a goal tolerance too fine for the grid: no grid.
    assert start_reach(paper_scene(tolerance=1e-5), np.array([0.0, 0.5, 0.5]), 0.0, 64) is None
    with pytest.raises(ValueError, match='margin must be a finite clearance'):
        start_reach(scene, q, margin=-0.1)
    with pytest.raises(ValueError, match='margin must be a finite clearance'):
        tolerant_start_out_of_reach(scene, q, margin=float('nan'))
