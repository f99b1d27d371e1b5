"""Connected components of cell masks on a joint grid whose periodic axes wrap round.

`label_components` labels a 3-D mask in one compiled union-find pass. Cells are joined
when they touch at a face, an edge or a corner within the axes it is told (all three:
the 26 neighbours; two: the 8 neighbours in each layer across the third, as the
failure-tolerant set labels the layers of each joint, tolerant_set.py), round the
periodic ones. Components are numbered 1..K, and 0 is outside the mask.
"""

from __future__ import annotations

import itertools

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
    labels = np.zeros(mask.shape, dtype=np.int32)
    if mask.size == 0:
        return labels
    _label(mask.ravel(), np.array(mask.shape, dtype=np.int64), _earlier_neighbours(across),
           np.array([axis in across and bool(periodic[axis]) for axis in range(3)]),
           np.array(across, dtype=np.int64), labels.ravel())
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


def _earlier_neighbours(across: tuple[int, ...]) -> np.ndarray:
    """Offsets (k, 3) to the neighbours a C-order pass meets before the cell, one behind first.

    The neighbour one step back along the first axis of `across` touches all the others,
    so when it is in the mask the others are already joined to it.
    """
    offsets = []
    for steps in itertools.product((-1, 0, 1), repeat=len(across)):
        if steps < (0,) * len(across):  # earlier in C order
            offset = [0, 0, 0]
            for axis, step in zip(across, steps, strict=True):
                offset[axis] = step
            offsets.append(offset)
    behind = [0, 0, 0]
    behind[across[0]] = -1
    offsets.sort(key=lambda offset: offset != behind)
    return np.array(offsets, dtype=np.int64)


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
def _label(mask, shape, earlier, wrap, across, labels):
    """Fill `labels` (flat, C order) with the components of `mask` (flat); return K.

    One pass in C order gives each cell the label of its first earlier neighbour in the
    mask and joins the labels of the others (`earlier` (k, 3) offsets, one behind first);
    then the last cell along each wrapped axis is joined to the first cells its
    neighbours wrap round to; the roots are numbered 1..K by their smallest label.
    """
    strides = np.array([shape[1] * shape[2], shape[2], 1], dtype=np.int64)
    # A new label needs its cell's predecessor along the last axis of `across` out of the
    # mask: at most half the cells of each line along that axis get one.
    line = shape[across[-1]]
    parent = np.empty(mask.size // line * ((line + 1) // 2) + 1, dtype=np.int32)
    parent[0] = 0
    count = 0
    delta = (earlier * strides).sum(axis=1)  # flat offsets of the earlier neighbours
    low = np.zeros(3, dtype=np.int64)  # cells inside [low, high] on every axis have them all
    high = shape - 1
    for axis in across:
        low[axis], high[axis] = 1, shape[axis] - 2
    f = -1
    for i in range(shape[0]):
        for j in range(shape[1]):
            for k in range(shape[2]):
                f += 1
                if not mask[f]:
                    labels[f] = 0
                    continue
                back = i if across[0] == 0 else j if across[0] == 1 else k
                if back > 0 and mask[f + delta[0]]:
                    # The one behind touches every other earlier neighbour: they are joined.
                    labels[f] = labels[f + delta[0]]
                    continue
                interior = low[0] <= i <= high[0] and low[1] <= j <= high[1] \
                    and low[2] <= k <= high[2]
                found = 0
                for o in range(1, earlier.shape[0]):
                    if not interior and not (
                            0 <= i + earlier[o, 0] < shape[0]
                            and 0 <= j + earlier[o, 1] < shape[1]
                            and 0 <= k + earlier[o, 2] < shape[2]):
                        continue
                    g = f + delta[o]
                    if mask[g]:
                        found = labels[g] if found == 0 else _join(parent, found, labels[g])
                if found == 0:
                    count += 1
                    parent[count] = count
                    found = count
                labels[f] = found
    for axis in range(3):
        if wrap[axis]:
            _join_round(mask, shape, strides, wrap, across, axis, parent, labels)
    number = np.zeros(count + 1, dtype=np.int32)
    components = 0
    for label in range(1, count + 1):
        root = _root(parent, label)
        if root == label:
            components += 1
            number[label] = components
        else:
            number[label] = number[root]
    for f in range(mask.size):
        labels[f] = number[labels[f]]
    return components


@numba.njit(cache=True)
def _join_round(mask, shape, strides, wrap, across, axis, parent, labels):
    """Join the cells last along `axis` to their neighbours first along it (wrapped round)."""
    b, c = (1, 2) if axis == 0 else (0, 2) if axis == 1 else (0, 1)
    reach_b = 1 if b in across else 0  # how far a neighbour may be along b and c
    reach_c = 1 if c in across else 0
    last = (shape[axis] - 1) * strides[axis]
    for u in range(shape[b]):
        for v in range(shape[c]):
            f = last + u * strides[b] + v * strides[c]
            if not mask[f]:
                continue
            for du in range(-reach_b, reach_b + 1):
                x = _index_along(u + du, shape[b], wrap[b])
                for dv in range(-reach_c, reach_c + 1):
                    y = _index_along(v + dv, shape[c], wrap[c])
                    if x >= 0 and y >= 0 and mask[x * strides[b] + y * strides[c]]:
                        _join(parent, labels[f], labels[x * strides[b] + y * strides[c]])


@numba.njit(cache=True)
def _index_along(index, size, wrap):
    """Return `index` on an axis of `size` cells, wrapped round if `wrap`; -1 if off it."""
    if wrap:
        return index % size
    return index if 0 <= index < size else -1
