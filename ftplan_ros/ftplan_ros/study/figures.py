"""Figures of a study: a map's workspace coloured by outcome and by clearance, a sweep's rates.

matplotlib's object-oriented API only, as in `ftplan_ros.figures` (whose figure, scenery
and file helpers these reuse): every function returns a new Figure on its own Agg canvas.
Positions are in metres. Artists carry a `gid` ('outcome', 'clearance', 'obstacle',
'feasible_rate', 'wilson_band', ...) so tests and scripts can find them.
"""

from __future__ import annotations

import numpy as np
import pyarrow as pa
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from ..figures.planar import draw_reach, draw_scenery
from ..figures.style import GOAL_COLOUR, new_figure
from .results import OUTCOMES
from .spec import PositionGrid, Study
from .summary import feasible_rate_by

OUTCOME_COLOURS = ('#1a9641', '#fdae61', '#d9d9d9', '#d7191c')   # in the order of OUTCOMES
OUTCOME_LABELS = ('failure-tolerant', 'reachable, not failure-tolerant', 'unreachable', 'error')
RATE_COLOUR = '#2c7bb6'


def map_figure(study: Study, table: pa.Table) -> Figure:
    """Draw a planar map: cells coloured by outcome (left) and by minimum clearance (right).

    Each cell is one grid position of the varied start (or goal), centred on it; cells
    without a row (a study still running) stay blank. The clearance is that of the
    verified failure surface [m], drawn for failure-tolerant cells only. Both panels show
    the base scene's obstacles, the arm's base and reach, and the fixed end of the task.
    Raises ValueError for a sweep or a map that is not over x and y.
    """
    grid = study.vary
    if not isinstance(grid, PositionGrid) or study.dim != 2:
        raise ValueError('map figures draw maps over planar positions (x, y)')
    codes = _grid_values(grid, table, [OUTCOMES.index(o) for o in
                                       table.column('outcome').to_pylist()])
    clearance = _grid_values(grid, table, [
        c if f and c is not None else np.nan
        for c, f in zip(table.column('min_clearance').to_pylist(),
                        table.column('feasible').to_pylist(), strict=True)])
    x_edges, y_edges = (_edges(values, other) for values, other in
                        ((grid.axes[0], grid.axes[1]), (grid.axes[1], grid.axes[0])))
    figure = new_figure((12.0, 7.2))
    outcome_ax, clearance_ax = figure.subplots(1, 2, sharex=True, sharey=True)

    outcome_ax.pcolormesh(x_edges, y_edges, np.ma.masked_invalid(codes),
                          cmap=ListedColormap(OUTCOME_COLOURS), vmin=-0.5,
                          vmax=len(OUTCOMES) - 0.5, gid='outcome', zorder=0)
    counts = [int(np.sum(codes == k)) for k in range(len(OUTCOMES))]
    handles = [Patch(facecolor=colour, edgecolor='0.4', label=f'{label} ({count})')
               for colour, label, count in zip(OUTCOME_COLOURS, OUTCOME_LABELS, counts,
                                               strict=True) if count]
    _finish_map(outcome_ax, study, 'outcome', handles)

    finite = np.where(np.isfinite(clearance), clearance, np.nan)
    mesh = clearance_ax.pcolormesh(x_edges, y_edges, np.ma.masked_invalid(finite),
                                   cmap='viridis', gid='clearance', zorder=0)
    if np.isfinite(finite).any():
        figure.colorbar(mesh, ax=clearance_ax, label='minimum clearance of S_F [m]',
                        shrink=0.85)
        title = 'minimum clearance of the failure-tolerant plans'
    else:
        title = 'minimum clearance: no finite value (no obstacles, or no plan)'
    _finish_map(clearance_ax, study, title, [])
    done = table.num_rows
    figure.suptitle(f'{study.name}: {grid.endpoint} positions, {done} of {study.tasks} tasks, '
                    f'methods {", ".join(study.planner.methods)}', fontsize='large')
    return figure


def sweep_figure(study: Study, table: pa.Table) -> Figure:
    """Draw the feasible rate against the number of random obstacles, with 95 % Wilson bands.

    Rates are over the tasks that did not raise; each point is labelled with its task count.
    """
    rates = feasible_rate_by(table, 'random_obstacles')
    figure = new_figure((8.0, 5.0))
    ax = figure.add_subplot()
    x = rates['value'].astype(float)
    if len(x) > 1:
        ax.fill_between(x, rates['low'], rates['high'], color=RATE_COLOUR, alpha=0.25, lw=0,
                        gid='wilson_band', label='95 % Wilson interval')
    else:
        ax.errorbar(x, rates['rate'], yerr=[rates['rate'] - rates['low'],
                                            rates['high'] - rates['rate']],
                    fmt='none', ecolor=RATE_COLOUR, capsize=6, gid='wilson_band',
                    label='95 % Wilson interval')
    ax.plot(x, rates['rate'], '-o', color=RATE_COLOUR, lw=1.8, ms=5, gid='feasible_rate',
            label='failure-tolerant plan found')
    for value, rate, tasks in zip(x, rates['rate'], rates['tasks'], strict=True):
        ax.annotate(f'{tasks}', (value, rate), textcoords='offset points', xytext=(0, 7),
                    ha='center', fontsize='x-small', color='0.35')
    ax.set_ylim(0.0, 1.08)   # room for the counts above a rate of 1
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel('random obstacles per task')
    ax.set_ylabel('share of tasks with a failure-tolerant plan')
    ax.grid(alpha=0.3)
    ax.legend(loc='upper right', fontsize='small')
    ax.set_title(f'{study.name}: {table.num_rows} tasks (count above each point), '
                 f'methods {", ".join(study.planner.methods)}')
    return figure


def _grid_values(grid: PositionGrid, table: pa.Table, values: list) -> np.ndarray:
    """Put per-row values into the grid (ny, nx); cells without a row are NaN."""
    nx, ny = grid.shape
    cells = np.full(nx * ny, np.nan)
    cells[table.column('task').to_numpy()] = np.asarray(values, dtype=float)
    return cells.reshape(ny, nx)


def _edges(values: tuple[float, ...], other: tuple[float, ...]) -> np.ndarray:
    """Cell edges around grid values [m]; one value gets the other axis' spacing as width."""
    values = np.asarray(values)
    if len(values) > 1:
        middles = 0.5 * (values[1:] + values[:-1])
        return np.concatenate([[2 * values[0] - middles[0]], middles,
                               [2 * values[-1] - middles[-1]]])
    width = float(np.diff(other).min()) if len(other) > 1 else 0.1
    return np.array([values[0] - width / 2, values[0] + width / 2])


def _finish_map(ax: Axes, study: Study, title: str, handles: list) -> None:
    scene = study.scene
    draw_scenery(ax, scene)
    fixed = 'goal' if study.vary.endpoint == 'start' else 'start'
    point = getattr(scene.task, fixed)
    if fixed == 'goal':
        ax.plot(*point, '*', ms=17, mfc=GOAL_COLOUR, mec='k', mew=1.0, zorder=7, gid='x_g',
                label=r'goal $\mathbf{x}_g$')
    else:
        ax.plot(*point, 'o', ms=10, mfc='white', mec='k', mew=1.8, zorder=7, gid='x_s',
                label=r'start $\mathbf{x}_s$')
    draw_reach(ax, float(scene.robot.tip_lever_arms()[0]), '0.3', 'reach')
    ax.set_aspect('equal', adjustable='box')
    ax.set_xlabel('x [m]')
    ax.set_ylabel('y [m]')
    ax.set_title(title)
    own, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + own, loc='upper left', bbox_to_anchor=(0.0, -0.1),
              ncol=2, fontsize='small', frameon=False)
