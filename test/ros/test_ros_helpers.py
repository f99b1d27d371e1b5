"""The nodes' small helpers: path timing and progress, approach moves, obstacle shapes."""

from dataclasses import replace

import numpy as np
import pytest
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from hypothesis import given, settings
from hypothesis import strategies as st
from ros_support import SCENES
from scipy.spatial.transform import Rotation
from spatial_scenes import panda_scene
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py import create_obstacle_markers
from ftplan_ros.core import CollisionChecker, InputError, Obstacle, Task, load_scene, task_errors
from ftplan_ros.core.model.angles import wrap_angle
from ftplan_ros.core.model.paths import point_at_fraction
from ftplan_ros.core.planning.approach import straight_move_ends
from ftplan_ros.core.validation import LARGEST_NUMBER
from ftplan_ros.execution.motion import (
    fraction_at_time,
    progress_along,
    time_at_fraction,
    time_path,
)
from ftplan_ros.nodes.obstacles import (
    ObstacleSet,
    obstacle_from_shape,
    quaternion_from_rpy,
    rpy_from_quaternion,
    shape_from_obstacle,
)
from ftplan_ros.nodes.plan_markers import display_web
from ftplan_ros.nodes.sim import task_scene
from ftplan_ros.nodes.tasks import (
    bind_task_kind,
    convert_task_point,
    end_effector_poses,
    kind_of_point,
    pose_of_task_point,
    task_point,
)
from ftplan_ros.simulation.initial import default_initial_configuration
from ftplan_ros.simulation.kinematic import Motion


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


def test_fractions_and_times_along_a_timed_path_are_one_measure_and_inverse():
    """The fraction of a timed path is of its length (as progress_along measures it), not of
    its time or its points; a pause holds it; time_at_fraction gives the first time."""
    path = np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 4.0], [3.0, 10.0]])   # lengths 5, 0, 6
    times = np.array([0.0, 1.0, 1.5, 4.5])
    assert fraction_at_time(path, times, 0.5) == pytest.approx(2.5 / 11)
    assert fraction_at_time(path, times, 1.2) == pytest.approx(5 / 11)       # the pause
    assert fraction_at_time(path, times, 3.0) == pytest.approx(8 / 11)
    assert (fraction_at_time(path, times, -1.0), fraction_at_time(path, times, 9.0)) == (0, 1)
    assert time_at_fraction(path, times, 5 / 11) == pytest.approx(1.0)
    assert time_at_fraction(path, times, 8 / 11) == pytest.approx(3.0)
    assert (time_at_fraction(path, times, 0.0), time_at_fraction(path, times, 1.0)) == (0, 4.5)
    for fraction in np.linspace(0.0, 1.0, 23):
        moment = time_at_fraction(path, times, fraction)
        assert fraction_at_time(path, times, moment) == pytest.approx(fraction)
        assert progress_along(path, point_at_fraction(path, fraction))[0] == \
            pytest.approx(fraction)


def test_straight_moves_offer_both_ways_round_shortest_first():
    periodic = np.array([True, True, False])
    q = np.array([3.0, 0.0, 0.0])
    moves = [np.stack([q, end]) for end in
             straight_move_ends(q, np.array([-3.0, 0.5, 1.0]), periodic)]
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


HUGE = st.one_of(st.floats(), st.sampled_from([1e300, -1e300, 1e6, 1.0000001e6, 5e-324]))


@pytest.mark.filterwarnings('ignore:overflow encountered:RuntimeWarning')  # norms of 1e300
@settings(max_examples=150, deadline=None, derandomize=True, database=None)
@given(st.lists(st.tuples(st.sampled_from([Marker.SPHERE, Marker.CUBE, Marker.CYLINDER]),
                          st.sampled_from([Marker.ADD, Marker.DELETE, Marker.DELETEALL]),
                          st.integers(0, 3), st.tuples(HUGE, HUGE, HUGE),
                          st.tuples(HUGE, HUGE, HUGE, HUGE), st.tuples(HUGE, HUGE, HUGE)),
                max_size=5))
def test_any_marker_array_gives_bounded_obstacles_or_a_value_error_leaving_the_set(markers):
    """Huge, tiny and non-finite numbers all the way to the core's obstacles."""
    obstacles = ObstacleSet(load_scene(SCENES / 'paper_a_free.yaml'))
    sphere = shape_from_obstacle(('a', 0), Obstacle('sphere', (1.0, 1.0, 0.0), radius=0.1))
    obstacles.update(create_obstacle_markers([sphere], 'base_link'))
    before = obstacles.scene().obstacles
    msg = MarkerArray(markers=[Marker(
        header=Header(frame_id='base_link'), ns='n', id=key, type=kind, action=action,
        pose=Pose(position=Point(x=p[0], y=p[1], z=p[2]),
                  orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3])),
        scale=Vector3(x=v[0], y=v[1], z=v[2])) for kind, action, key, p, q, v in markers])
    try:
        obstacles.update(msg)
    except ValueError as error:
        assert 'obstacle' in str(error)
        assert obstacles.scene().obstacles == before
        return
    for obstacle in obstacles.scene().obstacles:
        for name in ('center', 'radius', 'size', 'length', 'rpy'):
            values = np.atleast_1d(getattr(obstacle, name))
            assert np.all(np.isfinite(values)) and np.all(np.abs(values) <= LARGEST_NUMBER)


def test_sim_motion_samples_linearly_and_ends_exactly():
    motion = Motion(np.array([[0.0, 0.0], [1.0, 2.0]]), np.array([0.0, 2.0]), start=10.0)
    assert np.allclose(motion.sample(11.0)[0], [0.5, 1.0])
    q, done = motion.sample(12.5)
    assert done and np.array_equal(q, [1.0, 2.0])
    assert np.array_equal(motion.sample(9.0)[0], [0.0, 0.0])


def test_the_sim_motion_sweeps_through_every_waypoint_it_passes():
    corner = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
    motion = Motion(corner, np.array([0.0, 1.0, 2.0]), start=10.0)
    swept, finished = motion.swept(10.5, 11.5)
    assert np.allclose(swept, [[0.5, 0.0], [1.0, 0.0], [1.0, 0.5]]) and not finished
    assert np.allclose(motion.swept(10.2, 10.4)[0], [[0.2, 0.0], [0.4, 0.0]])
    swept, finished = motion.swept(11.5, 13.0)
    assert np.allclose(swept, [[1.0, 0.5], [1.0, 1.0], [1.0, 1.0]]) and finished


def test_the_sim_motion_puts_a_moment_of_its_command_on_its_own_clock():
    """Commanded 1 s a step from stamp 100 s, started at sim time 10 s; the sim slowed the
    second step to 3 s: a moment of the command maps to where the arm is then."""
    motion = Motion(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]), np.array([0.0, 1.0, 4.0]),
                    start=10.0, commanded=np.array([0.0, 1.0, 2.0]), stamp_ns=100 * 10**9)
    assert motion.time_of(100_500_000_000) == pytest.approx(10.5)
    assert motion.time_of(101_500_000_000) == pytest.approx(12.5)
    assert np.allclose(motion.sample(motion.time_of(101_500_000_000))[0], [1.0, 0.5])
    assert motion.time_of(99 * 10**9) == 10.0 and motion.time_of(200 * 10**9) == 14.0


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


@pytest.mark.parametrize('kind', ['pose', 'position'])
def test_the_default_initial_configuration_of_a_7_joint_arm_is_at_the_start_within_limits(
        tmp_path, kind):
    """r = 1 (pose): the clearest point of M_s; r = 4 (position): the clearest IK solution."""
    scene = task_scene(load_scene(panda_scene(tmp_path)), kind)
    robot = scene.robot
    theta = default_initial_configuration(scene)
    assert np.all(task_errors(robot, np.array(scene.task.start), theta) < 1e-9)
    assert np.all(robot.limits[:, 0] <= theta) and np.all(theta <= robot.limits[:, 1])
    assert CollisionChecker(robot, scene.obstacles).min_clearance(theta[None])[0] > 0.0
    unreachable = replace(scene, task=Task((5.0,) * len(scene.task.start),
                                           scene.task.goal))
    fallback = default_initial_configuration(unreachable)
    assert np.all(robot.limits[:, 0] <= fallback) and np.all(fallback <= robot.limits[:, 1])


def test_task_points_from_poses_and_between_kinds():
    rotation = Rotation.from_euler('xyz', [0.3, -0.5, 1.1])
    q = rotation.as_quat()
    p = np.array([0.4, -0.2, 0.6])
    pose = task_point('pose', p, q)
    axis = task_point('axis', p, q)
    assert np.allclose(axis[3:], rotation.as_matrix()[:, 2])
    assert np.array_equal(task_point('position', p, None), p)
    assert np.array_equal(task_point('planar', p, None), p[:2])
    assert np.allclose(convert_task_point(pose, 'axis'), axis)
    assert np.allclose(convert_task_point(axis, 'position'), p)
    assert convert_task_point(axis, 'pose') is None
    assert convert_task_point(p, 'axis') is None and convert_task_point(p[:2], 'position') is None
    # Back to a pose: an axis becomes an orientation whose z axis it is.
    position, quaternion = pose_of_task_point(axis)
    assert np.allclose(position, p)
    assert np.allclose(Rotation.from_quat(quaternion).as_matrix()[:, 2], axis[3:])
    assert np.allclose(pose_of_task_point(pose)[1], q)
    planar_position, no_orientation = pose_of_task_point([1.0, 2.0])
    assert np.array_equal(planar_position, [1.0, 2.0, 0.0]) and no_orientation is None
    with pytest.raises(ValueError, match='2, 3, 6 or 7 numbers'):
        kind_of_point([0.0] * 4)


def test_task_kinds_bind_spatial_arms_only(tmp_path):
    arm = load_scene(panda_scene(tmp_path)).robot
    assert bind_task_kind(arm, 'axis').task_dim == 5 and bind_task_kind(arm, '') is arm
    planar = load_scene(SCENES / 'paper_a_free.yaml').robot
    assert bind_task_kind(planar, 'planar') is planar
    with pytest.raises(InputError, match="task_kind: 'position': a planar arm"):
        bind_task_kind(planar, 'position')
    with pytest.raises(InputError, match="'planar': a spatial arm"):
        bind_task_kind(arm, 'planar')
    positions, orientations = end_effector_poses(arm, np.zeros((3, 7)))
    assert positions.shape == (3, 3) and orientations.shape == (3, 4)
    assert end_effector_poses(planar, np.zeros((2, 3)))[1] is None


def test_obstacles_that_come_before_the_robot_wait_for_it():
    scene = load_scene(SCENES / 'paper_a_free.yaml')
    obstacles = ObstacleSet(None)
    sphere = shape_from_obstacle(('a', 0), Obstacle('sphere', (1.0, 1.0, 0.0), radius=0.1))
    obstacles.update(create_obstacle_markers([sphere], 'base_link'))
    obstacles.update(create_obstacle_markers([sphere], 'map'))         # wrong frame
    assert obstacles.scene() is None and obstacles.checker is None and obstacles.pending == 2
    problems = obstacles.rebase(scene)
    assert len(problems) == 1 and "in frame 'map'" in problems[0]
    assert len(obstacles) == 1 and obstacles.pending == 0
    assert obstacles.checker.min_clearance(np.zeros((1, 3)))[0] > 0.0
    assert obstacles.scene().obstacles[0].radius == pytest.approx(0.1)
