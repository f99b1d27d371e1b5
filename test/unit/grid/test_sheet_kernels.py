"""The recovery sheets' compiled grid kernels (core/grid/sheet_kernels.py) against brute force."""

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import shortest_path

from ftplan_ros.core.grid.sheet_kernels import _piece_middles, bfs, greedy_cuts, mask_triangle_free


def test_the_grid_search_finds_a_shortest_path_through_the_mask():
    """`bfs` against shortest path lengths on the explicit graph of neighbouring cells."""
    rng = np.random.default_rng(21)
    found = 0
    for trial in range(200):
        dims = 2 + trial % 2
        shape = tuple(rng.integers(2, 12 if dims == 2 else 6, dims))
        mask = rng.random(shape) < 0.7
        target = mask & (rng.random(shape) < 0.05)
        periodic = rng.random(dims) < 0.5
        sources = np.argwhere(mask)[rng.integers(0, max(1, mask.sum()), 2)] if mask.any() \
            else np.zeros((1, dims), dtype=np.int64)
        cells = np.argwhere(mask)
        index = np.full(shape, -1)
        index[tuple(cells.T)] = np.arange(len(cells))
        u, v = [], []
        for offset in np.ndindex(*(3,) * dims):
            step = np.array(offset) - 1
            if not step.any():
                continue
            to = cells + step
            ok = np.all(periodic | ((to >= 0) & (to < shape)), axis=1)
            to = np.mod(to[ok], shape)
            keep = mask[tuple(to.T)]
            u.append(np.flatnonzero(ok)[keep])
            v.append(index[tuple(to[keep].T)])
        graph = coo_matrix((np.ones(sum(map(len, u))), (np.concatenate(u), np.concatenate(v))),
                           shape=(len(cells), len(cells)))
        distance = shortest_path(graph, unweighted=True,
                                 indices=index[tuple(sources.T)][mask[tuple(sources.T)]])
        goals = index[tuple(np.argwhere(target).T)]
        nearest = distance[:, goals].min() if len(goals) and len(distance) else np.inf
        path = bfs(mask, periodic, sources, target)
        if not np.isfinite(nearest):
            assert path is None, trial
            continue
        found += 1
        assert len(path) - 1 == nearest, trial
        assert mask[tuple(path.T)].all() and target[tuple(path[-1])]
        assert any(np.array_equal(path[0], s) for s in sources)
        gaps = np.abs(np.diff(path, axis=0))
        gaps = np.where(periodic, np.minimum(gaps, np.array(shape) - gaps), gaps)
        assert gaps.max(initial=0) <= 1, trial
    assert found > 50


def sorted_piece_middles(a, b):
    """Reference for `_piece_middles`: every grid crossing's t, sorted; slivers left out."""
    ts = [0.0, 1.0]
    for axis in range(len(a)):
        low, high = sorted((a[axis], b[axis]))
        ts += [(line - a[axis]) / (b[axis] - a[axis])
               for line in np.arange(np.floor(low) + 1.0, high) if line < high]
    ts = np.sort(ts)
    sliver = 1e-9 / max(1e-300, np.abs(b - a).max())
    pieces = np.diff(ts)
    keep = (pieces > sliver) | (len(pieces) == 1)
    return 0.5 * (ts[:-1] + ts[1:])[keep]


def test_a_segments_pieces_come_in_order_at_every_grid_crossing():
    """`_piece_middles` against sorting every crossing, on segments through grid lines and
    corners, of no length, or nearly on a line; and the cells of dense samples (off the
    grid lines) are the cells of the middles."""
    rng = np.random.default_rng(8)
    for trial in range(3000):
        dims = 2 + trial % 2
        a = rng.integers(-3, 9, dims) * rng.choice([1.0, 0.5])
        b = a.copy() if trial % 11 == 0 else rng.integers(-3, 9, dims) * rng.choice([1.0, 0.5])
        if trial % 3:
            a = a + rng.uniform(-1.0, 1.0, dims) * rng.choice([1.0, 1e-10])
            b = b + rng.uniform(-1.0, 1.0, dims) * rng.choice([1.0, 1e-10])
        middles = _piece_middles(a, b)
        expected = sorted_piece_middles(a, b)
        assert middles.shape == expected.shape and np.array_equal(middles, expected), trial
        samples = a + np.linspace(0.0, 1.0, 2001)[:, None] * (b - a)
        off_lines = np.all(np.abs(samples - np.round(samples)) > 1e-6, axis=1)
        seen = {tuple(c) for c in np.floor(samples[off_lines]).astype(int)}
        cells = {tuple(c) for c in np.floor(a + middles[:, None] * (b - a)).astype(int)}
        assert seen <= cells, trial


def test_straight_cuts_stay_in_the_mask_and_within_the_longest_cut():
    """`greedy_cuts` on random walks through random masks, 2-D and 3-D, periodic or not.

    A step to the next point is the caller's path and is kept as it is; every longer cut
    is sampled densely (the cells it passes are found by flooring the samples), so a cut
    through a cell outside the mask fails the test. Each cut is also checked not to be
    longer than allowed, and the walk's ends are kept.
    """
    rng = np.random.default_rng(5)
    shortened = 0
    for trial in range(120):
        dims = 2 + trial % 2
        size = 10
        mask = rng.random((size,) * dims) < 0.8
        periodic = rng.random(dims) < 0.5
        steps = rng.integers(-1, 2, (40, dims))
        walk = np.cumsum(np.vstack([rng.integers(0, size, dims), steps]), axis=0)
        cells = np.where(periodic, np.mod(walk, size), np.clip(walk, 0, size - 1))
        mask[tuple(cells.T)] = True  # the walk's own cells are free
        offsets = np.where(periodic, walk, cells) + 0.5 + rng.uniform(-0.3, 0.3, walk.shape)
        longest = rng.choice([3.0, 16.0, np.inf])
        kept = greedy_cuts(mask, periodic, offsets, longest)
        assert kept[0] == 0 and kept[-1] == len(offsets) - 1, trial
        assert np.all(np.diff(kept) > 0), trial
        for first, last in zip(kept[:-1], kept[1:], strict=True):
            if last == first + 1:
                continue
            a, b = offsets[first], offsets[last]
            assert np.abs(b - a).max() <= longest, trial
            samples = np.floor(a + np.linspace(0.0, 1.0, 4001)[:, None] * (b - a)).astype(int)
            inside = np.all(periodic | ((samples >= 0) & (samples < size)), axis=1)
            assert inside.all(), trial
            assert mask[tuple(np.mod(samples, size).T)].all(), trial
        shortened += len(kept) < len(offsets)
    assert shortened > 60


def triangle_meets_cell(corners, cell):
    """Whether the closed triangle (3, 2) and the closed unit square at `cell` (2,) meet:
    no separating axis among the square's two and the triangle's three edge normals."""
    square = np.asarray(cell, dtype=float) + np.array([[0, 0], [1, 0], [0, 1], [1, 1]])
    edges = np.roll(corners, -1, axis=0) - corners
    axes = np.vstack([np.eye(2), np.stack([-edges[:, 1], edges[:, 0]], axis=1)])
    for axis in axes:
        on_triangle, on_square = corners @ axis, square @ axis
        if on_triangle.max() < on_square.min() - 1e-12 or \
                on_square.max() < on_triangle.min() - 1e-12:
            return False
    return True


def test_a_triangle_is_free_exactly_when_no_cell_it_meets_is_blocked():
    """`mask_triangle_free` on random triangles (large, small, thin, on grid lines, leaving a
    bounded axis) in masks with one blocked cell: a dense sample of the triangle inside
    the blocked cell makes it not free, and a triangle said not free meets the blocked
    cell or leaves a bounded axis (exact separating-axis test)."""
    rng = np.random.default_rng(12)
    size = 12
    blocked_hits = 0
    weights = np.array([(i, j) for i in range(61) for j in range(61 - i)]) / 60.0
    for trial in range(3000):
        periodic = rng.random(2) < 0.5
        span = rng.choice([0.3, 2.0, 6.0, 14.0])
        corners = rng.uniform(-2.0, size + 2.0, 2) + rng.uniform(-span, span, (3, 2))
        corners[0] = rng.uniform(-2.0, size + 2.0, 2)
        if trial % 4 == 0:
            corners = np.round(corners * 2.0) / 2.0  # on grid lines and cell centres
        cell = rng.integers(0, size, 2)
        mask = np.ones((size, size), dtype=bool)
        mask[tuple(cell)] = False
        free = mask_triangle_free(mask, corners[0], corners[1], corners[2], periodic)
        # Copies of the blocked cell round the periodic axes, near the triangle.
        shifts = [np.array([i, j]) * size for i in (-2, -1, 0, 1, 2) for j in (-2, -1, 0, 1, 2)
                  if (i == 0 or periodic[0]) and (j == 0 or periodic[1])]
        copies = [cell + shift for shift in shifts]
        points = corners[0] + weights[:, :1] * (corners[1] - corners[0]) \
            + weights[:, 1:] * (corners[2] - corners[0])
        off_lines = np.all(np.abs(points - np.round(points)) > 1e-6, axis=1)
        inside = points[off_lines]
        sampled = any(np.all(np.floor(inside) == copy, axis=1).any() for copy in copies)
        leaves = np.any(~periodic & ((inside < 0) | (inside >= size)).any(axis=0))
        if sampled or leaves:
            assert not free, trial
        if not free:
            blocked_hits += 1
            low, high = corners.min(axis=0), corners.max(axis=0)
            beyond = np.any(~periodic & ((low < -1e-9) | (high > size + 1e-9)))
            assert beyond or any(triangle_meets_cell(corners, copy) for copy in copies), trial
    assert 300 < blocked_hits < 2700
    mask = np.ones((size, size), dtype=bool)
    for bad in (np.nan, np.inf):
        assert not mask_triangle_free(mask, np.array([1.0, 1.0]), np.array([2.0, bad]),
                                  np.array([3.0, 1.0]), np.ones(2, dtype=bool))
