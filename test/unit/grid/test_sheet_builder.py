"""Recovery columns and sheets of one joint (core/grid/sheet_builder.py)."""

from dataclasses import replace

import pytest
from ftplan_testing import SCENES, paper_scene

from ftplan_ros.core import load_scene, plan
from ftplan_ros.core.grid.recovery_sheets import METHOD
from ftplan_ros.core.grid.sheet_builder import goal_step

from .references import assert_every_lock_recovers


def test_a_fine_goal_tolerance_gets_a_goal_row_fine_enough():
    """At a goal tolerance of 1 mm (1 m links) the goal row's chords of 0.15 rad strayed
    1.6 mm from the goal and the self-check failed every web: shorter chords pass it."""
    scene = load_scene(SCENES / 'crowded_sheets_100.yaml')
    finer = replace(scene, task=replace(scene.task, goal_tolerance=0.001))
    result = plan(finer)
    assert result.feasible and result.stats['method'] == METHOD, result.reason
    assert result.stats['goal_error_bound_m'] <= 0.001
    assert_every_lock_recovers(finer, result, 100)


@pytest.mark.parametrize('tolerance, step', [(0.05, 0.15), (0.01, 0.15), (0.0025, 0.075),
                                             (0.0001, 0.015)])
def test_goal_row_chords_shorten_as_the_square_root_of_a_tolerance_below_the_reach_over_300(
        tolerance, step):
    """The paper's arm reaches 3 m: chords of 0.15 rad down to a tolerance of 1 cm."""
    assert goal_step(paper_scene(tolerance=tolerance)) == pytest.approx(step)
