"""Exhaustive joint-space grids: the brute-force baselines the planner is checked against.

* `recoverable_in_plane`: with joint i locked at θ_i, can the arm at θ reach x_g? Every
  cell of a grid over the failure plane is judged by its centre with the cell's motion
  bound added, so it counts as *possibly free* when some configuration in it might be
  collision-free, and as *possibly a goal* when some configuration in it might reach
  x_g; cells touching at a face, edge or corner are neighbours. The flood fill
  over-approximates, so its "no" proves that the arm cannot recover: the referee of a
  plan (bench/scenes.referee_accepts) and the tests ask it.
* `grid_plan` (the exhaustive grid baseline): the grid planner for the whole problem; it
  samples cell centres, so its answers prove nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ..collision.checker import CollisionChecker
from ..model.robot import Robot, task_errors
from ..paper.manifolds import ManifoldOptions, trace_self_motion_manifolds


@dataclass(frozen=True)
class JointGrid:
    """Cells of `step` (n,) [rad] from `lower` (n,) [rad]; `shape` (n,) cells per joint."""

    lower: np.ndarray
    step: np.ndarray
    shape: tuple[int, ...]
    periodic: np.ndarray

    @classmethod
    def over(cls, robot: Robot, cells_per_joint: int) -> JointGrid:
        """Make a grid of `cells_per_joint` cells along every joint's range."""
        limits = robot.limits
        step = (limits[:, 1] - limits[:, 0]) / cells_per_joint
        return cls(limits[:, 0], step, (cells_per_joint,) * robot.n_joints, robot.periodic)

    def centers(self) -> np.ndarray:
        """Cell centres (*shape, n) [rad]."""
        axes = [self.lower[j] + (np.arange(size) + 0.5) * self.step[j]
                for j, size in enumerate(self.shape)]
        return np.stack(np.meshgrid(*axes, indexing='ij'), axis=-1)

    def cell_of(self, theta: np.ndarray) -> tuple[int, ...]:
        """Index of the cell holding θ (n,) [rad] (periodic joints wrapped)."""
        offset = (np.asarray(theta) - self.lower) / self.step
        index = np.floor(offset).astype(int)
        shape = np.array(self.shape)
        index = np.where(self.periodic, index % shape, np.clip(index, 0, shape - 1))
        return tuple(int(k) for k in index)


def possibly_free(checker: CollisionChecker, centers: np.ndarray, half_width: np.ndarray,
                  ) -> np.ndarray:
    """Mark (bool, ...) cells where a configuration within `half_width` (n,) [rad] may be free."""
    flat = centers.reshape(-1, centers.shape[-1])
    clearance = checker.clearance(flat, needed=0.0)
    motion = checker.lever_arms() @ half_width
    return np.all(clearance > -motion, axis=1).reshape(centers.shape[:-1])


def possibly_goal(robot: Robot, x: np.ndarray, centers: np.ndarray, half_width: np.ndarray,
                  tolerance: float = 0.0) -> np.ndarray:
    """Mark (bool, ...) cells where a configuration within `half_width` (n,) [rad] may reach x.

    Reaching means coming within `tolerance` [m] of the task point x's position (its
    orientation is not looked at: the grids are for planar arms).
    """
    flat = centers.reshape(-1, centers.shape[-1])
    error = task_errors(robot, x, flat)[:, 0]
    reach = robot.tip_lever_arms() @ half_width + tolerance
    return (error <= reach).reshape(centers.shape[:-1])


def label_periodic(mask: np.ndarray, periodic: np.ndarray) -> np.ndarray:
    """Label the connected components of `mask` (full connectivity), joined across periodic faces.

    The mask is padded by one wrapped cell along each periodic axis and labelled; a pad
    cell is a copy of the cell across the seam, so its label and that cell's label are
    one component. Returns labels like `scipy.ndimage.label` (0 = not in the mask).
    """
    pad = [(1, 1) if p else (0, 0) for p in periodic]
    labels, count = ndimage.label(np.pad(mask, pad, mode='wrap'),
                                  structure=np.ones((3,) * mask.ndim, dtype=bool))
    inner = labels[tuple(slice(1, -1) if p else slice(None) for p in periodic)]
    if count == 0:
        return inner
    origin = np.pad(np.arange(mask.size).reshape(mask.shape), pad, mode='wrap')
    marked = labels > 0
    pairs = (labels[marked], inner.ravel()[origin[marked]])
    graph = coo_matrix((np.ones(len(pairs[0])), pairs), shape=(count + 1, count + 1))
    _, merged = connected_components(graph, directed=False)
    return np.where(inner > 0, merged[inner] + 1, 0)


def recoverable_in_plane(checker: CollisionChecker, theta: np.ndarray, joint: int,
                         x_goal: np.ndarray, cells_per_joint: int,
                         extra_goals: np.ndarray | None = None,
                         goal_tolerance: float = 0.0) -> bool:
    """Whether the arm at θ (n,) [rad] may reach x_g with `joint` locked: a flood fill in H_i.

    The failure plane θ_joint = θ[joint] is gridded over the other joints; the fill
    starts from θ's cell. `extra_goals` (g, n) [rad] are exact goal configurations in the
    plane (e.g. from exact inverse kinematics) whose cells count as goals too; a cell
    that may come within `goal_tolerance` [m] of x_g is a goal.
    """
    robot = checker.robot
    free_joints = [j for j in range(robot.n_joints) if j != joint]
    grid = JointGrid.over(robot, cells_per_joint)
    plane = JointGrid(grid.lower[free_joints], grid.step[free_joints],
                      grid.shape[:-1], grid.periodic[free_joints])
    centers_free = plane.centers()
    centers = np.empty(centers_free.shape[:-1] + (robot.n_joints,))
    centers[..., free_joints] = centers_free
    centers[..., joint] = theta[joint]
    half = 0.5 * grid.step
    half[joint] = 0.0  # the locked joint is exact
    free = possibly_free(checker, centers, half)
    goal = possibly_goal(robot, x_goal, centers, half, goal_tolerance) & free
    for exact in [] if extra_goals is None else extra_goals:
        goal[plane.cell_of(exact[free_joints])] = True
    labels = label_periodic(free, plane.periodic)
    start = labels[plane.cell_of(theta[free_joints])]
    return bool(start > 0 and np.any(goal & (labels == start)))


@dataclass(frozen=True)
class GridPlan:
    """The grid's answer: `feasible` unless it proves no failure-tolerant motion exists."""

    feasible: bool
    safe_cells: int     # cells from which every locked joint may still reach x_g
    free_cells: int


def grid_plan(checker: CollisionChecker, x_start: np.ndarray, x_goal: np.ndarray,
              cells_per_joint: int) -> GridPlan:
    """Run the exhaustive baseline: grid, flood fill in every failure plane, path search.

    As a plain grid planner would, a cell is free when its centre is collision-free; goal
    and start cells are those the self-motion manifolds pass through. A cell is safe when,
    for every joint i, its slice of the grid along axis i connects it to a goal cell
    through free cells. A motion exists when a start cell and a goal cell lie in one
    component of safe cells. (Centre sampling can miss narrow passages: its "no" is not a
    proof.)
    """
    robot = checker.robot
    grid = JointGrid.over(robot, cells_per_joint)
    centers = grid.centers()
    half = 0.5 * grid.step
    free = possibly_free(checker, centers, np.zeros_like(half))
    goal = _preimage_cells(robot, grid, x_goal) & free
    start = _preimage_cells(robot, grid, x_start) & free
    safe = free.copy()
    for joint in range(robot.n_joints):
        others = np.delete(grid.periodic, joint)
        recoverable = np.zeros_like(free)
        for k in range(grid.shape[joint]):
            index = [slice(None)] * robot.n_joints
            index[joint] = k
            labels = label_periodic(free[tuple(index)], others)
            reached = np.unique(labels[goal[tuple(index)]])
            recoverable[tuple(index)] = np.isin(labels, reached[reached > 0])
        safe &= recoverable
    labels = label_periodic(safe, grid.periodic)
    joined = np.intersect1d(np.unique(labels[start & safe]), np.unique(labels[goal & safe]))
    return GridPlan(bool(np.any(joined > 0)), int(safe.sum()), int(free.sum()))


def _preimage_cells(robot: Robot, grid: JointGrid, x: np.ndarray) -> np.ndarray:
    """Mark (bool, *shape) the cells that a self-motion manifold of x (m,) [m] crosses."""
    step = 0.25 * float(grid.step.min())  # samples several times finer than the cells
    branches = trace_self_motion_manifolds(robot, x, np.random.default_rng(0),
                                           ManifoldOptions(step_max=step))
    marked = np.zeros(grid.shape, dtype=bool)
    for branch in branches:
        for theta in branch.points:
            marked[grid.cell_of(theta)] = True
    return marked
