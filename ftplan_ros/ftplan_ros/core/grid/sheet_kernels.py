"""Compiled kernels of the recovery sheets: routes, cuts and triangles on 2-D cell masks.

A layer of the joint grid (`tolerant_set.py`) seen across one joint is a 2-D mask of
certified cells, periodic where the joints wrap. The sheet builder (`sheet_builder.py`)
routes through it breadth-first (`bfs`), shortens routes by straight cuts that stay in
the mask (`shortcut`), and checks triangles of its sheets against it
(`mask_triangle_free`). Positions are in cell units unless a docstring says radians.
"""

from __future__ import annotations

import numba
import numpy as np

# [cells] longest straight cut of a route: the self-check quarters a triangle a bounded
# number of times, so a triangle many cells wide near an obstacle would go uncertified
_LONGEST_CUT = 16


@numba.njit(cache=True)
def wrap_index(index, periodic, size):
    """Return a cell index on an axis of `size` cells: wrapped if periodic, else clipped."""
    return index % size if periodic else min(max(index, 0), size - 1)


def shortcut(points: np.ndarray, mask: np.ndarray, lower: np.ndarray, step: np.ndarray,
              periodic: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drop route points (r, 2) while the straight cut between the kept ones stays in mask.

    A cut spans at most `_LONGEST_CUT` cells along each axis. Returns the kept points and
    the cells (c, 2) their segments pass through.
    """
    offsets = (points - lower) / step
    kept = greedy_cuts(mask, periodic, offsets, _LONGEST_CUT)
    return points[kept], route_cells(offsets[kept], periodic.astype(np.bool_), mask.shape[0])


@numba.njit(cache=True)
def mask_triangle_free(mask, a, b, c, periodic):
    """Whether every cell the triangle a, b, c (in cell units) meets is in the 2-D mask.

    Row by row along the first axis: within a row's band, the triangle reaches along the
    second axis from the least to the greatest of its corners in the band and its edges'
    crossings of the band's two lines; every cell of that reach is checked. Cells the
    triangle meets by less than a billionth of a cell (a boundary it runs along) are
    left out, as `_cut_free` leaves out such pieces. A corner that is not finite is not
    free.
    """
    corners = np.empty((3, 2))
    corners[0], corners[1], corners[2] = a, b, c
    if not np.all(np.isfinite(corners)):
        return False
    low, high = corners[:, 0].min(), corners[:, 0].max()
    first = int(np.floor(low + _SLIVER))
    last = max(first, int(np.ceil(high - _SLIVER)) - 1)
    for row in range(first, last + 1):
        bottom, top = max(float(row), low), min(row + 1.0, high)
        least, most = np.inf, -np.inf
        for k in range(3):
            if bottom <= corners[k, 0] <= top:
                least, most = min(least, corners[k, 1]), max(most, corners[k, 1])
            p, q = corners[k], corners[(k + 1) % 3]
            if p[0] == q[0]:
                continue  # along the band: its corners count
            for level in (bottom, top):
                if min(p[0], q[0]) <= level <= max(p[0], q[0]):
                    across = p[1] + (level - p[0]) * (q[1] - p[1]) / (q[0] - p[0])
                    least, most = min(least, across), max(most, across)
        if not _row_free(mask, periodic, row, least, most):
            return False
    return True


@numba.njit(cache=True, inline='always')
def _row_free(mask, periodic, row, least, most):
    """Whether the cells of `row` from `least` to `most` (cell units) are all in the mask."""
    size_row, size_column = mask.shape
    if periodic[0]:
        row %= size_row
    elif row < 0 or row >= size_row:
        return False
    first = int(np.floor(least + _SLIVER))
    last = max(first, int(np.ceil(most - _SLIVER)) - 1)
    for column in range(first, last + 1):
        if periodic[1]:
            at = column % size_column
        elif 0 <= column < size_column:
            at = column
        else:
            return False
        if not mask[row, at]:
            return False
    return True


# [cells] how little of a cell a triangle may meet and leave it out (rounding at a line)
_SLIVER = 1e-9


@numba.njit(cache=True)
def _piece_middles(a, b):
    """Return t in [0, 1] at the middle of each piece of segment a-b between grid crossings.

    a and b are in cell units, of any dimension. Pieces shorter than a billionth of a
    cell are rounding at a grid line and are left out, so a segment through a grid corner
    does not enter the cells beside it.
    """
    crossings = np.empty((2, a.shape[0]))
    pieces, sliver = _first_crossings(a, b, crossings)
    middles = np.empty(pieces)
    found = 0
    before = 0.0
    for _ in range(pieces):
        after = _next_crossing(a, b, crossings)
        if after - before > sliver or pieces == 1:
            middles[found] = 0.5 * (before + after)
            found += 1
        before = after
    return middles[:found]


@numba.njit(cache=True, inline='always')
def _first_crossings(a, b, crossings):
    """Set up the walk along segment a-b over its grid crossings (`_next_crossing`).

    `crossings` (2, d) gets each axis's first grid line strictly between the ends (in
    the order the segment meets them) and how many it has. Returns the number of pieces
    and the length in t [0, 1] of a sliver, a billionth of a cell along the longest axis.
    """
    longest = 0.0
    pieces = 1
    for axis in range(a.shape[0]):
        low, high = min(a[axis], b[axis]), max(a[axis], b[axis])
        longest = max(longest, high - low)
        first, last = np.floor(low) + 1.0, np.ceil(high) - 1.0
        count = max(0.0, last - first + 1.0)
        crossings[0, axis] = first if b[axis] > a[axis] else last
        crossings[1, axis] = count
        pieces += int(count)
    return pieces, 1e-9 / max(1e-300, longest)


@numba.njit(cache=True, inline='always')
def _next_crossing(a, b, crossings):
    """Return t of the segment's next grid crossing (1 after the last), and pass it.

    Each axis meets its lines in order of t, so the next of all is the least of each
    axis's next: no sorting.
    """
    after, nearest = 1.0, -1
    for axis in range(a.shape[0]):
        if crossings[1, axis] > 0.0:
            t = (crossings[0, axis] - a[axis]) / (b[axis] - a[axis])
            if nearest < 0 or t < after:
                after, nearest = t, axis
    if nearest >= 0:
        crossings[0, nearest] += 1.0 if b[nearest] > a[nearest] else -1.0
        crossings[1, nearest] -= 1.0
    return after


@numba.njit(cache=True)
def route_cells(points, periodic, size):
    """Cells (c, 2) the route through `points` (r, 2) [cell units] passes, in order.

    Each segment's cells, then the last point's; indices are wrapped round the periodic
    axes and clipped to the grid along the others.
    """
    ends = np.vstack((points, points[-1:]))  # the last point: a segment of no length
    pieces = [_piece_middles(ends[k], ends[k + 1]) for k in range(points.shape[0])]
    count = 0
    for middles in pieces:
        count += middles.shape[0]
    cells = np.empty((count, 2), dtype=np.int64)
    row = 0
    for k in range(points.shape[0]):
        a, b = ends[k], ends[k + 1]
        for t in pieces[k]:
            for axis in range(2):
                cells[row, axis] = wrap_index(int(np.floor(a[axis] + t * (b[axis] - a[axis]))),
                                               periodic[axis], size)
            row += 1
    return cells


def greedy_cuts(mask: np.ndarray, periodic: np.ndarray, offsets: np.ndarray,
                 longest: float) -> np.ndarray:
    """Return the indices of the points (r, d) [cell units] a path keeps, cut straight in mask.

    From each kept point the path jumps to the farthest later point before the first
    whose straight cut leaves the mask's cells or spans more than `longest` cells along
    an axis; the first and last points are kept.
    """
    return _greedy_cuts_kernel(np.ascontiguousarray(mask).ravel(), np.array(mask.shape),
                               periodic.astype(np.bool_), np.ascontiguousarray(offsets),
                               float(longest))


@numba.njit(cache=True)
def _greedy_cuts_kernel(mask, shape, periodic, offsets, longest):
    kept = np.empty(offsets.shape[0], dtype=np.int64)
    kept[0] = 0
    count = 1
    k = 0
    crossings = np.empty((2, offsets.shape[1]))
    while k < offsets.shape[0] - 1:
        far = k + 1
        for candidate in range(k + 2, offsets.shape[0]):
            if np.max(np.abs(offsets[candidate] - offsets[k])) > longest or not _cut_free(
                    mask, shape, periodic, offsets[k], offsets[candidate], crossings):
                break
            far = candidate
        kept[count] = far
        count += 1
        k = far
    return kept[:count]


@numba.njit(cache=True)
def _cut_free(mask, shape, periodic, a, b, crossings):
    """Whether every cell the segment a-b (in cell units) passes through is in the flat mask.

    The pieces of `_piece_middles`, walked without storing them; `crossings` (2, d) is
    scratch space for the walk.
    """
    pieces, sliver = _first_crossings(a, b, crossings)
    before = 0.0
    for _ in range(pieces):
        after = _next_crossing(a, b, crossings)
        if (after - before > sliver or pieces == 1) and not _cell_in(
                mask, shape, periodic, a, b, 0.5 * (before + after)):
            return False
        before = after
    return True


@numba.njit(cache=True, inline='always')
def _cell_in(mask, shape, periodic, a, b, t):
    """Whether the cell holding the point at t of segment a-b (cell units) is in the flat mask."""
    flat = 0
    for axis in range(a.shape[0]):
        value = int(np.floor(a[axis] + t * (b[axis] - a[axis])))
        if periodic[axis]:
            value %= shape[axis]
        elif value < 0 or value >= shape[axis]:
            return False
        flat = flat * shape[axis] + value
    return mask[flat]


# The steps to a cell's neighbours in 2-D and 3-D (at most one cell along each axis), in
# C order.
_NEIGHBOUR_STEPS = {dims: np.array([o for o in np.ndindex(*(3,) * dims) if any(v != 1 for v in o)],
                                   dtype=np.int64) - 1 for dims in (2, 3)}


def bfs(mask: np.ndarray, periodic: np.ndarray, sources: np.ndarray, target: np.ndarray,
         ) -> np.ndarray | None:
    """Cells (c, d) of a shortest path in mask (d = 2 or 3) from a source to a target cell."""
    offsets = _NEIGHBOUR_STEPS[mask.ndim]
    flat_sources = np.ravel_multi_index(tuple(np.asarray(sources).T), mask.shape)
    found = _bfs_kernel(np.ascontiguousarray(mask).ravel(), np.array(mask.shape),
                        periodic.astype(np.bool_), offsets, flat_sources.astype(np.int64),
                        np.ascontiguousarray(target).ravel())
    if len(found) == 0:
        return None
    return np.stack(np.unravel_index(found, mask.shape), axis=1)


_UNSEEN = 255  # `_bfs_kernel`'s step code of a cell not reached yet


_SOURCE = 254  # and of a source cell


# One piece, as a kernel: the search and the walk back share the queue and each cell's step.
@numba.njit(cache=True)
def _bfs_kernel(mask, shape, periodic, offsets, sources, target):
    """Breadth-first search over flat cells; returns the flat path or an empty array.

    The queue is first in, first out, so the first target cell queued is the first one a
    search that looks at the cells it takes out would reach: the search stops there. Each
    cell keeps the index of the step (a row of `offsets`) that reached it, one byte, and
    the path is walked back by those steps.
    """
    total = mask.shape[0]
    dims = shape.shape[0]
    came = np.full(total, _UNSEEN, dtype=np.uint8)
    queue = np.empty(total, dtype=np.int32)
    tail = 0
    end = -1
    for s in sources:
        if mask[s] and came[s] == _UNSEEN:
            came[s] = _SOURCE
            queue[tail] = s
            tail += 1
            if end < 0 and target[s]:
                end = s
    index = np.empty(dims, dtype=np.int64)
    jumps = np.zeros(offsets.shape[0], dtype=np.int64)  # flat steps to the neighbours
    for o in range(offsets.shape[0]):
        for d in range(dims):
            jumps[o] = jumps[o] * shape[d] + offsets[o, d]
    head = 0
    while end < 0 and head < tail:
        cell = queue[head]
        head += 1
        rest = cell
        interior = True
        for d in range(dims - 1, -1, -1):
            index[d] = rest % shape[d]
            rest //= shape[d]
            interior = interior and 0 < index[d] < shape[d] - 1
        for o in range(offsets.shape[0]):
            if interior:  # no neighbour across a face of the grid: a flat step suffices
                flat = cell + jumps[o]
            else:
                flat = 0
                for d in range(dims):
                    value = index[d] + offsets[o, d]
                    if value < 0 or value >= shape[d]:
                        if not periodic[d]:
                            flat = -1
                            break
                        value %= shape[d]
                    flat = flat * shape[d] + value
                if flat < 0:
                    continue
            if mask[flat] and came[flat] == _UNSEEN:
                came[flat] = o
                queue[tail] = flat
                tail += 1
                if target[flat]:
                    end = flat
                    break
    if end < 0:
        return np.empty(0, dtype=np.int64)
    length = 1
    cell = end
    while came[cell] != _SOURCE:
        cell = _step_back(cell, offsets[came[cell]], shape, index)
        length += 1
    path = np.empty(length, dtype=np.int64)
    cell = end
    for k in range(length - 1, -1, -1):
        path[k] = cell
        if k:
            cell = _step_back(cell, offsets[came[cell]], shape, index)
    return path


@numba.njit(cache=True)
def _step_back(cell, offset, shape, index):
    """Return the flat cell one step `offset` (d,) before `cell`, round every axis.

    A step never left the grid along an axis that does not wrap, so wrapping undoes it
    exactly. `index` (d,) is scratch space.
    """
    rest = cell
    for d in range(shape.shape[0] - 1, -1, -1):
        index[d] = rest % shape[d]
        rest //= shape[d]
    flat = 0
    for d in range(shape.shape[0]):
        flat = flat * shape[d] + (index[d] - offset[d]) % shape[d]
    return flat


