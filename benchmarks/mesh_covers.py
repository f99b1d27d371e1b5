"""The Panda of franka's own meshes against the primitive Panda, on the same tasks.

    .venv/bin/python benchmarks/mesh_covers.py --robots DIR [--tasks 20] [--seed 0] [--json F]

DIR is example-robot-data's `robots` folder (the one holding panda_description/), or
the environment's FTPLAN_ROBOTS_DIR. The mesh Panda is panda_description's URDF: ten
convex STL collision meshes (link0-7, the hand; the fingers are boxes), read with
`package://` paths looked up two folders above DIR. Both Pandas get the self-collision
exceptions of config/robots/panda.yaml, so that only the geometry differs.

The tasks are config/scenes/panda_shelf.yaml, then random pose tasks among 10 random
obstacles (ftplan_ros/bench/spatial.py). Each is planned cold by both Pandas with one
seed; the kernels are loaded first. Printed: each task's answers and times, then per
Panda the plans found and the plan time's p50/p95, the mesh Panda's ratios to the
primitive one's, and the share of tasks where both answer alike (plan or no plan).
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import yaml

from ftplan_ros.bench.spatial import random_task
from ftplan_ros.core import load_kernels, load_scene, plan, robot_from_urdf

REPO = Path(__file__).resolve().parents[1]
PANDA = REPO / 'config' / 'robots' / 'panda.yaml'
SHELF = REPO / 'config' / 'scenes' / 'panda_shelf.yaml'


def mesh_panda(robots: Path):
    """The Panda of panda_description's URDF, with panda.yaml's self-collision exceptions."""
    description = robots / 'panda_description'
    xml = (description / 'urdf' / 'panda.urdf').read_text()
    exceptions = yaml.safe_load(PANDA.read_text())['robot']['disabled_collisions']
    return robot_from_urdf(xml, 'panda_hand_tcp', 'panda_link0',
                           disabled_collisions=exceptions, mesh_dirs=[str(robots.parents[1])])


def tasks(count: int, seed: int) -> list:
    """panda_shelf, then `count` - 1 random pose tasks (bench/spatial.py) of the primitive Panda."""
    rng = np.random.default_rng(seed)
    return [load_scene(SHELF)] + [random_task('panda', rng) for _ in range(count - 1)]


def timed_plan(scene, seed: int) -> tuple[bool, float, str]:
    """Plan cold; return (feasible, plan time [s], reason)."""
    started = time.perf_counter()
    result = plan(scene, rng=np.random.default_rng(seed))
    return result.feasible, time.perf_counter() - started, result.reason


def summary(rows: list[dict]) -> dict:
    """Plans found, p50/p95 [s] per Panda, the ratios mesh / primitive and the agreement."""
    out = {}
    for name in ('primitive', 'mesh'):
        times = np.array([row[name]['time_s'] for row in rows])
        out[name] = {'plans': sum(row[name]['feasible'] for row in rows),
                     'p50_s': float(np.percentile(times, 50)),
                     'p95_s': float(np.percentile(times, 95))}
    for stat in ('p50_s', 'p95_s'):
        out[f'ratio_{stat[:3]}'] = out['mesh'][stat] / out['primitive'][stat]
    agree = sum(row['primitive']['feasible'] == row['mesh']['feasible'] for row in rows)
    out['agreement'] = agree / len(rows)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--robots', type=Path, default=os.environ.get('FTPLAN_ROBOTS_DIR'),
                        help="example-robot-data's robots folder (default: $FTPLAN_ROBOTS_DIR)")
    parser.add_argument('--tasks', type=int, default=20)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('--json', type=Path)
    args = parser.parse_args(argv)
    if args.robots is None or not (args.robots / 'panda_description').is_dir():
        parser.error('--robots (or FTPLAN_ROBOTS_DIR) must name the folder holding '
                     'panda_description/')
    logging.basicConfig(level=logging.INFO, format='%(message)s', stream=sys.stdout)
    started = time.perf_counter()
    mesh = mesh_panda(args.robots)
    print(f'mesh Panda loaded in {time.perf_counter() - started:.2f} s')
    scenes = tasks(args.tasks, args.seed)
    for robot in (scenes[0].robot, mesh):
        load_kernels(robot)
    rows = []
    for k, scene in enumerate(scenes):
        row = {'task': k}
        for name, robot in (('primitive', scene.robot), ('mesh', mesh)):
            variant = replace(scene, robot=robot.with_task_kind(scene.robot.task_kind))
            feasible, seconds, reason = timed_plan(variant, args.seed)
            row[name] = {'feasible': feasible, 'time_s': seconds, 'reason': reason}
        rows.append(row)
        print(f"task {k:3d}: primitive {row['primitive']['feasible']!s:5} "
              f"{row['primitive']['time_s']:7.2f} s   mesh {row['mesh']['feasible']!s:5} "
              f"{row['mesh']['time_s']:7.2f} s   {row['mesh']['reason'][:60]}", flush=True)
    result = summary(rows)
    for name in ('primitive', 'mesh'):
        stats = result[name]
        print(f"{name:9}: {stats['plans']}/{len(rows)} plans, p50 {stats['p50_s']:.2f} s, "
              f"p95 {stats['p95_s']:.2f} s")
    print(f"mesh / primitive: p50 {result['ratio_p50']:.2f}x, p95 {result['ratio_p95']:.2f}x; "
          f"answers agree on {100 * result['agreement']:.0f} % of {len(rows)} tasks")
    if args.json:
        args.json.write_text(json.dumps({'tasks': rows, 'summary': result}, indent=1))
    return 0


if __name__ == '__main__':
    sys.exit(main())
