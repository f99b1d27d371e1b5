"""Plans for an arm standing at q: a plan it can get to, or what is known of why not.

`plan_from` is the planner's entry point when the arm's configuration q (n,) [rad] is
known. It answers one of three (`Outcome`):

- a plan with a certified approach: a failure-tolerant plan, and a path from q to its
  θ_s (plus whole turns) certified collision-free (approach.py);
- none reachable (proved): no failure-tolerant plan starts where the arm can get to,
  because none exists at all (a joint grid proved it), or because joint grids prove that
  every start that may be failure-tolerant lies beyond every collision-free path from q
  (grid/start_reach.py);
- none found within the search: neither, and the answer says how far it looked.

The search, cheapest first:

1. `core.plan`, preferring the starts on the arc of M_s^F through q (reached by
   self-motion); its θ_s approached along that arc, along M_s, straight, or through the
   certified cells of a 64^3 joint grid.
2. Planar 3R arms among disks: joint grids of 64 cells per joint and finer, up to
   `ApproachOptions.proof_cells`, in turn (`StartReach`): a path to θ_s through the
   grid's certified free cells; the proof that no start within reach may be
   failure-tolerant; plans from the exact starts the grid puts within reach, likeliest
   first, `reach_starts` in all, each approached through the grid's cells.
3. RRT-Connect from q to θ_s (`rrt_attempts` x `rrt_time`).
4. Arms with one degree of redundancy: the free arcs of M_s that a joint move from q
   reaches (RRT-Connect for each), preferred in another plan.

The plans' starts are clear by the plan's margin, the approaches' paths by their own:
the grids take the smaller, so that a proof covers both.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum

import numpy as np

from ..collision.checker import CollisionChecker
from ..grid.free_components import proof_grids
from ..grid.start_reach import StartReach, start_reach
from ..model.angles import configuration_difference
from ..model.scene import Scene
from ..paper.manifolds import ManifoldCache
from ..paper.options import PlannerOptions
from ..paper.result import PlanResult
from .approach import Approach, ApproachOptions, ApproachPlanner, Route
from .planner import plan


class Outcome(StrEnum):
    """What `plan_from` found (the value is what reports say)."""

    PLANNED = 'plan with a certified approach'
    NONE_REACHABLE = 'none reachable (proved)'
    NONE_FOUND = 'none found within the search'


@dataclass(frozen=True, eq=False)
class ReachablePlan:
    """The answer for an arm standing at q.

    `result`: the plan the arm gets to (PLANNED), else the first plan found (which starts
    where no approach reached) or why there is none. `approach`: the certified path from q
    to its θ_s, else why there is none (None without a plan). `reason`: why no plan is for
    this arm (empty when PLANNED); `searched`: how far the search looked.
    """

    outcome: Outcome
    result: PlanResult
    approach: Approach | None
    reason: str = ''
    searched: str = ''

    @property
    def ok(self) -> bool:
        """Whether there is a plan with a certified approach."""
        return self.outcome is Outcome.PLANNED


def plan_from(scene: Scene, q: np.ndarray, options: PlannerOptions | None = None,
              rng: np.random.Generator | None = None,
              progress: Callable[[str], None] | None = None,
              cache: ManifoldCache | None = None,
              approach_options: ApproachOptions | None = None) -> ReachablePlan:
    """Plan the scene's task for an arm standing at q (n,) [rad]; see the module docstring.

    `options`, `rng`, `progress` and `cache` are `core.plan`'s, for every plan of the
    search; `approach_options` default to the plan's margin.
    """
    return ReachSearch(scene, q, options, rng, progress, cache, approach_options).run()


class ReachSearch:
    """The search of `plan_from`, one stage per method; `looked` records how far it went."""

    def __init__(self, scene: Scene, q: np.ndarray, options: PlannerOptions | None = None,
                 rng: np.random.Generator | None = None,
                 progress: Callable[[str], None] | None = None,
                 cache: ManifoldCache | None = None,
                 approach_options: ApproachOptions | None = None):
        self.scene = scene
        self.q = np.asarray(q, dtype=float)
        self.options = options or PlannerOptions()
        self.rng = rng
        self.report = progress or (lambda line: None)
        self.cache = cache
        self.approach_options = approach_options or ApproachOptions(
            margin=self.options.verification.margin)
        self.planner = ApproachPlanner(CollisionChecker(scene.robot, scene.obstacles),
                                       self.approach_options, rng)
        x_s = None if scene.task is None else np.asarray(scene.task.start, dtype=float)
        self.arc = None if x_s is None else self.planner.reachable_arc(x_s, self.q)
        self.margin = min(self.options.verification.margin, self.approach_options.margin)
        self.looked: list[str] = []
        self.tried_starts: list[np.ndarray] = []

    def run(self) -> ReachablePlan:
        """Search in the module docstring's order; stop at the first plan approached or proof."""
        prefer = None if self.arc is None else self.planner.prefer_reachable(self.arc)
        first = self._plan(prefer_starts=prefer)
        if not first.feasible:
            outcome = Outcome.NONE_REACHABLE if first.proved_infeasible else Outcome.NONE_FOUND
            return ReachablePlan(outcome, first, None, first.reason, 'one plan from anywhere')
        self.looked.append('a plan preferring the starts on the arm\'s arc of M_s^F' if
                           self.arc is not None else 'a plan from anywhere')
        found = self.planner.approach(self.q, first.theta_s, arc=self.arc, rrt=False)
        if found.ok:
            return self._planned(first, found)
        answer = self._on_grids(first)
        if answer is not None:
            return answer
        found = self.planner.joint_move(self.q, first.theta_s)
        self.looked.append(f'RRT-Connect to its theta_s ({self.approach_options.rrt_attempts} '
                           f'x {self.approach_options.rrt_time:g} s)')
        if found.ok:
            return self._planned(first, found)
        answer = self._on_other_arcs(first)
        if answer is not None:
            return answer
        return ReachablePlan(Outcome.NONE_FOUND, first, found, 'no failure-tolerant plan '
                             f'found that starts where the arm can get to; one starts at '
                             f'theta_s = {_angles(first.theta_s)} rad, which no approach '
                             f'reached: {found.reason}', self._searched())

    def _plan(self, **kwargs) -> PlanResult:
        return plan(self.scene, self.options, self.rng, self.report, cache=self.cache, **kwargs)

    def _planned(self, result: PlanResult, approach: Approach) -> ReachablePlan:
        return ReachablePlan(Outcome.PLANNED, result, approach, '', self._searched())

    def _searched(self) -> str:
        return '; '.join(self.looked)

    # Stage 2: joint grids -----------------------------------------------------------

    def _on_grids(self, first: PlanResult) -> ReachablePlan | None:
        """Try each grid (coarse first): a path to θ_s, the proof, plans from starts in reach."""
        for cells in proof_grids(self.approach_options.proof_cells):
            reach = start_reach(self.scene, self.q, self.margin, cells)
            if reach is None:
                continue
            self.report(f'looking for failure-tolerant starts within reach on {cells}^3 cells')
            found = self.planner.through_cells(self.q, first.theta_s, reach.walls)
            if found.ok:
                self.looked.append(f'the certified cells of a {cells}^3 joint grid')
                return self._planned(first, found)
            if reach.proved_none:
                self.looked.append(f'joint grids up to {cells}^3 cells')
                return self._proved_none(first, cells)
            planned = self._from_starts(reach)
            self.looked.append(f'a {cells}^3 joint grid: not proved that no start within '
                               f'reach is failure-tolerant; {_count(self.tried_starts, "start")} '
                               f'within reach planned from so far')
            if planned is not None:
                return self._planned(*planned)
        return None

    def _from_starts(self, reach: StartReach) -> tuple[PlanResult, Approach] | None:
        """Plan from the grid's starts within reach not tried yet; the first one approached."""
        tolerance = self.approach_options.arc_tolerance
        periodic = self.scene.robot.periodic
        for theta in reach.starts:
            if len(self.tried_starts) >= self.approach_options.reach_starts:
                return None
            if any(np.abs(configuration_difference(theta, tried, periodic)).max() <= tolerance
                   for tried in self.tried_starts):
                continue
            self.tried_starts.append(theta)
            result = self._plan(start_configuration=theta)
            if not result.feasible:
                continue
            found = self.planner.approach(self.q, result.theta_s, arc=self.arc, rrt=False)
            if not found.ok:
                found = self.planner.through_cells(self.q, result.theta_s, reach.walls)
            if found.ok:
                return result, found
        return None

    def _proved_none(self, first: PlanResult, cells: int) -> ReachablePlan:
        clear = f', clear by more than {self.margin:g} m' if self.margin > 0 else ''
        return ReachablePlan(Outcome.NONE_REACHABLE, first, Approach(
            None, Route.NONE, f'no collision-free path reaches its theta_s (proved on the '
            f'{cells}^3 joint grid)'),
            f'no failure-tolerant plan starts where the arm can get to from here (proved on '
            f'a {cells}^3 joint grid: no start that may be failure-tolerant lies in its '
            f'component of possibly free cells{clear}); one starts at theta_s = '
            f'{_angles(first.theta_s)} rad, out of the arm\'s reach', self._searched())

    # Stage 4: the other arcs of M_s ---------------------------------------------------

    def _on_other_arcs(self, first: PlanResult) -> ReachablePlan | None:
        """Prefer the free arcs of M_s a joint move reaches in another plan; approach it."""
        exclude = [first.theta_s, self.q if self.arc is None else self.arc[0]]
        arcs, tried = _joint_move_arcs(self.planner, self.q, first, exclude)
        self.looked.append(f'{_count(range(tried), "other free arc")} of M_s, {len(arcs)} '
                           f'reached by a joint move')
        if not arcs:
            return None
        second = self._plan(prefer_starts=self.planner.prefer_reachable(np.vstack(arcs)))
        if not second.feasible:
            return None
        found = self.planner.approach(self.q, second.theta_s, arc=self.arc)
        return self._planned(second, found) if found.ok else None


def _joint_move_arcs(planner: ApproachPlanner, q: np.ndarray, result: PlanResult,
                     exclude: list[np.ndarray]) -> tuple[list[np.ndarray], int]:
    """Return the free arcs (k, n) of the plan's M_s reached from q by a joint move.

    Arcs holding a configuration of `exclude` (q's own, the θ_s that failed) are left
    out; each other arc is tried at its middle point. Also returns how many were tried.
    """
    robot = planner.robot
    reached, tried = [], 0
    for branch in result.start_manifolds:
        if branch.clearance is None:
            continue
        for first, count in branch.free_arcs(planner.options.margin):
            points = branch.arc_points(first, count)
            if any(np.min(np.max(np.abs(configuration_difference(points, theta, robot.periodic)),
                                 axis=1)) <= planner.options.arc_tolerance for theta in exclude):
                continue
            tried += 1
            if planner.joint_move(q, points[len(points) // 2]).ok:
                reached.append(points)
    return reached, tried


def _angles(theta: np.ndarray) -> str:
    """θ (n,) [rad] as '[a, b, c]' to 4 decimals."""
    return '[' + ', '.join(f'{v:.4f}' for v in theta) + ']'


def _count(items, noun: str) -> str:
    """'1 start', '3 starts'."""
    return f'{len(items)} {noun}' + ('' if len(items) == 1 else 's')
