"""The nodes' small helpers: path timing and progress, approach moves, obstacle shapes."""

import numpy as np
import pytest
from ros_support import SCENES
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py import create_obstacle_markers
from ftplan_ros.core import Obstacle, load_scene
from ftplan_ros.core.angles import wrap_angle
from ftplan_ros.nodes.motion import progress_along, straight_moves, time_path
from ftplan_ros.nodes.obstacles import (
    ObstacleSet,
    obstacle_from_shape,
    quaternion_from_rpy,
    rpy_from_quaternion,
    shape_from_obstacle,
)
from ftplan_ros.nodes.planner import display_web
from ftplan_ros.nodes.sim import Motion, default_initial_configuration


def test_time_path_keeps_the_speed_limit_and_strictly_increasing_times():
    path = np.array([[0.0, 0.0], [0.5, -1.0], [0.5, -1.0], [0.6, -1.0]])
    times = time_path(path, max_speed=2.0)
    assert times[0] == 0.0 and np.all(np.diff(times) > 0.0)
    speeds = np.abs(np.diff(path, axis=0)).max(axis=1) / np.diff(times)
    assert speeds.max() == pytest.approx(2.0)


def test_progress_along_a_path_also_across_whole_turns():
    path = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    assert progress_along(path, np.array([0.5, 0.0, 0.0])) == pytest.approx((0.25, 0.0))
    assert progress_along(path, np.array([1.0, 1.0, 0.0]))[0] == pytest.approx(1.0)
    fraction, distance = progress_along(path, np.array([1.0, 0.5, 0.1]))
    assert fraction == pytest.approx(0.75) and distance == pytest.approx(0.1)
    turned = np.array([1.0 + 2 * np.pi, 0.5, 0.0])
    assert progress_along(path, turned, np.ones(3, bool)) == pytest.approx((0.75, 0.0))
    assert progress_along(path, turned)[1] > 6.0                 # not periodic: far away


def test_straight_moves_offer_both_ways_round_shortest_first():
    periodic = np.array([True, True, False])
    moves = straight_moves(np.array([3.0, 0.0, 0.0]), np.array([-3.0, 0.5, 1.0]), periodic)
    assert len(moves) == 4
    lengths = [np.linalg.norm(m[1] - m[0]) for m in moves]
    assert lengths == sorted(lengths)
    for move in moves:
        assert np.allclose(wrap_angle(move[1, :2]), wrap_angle(np.array([-3.0, 0.5])))
        assert move[1, 2] == 1.0
    assert moves[0][1, 0] == pytest.approx(2 * np.pi - 3.0)      # through pi, not round zero


@pytest.mark.parametrize('obstacle', [
    Obstacle('sphere', (1.0, 0.5, 0.0), radius=0.2),
    Obstacle('box', (0.5, -1.0, 0.2), size=(0.2, 0.4, 1.0), rpy=(0.0, 0.0, 0.7)),
    Obstacle('cylinder', (-1.0, 1.0, 0.0), radius=0.1, length=2.0, rpy=(0.3, -0.2, 1.1)),
])
def test_obstacles_survive_the_marker_round_trip(obstacle):
    back = obstacle_from_shape(shape_from_obstacle(('ns', 3), obstacle))
    assert back.shape == obstacle.shape
    assert np.allclose(back.center, obstacle.center)
    assert back.radius == pytest.approx(obstacle.radius)
    assert np.allclose(back.size, obstacle.size) and back.length == pytest.approx(obstacle.length)
    assert np.allclose(back.rpy, obstacle.rpy)
    q = quaternion_from_rpy(obstacle.rpy)
    assert np.linalg.norm(q) == pytest.approx(1.0)
    assert np.allclose(rpy_from_quaternion(q), obstacle.rpy)


def test_an_obstacle_set_is_all_or_nothing():
    scene = load_scene(SCENES / 'paper_a_free.yaml')
    obstacles = ObstacleSet(scene)
    sphere = shape_from_obstacle(('a', 0), Obstacle('sphere', (1.0, 1.0, 0.0), radius=0.1))
    obstacles.update(create_obstacle_markers([sphere], 'base_link'))
    assert len(obstacles.scene().obstacles) == 1
    bad = MarkerArray(markers=[Marker(action=Marker.DELETEALL),
                               Marker(type=Marker.ARROW, action=Marker.ADD)])
    with pytest.raises(ValueError, match='ARROW'):
        obstacles.update(bad)
    assert len(obstacles) == 1                                    # the DELETEALL did not apply
    assert obstacles.scene().obstacles[0].radius == pytest.approx(0.1)


def test_sim_motion_samples_linearly_and_ends_exactly():
    motion = Motion(np.array([[0.0, 0.0], [1.0, 2.0]]), np.array([0.0, 2.0]), start=10.0)
    assert np.allclose(motion.sample(11.0)[0], [0.5, 1.0])
    q, done = motion.sample(12.5)
    assert done and np.array_equal(q, [1.0, 2.0])
    assert np.array_equal(motion.sample(9.0)[0], [0.0, 0.0])


def test_the_default_initial_configuration_is_at_the_task_start_and_clear():
    scene = load_scene(SCENES / 'fig3a.yaml')
    theta = default_initial_configuration(scene)
    assert np.allclose(scene.robot.forward_kinematics(theta), scene.task.start, atol=1e-9)
    assert np.all(np.abs(theta) <= np.pi)


def test_the_rviz_web_is_thinned_but_keeps_its_border():
    web = np.random.default_rng(0).normal(size=(94, 137, 3))
    thin = display_web(web)
    assert thin.shape == (40, 40, 3)
    assert np.array_equal(thin[0, 0], web[0, 0]) and np.array_equal(thin[-1, -1], web[-1, -1])
    assert display_web(web[:5, :7]).shape == (5, 7, 3)
