"""GJK lower bounds between convex pieces (core/collision/convex_kernels.py), by sampling.

References sample both shapes' surfaces densely (test/shape_references.py): the closest
pair of samples is at least the distance and exceeds it by less than the spacing.
"""

import numpy as np
import pytest
from ftplan_testing import capsule_hull, torus
from scipy.spatial import ConvexHull
from shape_references import closest, distance_to_obstacle, posed, random_pose, surface_points

from ftplan_ros.core.collision.checker import obstacle_shape, piece_table, shape_parameters
from ftplan_ros.core.collision.convex_kernels import HULL, convex_lower_bound, refined_distance
from ftplan_ros.core.collision.distance_kernels import CODES
from ftplan_ros.core.model.geometry import Shape
from ftplan_ros.core.model.scene import Obstacle

SPACING = 0.0015  # [m]
NO_VERTICES = np.zeros((0, 3))


def hull_points(vertices):
    """Samples (P, 3) of the surface of the hull of `vertices`."""
    return surface_points(Shape('mesh', vertices=vertices,
                                faces=ConvexHull(vertices).simplices), SPACING)


def primitive(kind, rng):
    if kind == 'box':
        return Shape('box', size=tuple(rng.uniform(0.04, 0.2, 3)))
    if kind in ('cylinder', 'capsule'):
        return Shape(kind, radius=rng.uniform(0.02, 0.06), length=rng.uniform(0.05, 0.25))
    return Shape('sphere', radius=rng.uniform(0.02, 0.1))


@pytest.mark.parametrize('kind', ['sphere', 'box', 'cylinder', 'capsule', 'hull'])
def test_a_hull_against_each_kind_is_a_lower_bound_and_exact_when_apart(kind, rng):
    vertices, _ = capsule_hull(0.15, 0.04)
    near = posed(hull_points(vertices), np.eye(4))
    apart = 0
    for _ in range(25):
        pose_a, pose_b = random_pose(rng, 0.15), random_pose(rng, 0.15)
        if kind == 'hull':
            other = capsule_hull(0.1, 0.03, seed=int(rng.integers(100)))[0]
            value = convex_lower_bound(HULL, np.zeros(3), pose_a, vertices, HULL, np.zeros(3),
                                       pose_b, other, np.inf)
            far = hull_points(other)
        else:
            shape = primitive(kind, rng)
            value = convex_lower_bound(HULL, np.zeros(3), pose_a, vertices, CODES[kind],
                                       shape_parameters(shape), pose_b, NO_VERTICES, np.inf)
            far = surface_points(shape, SPACING)
        sampled = closest(posed(near, pose_a), posed(far, pose_b))
        assert value <= sampled + 1e-9
        if sampled > 2 * SPACING:
            apart += 1
            assert value >= sampled - 2 * SPACING
        else:
            assert value <= 2 * SPACING
    assert apart >= 10


def test_overlapping_pieces_read_at_most_zero_and_enough_stops_early(rng):
    vertices, _ = capsule_hull(0.15, 0.04)
    box = Shape('box', size=(0.1, 0.1, 0.1))
    inside = np.eye(4)
    inside[:3, 3] = [0.0, 0.0, 0.1]  # the box's centre on the hull's axis
    assert convex_lower_bound(HULL, np.zeros(3), np.eye(4), vertices, CODES['box'],
                              shape_parameters(box), inside, NO_VERTICES, np.inf) <= 0.0
    far = np.eye(4)
    far[:3, 3] = [1.0, 0.0, 0.0]
    exact = convex_lower_bound(HULL, np.zeros(3), np.eye(4), vertices, CODES['box'],
                               shape_parameters(box), far, NO_VERTICES, np.inf)
    early = convex_lower_bound(HULL, np.zeros(3), np.eye(4), vertices, CODES['box'],
                               shape_parameters(box), far, NO_VERTICES, 0.1)
    assert exact == pytest.approx(1.0 - 0.05 - vertices[:, 0].max(), abs=1e-9)
    assert 0.1 <= early <= exact


@pytest.mark.parametrize('kind', ['sphere', 'box', 'cylinder'])
def test_a_torus_refined_by_its_triangles_is_exact_and_never_above(kind, rng):
    """The torus's pieces bulge over its hole: tier 3 measures the triangles they hold."""
    vertices, faces = torus()
    mesh = Shape('mesh', vertices=vertices, faces=faces)
    table, start = piece_table([mesh])
    samples = surface_points(mesh, SPACING)
    gaps = 0
    for _ in range(20):
        pose = random_pose(rng, 0.05)
        centre = tuple(rng.uniform(-0.1, 0.1, 3))
        obstacle = Obstacle('sphere', centre, radius=0.01) if kind == 'sphere' else \
            Obstacle('box', centre, size=(0.02, 0.03, 0.01)) if kind == 'box' else \
            Obstacle('cylinder', centre, radius=0.01, length=0.03)
        obstacles, _ = piece_table([obstacle_shape(obstacle)])
        frame = np.eye(4)
        frame[:3, 3] = centre
        value = refined_distance(table, start[0], start[1], pose, obstacles, 0, 1, frame)
        sampled = distance_to_obstacle(obstacle, posed(samples, pose)).min()
        assert value <= max(sampled, 0.0) + 1e-9
        if sampled > SPACING:
            assert value >= sampled - SPACING
            gaps += 1
    assert gaps >= 8
