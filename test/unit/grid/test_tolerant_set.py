"""The failure-tolerant set G on a joint grid (core/grid/tolerant_set.py) against brute force.

Kinematics against circle intersections and numerical root finding; the certified
(inside) and liberal (outside) sets against configurations a verified plan passes through
and an over-approximating flood fill of each failure plane.
"""

import numpy as np
import pytest
from ftplan_testing import SCENES, paper_scene
from scipy.optimize import least_squares

from ftplan_ros.core import CollisionChecker, InputError, load_scene, parse_scene, plan, recover
from ftplan_ros.core.grid.cell_classes import supports
from ftplan_ros.core.grid.exhaustive import recoverable_in_plane
from ftplan_ros.core.grid.tolerant_set import (
    locked_goal_configurations,
    locked_goal_configurations_at,
    pooled_tolerant_set,
    preimage_samples,
    sub_slab_count,
    tolerant_set,
    two_link_solutions,
)
from ftplan_ros.core.model.paths import densify, point_at_fraction
from ftplan_ros.core.model.robot import PlanarChain
from ftplan_ros.core.model.scene import Obstacle

from .references import LINKS, planar_fk, sample_cells, wrapped


def same_configurations(a, b, atol=1e-9):
    """Whether the rows of a and b (s, n) [rad] are the same set, modulo whole turns."""
    if len(a) != len(b):
        return False
    return all(np.any(np.all(np.abs(wrapped(b - row)) < atol, axis=1)) for row in a) and \
        all(np.any(np.all(np.abs(wrapped(a - row)) < atol, axis=1)) for row in b)


def circle_solutions(a, b, target):
    """The 2R arm's solutions (s, 2) [rad]: elbows where the circles |e| = a, |t - e| = b meet."""
    d = float(np.linalg.norm(target))
    if d == 0.0 or d > a + b or d < abs(a - b):
        return np.empty((0, 2))
    along = (d * d + a * a - b * b) / (2.0 * d)
    height = np.sqrt(max(a * a - along * along, 0.0))
    u = target / d
    normal = np.array([-u[1], u[0]])
    out = []
    for sign in (1.0, -1.0) if height > 0 else (1.0,):
        elbow = along * u + sign * height * normal
        first = np.arctan2(elbow[1], elbow[0])
        rest = target - elbow
        out.append((first, np.arctan2(rest[1], rest[0]) - first))
    return np.array(out)


# Kinematics -----------------------------------------------------------------------------

def test_two_link_solutions_are_the_circle_intersections():
    rng = np.random.default_rng(3)
    found = 0
    for _ in range(300):
        a, b = rng.uniform(0.2, 2.0, 2)
        target = rng.uniform(-1.2, 1.2) * (a + b) * np.array([np.cos(t := rng.uniform(-4, 4)),
                                                               np.sin(t)])
        solutions = two_link_solutions(a, b, target)
        expected = circle_solutions(a, b, target)
        assert same_configurations(solutions, expected), (a, b, target)
        if len(solutions):
            found += 1
            assert np.allclose(planar_fk(np.array([a, b]), solutions), target, atol=1e-9)
    assert 100 < found < 300


def test_two_link_solutions_out_of_reach_or_without_a_link_are_none():
    assert two_link_solutions(1.0, 1.0, np.array([2.1, 0.0])).shape == (0, 2)
    assert two_link_solutions(2.0, 1.0, np.array([0.5, 0.0])).shape == (0, 2)
    assert two_link_solutions(0.0, 1.0, np.array([1.0, 0.0])).shape == (0, 2)
    at_full_stretch = two_link_solutions(1.0, 1.0, np.array([0.0, 2.0]))
    assert np.allclose(planar_fk(np.ones(2), at_full_stretch), [0.0, 2.0])


def numerical_locked_solutions(joint, value, x, grid=60):
    """Every configuration with θ_joint = value and the tool at x, by least squares.

    Seeds from a grid over the two free joints; roots with residual below 1e-10 m, once
    each.
    """
    others = [a for a in range(3) if a != joint]

    def residual(free):
        theta = np.empty(3)
        theta[joint], theta[others] = value, free
        return planar_fk(LINKS, theta) - x

    axis = np.linspace(-np.pi, np.pi, grid, endpoint=False)
    seeds = np.stack(np.meshgrid(axis, axis, indexing='ij'), -1).reshape(-1, 2)
    theta = np.empty((len(seeds), 3))
    theta[:, joint], theta[:, others] = value, seeds
    near = seeds[np.linalg.norm(planar_fk(LINKS, theta) - x, axis=1) < 0.2]
    roots = []
    for seed in near:
        fit = least_squares(residual, seed, xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if np.linalg.norm(fit.fun) < 1e-10:
            root = np.empty(3)
            root[joint], root[others] = value, fit.x
            if not any(np.all(np.abs(wrapped(root - r)) < 1e-6) for r in roots):
                roots.append(root)
    return np.array(roots).reshape(-1, 3)


@pytest.mark.parametrize('joint', [0, 1, 2])
def test_locked_goal_configurations_are_all_the_roots(joint):
    rng = np.random.default_rng(10 + joint)
    counts = set()
    for _ in range(6):
        x = rng.uniform(0.4, 2.4) * np.array([np.cos(t := rng.uniform(-4, 4)), np.sin(t)])
        value = rng.uniform(-np.pi, np.pi)
        solutions = locked_goal_configurations(LINKS, x, joint, value)
        assert np.all(solutions[:, joint] == value)
        assert np.allclose(planar_fk(LINKS, solutions), x, atol=1e-9)
        assert same_configurations(solutions, numerical_locked_solutions(joint, value, x),
                                   atol=1e-6)
        counts.add(len(solutions))
        # The vectorised form gives the same configurations, value by value.
        many, which = locked_goal_configurations_at(LINKS, x, joint, np.array([value, 0.3]))
        assert same_configurations(many[which == 0], solutions)
        assert same_configurations(many[which == 1],
                                   locked_goal_configurations(LINKS, x, joint, 0.3))
    assert 2 in counts


def test_preimage_samples_reach_the_point():
    x = np.array([1.3, -0.6])
    samples = preimage_samples(LINKS, x, 64)
    assert len(samples) > 64
    assert np.allclose(planar_fk(LINKS, samples), x, atol=1e-9)
    # The last link's absolute angle takes the sampled values.
    assert len(np.unique(np.round(wrapped(samples.sum(axis=1)), 9))) > 32


def test_half_a_sub_slab_moves_the_tool_within_the_tolerance():
    robot = PlanarChain((1.0, 0.7, 0.4), ('a', 'b', 'c'))
    rng = np.random.default_rng(4)
    thetas = rng.uniform(-np.pi, np.pi, (4000, 3))
    for joint in range(3):
        for step, tolerance in ((0.1, 0.01), (0.05, 0.002), (0.2, 0.05)):
            m = sub_slab_count(robot, step, joint, tolerance)
            moved = thetas.copy()
            moved[:, joint] += step / (2 * m)
            shift = np.linalg.norm(planar_fk(np.array(robot.link_lengths), moved)
                                   - planar_fk(np.array(robot.link_lengths), thetas), axis=1)
            assert shift.max() <= tolerance
            if m > 1:  # and not absurdly many sub-slabs
                assert shift.max() > 0.3 * tolerance


# G from both sides ----------------------------------------------------------------------

@pytest.fixture(scope='module')
def fig3a():
    scene = load_scene(SCENES / 'fig3a.yaml')
    return scene, tolerant_set(scene, 64), plan(scene)


def test_a_pooled_grid_takes_its_start_and_goal_cells_from_the_finer_grid(fig3a):
    """The blocks holding a cell of the finer grid's masks: no wider than the pooled
    lattice's own bounds, and holding every exact start and goal configuration."""
    scene, grid, _ = fig3a
    pooled = pooled_tolerant_set(grid)
    task, blocks = scene.task, (32, 2, 32, 2, 32, 2)
    for mine, finer, x, tolerance in ((pooled.near_start, grid.near_start, task.start, 0.0),
                                      (pooled.near_goal, grid.near_goal, task.goal,
                                       task.goal_tolerance)):
        x = np.asarray(x, dtype=float)
        assert np.array_equal(mine, finer.reshape(blocks).any(axis=(1, 3, 5)))
        own = pooled.lattice.tool_near(scene.robot, x, tolerance)
        assert not (mine & ~own).any() and mine.sum() < own.sum()
        exact = preimage_samples(LINKS, x, 400)
        assert mine[tuple(pooled.lattice.cell_of(exact).T)].all()


def test_certified_cells_escape_by_the_flood_fill_referee(fig3a):
    """A flood fill of the failure plane (over-approximating) never refutes an escape."""
    scene, grid, _ = fig3a
    checker = CollisionChecker(scene.robot, scene.obstacles)
    rng = np.random.default_rng(12)
    x_goal = np.asarray(scene.task.goal, dtype=float)
    for joint in grid.joints:
        cells = np.argwhere(grid.escape(joint).cells & grid.classes.certified)
        assert len(cells) > 1000
        for theta in sample_cells(grid.lattice, cells[rng.choice(len(cells), 6)], 1, rng):
            assert checker.min_clearance(theta[None])[0] > 0
            assert recoverable_in_plane(checker, theta, joint, x_goal, 180,
                                        goal_tolerance=scene.task.goal_tolerance)
        # Its goal configurations are exact, free and in certified cells.
        goals = grid.escape(joint).goal_points
        assert np.allclose(planar_fk(LINKS, goals), x_goal, atol=1e-9)
        assert checker.min_clearance(goals).min() > 0
        assert grid.escape(joint).cells[tuple(grid.lattice.cell_of(goals).T)].all()


def test_a_verified_plan_stays_in_the_liberal_cells(fig3a):
    """Every point of a plan's motion is in G, so in the over-approximation of G."""
    scene, grid, result = fig3a
    assert result.feasible
    lattice = grid.lattice
    nominal = densify(result.nominal_path, 0.005)
    assert grid.liberal_all[tuple(lattice.cell_of(nominal).T)].all()
    for fraction in np.linspace(0.0, 1.0, 9):
        theta = point_at_fraction(result.nominal_path, fraction)
        for joint in grid.joints:
            path = densify(recover(result.surface, theta, joint).path, 0.005)
            assert grid.liberal_escape(joint)[tuple(lattice.cell_of(path).T)].all()
            assert grid.classes.possible[tuple(lattice.cell_of(path).T)].all()


def test_free_goal_configurations_are_liberal(fig3a):
    scene, grid, _ = fig3a
    checker = CollisionChecker(scene.robot, scene.obstacles)
    goals = preimage_samples(LINKS, np.asarray(scene.task.goal, dtype=float), 720)
    free = goals[checker.min_clearance(goals) > 0]
    assert 100 < len(free) < len(goals)
    assert grid.liberal_all[tuple(grid.lattice.cell_of(free).T)].all()
    assert np.all(grid.certified_all <= grid.liberal_all)


def test_the_grid_takes_planar_3r_arms_among_disks_only():
    assert supports(paper_scene())
    four = parse_scene({'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0, 1.0]},
                        'task': {'start': [2.0, 0.0], 'goal': [1.0, 0.0]}})
    boxed = paper_scene().with_obstacles([Obstacle('box', (1.5, 1.5, 0.0), size=(0.2, 0.2, 0.2))])
    for scene in (four, boxed):
        assert not supports(scene)
        with pytest.raises(InputError, match='planar 3R arms among disks'):
            tolerant_set(scene, 32)

