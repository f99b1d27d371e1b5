"""Free components of the joint grid (core/grid/free_components.py): sound proofs of no
move, and free paths through certified cells."""

import numpy as np
from ftplan_testing import paper_scene

from ftplan_ros.core import CollisionChecker, parse_scene
from ftplan_ros.core.grid.free_components import FreeComponents
from ftplan_ros.core.model.paths import densify
from ftplan_ros.core.planning.approach import ApproachOptions, ApproachPlanner


def test_the_grid_never_separates_configurations_a_certified_move_joins():
    """Soundness of the proof that no joint move exists, on random disks, a joint held or not."""
    rng = np.random.default_rng(5)
    proved, proved_held, joined, colliding = 0, 0, 0, 0
    for _ in range(8):
        disks = [(tuple(rng.uniform(-2.5, 2.5, 2)), float(rng.uniform(0.1, 0.4)))
                 for _ in range(int(rng.integers(1, 6)))]
        scene = paper_scene(obstacles=disks)
        approaches = ApproachPlanner(CollisionChecker(scene.robot, scene.obstacles),
                                     ApproachOptions(margin=0.01))
        components = approaches.free_components
        starts = rng.uniform(-np.pi, np.pi, (60, 3))
        ends = starts + rng.normal(0.0, 0.6, starts.shape)
        for n, (a, b) in enumerate(zip(starts, ends, strict=True)):
            held = None if n % 3 == 0 else n % 3  # joint 2 or 3 held in 2 pairs of 3
            if held is not None:
                b[held] = a[held]
            separated = components.separated(a, b, held)
            proved += separated
            proved_held += separated and held is not None
            if approaches.certify(np.stack([a, b])):
                joined += 1
                assert not separated, (disks, a, b, held)
        # A configuration kept apart from itself lies in a cell that surely collides.
        alone = [c for c in starts if components.separated(c, c)]
        if alone:
            clearance = CollisionChecker(scene.robot, scene.obstacles).min_clearance(
                np.array(alone))
            assert np.all(clearance <= 0.01)
            colliding += len(alone)
    assert joined > 100 and proved > 20 and proved_held > 10 and colliding > 5


def test_a_chain_of_certified_cells_is_a_free_path_from_a_to_b():
    """`path` joins two configurations of one component of the certified free cells: it
    starts at a, ends at b plus whole turns, turns no joint more than π/2 in a step, and is
    clear by more than the margin at samples 0.002 rad apart (measured exactly, not by the
    grid). Pairs it joins are never proved apart (separated)."""
    rng = np.random.default_rng(11)
    joined, apart, crossing = 0, 0, 0
    for _ in range(6):
        disks = [(tuple(rng.uniform(-2.5, 2.5, 2)), float(rng.uniform(0.1, 0.4)))
                 for _ in range(int(rng.integers(2, 7)))]
        scene = paper_scene(obstacles=disks)
        checker = CollisionChecker(scene.robot, scene.obstacles)
        walls = FreeComponents.over(scene, 64, margin=0.01)
        for a, b in rng.uniform(-np.pi, np.pi, (40, 2, 3)):
            path = walls.path(a, b)
            if path is None:
                apart += 1
                assert not walls.joined(a, b)
                continue
            joined += 1
            assert walls.joined(a, b) and not walls.separated(a, b)
            assert np.array_equal(path[0], a)
            turns = (path[-1] - b) / (2 * np.pi)
            assert np.allclose(turns, np.round(turns), atol=1e-12)
            crossing += bool(np.any(np.round(turns)))
            assert np.all(np.abs(np.diff(path, axis=0)) <= 0.5 * np.pi + 1e-9)  # no long step
            assert checker.min_clearance(densify(path, 0.002)).min() > 0.01
    assert joined > 60 and apart > 10 and crossing > 5


def test_configurations_beyond_the_grid_are_joined_to_nothing():
    walls = FreeComponents.over(paper_scene(), 32)
    a = np.zeros(3)
    for b in (np.full(3, np.nan), np.array([0.0, 0.0, np.inf])):
        assert not walls.joined(a, b) and walls.path(a, b) is None
    limited = FreeComponents.over(parse_scene({'robot': {
        'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0],
        'joint_limits': [[-1.0, 1.0]] * 3}}), 32)
    assert limited.joined(a, np.full(3, 0.5))
    assert not limited.joined(a, np.array([0.0, 1.5, 0.0]))
