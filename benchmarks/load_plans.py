"""Load the planner: concurrent plan clients, on 0, 1, 2 ... plan workers (issues 10 and 33).

    .venv/bin/python benchmarks/load_plans.py [--scene fig3a] [--clients 20] \
        [--requests 10] [--workers 0 ...] [--plan-timeout 30.0 ...] [--rounds 1] [--seed 0]

For each `--workers` and `--plan-timeout`, `--rounds` times in turn (the load of a
shared machine drifts: each setting sees it alike), the installed planner (`make install`; its own
process, as `ros2 run` starts it) serves the scene with that `plan_workers` and
`plan_timeout` while this process runs the clients of test/ros/loading.py. On a planar
scene (fig3a) they ask for the arm from (2, 0) to one of four goals while the obstacles
change at 10 Hz; on a spatial one (panda_shelf, panda_free_pose) they all ask for the
scene's task among its static obstacles. Every request must be answered (a plan, or an
empty Path with the planner's reason), every plan's status must name the scene's robot
(its digest) and every plan's S_F must be collision-free for the obstacle set its status
names. Prints one row per run: requests, throughput
(answered requests per second of the run), answered, plans, refusals by reason, latency
p50/p95/max [s] (request sent -> response) and the soundness counts; then per setting,
over its rounds, the throughput against the first setting's and the latency p50/p95.
Exit 1 if a request went unanswered or a plan was unsound.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'ros'))  # the tests' domain claim and load run

from ros_domain import claim_domain  # noqa: E402

claim_domain()
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')

import numpy as np  # noqa: E402
import rclpy  # noqa: E402  (after the environment: rclpy reads it at init)
from loading import FIG3A_TASKS, LoadReport, LoadRun  # noqa: E402
from nav_msgs.srv import GetPlan  # noqa: E402
from rclpy.context import Context  # noqa: E402

from ftplan_ros.core import Scene, load_scene  # noqa: E402

SCENES = REPO / 'config' / 'scenes'
PLANNER = REPO / 'install' / 'ftplan_ros' / 'lib' / 'ftplan_ros' / 'planner'
OBSTACLE_RATE = 10.0  # [Hz] obstacle changes during a run on a planar scene


def run(scene_file: Path, workers: int, plan_timeout: float, clients: int, requests: int,
        seed: int) -> tuple[LoadReport, str]:
    """One load run against a fresh planner process: (its report, how the planner ended)."""
    scene = load_scene(scene_file)
    planner = subprocess.Popen([str(PLANNER), '--ros-args', '-p', f'scene_file:={scene_file}',
                                '-p', f'plan_workers:={workers}',
                                '-p', f'plan_timeout:={plan_timeout}', '--log-level', 'error'],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    context = Context()
    rclpy.init(context=context)
    try:
        probe = rclpy.create_node('ftplan_load_probe', context=context)
        client = probe.create_client(GetPlan, '/ftplan/plan')
        if not client.wait_for_service(timeout_sec=120.0):
            raise RuntimeError('the planner did not start')
        probe.destroy_node()
        time.sleep(1.0)
        report = LoadRun(context, scene, clients, requests, seed=seed, **_load(scene)).run()
    finally:
        planner.send_signal(2)
        planner.wait(timeout=60)
        rclpy.try_shutdown(context=context)
    ended = 'planner alive to the end' if planner.returncode == 0 else \
        f'planner exit code {planner.returncode}'
    return report, ended


def _load(scene: Scene) -> dict:
    """What the clients ask for, and how often the obstacles change."""
    if scene.task is not None and scene.task.kind != 'planar':
        return {'tasks': ((scene.task.start, scene.task.goal),), 'obstacle_rate': 0.0}
    return {'tasks': FIG3A_TASKS, 'obstacle_rate': OBSTACLE_RATE}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--scene', default='fig3a',
                        help='a scene of config/scenes (fig3a, panda_shelf, ...) or a file')
    parser.add_argument('--clients', type=int, default=20)
    parser.add_argument('--requests', type=int, default=10, help='per client (10)')
    parser.add_argument('--workers', type=int, nargs='+', default=[0],
                        help='plan_workers of each run (0: planning in the node process)')
    parser.add_argument('--plan-timeout', type=float, nargs='+', default=[30.0, 0.5])
    parser.add_argument('--rounds', type=int, default=1, help='runs of each setting (1)')
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args()
    scene_file = Path(args.scene) if args.scene.endswith('.yaml') else \
        SCENES / f'{args.scene}.yaml'
    failed = False
    reports: dict[tuple[int, float], list[LoadReport]] = defaultdict(list)
    for _ in range(args.rounds):
        for workers in args.workers:
            for timeout in args.plan_timeout:
                report, ended = run(scene_file, workers, timeout, args.clients, args.requests,
                                    args.seed)
                print(f'{scene_file.stem}, plan_workers {workers}, plan_timeout {timeout:g} '
                      f's: {report.summary()}; {ended}', flush=True)
                if report.unsound:
                    print('  UNSOUND: ' + '; '.join(report.unsound[:5]), flush=True)
                failed |= bool(report.unanswered or report.unsound)
                reports[workers, timeout].append(report)
    print(f'\n{scene_file.stem}, {args.clients} clients x {args.requests} requests, '
          f'{args.rounds} rounds:')
    base = None
    for (workers, timeout), runs in reports.items():
        throughput = sum(r.answered for r in runs) / sum(r.seconds for r in runs)
        base = base or throughput
        latencies = [t for r in runs for t in r.latencies]
        p50, p95 = np.percentile(latencies, [50, 95]) if latencies else (np.nan, np.nan)
        print(f'plan_workers {workers}, plan_timeout {timeout:g} s: {throughput:.2f} '
              f'answered/s ({throughput / base:.2f}x the first), latency p50 {p50:.2f} s, '
              f'p95 {p95:.2f} s')
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
