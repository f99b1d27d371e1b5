"""Drills (core/planning/drill.py): random locks along a plan, each trial checked again."""

import json

import numpy as np
import pytest
from ftplan_testing import SCENES, within_limits

from ftplan_ros.core import load_scene, plan
from ftplan_ros.core.model.paths import path_until
from ftplan_ros.core.model.robot import task_errors
from ftplan_ros.core.planning.drill import drill_json, drilled_motion, run_drill, summarize_drill


@pytest.fixture(scope='module')
def fig3b():
    scene = load_scene(SCENES / 'fig3b.yaml')
    return scene, plan(scene)


def test_every_drill_trial_reaches_the_goal(fig3b):
    scene, result = fig3b
    trials = run_drill(scene, result, 150, np.random.default_rng(7))
    assert all(t.ok for t in trials)
    assert {t.joint for t in trials} == {0, 1, 2}
    assert min(t.progress for t in trials) < 0.1 and max(t.progress for t in trials) > 0.9
    table = summarize_drill(trials, scene.robot.joint_names)
    assert table.splitlines()[-1].startswith('all') and ' 150 ' in table.splitlines()[-1]


def test_drilled_motion_follows_the_nominal_path_then_keeps_the_joint(fig3b):
    _, result = fig3b
    motion, lock, locked = drilled_motion(result, 1, 0.4)
    before = path_until(result.nominal_path, 0.4)
    assert np.allclose(motion[:lock + 1], before)
    assert np.all(motion[lock:, 1] == locked)


def test_a_drill_needs_a_plan():
    scene = load_scene(SCENES / 'infeasible.yaml')
    with pytest.raises(ValueError, match='needs a feasible plan'):
        run_drill(scene, plan(scene), 5, np.random.default_rng(0))


def test_every_drill_of_the_position_plan_reaches_the_goal(panda_position,
                                                          panda_position_drill):
    scene, result = panda_position
    trials = panda_position_drill
    assert len(trials) == 100 and all(trial.ok for trial in trials)
    frozen = {scene.robot.joint_names.index(name)
              for name in result.stats['curve']['frozen_joints']}
    assert {trial.joint for trial in trials} >= frozen  # frozen joints' locks come for free


def test_the_drill_json_can_be_checked_again(panda_position, panda_position_drill):
    """Every trial's path: from θ_s, continuous, the locked joint held, ending at the goal."""
    scene, result = panda_position
    data = json.loads(json.dumps(drill_json(panda_position_drill, scene.robot.joint_names)))
    names = data['joint_names']
    assert names == list(scene.robot.joint_names)
    assert len(data['trials']) == 100 and data['summary']['reached'] == 100
    steps = []
    for trial in data['trials']:
        path = np.asarray(trial['path'])
        joint, lock = names.index(trial['joint']), trial['lock_index']
        assert path.shape[1] == 7 and 0 <= lock < len(path)
        assert np.allclose(path[0], result.theta_s, atol=1e-12)
        assert np.all(path[lock:, joint] == path[lock, joint])
        assert within_limits(scene.robot, path)
        assert trial['reached'] is True and 0.0 <= trial['progress'] <= 1.0
        assert scene.task.reached(task_errors(scene.robot, scene.task.goal, path[-1]))
        assert trial['goal_error'] <= scene.task.goal_tolerance
        assert trial['min_clearance'] > 0.0
        steps.append(np.max(np.abs(np.diff(path, axis=0))))
    worst = int(np.argmax(steps))
    assert steps[worst] <= 0.05, (f'trial {worst} ({data["trials"][worst]["joint"]} at '
                                  f'{data["trials"][worst]["progress"]:.3f}) steps '
                                  f'{steps[worst]:.4f} rad')
