"""The existence reference (core/grid/existence.py): its proofs against the planner and brute force.

A YES must never meet a proof of the opposite, a NO never a verified plan; the scenes
where the reference proves NO are checked by brute force too (every goal configuration
collides).
"""

import numpy as np
import pytest
from ftplan_testing import SCENES, paper_scene

from ftplan_ros.bench.crowded import crowded_scene
from ftplan_ros.bench.scenes import random_scene
from ftplan_ros.core import CollisionChecker, load_scene, parse_scene, plan
from ftplan_ros.core.grid.components import components
from ftplan_ros.core.grid.existence import (
    Existence,
    ExistenceAnswer,
    decide_existence,
    proves_no,
    proves_yes,
)
from ftplan_ros.core.grid.recovery_sheets import PROVED_NONE
from ftplan_ros.core.grid.tolerant_set import (
    TolerantSet,
    pooled_tolerant_set,
    preimage_samples,
    tolerant_set,
)
from ftplan_ros.core.model.scene import Obstacle


def goal_configurations(x, count=2000):
    """Configurations (s, 3) [rad] of the paper's arm with the tool at x, by circles.

    For each absolute angle φ of the last link the wrist is at x - (cos φ, sin φ); the
    elbow lies where |e| = 1 and |wrist - e| = 1 meet.
    """
    out = []
    for phi in np.linspace(-np.pi, np.pi, count, endpoint=False):
        wrist = np.asarray(x, dtype=float) - np.array([np.cos(phi), np.sin(phi)])
        d = np.linalg.norm(wrist)
        if not 0.0 < d <= 2.0:
            continue
        u = wrist / d
        height = np.sqrt(max(1.0 - (d / 2.0) ** 2, 0.0))
        for sign in (1.0, -1.0):
            elbow = 0.5 * d * u + sign * height * np.array([-u[1], u[0]])
            a = np.arctan2(elbow[1], elbow[0])
            b = np.arctan2(wrist[1] - elbow[1], wrist[0] - elbow[0])
            out.append((a, b - a, phi - b))
    return np.array(out)


def walled_goal():
    """The goal 0.1 m clear of twelve disks around it: the last link cannot leave it."""
    angles = np.linspace(0.0, 2.0 * np.pi, 12, endpoint=False)
    return parse_scene({
        'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]},
        'obstacles': [{'type': 'sphere', 'radius': 0.45,
                       'center': [1.5 + 0.55 * np.cos(a), 0.55 * np.sin(a)]} for a in angles],
        'task': {'start': [-2.0, 0.5], 'goal': [1.5, 0.0]}})


@pytest.mark.parametrize('name, cells', [('fig3a', 128), ('fig3b', 64), ('fig3c', 128),
                                         ('paper_a_free', 64)])
def test_the_paper_scenes_have_a_plan_and_the_reference_proves_it(name, cells):
    scene = load_scene(SCENES / f'{name}.yaml')
    answer = decide_existence(scene, cells)
    assert answer.existence is Existence.YES
    assert isinstance(answer, ExistenceAnswer) and answer.cells == cells
    assert 0 < answer.certified_cells <= answer.liberal_cells <= cells ** 3
    assert answer.time_s > 0
    result = plan(scene)
    assert result.feasible, result.reason


def test_the_infeasible_scene_is_never_called_feasible():
    scene = load_scene(SCENES / 'infeasible.yaml')
    for cells in (64, 128):
        grid = tolerant_set(scene, cells)
        assert not proves_yes(grid)
    assert not plan(scene).feasible


def test_a_walled_goal_is_proved_to_have_no_plan_and_brute_force_agrees():
    scene = walled_goal()
    checker = CollisionChecker(scene.robot, scene.obstacles)
    # Every configuration with the tool within the goal tolerance collides: a plan
    # cannot end anywhere.
    x = np.asarray(scene.task.goal)
    radius = scene.task.goal_tolerance
    for angle in np.linspace(0.0, 2.0 * np.pi, 7):
        for reach in (0.0, 0.5 * radius, radius):
            point = x + reach * np.array([np.cos(angle), np.sin(angle)])
            goals = goal_configurations(point)
            assert np.allclose(scene.robot.forward_kinematics(goals), point, atol=1e-9)
            assert len(goals) > 2000
            assert checker.min_clearance(goals).max() <= 0.0
    assert checker.min_clearance(np.array([[np.pi, 0.0, 0.0]]))[0] > 0.0  # the arm fits elsewhere
    answer = decide_existence(scene, 64)
    assert answer.existence is Existence.NO and answer.certified_cells == 0
    result = plan(scene)
    assert not result.feasible
    assert result.stats.get('proved_infeasible') and 'proved on a joint grid' in result.reason


def test_an_obstacle_free_paper_task_is_no_proof_of_no():
    grid = tolerant_set(paper_scene(), 64)
    assert proves_yes(grid) and not proves_no(grid)
    assert grid.certified_all.all() and grid.liberal_all.all()


def sampled_scenes():
    """Seeded random scenes (bench/scenes.py) and a cheap crowded one (bench/crowded.py).

    (Random seeds 0 and 6 are proved to have no plan, 2, 4 and 7 have plans.)
    """
    scenes = []
    for seed in (0, 2, 3, 4, 6, 7):
        rng = np.random.default_rng([7, seed])
        scenes.append((f'random {seed}', random_scene(rng, int(rng.integers(0, 13)))))
    for seed in (3,):
        scenes.append((f'crowded {seed}', crowded_scene(np.random.default_rng(seed), disks=3,
                                                        attempts=5, cells=64)))
    return scenes


def test_the_reference_and_the_planner_never_contradict_each_other():
    """NO (a proof) never meets a verified plan; YES and NO never meet on one grid, nor YES
    and a NO on the grid's classes pooled to half as many cells per joint."""
    verdicts = set()
    for name, scene in sampled_scenes():
        grid = tolerant_set(scene, 64)
        yes, no = proves_yes(grid), proves_no(grid)
        assert not (yes and no), name
        assert not (yes and proves_no(pooled_tolerant_set(grid)))
        result = plan(scene)
        assert not (no and result.feasible), name
        if result.stats.get('proved_infeasible'):
            assert not yes, name
        verdicts.add((yes, no, result.feasible))
    # Both proofs and both planner outcomes occur in the sample.
    assert (True, False, True) in verdicts and (False, True, False) in verdicts


def test_a_no_plan_proof_on_pooled_classes_comes_before_the_finer_grid():
    """Random scene 0 of the recall bench (seed 1): the proof fails on 64^3 cells but
    holds on the 128^3 classes pooled to 64^3, which the planner tries before labelling
    128^3 and reports."""
    rng = np.random.default_rng([1, 0, 0])
    scene = random_scene(rng, int(rng.integers(0, 21)))
    assert not proves_no(tolerant_set(scene, 64))
    fine = tolerant_set(scene, 128)
    assert proves_no(pooled_tolerant_set(fine))
    result = plan(scene)
    assert not result.feasible and result.stats['proved_infeasible']
    assert result.reason.startswith(f'{PROVED_NONE}, 64^3 cells pooled from 128^3')


def test_a_pooled_grid_proves_no_with_the_finer_grids_start_and_goal_cells():
    """Random scene 10 of the recall bench (seed 1): on the 128^3 classes pooled to 64^3,
    the proof holds with the 128^3 cells that may hold a start or a goal, pooled, and
    fails with the 64^3 cells' own, wider, bounds. The planner proves it there."""
    rng = np.random.default_rng([1, 0, 10])
    scene = random_scene(rng, int(rng.integers(0, 21)))
    fine = tolerant_set(scene, 128)
    pooled = pooled_tolerant_set(fine)
    assert proves_no(pooled)
    own_bounds = TolerantSet(scene, fine.classes.pooled(), fine.joints)
    assert not proves_no(own_bounds)
    assert pooled.near_start.sum() < own_bounds.near_start.sum()
    result = plan(scene)
    assert not result.feasible and result.stats['proved_infeasible']
    assert result.reason.startswith(f'{PROVED_NONE}, 64^3 cells pooled from 128^3')


def test_stopping_at_the_first_joints_never_changes_an_answer():
    """proves_no and certified_holding stop early; every joint counted, they say the same.

    The referees are the full intersections over every joint (liberal_all and
    certified_all), on the sampled scenes, the walled goal and three scenes of the
    recall bench (seed 1) whose starts leave the liberal side early, in three joint orders.
    """
    scenes = [scene for _, scene in sampled_scenes()] + [walled_goal()]
    for k in (2, 14, 18):
        rng = np.random.default_rng([1, 0, k])
        scenes.append(random_scene(rng, int(rng.integers(0, 21))))
    stopped = early = 0
    for scene in scenes:
        for order in ((0, 1, 2), (2, 1, 0), (1, 2, 0)):
            grid = tolerant_set(scene.with_tolerated([f'joint{j + 1}' for j in order]), 64)
            lattice, task = grid.lattice, grid.scene.task
            start = lattice.tool_near(grid.scene.robot, np.asarray(task.start, dtype=float))
            assert np.array_equal(grid.liberal_all, np.logical_and.reduce(
                [grid.classes.possible] + [grid.liberal_escape(j) for j in order]))
            found = components(grid.liberal_all, lattice.periodic)
            shared = found.holding(start) & found.holding(grid.near_goal)
            assert proves_no(grid) == (not shared[1:].any())
            first = grid.classes.possible & grid.liberal_escape(order[0])
            early += not ((first & start).any() and (first & grid.near_goal).any())
            everything = grid.certified_all
            starts = lattice.cell_of(preimage_samples(np.asarray(scene.robot.link_lengths),
                                                      np.asarray(task.start), 256))
            held = grid.certified_holding(starts)
            if everything[tuple(starts.T)].any():
                assert np.array_equal(held, everything)
            else:
                assert held is None
                stopped += 1
    assert stopped and early  # some scenes' starts (or goals) are out after the first joint


def test_the_reference_takes_planar_3r_arms_among_disks_only():
    boxed = paper_scene().with_obstacles([Obstacle('box', (1.5, 1.5, 0.0), size=(0.2, 0.2, 0.2))])
    with pytest.raises(ValueError, match='planar 3R arms among disks'):
        decide_existence(boxed, 64)
