"""Connected components of cell masks on a joint grid whose periodic axes wrap round.

`label_components` labels a 3-D mask in one compiled pass over runs. Cells are joined
when they touch at a face, an edge or a corner within the axes it is told (all three:
the 26 neighbours; two: the 8 neighbours in each layer across the third, as the
failure-tolerant set labels the layers of each joint, tolerant_set.py), round the
periodic ones. Components are numbered 1..K, and 0 is outside the mask.
"""

from __future__ import annotations

import numba
import numpy as np


def label_components(mask: np.ndarray, periodic: np.ndarray,
                     across: tuple[int, ...] = (0, 1, 2)) -> np.ndarray:
    """Label the components of `mask` (N0, N1, N2) bool: int32 (N0, N1, N2).

    Cells are neighbours when their indices differ by at most one along each axis of
    `across` and not at all along the others; along an axis that `periodic` (3,) marks,
    index 0 and index N-1 differ by one.
    """
    mask = np.ascontiguousarray(mask, dtype=np.bool_)
    across = tuple(sorted(across))
    labels = np.empty(mask.shape, dtype=np.int32)
    if mask.size == 0:
        return labels
    along = across[-1]
    lines = [axis for axis in range(3) if axis != along]
    _label(mask.ravel(), np.array(mask.shape, dtype=np.int64),
           np.array(lines + [along], dtype=np.int64),
           np.array([axis in across for axis in lines]),
           np.array([axis in across and bool(periodic[axis]) for axis in lines + [along]]),
           labels.ravel())
    return labels


def layer_labels(mask: np.ndarray, joint: int, periodic: np.ndarray) -> np.ndarray:
    """Label the components of each θ_joint-layer of `mask` (cells touching in the layer)."""
    return label_components(mask, periodic, tuple(a for a in range(3) if a != joint))


def cells_of(labels: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """(labels.shape) bool: the cells whose label (0..K) `chosen` (K+1,) bool marks.

    The same as `chosen[labels]`, in a compiled loop (numpy's gather by int32 labels is
    slower by about three times).
    """
    if labels.size and not 0 <= labels.min() <= labels.max() < len(chosen):
        raise ValueError(f'labels 0..{labels.max()} need {labels.max() + 1} choices, '
                         f'got {len(chosen)}')
    out = np.empty(labels.shape, dtype=np.bool_)
    _gather(np.ascontiguousarray(chosen, dtype=np.bool_), np.ascontiguousarray(labels).ravel(),
            out.ravel())
    return out


@numba.njit(cache=True)
def _gather(chosen, labels, out):
    """out[f] = chosen[labels[f]] for every cell f (flat arrays)."""
    for f in range(labels.size):
        out[f] = chosen[labels[f]]


@numba.njit(cache=True)
def _root(parent, label):
    """Return the root of `label` in the union-find forest `parent`, halving the path."""
    while parent[label] != label:
        parent[label] = parent[parent[label]]
        label = parent[label]
    return label


@numba.njit(cache=True)
def _join(parent, a, b):
    """Join the trees of labels a and b under the smaller root; return that root."""
    a, b = _root(parent, a), _root(parent, b)
    if a < b:
        parent[b] = a
        return a
    parent[a] = b
    return b


@numba.njit(cache=True)
def _label(mask, shape, axes, joined, wrap, labels):
    """Fill `labels` (flat, C order) with the components of `mask` (flat); return K.

    The cells lie on lines along the last of `axes` (3,), one line per index pair along
    the first two; each line's cells in the mask form runs. A run is one node of a
    union-find forest: runs on neighbouring lines (a step along each of the first two
    axes that `joined` (2,) marks, round those `wrap` (3,) marks) are joined where they
    overlap once widened by a cell, and the last run of a line to the first of its
    neighbours round a wrapped last axis. Roots are numbered 1..K in run order.
    """
    strides = np.array([shape[1] * shape[2], shape[2], 1], dtype=np.int64)
    size_p, size_q, size_r = shape[axes[0]], shape[axes[1]], shape[axes[2]]
    step_p, step_q, step_r = strides[axes[0]], strides[axes[1]], strides[axes[2]]
    lines = size_p * size_q
    first = np.empty(lines + 1, dtype=np.int64)  # line l holds runs first[l]..first[l+1]-1
    starts = np.empty(lines * ((size_r + 1) // 2), dtype=np.int32)
    ends = np.empty_like(starts)
    count = 0
    for line in range(lines):
        first[line] = count
        base = (line // size_q) * step_p + (line % size_q) * step_q
        r = 0
        while r < size_r:
            if mask[base + r * step_r]:
                starts[count] = r
                while r + 1 < size_r and mask[base + (r + 1) * step_r]:
                    r += 1
                ends[count] = r
                count += 1
            r += 1
    first[lines] = count
    parent = np.arange(count, dtype=np.int32)
    # Each pair of neighbouring lines once: the neighbours one step back (as C order).
    steps = np.array([[-1, -1], [-1, 0], [-1, 1], [0, -1], [0, 0]], dtype=np.int64)
    for line in range(lines):
        p, q = line // size_q, line % size_q
        for s in range(steps.shape[0]):
            dp, dq = steps[s, 0], steps[s, 1]
            if (dp != 0 and not joined[0]) or (dq != 0 and not joined[1]):
                continue
            if dp == 0 and dq == 0 and not wrap[2]:
                continue
            other_p = _index_along(p + dp, size_p, wrap[0])
            other_q = _index_along(q + dq, size_q, wrap[1])
            if other_p < 0 or other_q < 0:
                continue
            other = other_p * size_q + other_q
            if dp != 0 or dq != 0:
                _join_overlaps(parent, starts, ends, first[line], first[line + 1],
                               first[other], first[other + 1])
            if wrap[2]:
                _join_round(parent, starts, ends, first[line], first[line + 1], first[other],
                            first[other + 1], size_r)
    number = np.zeros(count, dtype=np.int32)
    components = 0
    for run in range(count):
        root = _root(parent, run)
        if root == run:
            components += 1
            number[run] = components
        else:
            number[run] = number[root]  # a root is the smallest run of its tree: numbered
    for line in range(lines):
        base = (line // size_q) * step_p + (line % size_q) * step_q
        r = 0
        for run in range(first[line], first[line + 1]):
            while r < starts[run]:
                labels[base + r * step_r] = 0
                r += 1
            while r <= ends[run]:
                labels[base + r * step_r] = number[run]
                r += 1
        while r < size_r:
            labels[base + r * step_r] = 0
            r += 1
    return components


@numba.njit(cache=True)
def _join_overlaps(parent, starts, ends, a, a_end, b, b_end):
    """Join the runs a..a_end-1 and b..b_end-1 (each sorted) that overlap once widened by a cell."""
    while a < a_end and b < b_end:
        if starts[b] <= ends[a] + 1 and ends[b] >= starts[a] - 1:
            _join(parent, a, b)
        if ends[a] < ends[b]:
            a += 1
        else:
            b += 1


@numba.njit(cache=True)
def _join_round(parent, starts, ends, a, a_end, b, b_end, size):
    """Join a line's last run to another's first where they touch round a wrapped axis."""
    if a == a_end or b == b_end:
        return
    if ends[a_end - 1] == size - 1 and starts[b] == 0:
        _join(parent, a_end - 1, b)
    if ends[b_end - 1] == size - 1 and starts[a] == 0:
        _join(parent, b_end - 1, a)


@numba.njit(cache=True)
def _index_along(index, size, wrap):
    """Return `index` on an axis of `size` cells, wrapped round if `wrap`; -1 if off it."""
    if wrap:
        return index % size
    return index if 0 <= index < size else -1
