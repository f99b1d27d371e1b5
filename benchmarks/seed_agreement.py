"""Whether plans of 3-D position tasks on 7-joint arms hinge on the seed (issue 35, item 5).

    .venv/bin/python benchmarks/seed_agreement.py --seeds 10 --bench-tasks 4

Plans every free-space position task (redundancy 4: planned on curves, every joint
tolerated) with seeds 0 .. seeds-1 and prints a table task x seed (Y: a verified plan,
n: none) with each plan's time [s] and whether the seeds agree. The tasks are the scenes
`panda_free_position` and `iiwa_free_position` and, per arm, the first `--bench-tasks` of
the spatial benchmark's tasks (`ftplan bench --robot ...`, its seed 0) with their
obstacles taken away and only the positions of their start and goal kept.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from ftplan_ros.bench.spatial import random_task
from ftplan_ros.core import Scene, Task, load_scene, plan

SCENES = Path(__file__).resolve().parents[1] / 'config' / 'scenes'


def free_position_tasks(bench_tasks: int) -> dict[str, Scene]:
    """Name -> free-space position task (see the module docstring)."""
    tasks = {name: load_scene(SCENES / f'{name}.yaml')
             for name in ('panda_free_position', 'iiwa_free_position')}
    for robot in ('panda', 'iiwa14'):
        rng = np.random.default_rng(0)
        for k in range(bench_tasks):
            pose = random_task(robot, rng)
            task = Task(tuple(pose.task.start[:3]), tuple(pose.task.goal[:3]),
                        pose.task.goal_tolerance)
            tasks[f'{robot} bench {k}'] = Scene(pose.robot).with_task(task)
    return tasks


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--seeds', type=int, default=10, help='seeds 0 .. SEEDS-1 (10)')
    parser.add_argument('--bench-tasks', type=int, default=4,
                        help="the spatial benchmark's tasks per arm (4)")
    args = parser.parse_args()
    seeds = range(args.seeds)
    print(f'{"task":<22}' + ''.join(f'{seed:>7}' for seed in seeds) + '  agree')
    disagreements = 0
    for name, scene in free_position_tasks(args.bench_tasks).items():
        cells, answers = [], set()
        for seed in seeds:
            started = time.perf_counter()
            result = plan(scene, rng=np.random.default_rng(seed))
            answers.add(result.feasible)
            cells.append(f'{"Y" if result.feasible else "n"} {time.perf_counter() - started:4.1f}')
        disagreements += len(answers) > 1
        print(f'{name:<22}' + ''.join(f'{cell:>7}' for cell in cells) +
              f'  {"yes" if len(answers) == 1 else "NO"}', flush=True)
    print(f'tasks whose seeds disagree: {disagreements}', file=sys.stderr)
    return 1 if disagreements else 0


if __name__ == '__main__':
    raise SystemExit(main())
