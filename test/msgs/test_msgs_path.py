import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from nav_msgs.msg import Path
from std_msgs.msg import Header

from ftplan_msgs_py.path import create_path, read_path, read_path_poses

QUATERNIONS = np.array([[0.0, 0.0, 0.0, 1.0], [1.0, 0.0, 0.0, 0.0],
                        [0.5, 0.5, 0.5, 0.5], [0.0, 0.6, 0.0, 0.8]])


def test_create_2d_path_sets_z_zero_identity_orientation_and_stamps():
    msg = create_path([[2.0, 0.0], [1.5, 0.5], [1.0, 0.0]], 'base_link',
                      stamp=Time(sec=10, nanosec=20))
    assert msg.header.frame_id == 'base_link'
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (10, 20)
    assert len(msg.poses) == 3
    for pose in msg.poses:
        assert pose.header.frame_id == 'base_link'
        assert (pose.header.stamp.sec, pose.header.stamp.nanosec) == (10, 20)
        assert pose.pose.position.z == 0.0
        o = pose.pose.orientation
        assert (o.x, o.y, o.z, o.w) == (0.0, 0.0, 0.0, 1.0)
    assert np.allclose(read_path(msg), [[2.0, 0.0, 0.0], [1.5, 0.5, 0.0], [1.0, 0.0, 0.0]])


def test_3d_round_trip():
    positions = np.random.default_rng(0).uniform(-2.0, 2.0, size=(20, 3))
    assert np.allclose(read_path(create_path(positions, 'world')), positions)


def test_empty_path_means_no_plan():
    msg = create_path([], 'base_link')
    assert len(msg.poses) == 0
    assert read_path(msg).shape == (0, 3)
    assert read_path(create_path(np.zeros((0, 2)), 'base_link')).shape == (0, 3)


def test_read_hand_built_path_with_unframed_poses():
    msg = Path(header=Header(frame_id='base_link'), poses=[
        PoseStamped(pose=Pose(position=Point(x=1.0, y=2.0, z=3.0))),
        PoseStamped(header=Header(frame_id='base_link'), pose=Pose(position=Point(x=4.0))),
    ])
    assert np.allclose(read_path(msg), [[1.0, 2.0, 3.0], [4.0, 0.0, 0.0]])


def test_read_rejects_pose_in_another_frame():
    msg = Path(header=Header(frame_id='base_link'), poses=[
        PoseStamped(header=Header(frame_id='map'), pose=Pose()),
    ])
    with pytest.raises(ValueError, match="pose 0 is in frame 'map'"):
        read_path(msg)


def test_read_rejects_non_finite_position():
    msg = create_path([[0.0, 0.0], [1.0, 0.0]], 'base_link')
    msg.poses[1].pose.position.y = math.nan
    with pytest.raises(ValueError, match='pose 1 position has a non-finite value'):
        read_path(msg)


@pytest.mark.parametrize('positions', [np.zeros((3, 4)), np.zeros(3), np.zeros((3, 1)),
                                       np.zeros((3, 0))])
def test_create_rejects_bad_shapes(positions):
    with pytest.raises(ValueError, match='positions has shape'):
        create_path(positions, 'base_link')


@pytest.mark.parametrize('bad', [math.nan, math.inf])
def test_create_rejects_non_finite_positions(bad):
    with pytest.raises(ValueError, match='non-finite'):
        create_path([[0.0, 0.0], [bad, 1.0]], 'base_link')


def test_create_rejects_empty_frame():
    with pytest.raises(ValueError, match='frame_id'):
        create_path([[0.0, 0.0]], '')


def test_orientations_round_trip_and_are_normalised():
    positions = np.random.default_rng(1).uniform(-1.0, 1.0, size=(4, 3))
    msg = create_path(positions, 'panda_link0', orientations=QUATERNIONS * (1.0 + 5e-4))
    read_positions, orientations = read_path_poses(msg)
    assert np.allclose(read_positions, positions) and np.allclose(orientations, QUATERNIONS)
    assert np.allclose(np.linalg.norm(orientations, axis=1), 1.0, atol=1e-15)
    assert np.allclose(read_path(msg), positions)


def test_without_orientations_the_poses_read_back_as_identities():
    _, orientations = read_path_poses(create_path([[1.0, 0.0], [0.5, 0.5]], 'base_link'))
    assert np.array_equal(orientations, [[0.0, 0.0, 0.0, 1.0]] * 2)
    empty = read_path_poses(create_path([], 'base_link', orientations=[]))
    assert empty.position.shape == (0, 3) and empty.orientation.shape == (0, 4)


@pytest.mark.parametrize('orientations, problem', [
    (QUATERNIONS[:3], r'orientations has shape \(3, 4\); pass \(4, 4\)'),
    (QUATERNIONS[:, :3], r'orientations has shape \(4, 3\)'),
    (np.vstack([QUATERNIONS[:3], np.zeros(4)]), r'orientations\[3\] must be a unit quaternion'),
    (np.vstack([QUATERNIONS[:3], [math.nan, 0.0, 0.0, 1.0]]), 'orientations has a non-finite'),
])
def test_create_refuses_bad_orientations(orientations, problem):
    with pytest.raises(ValueError, match=problem):
        create_path(np.zeros((4, 3)), 'base_link', orientations=orientations)


@pytest.mark.parametrize('quaternion, problem', [
    (Quaternion(x=0.0, y=0.0, z=0.0, w=0.0), 'pose 1 orientation must be a unit quaternion'),
    (Quaternion(x=0.0, y=0.0, z=0.0, w=math.inf), 'pose 1 orientation has a non-finite'),
])
def test_read_poses_refuses_a_bad_orientation_naming_the_pose(quaternion, problem):
    msg = create_path(np.zeros((2, 3)), 'base_link')
    msg.poses[1].pose.orientation = quaternion
    with pytest.raises(ValueError, match=problem):
        read_path_poses(msg)
    assert read_path(msg).shape == (2, 3)       # positions alone do not look at it
