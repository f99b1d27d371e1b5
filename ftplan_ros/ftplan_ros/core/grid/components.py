"""Connected components of cell masks on a joint grid whose periodic axes wrap round.

`components` finds the components of a 3-D mask in one compiled pass over runs: the
cells of the mask along each line of the grid. Cells are joined when they touch at a
face, an edge or a corner within the axes it is told (all three: the 26 neighbours; two:
the 8 neighbours in each layer across the third, as the failure-tolerant set labels the
layers of each joint, tolerant_set.py), round the periodic ones. Components are
numbered 1..K, and 0 is outside the mask. The answer stays in runs: the components at
given cells, those holding a cell of another mask and the cells of chosen components
are read from them without writing a label per cell.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

_EIGHT_INSIDE = np.uint64(0x0101010101010101)  # eight cells of a bool mask, all True


@dataclass(frozen=True, eq=False)
class Components:
    """The components of a mask (N0, N1, N2) as runs of cells along lines.

    Lines run along `axes[2]`, one per index pair along `axes[0]` and `axes[1]`; line l
    holds the runs first[l]..first[l+1]-1, run r covers indices starts[r]..ends[r] of its
    line and belongs to component number[r] (1..count).
    """

    shape: tuple[int, int, int]
    axes: np.ndarray
    first: np.ndarray
    starts: np.ndarray
    ends: np.ndarray
    number: np.ndarray
    count: int

    def at(self, cells: np.ndarray) -> np.ndarray:
        """Components (k,) int32 of the cells (k, 3) (indices within the grid); 0 outside."""
        cells = np.asarray(cells)
        if cells.ndim != 2 or cells.shape[1] != 3 or not (
                cells.size == 0 or np.issubdtype(cells.dtype, np.integer)):
            raise ValueError(f'cells must be integer indices (k, 3), got {cells.dtype} '
                             f'{cells.shape}')
        cells = np.ascontiguousarray(cells, dtype=np.int64)
        if cells.size and not (np.all(cells >= 0) and np.all(cells < self.shape)):
            raise ValueError(f'cells must lie within the grid {self.shape}')
        return _at(self.first, self.starts, self.ends, self.number, self._sizes(), self.axes,
                   cells)

    def holding(self, seeds: np.ndarray) -> np.ndarray:
        """(count + 1,) bool: the components that hold a cell of `seeds` (the mask's shape)."""
        seeds = np.ascontiguousarray(seeds, dtype=np.bool_)
        if seeds.shape != self.shape:
            raise ValueError(f'seeds must have the shape {self.shape}, got {seeds.shape}')
        out = np.zeros(self.count + 1, dtype=np.bool_)
        _holding(self.first, self.starts, self.ends, self.number, self._sizes(), self._strides(),
                 self.axes, seeds.ravel(), out)
        return out

    def cells(self, chosen: np.ndarray) -> np.ndarray:
        """(shape) bool: the cells of the components `chosen` (count + 1,) bool marks."""
        mine = self._chosen_runs(chosen)
        out = np.zeros(self.shape, dtype=np.bool_)
        _paint(mine, mine, self.first, self.starts, self.ends, self._sizes(), self._strides(),
               self.axes, out.ravel())
        return out

    def clear_others(self, chosen: np.ndarray, out: np.ndarray) -> None:
        """Set `out` False on the cells of the components that `chosen` does not mark.

        `out` has the mask's shape (bool, C-contiguous) and `chosen` is (count + 1,) bool.
        Within the mask this is `out &= self.cells(chosen)`, without a mask of the chosen
        cells: only the others' cells are written.
        """
        mine = self._chosen_runs(chosen)  # False on the runs to clear: the value they get
        if out.shape != self.shape or out.dtype != np.bool_ or not out.flags.c_contiguous:
            raise ValueError(f'out must be a C-contiguous bool array of shape {self.shape}')
        _paint(~mine, mine, self.first, self.starts, self.ends, self._sizes(),
               self._strides(), self.axes, out.ravel())

    def _chosen_runs(self, chosen: np.ndarray) -> np.ndarray:
        """Mark each run (runs,) bool whose component `chosen` (count + 1,) bool marks."""
        chosen = np.asarray(chosen, dtype=np.bool_)
        if chosen.shape != (self.count + 1,):
            raise ValueError(f'{self.count} components need {self.count + 1} choices, got '
                             f'shape {chosen.shape}')
        return chosen[self.number]

    def labels(self) -> np.ndarray:
        """(shape) int32: each cell's component, 0 outside the mask."""
        out = np.zeros(self.shape, dtype=np.int32)
        _paint(self.number > 0, self.number, self.first, self.starts, self.ends, self._sizes(),
               self._strides(), self.axes, out.ravel())
        return out

    def _sizes(self) -> np.ndarray:
        return np.array(self.shape, dtype=np.int64)

    def _strides(self) -> np.ndarray:
        return np.array([self.shape[1] * self.shape[2], self.shape[2], 1], dtype=np.int64)


def components(mask: np.ndarray, periodic: np.ndarray,
               across: tuple[int, ...] = (0, 1, 2)) -> Components:
    """Find the components of `mask` (N0, N1, N2) bool.

    Cells are neighbours when their indices differ by at most one along each axis of
    `across` and not at all along the others; along an axis that `periodic` (3,) marks,
    index 0 and index N-1 differ by one.
    """
    if np.ndim(mask) != 3:
        raise ValueError(f'the mask must be 3-D, got shape {np.shape(mask)}')
    mask = np.ascontiguousarray(mask, dtype=np.bool_)
    periodic = np.asarray(periodic, dtype=bool)
    if periodic.shape != (3,):
        raise ValueError(f'periodic must hold 3 flags, got shape {periodic.shape}')
    across = tuple(sorted(set(across)))
    if not across or not set(across) <= {0, 1, 2}:
        raise ValueError(f'across must name axes among 0, 1 and 2, got {across}')
    along = across[-1]
    lines = [axis for axis in range(3) if axis != along]
    axes = np.array(lines + [along], dtype=np.int64)
    flat = mask.ravel()
    words = flat.view(np.uint64) if flat.size % 8 == 0 else np.zeros(0, dtype=np.uint64)
    first, starts, ends, number, count = _runs(
        flat, words, np.array(mask.shape, dtype=np.int64), axes,
        np.array([axis in across for axis in lines]),
        np.array([axis in across and bool(periodic[axis]) for axis in lines + [along]]))
    return Components(tuple(int(v) for v in mask.shape), axes, first, starts, ends, number,
                      int(count))


def layer_components(mask: np.ndarray, joint: int, periodic: np.ndarray) -> Components:
    """Find the components of each θ_joint-layer of `mask` (cells touching in the layer)."""
    if joint not in (0, 1, 2):
        raise ValueError(f'joint must be 0, 1 or 2, got {joint}')
    return components(mask, periodic, tuple(a for a in range(3) if a != joint))


def overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two bool masks of one shape share a cell; stops at the first shared one.

    Cells are compared eight at a time where the masks' size allows it.
    """
    if a.shape != b.shape:
        raise ValueError(f'masks of shapes {a.shape} and {b.shape} cannot overlap')
    a = np.ascontiguousarray(a, dtype=np.bool_).ravel()
    b = np.ascontiguousarray(b, dtype=np.bool_).ravel()
    if a.size % 8 == 0:
        a, b = a.view(np.uint64), b.view(np.uint64)
    return bool(_overlap(a, b))


@numba.njit(cache=True)
def _overlap(a, b):
    for k in range(a.shape[0]):
        if a[k] & b[k]:
            return True
    return False


@numba.njit(cache=True)
def _line_base(line, sizes, strides, axes):
    """Flat index of the first cell of line `line`."""
    size_q = sizes[axes[1]]
    return (line // size_q) * strides[axes[0]] + (line % size_q) * strides[axes[1]]


@numba.njit(cache=True)
def _paint(selected, values, first, starts, ends, sizes, strides, axes, out):
    """out[cell] = values[run] for the cells of every run that `selected` marks (flat)."""
    step_r = strides[axes[2]]
    for line in range(first.shape[0] - 1):
        base = _line_base(line, sizes, strides, axes)
        for run in range(first[line], first[line + 1]):
            if selected[run]:
                value = values[run]
                for r in range(starts[run], ends[run] + 1):
                    out[base + r * step_r] = value


@numba.njit(cache=True)
def _holding(first, starts, ends, number, sizes, strides, axes, seeds, out):
    """out[number[run]] = True for every run that holds a cell of `seeds` (flat)."""
    step_r = strides[axes[2]]
    for line in range(first.shape[0] - 1):
        base = _line_base(line, sizes, strides, axes)
        for run in range(first[line], first[line + 1]):
            if out[number[run]]:
                continue
            for r in range(starts[run], ends[run] + 1):
                if seeds[base + r * step_r]:
                    out[number[run]] = True
                    break


@numba.njit(cache=True)
def _at(first, starts, ends, number, sizes, axes, cells):
    """Component of each cell (k, 3), by bisection among the runs of its line; 0 outside."""
    out = np.zeros(cells.shape[0], dtype=np.int32)
    size_q = sizes[axes[1]]
    for k in range(cells.shape[0]):
        line = cells[k, axes[0]] * size_q + cells[k, axes[1]]
        r = cells[k, axes[2]]
        low, high = first[line], first[line + 1]
        while low < high:  # the first run that ends at or after r
            middle = (low + high) // 2
            if ends[middle] < r:
                low = middle + 1
            else:
                high = middle
        if low < first[line + 1] and starts[low] <= r:
            out[k] = number[low]
    return out


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


# One piece, as a kernel: finding runs, joining them and numbering share one union-find.
@numba.njit(cache=True)
def _runs(mask, words, shape, axes, joined, wrap):
    """Find the runs of `mask` (flat, C order) and their components (see `Components`).

    `words` holds the mask's bytes eight at a time (uint64), to skip cells by the eight;
    it is empty when the mask's size is not a multiple of 8.

    The cells lie on lines along the last of `axes` (3,), one line per index pair along
    the first two; each line's cells in the mask form runs. A run is one node of a
    union-find forest: runs on neighbouring lines (a step along each of the first two
    axes that `joined` (2,) marks, round those `wrap` (3,) marks) are joined where they
    overlap once widened by a cell, and the last run of a line to the first of its
    neighbours round a wrapped last axis. Roots are numbered 1..K in run order.

    Returns first, starts, ends, number and K.
    """
    strides = np.array([shape[1] * shape[2], shape[2], 1], dtype=np.int64)
    size_p, size_q, size_r = shape[axes[0]], shape[axes[1]], shape[axes[2]]
    step_p, step_q, step_r = strides[axes[0]], strides[axes[1]], strides[axes[2]]
    lines = size_p * size_q
    first = np.empty(lines + 1, dtype=np.int64)  # line l holds runs first[l]..first[l+1]-1
    starts = np.empty(lines * ((size_r + 1) // 2), dtype=np.int32)
    ends = np.empty_like(starts)
    # Lines run along the last axis (their cells side by side) when it is among `across`;
    # otherwise the last axis is one of the line axes: neighbouring lines lie side by side.
    if step_r == 1:
        count = _line_runs(mask, words, size_p, size_q, size_r, step_p, step_q, first, starts,
                           ends)
    else:
        count = _plane_runs(mask, words, size_p, size_q, size_r, step_p, step_r, first, starts,
                            ends)
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
    return first, starts[:count].copy(), ends[:count].copy(), number, components


@numba.njit(cache=True)
def _line_runs(mask, words, size_p, size_q, size_r, step_p, step_q, first, starts, ends):
    """Find `_runs`'s runs line by line, each line's cells side by side (`_next_change`).

    Fills first[:-1], starts and ends; returns the number of runs.
    """
    count = 0
    for line in range(size_p * size_q):
        first[line] = count
        base = (line // size_q) * step_p + (line % size_q) * step_q
        stop = base + size_r
        r = _next_change(mask, words, base, stop, False)
        while r < stop:
            end = _next_change(mask, words, r + 1, stop, True)
            starts[count] = r - base
            ends[count] = end - 1 - base
            count += 1
            r = _next_change(mask, words, end, stop, False)
    return count


@numba.njit(cache=True)
def _plane_runs(mask, words, size_p, size_q, size_r, step_p, step_r, first, starts, ends):
    """Find `_runs`'s runs where lines are strided but neighbouring lines lie side by side.

    Each plane of lines is read row by row (step_q = 1, in memory order), with the run
    open on each line carried along; a plane's runs land in a slot of (size_r + 1) // 2
    per line and are packed in line order once the plane is read (the plane's lines come
    one after another in line order). Where rows start on whole words, eight cells that
    equal the row before open and close no run and are passed over at once. Fills
    first[:-1], starts and ends; returns the number of runs.
    """
    slots = (size_r + 1) // 2
    held = np.zeros(size_q, dtype=np.int64)
    opened = np.empty(size_q, dtype=np.int64)
    plane_starts = np.empty(size_q * slots, dtype=np.int32)
    plane_ends = np.empty_like(plane_starts)
    by_words = words.shape[0] > 0 and size_q % 8 == 0 and step_p % 8 == 0 and step_r % 8 == 0
    nothing = np.uint64(0)
    count = 0
    for p in range(size_p):
        opened[:] = -1
        held[:] = 0
        for r in range(size_r + 1):
            row = p * step_p + r * step_r
            for q0 in range(0, size_q, 8):
                if by_words:
                    now = words[(row + q0) // 8] if r < size_r else nothing
                    before = words[(row - step_r + q0) // 8] if r > 0 else nothing
                    if now == before:
                        continue
                for q in range(q0, min(q0 + 8, size_q)):
                    inside = r < size_r and mask[row + q]
                    if inside and opened[q] < 0:
                        opened[q] = r
                    elif not inside and opened[q] >= 0:
                        plane_starts[q * slots + held[q]] = opened[q]
                        plane_ends[q * slots + held[q]] = r - 1
                        held[q] += 1
                        opened[q] = -1
        for q in range(size_q):
            first[p * size_q + q] = count
            for k in range(held[q]):
                starts[count] = plane_starts[q * slots + k]
                ends[count] = plane_ends[q * slots + k]
                count += 1
    return count


@numba.njit(cache=True)
def _next_change(mask, words, start, stop, value):
    """Return the first flat index in start..stop-1 whose cell is not `value`, else stop.

    Whole words of eight cells that are all `value` are passed over at once (`words`, as
    `_runs` takes them; cell by cell when it is empty).
    """
    i = start
    if words.shape[0]:
        pattern = _EIGHT_INSIDE if value else np.uint64(0)
        while i < stop and i % 8:
            if mask[i] != value:
                return i
            i += 1
        while i + 8 <= stop and words[i // 8] == pattern:
            i += 8
    while i < stop:
        if mask[i] != value:
            return i
        i += 1
    return stop


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
