"""Link shapes (core/model/geometry.py) against their sampled surfaces: supports, separations
and signed distances never claim more than the samples show.
"""

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation
from shape_references import (
    closest,
    distance_to_obstacle,
    posed,
    random_link_shape,
    random_pose,
    surface_points,
)

from ftplan_ros.core.model.geometry import rotation_from_rpy, separation, signed_distance, support
from ftplan_ros.core.model.scene import Obstacle


def test_rotation_from_rpy_is_z_y_x():
    assert np.allclose(rotation_from_rpy((0, 0, np.pi / 2)) @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(rotation_from_rpy((0, np.pi / 2, 0)) @ [0, 0, 1], [1, 0, 0])
    assert np.allclose(rotation_from_rpy((np.pi / 2, 0, 0)) @ [0, 1, 0], [0, 0, 1])
    rpy = (0.3, -1.1, 2.5)
    assert np.allclose(rotation_from_rpy(rpy), Rotation.from_euler('xyz', rpy).as_matrix())


SHAPES = ['sphere', 'box', 'cylinder', 'capsule', 'cube', 'tetrahedron']


@pytest.mark.parametrize('kind', SHAPES)
def test_support_is_the_farthest_point_along_a_direction(kind, rng):
    for _ in range(10):
        shape, pose = random_link_shape(kind, rng), random_pose(rng, spread=0.5)
        points = posed(surface_points(shape, 0.004), pose)
        for direction in Rotation.random(5, random_state=rng.integers(1 << 31)).apply([1, 0, 0]):
            value = support(shape, pose[:3, :3], pose[:3, 3], direction)
            farthest = float(np.max(points @ direction))
            assert farthest - 1e-12 <= value <= farthest + 0.004
        centre, radius = shape.bounding_sphere()
        assert np.all(np.linalg.norm(posed(surface_points(shape, 0.01), np.eye(4)) - centre,
                                     axis=1) <= radius + 1e-12)


@pytest.mark.parametrize('first', SHAPES)
@pytest.mark.parametrize('second', SHAPES)
def test_separation_is_a_lower_bound_for_any_direction(first, second, rng):
    for _ in range(5):
        a, b = random_link_shape(first, rng), random_link_shape(second, rng)
        pose_a, pose_b = random_pose(rng, 0.3), random_pose(rng, 0.3)
        points_a = posed(surface_points(a, 0.01), pose_a)
        points_b = posed(surface_points(b, 0.01), pose_b)
        nearest = closest(points_a, points_b)
        axis = pose_b[:3, 3] - pose_a[:3, 3]
        for direction in [axis / np.linalg.norm(axis),
                          *Rotation.random(4, random_state=rng.integers(1 << 31)).apply([1, 0, 0])]:
            bound = separation(a, (pose_a[:3, :3], pose_a[:3, 3]), b,
                               (pose_b[:3, :3], pose_b[:3, 3]), direction)
            assert bound <= nearest + 1e-12


@pytest.mark.parametrize('kind', ['sphere', 'box', 'cylinder', 'capsule'])
def test_signed_distances_of_the_primitives(kind, rng):
    shape = random_link_shape(kind, rng)
    points = rng.uniform(-0.4, 0.4, (500, 3))
    values = signed_distance(shape, points)
    surface = surface_points(shape, 0.003)
    nearest = cKDTree(surface).query(points)[0]
    assert np.allclose(np.abs(values), nearest, atol=0.003)
    if kind != 'capsule':
        as_obstacle = Obstacle(kind, (0.0, 0.0, 0.0), radius=shape.radius, size=shape.size,
                               length=shape.length)
        assert np.allclose(values, distance_to_obstacle(as_obstacle, points), atol=1e-12)
    with pytest.raises(ValueError, match='meshes'):
        signed_distance(random_link_shape('cube', rng), points)
