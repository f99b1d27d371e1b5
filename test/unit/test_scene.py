import math

import numpy as np
import pytest
import yaml
from ftplan_testing import SCENES

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.scene import load_scene, parse_scene, scene_to_dict

GOOD = {
    'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0], 'link_radius': 0.0,
              'joint_names': ['joint1', 'joint2', 'joint3'], 'joint_limits': None},
    'obstacles': [{'type': 'sphere', 'center': [1.2, 0.6], 'radius': 0.2}],
    'task': {'start': [2.0, 0.0], 'goal': [1.0, 0.0], 'goal_tolerance': 0.01},
}


def with_change(path, value):
    """GOOD with the item at `path` (a tuple of keys/indices) set to `value` (or deleted)."""
    data = yaml.safe_load(yaml.safe_dump(GOOD))
    node = data
    for key in path[:-1]:
        node = node[key]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


@pytest.mark.parametrize('name', sorted(p.stem for p in SCENES.glob('*.yaml')))
def test_every_shipped_scene_loads(name):
    scene = load_scene(SCENES / f'{name}.yaml')
    assert scene.robot.n_joints == 3
    assert scene.task is not None


def test_contract_example_parses():
    scene = parse_scene(GOOD)
    assert scene.robot.link_lengths == (1.0, 1.0, 1.0)
    assert scene.obstacles[0].center == (1.2, 0.6, 0.0)
    assert scene.task.goal == (1.0, 0.0)
    assert scene.frame_id == 'base_link'


def test_defaults_and_round_trip():
    scene = parse_scene({'robot': {'type': 'planar', 'link_lengths': [1, 2, 3]}})
    assert scene.robot.joint_names == ('joint1', 'joint2', 'joint3')
    assert scene.robot.link_lengths == (1.0, 2.0, 3.0)
    assert scene.task is None and scene.obstacles == ()
    full = parse_scene(GOOD)
    assert parse_scene(scene_to_dict(full)) == full


def test_box_and_cylinder_obstacles():
    scene = parse_scene(with_change(('obstacles',), [
        {'type': 'box', 'center': [1, 1], 'size': [0.2, 0.4], 'rpy': [0, 0, 0.5]},
        {'type': 'cylinder', 'center': [0, 1, 0], 'radius': 0.1, 'length': 2.0}]))
    box, cylinder = scene.obstacles
    assert box.size == (0.2, 0.4, 1.0) and box.rpy == (0.0, 0.0, 0.5)
    assert cylinder.radius == 0.1 and cylinder.length == 2.0


def test_robot_file_reference(tmp_path):
    (tmp_path / 'arm.yaml').write_text(yaml.safe_dump({'robot': GOOD['robot']}))
    (tmp_path / 'scene.yaml').write_text('robot: arm.yaml\n')
    assert load_scene(tmp_path / 'scene.yaml').robot.n_joints == 3
    (tmp_path / 'bad.yaml').write_text('robot: missing.yaml\n')
    with pytest.raises(InputError, match='robot: cannot read robot file missing.yaml'):
        load_scene(tmp_path / 'bad.yaml')


@pytest.mark.parametrize('path, value, field', [
    (('robot', 'link_lengths', 1), -1.0, r'robot\.link_lengths\[1\]: must be > 0'),
    (('robot', 'link_lengths', 0), 0.0, r'robot\.link_lengths\[0\]: must be > 0'),
    (('robot', 'link_lengths', 2), math.nan, r'robot\.link_lengths\[2\]: must be finite'),
    (('robot', 'link_lengths', 2), math.inf, r'robot\.link_lengths\[2\]: must be finite'),
    (('robot', 'link_lengths', 2), True, r'robot\.link_lengths\[2\]: must be a number'),
    (('robot', 'link_lengths', 2), 'long', r'robot\.link_lengths\[2\]: must be a number'),
    (('robot', 'link_lengths'), [], r'robot\.link_lengths: needs at least one link'),
    (('robot', 'link_lengths'), 3.0, r'robot\.link_lengths: must be a list'),
    (('robot', 'link_radius'), -0.1, r'robot\.link_radius: must be >= 0'),
    (('robot', 'type'), 'scara', r'robot\.type: must be "planar", "urdf" or "dh"'),
    (('robot', 'colour'), 'red', r'robot\.colour: unknown key'),
    (('robot', 'joint_names'), ['a', 'a', 'b'], r'robot\.joint_names: names must be unique'),
    (('robot', 'joint_names'), ['a', 'b'], r'robot\.joint_names: has 2 names for 3 joints'),
    (('robot', 'joint_names', 1), '', r'robot\.joint_names\[1\]: must be a non-empty string'),
    (('robot', 'joint_limits'), [[0, 1]], r'robot\.joint_limits: has 1 entries for 3 joints'),
    (('robot', 'joint_limits'), [None, [1, 0], None], r'robot\.joint_limits\[1\]: lower limit'),
    (('robot', 'link_lengths'), KeyError, r'robot\.link_lengths: is missing'),
    (('obstacles', 0, 'radius'), 0.0, r'obstacles\[0\]\.radius: must be > 0'),
    (('obstacles', 0, 'radius'), -0.2, r'obstacles\[0\]\.radius: must be > 0'),
    (('obstacles', 0, 'center'), [1.0], r'obstacles\[0\]\.center: needs 2 or 3 values'),
    (('obstacles', 0, 'center', 0), math.nan, r'obstacles\[0\]\.center\[0\]: must be finite'),
    (('obstacles', 0, 'type'), 'cone', r'obstacles\[0\]\.type: must be one of'),
    (('obstacles', 0, 'size'), [1, 1], r'obstacles\[0\]\.size: unknown key'),
    (('obstacles', 0), 'disk', r'obstacles\[0\]: must be a mapping'),
    (('task', 'goal'), [1.0, 0.0, 0.0], r'task\.goal: needs 2 values, got 3'),
    (('task', 'start', 1), math.inf, r'task\.start\[1\]: must be finite'),
    (('task', 'goal_tolerance'), 0.0, r'task\.goal_tolerance: must be > 0'),
    (('task', 'speed'), 1.0, r'task\.speed: unknown key'),
    (('frame_id',), '', r'frame_id: must be a non-empty string'),
    (('extra',), 1, r'scene\.extra: unknown key'),
])
def test_bad_values_name_their_field(path, value, field):
    with pytest.raises(InputError, match=field):
        parse_scene(with_change(path, value))


def test_bad_boxes():
    bad = with_change(('obstacles',), [{'type': 'box', 'center': [1, 1], 'size': [0.2, -1]}])
    with pytest.raises(InputError, match=r'obstacles\[0\]\.size\[1\]: must be > 0'):
        parse_scene(bad)


@pytest.mark.parametrize('text, message', [
    ('robot: {type: planar, link_lengths: [1, 1\n', 'malformed YAML at line'),
    ('robot:\n\t- tab\n', 'malformed YAML'),
    ('- just\n- a list\n', 'scene: must be a mapping'),
    ('', 'scene: must be a mapping'),
])
def test_malformed_files(tmp_path, text, message):
    path = tmp_path / 'scene.yaml'
    path.write_text(text)
    with pytest.raises(InputError, match=message):
        load_scene(path)


def test_missing_file(tmp_path):
    with pytest.raises(InputError, match='cannot read scene file'):
        load_scene(tmp_path / 'nope.yaml')


def test_with_obstacles_keeps_the_rest():
    scene = parse_scene(GOOD)
    more = scene.with_obstacles(scene.obstacles)
    assert len(more.obstacles) == 2 and more.task == scene.task
    assert np.allclose(more.obstacles[1].center, scene.obstacles[0].center)
