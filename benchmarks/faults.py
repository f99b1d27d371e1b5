"""Kill each node with SIGKILL in the middle of an execution, restart it, and see (issue 10).

    .venv/bin/python benchmarks/faults.py [--nodes planner executor sim injector]

The planner, executor (slow: 0.3 rad/s, so that an execution lasts ~10 s), sim and
injector run as the installed executables (`make install`), each in its own process, on
fig3a. For each node in turn: plan and execute; once the nominal path is 30 % done,
SIGKILL the node and watch for 5 s what the others do (the executor's and the sim's
statuses); then restart it and run a whole plan and execution again, with a drill
(joint2 locked at 50 %) when the injector is up. Prints, per node, what happened after
the kill and after the restart. Exit 1 if a run after a restart failed or the sim
reported a collision.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test' / 'ros'))  # the tests' domain claim

from ros_domain import claim_domain  # noqa: E402

claim_domain()
os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')

import rclpy  # noqa: E402  (after the environment: rclpy reads it at init)
from std_srvs.srv import Trigger  # noqa: E402

from ftplan_ros.plan_client import Outcome, PlanClient  # noqa: E402

SCENE = REPO / 'config' / 'scenes' / 'fig3a.yaml'
LIB = REPO / 'install' / 'ftplan_ros' / 'lib' / 'ftplan_ros'
PARAMETERS = {'planner': [], 'executor': ['max_joint_speed:=0.3', 'joint_state_timeout:=1.0'],
              'sim': ['max_joint_speed:=4.0'], 'injector': ["drills:=['joint2@0.5']"]}
EXECUTION = 'ftplan_executor: execution'
ARM = 'ftplan_sim: arm'


class Nodes:
    """The four node processes; start, kill and restart them by name."""

    def __init__(self, logs: Path):
        self.logs = logs
        self.processes: dict[str, subprocess.Popen] = {}
        self.starts: dict[str, int] = {}

    def start(self, name: str) -> None:
        """Start (or restart) node `name`."""
        self.starts[name] = self.starts.get(name, 0) + 1
        args = [str(LIB / name), '--ros-args', '-p', f'scene_file:={SCENE}',
                '--log-level', 'warn']
        for parameter in PARAMETERS[name]:
            args += ['-p', parameter]
        stem = self.logs / f'{name}-{self.starts[name]}'
        with open(f'{stem}.out', 'w') as out, open(f'{stem}.err', 'w') as err:
            self.processes[name] = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=out,
                                                    stderr=err)

    def kill(self, name: str) -> None:
        """SIGKILL node `name` and reap it."""
        self.processes[name].send_signal(signal.SIGKILL)
        self.processes[name].wait()

    def stop(self) -> None:
        """Stop every node."""
        for process in self.processes.values():
            if process.poll() is None:
                process.send_signal(signal.SIGINT)
        for process in self.processes.values():
            try:
                process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                process.kill()


def run_once(client: PlanClient, timeout: float = 120.0) -> tuple[bool, str]:
    """Reset, plan and execute the scene's task; (success, what happened).

    A request that goes unanswered for 20 s is sent again: right after a restart a
    killed server still looks available (until its DDS lease ends, ~20 s), and a request
    sent before the new one matches is lost.
    """
    lost = []
    deadline = time.monotonic() + 60.0
    while True:
        ok, message = client.trigger('/ftplan_executor/reset', 10.0)
        if ok:
            break
        if 'no answer' in message:
            lost.append('executor reset')
        if time.monotonic() > deadline:
            return False, f'the executor did not become idle: {message}'
        client.spin_until(lambda: False, 0.5)
    while 'no answer' in client.trigger('/ftplan_sim/reset', 10.0)[1]:
        lost.append('sim reset')
    motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=20.0)
    if motion.result is Outcome.TIMED_OUT:
        lost.append('plan request')
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=60.0)
    if not motion.succeeded:
        return False, f'plan: {motion.message}'
    report = client.execute(motion, timeout=timeout)
    if report.result is Outcome.TIMED_OUT and 'no answer' in report.message:
        lost.append('execute request')
        report = client.execute(motion, timeout=timeout)
    arm = client.status(ARM)
    collisions = arm.values.get('collisions', '?') if arm else '?'
    lock = report.values.get('locked_joint', '')
    what = f'{report.result.value}: {report.message}' + (f' ({lock} locked)' if lock else '') \
        + f'; sim collisions {collisions}' + (f'; lost and sent again: {", ".join(lost)}'
                                              if lost else '')
    return report.result is Outcome.SUCCEEDED and collisions == '0', what


def kill_mid_execution(nodes: Nodes, client: PlanClient, name: str) -> tuple[bool, str, str]:
    """Kill `name` at 30 % of the nominal path, watch 5 s, restart it, run again."""
    client.trigger('/ftplan_executor/reset', 10.0)
    client.trigger('/ftplan_sim/reset', 10.0)
    motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=60.0)
    mark = client.status_mark
    started = client.execute_client.call_async(Trigger.Request())
    client.spin_until(started.done, 10.0)
    number = started.result().message.split(':')[0] if started.done() else '?'
    client.wait_for_status(EXECUTION, lambda v: v.get('state') == 'nominal' and
                           float(v.get('progress', 0)) > 0.3, 60.0, mark)
    nodes.kill(name)
    killed = time.monotonic()
    client.spin_until(lambda: False, 5.0)
    after = [r for r in client.statuses(EXECUTION, mark)]
    final = next((r for r in reversed(after) if r.values.get('state') in ('done', 'failed')),
                 None)
    arm = client.status(ARM)
    arm_after = [r for r in client.statuses(ARM, mark)]
    if name == 'executor':
        executor = 'executor gone (last state ' + (after[-1].values.get('state', '?') if after
                                                    else '?') + ')'
    elif final is not None:
        executor = f'executor {final.values["state"]}: "' + \
            (final.values.get('reason') or final.values.get('goal_error_m', '') and
             f'at the goal, error {float(final.values["goal_error_m"]):.1e} m') + '"'
    else:
        executor = f'executor still {after[-1].values.get("state") if after else "silent"}'
    sim = 'sim gone' if name == 'sim' else (
        f'sim {arm.values.get("state")}, goal reached {arm.values.get("goal_reached")}, '
        f'collisions {arm.values.get("collisions")}' if arm_after else 'sim silent')
    seen = (f'{number} of plan {motion.stamp}: {executor}; {sim} '
            f'({time.monotonic() - killed:.0f} s after the kill)')
    nodes.start(name)
    client.spin_until(lambda: False, 3.0)
    ok, after = run_once(client)
    return ok, seen, after


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--nodes', nargs='+', default=['planner', 'executor', 'sim', 'injector'])
    args = parser.parse_args()
    logs = Path(tempfile.mkdtemp(prefix='ftplan-faults-'))
    nodes = Nodes(logs)
    for name in PARAMETERS:
        nodes.start(name)
    rclpy.init()
    client = PlanClient('ftplan_faults')
    failed = False
    try:
        if not client.wait_until_ready(timeout=120.0):
            print(f'the nodes did not start; logs in {logs}')
            return 1
        for name in args.nodes:
            ok, seen, after = kill_mid_execution(nodes, client, name)
            failed |= not ok
            print(f'SIGKILL {name} at 30 % of execution {seen}\n  restarted {name}: next run '
                  f'{after}', flush=True)
    finally:
        client.destroy_node()
        rclpy.try_shutdown()
        nodes.stop()
    print(f'node logs: {logs}')
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
