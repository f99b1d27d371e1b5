"""The MuJoCo arm (simulation/mujoco_arm.py, mujoco_model.py) without ROS.

The translation is checked against our own kinematics; the arm is stepped by hand at
100 Hz. The obstacles are what the sim node hands the arm: a checker over the scene's.
"""

from dataclasses import dataclass

import mujoco
import numpy as np
import pytest
from ftplan_testing import ROBOTS, SCENES

from ftplan_ros.core import CollisionChecker, InputError, load_scene
from ftplan_ros.core.model.scene import Obstacle
from ftplan_ros.simulation.arm import ArmOptions, Locked
from ftplan_ros.simulation.mujoco_arm import MujocoArm
from ftplan_ros.simulation.mujoco_model import (
    PhysicsOptions,
    find_physics_file,
    model_xml,
    read_physics_options,
)

DT = 0.01  # [s] a step at 100 Hz


@dataclass
class Obstacles:
    """The obstacles of the moment, as the sim node's ObstacleSet holds them."""

    checker: CollisionChecker
    lost: str = ''


def physics_for(robot) -> PhysicsOptions:
    path = find_physics_file(ROBOTS, robot.joint_names)
    return read_physics_options(path.read_text(), path.name)


def mujoco_arm(scene_name: str, q) -> tuple[MujocoArm, Obstacles]:
    scene = load_scene(SCENES / f'{scene_name}.yaml')
    obstacles = Obstacles(CollisionChecker(scene.robot, scene.obstacles))
    return MujocoArm(scene.robot, np.array(q, dtype=float), ArmOptions(),
                     physics_for(scene.robot), obstacles), obstacles


def run(arm: MujocoArm, seconds: float) -> list:
    return [arm.step(DT) for _ in range(round(seconds / DT))]


@pytest.mark.parametrize('scene_name', ['fig3a', 'arm4_spheres', 'panda_shelf', 'iiwa_table'])
def test_mujoco_poses_every_link_where_our_kinematics_does(scene_name):
    """Planar, DH and URDF arms: MuJoCo's body frames are our link frames at any q."""
    scene = load_scene(SCENES / f'{scene_name}.yaml')
    robot = scene.robot
    model = mujoco.MjModel.from_xml_string(model_xml(robot, scene.obstacles, PhysicsOptions()))
    data = mujoco.MjData(model)
    rng = np.random.default_rng(3)
    low, high = np.maximum(robot.limits[:, 0], -3.0), np.minimum(robot.limits[:, 1], 3.0)
    for q in rng.uniform(low, high, size=(5, robot.n_joints)):
        data.qpos[[model.joint(name).qposadr[0] for name in robot.joint_names]] = q
        mujoco.mj_kinematics(model, data)
        for link, frame in zip(robot.link_names, robot.link_frames(q), strict=True):
            body = model.body(link).id
            assert np.allclose(data.xpos[body], frame[:3, 3], atol=1e-9)
            assert np.allclose(data.xmat[body].reshape(3, 3), frame[:3, :3], atol=1e-9)
    assert model.ngeom == len(robot.collision_shapes) + len(scene.obstacles)
    assert model.nu == 2 * robot.n_joints  # a position and a velocity servo per joint


def test_obstacles_become_static_geoms_of_their_size_and_place():
    box = Obstacle('box', (0.7, 0.0, 0.2), size=(0.3, 0.8, 0.02), rpy=(0.0, 0.0, 0.5))
    scene = load_scene(SCENES / 'panda_shelf.yaml')
    model = mujoco.MjModel.from_xml_string(model_xml(scene.robot, [box], PhysicsOptions()))
    geom = model.geom('obstacle0')
    assert geom.bodyid[0] == 0 and geom.type[0] == mujoco.mjtGeom.mjGEOM_BOX
    assert np.allclose(geom.size, [0.15, 0.4, 0.01]) and np.allclose(geom.pos, box.center)
    assert np.allclose(geom.quat, [np.cos(0.25), 0.0, 0.0, np.sin(0.25)])


def test_the_arm_tracks_a_command_and_settles_at_its_end():
    arm, _ = mujoco_arm('panda_shelf', [0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.0])
    goal = np.array([0.3, -0.3, 0.2, -1.8, 0.2, 1.7, 0.3])
    arm.follow(goal[None], np.array([0.5]), 0, 0)
    run(arm, 2.0)
    assert not arm.moving and np.max(np.abs(arm.q - goal)) < 1e-3
    assert 0.0 < arm.tracking_error < 0.05
    # A joint's lag turns the points beyond it about its axis: no point of the skeleton
    # strays farther than the lever arms to the tool times the largest lag.
    reach = float(np.sum(arm.robot.tip_lever_arms()))
    assert 0.0 < arm.tracking_displacement <= arm.tracking_error * reach


def test_a_locked_joint_is_held_by_its_brake_while_the_others_move():
    """Panda's shoulder (joint 2) carries the arm's weight: the brake holds it there."""
    start = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.0])
    arm, _ = mujoco_arm('panda_shelf', start)
    outcome = arm.lock(1, None, 0)
    assert isinstance(outcome, Locked) and outcome.angle == pytest.approx(-0.5, abs=1e-6)
    goal = start + np.array([0.4, 0.4, 0.3, 0.3, 0.3, 0.3, 0.3])  # moves joint 2 too
    following = arm.follow(goal[None], np.array([0.5]), 0, 0)
    assert [held.joint for held in following.held] == [1]
    held = [abs(arm.q[1] - outcome.angle) for _ in range(150) if arm.step(DT)]
    assert max(held) < 1e-3
    free = [0, 2, 3, 4, 5, 6]
    assert np.max(np.abs(arm.q[free] - goal[free])) < 1e-3
    assert abs(arm.effort()[1]) > 1.0  # the brake's torque, holding the arm's weight [Nm]


def test_a_lock_with_brake_on_lock_stops_the_arm_soon():
    arm, _ = mujoco_arm('fig3a', [0.0, 0.0, 0.0])
    arm.follow(np.array([[1.0, 1.0, 1.0]]), np.array([1.0]), 0, 0)
    run(arm, 0.3)
    arm.lock(2, None, 0)
    run(arm, 1.0)
    # The free joints brake at the acceleration limits (planar3r's default 2 rad/s²): from
    # 1 rad/s that takes 0.5 s, then the actuators settle.
    assert not arm.moving and 0.5 <= arm.standstill_time < 0.7


def test_a_colliding_command_is_reported_as_a_contact_with_its_bodies_and_depth():
    """fig3a's first sphere lies in the way of link 1 turning: both bodies are named."""
    arm, _ = mujoco_arm('fig3a', [0.0, 0.0, 0.0])
    arm.follow(np.array([[0.6, 0.0, 0.0]]), np.array([1.0]), 0, 0)
    contacts = [contact for step in run(arm, 1.5) for contact in step.contacts]
    assert contacts, 'no contact reported'
    first = contacts[0]
    assert {first.first, first.second} == {'link1', 'obstacle0'} and first.depth > 0.0


def test_an_obstacle_update_reaches_mujoco():
    """Without the sphere the same command touches nothing; with it back, it does."""
    scene = load_scene(SCENES / 'fig3a.yaml')
    arm, obstacles = mujoco_arm('fig3a', [0.0, 0.0, 0.0])
    obstacles.checker = CollisionChecker(scene.robot, ())
    arm.follow(np.array([[0.6, 0.0, 0.0]]), np.array([1.0]), 0, 0)
    assert not any(step.contacts for step in run(arm, 1.5))
    obstacles.checker = CollisionChecker(scene.robot, scene.obstacles)
    assert any(step.contacts for step in run(arm, 0.5))


def test_joint_states_carry_the_torques_that_hold_the_arm_against_gravity():
    arm, _ = mujoco_arm('panda_shelf', [0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.0])
    run(arm, 0.5)
    step = arm.step(DT)
    assert np.allclose(step.effort, arm.data.qfrc_bias[arm._dof], atol=0.05)
    assert np.max(np.abs(step.effort)) > 1.0 and np.max(np.abs(step.velocity)) < 1e-2


def test_a_bad_physics_file_names_the_field_to_fix():
    with pytest.raises(InputError, match=r'panda_mujoco.yaml: mujoco.joints.j1.kp'):
        read_physics_options('mujoco:\n  joints:\n    j1: {kp: -1.0, kv: 1.0, torque: 1.0}\n',
                             'panda_mujoco.yaml')
    with pytest.raises(InputError, match=r'mujoco.timestep'):
        read_physics_options('mujoco: {timestep: .nan}\n', 'x.yaml')
    with pytest.raises(InputError, match=r'mujoco.damping.*unknown key'):
        read_physics_options('mujoco: {damping: 1.0}\n', 'x.yaml')


def test_the_physics_file_is_found_by_the_robots_joint_names():
    assert find_physics_file(ROBOTS, ['panda_joint1']).name == 'panda_mujoco.yaml'
    assert find_physics_file(ROBOTS, ['joint1', 'joint2', 'joint3']).name == \
        'planar3r_mujoco.yaml'
    assert find_physics_file(ROBOTS, ['no_such_joint']) is None
