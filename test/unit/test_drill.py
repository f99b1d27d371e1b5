import numpy as np
import pytest
from ftplan_testing import SCENES

from ftplan_ros.core import load_scene, plan
from ftplan_ros.core.model.paths import path_until
from ftplan_ros.core.planning.drill import drilled_motion, run_drill, summarize_drill


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
