"""Task points of each kind (core/model/task_space.py) against scipy's rotations."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftplan_ros.core.model.task_space import (
    POINT_SIZE,
    describe_point,
    point_position,
    points_from_frames,
    unit_vector,
)


def frames_of(rotations, positions):
    out = np.tile(np.eye(4), (len(positions), 1, 1))
    out[:, :3, :3] = rotations.as_matrix()
    out[:, :3, 3] = positions
    return out


def test_task_points_of_frames_are_the_position_the_z_axis_or_a_ros_quaternion(rng):
    rotations = Rotation.random(6, random_state=rng.integers(1 << 31))
    frames = frames_of(rotations, rng.uniform(-1.0, 1.0, (6, 3)))
    assert np.array_equal(points_from_frames('position', frames), frames[:, :3, 3])
    axis = points_from_frames('axis', frames)
    assert np.array_equal(axis[:, :3], frames[:, :3, 3])
    assert np.allclose(axis[:, 3:], rotations.apply([0.0, 0.0, 1.0]))
    pose = points_from_frames('pose', frames)
    assert np.allclose(np.linalg.norm(pose[:, 3:], axis=1), 1.0)
    assert np.allclose(Rotation.from_quat(pose[:, 3:]).as_matrix(), rotations.as_matrix())
    for kind in ('position', 'axis', 'pose'):
        assert points_from_frames(kind, frames.reshape(2, 3, 4, 4)).shape == (2, 3,
                                                                              POINT_SIZE[kind])
    # ROS order (x, y, z, w): a quarter turn about z.
    quarter = frames_of(Rotation.from_euler('z', [np.pi / 2]), np.zeros((1, 3)))
    assert np.allclose(np.abs(points_from_frames('pose', quarter)[0, 3:]),
                       [0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)])


def test_a_unit_vector_is_normalised_within_the_tolerance_and_refused_beyond_it():
    assert np.array_equal(unit_vector([0.0, 0.0, 1.0], 'axis'), [0.0, 0.0, 1.0])
    assert np.linalg.norm(unit_vector([0.0, 0.6, -0.8005], 'axis')) == pytest.approx(1.0)
    for far in ([0.0, 0.0, 1.002], [0.0, 0.0, 0.0], [np.nan, 0.0, 1.0]):
        with pytest.raises(ValueError, match='task.goal.axis must have norm 1'):
            unit_vector(far, 'task.goal.axis')


def test_the_position_of_a_task_point_and_its_one_line_description():
    assert np.array_equal(point_position([1.0, 2.0]), [1.0, 2.0])
    pose = [0.1, 0.2, 0.3, 0.0, 0.0, 0.0, 1.0]
    assert np.array_equal(point_position(pose), [0.1, 0.2, 0.3])
    assert describe_point('planar', [1.0, 2.0]) == '[1.000, 2.000]'
    assert describe_point('position', [0.1, 0.2, 0.3]) == '[0.100, 0.200, 0.300]'
    assert describe_point('axis', [0.1, 0.2, 0.3, 0.0, 0.6, 0.8]) == \
        '[0.100, 0.200, 0.300] axis [0.000, 0.600, 0.800]'
    assert describe_point('pose', pose) == '[0.100, 0.200, 0.300] q [0.000, 0.000, 0.000, 1.000]'
