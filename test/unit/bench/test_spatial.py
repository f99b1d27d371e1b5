"""The benchmark of 7-joint arms (bench/spatial.py): its random tasks and its table."""

import numpy as np
import pytest

from ftplan_ros.bench.spatial import DRILL_TRIALS, OBSTACLES, TaskRun, random_task, summarize
from ftplan_ros.core import CollisionChecker


@pytest.mark.parametrize('name, elbow', [('panda', 'panda_joint4'), ('iiwa14', 'iiwa_joint_4')])
def test_a_random_task_tolerates_all_but_the_elbow_among_obstacles_clear_of_the_base(name,
                                                                                    elbow):
    scene = random_task(name, np.random.default_rng(3))
    again = random_task(name, np.random.default_rng(3))
    assert scene.obstacles == again.obstacles and scene.task == again.task
    robot = scene.robot
    assert robot.task_kind == scene.task.kind == 'pose'
    assert scene.tolerate == tuple(joint for joint in robot.joint_names if joint != elbow)
    assert len(scene.obstacles) == OBSTACLES
    assert np.all(CollisionChecker(robot, scene.obstacles).base_clearance() > 0.05)
    assert (scene.task.goal_tolerance, scene.task.orientation_tolerance) == (0.005, 0.01)


def run(planner, baseline, drill=DRILL_TRIALS, planner_s=0.1, baseline_s=1.0):
    return TaskRun(planner, planner_s, drill if planner else 0, baseline, baseline_s, '', '')


def test_the_table_counts_the_answers_that_differ_and_the_drills_that_failed():
    runs = [run(True, True), run(True, False, planner_s=0.3), run(False, True),
            run(False, False), run(True, True, drill=DRILL_TRIALS - 1)]
    lines = summarize('panda', runs).splitlines()
    assert lines[0].startswith(f'panda: 5 random pose tasks among {OBSTACLES} obstacles')
    assert lines[2].split()[-3:] == ['3', '100', '260']  # planner yes, p50 and p95 [ms]
    assert lines[3].split()[-3:] == ['3', '1000', '1000']
    assert lines[4] == ('answers agree on 3/5; planner yes, baseline no: 1; baseline yes, '
                        'planner no: 1')
    assert lines[5] == f'plans whose {DRILL_TRIALS}-trial drill failed: 1 (must be 0)'
