import math

import numpy as np
import pytest
from geometry_msgs.msg import Point, Pose, Quaternion

from ftplan_msgs_py.pose import (
    QUATERNION_TOLERANCE,
    create_pose,
    read_point,
    read_pose,
    read_quaternion,
    unit_quaternions,
)

HALF_TURN_ABOUT_X = [1.0, 0.0, 0.0, 0.0]


def test_round_trip_of_a_pose():
    q = np.array([0.1, -0.2, 0.3, 0.9])
    q /= np.linalg.norm(q)
    position, orientation = read_pose(create_pose([0.5, -0.2, 0.4], q))
    assert np.allclose(position, [0.5, -0.2, 0.4]) and np.allclose(orientation, q)


def test_a_planar_position_gets_z_zero_and_no_orientation_is_the_identity():
    pose = create_pose([2.0, 1.0])
    assert (pose.position.x, pose.position.y, pose.position.z) == (2.0, 1.0, 0.0)
    o = pose.orientation
    assert (o.x, o.y, o.z, o.w) == (0.0, 0.0, 0.0, 1.0)


def test_a_nearly_unit_quaternion_is_normalised():
    nearly = np.array(HALF_TURN_ABOUT_X) * (1.0 + 0.5 * QUATERNION_TOLERANCE)
    got = read_quaternion(Quaternion(x=nearly[0], y=nearly[1], z=nearly[2], w=nearly[3]))
    assert np.linalg.norm(got) == pytest.approx(1.0, abs=1e-15)
    assert np.allclose(create_pose([0.0, 0.0, 0.0], nearly).orientation.x, 1.0)


@pytest.mark.parametrize('quaternion, norm', [((0.0, 0.0, 0.0, 0.0), 'norm 0'),
                                              ((0.0, 0.0, 0.0, 1.01), 'norm 1.01'),
                                              ((1.0, 1.0, 0.0, 0.0), 'norm 1.41421')])
def test_a_quaternion_that_is_not_unit_is_refused_naming_the_field(quaternion, norm):
    x, y, z, w = quaternion
    msg = Pose(orientation=Quaternion(x=x, y=y, z=z, w=w))
    with pytest.raises(ValueError, match=rf'goal\.pose\.orientation must be a unit '
                                         rf'quaternion .*{norm}'):
        read_pose(msg, 'goal.pose')
    with pytest.raises(ValueError, match='orientation must be a unit quaternion'):
        create_pose([0.0, 0.0, 0.0], quaternion)


def test_a_zero_quaternion_says_what_it_probably_is():
    with pytest.raises(ValueError, match=r'zero quaternion: unset\? no rotation is '
                                         r'\(0, 0, 0, 1\)'):
        read_quaternion(Quaternion(x=0.0, y=0.0, z=0.0, w=0.0), 'start.pose.orientation')


@pytest.mark.parametrize('bad', [math.nan, math.inf])
def test_non_finite_values_are_refused_naming_the_field(bad):
    with pytest.raises(ValueError, match=r'start\.pose\.position has a non-finite value'):
        read_pose(Pose(position=Point(x=0.0, y=bad, z=0.0)), 'start.pose')
    with pytest.raises(ValueError, match=r'q has a non-finite value'):
        read_quaternion(Quaternion(x=bad, y=0.0, z=0.0, w=1.0), 'q')
    with pytest.raises(ValueError, match='position has a non-finite value'):
        read_point(Point(x=bad))
    with pytest.raises(ValueError, match='position has a non-finite value'):
        create_pose([bad, 0.0, 0.0])


@pytest.mark.parametrize('position', [[0.0], [0.0, 0.0, 0.0, 0.0], [[0.0, 0.0, 0.0]]])
def test_create_refuses_a_position_of_the_wrong_shape(position):
    with pytest.raises(ValueError, match='position has shape'):
        create_pose(position)


def test_create_refuses_more_than_one_quaternion():
    with pytest.raises(ValueError, match='pass one quaternion'):
        create_pose([0.0, 0.0, 0.0], [HALF_TURN_ABOUT_X, HALF_TURN_ABOUT_X])


def test_unit_quaternions_name_the_row_and_the_shape():
    rows = np.array([HALF_TURN_ABOUT_X, [0.0, 0.0, 0.0, 2.0]])
    with pytest.raises(ValueError, match=r'quats\[1\] must be a unit quaternion .*norm 2'):
        unit_quaternions(rows, 'quats')
    with pytest.raises(ValueError, match=r'quats has shape \(2, 3\)'):
        unit_quaternions(np.zeros((2, 3)), 'quats')
    with pytest.raises(ValueError, match='quats must be a numeric array'):
        unit_quaternions([['a', 'b', 'c', 'd']], 'quats')
