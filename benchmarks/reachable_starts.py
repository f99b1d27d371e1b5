"""Plans from the sim's default start on fresh crowded planar scenes, against an independent check.

    .venv/bin/python benchmarks/reachable_starts.py [--scenes 40] [--seed 2024] [--cells 160]
        [--json OUT.json]

Per scene (bench/crowded.py's crowded_scene with seed [SEED, 1, k], as `ftplan bench`
makes its crowded group): the arm stands at the sim's default start (the clearest
configuration of M_s), `plan_from` answers (a plan with a certified approach, none
reachable (proved), none found within the search), and ftplan_ros/bench/reach.py checks
the answer and, by brute force, whether a start that may be failure-tolerant lies within
the arm's reach. Prints one line per scene and the table; exit 1 on a contradiction.
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from pathlib import Path

import numpy as np

from ftplan_ros.bench.crowded import crowded_scene
from ftplan_ros.bench.reach import run_reach_scene, summarize_reach
from ftplan_ros.core import load_kernels
from ftplan_ros.nodes.sim import default_initial_configuration
from ftplan_ros.progress import Progress


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--scenes', type=int, default=40)
    parser.add_argument('--seed', type=int, default=2024)
    parser.add_argument('--cells', type=int, default=160,
                        help='cells per joint of the independent flood fill (160)')
    parser.add_argument('--json', type=Path, default=None)
    args = parser.parse_args()
    progress = Progress()
    runs = []
    for k in range(args.scenes):
        scene = crowded_scene(np.random.default_rng([args.seed, 1, k]), cells=128,
                              name=f'crowded_{args.seed}_{k}')
        if k == 0:
            load_kernels(scene.robot)  # not part of the times
        q = default_initial_configuration(scene)
        run = run_reach_scene(scene, q, k, args.cells)
        runs.append(run)
        progress.line(f'scene {k}: {run.outcome} in {run.plan_s:.2f} s '
                      f'({run.route or run.reason[:90]}); '
                      f'independent: {"none" if run.independent_none else "some"} of '
                      f'{run.starts_in_reach} starts within reach may be tolerant'
                      + ('; CONTRADICTION' if run.contradiction else ''))
    print(summarize_reach(runs))
    if args.json is not None:
        args.json.write_text(json.dumps([asdict(r) for r in runs], indent=1))
    return 1 if any(r.contradiction for r in runs) else 0


if __name__ == '__main__':
    sys.exit(main())
