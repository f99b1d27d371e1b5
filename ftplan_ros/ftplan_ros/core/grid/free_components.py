"""Which configurations collision-free joint paths join, on a joint grid, from both sides.

A path clear of the obstacles lies in the cells of a joint grid that may hold a free
configuration (the `possible` cells of `cell_classes.classify_cells`), and it passes
from one such cell to the next where they touch, at a face, an edge or a corner. Two
configurations whose cells lie in different components of those cells (round the
periodic joints) are therefore joined by no collision-free path at all, however one
searches (`separated`). A configuration in a cell of no component collides.

The other way round, every configuration of a certified free cell is free, and the
segment between the centres of two closed cells that touch lies in the two: the
centres of a chain of touching certified cells make a free path (`path`), between any
two configurations of one component of the certified cells.

The grid applies to planar 3R arms among disks (`cell_classes.supports`); the approach
planner asks it before it searches with RRT-Connect.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cached_property

import numpy as np

from ..model.angles import wrap_steps
from ..model.robot import Robot
from ..model.scene import Obstacle, Scene
from .cell_classes import CellClasses, classify_cells, supports
from .components import Components, components, layer_components
from .sheet_kernels import bfs, greedy_cuts

# Cells per joint. The proof holds at any resolution; a finer grid proves more pairs
# apart (narrower gaps), a coarser one is quicker: 64^3 classifies in 1-4 ms.
GRID_CELLS = 64
# Cells per joint of the grids `start_reach.tolerant_start_out_of_reach` may try, coarse
# first: 64^3 takes about 10 ms, 128^3 (the recovery sheets' first grid) about 40, 256^3
# about 0.3 s and 120 MB more, 384^3 about 0.9 s and 400 MB (a narrow gap may need it).
PROOF_GRIDS = (64, 128, 256, 384)
START_GRIDS = PROOF_GRIDS[:2]  # the default: cheap enough for every failed request
# [rad] longest joint step of a straight cut of `FreeComponents.path`: well below π, so
# that a controller interpolating a periodic joint the short way round follows it
_LONGEST_CUT = 0.5 * np.pi


class FreeComponents:
    """The components of the possibly free and the certified free cells of a joint grid.

    Free means clear of the obstacles by more than the margin the cells were classified
    with [m]. With a joint held, a path stays in its failure plane, which lies in the
    closed layer of cells holding the held value: the components of that layer's
    possibly free cells (8 neighbours in the layer) decide instead.
    """

    def __init__(self, classes: CellClasses):
        self.classes = classes
        self.lattice = classes.lattice
        self.possible = classes.possible
        self.found = components(classes.possible, self.lattice.periodic)
        self._layers: dict[int, Components] = {}

    @classmethod
    def over(cls, scene: Scene, cells: int = GRID_CELLS, margin: float = 0.0) -> FreeComponents:
        """Classify the scene's grid of `cells` per joint, free meaning clear by > `margin` [m]."""
        return cls(classify_cells(scene, cells, margin=margin))

    @classmethod
    def where_it_applies(cls, robot: Robot, obstacles: Sequence[Obstacle],
                         margin: float = 0.0) -> FreeComponents | None:
        """Return the components for a planar 3R arm among disks; None for other scenes."""
        scene = Scene(robot, tuple(obstacles))
        return cls.over(scene, margin=margin) if supports(scene) else None

    def separated(self, a: np.ndarray, b: np.ndarray, held: int | None = None) -> bool:
        """Whether no path clear by more than the margin joins configurations a and b [rad].

        With `held`, only paths that keep that joint at a's angle count (b must have it
        too). True only when proved: their cells lie in different components, or one of
        them collides. False when a path may exist, and for configurations that are not
        finite or lie outside the joint limits.
        """
        points = self._points(a, b)
        if points is None:
            return False
        if held is not None and points[0, held] != points[1, held]:
            return False
        cells = self.lattice.cell_of(points)
        found = self.found if held is None else self._layer_components(held)
        first, second = found.at(cells)
        return bool(first == 0 or second == 0 or first != second)

    def joined(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether certified free cells join configurations a and b [rad] (so `path` does)."""
        points = self._points(a, b)
        if points is None:
            return False
        first, second = self.certified_found.at(self.lattice.cell_of(points))
        return bool(first > 0 and first == second)

    def path(self, a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
        """Return a free path (k, 3) [rad] from a to b (plus whole turns) through certified cells.

        a, each certified cell's centre along a shortest chain of touching cells, then b,
        lifted (continuous); shortened by straight cuts that pass certified cells only and
        turn no joint more than `_LONGEST_CUT`. None unless `joined(a, b)`.
        """
        if not self.joined(a, b):
            return None
        lattice = self.lattice
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        target = np.zeros(self.classes.certified.shape, dtype=np.bool_)
        target[tuple(lattice.cell_of(b[None])[0])] = True
        cells = bfs(self.classes.certified, lattice.periodic, lattice.cell_of(a[None]), target)
        points = [a]
        for point in list(lattice.centres(cells)) + [b]:
            points.append(points[-1] + wrap_steps(point - points[-1], lattice.periodic))
        points = np.array(points)
        kept = greedy_cuts(self.classes.certified, lattice.periodic,
                           (points - lattice.lower) / lattice.step,
                           np.floor(_LONGEST_CUT / lattice.step.max()))
        return points[kept]

    @cached_property
    def certified_found(self) -> Components:
        """The components of the certified free cells (26 neighbours, round the torus)."""
        return components(self.classes.certified, self.lattice.periodic)

    def _points(self, a: np.ndarray, b: np.ndarray) -> np.ndarray | None:
        """(2, 3) [rad] of a and b; None when one is not finite or lies beyond the limits."""
        points = np.array([a, b], dtype=float)
        if not np.all(np.isfinite(points)) or not np.all(self.lattice.inside(points)):
            return None
        return points

    def _layer_components(self, joint: int) -> Components:
        """Return the components of each θ_joint-layer's possibly free cells (cached)."""
        if joint not in self._layers:
            self._layers[joint] = layer_components(self.possible, joint, self.lattice.periodic)
        return self._layers[joint]


def proof_grids(finest: int) -> tuple[int, ...]:
    """Return the grids of `PROOF_GRIDS` up to `finest` cells per joint (one of them)."""
    if finest not in PROOF_GRIDS:
        raise ValueError(f'the finest proof grid must be one of {PROOF_GRIDS} cells per '
                         f'joint, got {finest}')
    return PROOF_GRIDS[:PROOF_GRIDS.index(finest) + 1]
