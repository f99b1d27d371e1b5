import math

import numpy as np
import pytest
from builtin_interfaces.msg import Duration, Time
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ftplan_msgs_py.joint_trajectory import create_joint_trajectory, read_joint_trajectory

NAMES = ['joint1', 'joint2', 'joint3']


def point(positions, sec=0, nanosec=0):
    return JointTrajectoryPoint(positions=positions,
                                time_from_start=Duration(sec=sec, nanosec=nanosec))


def test_create_fills_every_field():
    q = np.array([[0.0, 0.1, 0.2], [1.0, 1.1, 1.2], [2.0, 2.1, 2.2]])
    msg = create_joint_trajectory(NAMES, q, [0.0, 0.5, 1.25], stamp=Time(sec=2),
                                  frame_id='base_link')
    assert list(msg.joint_names) == NAMES
    assert msg.header.stamp.sec == 2 and msg.header.frame_id == 'base_link'
    assert [(p.time_from_start.sec, p.time_from_start.nanosec) for p in msg.points] == [
        (0, 0), (0, 500_000_000), (1, 250_000_000)]
    assert np.allclose([list(p.positions) for p in msg.points], q)
    assert all(len(p.velocities) == 0 for p in msg.points)


def test_round_trip_allows_equal_times():
    q = np.random.default_rng(1).uniform(-math.pi, math.pi, size=(5, 3))
    t = np.array([0.0, 0.5, 0.5, 1.0, 3.0])
    result = read_joint_trajectory(create_joint_trajectory(NAMES, q, t), NAMES)
    assert np.allclose(result.positions, q)
    assert np.allclose(result.times, t)


def test_empty_trajectory_round_trips():
    msg = create_joint_trajectory(NAMES, [], [])
    assert len(msg.points) == 0
    result = read_joint_trajectory(msg, NAMES)
    assert result.positions.shape == (0, 3)
    assert result.times.shape == (0,)


def test_read_matches_by_name_and_ignores_extra_joints():
    msg = JointTrajectory(joint_names=['joint3', 'gripper', 'joint1', 'joint2'], points=[
        point([3.0, 9.0, 1.0, 2.0], sec=0),
        point([6.0, 9.0, 4.0, 5.0], sec=1, nanosec=500_000_000),
    ])
    positions, times = read_joint_trajectory(msg, NAMES)
    assert np.allclose(positions, [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    assert np.allclose(times, [0.0, 1.5])


def test_read_missing_joint_is_named():
    msg = JointTrajectory(joint_names=['joint1', 'joint3'], points=[point([0.0, 0.0])])
    with pytest.raises(ValueError, match=r"lacks joint\(s\) \['joint2'\]"):
        read_joint_trajectory(msg, NAMES)


def test_read_rejects_duplicate_joint_names():
    msg = JointTrajectory(joint_names=['joint1', 'joint1'], points=[])
    with pytest.raises(ValueError, match="joint_names lists joint 'joint1' twice"):
        read_joint_trajectory(msg, ['joint1'])


def test_read_rejects_point_with_wrong_number_of_positions():
    msg = JointTrajectory(joint_names=NAMES, points=[point([0.0, 0.0, 0.0]),
                                                     point([0.0, 0.0], sec=1)])
    with pytest.raises(ValueError, match='point 1 has 2 positions for 3 joint names'):
        read_joint_trajectory(msg, NAMES)


def test_read_rejects_non_finite_position_naming_point_and_joint():
    msg = JointTrajectory(joint_names=NAMES, points=[point([0.0, 0.0, 0.0]),
                                                     point([0.0, math.nan, 0.0], sec=1)])
    with pytest.raises(ValueError, match="point 1 position of joint 'joint2'"):
        read_joint_trajectory(msg, NAMES)


def test_read_rejects_decreasing_times():
    msg = JointTrajectory(joint_names=NAMES, points=[point([0.0] * 3, sec=2),
                                                     point([0.0] * 3, sec=1)])
    with pytest.raises(ValueError, match=r'decreases from 2\.0 s \(point 0\) to 1\.0 s'):
        read_joint_trajectory(msg, NAMES)


def test_read_rejects_negative_times():
    msg = JointTrajectory(joint_names=NAMES, points=[point([0.0] * 3, sec=-1)])
    with pytest.raises(ValueError, match='point 0 is -1.0 s; times must be >= 0'):
        read_joint_trajectory(msg, NAMES)


def test_create_rejects_decreasing_times():
    with pytest.raises(ValueError, match=r'times_from_start decreases .* \(point 2\)'):
        create_joint_trajectory(NAMES, np.zeros((4, 3)), [0.0, 1.0, 2.0, 1.5])


def test_create_rejects_negative_times():
    with pytest.raises(ValueError, match='>= 0'):
        create_joint_trajectory(NAMES, np.zeros((2, 3)), [-0.5, 1.0])


@pytest.mark.parametrize('bad', [math.nan, math.inf])
def test_create_rejects_non_finite_times_and_positions(bad):
    with pytest.raises(ValueError, match='times_from_start has a non-finite value'):
        create_joint_trajectory(NAMES, np.zeros((2, 3)), [0.0, bad])
    q = np.zeros((2, 3))
    q[1, 2] = bad
    with pytest.raises(ValueError, match=r'positions has a non-finite value .* \(1, 2\)'):
        create_joint_trajectory(NAMES, q, [0.0, 1.0])


@pytest.mark.parametrize('positions', [np.zeros((2, 2)), np.zeros(3), np.zeros((2, 3, 1))])
def test_create_rejects_positions_not_k_by_n(positions):
    with pytest.raises(ValueError, match=r'positions has shape .*; pass \(k, 3\)'):
        create_joint_trajectory(NAMES, positions, [0.0, 1.0])


def test_create_rejects_times_of_wrong_length():
    with pytest.raises(ValueError, match=r'times_from_start has shape \(3,\); pass \(2,\)'):
        create_joint_trajectory(NAMES, np.zeros((2, 3)), [0.0, 1.0, 2.0])


def test_create_rejects_duplicate_names():
    with pytest.raises(ValueError, match='twice'):
        create_joint_trajectory(['joint1', 'joint1'], np.zeros((1, 2)), [0.0])


def test_create_rejects_a_frame_id_that_is_not_a_string():
    with pytest.raises(ValueError, match='frame_id must be a string'):
        create_joint_trajectory(NAMES, np.zeros((1, 3)), [0.0], frame_id=3)


def test_create_fills_velocities_and_accelerations_when_given():
    msg = create_joint_trajectory(['a', 'b'], [[0.0, 1.0], [0.5, 1.5]], [0.1, 0.2],
                                  velocities=[[1.0, 2.0], [0.0, 0.0]],
                                  accelerations=[[3.0, 4.0], [0.0, 0.0]])
    assert list(msg.points[0].velocities) == [1.0, 2.0]
    assert list(msg.points[0].accelerations) == [3.0, 4.0]
    assert list(create_joint_trajectory(['a'], [[0.0]], [0.1]).points[0].velocities) == []


@pytest.mark.parametrize('rates', [{'velocities': [[1.0]]},
                                   {'accelerations': [[math.nan, 0.0]]}])
def test_create_rejects_rates_unlike_the_positions(rates):
    with pytest.raises(ValueError):
        create_joint_trajectory(['a', 'b'], [[0.0, 1.0]], [0.1], **rates)
