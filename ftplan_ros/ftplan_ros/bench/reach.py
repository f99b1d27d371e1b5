"""Benchmark: plans from where the arm stands, against an independent check by brute force.

For each crowded planar scene (crowded.py) and the arm standing at a given configuration
q (the benchmark script passes the sim's default start), in one run:

* the planner's answer (`core.planning.reachable.plan_from`): a plan with a certified
  approach, none reachable (proved), or none found within the search; and its time;
* `independent_reach`, which shares no code with the planner's grids: a flood fill from
  q's cell over the possibly free cells of an exhaustive joint grid (each cell's centre
  clearance plus the cell's motion bound: `exhaustive.possibly_free`) bounds where the arm
  can get to from above; each exact start of M_s in that component is asked, joint by
  joint, whether the arm there may still reach the goal with the joint locked
  (`exhaustive.recoverable_in_plane`, an over-approximating flood fill of the failure
  plane). When no start may, no failure-tolerant start lies within reach (at those
  samples of M_s, and at the plan's θ_s if there is one);
* a plan found is checked: its approach starts at q, ends at θ_s plus whole turns, and
  sampled every `SAMPLE_STEP` rad is clear by more than the margin; the referee
  (`scenes.referee_accepts`) accepts the plan.

A contradiction is a plan whose check fails, or a plan with an approach where the
independent check finds no start that may be failure-tolerant within reach. A proof of
none reachable where the independent check finds one that may be is a disagreement the
table counts (the check's cells may be too coarse to see the gap), not a contradiction.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from ..core import CollisionChecker
from ..core.grid.exhaustive import JointGrid, label_periodic, possibly_free, recoverable_in_plane
from ..core.grid.tolerant_set import preimage_samples
from ..core.model.paths import densify
from ..core.model.scene import Scene
from ..core.planning.reachable import Outcome, ReachablePlan, plan_from
from .scenes import referee_accepts

SAMPLE_STEP = 0.002  # [rad] between the samples of an approach the check measures


@dataclass(frozen=True)
class IndependentReach:
    """The brute-force answer: starts of M_s within reach, and those that may be tolerant."""

    starts_in_reach: int      # exact starts in q's component of possibly free cells
    maybe_tolerant: int       # of them, those every joint's lock may still recover from
    time_s: float

    @property
    def none(self) -> bool:
        """Whether no start within reach may be failure-tolerant."""
        return self.maybe_tolerant == 0


def independent_reach(scene: Scene, q: np.ndarray, extra_starts: np.ndarray | None = None,
                      cells: int = 160, plane_cells: int = 180, samples: int = 720,
                      stop_at_first: bool = True) -> IndependentReach:
    """Check by brute force whether a start that may be failure-tolerant lies within q's reach.

    `cells` per joint of the flood fill of joint space, `plane_cells` of each failure
    plane's, `samples` exact starts of M_s (one per angle of the last link, both elbows),
    plus `extra_starts` (s, 3) [rad]. With `stop_at_first` the count of starts that may be
    tolerant stops at 1.
    """
    started = time.perf_counter()
    robot, task = scene.robot, scene.task
    checker = CollisionChecker(robot, scene.obstacles)
    grid = JointGrid.over(robot, cells)
    labels = label_periodic(possibly_free(checker, grid.centers(), 0.5 * grid.step),
                            grid.periodic)
    mine = labels[grid.cell_of(q)]
    starts = preimage_samples(np.asarray(robot.link_lengths, dtype=float),
                              np.asarray(task.start, dtype=float), samples // 2)
    if extra_starts is not None:
        starts = np.vstack([starts, np.asarray(extra_starts, dtype=float).reshape(-1, 3)])
    starts = starts[checker.min_clearance(starts) > 0.0]
    within = [theta for theta in starts if mine > 0 and labels[grid.cell_of(theta)] == mine]
    maybe = 0
    for theta in within:
        if all(recoverable_in_plane(checker, theta, joint, np.asarray(task.goal, dtype=float),
                                    plane_cells, goal_tolerance=task.goal_tolerance)
               for joint in scene.tolerated_joints):
            maybe += 1
            if stop_at_first:
                break
    return IndependentReach(len(within), maybe, time.perf_counter() - started)


def approach_checks(scene: Scene, q: np.ndarray, answer: ReachablePlan,
                    margin: float = 0.0) -> bool:
    """Whether a plan's approach joins q to θ_s (plus whole turns) clear by > margin [m]."""
    path = answer.approach.path
    turns = (path[-1] - answer.result.theta_s) / (2.0 * np.pi)
    periodic = scene.robot.periodic
    ends = np.array_equal(path[0], q) and np.allclose(
        np.where(periodic, turns - np.round(turns), turns), 0.0, atol=1e-9)
    checker = CollisionChecker(scene.robot, scene.obstacles)
    return bool(ends and checker.min_clearance(densify(path, SAMPLE_STEP)).min() > margin)


@dataclass(frozen=True)
class ReachRun:
    """One scene's answers, checks and times [s]."""

    index: int
    outcome: str
    plan_s: float
    independent_none: bool
    starts_in_reach: int
    independent_s: float
    checked: bool            # a plan's approach and guarantee pass their checks (True without)
    contradiction: bool
    route: str
    searched: str
    reason: str


def run_reach_scene(scene: Scene, q: np.ndarray, index: int, cells: int = 160) -> ReachRun:
    """Plan for the arm at q, check the answer and the starts within reach independently."""
    started = time.perf_counter()
    answer = plan_from(scene, q)
    plan_s = time.perf_counter() - started
    extra = answer.result.theta_s if answer.ok else None
    independent = independent_reach(scene, q, extra, cells=cells)
    checked = True
    if answer.ok:
        checked = approach_checks(scene, q, answer) and referee_accepts(
            CollisionChecker(scene.robot, scene.obstacles), answer.result,
            np.asarray(scene.task.goal), scene.task.goal_tolerance)
    contradiction = not checked or (answer.ok and independent.none)
    route = answer.approach.route.value if answer.ok else ''
    return ReachRun(index, answer.outcome.value, plan_s, independent.none,
                    independent.starts_in_reach, independent.time_s, checked, contradiction,
                    route, answer.searched, answer.reason)


def summarize_reach(runs: list[ReachRun]) -> str:
    """Return the table: outcomes against the independent check, times p50/p95/max [s]."""
    lines = [f'{"outcome":<32}{"scenes":>7}{"indep. none":>13}{"indep. maybe":>14}'
             f'{"plan p50":>10}{"p95":>8}{"max":>8}']
    for outcome in Outcome:
        mine = [r for r in runs if r.outcome == outcome.value]
        times = np.array([r.plan_s for r in mine])
        stats = (f'{np.percentile(times, 50):>10.2f}{np.percentile(times, 95):>8.2f}'
                 f'{times.max():>8.2f}') if len(mine) else f'{"-":>10}{"-":>8}{"-":>8}'
        none = sum(r.independent_none for r in mine)
        lines.append(f'{outcome.value:<32}{len(mine):>7}{none:>13}{len(mine) - none:>14}{stats}')
    every = np.array([r.plan_s for r in runs])
    check = np.array([r.independent_s for r in runs])
    lines.append(f'{len(runs)} scenes: plan_from p50 {np.percentile(every, 50):.2f} s, p95 '
                 f'{np.percentile(every, 95):.2f} s; the independent check p50 '
                 f'{np.percentile(check, 50):.2f} s; contradictions: '
                 f'{sum(r.contradiction for r in runs)}')
    routes = sorted({r.route for r in runs if r.route})
    lines.append('approaches: ' + ', '.join(
        f'{route} {sum(r.route == route for r in runs)}' for route in routes))
    return '\n'.join(lines)

