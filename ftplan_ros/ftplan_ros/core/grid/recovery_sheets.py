"""Past the paper's surface: a web of recovery sheets over the failure-tolerant set G.

The paper's failure surface fans out from θ_s to one arc of M_g^F through monotonic
paths; crowded scenes often leave no such fan although a plan exists. This planner
(method 'recovery_sheets') looks for the plan in G itself and builds a web whose slices
are the recoveries (planar 3R arms among disks; `tolerant_set.py`):

1. G is computed on a joint grid of N^3 cells from inside: cells every configuration of
   which is free and can escape to the goal with any tolerated joint locked.
2. The nominal path runs from an exact start configuration (M_s) through certified cells
   (breadth-first, 26 neighbours, round the torus) to an exact goal configuration: θ_s,
   each cell's centre and the middle of each step. Every piece between two waypoints
   then lies in one closed cell, so in one θ_i-layer for every joint i.
3. For each tolerated joint i and each waypoint j, a recovery column at the constant
   level v_j = γ_i(j): it starts at γ(j) exactly, follows the nominal path's projection
   onto the plane θ_i = v_j (`P_j, P_{j+1}, ...`), then a route through the certified
   cells of the layer (breadth-first in 2-D, shortened by straight cuts) to a goal
   configuration of the layer's component at that level (a grid sample within the goal
   tolerance, `tolerant_set.py`). Consecutive columns share the rest of their route, so
   the strip between them is a thin prism over the same cells: a *sheet*. A sheet ends
   where the shared route stops being free at the next level; the next sheet starts
   with a fresh route from the same waypoint.
4. The web is the nominal path (a sheet of its own) followed by the sheets, each closed
   by repeating its last column (`FailureSurface.cuts`); the sheets meet the nominal
   path where they share its points (their bottom rows are nominal waypoints).

Why a recovery exists (the structure part 3 of the self-check proves on the finished
web by its explicit slice check, `slices.py`): a lock of joint i at a point p of the
nominal segment (j, j+1) has p_i between v_j and v_{j+1}; the segment is the bottom rung
of a strip whose two columns stay at v_j and v_{j+1}, so every rung and diagonal of the
strip crosses p_i and the slice climbs the strip to its top chord, which lies within the
goal tolerance; a lock at a waypoint follows its column. Each sheet's goal row, every
triangle's clearance and the slices themselves are then checked like any web
(verification.py); the grid is only the guide.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterator
from dataclasses import replace

import numpy as np

from ..collision.checker import CollisionChecker
from ..model.angles import wrap_angle, wrap_steps
from ..model.robot import PlanarChain
from ..model.scene import Obstacle, Scene, Task
from ..paper.failure_surface import FailureSurface
from ..paper.manifolds import project_to_preimage
from ..paper.options import PlannerOptions
from ..paper.result import PlanResult
from ..paper.slices import slice_problem
from ..paper.verification import verify_surface
from .cell_classes import supports
from .components import components
from .existence import exact_goals, exact_starts, proves_no
from .sheet_builder import SheetBuilder, TriangleCheck
from .sheet_kernels import bfs, greedy_cuts, mask_triangle_free, route_cells, wrap_index
from .tolerant_set import (
    TolerantSet,
    fits_goal_tolerance,
    pooled_tolerant_set,
    tolerant_set,
)

log = logging.getLogger(__name__)

METHOD = 'recovery_sheets'
PAPER_METHOD = 'paper_surface'
_MOST_ROUNDS = 12  # rounds of waypoints added to the nominal path (where strips need them)
_LAYERS_PER_STRIP = 4  # the nominal path gets a waypoint every this many θ_i-layers
PROVED_NONE = 'no failure-tolerant plan exists (proved on a joint grid)'
_NO_GRID = 'no joint grid of sheet_cells is fine enough for the goal tolerance'


def past_the_paper(scene: Scene, result: PlanResult, options: PlannerOptions,
                   report: Callable[[str], None], start_configuration: np.ndarray | None = None,
                   prefer_starts: Callable[[np.ndarray], np.ndarray] | None = None,
                   checker: CollisionChecker | None = None) -> PlanResult:
    """Name the paper's result's method; where it found no plan, run the recovery sheets.

    The sheets run for planar 3R arms among disks when `options.methods` lists them. A
    failure says whether the grid proved that no plan exists or found none at its
    resolution, after the paper's own reason. `checker` is the scene's, if the caller
    has one.
    """
    result = replace(result, stats={'method': PAPER_METHOD} | result.stats)
    if result.feasible or not sheets_apply(scene, options):
        return result
    # No start passes the necessary condition (eq. 6) for every joint, with starts a
    # quarter step apart along M_s: no plan has room to start, unless between those
    # starts. No web is searched; the sheets' grids try to prove that none exists, unless
    # the question was one given start (it fails the condition: that is all).
    no_room = result.necessary_starts is not None and len(result.necessary_starts) == 0
    if no_room and start_configuration is not None:
        return result
    sheets = RecoverySheets(scene, options, report, start_configuration, prefer_starts, checker)
    return with_sheets(result, sheets.prove_none(previous=result) if no_room
                       else sheets.run(previous=result))


def with_sheets(paper: PlanResult, sheets: PlanResult) -> PlanResult:
    """Combine the paper's result with the recovery sheets' (`RecoverySheets.run`).

    The paper's plan if it has one, else the sheets', else a failure that says whether
    the grid proved that no plan exists or found none at its resolution, after the
    paper's own reason.
    """
    paper = replace(paper, stats={'method': PAPER_METHOD} | paper.stats)
    if paper.feasible:
        return paper
    if sheets.feasible:
        return replace(sheets, stats=sheets.stats | {'paper_reason': paper.reason,
                                                     'paper_plan_stats': paper.stats})
    stats = paper.stats | {f'sheets_{key}': value for key, value in sheets.stats.items()
                           if key not in ('method', 'tolerated_joints')}
    stats['proved_infeasible'] = sheets.proved_infeasible
    return replace(paper, stats=stats, reason=f'{sheets.reason}; the paper\'s surface: '
                   f'{paper.reason}', proved_infeasible=sheets.proved_infeasible)


def sheets_apply(scene: Scene, options: PlannerOptions) -> bool:
    """Whether the recovery sheets follow the paper's search: listed, planar 3R among disks."""
    return METHOD in options.methods and supports(scene)


class RecoverySheets:
    """Plan a planar 3R scene by recovery sheets over G (see the module docstring).

    `prefer_starts` maps start configurations (c, 3) to a mask (c,) of those to try
    first (as `planner.plan` takes it). A `checker` of the scene may be shared with the
    paper's search (its count of clearance queries then covers both).
    """

    def __init__(self, scene: Scene, options: PlannerOptions, report: Callable[[str], None],
                 start_configuration: np.ndarray | None = None,
                 prefer_starts: Callable[[np.ndarray], np.ndarray] | None = None,
                 checker: CollisionChecker | None = None):
        self.scene = scene
        self.options = options
        self.report = report
        if start_configuration is not None:  # onto M_s, as the paper's search takes it
            start_configuration = project_to_preimage(
                scene.robot, np.asarray(scene.task.start, dtype=float),
                np.asarray(start_configuration, dtype=float))
        self.start_configuration = start_configuration
        self.prefer_starts = prefer_starts
        self.margin = options.verification.margin
        self.checker = checker or CollisionChecker(scene.robot, scene.obstacles)

    def run(self, previous: PlanResult | None = None) -> PlanResult:
        """Try each grid in turn; the result keeps `previous`'s manifolds for the figures.

        Each grid of `options.sheet_cells` is classified, then tried pooled to half as many
        cells per joint, then as it is (`_grids`). Where no web is found on a grid, the
        grid may prove that no plan exists.
        """
        stats: dict = {'method': METHOD}
        reason = _NO_GRID
        for cells, grid, where in self._grids(self.options.sheet_cells):
            self.report(f'recovery sheets on {where}')
            surface, reason = self._plan_on(grid)
            stats.update(grid_cells=grid.lattice.cells, classified_cells=cells)
            if surface is not None:
                surface = _wrapped(surface, self.scene.robot.periodic)
                verdict = verify_surface(surface, self.checker, self.scene.task,
                                         self.options.verification)
                if verdict.ok:
                    stats.update(min_clearance_m=verdict.min_clearance,
                                 recovery_min_clearance_m=verdict.recovery_min_clearance,
                                 goal_error_bound_m=verdict.max_goal_error,
                                 clearance_samples=verdict.clearance_samples,
                                 criterion='a shortest path through the failure-tolerant '
                                 'set', web_shape=list(surface.paths.shape))
                    return self._result(True, '', surface, stats, previous)
                reason = f'the recovery sheets failed the self-check: {verdict.reason}'
                log.debug(reason)
                continue
            if proves_no(grid):
                stats['proved_infeasible'] = True
                return self._result(False, self._proved(where), None, stats, previous,
                                    proved_infeasible=True)
        return self._result(False, 'no failure-tolerant plan found within the resolution of '
                            f'the joint grid ({reason})', None, stats, previous)

    def prove_none(self, previous: PlanResult | None = None) -> PlanResult:
        """Try to prove that no plan exists, on the grids `run` takes, without searching webs.

        For scenes where a plan is unlikely (no start passes the paper's necessary
        condition). The result is never feasible; its `proved_infeasible` says whether a
        grid proved it.
        """
        stats: dict = {'method': METHOD}
        tried = _NO_GRID
        for cells, grid, where in self._grids(self.options.sheet_cells):
            self.report(f'trying to prove that no plan exists, on {where}')
            stats.update(grid_cells=grid.lattice.cells, classified_cells=cells)
            if proves_no(grid):
                stats['proved_infeasible'] = True
                return self._result(False, self._proved(where), None, stats, previous,
                                    proved_infeasible=True)
            tried = f'the finest grid tried: {where}'
        return self._result(False, f'no failure-tolerant plan found (not proved that none '
                            f'exists; {tried})', None, stats, previous)

    def _grids(self, sizes: tuple[int, ...]) -> Iterator[tuple[int, TolerantSet, str]]:
        """Yield (cells, grid, where) for each size: its grid pooled, then as classified.

        Pooled (`pooled_tolerant_set`) comes first: sharper than classifying that many
        cells, and an eighth of the cells to label. Sizes too coarse for the goal
        tolerance (`fits_goal_tolerance`) are passed over.
        """
        for cells in sizes:
            if not fits_goal_tolerance(self.scene, cells):
                continue
            classified = tolerant_set(self.scene, cells, margin=self.margin)
            for grid in (pooled_tolerant_set(classified), classified):
                if grid is not None:
                    yield cells, grid, f'{grid.lattice.cells}^3 cells' + (
                        f' pooled from {cells}^3' if grid is not classified else '')

    def _proved(self, where: str) -> str:
        """Return the reason of a failure the grid `where` proved, with the margin it holds for."""
        return f'{PROVED_NONE}, {where}' + (
            f', for a clearance above the margin of {self.margin:g} m' if self.margin > 0 else '')

    def _result(self, feasible: bool, reason: str, surface: FailureSurface | None,
                stats: dict, previous: PlanResult | None,
                proved_infeasible: bool = False) -> PlanResult:
        robot = self.scene.robot
        stats['collision_checks'] = self.checker.checks
        stats['tolerated_joints'] = [robot.joint_names[i] for i in self.scene.tolerated_joints]
        manifolds = (previous.start_manifolds, previous.goal_manifolds) if previous else ((), ())
        return PlanResult(feasible, robot.joint_names, reason, surface, stats, *manifolds,
                          periodic=robot.periodic, proved_infeasible=proved_infeasible)

    def _plan_on(self, grid: TolerantSet) -> tuple[FailureSurface | None, str]:
        """Build the web on one grid, or say why not."""
        found = _nominal_cells(grid, self.start_configuration, self.prefer_starts)
        if found is None:
            return None, 'no path through the certified failure-tolerant cells'
        gamma = _split_at_layers(_nominal_path(grid, *found), grid, _LAYERS_PER_STRIP)
        memo: dict = {}  # what the rounds find on the segments they leave as they were
        for _ in range(_MOST_ROUNDS):
            sheets, splits = [], {}
            for joint in grid.joints:
                builder = SheetBuilder(grid, gamma, joint, self.margin, memo)
                blocks = builder.build()
                if blocks is None and not builder.splits:
                    return None, f'no recovery sheet for joint {joint + 1}'
                splits.update(builder.splits)
                sheets.append(blocks)
            if splits:
                gamma = _split_segments(gamma, splits)
                continue
            rows = max(len(column) for blocks in sheets for block in blocks for column in block)
            if rows <= len(gamma):
                return _assemble(gamma, sheets, grid.joints), ''
            gamma = _lengthen_end(gamma, rows - len(gamma))
        return None, 'the recovery sheets need too many waypoints'


# Step 2: the nominal path ---------------------------------------------------------------

def _nominal_cells(grid: TolerantSet, start_configuration: np.ndarray | None,
                   prefer_starts: Callable[[np.ndarray], np.ndarray] | None = None,
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """θ_s, the cells (c, 3) from its cell to a goal cell, and the goal configuration.

    Starts that `prefer_starts` marks are tried first.
    """
    lattice = grid.lattice
    starts = exact_starts(grid) if start_configuration is None else \
        np.asarray(start_configuration, dtype=float).reshape(1, -1)
    starts = starts[lattice.inside(starts)]
    start_cells = lattice.cell_of(starts)
    inside = grid.certified_holding(start_cells)  # None: no start cell is in G
    if inside is None:
        return None
    goals = exact_goals(grid)
    goals = goals[lattice.inside(goals)]
    goal_cells = lattice.cell_of(goals)
    start_ok = inside[tuple(start_cells.T)]
    goal_ok = inside[tuple(goal_cells.T)]
    if not start_ok.any() or not goal_ok.any():
        return None
    target = np.zeros(inside.shape, dtype=np.bool_)
    target[tuple(goal_cells[goal_ok].T)] = True
    preferred = np.asarray(prefer_starts(starts), dtype=bool) & start_ok \
        if prefer_starts is not None else np.zeros(len(starts), dtype=bool)
    path = None
    for usable in (preferred, start_ok):
        if usable.any():
            path = bfs(inside, lattice.periodic, start_cells[usable], target)
            if path is not None:
                start_ok = usable
                break
    if path is None:
        return None
    first = np.flatnonzero(np.all(start_cells == path[0], axis=1) & start_ok)[0]
    last = np.flatnonzero(np.all(goal_cells == path[-1], axis=1) & goal_ok)[0]
    return starts[first], path, goals[last]


def _nominal_path(grid: TolerantSet, theta_s: np.ndarray, cells: np.ndarray,
                  theta_g: np.ndarray) -> np.ndarray:
    """Waypoints (W+1, 3) [rad], lifted, from θ_s through the cells to the goal.

    The cell centres are joined by straight cuts wherever the cut passes certified cells
    only (so every point of the path lies in G).
    """
    lattice = grid.lattice
    periodic = lattice.periodic
    points = [np.asarray(theta_s, dtype=float)]
    for centre in list(lattice.centres(cells)) + [np.asarray(theta_g, dtype=float)]:
        points.append(points[-1] + wrap_steps(centre - points[-1], periodic))
    points = np.array(points)
    offsets = (points - lattice.lower) / lattice.step
    gamma = points[greedy_cuts(grid.certified_all, periodic, offsets, np.inf)]
    keep = np.concatenate([[True], np.any(np.diff(gamma, axis=0) != 0.0, axis=1)])
    return gamma[keep]


def _split_at_layers(gamma: np.ndarray, grid: TolerantSet, every: int = 1) -> np.ndarray:
    """Add a waypoint wherever the path crosses every `every`-th θ_i-layer boundary.

    (For every tolerated joint i.) With `every` = 1 each segment lies in one closed layer
    of each joint, and its recovery strip needs the cells certified in that layer only;
    coarser, fewer strips span a few layers, whose certified cells they need at once.
    """
    lattice = grid.lattice
    points = [gamma[0]]
    for a, b in zip(gamma[:-1], gamma[1:], strict=True):
        crossings = []
        for i in grid.joints:
            if a[i] == b[i]:
                continue
            low, high = sorted((a[i], b[i]))
            width = every * lattice.step[i]
            first = np.floor((low - lattice.lower[i]) / width) + 1
            lines = lattice.lower[i] + width * np.arange(
                first, np.ceil((high - lattice.lower[i]) / width))
            for line in lines[(lines > low) & (lines < high)]:
                crossings.append(((line - a[i]) / (b[i] - a[i]), i, line))
        last_t = 0.0
        for t, i, line in sorted(crossings):
            if t - last_t < 1e-9 and len(points) > 1 and last_t > 0.0:
                points[-1][i] = line  # boundaries of two joints crossed at one point
                continue
            if t > 1.0 - 1e-9:
                continue
            point = a + t * (b - a)
            point[i] = line
            points.append(point)
            last_t = t
        points.append(b)
    return np.array(points)


def _split_segments(gamma: np.ndarray, splits: dict) -> np.ndarray:
    """Add a waypoint at fraction `splits[j]` of each segment j (the same motion)."""
    points = [gamma[0]]
    for j in range(len(gamma) - 1):
        if j in splits:
            points.append(gamma[j] + splits[j] * (gamma[j + 1] - gamma[j]))
        points.append(gamma[j + 1])
    return np.array(points)


def _lengthen_end(gamma: np.ndarray, extra: int) -> np.ndarray:
    """Split the last segment into `extra` + 1 pieces (more rows; the same motion)."""
    a, b = gamma[-2], gamma[-1]
    t = np.arange(1, extra + 1)[:, None] / (extra + 1)
    return np.vstack([gamma[:-1], a + t * (b - a), b[None]])


# Step 3: recovery sheets ----------------------------------------------------------------











def _assemble(gamma: np.ndarray, sheets: list[list[list[np.ndarray]]],
              joints: tuple[int, ...]) -> FailureSurface:
    """Lay the nominal sheet and every joint's sheets side by side, padded at the top."""
    rows = len(gamma)
    paths = [gamma, gamma]
    hit_paths = []
    for blocks in sheets:
        for number, block in enumerate(blocks):
            padded = [np.vstack([column, np.repeat(column[-1:], rows - len(column), 0)])
                      for column in block]
            if np.array_equal(padded[0], paths[-1]):
                # It begins with the column the last sheet ended with: one sheet goes on.
                paths.pop()
                padded = padded[1:]
            if number == 0:  # the column of the lock at θ_s: its top is the H_i hit
                hit_paths.append(len(paths) - (len(padded) < len(block)))
            paths += padded + [padded[-1]]  # a repeated path closes the sheet
    return FailureSurface(np.array(paths[:-1]), 0, tuple(hit_paths), tuple(joints))


def _wrapped(surface: FailureSurface, periodic: np.ndarray) -> FailureSurface:
    """Move the web by whole turns of its periodic joints so that θ_s lies in (-π, π]."""
    shift = np.where(periodic, wrap_angle(surface.theta_s) - surface.theta_s, 0.0)
    return FailureSurface(surface.paths + shift, surface.nominal, surface.hit_paths,
                          surface.tolerated)


# Grid helpers ---------------------------------------------------------------------------


def load_sheet_kernels() -> None:
    """Run the compiled kernels of the recovery sheets once (numba loads them on first use)."""
    scene = Scene(PlanarChain((1.0, 1.0, 1.0), ('joint1', 'joint2', 'joint3')),
                  (Obstacle('sphere', (2.5, 0.0, 0.0), radius=0.2),),
                  Task((2.0, 0.5), (1.0, 0.5)))
    grid = tolerant_set(scene, 32)
    proves_no(grid)  # the liberal side's kernels too
    pooled_tolerant_set(grid)
    mask = grid.classes.certified
    components(mask, grid.lattice.periodic).at(np.zeros((1, 3), dtype=np.int64))
    wrap_index(0, grid.lattice.periodic[0], 4)  # as the builders call it, from Python
    bfs(mask, grid.lattice.periodic, np.zeros((1, 3), dtype=np.int64), mask)
    bfs(mask[0], grid.lattice.periodic[1:], np.zeros((1, 2), dtype=np.int64), mask[0])
    route_cells(np.array([[0.0, 0.0], [1.0, 1.0]]), np.ones(2, dtype=np.bool_), 4)
    for difference in (np.zeros(2), np.zeros(3), np.zeros((2, 2))):
        wrap_steps(difference, np.ones(difference.shape[-1], dtype=np.bool_))
    greedy_cuts(mask, grid.lattice.periodic, np.array([[0.0, 0, 0], [1, 1, 1], [2, 2, 2]]), 16)
    greedy_cuts(mask[0], grid.lattice.periodic[1:], np.array([[0.0, 0], [1, 1], [2, 2]]), 16)
    mask_triangle_free(mask[0], np.zeros(2), np.ones(2), np.array([0.0, 1.0]),
                   grid.lattice.periodic[1:])
    TriangleCheck(scene)(np.eye(3))
    paths = np.zeros((2, 2, 3))
    paths[:, 1, 0] = 1.0
    paths[1, :, 1] = 1.0
    slice_problem(FailureSurface(paths, 0, (), ()), (0,))
