"""Scene files (core/io/scene_file.py): the format of CONTRACT.md, each bad value named."""

import itertools
import math
import shutil

import numpy as np
import pytest
import yaml
from ftplan_testing import ROBOTS, SCENES, WAM4, bot_urdf, robot_config, write_bot

from ftplan_ros.core.collision.checker import CollisionChecker
from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.fingerprint import scene_to_dict
from ftplan_ros.core.io.scene_file import load_scene, parse_scene
from ftplan_ros.core.model.robot import PlanarChain
from ftplan_ros.core.model.spatial import SpatialArm
from ftplan_ros.core.model.task_space import TASK_DIM

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
    assert scene.task is not None
    assert scene.robot.task_kind == scene.task.kind
    assert scene.robot.n_joints > TASK_DIM[scene.task.kind]


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
    with pytest.raises(InputError, match=r'^robot: cannot read .*missing\.yaml'):
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


@pytest.mark.parametrize('limits', [[-1000.0, 1000.0], [-7.0, 0.0]])
def test_joint_limits_wider_than_a_turn_either_way_are_refused(limits):
    with pytest.raises(ValueError, match=r'robot\.joint_limits\[1\]: limits must be within ±2π'):
        parse_scene(with_change(('robot', 'joint_limits'), [None, limits, None]))


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
    with pytest.raises(InputError, match=r'nope\.yaml: cannot read .*nope\.yaml'):
        load_scene(tmp_path / 'nope.yaml')


# Spatial scenes ---------------------------------------------------------------------------

POSE = {'start': {'position': [0.5, -0.2, 0.4], 'orientation': [1.0, 0.0, 0.0, 0.0]},
        'goal': {'position': [0.5, 0.2, 0.4], 'orientation': [0.0, 1.0, 0.0, 0.0]},
        'goal_tolerance': 0.005, 'orientation_tolerance': 0.02}
AXIS = {'start': {'position': [0.5, -0.2, 0.4], 'axis': [0.0, 0.0, -1.0]},
        'goal': {'position': [0.5, 0.2, 0.4], 'axis': [0.0, 0.6, -0.8]}}
POSITION = {'start': [0.5, -0.2, 0.4], 'goal': [0.5, 0.2, 0.4]}
PANDA = {'robot': '../robots/panda.yaml', 'task': POSE,
         'obstacles': [{'type': 'box', 'center': [0.5, 0.0, 0.2], 'size': [0.3, 0.6, 0.02]}],
         'tolerate': ['panda_joint7', 'panda_joint1', 'panda_joint2']}


def panda(**changes):
    """The Panda scene PANDA with its keys changed (a value None deletes the key)."""
    data = yaml.safe_load(yaml.safe_dump(PANDA))
    for key, value in changes.items():
        if value is None:
            data.pop(key, None)
        else:
            data[key] = value
    return parse_scene(data, directory=SCENES)


@pytest.mark.parametrize('task, kind', [(POSE, 'pose'), (AXIS, 'axis'), (POSITION, 'position')])
def test_spatial_tasks_set_the_kind(task, kind):
    scene = panda(task=task)
    assert isinstance(scene.robot, SpatialArm) and scene.robot.n_joints == 7
    assert scene.task.kind == scene.robot.task_kind == kind
    assert len(scene.task.goal) == {'pose': 7, 'axis': 6, 'position': 3}[kind]
    assert scene.obstacles[0].size == (0.3, 0.6, 0.02)


def test_pose_and_axis_points_are_in_ros_order_and_unit():
    scene = panda(task={'start': {'position': [0.5, -0.2, 0.4],
                                  'orientation': [0.0, 0.0, 0.0, 1.0005]},
                        'goal': POSE['goal']})
    assert scene.task.start == pytest.approx((0.5, -0.2, 0.4, 0.0, 0.0, 0.0, 1.0))
    assert scene.task.goal[3:] == (0.0, 1.0, 0.0, 0.0)
    assert scene.task.goal_tolerance == 0.01 and scene.task.orientation_tolerance == 0.01
    assert panda().task.goal_tolerance == 0.005
    assert panda().task.orientation_tolerance == 0.02
    axis = panda(task=AXIS).task
    assert axis.goal[3:] == pytest.approx((0.0, 0.6, -0.8))


def test_tolerate_is_kept_in_joint_order():
    scene = panda()
    assert scene.tolerate == ('panda_joint1', 'panda_joint2', 'panda_joint7')
    assert scene.tolerated_joints == (0, 1, 6)
    assert panda(tolerate=None).tolerated_joints == tuple(range(7))
    assert scene.with_tolerated(None).tolerate is None
    assert scene.with_tolerated(['panda_joint3']).tolerated_joints == (2,)


def test_urdf_and_dh_robots_inline(tmp_path):
    write_bot(tmp_path)
    scene = tmp_path / 'scene.yaml'
    scene.write_text(yaml.safe_dump({
        'robot': {'type': 'urdf', 'file': 'testbot.urdf', 'tip_link': 'tcp',
                  'tip_offset': [0.0, 0.0, 0.05]},
        'task': {'start': [0.3, 0.0, 0.5], 'goal': [0.2, 0.2, 0.5]}}))
    robot = load_scene(scene).robot
    assert robot.joint_names == ('spin', 'tilt', 'elbow', 'wrist')
    assert robot.task_kind == 'position'
    assert np.allclose(robot.model.tool[:3, 3],
                       robot.model.tool[:3, :3] @ [0, 0, 0.05] + [0.0, 0.0, 0.1], atol=1e-12)
    dh = parse_scene({'robot': WAM4, 'task': {'start': [0.3, 0.0, 0.5], 'goal': [0.3, 0.1, 0.5]}})
    assert dh.robot.joint_names == tuple(WAM4['joint_names']) and dh.robot.n_joints == 4
    assert list(dh.robot.periodic) == [True, False, False, False]


def test_a_robot_yaml_names_its_urdf_relative_to_itself(tmp_path):
    (tmp_path / 'robots').mkdir()
    (tmp_path / 'scenes').mkdir()
    write_bot(tmp_path / 'robots')
    (tmp_path / 'robots' / 'bot.yaml').write_text(yaml.safe_dump({'robot': {
        'type': 'urdf', 'file': 'testbot.urdf', 'tip_link': 'tcp', 'base_link': 'base',
        'disabled_collisions': [['base', 'l1'], ['l1', 'l2'], ['l2', 'l3'], ['l3', 'hand']]}}))
    (tmp_path / 'scenes' / 'scene.yaml').write_text('robot: ../robots/bot.yaml\n')
    robot = load_scene(tmp_path / 'scenes' / 'scene.yaml').robot
    assert robot.model.disabled_pairs == {(0, 1), (1, 2), (2, 3), (3, 4)}
    assert robot.self_collision_pairs == ((0, 2), (0, 3), (0, 4), (1, 3), (1, 4), (2, 4))


def test_the_shipped_robot_yamls_copied_elsewhere_still_load(tmp_path):
    for name in ('panda.yaml', 'panda.urdf', 'panda_joint_limits.yaml'):
        shutil.copy(ROBOTS / name, tmp_path / name)
    (tmp_path / 'scene.yaml').write_text('robot: panda.yaml\n')
    robot = load_scene(tmp_path / 'scene.yaml').robot
    assert robot.model.disabled_pairs == robot_config('panda').model.disabled_pairs


def test_a_scene_without_a_robot_takes_the_callers(tmp_path):
    path = tmp_path / 'scene.yaml'
    path.write_text(yaml.safe_dump({'task': POSITION, 'tolerate': ['panda_joint2']}))
    arm = robot_config('panda', 'pose')
    scene = load_scene(path, robot=arm)
    assert scene.robot.model is arm.model and scene.robot.task_kind == 'position'
    assert scene.tolerated_joints == (1,)
    with pytest.raises(InputError, match=r'^robot: is missing'):
        load_scene(path)


def task_with(point_key, value):
    task = yaml.safe_load(yaml.safe_dump(POSE))
    task['start'][point_key] = value
    return task


@pytest.mark.parametrize('changes, field', [
    ({'task': task_with('orientation', [1.0, 0.0, 0.0, 0.1])},
     r'task\.start\.orientation: a quaternion must have norm 1'),
    ({'task': task_with('orientation', [1.0, 0.0, 0.0])},
     r'task\.start\.orientation: needs 4 values'),
    ({'task': task_with('orientation', [0.0, 0.0, 0.0, 0.0])},
     r'task\.start\.orientation: a quaternion must have norm 1'),
    ({'task': {'start': AXIS['start'], 'goal': {'position': [0.5, 0.2, 0.4],
                                                'axis': [0.0, 0.0, -2.0]}}},
     r'task\.goal\.axis: an axis must have norm 1'),
    ({'task': task_with('axis', [0.0, 0.0, 1.0])},
     r'task\.start: needs exactly one of orientation \(a pose\) or axis'),
    ({'task': {'start': {'position': [0.5, -0.2, 0.4]}, 'goal': POSE['goal']}},
     r'task\.start: needs exactly one of'),
    ({'task': {'start': POSE['start'], 'goal': [0.5, 0.2, 0.4]}},
     r'task\.goal: must have the same form as task\.start'),
    ({'task': {'start': AXIS['start'], 'goal': POSE['goal']}},
     r'task\.goal: must have the same form as task\.start'),
    ({'task': {'start': [0.5, 0.2], 'goal': [0.5, 0.2, 0.4]}},
     r'task\.start: needs 3 values, got 2'),
    ({'task': task_with('colour', 'red')}, r'task\.start\.colour: unknown key'),
    ({'task': task_with('position', [0.5, math.nan, 0.4])},
     r'task\.start\.position\[1\]: must be finite'),
    ({'tolerate': ['panda_joint1', 'elbow']},
     r"tolerate\[1\]: unknown joint 'elbow' \(joints: panda_joint1"),
    ({'tolerate': ['panda_joint1', 'panda_joint1']}, r'tolerate: names a joint twice'),
    ({'tolerate': []}, r'tolerate: names no joint'),
    ({'obstacles': [{'type': 'sphere', 'center': [0.5, 0.2], 'radius': 0.1}]},
     r'obstacles\[0\]\.center: needs 3 values \(x, y, z\) beside a spatial robot, got 2'),
    ({'obstacles': [{'type': 'box', 'center': [0.5, 0.2, 0.3], 'size': [0.1, 0.1]}]},
     r'obstacles\[0\]\.size: needs 3 values \(x, y, z\) beside a spatial robot, got 2'),
    ({'tolerate': 'panda_joint1'}, r'tolerate: must be a list'),
    ({'robot': {'type': 'urdf', 'file': '../robots/panda.urdf', 'tip_link': 'panda_hand_tcp',
                'disabled_collisions': [['panda_link0', 'panda_link1'],
                                        ['panda_link1', 'panda_finger']]}},
     r"robot\.disabled_collisions\[1\]: unknown link 'panda_finger'"),
    ({'robot': {'type': 'urdf', 'file': '../robots/panda.urdf', 'tip_link': 'panda_hand_tcp',
                'disabled_collisions': [['panda_link0']]}},
     r'robot\.disabled_collisions\[0\]: must be two link names'),
    ({'robot': {'type': 'urdf', 'file': '../robots/nope.urdf', 'tip_link': 'panda_hand_tcp'}},
     r'robot\.file: cannot read .*nope\.urdf'),
    ({'robot': {'type': 'urdf', 'file': '../robots/panda.urdf', 'tip_link': 'panda_hand_tcp',
                'tip_offset': [0.0, 0.1]}},
     r'robot\.tip_offset: needs 3 values'),
    ({'robot': {'type': 'urdf', 'file': '../robots/panda.urdf'}}, r'robot\.tip_link: is missing'),
    ({'robot': {'type': 'urdf', 'file': '../robots/panda.urdf', 'tip_link': 7}},
     r'robot\.tip_link: must be a link name'),
])
def test_bad_spatial_input_names_its_field(changes, field):
    with pytest.raises(InputError, match=field) as error:
        panda(**changes)
    assert '\n' not in str(error.value)


def test_a_planar_arm_takes_planar_points_only():
    data = with_change(('task', 'goal'), {'position': [1.0, 0.0, 0.0],
                                          'orientation': [0.0, 0.0, 0.0, 1.0]})
    with pytest.raises(InputError, match=r'task\.goal: a planar arm takes \[x, y\]'):
        parse_scene(data)
    assert isinstance(parse_scene(GOOD).robot, PlanarChain)


# Robots from URDF files and DH tables ---------------------------------------------------

@pytest.mark.parametrize('row, field', [
    ({'a': 0.1, 'alpha': 0.0}, r'robot\.rows\[0\]\.d: is missing'),
    ({'a': 0.1, 'alpha': 0.0, 'd': 'x'}, r'robot\.rows\[0\]\.d: must be a number'),
    ({'a': 0.1, 'alpha': 0.0, 'd': 0.1, 'theta': 1.0}, r'robot\.rows\[0\]\.theta: unknown key'),
    ({'a': 0.1, 'alpha': 0.0, 'd': 0.1, 'limits': [1.0, 0.0]},
     r'robot\.rows\[0\]\.limits: lower limit'),
])
def test_bad_rows_name_their_field(row, field):
    with pytest.raises(InputError, match=field):
        parse_scene({'robot': {'type': 'dh', 'rows': [row]}})
    with pytest.raises(InputError, match=r'robot\.rows: needs at least one joint'):
        parse_scene({'robot': {'type': 'dh', 'rows': []}})


def test_a_urdf_scene_finds_its_mesh_beside_the_file(urdf_file):
    path = urdf_file(bot_urdf())
    scene = path.parent / 'scene.yaml'
    scene.write_text(yaml.safe_dump({'robot': {'type': 'urdf', 'file': path.name,
                                               'tip_link': 'tcp'}}))
    robot = load_scene(scene).robot
    assert [item.shape.kind for item in robot.collision_shapes].count('mesh') == 1


@pytest.mark.parametrize('name', ['panda', 'iiwa14'])
def test_robot_yamls_load_with_their_disabled_collisions(name):
    robot = robot_config(name)
    listed = yaml.safe_load((ROBOTS / f'{name}.yaml').read_text())['robot']
    disabled = {tuple(sorted(robot.link_names.index(link) for link in pair))
                for pair in listed['disabled_collisions']}
    assert robot.model.disabled_pairs == disabled
    with_geometry = sorted({item.link for item in robot.collision_shapes})
    expected = [pair for pair in itertools.combinations(with_geometry, 2)
                if pair not in disabled]
    assert list(robot.self_collision_pairs) == expected
    checker = CollisionChecker(robot, [])
    checked = {tuple(links) for links in checker.channel_links.tolist() if links[1] >= 0}
    assert checked == set(expected)
    assert robot.link_names[0] == listed['base_link']
    assert robot.model.tool_frame == listed['tip_link']
