"""The planar arm in its plane (the paper's Fig. 3) and its executed motions, in metres.

The obstacles are drawn as their sections with the arm's plane z = 0; the arm as its
links and joints (`PlanarChain.joint_positions`). Angles arrive in radians.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle, Polygon
from scipy.spatial import ConvexHull, QhullError

from ..core.collision.checker import rotation_from_rpy
from ..core.model.paths import densify, point_at_fraction
from ..core.model.robot import PlanarChain
from ..core.model.scene import Obstacle, Scene
from ..core.paper.result import PlanResult
from .style import (
    FAILURE_COLOUR,
    FINAL_COLOUR,
    GOAL_COLOUR,
    OBSTACLE_EDGE,
    OBSTACLE_FACE,
    SNAPSHOTS,
    TRACE_STEP,
    degrees_text,
    draw_arm,
    hit_colour,
    reason_title,
)

_RIM_POINTS = 48     # points on each rim of a cylinder when its section is a polygon


def draw_workspace(ax: Axes, scene: Scene, result: PlanResult) -> None:
    """Draw the plane of the arm at θ_s (see `figures.workspace_figure`), axes in metres."""
    robot = scene.robot
    draw_scenery(ax, scene)
    surface = result.surface
    if result.feasible and surface is not None:
        hits = surface.goal_points[list(surface.hit_paths)]
        for i, hit in enumerate(hits):
            draw_arm(ax, robot.joint_positions(hit), hit_colour(i), width=1.6, alpha=0.8,
                     label=f'H{i + 1} hit', gid=f'arm:H{i + 1}', marker_size=4.0)
        ax.plot(*_tip_trace(robot, surface.nominal_path).T, '--', color='k', lw=1.3,
                gid='trace', label='nominal path (end effector)')
        draw_arm(ax, robot.joint_positions(surface.theta_s), 'k', width=3.5,
                 label=r'$\theta_s$', gid='arm:theta_s', zorder=5)
        title = rf'{scene.name}: $\theta_s$ = {degrees_text(surface.theta_s)}'
    else:
        title = reason_title(result)
    draw_task(ax, scene)
    _finish_workspace(ax, robot, title)


def draw_scenery(ax: Axes, scene: Scene) -> None:
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


def draw_task(ax: Axes, scene: Scene) -> None:
    """Mark x_s and x_g [m], if the scene has a task."""
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
    draw_reach(ax, float(np.sum(robot.link_lengths)), '0.6', '_nolegend_')
    ax.set_aspect('equal', adjustable='box')
    ax.set_xlabel('x [m]')
    ax.set_ylabel('y [m]')
    ax.grid(alpha=0.3)
    ax.set_title(title)
    ax.legend(loc='upper left', bbox_to_anchor=(1.02, 1.0), fontsize='small')


def draw_reach(ax: Axes, reach: float, colour: str, label: str) -> None:
    """Draw the circle of radius `reach` [m] about the base, dotted: as far as the arm reaches."""
    ring = np.linspace(0.0, 2.0 * np.pi, 241)
    ax.plot(reach * np.cos(ring), reach * np.sin(ring), ':', color=colour, lw=0.9, gid='reach',
            label=label)


def _tip_trace(robot: PlanarChain, path: np.ndarray) -> np.ndarray:
    """End-effector positions (m, 2) [m] along a joint path (k, n) [rad], densely sampled."""
    return robot.forward_kinematics(densify(path, TRACE_STEP) if len(path) > 1 else path)


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


def screening_spheres(obstacle: Obstacle, link_radius: float,
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


def draw_motion(ax: Axes, scene: Scene, motion: np.ndarray, failure_index: int | None,
                locked_joint: int | None, title: str) -> None:
    """Draw a checked joint motion (k, n) [rad] in the plane (see `figures.motion_figure`)."""
    robot = scene.robot
    draw_scenery(ax, scene)
    fractions = np.linspace(0.0, 1.0, SNAPSHOTS) if len(motion) > 1 else [0.0]
    for k, fraction in enumerate(fractions):
        theta = point_at_fraction(motion, fraction) if len(motion) > 1 else motion[0]
        draw_arm(ax, robot.joint_positions(theta), '0.3', width=1.4,
                 alpha=0.12 + 0.3 * k / len(fractions),
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
        draw_arm(ax, robot.joint_positions(failed), FAILURE_COLOUR, width=3.0,
                 label='at the failure', gid='arm:failure', zorder=5)
        if locked_joint is not None:
            where = robot.joint_positions(failed)[locked_joint]
            ax.plot(*where, 'o', ms=19, mfc='none', mec=FAILURE_COLOUR, mew=2.5, zorder=6,
                    gid='locked_joint', label=f'{robot.joint_names[locked_joint]} locked at '
                    f'{np.degrees(failed[locked_joint]):.1f}°')
    draw_arm(ax, robot.joint_positions(motion[-1]), FINAL_COLOUR, width=3.0, label='final',
             gid='arm:final', zorder=5)
    draw_task(ax, scene)
    _finish_workspace(ax, robot, title)
