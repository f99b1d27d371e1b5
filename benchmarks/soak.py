"""Soak: many `ftplan-bringup` drills over several scenes, from the sim's default start (issue 10).

    .venv/bin/python benchmarks/soak.py [--drills 1000] [--seed 1] [--speed 4.0] \
        [--scenes config/scenes/fig3a.yaml test/ros/scenes/crowded_32.yaml ...]

Per scene, what `ftplan-bringup --scene S --trials N --seed K` does (its Suite and
Director, in this process): the four nodes, one plan of the scene's task from where the
sim starts (its default: the clearest configuration of M_s), then N executions, each with
a random tolerated joint locked at a random moment of the nominal path. The drills are
split evenly over the scenes. Prints, per scene and in all: runs, runs that reached the
goal without collision, runs drilled as asked (the lock landed within 0.02 of its
fraction: `Drill.missed`), the failures and the runs not drilled with their reasons, the
approaches taken and the recovery time (lock event -> arm at the goal, wall time)
p50/p95. Exit 1 if any run failed or was not drilled as asked. The default scenes:
fig3a, crowded_sheets_100 (only the recovery sheets of issue 9 solve it) and six of the
tests' (test/ros/scenes): two crowded ones (the paper's arm among 12 disks), two where
the planner's favourite θ_s lies on another arc of M_s than the sim's start (split_arcs:
a start on the sim's arc is preferred; detour: a start within reach that the joint grid
offers), and two crowded ones whose θ_s does lie on another arc (another_arc_rrt:
RRT-Connect goes round the disks; another_arc_cells: through the grid's certified cells).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'ros'))  # the tests' domain claim

from ros_domain import claim_domain  # noqa: E402

claim_domain()
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')

import rclpy  # noqa: E402  (after the environment: rclpy reads it at init)
from rclpy.context import Context  # noqa: E402
from rclpy.logging import LoggingSeverity  # noqa: E402

from ftplan_ros.bringup import Director, Suite  # noqa: E402
from ftplan_ros.core import load_scene  # noqa: E402
from ftplan_ros.plan_client import PlanClient  # noqa: E402
from ftplan_ros.progress import Progress  # noqa: E402

SCENES = [REPO / 'config' / 'scenes' / f'{name}.yaml'
          for name in ('fig3a', 'crowded_sheets_100')] + [
    REPO / 'test' / 'ros' / 'scenes' / f'{name}.yaml'
    for name in ('crowded_6', 'crowded_12', 'split_arcs', 'detour', 'another_arc_rrt',
                 'another_arc_cells')]


def soak_scene(path: Path, drills: int, seed: int, speed: float) -> dict:
    """Run `drills` random drills of one scene through the nodes; return the tallies."""
    scene = load_scene(path)
    context = Context()
    rclpy.init(context=context)
    suite = client = None
    started = time.monotonic()
    try:
        suite = Suite(path.resolve(), speed=speed, random_drills=drills, seed=seed,
                      context=context, log_level=LoggingSeverity.ERROR)
        client = PlanClient('ftplan_soak', context=context)
        director = Director(client, scene, Progress(quiet=True))
        motion = director.plan(timeout=120.0)
        if not motion.succeeded:
            return {'scene': scene.name, 'runs': [], 'plan': motion.message}
        approach = client.status('ftplan_planner: plan')
        runs = []
        for number in range(1, drills + 1):
            runs.append(director.run(number, timeout=120.0, drilled=True))
            if number % 50 == 0:
                ok = sum(r.ok for r in runs)
                print(f'  {scene.name}: {number}/{drills} runs, {ok} reached '
                      f'({time.monotonic() - started:.0f} s)', file=sys.stderr, flush=True)
        return {'scene': scene.name, 'runs': runs, 'plan': motion.message,
                'approach': approach.values.get('approach', '') if approach else '',
                'seconds': time.monotonic() - started}
    finally:
        if client is not None:
            client.destroy_node()
        if suite is not None:
            suite.shutdown()
        rclpy.try_shutdown(context=context)


def describe(name: str, runs: list, seconds: float) -> str:
    """One summary line: runs, reached, drilled as asked, recovery time percentiles."""
    reached = sum(r.ok for r in runs)
    drilled = sum(not r.missed for r in runs)
    times = np.array([r.recovery_time for r in runs if np.isfinite(r.recovery_time)])
    recovery = (f'recovery p50 {np.percentile(times, 50):.2f} s, p95 '
                f'{np.percentile(times, 95):.2f} s over {len(times)}') if len(times) else \
        'no recovery'
    clearance = min((r.min_clearance for r in runs if np.isfinite(r.min_clearance)),
                    default=float('nan'))
    return (f'{name:<14}{len(runs):>6} runs {reached:>6} reached without collision, {drilled:>6} '
            f'drilled as asked; {recovery}; least clearance {clearance:.4f} m; {seconds:.0f} s')


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--drills', type=int, default=1000)
    parser.add_argument('--seed', type=int, default=1)
    parser.add_argument('--speed', type=float, default=4.0,
                        help='fastest commanded joint speed [rad/s] (4.0)')
    parser.add_argument('--scenes', type=Path, nargs='+', default=SCENES)
    args = parser.parse_args()
    share = [args.drills // len(args.scenes) + (k < args.drills % len(args.scenes))
             for k in range(len(args.scenes))]
    results = []
    for path, drills in zip(args.scenes, share, strict=True):
        print(f'{path.stem}: {drills} drills', file=sys.stderr, flush=True)
        results.append(soak_scene(path, drills, args.seed, args.speed))
    every = [r for result in results for r in result['runs']]
    for result in results:
        print(describe(result['scene'], result['runs'], result.get('seconds', 0.0)))
        print(f'    plan: {result["plan"][:160]}')
        for run in result['runs']:
            if not run.ok:
                print(f'    run {run.run} {run.drill}: FAILED: {run.message}')
            if run.missed:
                print(f'    run {run.run} {run.drill}: NOT DRILLED: {run.missed}')
    print(describe('all', every, sum(r.get('seconds', 0.0) for r in results)))
    return 0 if every and all(r.ok and not r.missed for r in every) and \
        len(every) == args.drills else 1


if __name__ == '__main__':
    sys.exit(main())
