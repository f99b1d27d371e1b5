"""Benchmark the ROS layer: plan-service overhead and failure drills through the nodes.

    .venv/bin/python benchmarks/ros_bench.py [--requests 20] [--drills 100] [--seed 1]

1. Plan service round trip against the core's own plan time, on the same scenes, in one
   run. One planner node (the installed executable in its own process, as `ros2 run`
   starts it; --in-process keeps it in this process) holds the obstacle-free paper scene;
   each scene's disks arrive on /ftplan/obstacles and its task in the GetPlan request.
   Per request: the round trip (request sent -> response received, PlanClient) and the
   core's plan time inside that request (the planner's status). Their difference is the
   ROS overhead: request and response transport, checks, and publishing the latched
   results (the RViz markers go out after the response). For reference, the core is also
   timed in this process on the same scenes with a warm manifold cache, as the node has.
2. Failure drills through ROS: planner, executor, sim and injector in one process (the
   bringup's Suite), `--drills` executions of the fig3a plan, each with a random joint
   locked at a random moment (seeded). Success = the sim reports the goal reached and no
   collision. Recovery time = lock event -> arm at the goal [s of wall time].

Times are from this machine and this run; compare them with each other, not across runs.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'ros'))  # ros_domain: the tests' domain claim

from ros_domain import claim_domain  # noqa: E402

SCENES = ('fig3a', 'fig3b', 'fig3c', 'paper_a_free', 'paper_c_free')
BASE_SCENE = REPO / 'config' / 'scenes' / 'paper_a_free.yaml'
INSTALLED_PLANNER = REPO / 'install' / 'ftplan_ros' / 'lib' / 'ftplan_ros' / 'planner'


def _environment() -> None:
    """A ROS domain no test run or other benchmark uses, and the installed layout."""
    claim_domain()
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    prefix = f'{REPO}/install/ftplan_ros:{REPO}/install/ftplan_msgs_py'
    if prefix not in os.environ.get('AMENT_PREFIX_PATH', ''):
        os.environ['AMENT_PREFIX_PATH'] = ':'.join(
            p for p in (prefix, os.environ.get('AMENT_PREFIX_PATH', '')) if p)


_environment()

import rclpy  # noqa: E402  (after the environment: rclpy reads it at init)
from rclpy.parameter import Parameter  # noqa: E402
from visualization_msgs.msg import MarkerArray  # noqa: E402

from ftplan_msgs_py import create_obstacle_markers  # noqa: E402
from ftplan_ros.bringup import Director, Suite  # noqa: E402
from ftplan_ros.core import ManifoldCache, load_scene, plan  # noqa: E402
from ftplan_ros.nodes.obstacles import shape_from_obstacle  # noqa: E402
from ftplan_ros.nodes.planner import PlannerNode  # noqa: E402
from ftplan_ros.nodes.qos import LATCHED_QOS  # noqa: E402
from ftplan_ros.nodes.spinning import BackgroundSpin  # noqa: E402
from ftplan_ros.plan_client import Outcome, PlanClient  # noqa: E402


def percentiles(values, *qs) -> list[float]:
    values = np.asarray(values, dtype=float)
    return [float(np.percentile(values, q)) if len(values) else float('nan') for q in qs]


def start_planner(in_process: bool):
    """The planner over the obstacle-free scene: (stop function, description)."""
    if not in_process and INSTALLED_PLANNER.exists():
        process = subprocess.Popen(
            [str(INSTALLED_PLANNER), '--ros-args', '-p', f'scene_file:={BASE_SCENE}',
             '--log-level', 'warn'], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

        def stop():
            process.terminate()
            process.wait(timeout=10)
        return stop, 'installed planner in its own process'
    spin = BackgroundSpin([PlannerNode(parameter_overrides=[
        Parameter('scene_file', value=str(BASE_SCENE))])])
    return spin.stop, 'planner node in this process'


def bench_plan_service(requests: int, in_process: bool) -> list[dict]:
    """Round trips and in-service core times per scene, and the core timed directly."""
    stop, where = start_planner(in_process)
    client = PlanClient('ftplan_bench_client')
    obstacles = client.create_publisher(MarkerArray, '/ftplan/obstacles', LATCHED_QOS)
    rows = []
    # One cache over the scenes in the planner's order, so the direct runs reuse manifolds
    # traced from the same random state as the node's (warm times depend on it).
    direct_cache = ManifoldCache()
    try:
        if not client.spin_until(client.plan_client.service_is_ready, 30.0):
            raise SystemExit('the planner did not come up')
        print(f'plan service: {where}, {requests} requests per scene', file=sys.stderr)
        for name in SCENES:
            scene = load_scene(REPO / 'config' / 'scenes' / f'{name}.yaml')
            shapes = [shape_from_obstacle(('bench', k), ob) for k, ob in enumerate(scene.obstacles)]
            mark, count = client.status_mark, str(len(shapes))
            obstacles.publish(create_obstacle_markers(shapes, 'base_link', clear_first=True))
            applied = client.wait_for_status(
                'ftplan_planner: obstacles', lambda v, n=count: v.get('obstacles') == n, 10.0,
                mark)
            if applied is None:
                raise SystemExit(f'{name}: the planner did not take the obstacles')
            trips, inside = [], []
            for _ in range(requests):
                motion = client.plan(goal=scene.task.goal, start=scene.task.start, timeout=60.0)
                if motion.result not in (Outcome.SUCCEEDED, Outcome.FAILED):
                    raise SystemExit(f'{name}: {motion.message}')
                trips.append(motion.round_trip_s)
                inside.append(motion.plan_time_s)
            direct = []
            for _ in range(requests):
                started = time.perf_counter()
                plan(scene, rng=np.random.default_rng(0), cache=direct_cache)
                direct.append(time.perf_counter() - started)
            overhead = np.array(trips) - np.array(inside)
            rows.append({'scene': name, 'feasible': motion.succeeded, 'trip': trips,
                         'inside': inside, 'direct': direct, 'overhead': overhead.tolist()})
            print(f'  {name}: done', file=sys.stderr)
    finally:
        client.destroy_node()
        stop()
    return rows


def bench_drills(drills: int, seed: int, speed: float) -> list:
    """`drills` random failure drills through the four nodes in this process."""
    scene_file = REPO / 'config' / 'scenes' / 'fig3a.yaml'
    suite = Suite(scene_file, speed=speed, random_drills=drills, seed=seed,
                  log_level=rclpy.logging.LoggingSeverity.ERROR)
    client = PlanClient('ftplan_bench_director')
    runs = []
    try:
        director = Director(client, load_scene(scene_file))
        motion = director.plan(timeout=120.0)
        if not motion.succeeded:
            raise SystemExit(f'fig3a: no plan: {motion.message}')
        started = time.perf_counter()
        for k in range(drills):
            runs.append(director.run(k + 1, timeout=120.0))
            if (k + 1) % 10 == 0 or k + 1 == drills:
                print(f'  drills: {k + 1}/{drills} ({time.perf_counter() - started:.0f} s)',
                      file=sys.stderr)
    finally:
        client.destroy_node()
        suite.shutdown()
    return runs


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--requests', type=int, default=20, help='plan requests per scene')
    parser.add_argument('--drills', type=int, default=100, help='ROS failure drills (>= 100)')
    parser.add_argument('--seed', type=int, default=1, help='seed of the random drills')
    parser.add_argument('--speed', type=float, default=2.0, help='joint speed [rad/s]')
    parser.add_argument('--in-process', action='store_true',
                        help='run the planner in this process instead of its own')
    args = parser.parse_args(argv)
    rclpy.init()
    try:
        rows = bench_plan_service(args.requests, args.in_process)
        runs = bench_drills(args.drills, args.seed, args.speed)
    finally:
        rclpy.try_shutdown()

    print('\nPlan service round trip vs the core\'s plan time (p50 [ms]; overhead p50/p95 '
          'of round trip - in-service core time)')
    header = (f'{"scene":<14}{"feasible":>9}{"round trip":>12}{"core in svc":>13}'
              f'{"core direct":>13}{"overhead p50":>14}{"p95":>8}')
    print(header)
    print('-' * len(header))
    for row in rows:
        trip, inside, direct = (percentiles(row[k], 50)[0] * 1e3
                                for k in ('trip', 'inside', 'direct'))
        p50, p95 = (v * 1e3 for v in percentiles(row['overhead'], 50, 95))
        print(f'{row["scene"]:<14}{str(row["feasible"]):>9}{trip:>12.1f}{inside:>13.1f}'
              f'{direct:>13.1f}{p50:>14.2f}{p95:>8.2f}')
    every = [v for row in rows for v in row['overhead']]
    p50, p95 = (v * 1e3 for v in percentiles(every, 50, 95))
    print(f'{"all":<14}{"":>9}{"":>12}{"":>13}{"":>13}{p50:>14.2f}{p95:>8.2f}')
    print(f'overhead p50 {p50:.2f} ms over {len(every)} requests: '
          f'{"within" if p50 <= 5.0 else "ABOVE"} the 5 ms target')

    ok = [r for r in runs if r.ok]
    recovered = [r for r in runs if r.locked_joint]
    times = [r.recovery_time for r in recovered]
    print(f'\nROS failure drills on fig3a (seed {args.seed}, {args.speed} rad/s)')
    header = (f'{"joint":<10}{"drills":>7}{"reached":>9}{"recovered":>11}'
              f'{"recovery p50/p95 [s]":>23}')
    print(header)
    print('-' * len(header))
    names = sorted({r.drill.split('@')[0] for r in runs if r.drill})
    for name in names + ['all']:
        group = [r for r in runs if name == 'all' or r.drill.startswith(name + '@')]
        rec = [r.recovery_time for r in group if r.locked_joint]
        p50, p95 = percentiles(rec, 50, 95)
        print(f'{name:<10}{len(group):>7}{sum(r.ok for r in group):>9}{len(rec):>11}'
              f'{f"{p50:.2f} / {p95:.2f}":>23}')
    p50, p95 = percentiles(times, 50, 95)
    late = len(runs) - len(times)
    print(f'success rate {len(ok)}/{len(runs)} = {len(ok) / max(1, len(runs)):.1%}; '
          f'recovery time p50 {p50:.2f} s, p95 {p95:.2f} s over {len(times)} recoveries'
          + (f' ({late} locked after arrival)' if late else '')
          + f'; minimum clearance {min(r.min_clearance for r in runs):.4f} m')
    failed = [r for r in runs if not r.ok]
    for r in failed[:10]:
        print(f'  FAILED run {r.run} {r.drill}: {r.message}')
    return 0 if not failed else 1


if __name__ == '__main__':
    sys.exit(main())
