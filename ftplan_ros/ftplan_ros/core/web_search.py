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
import math
from collections.abc import Callable, Iterator
from dataclasses import replace

import numba
import numpy as np

from .angles import wrap_angle, wrap_steps
from .cell_classes import disk_arrays, link_lever_arms, supports, triangle_free
from .collision import CollisionChecker
from .components import components
from .failure_surface import FailureSurface
from .manifolds import project_to_preimage
from .options import PlannerOptions
from .reference import proves_no
from .result import PlanResult
from .scene import Scene
from .tolerant_set import (
    TolerantSet,
    fits_goal_tolerance,
    pooled_tolerant_set,
    preimage_samples,
    tolerant_set,
)
from .verification import verify_surface

log = logging.getLogger(__name__)

METHOD = 'recovery_sheets'
PAPER_METHOD = 'paper_surface'
_MOST_ROUNDS = 12  # rounds of waypoints added to the nominal path (where strips need them)
_SHORTEST_SEGMENT = 1e-4  # [rad] a nominal segment is not split below this
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
    no_room = result.stats.get('theta_S', 1) == 0 and result.stats.get('start_candidates', 0) > 0
    if no_room and start_configuration is not None:
        return result
    sheets = WebSearch(scene, options, report, start_configuration, prefer_starts, checker)
    return with_sheets(result, sheets.prove_none(previous=result) if no_room
                       else sheets.run(previous=result))


def with_sheets(paper: PlanResult, sheets: PlanResult) -> PlanResult:
    """Combine the paper's result with the recovery sheets' (`WebSearch.run`).

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
    stats['proved_infeasible'] = bool(sheets.stats.get('proved_infeasible', False))
    return replace(paper, stats=stats, reason=f'{sheets.reason}; the paper\'s surface: '
                   f'{paper.reason}')


def sheets_apply(scene: Scene, options: PlannerOptions) -> bool:
    """Whether the recovery sheets follow the paper's search: listed, planar 3R among disks."""
    return METHOD in options.methods and supports(scene)


class WebSearch:
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
                return self._result(False, self._proved(where), None, stats, previous)
        return self._result(False, 'no failure-tolerant plan found within the resolution of '
                            f'the joint grid ({reason})', None, stats, previous)

    def prove_none(self, previous: PlanResult | None = None) -> PlanResult:
        """Try to prove that no plan exists, on the grids `run` takes, without searching webs.

        For scenes where a plan is unlikely (no start passes the paper's necessary
        condition). The result is never feasible; stats['proved_infeasible'] says whether
        a grid proved it.
        """
        stats: dict = {'method': METHOD}
        tried = _NO_GRID
        for cells, grid, where in self._grids(self.options.sheet_cells):
            self.report(f'trying to prove that no plan exists, on {where}')
            stats.update(grid_cells=grid.lattice.cells, classified_cells=cells)
            if proves_no(grid):
                stats['proved_infeasible'] = True
                return self._result(False, self._proved(where), None, stats, previous)
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
                stats: dict, previous: PlanResult | None) -> PlanResult:
        robot = self.scene.robot
        stats['collision_checks'] = self.checker.checks
        stats['tolerated_joints'] = [robot.joint_names[i] for i in self.scene.tolerated_joints]
        manifolds = (previous.start_manifolds, previous.goal_manifolds) if previous else ((), ())
        return PlanResult(feasible, robot.joint_names, reason, surface, stats, *manifolds,
                          periodic=robot.periodic)

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
                builder = _SheetBuilder(grid, gamma, joint, self.margin, memo)
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
    robot, task = grid.scene.robot, grid.scene.task
    lengths = np.asarray(robot.link_lengths, dtype=float)
    if start_configuration is not None:
        starts = np.asarray(start_configuration, dtype=float).reshape(1, -1)
    else:
        starts = preimage_samples(lengths, np.asarray(task.start, dtype=float),
                                  8 * lattice.cells)
    starts = starts[lattice.inside(starts)]
    start_cells = lattice.cell_of(starts)
    inside = grid.certified_holding(start_cells)  # None: no start cell is in G
    if inside is None:
        return None
    goals = np.vstack([grid.escape(j).goal_points for j in grid.joints]
                      + [preimage_samples(lengths, np.asarray(task.goal, dtype=float),
                                          8 * lattice.cells)])
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
            path = _bfs(inside, lattice.periodic, start_cells[usable], target)
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
    gamma = points[_greedy_cuts(grid.certified_all, periodic, offsets, np.inf)]
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

class _SheetBuilder:
    """Recovery columns of one joint, as sheets (lists of columns (L, 3) [rad]).

    Where a strip cannot be built, `splits` maps its segment to the fraction at which a
    waypoint would help (at a sub-slab or layer boundary, else halfway). `memo` keeps the
    outcome of each new sheet and each extension by what it depends on (the joint, the
    segment's two waypoints, the sheet's route and first goal), for the builders of later
    rounds, whose paths differ only where waypoints were added.
    """

    def __init__(self, grid: TolerantSet, gamma: np.ndarray, joint: int, margin: float = 0.0,
                 memo: dict | None = None):
        self.grid = grid
        self.lattice = grid.lattice
        self.gamma = gamma
        self.joint = joint
        self.others = [a for a in range(3) if a != joint]
        self.periodic2 = self.lattice.periodic[self.others]
        self.step2 = self.lattice.step[self.others]
        self.lower2 = self.lattice.lower[self.others]
        self.size = self.lattice.cells
        self.layers = np.moveaxis(grid.classes.certified, joint, 0)  # layer first
        escape = grid.escape(joint)
        goals = escape.goal_points
        self.goal_points = goals
        # The goal samples by sub-slab: those of slab s are by_slab[first[s]:first[s + 1]],
        # in the order of goal_points.
        slabs = escape.goal_slabs
        self.by_slab = np.argsort(slabs, kind='stable')
        self.m = escape.sub_slabs
        self.slab_first = np.searchsorted(slabs[self.by_slab], np.arange(self.size * self.m + 1))
        self.goal_cells = self.lattice.cell_of(goals)[:, self.others]
        self.offsets2 = np.ascontiguousarray(  # [cell units], rows as the kernels were warmed
            (gamma[:, self.others] - self.lower2) / self.step2)
        self.free = _TriangleCheck(grid.scene, margin)
        self.goal_step = _goal_step(grid.scene)
        self.strip_layers = _strip_layers(gamma[:, joint], self.lattice.lower[joint],
                                          self.lattice.step[joint])
        self.splits: dict[int, float] = {}
        self.memo = {} if memo is None else memo

    def build(self) -> list[list[np.ndarray]] | None:
        """Sheets from the last waypoint back to θ_s, returned in order.

        None when a strip cannot be built (`splits` then says where waypoints would help,
        or is empty when nothing would).
        """
        W = len(self.gamma) - 1
        blocks = []
        block = None
        for j in range(W - 1, -1, -1):
            grown = self._extend(block, j) if block is not None else None
            if grown is not None:
                block = grown
                continue
            if block is not None:
                blocks.append(block)
            block = self._fresh(j)
            if block is None and j not in self.splits:
                return None
        if self.splits:
            return None
        blocks.append(block)
        return [self._columns(b) for b in reversed(blocks)]

    # A block: its first and last waypoints j0, j1, the route (2-D points, lifted) shared
    # by its columns from its hub on, the cells the route passes, and per column the goal
    # (3,) its last segment reaches from the route's end.

    def _levels(self, j: int) -> tuple[float, float]:
        return self.gamma[j, self.joint], self.gamma[j + 1, self.joint]

    def _strip_mask(self, j: int) -> np.ndarray:
        """(N, N) the cells certified free in every θ_i-layer the strip (j, j+1) spans."""
        first, last = (int(v) for v in self.strip_layers[j])
        key = ('mask', self.joint, first, last)  # the same for the builders of every round
        if key not in self.memo:
            layers = np.arange(first, last + 1)
            layers = np.mod(layers, self.size) if self.lattice.periodic[self.joint] else \
                np.clip(layers, 0, self.size - 1)
            self.memo[key] = np.logical_and.reduce(self.layers[layers], axis=0)
        return self.memo[key]

    def _cell2(self, point2: np.ndarray) -> tuple[int, int]:
        """Return the 2-D cell holding a point (2,) [rad] of the layer."""
        offset = (point2 - self.lower2) / self.step2
        return tuple(_wrap_index(math.floor(offset[a]), self.periodic2[a], self.size)
                     for a in range(2))

    def _fan_free(self, mask: np.ndarray, j: int, hub: np.ndarray) -> bool:
        """Whether the triangle (P_j, P_{j+1}, hub) lies in the mask's cells."""
        return _triangle_free(mask, self.offsets2[j], self.offsets2[j + 1],
                              (hub - self.lower2) / self.step2, self.periodic2)

    def _fresh(self, j: int) -> dict | None:
        """Start a new sheet of the strip (j, j+1), or ask for a split (`_new_sheet`)."""
        key = ('fresh', self.joint, self.gamma[j].tobytes(), self.gamma[j + 1].tobytes())
        if key not in self.memo:
            block = self._new_sheet(j)
            self.memo[key] = (block, self.splits.get(j))
        block, split = self.memo[key]
        if split is not None:
            self.splits[j] = split
        return None if block is None else dict(block, j0=j, j1=j + 1)

    def _new_sheet(self, j: int) -> dict | None:
        """Start a new sheet of the strip (j, j+1): a hub, a route from it to goals, two goals."""
        mask = self._strip_mask(j)
        levels = self._levels(j)
        ends = (self.gamma[j, self.others], self.gamma[j + 1, self.others])
        hub = None
        for point in (0.5 * (ends[0] + ends[1]), ends[1], ends[0]):
            cell = self._cell2(point)
            centre = point + wrap_steps(
                self.lower2 + (np.array(cell) + 0.5) * self.step2 - point, self.periodic2)
            if mask[cell] and self._fan_free(mask, j, centre):
                hub = (cell, centre)
                break
        later = self._goal_candidates(levels[1], levels[0])
        earlier = self._goal_candidates(levels[0], levels[1])
        if hub is None or not len(later) or not len(earlier):
            return self._split(j, layers=True)
        target = np.zeros(mask.shape, dtype=np.bool_)
        cells = self.goal_cells[later]
        target[tuple(cells[mask[tuple(cells.T)]].T)] = True
        path = _bfs(mask, self.periodic2, np.array([hub[0]]), target)
        if path is None:
            return self._split(j, layers=True)
        route, covered = self._lift_route(path, hub[1], mask)
        end = route[-1]
        best = None
        for b in later:
            if not np.array_equal(self.goal_cells[b], path[-1]):
                continue
            goal_b = self._goal(b, levels[1], end)
            for a in earlier:
                goal_a = goal_b.copy() if a == b else self._goal(a, levels[0], end)
                goal_a[self.joint] = levels[0]
                distance = np.max(np.abs(goal_a - goal_b))
                if (best is None or distance < best[0]) and distance <= self.goal_step and \
                        self._ends_free(mask, end, goal_a, goal_b):
                    best = (distance, goal_a, goal_b)
        if best is None:
            return self._split(j, layers=False)
        return {'j0': j, 'j1': j + 1, 'route': route, 'route_cells': covered,
                'goals': [best[1], best[2]]}

    def _split(self, j: int, layers: bool) -> None:
        """Ask for a waypoint inside segment j: at a layer (or sub-slab) boundary, or halfway."""
        at = self._split_fraction(j, layers)
        a, b = self.gamma[j], self.gamma[j + 1]
        if at is None and np.max(np.abs(b - a)) > _SHORTEST_SEGMENT:
            at = 0.5
        if at is not None:
            self.splits[j] = at
        return None

    def _extend(self, block: dict, j: int) -> dict | None:
        """Return the block with waypoint j's column in front, if free there (`_front_goal`)."""
        key = ('extend', self.joint, block['route'].tobytes(), block['goals'][0].tobytes(),
               self.gamma[j].tobytes(), self.gamma[j + 1].tobytes())
        if key not in self.memo:
            self.memo[key] = self._front_goal(block, j)
        goal = self.memo[key]
        if goal is None:
            return None
        grown = dict(block)
        grown.update(j0=j, goals=[goal] + block['goals'])
        return grown

    def _front_goal(self, block: dict, j: int) -> np.ndarray | None:
        """Return the goal of waypoint j's column in front of the block, or None.

        Over the strip (j, j+1) the new column's first piece and the next column's sweep
        the triangle (P_j, P_{j+1}, hub), which must lie in the cells certified in every
        layer the strip spans, like the shared route.
        """
        mask = self._strip_mask(j)
        if not self._fan_free(mask, j, block['route'][0]):
            return None
        route_cells = block['route_cells']
        if not mask[route_cells[:, 0], route_cells[:, 1]].all():
            return None
        v = self.gamma[j, self.joint]
        end, following = block['route'][-1], block['goals'][0]
        best = None
        for a in self._goal_candidates(v, self.gamma[j + 1, self.joint]):
            goal = self._goal(a, v, end)
            distance = np.max(np.abs(goal - following))
            if (best is None or distance < best[0]) and distance <= self.goal_step and \
                    self._ends_free(mask, end, goal, following):
                best = (distance, goal)
        return None if best is None else best[1]

    def _ends_free(self, mask: np.ndarray, end: np.ndarray, goal_a: np.ndarray,
                   goal_b: np.ndarray) -> bool:
        """Whether the two top triangles between the route's end and two goals are free."""
        end_a, end_b = goal_a.copy(), goal_b.copy()
        end_a[self.others] = end
        end_b[self.others] = end
        return all(self.free(np.array(corners)) for corners in
                   ((end_a, end_b, goal_b), (end_a, goal_b, goal_a)))

    def _split_fraction(self, j: int, layers: bool) -> float | None:
        """Return a layer (or sub-slab) boundary strictly inside segment j, nearest its middle."""
        a, b = self._levels(j)
        if a == b:
            return None
        lower = self.lattice.lower[self.joint]
        width = self.lattice.step[self.joint] / (1 if layers else self.m)
        low, high = sorted((a, b))
        boundaries = lower + width * np.arange(np.floor((low - lower) / width),
                                               np.ceil((high - lower) / width) + 1)
        margin = 1e-3 * (high - low)
        inside = boundaries[(boundaries > low + margin) & (boundaries < high - margin)]
        if not len(inside):
            return None if layers else self._split_fraction(j, True)
        middle = inside[np.argmin(np.abs(inside - 0.5 * (low + high)))]
        return float((middle - a) / (b - a))

    def _goal_candidates(self, level: float, toward: float) -> np.ndarray:
        """Goal samples usable at `level` (on its side toward `toward`).

        A sample is usable when `level` lies in its sub-slab: moved there along θ_i, it
        stays within the goal tolerance.
        """
        lattice = self.lattice
        side = int(toward > level) - int(toward < level)
        nudged = level + 1e-9 * side * lattice.step[self.joint]
        offset = (nudged - lattice.lower[self.joint]) / lattice.step[self.joint]
        layer = math.floor(offset)
        k = min(max(math.floor((offset - layer) * self.m), 0), self.m - 1)
        layer = _wrap_index(layer, lattice.periodic[self.joint], self.size)
        slab = layer * self.m + k
        return self.by_slab[self.slab_first[slab]:self.slab_first[slab + 1]]

    def _goal(self, index: int, level: float, near2: np.ndarray) -> np.ndarray:
        """Goal sample `index` at the locked value `level`, lifted next to `near2` (2,)."""
        theta = self.goal_points[index].copy()
        theta[self.others] = near2 + wrap_steps(theta[self.others] - near2, self.periodic2)
        theta[self.joint] = level
        return theta

    def _lift_route(self, path: np.ndarray, anchor: np.ndarray, mask: np.ndarray,
                    ) -> tuple[np.ndarray, np.ndarray]:
        """Centres (r, 2) of the 2-D cells `path`, lifted from `anchor`, with straight cuts.

        Also returns the cells (c, 2) the cut route passes through.
        """
        centres = self.lower2 + (path + 0.5) * self.step2
        first = anchor + wrap_steps(centres[0] - anchor, self.periodic2)
        steps = wrap_steps(np.diff(centres, axis=0), self.periodic2)
        lifted = first + np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
        return _shortcut(lifted, mask, self.lower2, self.step2, self.periodic2)

    def _columns(self, block: dict) -> list[np.ndarray]:
        """Return the columns (L, 3) of a block: γ(j), the hub and route at level v_j, the goal."""
        rows = self.gamma[block['j0']:block['j1'] + 1]
        columns = np.empty((len(rows), len(block['route']) + 2, 3))
        columns[:, 0] = rows
        for k, axis in enumerate(self.others):
            columns[:, 1:-1, axis] = block['route'][:, k]
        columns[:, 1:-1, self.joint] = rows[:, self.joint, None]
        columns[:, -1] = block['goals']
        return list(columns)


def _strip_layers(levels: np.ndarray, lower: float, step: float) -> np.ndarray:
    """Return the first and last θ_i-layer (W, 2) of each strip between levels (W+1,) [rad].

    Layers are closed: a strip from a layer boundary on does not span the layer below.
    Indices are not wrapped.
    """
    low, high = np.minimum(levels[:-1], levels[1:]), np.maximum(levels[:-1], levels[1:])
    nudge = 1e-9 * (high - low)
    return np.stack([np.floor((low + nudge - lower) / step),
                     np.floor((high - nudge - lower) / step)], axis=1).astype(np.int64)


def _goal_step(scene: Scene) -> float:
    """Largest step [rad] between the goals of neighbouring columns (the goal row's chords).

    A chord strays from the goal by the error of its ends (up to 0.9 of the tolerance,
    `sub_slab_count`) and its sag, which grows with the square of its length and with the
    reach. Chords of 0.15 rad pass the self-check at a tolerance of 1/300 of the reach
    (1 cm for 1 m links, the bench's) and, on 40 such scenes, down to 4 mm, but not at
    2 mm (7 of 34 webs failed it) or 1 mm; below 1/300 of the reach they shorten as the
    square root of the tolerance, which passed on all of them.
    """
    reach = float(scene.robot.tip_lever_arms()[0])
    return _LONGEST_GOAL_STEP * min(1.0, math.sqrt(scene.task.goal_tolerance / (reach / 300.0)))


# [rad] `_goal_step` for goal tolerances of 1/300 of the reach and coarser
_LONGEST_GOAL_STEP = 0.15
# [cells] longest straight cut of a route: the self-check quarters a triangle a bounded
# number of times, so a triangle many cells wide near an obstacle would go uncertified
_LONGEST_CUT = 16


class _TriangleCheck:
    """Whether a joint-space triangle (3, 3) [rad] is free: exact clearances, lever bounds."""

    def __init__(self, scene: Scene, margin: float = 0.0):
        robot = scene.robot
        self.lengths = np.asarray(robot.link_lengths, dtype=float)
        self.radius = float(robot.link_radius)
        self.centres, self.radii = disk_arrays(scene, margin)
        self.arms = link_lever_arms(self.lengths)

    def __call__(self, corners: np.ndarray) -> bool:
        return bool(triangle_free(self.lengths, self.radius, self.centres, self.radii,
                                  self.arms, np.ascontiguousarray(corners, dtype=float), 6))


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

@numba.njit(cache=True)
def _wrap_index(index, periodic, size):
    """Return a cell index on an axis of `size` cells: wrapped if periodic, else clipped."""
    return index % size if periodic else min(max(index, 0), size - 1)


def _shortcut(points: np.ndarray, mask: np.ndarray, lower: np.ndarray, step: np.ndarray,
              periodic: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drop route points (r, 2) while the straight cut between the kept ones stays in mask.

    A cut spans at most `_LONGEST_CUT` cells along each axis. Returns the kept points and
    the cells (c, 2) their segments pass through.
    """
    offsets = (points - lower) / step
    kept = _greedy_cuts(mask, periodic, offsets, _LONGEST_CUT)
    return points[kept], _route_cells(offsets[kept], periodic.astype(np.bool_), mask.shape[0])


@numba.njit(cache=True)
def _triangle_free(mask, a, b, c, periodic):
    """Whether every cell the triangle a, b, c (in cell units) meets is in the 2-D mask.

    Row by row along the first axis: within a row's band, the triangle reaches along the
    second axis from the least to the greatest of its corners in the band and its edges'
    crossings of the band's two lines; every cell of that reach is checked. Cells the
    triangle meets by less than a billionth of a cell (a boundary it runs along) are
    left out, as `_cut_free` leaves out such pieces. A corner that is not finite is not
    free.
    """
    corners = np.empty((3, 2))
    corners[0], corners[1], corners[2] = a, b, c
    if not np.all(np.isfinite(corners)):
        return False
    low, high = corners[:, 0].min(), corners[:, 0].max()
    first = int(np.floor(low + _SLIVER))
    last = max(first, int(np.ceil(high - _SLIVER)) - 1)
    for row in range(first, last + 1):
        bottom, top = max(float(row), low), min(row + 1.0, high)
        least, most = np.inf, -np.inf
        for k in range(3):
            if bottom <= corners[k, 0] <= top:
                least, most = min(least, corners[k, 1]), max(most, corners[k, 1])
            p, q = corners[k], corners[(k + 1) % 3]
            if p[0] == q[0]:
                continue  # along the band: its corners count
            for level in (bottom, top):
                if min(p[0], q[0]) <= level <= max(p[0], q[0]):
                    across = p[1] + (level - p[0]) * (q[1] - p[1]) / (q[0] - p[0])
                    least, most = min(least, across), max(most, across)
        if not _row_free(mask, periodic, row, least, most):
            return False
    return True


@numba.njit(cache=True, inline='always')
def _row_free(mask, periodic, row, least, most):
    """Whether the cells of `row` from `least` to `most` (cell units) are all in the mask."""
    size_row, size_column = mask.shape
    if periodic[0]:
        row %= size_row
    elif row < 0 or row >= size_row:
        return False
    first = int(np.floor(least + _SLIVER))
    last = max(first, int(np.ceil(most - _SLIVER)) - 1)
    for column in range(first, last + 1):
        if periodic[1]:
            at = column % size_column
        elif 0 <= column < size_column:
            at = column
        else:
            return False
        if not mask[row, at]:
            return False
    return True


# [cells] how little of a cell a triangle may meet and leave it out (rounding at a line)
_SLIVER = 1e-9


@numba.njit(cache=True)
def _piece_middles(a, b):
    """Return t in [0, 1] at the middle of each piece of segment a-b between grid crossings.

    a and b are in cell units, of any dimension. Pieces shorter than a billionth of a
    cell are rounding at a grid line and are left out, so a segment through a grid corner
    does not enter the cells beside it.
    """
    crossings = np.empty((2, a.shape[0]))
    pieces, sliver = _first_crossings(a, b, crossings)
    middles = np.empty(pieces)
    found = 0
    before = 0.0
    for _ in range(pieces):
        after = _next_crossing(a, b, crossings)
        if after - before > sliver or pieces == 1:
            middles[found] = 0.5 * (before + after)
            found += 1
        before = after
    return middles[:found]


@numba.njit(cache=True, inline='always')
def _first_crossings(a, b, crossings):
    """Set up the walk along segment a-b over its grid crossings (`_next_crossing`).

    `crossings` (2, d) gets each axis's first grid line strictly between the ends (in
    the order the segment meets them) and how many it has. Returns the number of pieces
    and the length in t [0, 1] of a sliver, a billionth of a cell along the longest axis.
    """
    longest = 0.0
    pieces = 1
    for axis in range(a.shape[0]):
        low, high = min(a[axis], b[axis]), max(a[axis], b[axis])
        longest = max(longest, high - low)
        first, last = np.floor(low) + 1.0, np.ceil(high) - 1.0
        count = max(0.0, last - first + 1.0)
        crossings[0, axis] = first if b[axis] > a[axis] else last
        crossings[1, axis] = count
        pieces += int(count)
    return pieces, 1e-9 / max(1e-300, longest)


@numba.njit(cache=True, inline='always')
def _next_crossing(a, b, crossings):
    """Return t of the segment's next grid crossing (1 after the last), and pass it.

    Each axis meets its lines in order of t, so the next of all is the least of each
    axis's next: no sorting.
    """
    after, nearest = 1.0, -1
    for axis in range(a.shape[0]):
        if crossings[1, axis] > 0.0:
            t = (crossings[0, axis] - a[axis]) / (b[axis] - a[axis])
            if nearest < 0 or t < after:
                after, nearest = t, axis
    if nearest >= 0:
        crossings[0, nearest] += 1.0 if b[nearest] > a[nearest] else -1.0
        crossings[1, nearest] -= 1.0
    return after


@numba.njit(cache=True)
def _route_cells(points, periodic, size):
    """Cells (c, 2) the route through `points` (r, 2) [cell units] passes, in order.

    Each segment's cells, then the last point's; indices are wrapped round the periodic
    axes and clipped to the grid along the others.
    """
    ends = np.vstack((points, points[-1:]))  # the last point: a segment of no length
    pieces = [_piece_middles(ends[k], ends[k + 1]) for k in range(points.shape[0])]
    count = 0
    for middles in pieces:
        count += middles.shape[0]
    cells = np.empty((count, 2), dtype=np.int64)
    row = 0
    for k in range(points.shape[0]):
        a, b = ends[k], ends[k + 1]
        for t in pieces[k]:
            for axis in range(2):
                cells[row, axis] = _wrap_index(int(np.floor(a[axis] + t * (b[axis] - a[axis]))),
                                               periodic[axis], size)
            row += 1
    return cells


def _greedy_cuts(mask: np.ndarray, periodic: np.ndarray, offsets: np.ndarray,
                 longest: float) -> np.ndarray:
    """Return the indices of the points (r, d) [cell units] a path keeps, cut straight in mask.

    From each kept point the path jumps to the farthest later point before the first
    whose straight cut leaves the mask's cells or spans more than `longest` cells along
    an axis; the first and last points are kept.
    """
    return _greedy_cuts_kernel(np.ascontiguousarray(mask).ravel(), np.array(mask.shape),
                               periodic.astype(np.bool_), np.ascontiguousarray(offsets),
                               float(longest))


@numba.njit(cache=True)
def _greedy_cuts_kernel(mask, shape, periodic, offsets, longest):
    kept = np.empty(offsets.shape[0], dtype=np.int64)
    kept[0] = 0
    count = 1
    k = 0
    crossings = np.empty((2, offsets.shape[1]))
    while k < offsets.shape[0] - 1:
        far = k + 1
        for candidate in range(k + 2, offsets.shape[0]):
            if np.max(np.abs(offsets[candidate] - offsets[k])) > longest or not _cut_free(
                    mask, shape, periodic, offsets[k], offsets[candidate], crossings):
                break
            far = candidate
        kept[count] = far
        count += 1
        k = far
    return kept[:count]


@numba.njit(cache=True)
def _cut_free(mask, shape, periodic, a, b, crossings):
    """Whether every cell the segment a-b (in cell units) passes through is in the flat mask.

    The pieces of `_piece_middles`, walked without storing them; `crossings` (2, d) is
    scratch space for the walk.
    """
    pieces, sliver = _first_crossings(a, b, crossings)
    before = 0.0
    for _ in range(pieces):
        after = _next_crossing(a, b, crossings)
        if (after - before > sliver or pieces == 1) and not _cell_in(
                mask, shape, periodic, a, b, 0.5 * (before + after)):
            return False
        before = after
    return True


@numba.njit(cache=True, inline='always')
def _cell_in(mask, shape, periodic, a, b, t):
    """Whether the cell holding the point at t of segment a-b (cell units) is in the flat mask."""
    flat = 0
    for axis in range(a.shape[0]):
        value = int(np.floor(a[axis] + t * (b[axis] - a[axis])))
        if periodic[axis]:
            value %= shape[axis]
        elif value < 0 or value >= shape[axis]:
            return False
        flat = flat * shape[axis] + value
    return mask[flat]


# The steps to a cell's neighbours in 2-D and 3-D (at most one cell along each axis), in
# C order.
_NEIGHBOUR_STEPS = {dims: np.array([o for o in np.ndindex(*(3,) * dims) if any(v != 1 for v in o)],
                                   dtype=np.int64) - 1 for dims in (2, 3)}


def _bfs(mask: np.ndarray, periodic: np.ndarray, sources: np.ndarray, target: np.ndarray,
         ) -> np.ndarray | None:
    """Cells (c, d) of a shortest path in mask (d = 2 or 3) from a source to a target cell."""
    offsets = _NEIGHBOUR_STEPS[mask.ndim]
    flat_sources = np.ravel_multi_index(tuple(np.asarray(sources).T), mask.shape)
    found = _bfs_kernel(np.ascontiguousarray(mask).ravel(), np.array(mask.shape),
                        periodic.astype(np.bool_), offsets, flat_sources.astype(np.int64),
                        np.ascontiguousarray(target).ravel())
    if len(found) == 0:
        return None
    return np.stack(np.unravel_index(found, mask.shape), axis=1)


_UNSEEN = 255  # `_bfs_kernel`'s step code of a cell not reached yet
_SOURCE = 254  # and of a source cell


@numba.njit(cache=True)
def _bfs_kernel(mask, shape, periodic, offsets, sources, target):
    """Breadth-first search over flat cells; returns the flat path or an empty array.

    The queue is first in, first out, so the first target cell queued is the first one a
    search that looks at the cells it takes out would reach: the search stops there. Each
    cell keeps the index of the step (a row of `offsets`) that reached it, one byte, and
    the path is walked back by those steps.
    """
    total = mask.shape[0]
    dims = shape.shape[0]
    came = np.full(total, _UNSEEN, dtype=np.uint8)
    queue = np.empty(total, dtype=np.int32)
    tail = 0
    end = -1
    for s in sources:
        if mask[s] and came[s] == _UNSEEN:
            came[s] = _SOURCE
            queue[tail] = s
            tail += 1
            if end < 0 and target[s]:
                end = s
    index = np.empty(dims, dtype=np.int64)
    jumps = np.zeros(offsets.shape[0], dtype=np.int64)  # flat steps to the neighbours
    for o in range(offsets.shape[0]):
        for d in range(dims):
            jumps[o] = jumps[o] * shape[d] + offsets[o, d]
    head = 0
    while end < 0 and head < tail:
        cell = queue[head]
        head += 1
        rest = cell
        interior = True
        for d in range(dims - 1, -1, -1):
            index[d] = rest % shape[d]
            rest //= shape[d]
            interior = interior and 0 < index[d] < shape[d] - 1
        for o in range(offsets.shape[0]):
            if interior:  # no neighbour across a face of the grid: a flat step suffices
                flat = cell + jumps[o]
            else:
                flat = 0
                for d in range(dims):
                    value = index[d] + offsets[o, d]
                    if value < 0 or value >= shape[d]:
                        if not periodic[d]:
                            flat = -1
                            break
                        value %= shape[d]
                    flat = flat * shape[d] + value
                if flat < 0:
                    continue
            if mask[flat] and came[flat] == _UNSEEN:
                came[flat] = o
                queue[tail] = flat
                tail += 1
                if target[flat]:
                    end = flat
                    break
    if end < 0:
        return np.empty(0, dtype=np.int64)
    length = 1
    cell = end
    while came[cell] != _SOURCE:
        cell = _step_back(cell, offsets[came[cell]], shape, index)
        length += 1
    path = np.empty(length, dtype=np.int64)
    cell = end
    for k in range(length - 1, -1, -1):
        path[k] = cell
        if k:
            cell = _step_back(cell, offsets[came[cell]], shape, index)
    return path


@numba.njit(cache=True)
def _step_back(cell, offset, shape, index):
    """Return the flat cell one step `offset` (d,) before `cell`, round every axis.

    A step never left the grid along an axis that does not wrap, so wrapping undoes it
    exactly. `index` (d,) is scratch space.
    """
    rest = cell
    for d in range(shape.shape[0] - 1, -1, -1):
        index[d] = rest % shape[d]
        rest //= shape[d]
    flat = 0
    for d in range(shape.shape[0]):
        flat = flat * shape[d] + (index[d] - offset[d]) % shape[d]
    return flat


def load_sheet_kernels() -> None:
    """Run the compiled kernels of the recovery sheets once (numba loads them on first use)."""
    from .scene import parse_scene
    from .slices import slice_problem
    scene = parse_scene({'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]},
                         'obstacles': [{'type': 'sphere', 'center': [2.5, 0.0], 'radius': 0.2}],
                         'task': {'start': [2.0, 0.5], 'goal': [1.0, 0.5]}})
    grid = tolerant_set(scene, 32)
    proves_no(grid)  # the liberal side's kernels too
    pooled_tolerant_set(grid)
    mask = grid.classes.certified
    components(mask, grid.lattice.periodic).at(np.zeros((1, 3), dtype=np.int64))
    _wrap_index(0, grid.lattice.periodic[0], 4)  # as the builders call it, from Python
    _bfs(mask, grid.lattice.periodic, np.zeros((1, 3), dtype=np.int64), mask)
    _bfs(mask[0], grid.lattice.periodic[1:], np.zeros((1, 2), dtype=np.int64), mask[0])
    _route_cells(np.array([[0.0, 0.0], [1.0, 1.0]]), np.ones(2, dtype=np.bool_), 4)
    for difference in (np.zeros(2), np.zeros(3), np.zeros((2, 2))):
        wrap_steps(difference, np.ones(difference.shape[-1], dtype=np.bool_))
    _greedy_cuts(mask, grid.lattice.periodic, np.array([[0.0, 0, 0], [1, 1, 1], [2, 2, 2]]), 16)
    _greedy_cuts(mask[0], grid.lattice.periodic[1:], np.array([[0.0, 0], [1, 1], [2, 2]]), 16)
    _triangle_free(mask[0], np.zeros(2), np.ones(2), np.array([0.0, 1.0]),
                   grid.lattice.periodic[1:])
    _TriangleCheck(scene)(np.eye(3))
    paths = np.zeros((2, 2, 3))
    paths[:, 1, 0] = 1.0
    paths[1, :, 1] = 1.0
    slice_problem(FailureSurface(paths, 0, (), ()), (0,))
