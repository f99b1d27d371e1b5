import numpy as np
import pytest

from ftplan_ros.core.collision import CollisionChecker, point_clearance, rotation_from_rpy
from ftplan_ros.core.robot import PlanarChain
from ftplan_ros.core.scene import Obstacle

ARM = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'))


def spheres(rng, count=8):
    return [Obstacle('sphere', (rng.uniform(-2.5, 2.5), rng.uniform(-2.5, 2.5),
                                rng.uniform(-0.1, 0.1)), radius=rng.uniform(0.05, 0.4))
            for _ in range(count)]


@pytest.mark.parametrize('radius', [0.0, 0.07])
def test_numpy_and_fcl_backends_agree(rng, radius):
    arm = PlanarChain((1.0, 0.8, 0.6), ('a', 'b', 'c'), link_radius=radius)
    obstacles = spheres(rng)
    thetas = rng.uniform(-np.pi, np.pi, (300, 3))
    fast = CollisionChecker(arm, obstacles, backend='numpy').clearance(thetas)
    exact = CollisionChecker(arm, obstacles, backend='fcl').clearance(thetas)
    positive = exact > 1e-3
    assert positive.sum() > 300  # most are clear; compare distances there
    # The fcl backend gives certified lower bounds: close, and never above the exact value.
    assert np.allclose(fast[positive], exact[positive], atol=1e-9)
    assert np.all(exact[positive] <= fast[positive] + 1e-12)
    # Where either reports contact, the other does not call the link free (fcl says 0 for
    # a link within its 1 cm padding).
    assert np.all(exact[fast <= 0] == 0)
    assert np.all(fast[exact <= 0] <= max(0.0, 0.01 - radius) + 1e-12)
    assert (fast < 0).sum() > 10


def test_box_distances_per_link():
    box = Obstacle('box', (1.5, 0.5, 0.0), size=(0.2, 0.2, 1.0))
    clearance = CollisionChecker(ARM, [box]).clearance(np.zeros((1, 3)))[0]
    assert np.allclose(clearance, [np.hypot(0.4, 0.4), 0.4, np.hypot(0.4, 0.4)], atol=2e-4)


def test_rotated_box_and_cylinder():
    # A box rotated 45 degrees about z: its corner points down at the arm.
    box = Obstacle('box', (1.5, 0.5, 0.0), size=(0.2, 0.2, 1.0), rpy=(0.0, 0.0, np.pi / 4))
    clearance = CollisionChecker(ARM, [box]).clearance(np.zeros((1, 3)))[0]
    assert clearance[1] == pytest.approx(0.5 - 0.1 * np.sqrt(2), abs=2e-4)
    # A cylinder lying along x above the arm (axis rotated from z by pitch 90 degrees).
    cylinder = Obstacle('cylinder', (1.5, 0.6, 0.0), radius=0.1, length=0.4,
                        rpy=(0.0, np.pi / 2, 0.0))
    clearance = CollisionChecker(ARM, [cylinder]).clearance(np.zeros((1, 3)))[0]
    assert clearance[1] == pytest.approx(0.5, abs=2e-4)
    assert clearance[0] == pytest.approx(np.hypot(0.3, 0.5), abs=2e-4)


def test_rotation_from_rpy_is_z_y_x():
    assert np.allclose(rotation_from_rpy((0, 0, np.pi / 2)) @ [1, 0, 0], [0, 1, 0])
    assert np.allclose(rotation_from_rpy((0, np.pi / 2, 0)) @ [0, 0, 1], [1, 0, 0])
    assert np.allclose(rotation_from_rpy((np.pi / 2, 0, 0)) @ [0, 1, 0], [0, 0, 1])


def test_penetration_is_negative_and_link_radius_counts():
    disk = Obstacle('sphere', (1.5, 0.1, 0.0), radius=0.2)
    thin = CollisionChecker(ARM, [disk]).clearance(np.zeros((1, 3)))[0]
    assert thin[1] == pytest.approx(-0.1)
    fat = CollisionChecker(PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'), link_radius=0.05),
                           [disk]).clearance(np.zeros((1, 3)))[0]
    assert fat[1] == pytest.approx(-0.15)


def test_no_obstacles_means_infinite_clearance_and_checks_are_counted():
    checker = CollisionChecker(ARM, [])
    assert np.all(np.isinf(checker.clearance(np.zeros((4, 3)))))
    checker.min_clearance(np.zeros((6, 3)))
    assert checker.checks == 10


def test_backend_choice():
    box = Obstacle('box', (1.5, 0.5, 0.0), size=(0.2, 0.2, 1.0))
    assert CollisionChecker(ARM, [box]).backend == 'fcl'
    assert CollisionChecker(ARM, [Obstacle('sphere', (1, 1, 0), radius=0.1)]).backend == 'numpy'
    with pytest.raises(ValueError, match='sphere obstacles only'):
        CollisionChecker(ARM, [box], backend='numpy')
    with pytest.raises(ValueError, match='unknown collision backend'):
        CollisionChecker(ARM, [], backend='gpu')


def test_point_clearance():
    obstacles = [Obstacle('sphere', (0.1, 0.0, 0.0), radius=0.2),
                 Obstacle('box', (1.0, 0.0, 0.0), size=(0.5, 0.5, 0.5))]
    distance = point_clearance(obstacles, np.zeros(3))
    assert distance[0] == 0
    assert distance[1] == pytest.approx(0.75, abs=1e-6)  # the point query is not lowered


def point_box_distance(points, center, size):
    """Exact distance from points (k, 3) to an axis-aligned box (independent of fcl)."""
    gap = np.maximum(np.abs(points - center) - 0.5 * np.asarray(size), 0.0)
    return np.linalg.norm(gap, axis=1)


def test_fcl_box_distances_match_a_dense_point_sampling(rng):
    center, size = np.array([1.2, 0.9, 0.0]), (0.3, 0.5, 0.4)
    checker = CollisionChecker(ARM, [Obstacle('box', tuple(center), size=size)])
    assert checker.backend == 'fcl'
    t = np.linspace(0.0, 1.0, 2001)[:, None]
    separated = touching = 0
    for theta in rng.uniform(-np.pi, np.pi, (40, 3)):
        clearance = checker.clearance(theta[None])[0]
        for j, (a, b) in enumerate(ARM.link_segments(theta)):
            sampled = point_box_distance(a + t * (b - a), center, size).min()
            if sampled > 1e-3:  # separated: fcl must agree with the sampling to its spacing
                assert clearance[j] == pytest.approx(sampled, abs=1e-3)
                assert clearance[j] <= sampled  # the sampled minimum can only be higher
                separated += 1
            else:  # a sample touches the box: so must fcl's link
                assert clearance[j] <= 1e-3
                touching += 1
    assert separated >= 100 and touching >= 1  # both branches ran, on most of the 120 links


def test_a_sphere_centred_on_the_point_is_answered():
    """fcl's signed-distance query never returns for concentric shapes: it is not used."""
    centred = [Obstacle('sphere', (0.0, 0.0, 0.0), radius=0.2),
               Obstacle('cylinder', (0.0, 0.0, 0.0), radius=0.2, length=0.4)]
    assert np.all(point_clearance(centred, np.zeros(3)) == 0)
