"""Connected components of cell masks on a joint grid whose periodic axes wrap round.

`label_wrapped` labels a mask under any 3x3x3 structure (scipy's labelling, then the
components that meet across a periodic axis merged); `layer_labels` labels the 2-D
layers of a 3-D mask at once (cells of a layer touching at an edge or a corner), in one
compiled pass: the failure-tolerant set labels the layers of each joint (tolerant_set.py).
Both number the components 1..K and give 0 outside the mask.
"""

from __future__ import annotations

import numba
import numpy as np
from scipy import ndimage


def label_wrapped(mask: np.ndarray, structure: np.ndarray, periodic: np.ndarray,
                  ) -> np.ndarray:
    """Label the components of `mask` under `structure`, joined across periodic axes.

    Like `scipy.ndimage.label` (0 outside the mask, components numbered from 1), with
    each periodic axis wrapped round: the mask is padded by one wrapped cell along those
    axes, and a pad cell's label is merged with the label of the cell it copies.
    """
    pad = [(1, 1) if p else (0, 0) for p in periodic]
    padded = np.pad(mask, pad, mode='wrap')
    labels, count = ndimage.label(padded, structure=structure)
    inner = labels[tuple(slice(1, -1) if p else slice(None) for p in periodic)]
    if count == 0:
        return inner
    first, second = [], []
    for axis, p in enumerate(periodic):
        if not p:
            continue
        size = mask.shape[axis]
        for pad_at, source in ((0, size), (size + 1, 1)):
            a = np.take(labels, pad_at, axis=axis).ravel()
            b = np.take(labels, source, axis=axis).ravel()
            keep = (a > 0) & (b > 0)
            first.append(a[keep])
            second.append(b[keep])
    if not first:
        return inner
    offset = np.array([1 if p else 0 for p in periodic], dtype=np.int64)
    return _merged_inner(labels, count, np.concatenate(first), np.concatenate(second), offset,
                         np.array(mask.shape, dtype=np.int64))


@numba.njit(cache=True)
def _merged_inner(labels, count, first, second, offset, shape):
    """Return the labels of the cells `offset` (3,) into `labels`, merged and renumbered.

    Labels first[p] and second[p] (1..count) are one component; the merged components
    are numbered 1.. in the order of their smallest label, 0 stays the background's.
    """
    parent = np.arange(count + 1)
    for p in range(first.shape[0]):
        a, b = first[p], second[p]
        while parent[a] != a:
            a = parent[a]
        while parent[b] != b:
            b = parent[b]
        if a != b:
            parent[max(a, b)] = min(a, b)
    number = np.zeros(count + 1, dtype=np.int32)
    components = 0
    for label in range(1, count + 1):
        root = parent[label]
        while parent[root] != root:
            root = parent[root]
        if root == label:
            components += 1
            number[label] = components
        else:
            number[label] = number[root]
    out = np.empty((shape[0], shape[1], shape[2]), dtype=np.int32)
    for i in range(shape[0]):
        for j in range(shape[1]):
            for k in range(shape[2]):
                out[i, j, k] = number[labels[i + offset[0], j + offset[1], k + offset[2]]]
    return out


def layer_structure(joint: int) -> np.ndarray:
    """Return the 3x3x3 structure joining cells of one θ_joint-layer that touch (8 in 2-D)."""
    structure = np.zeros((3, 3, 3), dtype=bool)
    index = [slice(None)] * 3
    index[joint] = 1
    structure[tuple(index)] = True
    return structure


def layer_labels(mask: np.ndarray, joint: int, periodic: np.ndarray) -> np.ndarray:
    """Label the components of each θ_joint-layer of `mask` (N0, N1, N2) bool: int32.

    The same partition as `label_wrapped(mask, layer_structure(joint), periodic)` with
    the layer's own axis not wrapped: cells of a layer that touch at an edge or a corner
    are joined, round the other axes that `periodic` (3,) marks.
    """
    mask = np.ascontiguousarray(mask, dtype=np.bool_)
    first, second = (axis for axis in range(3) if axis != joint)
    labels = np.empty(mask.shape, dtype=np.int32)
    _label_layers(mask.ravel(), np.array(mask.shape, dtype=np.int64), first, second,
                  bool(periodic[first]), bool(periodic[second]), labels.ravel())
    return labels


def cells_of(labels: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """(labels.shape) bool: the cells whose label (0..K) `chosen` (K+1,) bool marks.

    The same as `chosen[labels]`, in a compiled loop (numpy's gather by int32 labels is
    slower by about three times).
    """
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
def _label_layers(mask, shape, p, q, wrap_p, wrap_q, labels):
    """Fill `labels` (flat, C order) with the layer components of `mask` (flat); return K.

    p < q are the layer's axes. One raster pass gives each cell the label of a neighbour
    met before it (back along p, or along q, or both: the earlier half of the
    8-neighbourhood), joining the labels it meets; the wrapped edges are joined after
    it; the roots are numbered 1..K in the order of their smallest label.
    """
    strides = (shape[1] * shape[2], shape[2], 1)
    sp, sq = strides[p], strides[q]
    np_, nq = shape[p], shape[q]
    # A new label needs its cell's predecessor along q empty: at most half of every row.
    parent = np.empty(mask.size // nq * ((nq + 1) // 2) + 1, dtype=np.int32)
    parent[0] = 0
    count = 0
    f = -1
    for i in range(shape[0]):
        for j in range(shape[1]):
            for k in range(shape[2]):
                f += 1
                if not mask[f]:
                    labels[f] = 0
                    continue
                cp = i if p == 0 else j
                cq = j if q == 1 else k
                if cp > 0 and mask[f - sp]:
                    labels[f] = labels[f - sp]  # every earlier neighbour touches this one
                    continue
                found = 0
                if cp > 0 and cq + 1 < nq and mask[f - sp + sq]:
                    found = labels[f - sp + sq]
                if cq > 0 and mask[f - sq]:
                    found = labels[f - sq] if found == 0 else \
                        _join(parent, found, labels[f - sq])
                elif cp > 0 and cq > 0 and mask[f - sp - sq]:
                    found = labels[f - sp - sq] if found == 0 else \
                        _join(parent, found, labels[f - sp - sq])
                if found == 0:
                    count += 1
                    parent[count] = count
                    found = count
                labels[f] = found
    layer_axis = 3 - p - q
    sr = strides[layer_axis]
    for r in range(shape[layer_axis]):
        if wrap_q:  # the end of each row joins its start, one row either side
            for cp in range(np_):
                f = r * sr + cp * sp + (nq - 1) * sq
                if mask[f]:
                    for dp in (-1, 0, 1):
                        other = (cp + dp) % np_ if wrap_p else cp + dp
                        g = r * sr + other * sp
                        if 0 <= other < np_ and mask[g]:
                            _join(parent, labels[f], labels[g])
        if wrap_p:
            for cq in range(nq):
                f = r * sr + (np_ - 1) * sp + cq * sq
                if mask[f]:
                    for dq in (-1, 0, 1):
                        other = (cq + dq) % nq if wrap_q else cq + dq
                        g = r * sr + other * sq
                        if 0 <= other < nq and mask[g]:
                            _join(parent, labels[f], labels[g])
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
