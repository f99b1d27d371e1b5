"""Benchmark: how many existing failure-tolerant plans the planner finds, and how fast.

Two groups of seeded scenes for the paper's arm: random scenes (random start and goal,
0-20 random disks; bench/scenes.py) and crowded scenes (disks added next to the arm's own start
and goal poses while a plan still exists; bench/crowded.py). For each scene, in one run:

* the existence decision (core/grid/existence.py; "reference" in the tables) decides on
  an N^3 joint grid whether a plan exists: YES and NO are proofs, UNSURE means the grid
  is too coarse;
* the planner runs cold (manifolds traced) and warm (manifolds cached), and says which
  method produced its plan (the paper's surface or recovery sheets);
* every plan it returns is refereed: the existence decision must not have proved that
  none exists, and the referee (`scenes.referee_accepts`) must accept it: at 9 moments
  of the nominal path every joint's lock must be recoverable by an over-approximating
  flood fill of its failure plane (1 deg cells), whose "no" would prove the guarantee
  false.

Recall is the share of the existence decision's YES scenes the planner solves. Times are
p50/p95 within this run; the ratio is the existence decision's p50 over the planner's.
With the exhaustive grid baseline (`--grid-baseline N`), `exhaustive.grid_plan` also runs on N^3
cells (180: 2 deg, the baseline the issue first measured against); it samples cell centres,
so its answers prove nothing, and the table gives its p50 and the ratio to it besides.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..core import CollisionChecker, ManifoldCache, load_kernels, plan
from ..core.grid.exhaustive import grid_plan
from ..core.grid.existence import Existence, decide_existence
from ..core.io.fingerprint import scene_to_dict
from ..core.model.scene import Scene
from .crowded import crowded_scene
from .scenes import random_scene, referee_accepts

GROUPS = ('random', 'crowded')


@dataclass(frozen=True)
class RecallRun:
    """One scene's answers and times [s]."""

    group: str
    index: int
    disks: int
    existence: str           # the existence decision: yes, no or unsure
    existence_s: float
    feasible: bool
    method: str              # of the plan ('' without one)
    cold_s: float
    warm_s: float
    refuted: bool            # a plan the existence decision or the referee proves wrong
    proved_infeasible: bool  # the planner itself proved that no plan exists
    reason: str
    scene: dict
    grid_baseline_s: float | None = None  # the grid baseline's time, when it ran
    grid_baseline_feasible: bool | None = None


def run_recall_benchmark(scenes: int, seed: int, cells: int, crowded_cells: int,
                         json_path: Path | None, progress, grid_baseline: int = 0) -> int:
    """Run `scenes` scenes per group; print the tables; return 1 on a false guarantee.

    `grid_baseline` > 0: also time the grid baseline on that many cells per joint.
    """
    load_kernels(random_scene(np.random.default_rng(0), 0).robot)  # not part of the times
    made = []
    for group in GROUPS:
        for k in range(scenes):
            rng = np.random.default_rng([seed, GROUPS.index(group), k])
            if group == 'random':
                made.append((group, k, random_scene(rng, int(rng.integers(0, 21)))))
            else:
                made.append((group, k, crowded_scene(rng, cells=crowded_cells,
                                                     name=f'crowded_{seed}_{k}')))
            progress.count(len(made), 2 * scenes, 'scenes made')
    progress.begin()
    runs = []
    for done, (group, k, scene) in enumerate(made, start=1):
        runs.append(run_scene(scene, group, k, cells, grid_baseline))
        progress.count(done, len(made), 'scenes')
    print(summarize(runs, cells, grid_baseline))
    if json_path is not None:
        json_path.parent.mkdir(parents=True, exist_ok=True)
        json_path.write_text(json.dumps([asdict(run) for run in runs], indent=1,
                                        allow_nan=False))
    return 1 if any(r.refuted for r in runs) else 0


def run_scene(scene: Scene, group: str, index: int, cells: int,
              grid_baseline: int = 0) -> RecallRun:
    """Decide the scene's existence on the grid, plan it cold and warm, referee a plan.

    `grid_baseline` > 0: run the grid baseline on that many cells per joint too.
    """
    answer = decide_existence(scene, cells)
    cache = ManifoldCache()
    started = time.perf_counter()
    result = plan(scene, cache=cache)
    cold = time.perf_counter() - started
    started = time.perf_counter()
    plan(scene, cache=cache)
    warm = time.perf_counter() - started
    refuted = False
    if result.feasible:
        checker = CollisionChecker(scene.robot, scene.obstacles)
        refuted = answer.existence is Existence.NO or not referee_accepts(
            checker, result, np.asarray(scene.task.goal), scene.task.goal_tolerance)
    return RecallRun(group, index, len(scene.obstacles), answer.existence.value, answer.time_s,
                     result.feasible, result.stats.get('method', '') if result.feasible else '',
                     cold, warm, refuted, result.proved_infeasible,
                     result.reason, scene_to_dict(scene), *_grid_baseline(scene, grid_baseline))


def _grid_baseline(scene: Scene, cells: int) -> tuple[float | None, bool | None]:
    """Time [s] and answer of `grid_plan` on cells^3 (None, None when cells is 0)."""
    if cells == 0:
        return None, None
    started = time.perf_counter()
    answer = grid_plan(CollisionChecker(scene.robot, scene.obstacles),
                       np.asarray(scene.task.start), np.asarray(scene.task.goal), cells)
    return time.perf_counter() - started, answer.feasible


def summarize(runs: list[RecallRun], cells: int, grid_baseline: int = 0) -> str:
    """Tabulate recall and false guarantees, then times per group and method.

    With `grid_baseline` cells per joint, the grid baseline's p50 and ratio too, and its
    answers against the existence decision's.
    """
    lines = [f'reference: {cells}^3 joint grid, G from inside (YES proved) and outside '
             '(NO proved); planner cold (manifolds traced) and warm (cached)',
             f'{"group":<10}{"scenes":>7}{"yes":>5}{"no":>5}{"unsure":>7}{"found":>7}'
             f'{"recall":>8}{"paper":>7}{"sheets":>8}{"false":>7}{"no proved":>11}']
    for name, rows in _groups(runs):
        yes = [r for r in rows if r.existence == 'yes']
        no = [r for r in rows if r.existence == 'no']
        found = [r for r in yes if r.feasible]
        recall = f'{len(found) / len(yes):.0%}' if yes else '-'
        proved = f'{sum(r.proved_infeasible for r in no)}/{len(no)}'
        lines.append(
            f'{name:<10}{len(rows):>7}{len(yes):>5}{len(no):>5}'
            f'{sum(r.existence == "unsure" for r in rows):>7}{len(found):>7}{recall:>8}'
            f'{sum(r.method == "paper_surface" for r in found):>7}'
            f'{sum(r.method == "recovery_sheets" for r in found):>8}'
            f'{sum(r.refuted for r in rows):>7}{proved:>11}')
    baseline = f'grid {grid_baseline}^3'
    lines += ['', f'{"times p50 / p95 [ms]":<28}{"scenes":>7}{"cold":>16}{"warm":>16}'
              f'{"reference":>18}{"ref/cold p50":>14}'
              + (f'{baseline + " p50":>18}{"grid/cold p50":>15}' if grid_baseline else '')]
    selections = []
    for name, rows in _groups(runs):
        selections += [(f'{name}: all', rows),
                       (f'{name}: paper_surface', [r for r in rows
                                                   if r.method == 'paper_surface']),
                       (f'{name}: recovery_sheets', [r for r in rows
                                                     if r.method == 'recovery_sheets']),
                       (f'{name}: no plan', [r for r in rows if not r.feasible])]
    for name, rows in selections:
        if not rows:
            continue
        cold, warm, ref = (np.array([getattr(r, a) for r in rows]) * 1e3
                           for a in ('cold_s', 'warm_s', 'existence_s'))
        line = (f'{name:<28}{len(rows):>7}{_p(cold):>16}{_p(warm):>16}{_p(ref):>18}'
                f'{_ratio(np.median(ref) / np.median(cold)):>14}')
        if grid_baseline:
            grid = np.median([r.grid_baseline_s for r in rows]) * 1e3
            line += f'{grid:>18.0f}{_ratio(grid / np.median(cold)):>15}'
        lines.append(line)
    lines.append(f'false guarantees (a plan the reference or the referee refutes): '
                 f'{sum(r.refuted for r in runs)} (must be 0)')
    if grid_baseline:
        says = {verdict: f'{sum(r.grid_baseline_feasible for r in runs if r.existence == verdict)}'
                f' of {sum(r.existence == verdict for r in runs)}'
                for verdict in ('yes', 'no', 'unsure')}
        lines.append(f'{baseline} baseline (cell centres, no proof): a plan exists on '
                     f'{says["yes"]} YES scenes, on {says["no"]} NO scenes and on '
                     f'{says["unsure"]} UNSURE scenes')
    return '\n'.join(lines)


def _ratio(value: float) -> str:
    """Format a ratio of times: whole from 10, one decimal from 1, else two significant digits."""
    return f'{value:.0f}x' if value >= 10 else f'{value:.1f}x' if value >= 1 else f'{value:.2g}x'


def _groups(runs: list[RecallRun]) -> list[tuple[str, list[RecallRun]]]:
    out = [(g, [r for r in runs if r.group == g]) for g in GROUPS]
    return [(g, rows) for g, rows in out if rows] + [('all', runs)]


def _p(values: np.ndarray) -> str:
    return f'{np.percentile(values, 50):.0f} / {np.percentile(values, 95):.0f}'
