"""Every joint against progress along the nominal path: joint space for any number of joints.

One panel per joint (n rows) over a shared x axis, the fraction 0..1 of the nominal
path's joint-space length; angles in degrees. Each panel shows, for its joint j:

- the failure hypercube V_sg as a band [lower_j, upper_j] (the box spanned by θ_s and
  the goal points of S_F);
- the spread of the failure surface S_F: its paths run straight from θ_s to the goal
  points, so at waypoint w they span the smallest to the largest θ_j of the web;
- the nominal path θ_j(progress), and thin, in the colour of joint i, the path to the
  failure-plane hit θ_{H_i} (flat in panel i: joint i keeps its θ_s value on it);
- at progress 0: θ_s and the free arc of M_s through it as a strip (the values θ_j takes
  while the tool stays at x_s, without collision);
- at progress 1: M_g^F as the strip the goal points of S_F cover, and the hits θ_{H_i}
  of the tolerated joints, one colour per joint;
- the joint limits as dashed lines, where they come into view.

Angles are the plan's continuous ones (as in S_F), which may leave (-180, 180] on joints
that wrap. An infeasible result has no path to draw along: its panels show the branches of M_s at
0 and of M_g at 1 as ticks, the Θ_s candidates at 0 and the limits.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure, SubFigure
from matplotlib.ticker import MaxNLocator

from ..core.model.angles import configuration_difference, wrap_configuration
from ..core.model.paths import cumulative_fractions
from ..core.model.robot import Robot
from ..core.model.scene import Scene
from ..core.paper.result import PlanResult
from .style import (
    GOAL_COLOUR,
    HYPERCUBE_COLOUR,
    START_COLOUR,
    SURFACE_COLOUR,
    hit_colour,
)

_STRIP_WIDTH = 7.0   # [points] of the M_s and M_g^F strips
_X_MARGIN = 0.05     # room beside progress 0 and 1 for the strips and markers


def draw_joint_panels(figure: Figure | SubFigure, scene: Scene, result: PlanResult,
                      ) -> list[Axes]:
    """Fill `figure` with one panel per joint and return them, the first joint's on top.

    See the module docstring for what each panel holds; y axes in degrees, x the fraction
    of the nominal path's length. The legend goes to the right of the panels, in the
    figure (or subfigure) so that it takes no height from any of them.
    """
    robot = scene.robot
    axes = list(figure.subplots(robot.n_joints, 1, sharex=True, squeeze=False)[:, 0])
    if result.feasible and result.surface is not None:
        tolerated = set(result.tolerated_joints)
        _draw_plan(axes, robot, result)
        title = 'Joint space along the nominal path'
    else:
        tolerated = set(scene.tolerated_joints)
        _draw_manifolds(axes, robot, result)
        title = r'Joint space: no failure surface $\mathcal{S}_F$'
    frozen = set(result.stats.get('curve', {}).get('frozen_joints', ()))
    for j, ax in enumerate(axes):
        name = robot.joint_names[j]
        notes = ([] if j in tolerated else ['not tolerated']) + (
            ['frozen on the chosen curve'] if name in frozen else [])
        _draw_limits(ax, robot, j)
        _finish_panel(ax, name + (f' ({", ".join(notes)})' if notes else ''), j)
    if result.feasible and result.surface is not None:
        axes[-1].set_xlabel('progress along the nominal path (fraction of its joint-space '
                            'length)')
    else:  # no path: only its ends
        axes[-1].set_xticks([0.0, 1.0], [r'$\mathbf{x}_s$', r'$\mathbf{x}_g$'])
        axes[-1].set_xlabel('no nominal path: the self-motion manifolds of its ends')
    axes[0].set_title(title)
    handles, labels = axes[0].get_legend_handles_labels()
    figure.legend(handles, labels, loc='outside right upper', fontsize='small')
    return axes


def _draw_plan(axes: list[Axes], robot: Robot, result: PlanResult) -> None:
    """Draw V_sg, S_F, the nominal and hit paths, θ_s, M_s, M_g^F and the hits [deg]."""
    surface = result.surface
    progress = cumulative_fractions(surface.nominal_path)
    paths = np.degrees(surface.paths)
    spread = paths.min(axis=0), paths.max(axis=0)
    lower, upper = np.degrees(result.hypercube)
    start_arc = _start_arc(result)
    goal = np.degrees(surface.goal_points)
    theta_s = np.degrees(surface.theta_s)
    for j, ax in enumerate(axes):
        first = j == 0
        ax.axhspan(lower[j], upper[j], color=HYPERCUBE_COLOUR, alpha=0.6, lw=0, zorder=0,
                   gid='hypercube', label=_label(first, r'failure hypercube $V_{sg}$'))
        ax.fill_between(progress, spread[0][:, j], spread[1][:, j], color=SURFACE_COLOUR,
                        alpha=0.45, lw=0, zorder=1, gid='S_F',
                        label=_label(first, r'$\mathcal{S}_F$ (spread of its paths)'))
        for k, i in enumerate(surface.tolerated):
            ax.plot(progress, paths[surface.hit_paths[k], :, j], '-', color=hit_colour(i),
                    lw=0.9, alpha=0.75, zorder=2, gid=f'H{i + 1}:path', label='_nolegend_')
        ax.plot(progress, paths[surface.nominal, :, j], '-', color='k', lw=1.8, zorder=3,
                gid='nominal', label=_label(first, 'nominal path'))
        if start_arc is not None:
            _strip(ax, 0.0, np.degrees(start_arc[:, j]), START_COLOUR, 'M_s',
                   _label(first, r'free arc of $\mathcal{M}_s$ through $\theta_s$'))
        _strip(ax, 1.0, goal[:, j], GOAL_COLOUR, 'M_g^F',
               _label(first, r'$\mathcal{M}_g^F$ (goal points of $\mathcal{S}_F$)'))
        ax.plot(0.0, theta_s[j], '*', ms=11, color='k', mec='white', mew=0.6, zorder=6,
                gid='theta_s', label=_label(first, r'$\theta_s$'))
        for k, i in enumerate(surface.tolerated):
            ax.plot(1.0, goal[surface.hit_paths[k], j], 'o', ms=5.5, color=hit_colour(i),
                    mec='k', mew=0.5, zorder=6, gid=f'hit:H{i + 1}',
                    label=_label(first, f'H{i + 1} hit ({robot.joint_names[i]} locked)'))
        pad = max(0.15 * (upper[j] - lower[j]), 4.0)
        ax.set_ylim(lower[j] - pad, upper[j] + pad)


def _draw_manifolds(axes: list[Axes], robot: Robot, result: PlanResult) -> None:
    """Draw the branches of M_s (at 0) and M_g (at 1) as ticks, and the Θ_s candidates [deg]."""
    periodic = robot.periodic
    drawn = [np.degrees(robot.limits).T]  # (2, n): lower and upper
    for x, gid, branches, colour, label in (
            (0.0, 'M_s', result.start_manifolds, START_COLOUR, r'$\mathcal{M}_s$ ($\mathbf{x}_s$)'),
            (1.0, 'M_g', result.goal_manifolds, GOAL_COLOUR, r'$\mathcal{M}_g$ ($\mathbf{x}_g$)')):
        for k, branch in enumerate(branches):
            points = np.degrees(wrap_configuration(branch.points, periodic))
            drawn.append(points)
            for j, ax in enumerate(axes):
                ax.plot(np.full(len(points), x), points[:, j], '_', ms=_STRIP_WIDTH * 1.6,
                        color=colour, alpha=0.5, zorder=2, gid=gid,
                        label=_label(j == 0 and k == 0, label))
    if result.necessary_starts is not None and len(result.necessary_starts):
        candidates = np.degrees(wrap_configuration(result.necessary_starts, periodic))
        for j, ax in enumerate(axes):
            ax.plot(np.zeros(len(candidates)), candidates[:, j], '.', ms=4, color='k',
                    zorder=3, gid='Theta_S', label=_label(j == 0, r'$\Theta_s$ candidates'))
    values = np.vstack([points.reshape(-1, robot.n_joints) for points in drawn])
    for j, ax in enumerate(axes):
        low, high = values[:, j].min(), values[:, j].max()
        pad = max(0.08 * (high - low), 4.0)
        ax.set_ylim(low - pad, high + pad)


def _start_arc(result: PlanResult) -> np.ndarray | None:
    """Return the free arc (a, n) [rad] of the branch of M_s nearest θ_s, lifted onto θ_s.

    The arc is the run of collision-free branch points (Step 2's M_s^F) that holds the
    point nearest θ_s; periodic joints are shifted by whole turns so that this point
    lies next to θ_s. None when the result has no start branch.
    """
    theta_s = result.theta_s
    periodic = (np.zeros(len(theta_s), dtype=bool) if result.periodic is None
                else np.asarray(result.periodic))
    best = None
    for branch in result.start_manifolds:
        distance = np.linalg.norm(configuration_difference(branch.points, theta_s, periodic),
                                  axis=1)
        k = int(np.argmin(distance))
        if best is None or distance[k] < best[0]:
            best = (distance[k], branch, k)
    if best is None:
        return None
    _, branch, k = best
    size = len(branch.points)
    if branch.clearance is None:  # not screened: the whole branch
        arcs = [(0, size)]
    elif branch.free()[k]:
        arcs = branch.free_arcs()
    else:
        arcs = [(k, 1)]
    for first, count in arcs:
        index = first + np.arange(count)
        if k in index % size:
            arc = branch.points[index % size] + (index // size)[:, None] * branch.period
            near = arc[int(np.flatnonzero(index % size == k)[0])]
            turns = theta_s - near - configuration_difference(theta_s, near, periodic)
            return arc + turns
    return None


def _strip(ax: Axes, x: float, values: np.ndarray, colour: str, gid: str, label: str) -> None:
    """Draw the range of `values` [deg] as a thick vertical bar at progress x.

    Its ends are ticks as wide as the bar, so that a range of a single value still shows.
    """
    ax.plot([x, x], [values.min(), values.max()], '_-', color=colour, lw=_STRIP_WIDTH,
            ms=_STRIP_WIDTH * 1.5, mew=2.0, alpha=0.6, solid_capstyle='butt', zorder=4,
            gid=gid, label=label)


def _draw_limits(ax: Axes, robot: Robot, j: int) -> None:
    """Draw joint j's limits [deg] as dashed lines, unless it wraps."""
    if robot.periodic[j]:
        return
    for k, limit in enumerate(np.degrees(robot.limits[j])):
        ax.axhline(limit, ls='--', color='0.35', lw=1.0, zorder=1, gid='limit',
                   label=_label(j == 0 and k == 0, 'joint limits'))


def _finish_panel(ax: Axes, name: str, j: int) -> None:
    """Name joint j's panel, label its y axis (degrees) and set the x range."""
    ax.text(0.5, 0.94, name, transform=ax.transAxes, va='top', ha='center', fontsize='small',
            zorder=7, bbox={'facecolor': 'white', 'edgecolor': 'none', 'alpha': 0.75,
                            'pad': 1.0})
    ax.set_ylabel(rf'$\theta_{{{j + 1}}}$ [deg]')
    ax.yaxis.set_major_locator(MaxNLocator(nbins=4))
    ax.set_xlim(-_X_MARGIN, 1.0 + _X_MARGIN)
    ax.set_xticks(np.linspace(0.0, 1.0, 5))
    ax.grid(alpha=0.3)


def _label(show: bool, text: str) -> str:
    return text if show else '_nolegend_'
