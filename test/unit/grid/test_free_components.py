"""Free components of the joint grid (core/grid/free_components.py): sound proofs of no move."""

import numpy as np
from ftplan_testing import paper_scene

from ftplan_ros.core import CollisionChecker
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
