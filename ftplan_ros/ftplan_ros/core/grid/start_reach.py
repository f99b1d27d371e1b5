"""The failure-tolerant starts within the reach of an arm standing at q, on a joint grid.

The arm at q (clear of the obstacles) can get wherever a collision-free joint path from
q goes. On a joint grid of a planar 3R arm among disks, `free_components` bounds that
set from both sides, and `tolerant_set` bounds the starts a failure-tolerant plan may
have (θ_s in G, the tool at x_s):

* from above: every such path stays in the component of the possibly free cells that
  holds q's cell. When that component holds no cell that may meet G and may put the tool
  at the start (`TolerantSet.liberal_all & near_start`), no failure-tolerant plan starts
  where the arm can get to: `proved_none`.
* from below: every configuration of the component of the certified free cells that
  holds q's cell is reached from q through the centres of those cells
  (`FreeComponents.path`). The exact start configurations there (M_s in closed form) in
  cells that may meet G are the starts to plan from (`starts`): first those whose cells
  are certified inside G and joined there to an exact goal configuration (a plan from
  them exists, as existence.py proves YES), then those certified inside G, then the rest.

Between the two the grid cannot tell; a finer grid narrows the gap. Angles [rad],
lengths [m].
"""

from __future__ import annotations

import math
from functools import cached_property

import numpy as np

from ..collision.certification import LARGEST_ANGLE
from ..collision.checker import CollisionChecker
from ..model.angles import configuration_difference
from ..model.scene import Scene
from .cell_classes import supports
from .components import components
from .existence import components_at, exact_goals, exact_starts
from .free_components import START_GRIDS, FreeComponents
from .tolerant_set import TolerantSet, fits_goal_tolerance, tolerant_set


class StartReach:
    """What one joint grid tells of the failure-tolerant starts within q's reach.

    Built by `start_reach`, which checks that the grid applies to q.
    """

    def __init__(self, grid: TolerantSet, q: np.ndarray):
        self.grid = grid
        self.q = np.asarray(q, dtype=float)
        self.walls = FreeComponents(grid.classes)
        self._cell = grid.lattice.cell_of(self.q[None])

    @property
    def cells(self) -> int:
        """Cells per joint of the grid."""
        return self.grid.lattice.cells

    @cached_property
    def proved_none(self) -> bool:
        """Whether no start that may be failure-tolerant lies in q's possibly free component."""
        found = self.walls.found
        mine = found.at(self._cell)[0]
        return bool(mine > 0 and not found.holding(
            self.grid.liberal_all & self.grid.near_start)[mine])

    def in_reach(self, thetas: np.ndarray) -> np.ndarray:
        """(c,) bool: configurations (c, 3) [rad] certified free cells join to q."""
        thetas = np.asarray(thetas, dtype=float).reshape(-1, 3)
        lattice = self.grid.lattice
        out = np.all(np.isfinite(thetas), axis=1)
        out[out] = lattice.inside(thetas[out])
        found = self.walls.certified_found
        mine = found.at(self._cell)[0]
        if mine == 0 or not out.any():
            return np.zeros(len(thetas), dtype=bool)
        out[out] = found.at(lattice.cell_of(thetas[out])) == mine
        return out

    @cached_property
    def starts(self) -> np.ndarray:
        """Exact starts (s, 3) [rad] within reach that may be failure-tolerant, likeliest first.

        One per component of the cells that may meet G and per kind (a plan from it is
        proved, its cell is certified inside G, neither), the nearest to q [rad, the
        largest joint difference] of each; ordered by kind, then by that distance.
        """
        grid, lattice = self.grid, self.grid.lattice
        samples = exact_starts(grid)
        samples = samples[lattice.inside(samples)]
        samples = samples[self.in_reach(samples)]
        cells = tuple(lattice.cell_of(samples).T)
        samples = samples[grid.liberal_all[cells]]
        if len(samples) == 0:
            return samples
        cells = lattice.cell_of(samples)
        kind = 2 - grid.certified_all[tuple(cells.T)].astype(int)
        inside = components(grid.certified_all, lattice.periodic)
        goals = components_at(inside, lattice, exact_goals(grid))
        kind[np.isin(inside.at(cells), goals)] = 0
        group = components(grid.liberal_all, lattice.periodic).at(cells)
        distance = np.abs(configuration_difference(samples, self.q, lattice.periodic)).max(axis=1)
        order = np.lexsort((distance, group, kind))
        keys = np.stack([kind, group], axis=1)[order]
        first = np.concatenate([[True], np.any(keys[1:] != keys[:-1], axis=1)])
        chosen = order[first]
        return samples[chosen[np.lexsort((distance[chosen], kind[chosen]))]]


def start_reach(scene: Scene, q: np.ndarray, margin: float = 0.0,
                cells: int = START_GRIDS[0]) -> StartReach | None:
    """Return what a grid of `cells` per joint tells of the starts within q's reach.

    Free means clear of the disks by more than `margin` [m]. None where the grid does
    not apply: not a planar 3R arm among disks with a task, a goal tolerance too fine for
    the grid, and for a q (n,) [rad] that is not finite, lies beyond `LARGEST_ANGLE` or
    outside the joint limits, or is not clear (an arm in collision reaches nothing: its
    approach says why). Raises ValueError for a margin that is not finite and >= 0.
    """
    if not (math.isfinite(margin) and margin >= 0.0):
        raise ValueError(f'margin must be a finite clearance >= 0 [m], got {margin}')
    q = np.asarray(q, dtype=float).reshape(1, -1)
    if scene.task is None or not supports(scene) or q.shape[1] != scene.robot.n_joints \
            or not np.all(np.abs(q) <= LARGEST_ANGLE):  # False for NaN too
        return None
    if not fits_goal_tolerance(scene, cells):
        return None
    if not CollisionChecker(scene.robot, scene.obstacles).min_clearance(q)[0] > margin:
        return None
    grid = tolerant_set(scene, cells, margin=margin)
    if not np.all(grid.lattice.inside(q)):
        return None
    return StartReach(grid, q[0])


def tolerant_start_out_of_reach(scene: Scene, q: np.ndarray, margin: float = 0.0,
                                grids: tuple[int, ...] = START_GRIDS) -> int | None:
    """Return the cells per joint of a grid proving that no plan starts within q's reach.

    The grids of `grids` cells per joint are tried in turn (`StartReach.proved_none`);
    None when none proves it or none applies (`start_reach`).
    """
    for cells in grids:
        reach = start_reach(scene, q, margin, cells)
        if reach is not None and reach.proved_none:
            return cells
    return None
