"""Connected components on a joint grid (core/grid/components.py) against an explicit graph."""

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ftplan_ros.core.grid.components import components, layer_components, overlap


def union_find_labels(mask, structure, periodic):
    """Components of mask under structure, wrapping periodic axes: an explicit graph."""
    shape = np.array(mask.shape)
    index = np.arange(mask.size).reshape(mask.shape)
    u, v = [], []
    for offset in np.argwhere(structure) - 1:
        target = np.argwhere(mask) + offset
        inside = np.all(periodic | ((target >= 0) & (target < shape)), axis=1)
        source = np.argwhere(mask)[inside]
        target = np.mod(target[inside], shape)
        keep = mask[tuple(target.T)]
        u.append(index[tuple(source[keep].T)])
        v.append(index[tuple(target[keep].T)])
    u, v = np.concatenate(u), np.concatenate(v)
    graph = coo_matrix((np.ones(len(u)), (u, v)), shape=(mask.size, mask.size))
    _, label = connected_components(graph, directed=False)
    return label.reshape(mask.shape)


def test_label_components_finds_the_components_round_the_torus():
    """The compiled labelling against the explicit graph: all 26 neighbours, or a layer's 8."""
    rng = np.random.default_rng(12)
    for trial in range(400):
        shape = tuple(rng.integers(1, 8, 3))
        mask = rng.random(shape) < rng.uniform(0.2, 0.8)
        periodic = rng.random(3) < 0.5
        joint = int(rng.integers(3))
        if trial % 2:
            labels, structure = components(mask, periodic).labels(), np.ones((3, 3, 3), bool)
        else:
            labels = layer_components(mask, joint, periodic).labels()
            structure = np.zeros((3, 3, 3), bool)
            structure[(slice(None),) * joint + (1,)] = True  # one layer: index 1 along it
        assert labels.dtype == np.int32
        assert np.all((labels > 0) == mask)
        assert np.array_equal(np.unique(labels[mask]), np.arange(1, labels.max() + 1))
        truth = union_find_labels(mask, structure, periodic)
        a, b = labels[mask], truth[mask]
        # The same partition: equal labels exactly where the referee's are equal.
        assert np.array_equal(a[:, None] == a[None, :], b[:, None] == b[None, :]), trial
        # What the runs answer without labels: the same as the labels say.
        found = components(mask, periodic, (0, 1, 2) if trial % 2 else
                           tuple(a for a in range(3) if a != joint))
        chosen = rng.random(labels.max() + 1) < 0.5
        assert np.array_equal(found.cells(chosen), chosen[labels] & mask)
        cells = np.argwhere(np.ones(shape, bool))
        assert np.array_equal(found.at(cells), labels[tuple(cells.T)])
        seeds = rng.random(shape) < 0.2
        holding = np.zeros(labels.max() + 1, bool)
        holding[labels[seeds & mask]] = True
        assert np.array_equal(found.holding(seeds), holding)
    for shape in ((0, 3, 3), (3, 3, 0)):  # no cell: no component, and no write outside
        assert components(np.zeros(shape, bool), np.ones(3, bool)).labels().shape == shape
    found = components(np.ones((4, 4, 4), bool), np.zeros(3, bool))
    with pytest.raises(ValueError, match='need 2 choices'):
        found.cells(np.array([False]))
    with pytest.raises(ValueError, match='within the grid'):
        found.at(np.array([[0, 4, 0]]))
    with pytest.raises(ValueError, match='must have the shape'):
        found.holding(np.ones((4, 4, 3), bool))
    for cells in (np.zeros((3, 2), int), np.array([[0.9, 0.2, 3.7]])):
        with pytest.raises(ValueError, match=r'integer indices \(k, 3\)'):
            found.at(cells)
    with pytest.raises(ValueError, match='need 2 choices'):
        found.cells(np.bool_(True))
    for across in ((), (-1, 0), (0, 3)):
        with pytest.raises(ValueError, match='across must name axes'):
            components(np.ones((4, 4, 4), bool), np.zeros(3, bool), across)
    with pytest.raises(ValueError, match='3 flags'):
        components(np.ones((4, 4, 4), bool), np.zeros(2, bool))
    with pytest.raises(ValueError, match=r'3-D, got shape \(\)'):
        components(np.bool_(True), np.zeros(3, bool))
    with pytest.raises(ValueError, match='joint must be'):
        layer_components(np.ones((4, 4, 4), bool), 3, np.zeros(3, bool))


def test_label_components_reads_whole_words_of_cells_as_cell_by_cell():
    """Grids of 8 and 16 cells per axis, read eight cells at a time, against the explicit graph.

    The masks are blocky (4-cell blocks, a few cells flipped), so lines and rows hold
    whole words of eight cells in and out of the mask as well as words that change.
    """
    rng = np.random.default_rng(14)
    for trial in range(40):
        shape = tuple(int(v) for v in rng.choice([8, 16], 3))
        blocks = rng.random(tuple(v // 4 for v in shape)) < rng.uniform(0.3, 0.7)
        mask = np.kron(blocks, np.ones((4, 4, 4), bool)).astype(bool)
        mask ^= rng.random(shape) < 0.03
        periodic = rng.random(3) < 0.5
        for joint in (None, 0, 1, 2):
            if joint is None:
                labels, structure = components(mask, periodic).labels(), np.ones((3, 3, 3), bool)
            else:
                labels = layer_components(mask, joint, periodic).labels()
                structure = np.zeros((3, 3, 3), bool)
                structure[(slice(None),) * joint + (1,)] = True
            assert np.all((labels > 0) == mask)
            a, b = labels[mask], union_find_labels(mask, structure, periodic)[mask]
            assert np.array_equal(a[:, None] == a[None, :], b[:, None] == b[None, :]), \
                (trial, joint)


def test_clearing_the_other_components_keeps_the_chosen_ones_cells():
    rng = np.random.default_rng(16)
    for _ in range(30):
        shape = tuple(int(v) for v in rng.integers(1, 12, 3))
        mask = rng.random(shape) < 0.5
        for found in (components(mask, rng.random(3) < 0.5),
                      layer_components(mask, int(rng.integers(0, 3)), rng.random(3) < 0.5)):
            chosen = rng.random(found.count + 1) < 0.5
            out = mask & (rng.random(shape) < 0.7)
            expected = out & found.cells(chosen)
            found.clear_others(chosen, out)
            assert np.array_equal(out, expected)
    with pytest.raises(ValueError, match='C-contiguous'):
        found.clear_others(chosen, np.asfortranarray(np.ones((2, 3, 4), bool)))


def test_overlap_is_whether_two_masks_share_a_cell():
    """Random masks, and disjoint ones but for one cell, in sizes read eight cells at a time."""
    rng = np.random.default_rng(15)
    for trial in range(100):
        shape = tuple(int(v) for v in rng.integers(1, 9, 3)) if trial % 2 else (8, 4, 2)
        a, b = (rng.random(shape) < rng.uniform(0.0, 0.2) for _ in range(2))
        assert overlap(a, b) == bool((a & b).any())
        assert overlap(a, a) == bool(a.any())
        a = rng.random(shape) < 0.5
        b = ~a
        assert not overlap(a, b)
        shared = tuple(int(rng.integers(0, v)) for v in shape)
        a[shared] = b[shared] = True
        assert overlap(a, b)
    with pytest.raises(ValueError, match='shapes'):
        overlap(np.ones((2, 2, 2), bool), np.ones((2, 2, 3), bool))
