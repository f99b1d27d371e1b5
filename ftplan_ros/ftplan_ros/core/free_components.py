"""Configurations that no collision-free joint path joins, proved on a joint grid.

A path clear of the obstacles lies in the cells of a joint grid that may hold a free
configuration (the `possible` cells of `cell_classes.classify_cells`), and it passes
from one such cell to the next where they touch, at a face, an edge or a corner. Two
configurations whose cells lie in different components of those cells (round the
periodic joints) are therefore joined by no collision-free path at all, however one
searches. A configuration in a cell of no component collides. The grid applies to
planar 3R arms among disks (`cell_classes.supports`); the approach planner asks it
before it searches with RRT-Connect.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .cell_classes import classify_cells, supports
from .components import Components, components, layer_components
from .robot import Robot
from .scene import Obstacle, Scene

# Cells per joint. The proof holds at any resolution; a finer grid proves more pairs
# apart (narrower gaps), a coarser one is quicker: 64^3 classifies in 1-4 ms.
GRID_CELLS = 64


class FreeComponents:
    """The components of the possibly free cells of a joint grid over the robot's joints.

    Free means clear of the obstacles by more than `margin` [m]. With a joint held, a
    path stays in its failure plane, which lies in the closed layer of cells holding the
    held value: the components of that layer's possibly free cells (8 neighbours in the
    layer) decide instead.
    """

    def __init__(self, scene: Scene, cells: int = GRID_CELLS, margin: float = 0.0):
        classes = classify_cells(scene, cells, margin=margin)
        self.lattice = classes.lattice
        self.possible = classes.possible
        self.found = components(classes.possible, self.lattice.periodic)
        self._layers: dict[int, Components] = {}

    @classmethod
    def where_it_applies(cls, robot: Robot, obstacles: Sequence[Obstacle],
                         margin: float = 0.0) -> FreeComponents | None:
        """Return the components for a planar 3R arm among disks; None for other scenes."""
        scene = Scene(robot, tuple(obstacles))
        return cls(scene, margin=margin) if supports(scene) else None

    def separated(self, a: np.ndarray, b: np.ndarray, held: int | None = None) -> bool:
        """Whether no path clear by more than the margin joins configurations a and b [rad].

        With `held`, only paths that keep that joint at a's angle count (b must have it
        too). True only when proved: their cells lie in different components, or one of
        them collides. False when a path may exist, and for configurations that are not
        finite or lie outside the joint limits.
        """
        points = np.array([a, b], dtype=float)
        if not np.all(np.isfinite(points)) or not np.all(self.lattice.inside(points)):
            return False
        if held is not None and points[0, held] != points[1, held]:
            return False
        cells = self.lattice.cell_of(points)
        found = self.found if held is None else self._layer_components(held)
        first, second = found.at(cells)
        return bool(first == 0 or second == 0 or first != second)

    def _layer_components(self, joint: int) -> Components:
        """Return the components of each θ_joint-layer's possibly free cells (cached)."""
        if joint not in self._layers:
            self._layers[joint] = layer_components(self.possible, joint, self.lattice.periodic)
        return self._layers[joint]
