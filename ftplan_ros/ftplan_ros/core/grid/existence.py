"""Existence: decide from both sides whether a failure-tolerant plan exists at all.

A plan exists exactly when a path inside the failure-tolerant set G joins a start
configuration (on M_s, obstacle-free) to a goal configuration (tolerant_set.py). On a
joint grid of N^3 cells:

* YES (proved): the cells certified inside G for every tolerated joint hold a component
  (cells touching at a face, edge or corner; closed cells that touch share a point) with
  an exact point of M_s (closed-form inverse kinematics) in one cell and an exact goal
  configuration in another. Every configuration of those cells is in G, so the path
  through them is a plan.
* NO (proved): in the cells that may meet G, no component holds both a cell that may
  contain a start configuration and one that may contain a goal configuration. Any plan
  would be a connected set of G meeting both, covered by such cells.
* UNSURE otherwise: the grid is too coarse to decide.

Planar 3R arms among disks only (exact distances make both sides rigorous); the answer
also says how many cells each side kept, and the time it took.
"""

from __future__ import annotations

import enum
import time
from dataclasses import dataclass

import numpy as np

from ..model.scene import Scene
from .cell_classes import supports
from .components import Components, components
from .tolerant_set import TolerantSet, preimage_samples, tolerant_set


class Existence(enum.Enum):
    """Whether a failure-tolerant plan exists, as far as the grid can tell."""

    YES = 'yes'
    NO = 'no'
    UNSURE = 'unsure'


@dataclass(frozen=True)
class ExistenceAnswer:
    """The existence decision on one scene, with its grid and the time it took [s]."""

    existence: Existence
    cells: int
    certified_cells: int     # cells certified inside G
    liberal_cells: int       # cells that may meet G
    time_s: float


def decide_existence(scene: Scene, cells: int = 256) -> ExistenceAnswer:
    """Decide on N = `cells` cells per joint whether the scene's task has a plan."""
    if not supports(scene):
        raise ValueError('the existence decision handles planar 3R arms among disks only')
    started = time.perf_counter()
    grid = tolerant_set(scene, cells)
    existence = Existence.YES if proves_yes(grid) else \
        Existence.NO if proves_no(grid) else Existence.UNSURE
    return ExistenceAnswer(existence, cells, int(grid.certified_all.sum()),
                           int(grid.liberal_all.sum()), time.perf_counter() - started)


def proves_yes(grid: TolerantSet) -> bool:
    """Whether certified cells join an exact start configuration to an exact goal one."""
    inside = grid.certified_all
    if not inside.any():
        return False
    lattice = grid.lattice
    found = components(inside, lattice.periodic)
    return bool(np.intersect1d(components_at(found, lattice, exact_starts(grid)),
                               components_at(found, lattice, exact_goals(grid))).size)


def exact_starts(grid: TolerantSet) -> np.ndarray:
    """Exact start configurations (s, 3) [rad]: M_s at 8 angles of the last link per cell."""
    task = grid.scene.task
    return preimage_samples(np.asarray(grid.scene.robot.link_lengths, dtype=float),
                            np.asarray(task.start, dtype=float), 8 * grid.lattice.cells)


def exact_goals(grid: TolerantSet) -> np.ndarray:
    """Exact goal configurations (g, 3) [rad]: each joint's escapes' and M_g's samples."""
    task = grid.scene.task
    return np.vstack([grid.escape(j).goal_points for j in grid.joints] + [
        preimage_samples(np.asarray(grid.scene.robot.link_lengths, dtype=float),
                         np.asarray(task.goal, dtype=float), 8 * grid.lattice.cells)])


def proves_no(grid: TolerantSet) -> bool:
    """Whether no component of the cells that may meet G may hold both a start and a goal.

    The joints are taken in turn: once those so far leave no cell that may hold a start
    (or a goal), none is left when every joint counts, and the rest need not be computed.
    """
    start, goal = grid.near_start, grid.near_goal
    outside = grid.liberal_holding((start, goal))
    if outside is None:
        return True
    found = components(outside, grid.lattice.periodic)
    shared = found.holding(start) & found.holding(goal)
    return not shared[1:].any()


def components_at(found: Components, lattice, points: np.ndarray) -> np.ndarray:
    """Components (> 0) of the cells holding configurations (c, 3) [rad] within the limits."""
    points = points[lattice.inside(points)]
    at = found.at(lattice.cell_of(points))
    return np.unique(at[at > 0])
