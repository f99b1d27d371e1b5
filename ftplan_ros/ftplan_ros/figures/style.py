"""What every figure shares: colours, sizes, the Agg figure, the arm, text of angles and reasons."""

from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..core.paper.result import PlanResult

DPI = 120
SNAPSHOTS = 12  # arm drawings along an executed motion
# One colour per joint's failure plane H_i (a 7-joint arm uses all seven).
HIT_COLOURS = ('#d62728', '#1f77b4', '#2ca02c', '#9467bd', '#8c564b', '#e377c2', '#17becf')
START_COLOUR = '#7b3294'    # M_s and the Θ_s candidates
GOAL_COLOUR = '#e08214'     # M_g and x_g
SURFACE_COLOUR = '#6baed6'  # S_F
SURFACE_EDGE = '#08519c'
HYPERCUBE_COLOUR = '#fee391'  # the failure hypercube V_sg
FAILURE_COLOUR = '#d7191c'
FINAL_COLOUR = '#1a9641'
OBSTACLE_FACE = '#bdbdbd'
OBSTACLE_EDGE = '#525252'
TRACE_STEP = 0.01   # [rad] largest joint step between samples of an end-effector trace


def new_figure(size: tuple[float, float]) -> Figure:
    """Return an empty figure of `size` [in] on its own Agg canvas, laid out by constraints."""
    figure = Figure(figsize=size, layout='constrained')
    FigureCanvasAgg(figure)
    return figure


def draw_arm(ax: Axes, points: np.ndarray, colour: str, width: float, label: str, gid: str,
             zorder: float = 3, alpha: float = 1.0, marker_size: float = 6.0) -> Line2D:
    """Draw an arm's points (k, 2) or (k, 3) [m] (base, joints, tool) as one line with dots.

    `ax` is 2-D axes for points (k, 2), mplot3d axes for points (k, 3).
    """
    (line,) = ax.plot(*points.T, '-o', color=colour, lw=width, ms=marker_size,
                      alpha=alpha, zorder=zorder, gid=gid, label=label,
                      solid_capstyle='round')
    return line


def hit_colour(joint: int) -> str:
    """Return the colour of joint `joint`'s failure plane (0-based)."""
    return HIT_COLOURS[joint % len(HIT_COLOURS)]


def degrees_text(theta: np.ndarray) -> str:
    """Format a configuration (n,) [rad] in degrees, e.g. '[-75.4°, 101.4°, 6.0°]'."""
    return '[' + ', '.join(f'{value:.1f}°' for value in np.degrees(theta)) + ']'


def reason_title(result: PlanResult, width: int = 60) -> str:
    """Say why there is no plan, wrapped to lines of `width` characters."""
    reason = result.reason or 'no reason given'
    return textwrap.fill(f'No failure-tolerant plan: {reason}', width=width)
