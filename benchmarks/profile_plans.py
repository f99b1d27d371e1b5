"""Where the planar planner spends its time, per method, on the scenes of a recall run (issue 9).

    .venv/bin/ftplan bench --scenes 20 --seed 1 --json out/recall.json
    .venv/bin/python benchmarks/profile_plans.py out/recall.json

Each scene of the recall benchmark's JSON is planned once to warm its kernels, then again
under cProfile. Scenes are grouped by how the plan came out (the paper's surface, the
recovery sheets, no plan); for each group it prints the mean plan time [ms] and the share
of it spent in the planner's stages: tracing the manifolds, the paper's surface search and
its verification, the failure-tolerant set G on the joint grids (cell classes, each
joint's escapes from inside and from outside, labelling), the sheets' web, the self-check
of S_F, the proof that no plan exists. Shares overlap where one stage calls another: the
web's share holds the certified escapes (computed as its search asks for them), the
proof's the liberal ones.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import pstats
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

from ftplan_ros.core import parse_scene, plan

# (label, file, function) of the stages reported, in the order printed.
STAGES = (
    ('trace the manifolds', 'manifolds.py', 'trace_branch'),
    ('paper: surface search', 'surface_search.py', '_search'),
    ('paper: verify surfaces', 'surface_search.py', '_verify_best'),
    ('G: cell classes', 'cell_classes.py', 'classify_cells'),
    ('G: certified escapes', 'tolerant_set.py', 'certified_escape'),
    ('G: liberal escapes', 'tolerant_set.py', '_liberal_components'),
    ('  labelling (both sides)', 'components.py', 'components'),
    ('sheets: build the web', 'recovery_sheets.py', '_plan_on'),
    ('verify S_F (either method)', 'verification.py', 'verify_surface'),
    ('prove no plan exists', 'existence.py', 'proves_no'),
)


def profile_scene(scene) -> tuple[str, float, dict[tuple[str, str], float]]:
    """Plan the scene warm under cProfile; return how it came out and the times [s].

    The times are the wall time and the cumulative time of every (file name, function).
    """
    plan(scene, rng=np.random.default_rng(0))
    profiler = cProfile.Profile()
    started = time.perf_counter()
    profiler.enable()
    result = plan(scene, rng=np.random.default_rng(0))
    profiler.disable()
    wall = time.perf_counter() - started
    outcome = result.stats.get('method', '?') if result.feasible else 'no plan'
    cumulative: dict[tuple[str, str], float] = defaultdict(float)
    for (path, _, name), (_, _, _, total, _) in pstats.Stats(profiler).stats.items():
        cumulative[(Path(path).name, name)] += total
    return outcome, wall, cumulative


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('runs', type=Path, help='JSON written by `ftplan bench --json`')
    args = parser.parse_args()
    runs = json.loads(args.runs.read_text())
    walls: dict[str, list[float]] = defaultdict(list)
    stages: dict[str, dict[str, float]] = defaultdict(lambda: defaultdict(float))
    for k, run in enumerate(runs, start=1):
        outcome, wall, cumulative = profile_scene(parse_scene(run['scene'], name=f'scene {k}'))
        walls[outcome].append(wall)
        for label, file, function in STAGES:
            stages[outcome][label] += cumulative.get((file, function), 0.0)
        print(f'\r{k}/{len(runs)} scenes', end='', file=sys.stderr, flush=True)
    print(file=sys.stderr)
    for outcome, times in walls.items():
        total = sum(times)
        print(f'{outcome}: {len(times)} scenes, mean {1000 * total / len(times):.0f} ms')
        for label, _, _ in STAGES:
            share = stages[outcome][label] / total
            if share >= 0.005:
                print(f'  {label:<26}{100 * share:5.1f} %')
    return 0


if __name__ == '__main__':
    raise SystemExit(main())
