"""Clearances against independent references: closed forms and dense surface sampling.

The checker's distances come in tiers (checker.py); whatever the tier, a value must
never exceed the true distance, and it must equal it where it claims to be exact.
References (test/shape_references.py) are written independently of the core: signed
distances of the obstacles in closed form, shapes' surfaces sampled densely.
"""

import numpy as np
import pytest
from ftplan_testing import SCENES, bot, mesh_arm, robot_config
from shape_references import (
    SPACING,
    closest,
    distance_to_obstacle,
    posed,
    random_link_shape,
    random_pose,
    surface_points,
)

from ftplan_ros.core import load_scene, plan
from ftplan_ros.core.collision import checker as checker_module
from ftplan_ros.core.collision.checker import CollisionChecker
from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.scene_file import with_disabled_collisions
from ftplan_ros.core.model.chain import ChainModel
from ftplan_ros.core.model.dh import DHRow, chain_from_dh
from ftplan_ros.core.model.geometry import Shape
from ftplan_ros.core.model.robot import LinkShape, PlanarChain
from ftplan_ros.core.model.scene import Obstacle, Scene, Task
from ftplan_ros.core.model.spatial import SpatialArm
from ftplan_ros.core.planning.curves import FrozenJoints
from ftplan_ros.core.planning.planner import check_plannable

ARM = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'))


def one_shape_arm(shape, placement=None):
    """A one-joint arm (about z through the base) whose only link carries `shape`."""
    model = ChainModel('one', ('j',), ('base', 'link'), np.eye(4)[None], np.array([[0, 0, 1.0]]),
                       np.eye(4), (None,), (LinkShape(1, shape, np.eye(4) if placement is None
                                                      else placement),))
    return SpatialArm(model, 'position')


def random_obstacle(kind, rng, spread=0.5):
    center = tuple(rng.uniform(-spread, spread, 3))
    rpy = tuple(rng.uniform(-np.pi, np.pi, 3))
    if kind == 'sphere':
        return Obstacle('sphere', center, radius=rng.uniform(0.02, 0.15))
    if kind == 'box':
        return Obstacle('box', center, size=tuple(rng.uniform(0.05, 0.3, 3)), rpy=rpy)
    return Obstacle('cylinder', center, radius=rng.uniform(0.03, 0.1),
                    length=rng.uniform(0.05, 0.4), rpy=rpy)


def sampled_distance(arm, theta, obstacle):
    """Smallest obstacle distance [m] over the arm's only shape's sampled surface."""
    item, = arm.collision_shapes
    pose = arm.link_frames(theta)[0, item.link] @ item.placement
    return float(distance_to_obstacle(obstacle, posed(surface_points(item.shape), pose)).min())


# The planar arm of the paper ------------------------------------------------------------

def test_box_distances_per_link():
    box = Obstacle('box', (1.5, 0.5, 0.0), size=(0.2, 0.2, 1.0))
    clearance = CollisionChecker(ARM, [box]).clearance(np.zeros((1, 3)))[0]
    assert np.allclose(clearance, [np.hypot(0.4, 0.4), 0.4, np.hypot(0.4, 0.4)], atol=1e-8)


def test_rotated_box_and_cylinder():
    # A box rotated 45 degrees about z: its corner points down at the arm.
    box = Obstacle('box', (1.5, 0.5, 0.0), size=(0.2, 0.2, 1.0), rpy=(0.0, 0.0, np.pi / 4))
    clearance = CollisionChecker(ARM, [box]).clearance(np.zeros((1, 3)))[0]
    assert clearance[1] == pytest.approx(0.5 - 0.1 * np.sqrt(2), abs=1e-8)
    # A cylinder lying along x above the arm (axis rotated from z by pitch 90 degrees).
    cylinder = Obstacle('cylinder', (1.5, 0.6, 0.0), radius=0.1, length=0.4,
                        rpy=(0.0, np.pi / 2, 0.0))
    clearance = CollisionChecker(ARM, [cylinder]).clearance(np.zeros((1, 3)))[0]
    assert clearance[1] == pytest.approx(0.5, abs=1e-8)
    assert clearance[0] == pytest.approx(np.hypot(0.3, 0.5), abs=1e-8)


def test_penetration_is_negative_and_link_radius_counts():
    disk_ = Obstacle('sphere', (1.5, 0.1, 0.0), radius=0.2)
    thin = CollisionChecker(ARM, [disk_]).clearance(np.zeros((1, 3)))[0]
    assert thin[1] == pytest.approx(-0.1)
    fat = CollisionChecker(PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'), link_radius=0.05),
                           [disk_]).clearance(np.zeros((1, 3)))[0]
    assert fat[1] == pytest.approx(-0.15)


def test_no_obstacles_means_infinite_clearance_and_checks_are_counted():
    checker = CollisionChecker(ARM, [])
    assert np.all(np.isinf(checker.clearance(np.zeros((4, 3)))))
    checker.min_clearance(np.zeros((6, 3)))
    assert checker.checks == 10
    assert checker.clearance(np.zeros((0, 3))).shape == (0, 3)


def test_min_clearance_is_the_least_channel_and_keeps_a_nan():
    """The planar fast path and the general tiers: links placed by an angle, or a sum of
    angles, that is not finite read NaN, never clear, also with no obstacle near enough
    to measure (none at all, or only culled ones); one configuration gives one entry."""
    rng = np.random.default_rng(5)
    disks = [Obstacle('sphere', (1.5, 0.1, 0.0), radius=0.2),
             Obstacle('sphere', (-0.5, 1.2, 0.0), radius=0.3)]
    far = [Obstacle('sphere', (50.0, 0.0, 0.0), radius=0.1)]
    thetas = rng.uniform(-np.pi, np.pi, (200, 3))
    thetas[17, 1] = np.nan
    thetas[18, :2] = 1e308  # finite angles whose sum is not
    for obstacles in (disks, far, []):
        planar = CollisionChecker(ARM, obstacles)
        general = CollisionChecker(ARM, obstacles, backend='fcl')
        assert planar.planar_disks is not None and general.planar_disks is None
        assert np.array_equal(np.isnan(planar.clearance(thetas)),
                              np.isnan(general.clearance(thetas)))
        for checker in (planar, general):
            lowest = checker.min_clearance(thetas)
            assert np.array_equal(lowest, checker.clearance(thetas).min(axis=1), equal_nan=True)
            assert np.isnan(lowest[17:19]).all() and not np.isnan(np.delete(lowest, [17, 18])).any()
            assert checker.min_clearance(thetas[3]).shape == (1,)
    # A spatial arm's pair channel; its frames compose rotations, so 1e308 stays finite.
    pairs = CollisionChecker(folding_arm(), []).clearance(thetas[16:19])
    assert np.isnan(pairs[1, -1]) and not np.isnan(pairs[[0, 2]]).any()


def test_unknown_backend():
    with pytest.raises(ValueError, match='unknown collision backend'):
        CollisionChecker(ARM, [], backend='gpu')


def test_planar_spheres_against_the_segments_by_brute_force(rng):
    arm = PlanarChain((1.0, 0.8, 0.6), ('a', 'b', 'c'), link_radius=0.07)
    obstacles = [Obstacle('sphere', tuple(rng.uniform(-2.0, 2.0, 2)) + (0.0,),
                          radius=rng.uniform(0.05, 0.4)) for _ in range(6)]
    thetas = rng.uniform(-np.pi, np.pi, (100, 3))
    clearance = CollisionChecker(arm, obstacles).clearance(thetas)
    t = np.linspace(0.0, 1.0, 2001)[:, None]
    for theta, row in zip(thetas, clearance, strict=True):
        joints = np.hstack([arm.joint_positions(theta), np.zeros((4, 1))])
        for j in range(3):
            points = joints[j] + t * (joints[j + 1] - joints[j])
            expected = min(distance_to_obstacle(ob, points).min() for ob in obstacles) - 0.07
            assert expected - 5e-4 <= row[j] <= expected + 1e-9  # samples 0.5 mm apart


# Tier 1: closed forms with a sphere -----------------------------------------------------

@pytest.mark.parametrize('kind', ['box', 'cylinder', 'capsule', 'sphere'])
def test_sphere_obstacles_against_link_shapes_in_closed_form(kind, rng):
    for _ in range(20):
        shape, placement = random_link_shape(kind, rng), random_pose(rng)
        arm = one_shape_arm(shape, placement)
        ball = random_obstacle('sphere', rng)
        theta = rng.uniform(-np.pi, np.pi, (1, 1))
        pose = arm.link_frames(theta)[0, 1] @ placement
        local = (np.asarray(ball.center) - pose[:3, 3]) @ pose[:3, :3]
        if kind == 'box':
            half = 0.5 * np.asarray(shape.size)
            depth = np.min(half - np.abs(local))
            core = -depth if depth > 0 else np.linalg.norm(local - np.clip(local, -half, half))
        elif kind == 'cylinder':
            radial, height = np.hypot(*local[:2]) - shape.radius, abs(local[2]) - 0.5 * shape.length
            core = max(radial, height) if max(radial, height) < 0 else \
                np.hypot(max(radial, 0.0), max(height, 0.0))
        elif kind == 'capsule':
            along = np.clip(local[2], -0.5 * shape.length, 0.5 * shape.length)
            core = np.linalg.norm(local - [0, 0, along]) - shape.radius
        else:
            core = np.linalg.norm(local) - shape.radius
        value = CollisionChecker(arm, [ball]).clearance(theta)[0, 0]
        assert value == pytest.approx(core - ball.radius, abs=1e-9)


@pytest.mark.parametrize('kind', ['box', 'cylinder'])
def test_sphere_links_against_obstacles_in_closed_form(kind, rng):
    for _ in range(20):
        ball = Shape('sphere', radius=rng.uniform(0.02, 0.15))
        placement = random_pose(rng, spread=0.3)
        arm = one_shape_arm(ball, placement)
        obstacle = random_obstacle(kind, rng)
        theta = rng.uniform(-np.pi, np.pi, (1, 1))
        centre = (arm.link_frames(theta)[0, 1] @ placement)[:3, 3]
        expected = distance_to_obstacle(obstacle, centre[None])[0] - ball.radius
        assert CollisionChecker(arm, [obstacle]).clearance(theta)[0, 0] == \
            pytest.approx(expected, abs=1e-9)


# Tiers 2-3: boxes, cylinders and meshes against dense sampling ----------------------------

@pytest.mark.parametrize('link_kind, obstacle_kind', [
    ('box', 'box'), ('box', 'cylinder'), ('cylinder', 'box'), ('cylinder', 'cylinder'),
    ('capsule', 'box'), ('capsule', 'cylinder')])
def test_link_shapes_against_obstacles_match_dense_sampling(link_kind, obstacle_kind, rng):
    """Never above the sampled distance, and within the sampling error of it when apart."""
    apart = 0
    for _ in range(25):
        shape, placement = random_link_shape(link_kind, rng), random_pose(rng)
        arm = one_shape_arm(shape, placement)
        obstacle = random_obstacle(obstacle_kind, rng)
        theta = rng.uniform(-np.pi, np.pi, (1, 1))
        value = CollisionChecker(arm, [obstacle]).clearance(theta)[0, 0]
        sampled = sampled_distance(arm, theta, obstacle)
        assert value <= max(sampled, 0.0) + 1e-9
        if sampled > SPACING:
            apart += 1
            assert value >= sampled - SPACING
        else:
            assert value <= SPACING
    assert apart >= 15


def mesh_cases(mesh, obstacle_kind, rng, count=15):
    """(value, sampled distance) of random poses of a mesh link and an obstacle."""
    for _ in range(count):
        shape, placement = random_link_shape(mesh, rng), random_pose(rng)
        arm = one_shape_arm(shape, placement)
        obstacle = random_obstacle(obstacle_kind, rng)
        theta = rng.uniform(-np.pi, np.pi, (1, 1))
        yield (CollisionChecker(arm, [obstacle]).clearance(theta)[0, 0],
               sampled_distance(arm, theta, obstacle))


@pytest.mark.parametrize('mesh', ['cube', 'tetrahedron'])
@pytest.mark.parametrize('obstacle_kind', ['sphere', 'box', 'cylinder'])
def test_meshes_give_lower_bounds(mesh, obstacle_kind, rng):
    for value, sampled in mesh_cases(mesh, obstacle_kind, rng):
        assert value <= max(sampled, 0.0) + 1e-9


@pytest.mark.parametrize('obstacle_kind', ['sphere', 'box', 'cylinder'])
def test_mesh_distances_are_refined_to_the_truth(obstacle_kind, rng):
    """A convex mesh apart from an obstacle: tier 3 (fcl's nearest points) makes it exact.

    The separation of two convex shapes along the line of their nearest points is their
    distance; a bound far below it means the direction was wrong.
    """
    loose = []
    for value, sampled in mesh_cases('tetrahedron', obstacle_kind, rng):
        if sampled > SPACING and value < sampled - SPACING:
            loose.append((round(float(value), 4), round(sampled, 4)))
    assert not loose, f'(value, sampled distance) [m]: {loose}'


def test_capsule_pairs_against_dense_segment_sampling(rng):
    """Self-collision of capsule links: the segments' distance minus both radii."""
    rows = [DHRow(a=0.4, alpha=0.7, d=0.1), DHRow(a=0.3, alpha=-1.1, d=0.2),
            DHRow(a=0.35, alpha=0.4, d=0.0), DHRow(a=0.3, alpha=0.0, d=0.1)]
    model = chain_from_dh(rows, ['a', 'b', 'c', 'd'], 0.03)
    model = with_disabled_collisions(model, [])
    arm = SpatialArm(model, 'position')
    checker = CollisionChecker(arm, [])
    assert checker.pairs == ((1, 2), (1, 3), (1, 4), (2, 3), (2, 4), (3, 4))
    t = np.linspace(0.0, 1.0, 801)
    for theta in rng.uniform(-np.pi, np.pi, (12, 4)):
        row = checker.clearance(theta[None])[0, 4:]  # after the 4 links' obstacle channels
        frames = arm.link_frames(theta)
        segments = []
        for item in arm.collision_shapes:
            pose = frames[item.link] @ item.placement
            ends = pose[:3, 3] + np.outer([-0.5, 0.5], pose[:3, 2]) * item.shape.length
            segments.append(ends[0] + t[:, None] * (ends[1] - ends[0]))
        for value, (a, b) in zip(row, checker.pairs, strict=True):
            first, second = segments[a - 1], segments[b - 1]
            gaps = closest(first, second) - 0.06
            assert value <= gaps + 1e-9
            assert value >= gaps - 0.4 / 800


def test_self_collision_pairs_of_a_urdf_arm_are_lower_bounds(bot_urdf_file, rng):
    """Every pair of the test robot (a mesh link among them) against dense sampling."""
    arm = SpatialArm(with_disabled_collisions(bot(bot_urdf_file).model, []), 'position')
    checker = CollisionChecker(arm, [])
    items = arm.collision_shapes
    number = [sum(1 for other in items[:k] if other.link == item.link)
              for k, item in enumerate(items)]
    names = [f'{arm.link_names[item.link]}[{k}]' for item, k in zip(items, number, strict=True)]
    local = [surface_points(item.shape, 0.005) for item in items]
    pair_columns = [(c, name.split(' / ')) for c, name in enumerate(checker.channel_names)
                    if ' / ' in name]
    assert pair_columns
    for theta in rng.uniform(arm.limits[:, 0], arm.limits[:, 1], (8, arm.n_joints)):
        row = checker.clearance(theta[None])[0]
        frames = arm.link_frames(theta)
        points = [posed(p, frames[item.link] @ item.placement)
                  for p, item in zip(local, items, strict=True)]
        for c, (first, second) in pair_columns:
            a, b = names.index(first), names.index(second)
            assert row[c] <= closest(points[a], points[b]) + 1e-9


def test_the_screen_of_a_mesh_arm_is_its_meshes_distances(tmp_path, rng):
    """Step 2's cheap bounds (refine=False) of an arm of 300-triangle convex STL hulls.

    Against samples of the meshes 5 mm apart: never above, and within the sampling error
    below, for links against obstacles and links two apart (whose bounding spheres meet).
    Before covers, a mesh link was screened by its bounding sphere: centimetres too low.
    """
    arm = mesh_arm(tmp_path)
    obstacles = [random_obstacle(kind, rng, spread=0.6) for kind in ('sphere', 'box', 'cylinder')]
    checker = CollisionChecker(arm, obstacles)
    items = arm.collision_shapes
    local = [surface_points(item.shape, 0.005) for item in items]
    links = checker.channel_links
    assert (links[:, 1] >= 0).sum() == 3  # links 1-3, 2-4, 1-4
    checked = 0
    for theta in rng.uniform(-1.5, 1.5, (4, arm.n_joints)):
        screen = checker.clearance(theta[None], refine=False)[0]
        frames = arm.link_frames(theta)
        points = {item.link: posed(p, frames[item.link] @ item.placement)
                  for p, item in zip(local, items, strict=True)}
        for value, (a, b) in zip(screen, links, strict=True):
            sampled = closest(points[a], points[b]) if b >= 0 else min(
                distance_to_obstacle(obstacle, points[a]).min() for obstacle in obstacles)
            assert value <= max(sampled, 0.0) + 1e-9
            if sampled > 0.006:
                assert value >= sampled - 0.006, (a, b, value, sampled)
                checked += 1
    assert checked >= 20


# Backends, `needed`, `refine` and culling ----------------------------------------------------

@pytest.fixture(scope='module')
def panda_scene():
    rng = np.random.default_rng(3)
    obstacles = [random_obstacle(kind, rng, spread=0.7) for kind in
                 ('sphere', 'box', 'cylinder', 'box', 'cylinder', 'sphere', 'box')]
    robot = robot_config('panda', 'pose')
    thetas = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (60, robot.n_joints))
    return robot, obstacles, thetas


def test_fcl_backend_agrees_with_auto(panda_scene):
    robot, obstacles, thetas = panda_scene
    auto = CollisionChecker(robot, obstacles).clearance(thetas)
    measured = CollisionChecker(robot, obstacles, backend='fcl').clearance(thetas)
    assert np.allclose(auto, measured, atol=1e-12, rtol=0.0)
    assert (auto < 0.05).sum() > 20  # some channels were close enough to matter


def test_needed_values_are_exact_below_and_bounds_above(panda_scene, rng):
    robot, obstacles, thetas = panda_scene
    checker = CollisionChecker(robot, obstacles)
    full = checker.clearance(thetas)
    for needed in (0.0, 0.05, rng.uniform(0.0, 0.3, full.shape)):
        partial = checker.clearance(thetas, needed)
        below = full < needed
        assert below.any() and (~below).any()
        assert np.allclose(partial[below], full[below], atol=1e-12, rtol=0.0)
        above = np.broadcast_to(needed, full.shape)[~below]
        assert np.all(partial[~below] >= above - 1e-12)
        assert np.all(partial[~below] <= full[~below] + 1e-12)
        lowest = checker.min_clearance(thetas, float(np.min(needed)))
        assert np.all(lowest <= full.min(axis=1) + 1e-12)


def test_without_refinement_every_value_is_a_lower_bound(panda_scene):
    robot, obstacles, thetas = panda_scene
    checker = CollisionChecker(robot, obstacles)
    full = checker.clearance(thetas)
    screen = checker.clearance(thetas, refine=False)
    assert np.all(screen <= full + 1e-12)
    assert np.any(screen < full - 1e-3)  # the screen does skip work
    spheres = [ob for ob in obstacles if ob.shape == 'sphere']
    exact = CollisionChecker(robot, spheres)  # sphere obstacles: tier 1, exact either way
    moving = sum(item.link != 0 for item in robot.collision_shapes)
    assert np.array_equal(exact.clearance(thetas, refine=False)[:, :moving],
                          exact.clearance(thetas)[:, :moving])


def uncapped(robot, obstacles, thetas, monkeypatch):
    """Clearances with culling switched off: the reference for culled obstacles."""
    with monkeypatch.context() as patch:
        patch.setattr(checker_module, 'CULL_DISTANCE', np.inf)
        return CollisionChecker(robot, obstacles).clearance(thetas)


@pytest.mark.parametrize('name', ['panda', 'frozen-iiwa'])
def test_culled_obstacles_leave_lower_bounds(name, monkeypatch, rng):
    """Far obstacles are dropped, and the clearance is capped by a bound on their distance."""
    if name == 'panda':
        robot = robot_config('panda', 'pose')
    else:  # the first joint frozen: the arm's reach is measured from the second
        robot = FrozenJoints(robot_config('iiwa14', 'position'), (0,), (0.0,))
    far = [Obstacle('sphere', (0.0, 0.0, 2.7), radius=0.1),
           Obstacle('box', (3.0, 0.5, 0.2), size=(0.3, 0.3, 0.3), rpy=(0.2, 0.1, 0.0)),
           Obstacle('cylinder', (-2.0, -2.0, 0.5), radius=0.2, length=1.0)]
    near = [Obstacle('sphere', (0.5, 0.0, 0.5), radius=0.1)]
    thetas = rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (40, robot.n_joints))
    thetas[0] = 0.0  # stretched up
    moving = sum(item.link != 0 for item in robot.collision_shapes)
    capped = CollisionChecker(robot, far).clearance(thetas)[:, :moving]
    assert np.all(capped == capped[0, 0])  # culled: every channel holds the cap
    assert capped[0, 0] > checker_module.CULL_DISTANCE
    with_near = CollisionChecker(robot, far + near).clearance(thetas)[:, :moving]
    assert np.all(with_near <= uncapped(robot, far + near, thetas, monkeypatch)[:, :moving] + 1e-9)
    reference = uncapped(robot, far, thetas, monkeypatch)[:, :moving]
    assert np.all(capped <= reference + 1e-9), \
        f'cap {capped[0, 0]:.4f} m above the distance {reference.min():.4f} m'


@pytest.mark.parametrize('radius', [0.05, 0.8, 2.0])
def test_a_thick_links_radius_counts_in_its_reach_when_culling(radius, monkeypatch):
    """A capsule reaches its radius beyond its core: an obstacle there is not culled.

    The stretched arm's core ends at 3 m; the sphere's surface lies 1.4 m beyond it, past
    `CULL_DISTANCE` from the core's reach but inside a capsule of radius 2 m.
    """
    arm = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'), link_radius=radius)
    ball = [Obstacle('sphere', (4.5, 0.0, 0.0), radius=0.1)]
    thetas = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, np.pi / 2]])
    measured = CollisionChecker(arm, ball).clearance(thetas)
    reference = uncapped(arm, ball, thetas, monkeypatch)
    assert np.all(measured <= reference + 1e-9)
    assert np.isclose(reference[0, 2], 1.4 - radius)
    assert (measured[0, 2] < 0.0) == (radius > 1.4)


def test_obstacles_out_of_reach_do_not_change_the_plan():
    """1,000 boxes far away are culled (they took 427 s through the planner node once)."""
    scene = load_scene(SCENES / 'fig3a.yaml')
    far = [Obstacle('box', (20.0 + k % 40, 20.0 + k // 40, 0.0), size=(0.2, 0.2, 0.2))
           for k in range(1000)]
    crowded = scene.with_obstacles(far)
    assert len(CollisionChecker(crowded.robot, crowded.obstacles)._obstacles) == 3
    assert np.allclose(plan(crowded).theta_s, plan(scene).theta_s)


# Self-collision, the base, channel names ------------------------------------------------

def folding_arm(disabled=None):
    """Three capsule links of 0.5 m (radius 0.05) turning about parallel z axes."""
    rows = [DHRow(a=0.5, alpha=0.0, d=0.0) for _ in range(3)]
    model = chain_from_dh(rows, ['a', 'b', 'c'], 0.05)
    return SpatialArm(with_disabled_collisions(model, disabled), 'position')


def test_a_pair_that_touches_reads_negative_and_disabled_pairs_are_absent():
    arm = folding_arm()
    checker = CollisionChecker(arm, [])
    assert checker.pairs == ((1, 3),)  # adjacent links are exempt
    assert checker.channel_names[-1] == 'link1[0] / link3[0]'
    folded = np.array([[0.0, np.pi, np.pi], [0.0, 0.0, 0.0], [0.0, np.pi, 2.5]])
    clearance = checker.clearance(folded)
    assert clearance[0, -1] == pytest.approx(-0.1)  # link 3 lies on link 1
    assert clearance[1, -1] == pytest.approx(0.5 - 0.1)  # straight: 0.5 m apart
    assert clearance[2, -1] <= 0.0
    exempt = CollisionChecker(folding_arm([['link1', 'link2'], ['link2', 'link3'],
                                           ['link1', 'link3']]), [])
    assert exempt.pairs == () and exempt.n_channels == 3
    assert np.all(np.isinf(exempt.clearance(folded)))


def test_base_clearance_of_obstacles_over_the_base():
    robot = robot_config('panda', 'pose')
    obstacles = [Obstacle('sphere', (0.0, 0.0, 0.3), radius=0.05),
                 Obstacle('box', (0.0, 0.0, 0.05), size=(0.1, 0.1, 0.1)),
                 Obstacle('cylinder', (-0.075, 0.0, 0.2), radius=0.05, length=0.1)]
    clearance = CollisionChecker(robot, obstacles).base_clearance()
    assert clearance[0] == pytest.approx(0.3 - 0.145 - 0.05, abs=1e-9)  # above the top
    assert clearance[1] <= 0.0
    assert clearance[2] == pytest.approx(0.15 - 0.145, abs=1e-6)
    task = Task((0.4, 0.0, 0.5), (0.4, 0.2, 0.5))
    with pytest.raises(InputError, match=r'obstacles\[1\]: covers the robot base'):
        check_plannable(Scene(robot.with_task_kind('position'), tuple(obstacles), task))


def test_channels_are_named_per_shape():
    assert CollisionChecker(ARM, []).channel_names == ['link1[0]', 'link2[0]', 'link3[0]']
    robot = robot_config('panda', 'pose')
    checker = CollisionChecker(robot, [])
    names = checker.channel_names
    assert len(names) == checker.n_channels == len(checker.lever_arms())
    moving = [item for item in robot.collision_shapes if item.link != 0]
    assert names[:len(moving)] == [
        f'{robot.link_names[item.link]}[{sum(o.link == item.link for o in moving[:k])}]'
        for k, item in enumerate(moving)]
    assert names[len(moving)] == 'panda_link0[0] / panda_link4[0]'
    assert all(' / ' in name for name in names[len(moving):])
    links = checker.channel_links
    assert np.all(links[:len(moving), 1] == -1)
    assert {tuple(pair) for pair in links[len(moving):].tolist()} == set(robot.self_collision_pairs)
