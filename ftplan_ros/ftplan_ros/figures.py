"""Figures of a plan as in the paper: the arm in its workspace (Fig. 3), joint space (Fig. 4).

Only matplotlib's object-oriented API is used: every function returns a new `Figure` on
its own Agg canvas and never touches pyplot's global state, so figures can be drawn in
any thread and without a display. The core never imports this module.

Angles arrive in radians, as everywhere in ftplan; joint-space axes are drawn in degrees
and workspace axes in metres. Artists carry a `gid` naming what they show ('obstacle',
'arm:theta_s', 'arm:H1', 'S_F', 'theta_s', ...), so tests and scripts can find them.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch, Polygon
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from scipy.spatial import ConvexHull, QhullError

from .core.collision import CollisionChecker, rotation_from_rpy
from .core.paths import densify, point_at_fraction
from .core.result import PlanResult
from .core.robot import PlanarChain
from .core.scene import Obstacle, Scene

DPI = 120
SNAPSHOTS = 12  # arm drawings along an executed motion
HIT_COLOURS = ('#d62728', '#1f77b4', '#2ca02c', '#9467bd', '#8c564b', '#e377c2')
START_COLOUR = '#7b3294'    # M_s and the Θ_s candidates
GOAL_COLOUR = '#e08214'     # M_g and x_g
SURFACE_COLOUR = '#6baed6'  # S_F
SURFACE_EDGE = '#08519c'
FAILURE_COLOUR = '#d7191c'
FINAL_COLOUR = '#1a9641'
OBSTACLE_FACE = '#bdbdbd'
OBSTACLE_EDGE = '#525252'
_TRACE_STEP = 0.01   # [rad] largest joint step between samples of an end-effector trace
_RIM_POINTS = 48     # points on each rim of a cylinder when its section is a polygon
_WEB_LINES = 8       # web paths and rungs drawn over S_F, each way


def workspace_figure(scene: Scene, result: PlanResult) -> Figure:
    """Draw the arm in its workspace at θ_s among the obstacles (the paper's Fig. 3).

    Shows the obstacles' sections with the arm's plane z = 0, the arm at θ_s (thick,
    black, with its joints), the arm at each failure-plane hit θ_{H_i} ("H1 hit", ...),
    x_s, x_g and the end effector's trace along the nominal path (dashed); axes in metres,
    θ_s in degrees in the title. An infeasible result shows the obstacles, x_s, x_g and
    the reason in the title.
    """
    figure = _new_figure((9.6, 6.0))
    _draw_workspace(figure.add_subplot(), scene, result)
    return figure


def joint_space_figure(scene: Scene, result: PlanResult, grid_cells: int = 48) -> Figure:
    """Draw the first three joints' space in degrees (the paper's Fig. 4).

    Shows the self-motion manifolds M_s and M_g (dashed, wrapped to (-180, 180] and broken
    at the seam), the Θ_s candidates, θ_s, its failure-plane hits on M_g^F, the straight
    paths along the failure planes from θ_s to them, the nominal path and the failure
    surface S_F (its triangles, boundary and some of its web lines, in the continuous
    angles of the plan, which may leave (-180, 180]). C-space obstacles are drawn as the
    colliding cells of a `grid_cells`³ grid over the joint ranges that border a free cell
    (joints after the third at 0); `grid_cells` = 0 leaves them out. The default 48 takes
    well under a second for spheres and about a second for a few boxes or cylinders.
    An infeasible result shows what the planner saw (manifolds, Θ_s) and no S_F. Raises
    ValueError for a robot with fewer than three joints or a negative `grid_cells`.
    """
    figure = _new_figure((7.6, 7.0))
    _draw_joint_space(figure.add_subplot(projection='3d'), scene, result, grid_cells)
    return figure


def plan_figure(scene: Scene, result: PlanResult, grid_cells: int = 48) -> Figure:
    """Draw the workspace (left) and joint space (right) of a plan side by side.

    The panels are those of `workspace_figure` and `joint_space_figure` (metres, degrees).
    """
    figure = _new_figure((15.0, 7.0))
    grid = figure.add_gridspec(1, 2, width_ratios=(1.0, 1.15))
    _draw_workspace(figure.add_subplot(grid[0]), scene, result)
    _draw_joint_space(figure.add_subplot(grid[1], projection='3d'), scene, result, grid_cells)
    verdict = 'failure-tolerant plan' if result.feasible else 'no failure-tolerant plan'
    figure.suptitle(f'{scene.name}: {verdict}', fontsize='x-large')
    return figure


def motion_figure(scene: Scene, motion: np.ndarray, failure_index: int | None,
                  locked_joint: int | None, title: str = '') -> Figure:
    """Draw an executed joint motion (k, n) [rad] of the arm in its workspace [m].

    Faded arm snapshots along the motion, the end effector's trace (dashed up to the
    failure, solid after), the configuration `motion[failure_index]` where joint
    `locked_joint` (0-based) locked in red with that joint circled, the final
    configuration in green, x_s and x_g. Either index may be None (no failure); without
    `title` one is made from the locked joint, its angle in degrees and the goal error.
    """
    robot = scene.robot
    motion = np.asarray(motion, dtype=float)
    if motion.ndim != 2 or motion.shape[1] != robot.n_joints or len(motion) == 0:
        raise ValueError(f'motion must have shape (k, {robot.n_joints}) with k >= 1, '
                         f'got {motion.shape}')
    if not np.all(np.isfinite(motion)):
        raise ValueError('motion holds non-finite angles')
    if failure_index is not None and not 0 <= failure_index < len(motion):
        raise ValueError(f'failure_index {failure_index} is outside the motion\'s '
                         f'{len(motion)} configurations')
    if locked_joint is not None:
        if not 0 <= locked_joint < robot.n_joints:
            raise ValueError(f'locked_joint {locked_joint} is not a joint index '
                             f'(0..{robot.n_joints - 1})')
        if failure_index is None:
            raise ValueError('locked_joint needs the failure_index where it locked')

    figure = _new_figure((9.6, 6.0))
    ax = figure.add_subplot()
    _draw_scenery(ax, scene)
    fractions = np.linspace(0.0, 1.0, SNAPSHOTS) if len(motion) > 1 else [0.0]
    for k, fraction in enumerate(fractions):
        theta = point_at_fraction(motion, fraction) if len(motion) > 1 else motion[0]
        _draw_arm(ax, robot, theta, '0.3', width=1.4, alpha=0.12 + 0.3 * k / len(fractions),
                  label='arm along the motion' if k == 0 else '_nolegend_', gid='snapshot',
                  marker_size=3.5)
    split = len(motion) - 1 if failure_index is None else failure_index
    before, after = motion[:split + 1], motion[split:]
    ax.plot(*_tip_trace(robot, before).T, '--' if failure_index is not None else '-',
            color='k', lw=1.3, gid='trace', label='end effector' + (
                ' before the failure' if failure_index is not None else ''))
    if failure_index is not None and len(after) > 1:
        ax.plot(*_tip_trace(robot, after).T, '-', color=FAILURE_COLOUR, lw=1.6,
                gid='trace:recovery', label='end effector after the failure')
    if failure_index is not None:
        failed = motion[failure_index]
        _draw_arm(ax, robot, failed, FAILURE_COLOUR, width=3.0, label='at the failure',
                  gid='arm:failure', zorder=5)
        if locked_joint is not None:
            where = robot.joint_positions(failed)[locked_joint]
            ax.plot(*where, 'o', ms=19, mfc='none', mec=FAILURE_COLOUR, mew=2.5, zorder=6,
                    gid='locked_joint', label=f'{robot.joint_names[locked_joint]} locked at '
                    f'{np.degrees(failed[locked_joint]):.1f}°')
    _draw_arm(ax, robot, motion[-1], FINAL_COLOUR, width=3.0, label='final', gid='arm:final',
              zorder=5)
    _draw_task(ax, scene)
    if not title:
        title = 'Executed motion'
        if locked_joint is not None:
            title += (f': {robot.joint_names[locked_joint]} locked at '
                      f'{np.degrees(motion[failure_index, locked_joint]):.1f}°')
        if scene.task is not None:
            error = np.linalg.norm(robot.forward_kinematics(motion[-1]) - scene.task.goal)
            title += f', goal error {1000.0 * error:.1f} mm'
    _finish_workspace(ax, robot, title)
    return figure


def save_figure(figure: Figure, path: str | Path, dpi: int = DPI) -> Path:
    """Write the figure to `path` as a PNG at `dpi` [pixels/inch], creating its folders."""
    path = Path(path)
    if path.suffix.lower() != '.png':
        raise ValueError(f'save_figure writes PNG files: give a path ending in .png, not {path}')
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=dpi, format='png', bbox_inches='tight')  # keep outside legends
    return path


# --- workspace ---------------------------------------------------------------------------

def _new_figure(size: tuple[float, float]) -> Figure:
    figure = Figure(figsize=size, layout='constrained')
    FigureCanvasAgg(figure)
    return figure


def _draw_workspace(ax: Axes, scene: Scene, result: PlanResult) -> None:
    robot = scene.robot
    _draw_scenery(ax, scene)
    surface = result.surface
    if result.feasible and surface is not None:
        hits = surface.goal_points[list(surface.hit_paths)]
        for i, hit in enumerate(hits):
            _draw_arm(ax, robot, hit, _hit_colour(i), width=1.6, alpha=0.8,
                      label=f'H{i + 1} hit', gid=f'arm:H{i + 1}', marker_size=4.0)
        ax.plot(*_tip_trace(robot, surface.nominal_path).T, '--', color='k', lw=1.3,
                gid='trace', label='nominal path (end effector)')
        _draw_arm(ax, robot, surface.theta_s, 'k', width=3.5, label=r'$\theta_s$',
                  gid='arm:theta_s', zorder=5)
        title = rf'{scene.name}: $\theta_s$ = {_degrees(surface.theta_s)}'
    else:
        title = _reason_title(result)
    _draw_task(ax, scene)
    _finish_workspace(ax, robot, title)


def _draw_scenery(ax: Axes, scene: Scene) -> None:
    """Draw the arm's base and the obstacles' sections with the plane z = 0."""
    labelled = False
    for obstacle in scene.obstacles:
        patch = _obstacle_patch(obstacle)
        if patch is None:
            continue  # it does not cut the arm's plane
        patch.set(facecolor=OBSTACLE_FACE, edgecolor=OBSTACLE_EDGE, lw=1.0, gid='obstacle',
                  label='_nolegend_' if labelled else 'obstacles', zorder=1)
        ax.add_patch(patch)
        labelled = True
    ax.plot(0.0, 0.0, 's', ms=10, color='k', gid='base', zorder=6, label='_nolegend_')


def _draw_task(ax: Axes, scene: Scene) -> None:
    if scene.task is None:
        return
    ax.plot(*scene.task.start, 'o', ms=10, mfc='white', mec='k', mew=1.8, zorder=7,
            gid='x_s', label=r'$\mathbf{x}_s$')
    ax.plot(*scene.task.goal, '*', ms=17, mfc=GOAL_COLOUR, mec='k', mew=1.0, zorder=7,
            gid='x_g', label=r'$\mathbf{x}_g$')


def _finish_workspace(ax: Axes, robot: PlanarChain, title: str) -> None:
    """Fit the view to what is drawn, then add the arm's reach (a circle) outside the fit."""
    ax.margins(0.12)
    ax.autoscale_view()
    ax.set_autoscale_on(False)
    reach = float(np.sum(robot.link_lengths))
    ring = np.linspace(0.0, 2.0 * np.pi, 241)
    ax.plot(reach * np.cos(ring), reach * np.sin(ring), ':', color='0.6', lw=0.9, gid='reach',
            label='_nolegend_')
    ax.set_aspect('equal', adjustable='box')
    ax.set_xlabel('x [m]')
    ax.set_ylabel('y [m]')
    ax.grid(alpha=0.3)
    ax.set_title(title)
    ax.legend(loc='upper left', bbox_to_anchor=(1.02, 1.0), fontsize='small')


def _draw_arm(ax: Axes, robot: PlanarChain, theta: np.ndarray, colour: str, width: float,
              label: str, gid: str, alpha: float = 1.0, zorder: float = 3,
              marker_size: float = 6.0) -> Line2D:
    """Draw the links of configuration theta (n,) [rad] as one line with a dot per joint."""
    points = robot.joint_positions(np.asarray(theta, dtype=float))
    (line,) = ax.plot(points[:, 0], points[:, 1], '-o', color=colour, lw=width, ms=marker_size,
                      alpha=alpha, zorder=zorder, gid=gid, label=label,
                      solid_capstyle='round')
    return line


def _tip_trace(robot: PlanarChain, path: np.ndarray) -> np.ndarray:
    """End-effector positions (m, 2) [m] along a joint path (k, n) [rad], densely sampled."""
    return robot.forward_kinematics(densify(path, _TRACE_STEP) if len(path) > 1 else path)


def _obstacle_patch(obstacle: Obstacle) -> Circle | Polygon | None:
    """Return the obstacle's section with the plane z = 0 [m] as a patch, None if it misses it.

    Spheres and upright cylinders give disks; boxes and tilted cylinders the convex
    polygon where the plane cuts them (a rectangle for a box turned only by its yaw).
    """
    cx, cy, cz = obstacle.center
    if obstacle.shape == 'sphere':
        if abs(cz) >= obstacle.radius:
            return None
        return Circle((cx, cy), float(np.sqrt(obstacle.radius ** 2 - cz ** 2)))
    if obstacle.shape == 'cylinder' and abs(rotation_from_rpy(obstacle.rpy)[2, 2]) > 1 - 1e-9:
        return Circle((cx, cy), obstacle.radius) if abs(cz) < 0.5 * obstacle.length else None
    section = _plane_section(_hull_points(obstacle), 0.0)
    return None if section is None else Polygon(section[:, :2], closed=True)


def _hull_points(obstacle: Obstacle) -> np.ndarray:
    """Points (P, 3) [m] whose convex hull is the box, or a prism inside the cylinder."""
    if obstacle.shape == 'box':
        signs = np.array(np.meshgrid([-1, 1], [-1, 1], [-1, 1], indexing='ij')).reshape(3, -1).T
        local = 0.5 * signs * np.asarray(obstacle.size)
    else:
        ring = np.linspace(0.0, 2.0 * np.pi, _RIM_POINTS, endpoint=False)
        rim = obstacle.radius * np.stack([np.cos(ring), np.sin(ring)], axis=1)
        local = np.vstack([np.column_stack([rim, np.full(len(ring), h)])
                           for h in (-0.5 * obstacle.length, 0.5 * obstacle.length)])
    return local @ rotation_from_rpy(obstacle.rpy).T + np.asarray(obstacle.center)


def _plane_section(points: np.ndarray, level: float) -> np.ndarray | None:
    """Cut the convex hull of points (P, 3) [m] with z = level: its corners (c, 3), or None."""
    z = points[:, 2] - level
    above, below = points[z > 0.0], points[z < 0.0]
    t = (above[:, None, 2] - level) / (above[:, None, 2] - below[None, :, 2])
    crossings = above[:, None, :] + t[..., None] * (below[None, :, :] - above[:, None, :])
    candidates = np.vstack([points[z == 0.0], crossings.reshape(-1, 3)])
    candidates[:, 2] = level
    if len(candidates) < 3:
        return None
    try:
        hull = ConvexHull(candidates[:, :2])
    except QhullError:  # the plane only touches the obstacle
        return None
    return candidates[hull.vertices]


def _screening_spheres(obstacle: Obstacle, link_radius: float,
                       ) -> tuple[Obstacle | None, Obstacle | None]:
    """Spheres (outer, inner) [m] that decide a box or cylinder quickly for a planar arm.

    The arm's capsules stay within `link_radius` of the plane z = 0, so only the part of
    the obstacle in that slab matters: the outer sphere holds that part (a capsule clear
    of it is clear of the obstacle), the inner one lies inside the obstacle (a capsule
    touching it collides). (None, None) when the obstacle misses the slab; inner is None
    when no ball fits.
    """
    points = _hull_points(obstacle)
    inside = points[np.abs(points[:, 2]) <= link_radius]
    sections = [_plane_section(points, level) for level in (-link_radius, 0.0, link_radius)]
    slab = np.vstack([inside] + [cut for cut in sections if cut is not None])
    if len(slab) == 0:
        return None, None
    centre = 0.5 * (slab.min(axis=0) + slab.max(axis=0))
    radius = float(np.max(np.linalg.norm(slab - centre, axis=1)))
    if obstacle.shape == 'cylinder':  # the prism lies inside the round cylinder
        radius += obstacle.radius * (1.0 - np.cos(np.pi / _RIM_POINTS))
    outer = Obstacle('sphere', tuple(centre), radius=1.001 * radius + 1e-9)
    if sections[1] is None:
        return outer, None
    core = sections[1].mean(axis=0)
    facets = ConvexHull(points).equations  # normal · x + offset <= 0 inside
    depth = float(np.min(-(facets[:, :3] @ core + facets[:, 3])))
    return outer, (Obstacle('sphere', tuple(core), radius=0.999 * depth) if depth > 0 else None)


# --- joint space -------------------------------------------------------------------------

def _draw_joint_space(ax: Axes, scene: Scene, result: PlanResult, grid_cells: int) -> None:
    robot = scene.robot
    if robot.n_joints < 3:
        raise ValueError(f'joint-space figures need 3 joints or more, the robot has '
                         f'{robot.n_joints}')
    if grid_cells < 0:
        raise ValueError(f'grid_cells must be >= 0, got {grid_cells}')
    periodic = robot.periodic[:3]
    lower, upper = np.degrees(robot.limits[:3]).T
    extra: list[Patch] = []
    if grid_cells and scene.obstacles:
        cells = np.degrees(_c_space_obstacle_cells(robot, scene.obstacles, grid_cells))
        ax.plot(*cells.T, '.', ms=1.5, color='0.45', alpha=0.12, gid='C_obs',
                label=f'C-space obstacles ({grid_cells}³ grid)')
    for gid, branches, colour, label in (
            ('M_s', result.start_manifolds, START_COLOUR, r'$\mathcal{M}_s$ ($\mathbf{x}_s$)'),
            ('M_g', result.goal_manifolds, GOAL_COLOUR, r'$\mathcal{M}_g$ ($\mathbf{x}_g$)')):
        for k, branch in enumerate(branches):
            points = branch.points[:, :3]
            if branch.closed:
                points = np.vstack([points, points[:1] + branch.period[:3]])
            ax.plot(*_wrapped_polyline(np.degrees(points), periodic).T, '--', color=colour,
                    lw=1.3, gid=gid, label=label if k == 0 else '_nolegend_')
    if result.theta_S is not None and len(result.theta_S):
        candidates = _wrap_degrees(np.degrees(result.theta_S[:, :3]), periodic)
        ax.plot(*candidates.T, '.', ms=3.0, color=START_COLOUR, alpha=0.6, gid='Theta_S',
                label=r'$\Theta_s$ candidates')
    surface = result.surface
    if result.feasible and surface is not None:
        paths = np.degrees(surface.paths[..., :3])
        triangles = paths.reshape(-1, 3)[surface.triangles]
        ax.add_collection3d(Poly3DCollection(triangles, facecolor=SURFACE_COLOUR, alpha=0.3,
                                             edgecolor='none', gid='S_F'))
        extra.append(Patch(facecolor=SURFACE_COLOUR, edgecolor=SURFACE_EDGE, alpha=0.6,
                           label=r'$\mathcal{S}_F$'))
        ax.plot(*_web_lines(paths).T, '-', color=SURFACE_EDGE, lw=0.5, alpha=0.5,
                gid='S_F:web', label='_nolegend_')
        boundary = np.vstack([paths[0], paths[1:, -1], paths[-1, ::-1]])
        ax.plot(*boundary.T, '-', color=SURFACE_EDGE, lw=1.6, gid='S_F:boundary',
                label='_nolegend_')
        ax.plot(*paths[surface.nominal].T, '-', color='k', lw=2.6, gid='nominal',
                label='nominal path')
        for i, path in enumerate(surface.hit_paths):
            ax.plot(*paths[path].T, '-', color=_hit_colour(i), lw=1.8, gid=f'H{i + 1}:path',
                    label='_nolegend_')
            ax.plot(*paths[path, -1:].T, 'o', ms=8, color=_hit_colour(i), mec='k',
                    gid=f'hit:H{i + 1}', label=f'H{i + 1} hit')
        ax.plot(*paths[0, :1].T, '*', ms=18, color='k', mec='white', gid='theta_s',
                label=r'$\theta_s$')
        lower = np.minimum(lower, paths.min(axis=(0, 1)))
        upper = np.maximum(upper, paths.max(axis=(0, 1)))
        title = (r'Joint space: $\mathcal{M}_s$, $\mathcal{M}_g$ dashed;'
                 '\n' + rf'$\theta_s$ = {_degrees(surface.theta_s)} and $\mathcal{{S}}_F$')
    else:
        title = (r'Joint space: $\mathcal{M}_s$, $\mathcal{M}_g$ dashed;' '\n'
                 r'no failure surface $\mathcal{S}_F$')
    for j, axis in enumerate((ax.xaxis, ax.yaxis, ax.zaxis)):
        axis.set_label_text(rf'$\theta_{j + 1}$ ({robot.joint_names[j]}) [deg]')
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
        outer, inner = _screening_spheres(obstacle, robot.link_radius)
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


# --- text --------------------------------------------------------------------------------

def _hit_colour(joint: int) -> str:
    return HIT_COLOURS[joint % len(HIT_COLOURS)]


def _degrees(theta: np.ndarray) -> str:
    """Format a configuration (n,) [rad] in degrees, e.g. '[-75.4°, 101.4°, 6.0°]'."""
    return '[' + ', '.join(f'{value:.1f}°' for value in np.degrees(theta)) + ']'


def _reason_title(result: PlanResult) -> str:
    reason = result.reason or 'no reason given'
    return textwrap.fill(f'No failure-tolerant plan: {reason}', width=60)
