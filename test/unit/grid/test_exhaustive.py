"""The brute-force reference itself: periodic labelling and the grid baseline."""

from collections import deque

import numpy as np
from ftplan_testing import paper_scene

from ftplan_ros.core import CollisionChecker
from ftplan_ros.core.grid.exhaustive import JointGrid, grid_plan, label_periodic


def naive_components(mask, periodic):
    """Breadth-first search with full connectivity and wrap-around: a slow, obvious labelling."""
    labels = np.zeros(mask.shape, dtype=int)
    offsets = [np.array(o) for o in np.ndindex(*(3,) * mask.ndim)]
    count = 0
    for start in zip(*np.nonzero(mask), strict=True):
        if labels[start]:
            continue
        count += 1
        labels[start] = count
        queue = deque([np.array(start)])
        while queue:
            cell = queue.popleft()
            for offset in offsets:
                near = cell + offset - 1
                inside = True
                for axis, size in enumerate(mask.shape):
                    if periodic[axis]:
                        near[axis] %= size
                    elif not 0 <= near[axis] < size:
                        inside = False
                if inside and mask[tuple(near)] and not labels[tuple(near)]:
                    labels[tuple(near)] = count
                    queue.append(near)
    return labels


def same_partition(a, b):
    pairs = set(zip(a[a > 0].tolist(), b[b > 0].tolist(), strict=True))
    return len(pairs) == len(set(a[a > 0].tolist())) == len(set(b[b > 0].tolist()))


def test_periodic_labels_match_a_naive_search():
    rng = np.random.default_rng(0)
    for shape, periodic in [((9, 7), (True, True)), ((8, 8), (True, False)),
                            ((6, 5, 4), (True, False, True))]:
        for _ in range(20):
            mask = rng.uniform(size=shape) < 0.35
            fast = label_periodic(mask, np.array(periodic))
            assert np.array_equal(fast > 0, mask)
            assert same_partition(fast, naive_components(mask, periodic))


def test_grid_cells_wrap():
    grid = JointGrid.over(paper_scene().robot, 36)
    assert grid.cell_of(np.array([np.pi - 1e-9, -np.pi, 3 * np.pi + 0.01])) == (35, 0, 0)


def test_grid_baseline_answers():
    free = paper_scene()
    checker = CollisionChecker(free.robot, free.obstacles)
    assert grid_plan(checker, np.array([2.0, 0.0]), np.array([1.0, 0.0]), 40).feasible
    blocked = paper_scene(obstacles=[((1.0, 0.0), 0.25)])  # every goal configuration collides
    checker = CollisionChecker(blocked.robot, blocked.obstacles)
    answer = grid_plan(checker, np.array([2.0, 0.0]), np.array([1.0, 0.0]), 40)
    assert not answer.feasible and answer.safe_cells == 0 and answer.free_cells > 0
