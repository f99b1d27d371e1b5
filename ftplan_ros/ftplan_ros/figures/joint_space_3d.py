"""The first three joints' space of a planar 3R arm in degrees (the paper's Fig. 4).

Self-motion manifolds, Θ_s candidates, θ_s, the failure-plane hits, the nominal path and
the failure surface S_F in one 3-D view, with the C-space obstacles as grid cells.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Patch
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ..core.collision.checker import CollisionChecker
from ..core.model.robot import PlanarChain
from ..core.model.scene import Obstacle, Scene
from ..core.paper.failure_surface import FailureSurface
from ..core.paper.result import PlanResult
from .planar import screening_spheres
from .style import (
    GOAL_COLOUR,
    START_COLOUR,
    SURFACE_COLOUR,
    SURFACE_EDGE,
    degrees_text,
    hit_colour,
)

_WEB_LINES = 8       # web paths and rungs drawn over S_F, each way


def draw_joint_space(ax: Axes, scene: Scene, result: PlanResult, grid_cells: int) -> None:
    """Draw the 3-D joint space of a 3-joint arm (see `figures.joint_space_figure`)."""
    robot = scene.robot
    if robot.n_joints < 3:
        raise ValueError(f'joint-space figures need 3 joints or more, the robot has '
                         f'{robot.n_joints}')
    if grid_cells < 0:
        raise ValueError(f'grid_cells must be >= 0, got {grid_cells}')
    lower, upper = np.degrees(robot.limits[:3]).T
    extra: list[Patch] = []
    if grid_cells and scene.obstacles:
        cells = np.degrees(_c_space_obstacle_cells(robot, scene.obstacles, grid_cells))
        ax.plot(*cells.T, '.', ms=1.5, color='0.45', alpha=0.12, gid='C_obs',
                label=f'C-space obstacles ({grid_cells}³ grid)')
    _draw_manifolds(ax, result, robot.periodic[:3])
    surface = result.surface
    if result.feasible and surface is not None:
        paths = np.degrees(surface.paths[..., :3])
        extra.append(_draw_surface(ax, surface, paths))
        lower = np.minimum(lower, paths.min(axis=(0, 1)))
        upper = np.maximum(upper, paths.max(axis=(0, 1)))
        title = (r'Joint space: $\mathcal{M}_s$, $\mathcal{M}_g$ dashed;'
                 '\n' + rf'$\theta_s$ = {degrees_text(surface.theta_s)} and $\mathcal{{S}}_F$')
    else:
        title = (r'Joint space: $\mathcal{M}_s$, $\mathcal{M}_g$ dashed;' '\n'
                 r'no failure surface $\mathcal{S}_F$')
    _finish_axes(ax, robot.joint_names, lower, upper, title, extra)


def _draw_manifolds(ax: Axes, result: PlanResult, periodic: np.ndarray) -> None:
    """Draw M_s and M_g dashed and the Θ_s candidates as dots, in degrees (first 3 joints)."""
    for gid, branches, colour, label in (
            ('M_s', result.start_manifolds, START_COLOUR, r'$\mathcal{M}_s$ ($\mathbf{x}_s$)'),
            ('M_g', result.goal_manifolds, GOAL_COLOUR, r'$\mathcal{M}_g$ ($\mathbf{x}_g$)')):
        for k, branch in enumerate(branches):
            points = branch.points[:, :3]
            if branch.closed:
                points = np.vstack([points, points[:1] + branch.period[:3]])
            ax.plot(*_wrapped_polyline(np.degrees(points), periodic).T, '--', color=colour,
                    lw=1.3, gid=gid, label=label if k == 0 else '_nolegend_')
    if result.necessary_starts is not None and len(result.necessary_starts):
        candidates = _wrap_degrees(np.degrees(result.necessary_starts[:, :3]), periodic)
        ax.plot(*candidates.T, '.', ms=3.0, color=START_COLOUR, alpha=0.6, gid='Theta_S',
                label=r'$\Theta_s$ candidates')


def _draw_surface(ax: Axes, surface: FailureSurface, paths: np.ndarray) -> Patch:
    """Draw S_F, given as its paths (p, k, 3) in degrees, with its nominal and hit paths.

    Returns the legend's patch for S_F.
    """
    triangles = paths.reshape(-1, 3)[surface.triangles]
    ax.add_collection3d(Poly3DCollection(triangles, facecolor=SURFACE_COLOUR, alpha=0.3,
                                         edgecolor='none', gid='S_F'))
    ax.plot(*_web_lines(paths).T, '-', color=SURFACE_EDGE, lw=0.5, alpha=0.5,
            gid='S_F:web', label='_nolegend_')
    boundary = np.vstack([paths[0], paths[1:, -1], paths[-1, ::-1]])
    ax.plot(*boundary.T, '-', color=SURFACE_EDGE, lw=1.6, gid='S_F:boundary',
            label='_nolegend_')
    ax.plot(*paths[surface.nominal].T, '-', color='k', lw=2.6, gid='nominal',
            label='nominal path')
    for i, path in enumerate(surface.hit_paths):
        ax.plot(*paths[path].T, '-', color=hit_colour(i), lw=1.8, gid=f'H{i + 1}:path',
                label='_nolegend_')
        ax.plot(*paths[path, -1:].T, 'o', ms=8, color=hit_colour(i), mec='k',
                gid=f'hit:H{i + 1}', label=f'H{i + 1} hit')
    ax.plot(*paths[0, :1].T, '*', ms=18, color='k', mec='white', gid='theta_s',
            label=r'$\theta_s$')
    return Patch(facecolor=SURFACE_COLOUR, edgecolor=SURFACE_EDGE, alpha=0.6,
                 label=r'$\mathcal{S}_F$')


def _finish_axes(ax: Axes, joint_names: tuple[str, ...], lower: np.ndarray, upper: np.ndarray,
                 title: str, extra: list[Patch]) -> None:
    """Label the axes, tick them every 90° within lower..upper (3,) [deg], view, legend."""
    for j, axis in enumerate((ax.xaxis, ax.yaxis, ax.zaxis)):
        axis.set_label_text(rf'$\theta_{j + 1}$ ({joint_names[j]}) [deg]')
        ticks = np.arange(np.ceil(lower[j] / 90.0), np.floor(upper[j] / 90.0) + 1) * 90.0
        axis.set_ticks(ticks)
    ax.set_xlim(lower[0], upper[0])
    ax.set_ylim(lower[1], upper[1])
    ax.set_zlim(lower[2], upper[2])
    ax.view_init(elev=24.0, azim=-58.0)
    ax.set_title(title)
    handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + extra, loc='upper center', bbox_to_anchor=(0.5, 0.0),
              ncols=4, fontsize='small')


def _c_space_obstacle_cells(robot: PlanarChain, obstacles: Sequence[Obstacle],
                           cells: int) -> np.ndarray:
    """Centres (N, 3) [rad] of the colliding cells of a cells³ grid that touch a free cell.

    The grid spans the first three joints' ranges (robot.limits); joints after the third
    stay at 0. Only the cells on the obstacles' surfaces are kept, the inside being
    hidden anyway. A cell collides when the checker's clearance is <= 0 [m]. Boxes and
    cylinders go through fcl, which is slow, so each is first screened with two spheres
    (see `_screening_spheres`) and fcl decides only the cells between them.
    """
    lower, upper = robot.limits[:3].T
    axes = [lo + (np.arange(cells) + 0.5) * (hi - lo) / cells
            for lo, hi in zip(lower, upper, strict=True)]
    grid = np.stack(np.meshgrid(*axes, indexing='ij'), axis=-1).reshape(-1, 3)
    thetas = np.zeros((len(grid), robot.n_joints))
    thetas[:, :3] = grid
    spheres = [ob for ob in obstacles if ob.shape == 'sphere']
    colliding = np.zeros(len(grid), dtype=bool)
    if spheres:
        colliding = CollisionChecker(robot, spheres).min_clearance(thetas) <= 0.0
    for obstacle in obstacles:
        if obstacle.shape == 'sphere':
            continue
        outer, inner = screening_spheres(obstacle, robot.link_radius)
        if outer is None:
            continue
        undecided = ~colliding & (_sphere_clearance(robot, outer, thetas) <= 0.0)
        if inner is not None:
            surely = undecided & (_sphere_clearance(robot, inner, thetas) < 0.0)
            colliding |= surely
            undecided &= ~surely
        if undecided.any():
            colliding[undecided] = CollisionChecker(robot, [obstacle]).min_clearance(
                thetas[undecided]) <= 0.0
    solid = colliding.reshape(cells, cells, cells)
    exposed = np.zeros_like(solid)
    for axis in range(3):
        for shift in (1, -1):
            neighbour = np.roll(solid, shift, axis=axis)
            if not robot.periodic[axis]:  # past a joint limit counts as free
                edge = [slice(None)] * 3
                edge[axis] = 0 if shift == 1 else -1
                neighbour[tuple(edge)] = False
            exposed |= ~neighbour
    return grid[(solid & exposed).ravel()]


def _wrapped_polyline(points: np.ndarray, periodic: np.ndarray) -> np.ndarray:
    """Wrap a continuous polyline (k, d) [deg] to (-180, 180] with NaN rows where it jumps.

    `periodic` (d,) marks the components that wrap; a NaN row is inserted wherever a
    wrapped component jumps by more than 180°, so a line drawn through it breaks at
    the seam instead of crossing the whole plot.
    """
    wrapped = _wrap_degrees(points, periodic)
    jumps = np.any(np.abs(np.diff(wrapped, axis=0)) > 180.0, axis=1)
    return np.insert(wrapped, np.flatnonzero(jumps) + 1, np.nan, axis=0)


def _wrap_degrees(points: np.ndarray, periodic: np.ndarray) -> np.ndarray:
    return np.where(periodic, 180.0 - np.mod(180.0 - points, 360.0), points)


def _web_lines(paths: np.ndarray) -> np.ndarray:
    """Join some of the web's paths and rungs (points [deg]) in one polyline, NaN-separated."""
    n_paths, n_points = paths.shape[:2]
    gap = np.full((1, paths.shape[-1]), np.nan)
    pieces = []
    for k in np.unique(np.linspace(0, n_paths - 1, _WEB_LINES).round().astype(int)):
        pieces += [paths[k], gap]
    for w in np.unique(np.linspace(1, n_points - 1, _WEB_LINES).round().astype(int)):
        pieces += [paths[:, w], gap]
    return np.vstack(pieces)


def _sphere_clearance(robot: PlanarChain, sphere: Obstacle, thetas: np.ndarray) -> np.ndarray:
    return CollisionChecker(robot, [sphere]).min_clearance(thetas)
