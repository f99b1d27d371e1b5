"""Recovery columns and sheets of one joint (core/grid/sheet_builder.py)."""

from dataclasses import replace

from ftplan_testing import SCENES

from ftplan_ros.core import load_scene, plan
from ftplan_ros.core.grid.recovery_sheets import METHOD

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
