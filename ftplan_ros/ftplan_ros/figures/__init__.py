"""Figures of a plan as in the paper: the arm in its workspace (Fig. 3), joint space (Fig. 4).

Only matplotlib's object-oriented API is used: every function returns a new `Figure` on
its own Agg canvas and never touches pyplot's global state, so figures can be drawn in
any thread and without a display. The core never imports this package.

A planar arm is drawn in its plane (planar.py) and, with three joints, in the paper's
3-D joint space (joint_space_3d.py); a spatial arm in 3-D (spatial.py). Joint space for
any other arm is one panel per joint against progress along the nominal path
(progress.py).

Angles arrive in radians, as everywhere in ftplan; joint-space axes are drawn in degrees
and workspace axes in metres. Artists carry a `gid` naming what they show ('obstacle',
'arm:theta_s', 'arm:H1', 'S_F', 'theta_s', ...), so tests and scripts can find them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..core.model.robot import PlanarChain, task_errors
from ..core.model.scene import Scene
from ..core.paper.result import PlanResult
from . import planar, progress, spatial
from .joint_space_3d import _c_space_obstacle_cells, draw_joint_space
from .style import (
    DPI,
    FAILURE_COLOUR,
    FINAL_COLOUR,
    GOAL_COLOUR,
    HIT_COLOURS,
    SNAPSHOTS,
    START_COLOUR,
    SURFACE_COLOUR,
    new_figure,
)

__all__ = [
    'DPI', 'FAILURE_COLOUR', 'FINAL_COLOUR', 'GOAL_COLOUR', 'HIT_COLOURS', 'SNAPSHOTS',
    'START_COLOUR', 'SURFACE_COLOUR', '_c_space_obstacle_cells', 'joint_space_figure',
    'motion_figure', 'plan_figure', 'save_figure', 'workspace_figure',
]


def workspace_figure(scene: Scene, result: PlanResult) -> Figure:
    """Draw the arm in its workspace at θ_s among the obstacles (the paper's Fig. 3).

    Shows the arm at θ_s (thick, black, with its joints), the arm at each failure-plane
    hit θ_{H_i} ("H1 hit", ...), x_s, x_g and the end effector's trace along the nominal
    path (dashed); axes in metres, θ_s in degrees in the title. A planar arm is drawn in
    its plane with the obstacles' sections with it; a spatial arm in 3-D with equal scale
    on every axis, the obstacles as surfaces, the task's orientation at x_s and x_g and
    the tolerated joints in the title (spatial.py). An infeasible result shows the
    obstacles, x_s, x_g and the reason in the title.
    """
    if isinstance(scene.robot, PlanarChain):
        figure = new_figure((9.6, 6.0))
        planar.draw_workspace(figure.add_subplot(), scene, result)
    else:
        figure = new_figure((10.4, 7.6))
        spatial.draw_workspace(spatial.add_axes(figure), scene, result)
    return figure


def joint_space_figure(scene: Scene, result: PlanResult, grid_cells: int = 48) -> Figure:
    """Draw the arm's joint space in degrees: Fig. 4 for a planar 3R arm, else one panel per joint.

    Planar arm of three joints (the paper's Fig. 4): the self-motion manifolds M_s and M_g
    (dashed, wrapped to (-180, 180] and broken at the seam), the Θ_s candidates, θ_s, its
    failure-plane hits on M_g^F, the straight paths along the failure planes from θ_s to
    them, the nominal path and the failure surface S_F (its triangles, boundary and some
    of its web lines, in the continuous angles of the plan, which may leave (-180, 180]).
    C-space obstacles are drawn as the colliding cells of a `grid_cells`³ grid over the
    joint ranges that border a free cell; `grid_cells` = 0 leaves them out. The default
    48 takes well under a second for spheres and about a second for a few boxes or
    cylinders.

    Any other arm: every joint against progress along the nominal path (progress.py):
    the nominal path, the spread of S_F, the failure hypercube band, θ_s and M_s at 0,
    M_g^F and the hits at 1, the joint limits; `grid_cells` is not used.

    An infeasible result shows what the planner saw (manifolds, Θ_s) and no S_F. Raises
    ValueError for a negative `grid_cells`.
    """
    if grid_cells < 0:
        raise ValueError(f'grid_cells must be >= 0, got {grid_cells}')
    if _draws_fig4(scene):
        figure = new_figure((7.6, 7.0))
        draw_joint_space(figure.add_subplot(projection='3d'), scene, result, grid_cells)
    else:
        figure = new_figure((9.0, 1.2 + 1.05 * scene.robot.n_joints))
        progress.draw_joint_panels(figure, scene, result)
    return figure


def plan_figure(scene: Scene, result: PlanResult, grid_cells: int = 48) -> Figure:
    """Draw the workspace (left) and joint space (right) of a plan side by side.

    The panels are those of `workspace_figure` and `joint_space_figure` (metres, degrees).
    """
    if _draws_fig4(scene):
        figure = new_figure((15.0, 7.0))
        grid = figure.add_gridspec(1, 2, width_ratios=(1.0, 1.15))
        planar.draw_workspace(figure.add_subplot(grid[0]), scene, result)
        draw_joint_space(figure.add_subplot(grid[1], projection='3d'), scene, result,
                         grid_cells)
    else:
        figure = new_figure((16.0, max(7.6, 1.2 + 1.05 * scene.robot.n_joints)))
        left, right = figure.subfigures(1, 2, width_ratios=(1.0, 1.0))
        if isinstance(scene.robot, PlanarChain):
            planar.draw_workspace(left.add_subplot(), scene, result)
        else:
            spatial.draw_workspace(spatial.add_axes(left), scene, result, legend_below=True)
        progress.draw_joint_panels(right, scene, result)
    verdict = 'failure-tolerant plan' if result.feasible else 'no failure-tolerant plan'
    figure.suptitle(f'{scene.name}: {verdict}', fontsize='x-large')
    return figure


def motion_figure(scene: Scene, motion: np.ndarray, failure_index: int | None,
                  locked_joint: int | None, title: str = '') -> Figure:
    """Draw an executed joint motion (k, n) [rad] of the arm in its workspace [m].

    Faded arm snapshots along the motion, the end effector's trace (dashed up to the
    failure, solid after), the configuration `motion[failure_index]` where joint
    `locked_joint` (0-based) locked in red with that joint circled, the final
    configuration in green, x_s and x_g (in 3-D for a spatial arm). Either index may be
    None (no failure); without `title` one is made from the locked joint, its angle in
    degrees and the goal error [mm, and deg for an orientation].
    """
    robot = scene.robot
    motion = np.asarray(motion, dtype=float)
    _check_motion(robot.n_joints, motion, failure_index, locked_joint)
    title = title or _motion_title(scene, motion, failure_index, locked_joint)
    if isinstance(robot, PlanarChain):
        figure = new_figure((9.6, 6.0))
        planar.draw_motion(figure.add_subplot(), scene, motion, failure_index, locked_joint,
                           title)
    else:
        figure = new_figure((10.4, 7.6))
        spatial.draw_motion(spatial.add_axes(figure), scene, motion, failure_index,
                            locked_joint, title)
    return figure


def save_figure(figure: Figure, path: str | Path, dpi: int = DPI) -> Path:
    """Write the figure to `path` as a PNG at `dpi` [pixels/inch], creating its folders."""
    path = Path(path)
    if path.suffix.lower() != '.png':
        raise ValueError(f'save_figure writes PNG files: give a path ending in .png, not {path}')
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=dpi, format='png', bbox_inches='tight')  # keep outside legends
    return path


def _draws_fig4(scene: Scene) -> bool:
    """Whether joint space is the paper's 3-D Fig. 4: a planar arm of three joints."""
    return isinstance(scene.robot, PlanarChain) and scene.robot.n_joints == 3


def _check_motion(n: int, motion: np.ndarray, failure_index: int | None,
                  locked_joint: int | None) -> None:
    """Raise ValueError unless motion is (k, n) finite and the indices fit it."""
    if motion.ndim != 2 or motion.shape[1] != n or len(motion) == 0:
        raise ValueError(f'motion must have shape (k, {n}) with k >= 1, got {motion.shape}')
    if not np.all(np.isfinite(motion)):
        raise ValueError('motion holds non-finite angles')
    if failure_index is not None and not 0 <= failure_index < len(motion):
        raise ValueError(f'failure_index {failure_index} is outside the motion\'s '
                         f'{len(motion)} configurations')
    if locked_joint is not None:
        if not 0 <= locked_joint < n:
            raise ValueError(f'locked_joint {locked_joint} is not a joint index (0..{n - 1})')
        if failure_index is None:
            raise ValueError('locked_joint needs the failure_index where it locked')


def _motion_title(scene: Scene, motion: np.ndarray, failure_index: int | None,
                  locked_joint: int | None) -> str:
    """Say which joint locked at what angle [deg] and how far from x_g the motion ends."""
    robot = scene.robot
    title = 'Executed motion'
    if locked_joint is not None:
        title += (f': {robot.joint_names[locked_joint]} locked at '
                  f'{np.degrees(motion[failure_index, locked_joint]):.1f}°')
    if scene.task is not None:
        distance, angle = task_errors(robot, scene.task.goal, motion[-1])
        title += f', goal error {1000.0 * distance:.1f} mm'
        if scene.task.kind in ('axis', 'pose'):
            title += f' and {np.degrees(angle):.2f}°'
    return title
