"""Sampled self-collision exceptions of a robot without its own (core/io/sampled_exceptions.py).

The CAD arm (ftplan_testing.CAD_ARM) is the case the old default (adjacent links and links
touching at the middle of the joint ranges) got wrong: its `upper` and `fore` are 1 µm
apart there and overlap everywhere else, so every configuration collided.
"""

import numpy as np
import pytest
import yaml
from ftplan_testing import ROBOTS, write_cad_arm

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.sampled_exceptions import KIND
from ftplan_ros.core.io.scene_file import load_scene, parse_scene
from ftplan_ros.core.planning.drill import run_drill
from ftplan_ros.core.planning.planner import plan

LOGGER = 'ftplan_ros.core.io.sampled_exceptions'


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """An empty cache folder of the test's own."""
    monkeypatch.setenv('FTPLAN_CACHE_DIR', str(tmp_path / 'cache'))
    return tmp_path / 'cache' / KIND


def exempt(robot) -> set[tuple[str, str]]:
    """The robot's exempt link pairs, by name."""
    names = robot.link_names
    return {(names[a], names[b]) for a, b in robot.model.disabled_pairs}


def test_the_cad_arm_plans_a_position_task_and_survives_its_drill(tmp_path, cache, caplog):
    caplog.set_level('INFO', LOGGER)
    scene = load_scene(write_cad_arm(tmp_path))
    assert ('upper', 'fore') in exempt(scene.robot)
    assert 'upper/fore (always, 100.0 %)' in caplog.text
    result = plan(scene)
    assert result.feasible, result.reason
    trials = run_drill(scene, result, 20, np.random.default_rng(0))
    assert all(trial.ok for trial in trials)


def test_the_second_load_reads_the_cache_and_a_changed_model_samples_again(tmp_path, cache,
                                                                          caplog):
    caplog.set_level('INFO', LOGGER)
    path = write_cad_arm(tmp_path)
    first = load_scene(path).robot
    assert 'random configurations (sampled in' in caplog.text
    assert len(list(cache.iterdir())) == 1
    caplog.clear()
    assert exempt(load_scene(path).robot) == exempt(first)
    assert 'random configurations (read from' in caplog.text and 'sampled in' not in caplog.text
    urdf = tmp_path / 'cad_arm.urdf'
    urdf.write_text(urdf.read_text().replace('radius="0.04" length="0.2"',
                                             'radius="0.045" length="0.2"'))
    caplog.clear()
    load_scene(path)
    assert 'sampled in' in caplog.text and len(list(cache.iterdir())) == 2


def test_a_cache_entry_of_another_robot_is_not_used(tmp_path, cache, caplog):
    path = write_cad_arm(tmp_path)
    expected = exempt(load_scene(path).robot)
    (entry,) = cache.iterdir()
    entry.write_text('{"samples": 10000, "seed": 0, "pairs": [[1, 3, 10000]]}')
    assert exempt(load_scene(path).robot) == expected
    assert 'does not hold this robot\'s sampled self-collision counts' in caplog.text
    assert len(yaml.safe_load(entry.read_text())['pairs']) == 6  # sampled and written again


def test_never_false_keeps_the_pairs_that_never_touched_checked(tmp_path, cache, caplog):
    caplog.set_level('INFO', LOGGER)
    default = exempt(load_scene(write_cad_arm(tmp_path)).robot)
    caplog.clear()
    robot = load_scene(write_cad_arm(tmp_path, self_collision_sampling={'never': False})).robot
    assert exempt(robot) == {('base', 'upper'), ('upper', 'knuckle'), ('knuckle', 'fore'),
                             ('fore', 'hand'), ('upper', 'fore')}
    assert exempt(robot) < default
    assert 'read from' in caplog.text and 'never: false' in caplog.text  # the same counts
    assert plan(load_scene(write_cad_arm(tmp_path, self_collision_sampling={
        'never': False}))).feasible


@pytest.mark.parametrize('keys, field, words', [
    ({'self_collision_sampling': {'samples': 10}}, 'robot.self_collision_sampling.samples',
     'must be an integer >= 100'),
    ({'self_collision_sampling': {'samples': 10_000_000}},
     'robot.self_collision_sampling.samples', 'at most 1000000'),
    ({'self_collision_sampling': {'never': 'no'}}, 'robot.self_collision_sampling.never',
     'must be true or false'),
    ({'self_collision_sampling': {'seed': 3}}, 'robot.self_collision_sampling.seed',
     'unknown key'),
    ({'self_collision_sampling': {}, 'disabled_collisions': [['upper', 'fore']]},
     'robot.self_collision_sampling', 'robot.disabled_collisions gives them'),
])
def test_bad_sampling_settings_name_their_field(tmp_path, cache, keys, field, words):
    with pytest.raises(InputError, match=rf'^{field}: .*{words}'):
        load_scene(write_cad_arm(tmp_path, **keys))


def test_sampling_beside_an_srdf_is_refused(tmp_path, cache):
    (tmp_path / 'cad_arm.srdf').write_text('<robot name="cad_arm"/>')
    with pytest.raises(InputError, match=r'^robot\.self_collision_sampling: .*robot\.srdf'):
        load_scene(write_cad_arm(tmp_path, srdf='cad_arm.srdf', self_collision_sampling={}))


@pytest.mark.parametrize('name', ['panda', 'iiwa14'])
def test_robots_with_their_own_lists_keep_them_and_sample_nothing(cache, name):
    robot = parse_scene({'robot': f'{name}.yaml'}, directory=ROBOTS).robot
    listed = yaml.safe_load((ROBOTS / f'{name}.yaml').read_text())['robot']['disabled_collisions']
    assert exempt(robot) == {tuple(pair) for pair in listed}
    assert not cache.exists()
