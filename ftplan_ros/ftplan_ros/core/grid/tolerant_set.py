"""The failure-tolerant set G of a planar 3R arm among disks, on a joint grid, from both sides.

G holds the configurations from which the arm reaches the goal x_g (within the goal
tolerance) without collision whichever tolerated joint locks there: for every joint i,
the configuration and a goal configuration lie in one connected piece of the free part
of its failure plane {θ_i = const}. A failure-tolerant plan exists exactly when a path in
G joins a start configuration (on M_s, obstacle-free) to a goal configuration.

The joint space is cut into N^3 closed cells, each certified free, possibly free, or
surely colliding (`cell_classes.py`).

For joint i, the cells with the same θ_i-index form a layer (a slab of locked values). In
a layer, the free part of every failure plane {θ_i = v}, v in the slab, is

* contained in the union of the layer's possibly free cells, so a configuration whose
  cell's layer component (cells touching at a face, edge or corner) holds no cell that
  may reach x_g cannot escape (`escape_liberal`: an over-approximation of G_i);
* contains the union of its certified free cells, each closed cell meeting the plane in a
  free closed rectangle; cells touching at a corner share a point, so a layer component
  is connected in every plane of the slab. It reaches a goal configuration in the plane
  θ_i = v for every v of the slab when the exact inverse kinematics of the 2R arm left by
  the lock (`locked_goal_configurations`), solved at the middle of each of m sub-slabs,
  puts a solution in a cell of the component for every sub-slab: moving θ_i by at most
  half a sub-slab moves the tool by at most R_i · (sub-slab) / 2 <= the goal tolerance
  (`escape_certified`: an under-approximation of G_i).

Angles [rad], lengths [m]. On the grid, existence.py decides whether a plan exists and
the recovery sheets (recovery_sheets.py) find one.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np

from ..errors import InputError
from ..model.robot import PlanarChain
from ..model.scene import Scene
from .cell_classes import CellClasses, JointLattice, classify_cells, supports
from .components import Components, layer_components, overlap


def two_link_solutions(a: float, b: float, target: np.ndarray) -> np.ndarray:
    """Solutions (s, 2) [rad] (first link's angle, elbow) of a 2R arm of links a, b [m].

    `target` (2,) [m]; none when it is out of reach or a link has no length.
    """
    if a <= 0.0 or b <= 0.0:
        return np.empty((0, 2))
    r2 = float(target @ target)
    cos_elbow = (r2 - a * a - b * b) / (2.0 * a * b)
    if abs(cos_elbow) > 1.0:
        return np.empty((0, 2))
    out = []
    for elbow in {float(np.arccos(cos_elbow)), -float(np.arccos(cos_elbow))}:
        first = np.arctan2(target[1], target[0]) - np.arctan2(b * np.sin(elbow),
                                                              a + b * np.cos(elbow))
        out.append((first, elbow))
    return np.array(out)


def locked_goal_configurations(lengths: np.ndarray, x: np.ndarray, joint: int,
                               value: float) -> np.ndarray:
    """Every configuration (s, 3) [rad] with θ_joint = value and the tool exactly at x.

    The arm left by the lock is a 2R arm (two links made rigid by the locked joint count
    as one); its closed-form solutions are all there are, except in the degenerate case
    of a target at its base with equal links, where one of the circle of solutions is
    returned.
    """
    l1, l2, l3 = (float(v) for v in lengths)
    x = np.asarray(x, dtype=float)
    out = []
    if joint == 0:
        elbow = l1 * np.array([np.cos(value), np.sin(value)])
        for first, second in two_link_solutions(l2, l3, x - elbow):
            out.append((value, first - value, second))
    elif joint == 1:
        rigid = l1 + l2 * np.exp(1j * value)
        length, offset = abs(rigid), float(np.angle(rigid))
        for first, second in two_link_solutions(length, l3, x):
            out.append((first - offset, value, second + offset - value))
    else:
        rigid = l2 + l3 * np.exp(1j * value)
        length, offset = abs(rigid), float(np.angle(rigid))
        for first, second in two_link_solutions(l1, length, x):
            out.append((first, second - offset, value))
    return np.array(out, dtype=float).reshape(-1, 3)


def preimage_samples(lengths: np.ndarray, x: np.ndarray, count: int) -> np.ndarray:
    """Exact points (s, 3) [rad] of the pre-image of x: `count` angles of the last link.

    For each angle, the wrist's `two_link_solutions` in their order there.
    """
    l1, l2, l3 = (float(v) for v in lengths)
    if l1 <= 0.0 or l2 <= 0.0:
        return np.empty((0, 3))
    phi = np.linspace(-np.pi, np.pi, count, endpoint=False)
    wrists = np.asarray(x, dtype=float)[:2] - l3 * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    cos_elbow = (np.sum(wrists ** 2, axis=1) - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)
    reached = np.abs(cos_elbow) <= 1.0
    phi, wrists = phi[reached], wrists[reached]
    elbow = np.arccos(cos_elbow[reached])
    # The order of the set {elbow, -elbow} there, and a single solution at a straight elbow.
    sign = np.array([1.0 if next(iter({e, -e})) == e else -1.0 for e in elbow.tolist()])
    elbows = np.stack([sign * elbow, -sign * elbow], axis=1)
    keep = np.stack([np.ones(len(elbow), dtype=bool), elbow != 0.0], axis=1)
    row = np.broadcast_to(np.arange(len(elbow))[:, None], keep.shape)[keep]
    second = elbows[keep]
    first = np.arctan2(wrists[row, 1], wrists[row, 0]) - np.arctan2(
        l2 * np.sin(second), l1 + l2 * np.cos(second))
    return np.stack([first, second, phi[row] - first - second], axis=1)


class Escape(NamedTuple):
    """The cells certified to escape with one joint locked, and the goals that show it.

    `cells` (N, N, N) bool; `goal_points` (g, 3) [rad] are the exact goal configurations
    in their components, solved at the middle of sub-slab `goal_slabs` (g,) (layer · m + k)
    of m = `sub_slabs` per layer.
    """

    cells: np.ndarray
    goal_points: np.ndarray
    goal_slabs: np.ndarray
    sub_slabs: int


@dataclass(frozen=True, eq=False)
class TolerantSet:
    """G on a joint grid (see the module docstring) for a scene's task.

    `escape(i)` holds the cells every configuration of which can escape with joint i
    locked (under-approximation) and the goal configurations that show it; the cells that
    may hold such a configuration (`liberal_escape(i)`, the over-approximation) are only
    needed by a proof that no plan exists. Each is computed for one joint at a time, when
    first asked for, so that a search that fails after one joint skips the others. A
    grid pooled from a `finer` one (`pooled_tolerant_set`) takes the cells that may put
    the tool at the start or the goal from it.
    """

    scene: Scene
    classes: CellClasses
    joints: tuple[int, ...]
    finer: TolerantSet | None = None
    _escapes: dict = field(default_factory=dict, init=False, repr=False)
    _liberal_escapes: dict = field(default_factory=dict, init=False, repr=False)

    @property
    def lattice(self) -> JointLattice:
        """The grid."""
        return self.classes.lattice

    def escape(self, joint: int) -> Escape:
        """Return the side of G_joint certified from inside (`certified_escape`), computed once."""
        if joint not in self._escapes:
            self._escapes[joint] = certified_escape(self.scene, self.classes, joint)
        return self._escapes[joint]

    @cached_property
    def certified_all(self) -> np.ndarray:
        """(N, N, N) bool: cells inside G for every tolerated joint (under-approximation)."""
        return self.certified_holding(None)

    def certified_holding(self, cells: np.ndarray | None) -> np.ndarray | None:
        """`certified_all`, or None once the joints so far leave none of `cells` (k, 3) in it.

        Joints are taken in turn: a cell out after one joint is out of G, so the joints
        left need not be computed. With `cells` None, every joint is.
        """
        out = self.classes.certified.copy()
        for joint in self.joints:
            out &= self.escape(joint).cells
            if cells is not None and not out[tuple(np.asarray(cells).T)].any():
                return None
        return out

    @cached_property
    def near_goal(self) -> np.ndarray:
        """(N, N, N) bool: cells that may put the tool within the goal tolerance.

        On a pooled grid, the finer grid's cells pooled: a block may when one of its
        cells may, and their bounds are sharper.
        """
        task = self.scene.task
        return self._tool_near(np.asarray(task.goal, dtype=float), task.goal_tolerance)

    @cached_property
    def near_start(self) -> np.ndarray:
        """(N, N, N) bool: cells that may put the tool at the start (pooled as `near_goal`)."""
        return self._tool_near(np.asarray(self.scene.task.start, dtype=float), 0.0)

    def _tool_near(self, x: np.ndarray, tolerance: float) -> np.ndarray:
        if self.finer is not None:
            return self.finer.lattice.tool_near(self.scene.robot, x, tolerance, pooled=True)
        return self.lattice.tool_near(self.scene.robot, x, tolerance)

    def liberal_escape(self, joint: int) -> np.ndarray:
        """(N, N, N) bool: cells that may escape with `joint` locked (components found once).

        A cell may escape when its layer component of possibly free cells holds a cell
        that may put the tool within the goal tolerance (`escape_liberal`).
        """
        found, chosen = self._liberal_components(joint)
        return found.cells(chosen)

    def _liberal_components(self, joint: int) -> tuple[Components, np.ndarray]:
        """Return the layer components of the possibly free cells and which may escape.

        Found once per joint: (components, chosen (count + 1,) bool).
        """
        if joint not in self._liberal_escapes:
            found = layer_components(self.classes.possible, joint, self.lattice.periodic)
            self._liberal_escapes[joint] = found, found.holding(self._possible_goal)
        return self._liberal_escapes[joint]

    @cached_property
    def _possible_goal(self) -> np.ndarray:
        """(N, N, N) bool: cells that may be free and may put the tool at the goal."""
        return self.near_goal & self.classes.possible

    @cached_property
    def liberal_all(self) -> np.ndarray:
        """(N, N, N) bool: cells that may meet G (over-approximation)."""
        return self.liberal_holding(())

    def liberal_holding(self, masks: tuple[np.ndarray, ...]) -> np.ndarray | None:
        """`liberal_all`, or None once the joints so far leave no cell of some mask in it.

        `masks` are (N, N, N) bool; joints are taken in turn, as `certified_holding` does.
        """
        out = self.classes.possible.copy()
        for joint in self.joints:
            # out &= liberal_escape(joint): out lies within the possibly free cells, which
            # these components cover, so clearing the other components' cells does it.
            found, chosen = self._liberal_components(joint)
            found.clear_others(chosen, out)
            if not all(overlap(out, mask) for mask in masks):
                return None
        return out


def sub_slab_count(robot: PlanarChain, step: float, joint: int, tolerance: float) -> int:
    """Sub-slabs m of a layer such that half a sub-slab of θ_joint moves the tool <= tolerance."""
    reach = float(robot.tip_lever_arms()[joint])
    return max(1, int(np.ceil(reach * step / (2.0 * 0.9 * tolerance))))


def tolerant_set(scene: Scene, cells: int, margin: float = 0.0) -> TolerantSet:
    """Classify the N^3 cells (N = `cells` per joint) for G of scene.task; G itself on use.

    Free means clear of the disks by more than `margin` [m].
    """
    if not supports(scene):
        raise InputError('robot', 'the joint grid handles planar 3R arms among disks only')
    if cells >= 1 and not fits_goal_tolerance(scene, cells):  # (classify_cells checks < 1)
        raise ValueError(f'{cells} cells are too coarse for the goal tolerance')
    return TolerantSet(scene, classify_cells(scene, cells, margin),
                       tuple(scene.tolerated_joints))


def fits_goal_tolerance(scene: Scene, cells: int) -> bool:
    """Whether G can be built on `cells` cells per joint for the task's goal tolerance."""
    return cells >= 1 and _fine_enough(scene, JointLattice.over(scene.robot, cells))


def pooled_tolerant_set(grid: TolerantSet) -> TolerantSet | None:
    """G on the grid's classes pooled in blocks of 2^3 (`CellClasses.pooled`).

    The cells that may put the tool at the start or the goal are the grid's, pooled.
    None when the grid has an odd number of cells per joint, or when the pooled cells
    are too coarse for the goal tolerance.
    """
    if grid.lattice.cells % 2:
        return None
    classes = grid.classes.pooled()
    if not _fine_enough(grid.scene, classes.lattice):
        return None
    return TolerantSet(grid.scene, classes, grid.joints, finer=grid)


def _fine_enough(scene: Scene, lattice: JointLattice) -> bool:
    """Whether a layer of each tolerated joint needs at most 62 sub-slabs (one bit each)."""
    return all(sub_slab_count(scene.robot, lattice.step[joint], joint,
                              scene.task.goal_tolerance) <= 62
               for joint in scene.tolerated_joints)


def certified_escape(scene: Scene, classes: CellClasses, joint: int) -> Escape:
    """Find the cells certified to escape with `joint` locked (`escape_certified`), and goals.

    Components of certified free cells in each layer of the joint that cover every
    sub-slab with an exact goal configuration.
    """
    robot, task, lattice = scene.robot, scene.task, classes.lattice
    cells = lattice.cells
    found = layer_components(classes.certified, joint, lattice.periodic)
    m = sub_slab_count(robot, lattice.step[joint], joint, task.goal_tolerance)
    levels = lattice.lower[joint] + (np.arange(cells)[:, None]
                                     + (np.arange(m)[None, :] + 0.5) / m) * lattice.step[joint]
    points, slab = locked_goal_configurations_at(np.asarray(robot.link_lengths, dtype=float),
                                                 np.asarray(task.goal, dtype=float), joint,
                                                 levels.ravel())
    keep = lattice.inside(points)
    points, slab = points[keep], slab[keep]
    label = found.at(lattice.cell_of(points))
    coverage = np.zeros(found.count + 1, dtype=np.int64)
    np.bitwise_or.at(coverage, label, np.left_shift(1, slab % m).astype(np.int64))
    full = coverage == (1 << m) - 1
    full[0] = False
    return Escape(found.cells(full), points[full[label]], slab[full[label]], m)


def locked_goal_configurations_at(lengths: np.ndarray, x: np.ndarray, joint: int,
                                  values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`locked_goal_configurations` at many locked values (v,) [rad], vectorised.

    Returns the configurations (s, 3) [rad] and the index into `values` of each.
    """
    l1, l2, l3 = (float(v) for v in lengths)
    values = np.asarray(values, dtype=float)
    x = np.asarray(x, dtype=float)
    if joint == 0:
        a, b = np.full_like(values, l2), np.full_like(values, l3)
        target = x[None, :] - l1 * np.stack([np.cos(values), np.sin(values)], axis=1)
        offset = np.zeros_like(values)
    elif joint == 1:
        rigid = l1 + l2 * np.exp(1j * values)
        a, b, offset = np.abs(rigid), np.full_like(values, l3), np.angle(rigid)
        target = np.broadcast_to(x, (len(values), 2))
    else:
        rigid = l2 + l3 * np.exp(1j * values)
        a, b, offset = np.full_like(values, l1), np.abs(rigid), np.angle(rigid)
        target = np.broadcast_to(x, (len(values), 2))
    usable = (a > 0.0) & (b > 0.0)
    with np.errstate(divide='ignore', invalid='ignore'):
        cos_elbow = (np.sum(target ** 2, axis=1) - a * a - b * b) / (2.0 * a * b)
    usable &= np.abs(cos_elbow) <= 1.0
    out, which = [], []
    for sign in (1.0, -1.0):
        keep = usable if sign > 0 else usable & (np.abs(cos_elbow) < 1.0)
        elbow = sign * np.arccos(np.clip(cos_elbow[keep], -1.0, 1.0))
        first = np.arctan2(target[keep, 1], target[keep, 0]) - np.arctan2(
            b[keep] * np.sin(elbow), a[keep] + b[keep] * np.cos(elbow))
        v = values[keep]
        if joint == 0:
            theta = np.stack([v, first - v, elbow], axis=1)
        elif joint == 1:
            theta = np.stack([first - offset[keep], v, elbow + offset[keep] - v], axis=1)
        else:
            theta = np.stack([first, elbow - offset[keep], v], axis=1)
        out.append(theta)
        which.append(np.flatnonzero(keep))
    return np.vstack(out), np.concatenate(which)
