"""Motion limits (model/motion_limits.py, io/limits_file.py): URDF, MoveIt file, defaults."""

import math
import shutil

import numpy as np
import pytest
import yaml
from ftplan_testing import ROBOTS, SCENES

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.limits_file import load_joint_limits
from ftplan_ros.core.io.scene_file import load_scene
from ftplan_ros.core.model.motion_limits import (
    DEFAULT_MAX_ACCELERATION,
    DEFAULT_MAX_VELOCITY,
    MotionLimits,
    default_motion_limits,
    motion_limits_digest,
    parse_joint_limits,
    robot_motion_limits,
)

NAMES = ('j1', 'j2')
BASE = default_motion_limits(2, [0.5, 0.0])


def entry(**values):
    return {'joint_limits': {'j1': values}}


def test_the_defaults_take_the_urdf_velocity_where_it_is_given():
    assert BASE.velocity.tolist() == [0.5, DEFAULT_MAX_VELOCITY]
    assert BASE.acceleration.tolist() == [DEFAULT_MAX_ACCELERATION] * 2
    assert not BASE.jerk_bounded


def test_a_moveit_file_replaces_the_limits_it_gives_and_keeps_the_rest():
    limits = parse_joint_limits(entry(has_velocity_limits=True, max_velocity=3.0,
                                      has_acceleration_limits=True, max_acceleration=4.0,
                                      has_jerk_limits=True, max_jerk=50.0,
                                      has_position_limits=False), NAMES, BASE)
    assert limits.velocity.tolist() == [3.0, DEFAULT_MAX_VELOCITY]
    assert limits.acceleration.tolist() == [4.0, DEFAULT_MAX_ACCELERATION]
    assert limits.jerk[0] == 50.0 and math.isinf(limits.jerk[1])


def test_a_limit_whose_flag_is_false_is_not_taken():
    limits = parse_joint_limits(entry(has_velocity_limits=False, max_velocity=9.0), NAMES, BASE)
    assert limits.velocity[0] == 0.5


@pytest.mark.parametrize('data, field', [
    ({'joint_limits': {'j9': {}}}, 'joint_limits.joint_limits.j9'),
    (entry(has_velocity_limits=True), 'joint_limits.joint_limits.j1.max_velocity'),
    (entry(has_velocity_limits=True, max_velocity=-1.0),
     'joint_limits.joint_limits.j1.max_velocity'),
    (entry(has_acceleration_limits=True, max_acceleration=float('nan')),
     'joint_limits.joint_limits.j1.max_acceleration'),
    (entry(has_jerk_limits='yes', max_jerk=1.0), 'joint_limits.joint_limits.j1.has_jerk_limits'),
    (entry(max_speed=1.0), 'joint_limits.joint_limits.j1.max_speed'),
    ({'limits': {}}, 'joint_limits.limits'),
    ([], 'joint_limits'),
])
def test_a_bad_file_names_the_field(data, field):
    with pytest.raises(InputError) as error:
        parse_joint_limits(data, NAMES, BASE)
    assert error.value.field == field


@pytest.mark.parametrize('factors', [(0.0, 1.0), (1.0, 1.5), (float('nan'), 1.0)])
def test_scaling_factors_outside_0_1_are_refused(factors):
    with pytest.raises(InputError):
        BASE.scaled(*factors)


def test_scaling_multiplies_velocity_and_acceleration_and_jerk_with_acceleration():
    limits = parse_joint_limits(entry(has_jerk_limits=True, max_jerk=10.0), NAMES, BASE)
    scaled = limits.scaled(0.5, 0.25)
    assert np.allclose(scaled.velocity, limits.velocity * 0.5)
    assert np.allclose(scaled.acceleration, limits.acceleration * 0.25)
    assert scaled.jerk[0] == 2.5


def test_the_shipped_robots_reference_the_vendors_limits():
    panda = robot_motion_limits(load_scene(SCENES / 'panda_shelf.yaml').robot)
    assert panda.velocity.tolist() == [2.175] * 4 + [2.61] * 3
    assert panda.acceleration.tolist() == [15.0, 7.5, 10.0, 12.5, 15.0, 20.0, 20.0]
    assert panda.jerk.tolist() == [7500.0, 3750.0, 5000.0, 6250.0, 7500.0, 10000.0, 10000.0]
    iiwa = robot_motion_limits(load_scene(SCENES / 'iiwa_table.yaml').robot)
    assert np.allclose(np.degrees(iiwa.velocity), [85, 85, 100, 75, 130, 135, 135], atol=1e-4)
    planar = robot_motion_limits(load_scene(SCENES / 'fig3a.yaml').robot)
    assert planar.velocity.tolist() == [DEFAULT_MAX_VELOCITY] * 3


def test_a_robot_file_names_its_joint_limits_file_relative_to_itself(tmp_path):
    for name in ('panda.urdf', 'panda.srdf'):
        shutil.copy(ROBOTS / name, tmp_path / name)
    robot = yaml.safe_load((ROBOTS / 'panda.yaml').read_text())
    robot['robot']['joint_limits'] = 'limits/mine.yaml'
    (tmp_path / 'limits').mkdir()
    (tmp_path / 'limits' / 'mine.yaml').write_text(yaml.safe_dump(
        {'joint_limits': {'panda_joint3': {'has_acceleration_limits': True,
                                           'max_acceleration': 1.25}}}))
    (tmp_path / 'panda.yaml').write_text(yaml.safe_dump(robot))
    (tmp_path / 'scene.yaml').write_text(yaml.safe_dump({'robot': 'panda.yaml'}))
    limits = robot_motion_limits(load_scene(tmp_path / 'scene.yaml').robot)
    assert limits.acceleration[2] == 1.25 and limits.velocity[0] == 2.175
    (tmp_path / 'limits' / 'mine.yaml').unlink()
    with pytest.raises(InputError) as error:
        load_scene(tmp_path / 'scene.yaml')
    assert error.value.field == 'robot.joint_limits'


def test_load_joint_limits_reads_a_file(tmp_path):
    path = tmp_path / 'limits.yaml'
    path.write_text('joint_limits: {j2: {has_velocity_limits: true, max_velocity: 0.25}}\n')
    assert load_joint_limits(path, NAMES, BASE).velocity.tolist() == [0.5, 0.25]
    path.write_text('joint_limits: {j2: [1, 2\n')
    with pytest.raises(InputError):
        load_joint_limits(path, NAMES, BASE)


def test_the_motion_limits_digest_names_the_limits_a_plan_is_timed_within():
    """Issue 36, item 3: velocity, acceleration and jerk, as scaled; unbounded jerk too."""
    panda = robot_motion_limits(load_scene(SCENES / 'panda_shelf.yaml').robot)
    digest = motion_limits_digest(panda)
    assert len(digest) == 12 and int(digest, 16) >= 0
    assert motion_limits_digest(panda.scaled(1.0, 1.0)) == digest           # stable
    others = [panda.scaled(0.5, 1.0), panda.scaled(1.0, 0.5), BASE, BASE.scaled(1.0, 0.9),
              MotionLimits(panda.velocity, panda.acceleration, panda.jerk * 2.0)]
    assert len({digest, *map(motion_limits_digest, others)}) == len(others) + 1
    # Scaled limits are the limits: the same numbers from another file give the same digest.
    halved = MotionLimits(panda.velocity * 0.5, panda.acceleration, panda.jerk)
    assert motion_limits_digest(halved) == motion_limits_digest(panda.scaled(0.5, 1.0))
