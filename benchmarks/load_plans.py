"""Load the planner: 20 concurrent plan clients while the obstacles change at 10 Hz (issue 10).

    .venv/bin/python benchmarks/load_plans.py [--clients 20] [--requests 10] \
        [--plan-timeout 30.0 ...] [--seed 0]

For each `--plan-timeout`, the installed planner (`make install`; its own process, as
`ros2 run` starts it) serves fig3a with that `plan_timeout` while this process runs the
clients and the obstacle publisher of test/ros/loading.py: every request must be
answered (a plan, or an empty Path with the planner's reason), every plan's status must
name the scene's robot (its digest) and every plan's S_F must be collision-free for the
obstacle set its status names. Prints one row per setting:
requests, answered, plans, refusals by reason, latency p50/p95/max [s] (request sent ->
response) and the soundness counts. Exit 1 if a request went unanswered or a plan was
unsound.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'ros'))  # the tests' domain claim and load run

from ros_domain import claim_domain  # noqa: E402

claim_domain()
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')

import rclpy  # noqa: E402  (after the environment: rclpy reads it at init)
from loading import LoadRun  # noqa: E402
from nav_msgs.srv import GetPlan  # noqa: E402
from rclpy.context import Context  # noqa: E402

from ftplan_ros.core import load_scene  # noqa: E402

SCENE = REPO / 'config' / 'scenes' / 'fig3a.yaml'
PLANNER = REPO / 'install' / 'ftplan_ros' / 'lib' / 'ftplan_ros' / 'planner'


def run(plan_timeout: float, clients: int, requests: int, seed: int) -> tuple[str, bool]:
    """One load run against a fresh planner process: (its summary, whether it failed)."""
    planner = subprocess.Popen([str(PLANNER), '--ros-args', '-p', f'scene_file:={SCENE}',
                                '-p', f'plan_timeout:={plan_timeout}', '--log-level', 'error'],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    context = Context()
    rclpy.init(context=context)
    try:
        probe = rclpy.create_node('ftplan_load_probe', context=context)
        client = probe.create_client(GetPlan, '/ftplan/plan')
        if not client.wait_for_service(timeout_sec=60.0):
            raise RuntimeError('the planner did not start')
        probe.destroy_node()
        time.sleep(1.0)
        report = LoadRun(context, load_scene(SCENE), clients, requests, seed=seed).run()
    finally:
        planner.send_signal(2)
        planner.wait(timeout=30)
        rclpy.try_shutdown(context=context)
    alive = 'planner alive to the end' if planner.returncode == 0 else \
        f'planner exit code {planner.returncode}'
    failed = report.unanswered or report.unsound
    return (f'plan_timeout {plan_timeout:g} s: {report.summary()}; {alive}'
            + ('\n  UNSOUND: ' + '; '.join(report.unsound[:5]) if report.unsound else ''),
            bool(failed))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--clients', type=int, default=20)
    parser.add_argument('--requests', type=int, default=10, help='per client (10)')
    parser.add_argument('--plan-timeout', type=float, nargs='+', default=[30.0, 0.5])
    parser.add_argument('--seed', type=int, default=0)
    args = parser.parse_args()
    failed = False
    for timeout in args.plan_timeout:
        line, bad = run(timeout, args.clients, args.requests, args.seed)
        print(line, flush=True)
        failed |= bad
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
