"""Benchmark: the planner against the exhaustive grid baseline, on the same scenes, in one run.

Seeded random scenes for the paper's arm: random start and goal positions and 0-20
random disks (radius 0.1-0.3 m), plus a group with exactly 10 disks. For each scene the
planner runs cold (self-motion manifolds traced) and warm (manifolds cached, as the
planner node serves repeated requests for one task), and the grid baseline (flood fill
in every failure plane) runs once. Where the planner says feasible and the grid does
not, the referee decides: the planner's nominal path is checked at 9 moments for every
joint with an over-approximating flood fill in the failure plane (1 deg cells), whose
"no" would prove the plan wrong. Times are ratios within this run, never absolute claims.
"""

from __future__ import annotations

import json
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .core import CollisionChecker, ManifoldCache, parse_scene, plan
from .core.brute_force import grid_plan, recoverable_in_plane
from .core.paths import point_at_fraction
from .core.scene import Scene


@dataclass(frozen=True)
class SceneRun:
    """One scene's answers and times [s]."""

    group: str
    disks: int
    planner_feasible: bool
    planner_cold_s: float
    planner_warm_s: float
    grid_feasible: bool
    grid_s: float
    refuted: bool   # the referee found a lock on the nominal path with no way to the goal
    reason: str


def random_scene(rng: np.random.Generator, disks: int) -> Scene:
    """Make the paper's arm a random task among `disks` random disks clear of base, start, goal."""
    start = _polar(rng.uniform(1.8, 2.6), rng.uniform(-np.pi, np.pi))
    goal = _polar(rng.uniform(0.9, 1.5), rng.uniform(-np.pi, np.pi))
    obstacles = []
    while len(obstacles) < disks:
        radius = rng.uniform(0.1, 0.3)
        center = _polar(rng.uniform(0.3, 3.0), rng.uniform(-np.pi, np.pi))
        if min(np.linalg.norm(center), np.linalg.norm(center - start),
               np.linalg.norm(center - goal)) > radius + 0.05:
            obstacles.append({'type': 'sphere', 'center': center.round(3).tolist(),
                              'radius': round(float(radius), 3)})
    return parse_scene({'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]},
                        'obstacles': obstacles,
                        'task': {'start': start.round(3).tolist(),
                                 'goal': goal.round(3).tolist()}}, name='random')


def run_scene(scene: Scene, group: str, cells: int) -> SceneRun:
    """Plan the scene cold and warm, run the grid baseline, referee a disagreement."""
    cache = ManifoldCache()
    started = time.perf_counter()
    result = plan(scene, cache=cache)
    cold = time.perf_counter() - started
    started = time.perf_counter()
    plan(scene, cache=cache)
    warm = time.perf_counter() - started
    checker = CollisionChecker(scene.robot, scene.obstacles)
    x_s, x_g = np.asarray(scene.task.start), np.asarray(scene.task.goal)
    started = time.perf_counter()
    grid = grid_plan(checker, x_s, x_g, cells)
    grid_time = time.perf_counter() - started
    refuted = (result.feasible and not grid.feasible
               and not referee_agrees(checker, result, x_g, scene.task.goal_tolerance))
    return SceneRun(group, len(scene.obstacles), result.feasible, cold, warm, grid.feasible,
                    grid_time, refuted, result.reason)


def referee_agrees(checker: CollisionChecker, result, x_goal: np.ndarray,
                   goal_tolerance: float, moments: int = 9, cells: int = 360) -> bool:
    """Whether every lock at `moments` points of the nominal path may still reach x_g.

    Reaching means coming within `goal_tolerance` [m], as the guarantee says.
    """
    return all(recoverable_in_plane(checker, point_at_fraction(result.nominal_path, f), joint,
                                    x_goal, cells, goal_tolerance=goal_tolerance)
               for f in np.linspace(0.0, 1.0, moments)
               for joint in range(checker.robot.n_joints))


def run_benchmark(scenes: int, seed: int, cells: int, json_path: Path | None,
                  progress) -> int:
    """Run `scenes` random scenes and `scenes` 10-disk scenes; print the table; 1 if unsound."""
    rng = np.random.default_rng(seed)
    plan_of = [('0-20 disks', int(rng.integers(0, 21))) for _ in range(scenes)]
    plan_of += [('10 disks', 10) for _ in range(scenes)]
    runs = []
    for k, (group, disks) in enumerate(plan_of):
        runs.append(run_scene(random_scene(rng, disks), group, cells))
        progress.count(k + 1, len(plan_of))
    print(summarize(runs, cells))
    if json_path is not None:
        json_path.parent.mkdir(parents=True, exist_ok=True)
        json_path.write_text(json.dumps([asdict(run) for run in runs], indent=1))
    return 1 if any(r.refuted for r in runs) else 0


def summarize(runs: list[SceneRun], cells: int) -> str:
    """Tabulate times, ratios and how the answers compare, per group."""
    lines = [f'grid baseline: {cells}^3 cells ({360 / cells:.1f} deg), flood fill in every '
             'failure plane, then a path search',
             f'{"group":<22}{"scenes":>7}{"planner cold p50/p95 [ms]":>28}'
             f'{"warm p50/p95 [ms]":>20}{"grid p50/p95 [ms]":>20}{"grid/warm":>11}'
             f'{"grid/cold":>11}']
    groups = sorted({r.group for r in runs})
    selections = [(g, [r for r in runs if r.group == g]) for g in groups]
    selections += [(f'{g}, feasible', [r for r in runs if r.group == g and r.planner_feasible])
                   for g in groups]
    for name, rows in selections:
        if not rows:
            continue
        cold, warm, grid = (np.array([getattr(r, a) for r in rows]) * 1e3
                            for a in ('planner_cold_s', 'planner_warm_s', 'grid_s'))
        lines.append(f'{name:<22}{len(rows):>7}{_p(cold):>28}{_p(warm):>20}{_p(grid):>20}'
                     f'{np.median(grid) / np.median(warm):>10.0f}x'
                     f'{np.median(grid) / np.median(cold):>10.0f}x')
    agree = sum(r.planner_feasible == r.grid_feasible for r in runs)
    feasible_only = sum(r.planner_feasible and not r.grid_feasible for r in runs)
    grid_only = sum(r.grid_feasible and not r.planner_feasible for r in runs)
    unsound = sum(r.refuted for r in runs)
    lines += [
        f'answers: planner feasible in {sum(r.planner_feasible for r in runs)}/{len(runs)}, '
        f'centre-sampled grid in {sum(r.grid_feasible for r in runs)}/{len(runs)}; they agree '
        f'on {agree}/{len(runs)} ({agree / len(runs):.0%})',
        f'planner feasible, centre-sampled grid not: {feasible_only}; grid feasible, planner '
        f'not: {grid_only}',
        f'planner feasible, grid not, and the referee proves a lock unrecoverable: '
        f'{unsound} (must be 0)',
    ]
    return '\n'.join(lines)


def _p(values: np.ndarray) -> str:
    return f'{np.percentile(values, 50):.0f} / {np.percentile(values, 95):.0f}'


def _polar(radius: float, angle: float) -> np.ndarray:
    return radius * np.array([np.cos(angle), np.sin(angle)])
