"""Failure drills through ROS: all four nodes in one executor, every joint at five moments.

One test runs all fifteen drills on one plan (a module fixture would run once per xdist
worker); it checks every run and reports all the runs that failed at once.
"""

import itertools

from ros_support import FIG3A

from ftplan_ros.bringup import Director, Suite
from ftplan_ros.core import load_scene
from ftplan_ros.nodes.injector import parse_drill
from ftplan_ros.plan_client import PlanClient

JOINTS = ('joint1', 'joint2', 'joint3')
MOMENTS = (0.0, 0.25, 0.5, 0.75, 1.0)
DRILLS = [f'{joint}@{moment}' for joint, moment in itertools.product(JOINTS, MOMENTS)]


def problems_of(run, drill: str) -> list[str]:
    """What is wrong with one drilled run (empty when it is right)."""
    wanted = parse_drill(drill, JOINTS)
    problems = []
    if parse_drill(run.drill, JOINTS) != wanted:
        problems.append(f'the injector armed {run.drill}')
    if not run.ok:
        problems.append(f'failed: {run.message}')
    if run.collisions or not run.min_clearance > 0.0:
        problems.append(f'{run.collisions} collisions, clearance {run.min_clearance}')
    if not run.goal_error <= 0.01:
        problems.append(f'goal error {run.goal_error}')
    if wanted.fraction < 1.0:
        # The injector locks once the arm has done its share of the path, never before,
        # and the executor recovers with the core's recover().
        if run.locked_joint != wanted.joint:
            problems.append(f'locked joint {run.locked_joint!r}')
        elif not run.lock_progress >= wanted.fraction - 1e-9:
            problems.append(f'locked at {run.lock_progress:.3f} < {wanted.fraction}')
        elif not run.recovery_time > 0.0:
            problems.append('no recovery time')
    elif run.locked_joint and run.lock_progress < 0.99:
        # At the very end the lock comes just before arrival, or after it (ignored).
        problems.append(f'locked at {run.lock_progress:.3f} for a drill at the end')
    return problems


def test_every_joint_locked_at_every_moment_still_reaches_the_goal(ros_context):
    suite = Suite(FIG3A, speed=2.0, rate=100.0, drills=DRILLS, context=ros_context)
    client = PlanClient(context=ros_context)
    try:
        director = Director(client, load_scene(FIG3A))
        motion = director.plan(timeout=120.0)
        assert motion.succeeded, motion.message
        runs = {drill: director.run(k + 1, timeout=120.0) for k, drill in enumerate(DRILLS)}
    finally:
        client.destroy_node()
        suite.shutdown()
    failures = {drill: problems for drill, run in runs.items()
                if (problems := problems_of(run, drill))}
    assert not failures, failures
    recovered = [run for run in runs.values() if run.locked_joint]
    assert len(recovered) >= 12           # every drill before the end, at least
