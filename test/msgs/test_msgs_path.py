import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, PoseStamped
from nav_msgs.msg import Path
from std_msgs.msg import Header

from ftplan_msgs_py.path import create_path, read_path


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
