"""Recovery sheets of one joint: the columns over the nominal path, grouped in sheets.

Step 3 of the recovery-sheets planner (`recovery_sheets.py`): for a tolerated joint i and
each waypoint j of the nominal path, a recovery column at the constant level v_j =
γ_i(j), from γ(j) through the certified cells of the θ_i-layer to a goal configuration;
consecutive columns sharing their route form a sheet. Angles [rad]; routes on the layer's
2-D cell mask (`sheet_kernels.py`).
"""

from __future__ import annotations

import math

import numpy as np

from ..model.angles import wrap_steps
from ..model.scene import Scene
from .cell_classes import disk_arrays, link_lever_arms, triangle_free
from .sheet_kernels import bfs, mask_triangle_free, shortcut, wrap_index
from .tolerant_set import TolerantSet


class SheetBuilder:
    """Recovery columns of one joint, as sheets (lists of columns (L, 3) [rad]).

    Where a strip cannot be built, `splits` maps its segment to the fraction at which a
    waypoint would help (at a sub-slab or layer boundary, else halfway). `memo` keeps the
    outcome of each new sheet and each extension by what it depends on (the joint, the
    segment's two waypoints, the sheet's route and first goal), for the builders of later
    rounds, whose paths differ only where waypoints were added.
    """

    def __init__(self, grid: TolerantSet, gamma: np.ndarray, joint: int, margin: float = 0.0,
                 memo: dict | None = None):
        self.grid = grid
        self.lattice = grid.lattice
        self.gamma = gamma
        self.joint = joint
        self.others = [a for a in range(3) if a != joint]
        self.periodic2 = self.lattice.periodic[self.others]
        self.step2 = self.lattice.step[self.others]
        self.lower2 = self.lattice.lower[self.others]
        self.size = self.lattice.cells
        self.layers = np.moveaxis(grid.classes.certified, joint, 0)  # layer first
        escape = grid.escape(joint)
        goals = escape.goal_points
        self.goal_points = goals
        # The goal samples by sub-slab: those of slab s are by_slab[first[s]:first[s + 1]],
        # in the order of goal_points.
        slabs = escape.goal_slabs
        self.by_slab = np.argsort(slabs, kind='stable')
        self.m = escape.sub_slabs
        self.slab_first = np.searchsorted(slabs[self.by_slab], np.arange(self.size * self.m + 1))
        self.goal_cells = self.lattice.cell_of(goals)[:, self.others]
        self.offsets2 = np.ascontiguousarray(  # [cell units], rows as the kernels were warmed
            (gamma[:, self.others] - self.lower2) / self.step2)
        self.free = TriangleCheck(grid.scene, margin)
        self.goal_step = goal_step(grid.scene)
        self.strip_layers = strip_layers(gamma[:, joint], self.lattice.lower[joint],
                                          self.lattice.step[joint])
        self.splits: dict[int, float] = {}
        self.memo = {} if memo is None else memo

    def build(self) -> list[list[np.ndarray]] | None:
        """Sheets from the last waypoint back to θ_s, returned in order.

        None when a strip cannot be built (`splits` then says where waypoints would help,
        or is empty when nothing would).
        """
        W = len(self.gamma) - 1
        blocks = []
        block = None
        for j in range(W - 1, -1, -1):
            grown = self._extend(block, j) if block is not None else None
            if grown is not None:
                block = grown
                continue
            if block is not None:
                blocks.append(block)
            block = self._fresh(j)
            if block is None and j not in self.splits:
                return None
        if self.splits:
            return None
        blocks.append(block)
        return [self._columns(b) for b in reversed(blocks)]

    # A block: its first and last waypoints j0, j1, the route (2-D points, lifted) shared
    # by its columns from its hub on, the cells the route passes, and per column the goal
    # (3,) its last segment reaches from the route's end.

    def _levels(self, j: int) -> tuple[float, float]:
        return self.gamma[j, self.joint], self.gamma[j + 1, self.joint]

    def _strip_mask(self, j: int) -> np.ndarray:
        """(N, N) the cells certified free in every θ_i-layer the strip (j, j+1) spans."""
        first, last = (int(v) for v in self.strip_layers[j])
        key = ('mask', self.joint, first, last)  # the same for the builders of every round
        if key not in self.memo:
            layers = np.arange(first, last + 1)
            layers = np.mod(layers, self.size) if self.lattice.periodic[self.joint] else \
                np.clip(layers, 0, self.size - 1)
            self.memo[key] = np.logical_and.reduce(self.layers[layers], axis=0)
        return self.memo[key]

    def _cell2(self, point2: np.ndarray) -> tuple[int, int]:
        """Return the 2-D cell holding a point (2,) [rad] of the layer."""
        offset = (point2 - self.lower2) / self.step2
        return tuple(wrap_index(math.floor(offset[a]), self.periodic2[a], self.size)
                     for a in range(2))

    def _fan_free(self, mask: np.ndarray, j: int, hub: np.ndarray) -> bool:
        """Whether the triangle (P_j, P_{j+1}, hub) lies in the mask's cells."""
        return mask_triangle_free(mask, self.offsets2[j], self.offsets2[j + 1],
                              (hub - self.lower2) / self.step2, self.periodic2)

    def _fresh(self, j: int) -> dict | None:
        """Start a new sheet of the strip (j, j+1), or ask for a split (`_new_sheet`)."""
        key = ('fresh', self.joint, self.gamma[j].tobytes(), self.gamma[j + 1].tobytes())
        if key not in self.memo:
            block = self._new_sheet(j)
            self.memo[key] = (block, self.splits.get(j))
        block, split = self.memo[key]
        if split is not None:
            self.splits[j] = split
        return None if block is None else dict(block, j0=j, j1=j + 1)

    def _new_sheet(self, j: int) -> dict | None:
        """Start a new sheet of the strip (j, j+1): a hub, a route from it to goals, two goals."""
        mask = self._strip_mask(j)
        levels = self._levels(j)
        ends = (self.gamma[j, self.others], self.gamma[j + 1, self.others])
        hub = None
        for point in (0.5 * (ends[0] + ends[1]), ends[1], ends[0]):
            cell = self._cell2(point)
            centre = point + wrap_steps(
                self.lower2 + (np.array(cell) + 0.5) * self.step2 - point, self.periodic2)
            if mask[cell] and self._fan_free(mask, j, centre):
                hub = (cell, centre)
                break
        later = self._goal_candidates(levels[1], levels[0])
        earlier = self._goal_candidates(levels[0], levels[1])
        if hub is None or not len(later) or not len(earlier):
            return self._split(j, layers=True)
        target = np.zeros(mask.shape, dtype=np.bool_)
        cells = self.goal_cells[later]
        target[tuple(cells[mask[tuple(cells.T)]].T)] = True
        path = bfs(mask, self.periodic2, np.array([hub[0]]), target)
        if path is None:
            return self._split(j, layers=True)
        route, covered = self._lift_route(path, hub[1], mask)
        end = route[-1]
        best = None
        for b in later:
            if not np.array_equal(self.goal_cells[b], path[-1]):
                continue
            goal_b = self._goal(b, levels[1], end)
            for a in earlier:
                goal_a = goal_b.copy() if a == b else self._goal(a, levels[0], end)
                goal_a[self.joint] = levels[0]
                distance = np.max(np.abs(goal_a - goal_b))
                if (best is None or distance < best[0]) and distance <= self.goal_step and \
                        self._ends_free(mask, end, goal_a, goal_b):
                    best = (distance, goal_a, goal_b)
        if best is None:
            return self._split(j, layers=False)
        return {'j0': j, 'j1': j + 1, 'route': route, 'route_cells': covered,
                'goals': [best[1], best[2]]}

    def _split(self, j: int, layers: bool) -> None:
        """Ask for a waypoint inside segment j: at a layer (or sub-slab) boundary, or halfway."""
        at = self._split_fraction(j, layers)
        a, b = self.gamma[j], self.gamma[j + 1]
        if at is None and np.max(np.abs(b - a)) > _SHORTEST_SEGMENT:
            at = 0.5
        if at is not None:
            self.splits[j] = at
        return None

    def _extend(self, block: dict, j: int) -> dict | None:
        """Return the block with waypoint j's column in front, if free there (`_front_goal`)."""
        key = ('extend', self.joint, block['route'].tobytes(), block['goals'][0].tobytes(),
               self.gamma[j].tobytes(), self.gamma[j + 1].tobytes())
        if key not in self.memo:
            self.memo[key] = self._front_goal(block, j)
        goal = self.memo[key]
        if goal is None:
            return None
        grown = dict(block)
        grown.update(j0=j, goals=[goal] + block['goals'])
        return grown

    def _front_goal(self, block: dict, j: int) -> np.ndarray | None:
        """Return the goal of waypoint j's column in front of the block, or None.

        Over the strip (j, j+1) the new column's first piece and the next column's sweep
        the triangle (P_j, P_{j+1}, hub), which must lie in the cells certified in every
        layer the strip spans, like the shared route.
        """
        mask = self._strip_mask(j)
        if not self._fan_free(mask, j, block['route'][0]):
            return None
        route_cells = block['route_cells']
        if not mask[route_cells[:, 0], route_cells[:, 1]].all():
            return None
        v = self.gamma[j, self.joint]
        end, following = block['route'][-1], block['goals'][0]
        best = None
        for a in self._goal_candidates(v, self.gamma[j + 1, self.joint]):
            goal = self._goal(a, v, end)
            distance = np.max(np.abs(goal - following))
            if (best is None or distance < best[0]) and distance <= self.goal_step and \
                    self._ends_free(mask, end, goal, following):
                best = (distance, goal)
        return None if best is None else best[1]

    def _ends_free(self, mask: np.ndarray, end: np.ndarray, goal_a: np.ndarray,
                   goal_b: np.ndarray) -> bool:
        """Whether the two top triangles between the route's end and two goals are free."""
        end_a, end_b = goal_a.copy(), goal_b.copy()
        end_a[self.others] = end
        end_b[self.others] = end
        return all(self.free(np.array(corners)) for corners in
                   ((end_a, end_b, goal_b), (end_a, goal_b, goal_a)))

    def _split_fraction(self, j: int, layers: bool) -> float | None:
        """Return a layer (or sub-slab) boundary strictly inside segment j, nearest its middle."""
        a, b = self._levels(j)
        if a == b:
            return None
        lower = self.lattice.lower[self.joint]
        width = self.lattice.step[self.joint] / (1 if layers else self.m)
        low, high = sorted((a, b))
        boundaries = lower + width * np.arange(np.floor((low - lower) / width),
                                               np.ceil((high - lower) / width) + 1)
        margin = 1e-3 * (high - low)
        inside = boundaries[(boundaries > low + margin) & (boundaries < high - margin)]
        if not len(inside):
            return None if layers else self._split_fraction(j, True)
        middle = inside[np.argmin(np.abs(inside - 0.5 * (low + high)))]
        return float((middle - a) / (b - a))

    def _goal_candidates(self, level: float, toward: float) -> np.ndarray:
        """Goal samples usable at `level` (on its side toward `toward`).

        A sample is usable when `level` lies in its sub-slab: moved there along θ_i, it
        stays within the goal tolerance.
        """
        lattice = self.lattice
        side = int(toward > level) - int(toward < level)
        nudged = level + 1e-9 * side * lattice.step[self.joint]
        offset = (nudged - lattice.lower[self.joint]) / lattice.step[self.joint]
        layer = math.floor(offset)
        k = min(max(math.floor((offset - layer) * self.m), 0), self.m - 1)
        layer = wrap_index(layer, lattice.periodic[self.joint], self.size)
        slab = layer * self.m + k
        return self.by_slab[self.slab_first[slab]:self.slab_first[slab + 1]]

    def _goal(self, index: int, level: float, near2: np.ndarray) -> np.ndarray:
        """Goal sample `index` at the locked value `level`, lifted next to `near2` (2,)."""
        theta = self.goal_points[index].copy()
        theta[self.others] = near2 + wrap_steps(theta[self.others] - near2, self.periodic2)
        theta[self.joint] = level
        return theta

    def _lift_route(self, path: np.ndarray, anchor: np.ndarray, mask: np.ndarray,
                    ) -> tuple[np.ndarray, np.ndarray]:
        """Centres (r, 2) of the 2-D cells `path`, lifted from `anchor`, with straight cuts.

        Also returns the cells (c, 2) the cut route passes through.
        """
        centres = self.lower2 + (path + 0.5) * self.step2
        first = anchor + wrap_steps(centres[0] - anchor, self.periodic2)
        steps = wrap_steps(np.diff(centres, axis=0), self.periodic2)
        lifted = first + np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
        return shortcut(lifted, mask, self.lower2, self.step2, self.periodic2)

    def _columns(self, block: dict) -> list[np.ndarray]:
        """Return the columns (L, 3) of a block: γ(j), the hub and route at level v_j, the goal."""
        rows = self.gamma[block['j0']:block['j1'] + 1]
        columns = np.empty((len(rows), len(block['route']) + 2, 3))
        columns[:, 0] = rows
        for k, axis in enumerate(self.others):
            columns[:, 1:-1, axis] = block['route'][:, k]
        columns[:, 1:-1, self.joint] = rows[:, self.joint, None]
        columns[:, -1] = block['goals']
        return list(columns)


def strip_layers(levels: np.ndarray, lower: float, step: float) -> np.ndarray:
    """Return the first and last θ_i-layer (W, 2) of each strip between levels (W+1,) [rad].

    Layers are closed: a strip from a layer boundary on does not span the layer below.
    Indices are not wrapped.
    """
    low, high = np.minimum(levels[:-1], levels[1:]), np.maximum(levels[:-1], levels[1:])
    nudge = 1e-9 * (high - low)
    return np.stack([np.floor((low + nudge - lower) / step),
                     np.floor((high - nudge - lower) / step)], axis=1).astype(np.int64)


def goal_step(scene: Scene) -> float:
    """Largest step [rad] between the goals of neighbouring columns (the goal row's chords).

    A chord strays from the goal by the error of its ends (up to 0.9 of the tolerance,
    `sub_slab_count`) and its sag, which grows with the square of its length and with the
    reach. Chords of 0.15 rad pass the self-check at a tolerance of 1/300 of the reach
    (1 cm for 1 m links, the bench's) and, on 40 such scenes, down to 4 mm, but not at
    2 mm (7 of 34 webs failed it) or 1 mm; below 1/300 of the reach they shorten as the
    square root of the tolerance, which passed on all of them.
    """
    reach = float(scene.robot.tip_lever_arms()[0])
    return _LONGEST_GOAL_STEP * min(1.0, math.sqrt(scene.task.goal_tolerance / (reach / 300.0)))


# [rad] `goal_step` for goal tolerances of 1/300 of the reach and coarser
_LONGEST_GOAL_STEP = 0.15




class TriangleCheck:
    """Whether a joint-space triangle (3, 3) [rad] is free: exact clearances, lever bounds."""

    def __init__(self, scene: Scene, margin: float = 0.0):
        robot = scene.robot
        self.lengths = np.asarray(robot.link_lengths, dtype=float)
        self.radius = float(robot.link_radius)
        self.centres, self.radii = disk_arrays(scene, margin)
        self.arms = link_lever_arms(self.lengths)

    def __call__(self, corners: np.ndarray) -> bool:
        """Whether the joint-space triangle `corners` (3, 3) [rad] is certified free."""
        return bool(triangle_free(self.lengths, self.radius, self.centres, self.radii,
                                  self.arms, np.ascontiguousarray(corners, dtype=float), 6))


_SHORTEST_SEGMENT = 1e-4  # [rad] a nominal segment is not split below this
