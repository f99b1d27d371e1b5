"""Spatial arms in 3-D (mplot3d): the arm at θ_s and at its failure-plane hits, and motions.

The arm is drawn as its skeleton (`robot.skeleton`: base, joint origins, tool point)
with a dot at each point; obstacles as translucent surfaces (a box's six faces, a
cylinder's side and caps, a sphere's quads) posed by their rpy and clipped to the view;
x_s and x_g with a dotted drop line to the floor and the task's orientation: short x, y,
z arrows (red, green, blue) for a pose, a black arrow along the tool axis for an axis
task. Every axis has the same scale (metres), seen in orthographic projection; angles
arrive in radians. The view box fits what is drawn, obstacles within the arm's reach.
"""

from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure, SubFigure
from matplotlib.patches import Patch
from mpl_toolkits.mplot3d import Axes3D
from mpl_toolkits.mplot3d.art3d import Poly3DCollection
from scipy.spatial.transform import Rotation

from ..core.model.geometry import rotation_from_rpy
from ..core.model.paths import densify, point_at_fraction
from ..core.model.robot import Robot
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

AXIS_COLOURS = ('#e41a1c', '#4daf4a', '#377eb8')  # a frame's x, y, z axes
_ROUND = 32          # segments around a cylinder or a sphere
_TITLE_WIDTH = 84    # characters per title line
_ELEVATION = 22.0    # [deg] of the camera above the xy plane


def add_axes(figure: Figure | SubFigure) -> Axes3D:
    """Add 3-D axes filling `figure` that draw their artists in the order of their zorder.

    The arm and the markers are drawn over the translucent obstacles whatever the view:
    mplot3d's depth sorting of whole artists misplaces long lines among faces.
    """
    return figure.add_subplot(projection='3d', computed_zorder=False, proj_type='ortho')


def draw_workspace(ax: Axes3D, scene: Scene, result: PlanResult, legend_below: bool = False,
                   ) -> None:
    """Draw the arm at θ_s and at each failure-plane hit among the obstacles (see figures).

    The legend goes to the right of the axes, or below them with `legend_below`.
    """
    robot = scene.robot
    surface = result.surface
    feasible = result.feasible and surface is not None
    drawn = _task_points(scene)
    if feasible:
        hits = surface.goal_points[list(surface.hit_paths)]
        trace = _tool_trace(robot, surface.nominal_path)
        drawn += [robot.skeleton(surface.theta_s), *robot.skeleton(hits), trace]
    lower, upper = _view_box(robot, drawn, scene.obstacles)
    _draw_obstacles(ax, scene.obstacles, lower, upper)
    _draw_base(ax, robot)
    if feasible:
        for i, hit in zip(surface.tolerated, hits, strict=True):
            draw_arm(ax, robot.skeleton(hit), hit_colour(i), width=1.3, alpha=0.85, zorder=3,
                     label=f'H{i + 1} hit ({robot.joint_names[i]} locked)',
                     gid=f'arm:H{i + 1}', marker_size=3.0)
        ax.plot(*trace.T, '--', color='k', lw=1.4, zorder=4, gid='trace',
                label='nominal path (tool)')
        draw_arm(ax, robot.skeleton(surface.theta_s), 'k', width=3.2, zorder=5,
                 label=r'$\theta_s$', gid='arm:theta_s', marker_size=5.5)
        title = '\n'.join([scene.name, rf'$\theta_s$ = {degrees_text(surface.theta_s)}',
                           _wrap(_tolerated_text(robot, surface.tolerated))])
    else:
        title = reason_title(result, width=_TITLE_WIDTH)
    _draw_task(ax, scene, lower, upper)
    _finish(ax, robot, lower, upper, title, drawn, legend_below)


def draw_motion(ax: Axes3D, scene: Scene, motion: np.ndarray, failure_index: int | None,
                locked_joint: int | None, title: str) -> None:
    """Draw a checked joint motion (k, n) [rad] in 3-D (see `figures.motion_figure`)."""
    robot = scene.robot
    fractions = np.linspace(0.0, 1.0, SNAPSHOTS) if len(motion) > 1 else [0.0]
    snapshots = np.array([point_at_fraction(motion, f) if len(motion) > 1 else motion[0]
                          for f in fractions])
    split = len(motion) - 1 if failure_index is None else failure_index
    before = _tool_trace(robot, motion[:split + 1])
    after = _tool_trace(robot, motion[split:]) if split < len(motion) - 1 else None
    drawn = _task_points(scene) + [*robot.skeleton(snapshots), robot.skeleton(motion[-1]),
                                   before] + ([] if after is None else [after])
    lower, upper = _view_box(robot, drawn, scene.obstacles)
    _draw_obstacles(ax, scene.obstacles, lower, upper)
    _draw_base(ax, robot)
    for k, theta in enumerate(snapshots):
        draw_arm(ax, robot.skeleton(theta), '0.3', width=1.2,
                 alpha=0.12 + 0.3 * k / len(snapshots), zorder=2,
                 label='arm along the motion' if k == 0 else '_nolegend_', gid='snapshot',
                 marker_size=2.5)
    ax.plot(*before.T, '--' if failure_index is not None else '-', color='k', lw=1.3,
            zorder=4, gid='trace', label='tool' + (
                ' before the failure' if failure_index is not None else ''))
    if failure_index is not None and after is not None:
        ax.plot(*after.T, '-', color=FAILURE_COLOUR, lw=1.6, zorder=4, gid='trace:recovery',
                label='tool after the failure')
    if failure_index is not None:
        failed = motion[failure_index]
        draw_arm(ax, robot.skeleton(failed), FAILURE_COLOUR, width=3.0, zorder=5,
                 label='at the failure', gid='arm:failure', marker_size=5.0)
        if locked_joint is not None:
            where = _joint_points(robot, failed)[locked_joint]
            ax.plot(*where[:, None], 'o', ms=17, mfc='none', mec=FAILURE_COLOUR, mew=2.5,
                    zorder=6, gid='locked_joint',
                    label=f'{robot.joint_names[locked_joint]} locked at '
                          f'{np.degrees(failed[locked_joint]):.1f}°')
    draw_arm(ax, robot.skeleton(motion[-1]), FINAL_COLOUR, width=3.0, zorder=5, label='final',
             gid='arm:final', marker_size=5.0)
    _draw_task(ax, scene, lower, upper)
    _finish(ax, robot, lower, upper, _wrap(title), drawn)


def _joint_points(robot: Robot, theta: np.ndarray) -> np.ndarray:
    """Return the origins (n, 3) [m] of the joints at configuration theta (n,) [rad].

    They are the n skeleton points before the tool point (a planar chain's skeleton
    starts at joint 1, a spatial arm's at its base link).
    """
    skeleton = robot.skeleton(np.asarray(theta, dtype=float))
    return skeleton[len(skeleton) - 1 - robot.n_joints:-1]


# --- the arm and the task --------------------------------------------------------------------

def _draw_base(ax: Axes3D, robot: Robot) -> None:
    """Mark the robot's base frame origin [m] with a black square."""
    base = robot.skeleton(np.zeros(robot.n_joints))[0]
    ax.plot(*base[:, None], 's', ms=9, color='k', zorder=6, gid='base', label='_nolegend_')


def _tool_trace(robot: Robot, path: np.ndarray) -> np.ndarray:
    """Tool positions (m, 3) [m] along a joint path (k, n) [rad], densely sampled."""
    dense = densify(path, TRACE_STEP) if len(path) > 1 else path
    return robot.skeleton(dense)[:, -1]


def _task_points(scene: Scene) -> list[np.ndarray]:
    if scene.task is None:
        return []
    return [np.array([scene.task.start[:3], scene.task.goal[:3]], dtype=float)]


def _draw_task(ax: Axes3D, scene: Scene, lower: np.ndarray, upper: np.ndarray) -> None:
    """Mark x_s and x_g [m] with their orientation (pose) or tool axis (axis task)."""
    task = scene.task
    if task is None:
        return
    length = 0.09 * float(np.max(upper - lower))  # [m] of a drawn frame axis
    for gid, x, style in (
            ('x_s', task.start, {'marker': 'o', 'ms': 9, 'mfc': 'white', 'mec': 'k',
                                 'mew': 1.8, 'label': r'$\mathbf{x}_s$'}),
            ('x_g', task.goal, {'marker': '*', 'ms': 15, 'mfc': GOAL_COLOUR, 'mec': 'k',
                                'mew': 1.0, 'label': r'$\mathbf{x}_g$'})):
        position = np.asarray(x[:3], dtype=float)
        ax.plot(*position[:, None], ls='none', zorder=7, gid=gid, **style)
        ax.plot(*np.stack([position, [*position[:2], lower[2]]]).T, ':', color='0.4', lw=1.0,
                zorder=2, gid=f'{gid}:drop', label='_nolegend_')  # where it is over the floor
        if task.kind == 'pose':
            axes = Rotation.from_quat(x[3:7]).as_matrix().T  # rows: the frame's x, y, z
            ax.quiver(*np.tile(position, (3, 1)).T, *axes.T, length=length,
                      arrow_length_ratio=0.3, colors=AXIS_COLOURS, lw=2.0, zorder=6,
                      gid=f'{gid}:frame')
        elif task.kind == 'axis':
            ax.quiver(*position, *np.asarray(x[3:6], dtype=float), length=1.5 * length,
                      arrow_length_ratio=0.25, colors='k', lw=2.0, zorder=6,
                      gid=f'{gid}:axis')


def _finish(ax: Axes3D, robot: Robot, lower: np.ndarray, upper: np.ndarray, title: str,
            drawn: list[np.ndarray], legend_below: bool = False) -> None:
    """Set the view box with equal scale, a camera beside what is drawn, labels and legend."""
    ax.set_xlim(lower[0], upper[0])
    ax.set_ylim(lower[1], upper[1])
    ax.set_zlim(lower[2], upper[2])
    ax.set_box_aspect(upper - lower)
    ax.view_init(elev=_ELEVATION, azim=_azimuth(robot, drawn))
    ax.set_xlabel('x [m]')
    ax.set_ylabel('y [m]')
    ax.set_zlabel('z [m]')
    ax.tick_params(labelsize='small')
    ax.set_title(title)
    handles, _ = ax.get_legend_handles_labels()
    if any(artist.get_gid() == 'obstacle' for artist in ax.collections):
        handles.insert(0, Patch(facecolor=OBSTACLE_FACE, edgecolor=OBSTACLE_EDGE, alpha=0.5,
                                label='obstacles'))
    if legend_below:
        ax.legend(handles=handles, loc='upper center', bbox_to_anchor=(0.5, 0.0), ncols=3,
                  fontsize='small')
    else:
        ax.legend(handles=handles, loc='upper left', bbox_to_anchor=(1.02, 1.0),
                  fontsize='small')


def _azimuth(robot: Robot, drawn: list[np.ndarray]) -> float:
    """Return the camera azimuth [deg] under which the drawn points (..., 3) [m] spread most.

    Candidates every 5° are scored by the area of the points' spread on the screen (the
    determinant of their projected covariance) at the camera's elevation, slightly
    favouring matplotlib's default: 60° clockwise of the direction the arm reaches in
    from its base, a view from the front and the side.
    """
    base = robot.skeleton(np.zeros(robot.n_joints))[0]
    points = np.vstack([base[None]] + [np.reshape(p, (-1, 3)) for p in drawn])
    reach = points.mean(axis=0) - base
    preferred = np.arctan2(reach[1], reach[0]) - np.radians(60.0)
    azimuth = np.radians(np.arange(-180.0, 180.0, 5.0))
    elevation = np.radians(_ELEVATION)
    across = np.stack([-np.sin(azimuth), np.cos(azimuth), np.zeros_like(azimuth)], axis=1)
    up = np.stack([-np.sin(elevation) * np.cos(azimuth), -np.sin(elevation) * np.sin(azimuth),
                   np.full_like(azimuth, np.cos(elevation))], axis=1)
    centred = points - points.mean(axis=0)
    u, v = centred @ across.T, centred @ up.T  # (P, A) screen coordinates
    area = np.mean(u * u, axis=0) * np.mean(v * v, axis=0) - np.mean(u * v, axis=0) ** 2
    if area.max() <= 1e-12:  # a point or a vertical line: any view will do
        return float(np.degrees(preferred))
    score = area * (1.0 + 0.15 * np.cos(azimuth - preferred))
    return float(np.degrees(azimuth[np.argmax(score)]))


def _tolerated_text(robot: Robot, tolerated: tuple[int, ...]) -> str:
    """Say whose lock the plan survives, naming the shorter of the two lists of joints."""
    names = robot.joint_names
    others = [names[j] for j in range(robot.n_joints) if j not in tolerated]
    if not others:
        return 'tolerates a lock of any joint'
    if len(others) <= len(tolerated):
        return 'tolerates a lock of any joint but ' + ', '.join(others)
    return 'tolerates a lock of ' + ', '.join(names[j] for j in tolerated)


def _wrap(text: str) -> str:
    """Wrap each line of a title to `_TITLE_WIDTH` characters."""
    return '\n'.join(textwrap.fill(line, width=_TITLE_WIDTH) for line in text.splitlines())


# --- the view box and the obstacles ------------------------------------------------------------

def _view_box(robot: Robot, drawn: list[np.ndarray], obstacles: tuple[Obstacle, ...],
              ) -> tuple[np.ndarray, np.ndarray]:
    """Return the corners (3,), (3,) [m] of a box around what is drawn, with equal-ish sides.

    It holds the base, the points (..., 3) in `drawn` and the obstacles' parts within
    the arm's reach (the cube around joint 1 that the tool's lever arm spans); it is
    padded, and no side is shorter than half the longest (nor than 15 % of the reach),
    so a flat scene still shows depth.
    """
    base = robot.skeleton(np.zeros(robot.n_joints))[0]
    shoulder = _joint_points(robot, np.zeros(robot.n_joints))[0]  # joint 1 (fixed)
    reach = float(robot.tip_lever_arms()[0])  # of the tool from joint 1's axis
    points = [base[None]] + [np.asarray(p, dtype=float).reshape(-1, 3) for p in drawn]
    lower, upper = np.vstack(points).min(axis=0), np.vstack(points).max(axis=0)
    for obstacle in obstacles:
        faces = np.vstack(_obstacle_faces(obstacle))
        low = np.maximum(faces.min(axis=0), shoulder - reach)
        high = np.minimum(faces.max(axis=0), shoulder + reach)
        if np.all(low <= high):
            lower, upper = np.minimum(lower, low), np.maximum(upper, high)
    pad = max(0.05 * float(np.max(upper - lower)), 0.03)
    lower, upper = lower - pad, upper + pad
    longest = max(float(np.max(upper - lower)), 0.3 * reach)
    side = np.maximum(upper - lower, 0.5 * longest)
    centre = 0.5 * (lower + upper)
    return centre - 0.5 * side, centre + 0.5 * side


def _draw_obstacles(ax: Axes3D, obstacles: tuple[Obstacle, ...], lower: np.ndarray,
                    upper: np.ndarray) -> None:
    """Draw each obstacle as one translucent Poly3DCollection (gid 'obstacle'), clipped."""
    for obstacle in obstacles:
        faces = [_clip_polygon(face, lower, upper) for face in _obstacle_faces(obstacle)]
        faces = [face for face in faces if len(face) >= 3]
        if not faces:
            continue  # out of view
        # Polygons of one size: mplot3d pads ragged ones with uninitialised memory, which
        # its projection then multiplies (overflow warnings). A repeated corner is harmless.
        size = max(len(face) for face in faces)
        faces = np.array([np.vstack([face, np.repeat(face[-1:], size - len(face), axis=0)])
                          for face in faces])
        colours = _shaded(list(faces), OBSTACLE_FACE)
        boxy = obstacle.shape == 'box'  # a round shape's quads have no edges to show
        ax.add_collection3d(Poly3DCollection(
            faces, facecolors=colours, edgecolors=OBSTACLE_EDGE if boxy else colours,
            linewidths=0.6 if boxy else 0.0, gid='obstacle', zorder=1))


def _shaded(faces: list[np.ndarray], colour: str, alpha: float = 0.4) -> np.ndarray:
    """Return RGBA colours (F, 4) of `colour` lit by a light above the front left.

    A face's brightness follows the angle between its normal (Newell's, either side) and
    the light, so the faces of a box or the quads of a round shape read as a solid.
    """
    light = np.array([-0.4, -0.5, 1.0]) / np.linalg.norm([-0.4, -0.5, 1.0])
    normals = np.array([np.cross(face, np.roll(face, -1, axis=0)).sum(axis=0) for face in faces])
    lengths = np.linalg.norm(normals, axis=1)
    cosine = np.abs(normals @ light) / np.where(lengths > 0.0, lengths, 1.0)
    rgba = np.tile(to_rgba(colour, alpha), (len(faces), 1))
    rgba[:, :3] *= (0.55 + 0.45 * cosine)[:, None]
    return rgba


def _obstacle_faces(obstacle: Obstacle) -> list[np.ndarray]:
    """Return the obstacle's surface as planar polygons (k_i, 3) [m] in the base frame."""
    if obstacle.shape == 'box':
        signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        corners = 0.5 * signs * np.asarray(obstacle.size)
        quads = ((0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4),
                 (1, 5, 7, 3))
        local = [corners[list(quad)] for quad in quads]
    elif obstacle.shape == 'cylinder':
        angle = np.linspace(0.0, 2.0 * np.pi, _ROUND, endpoint=False)
        rim = obstacle.radius * np.column_stack([np.cos(angle), np.sin(angle)])
        half = 0.5 * obstacle.length
        bottom = np.column_stack([rim, np.full(_ROUND, -half)])
        top = np.column_stack([rim, np.full(_ROUND, half)])
        nxt = np.roll(np.arange(_ROUND), -1)
        local = [np.array([bottom[k], bottom[m], top[m], top[k]]) for k, m in
                 zip(range(_ROUND), nxt, strict=True)] + [bottom, top[::-1]]
    else:
        longitude = np.linspace(0.0, 2.0 * np.pi, _ROUND + 1)
        latitude = np.linspace(-0.5 * np.pi, 0.5 * np.pi, _ROUND // 2 + 1)
        lon, lat = np.meshgrid(longitude, latitude, indexing='ij')
        grid = obstacle.radius * np.stack([np.cos(lat) * np.cos(lon),
                                           np.cos(lat) * np.sin(lon), np.sin(lat)], axis=-1)
        local = [np.array([grid[a, b], grid[a + 1, b], grid[a + 1, b + 1], grid[a, b + 1]])
                 for a in range(len(longitude) - 1) for b in range(len(latitude) - 1)]
    rotation = rotation_from_rpy(obstacle.rpy)
    centre = np.asarray(obstacle.center, dtype=float)
    return [face @ rotation.T + centre for face in local]


def _clip_polygon(polygon: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Clip a planar convex polygon (k, 3) [m] to the box [lower, upper] (Sutherland-Hodgman)."""
    for axis in range(3):
        for bound, sign in ((lower[axis], 1.0), (upper[axis], -1.0)):
            if len(polygon) == 0:
                return polygon
            inside = sign * (polygon[:, axis] - bound) >= 0.0
            if inside.all():
                continue
            kept = []
            for k in range(len(polygon)):
                a, b = polygon[k], polygon[(k + 1) % len(polygon)]
                a_in, b_in = inside[k], inside[(k + 1) % len(polygon)]
                if a_in:
                    kept.append(a)
                if a_in != b_in:
                    t = (bound - a[axis]) / (b[axis] - a[axis])
                    kept.append(a + t * (b - a))
            polygon = np.array(kept).reshape(-1, 3)
    return polygon
