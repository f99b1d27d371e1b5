"""The cell classes of a joint grid (core/grid/cell_classes.py) against dense sampling.

Clearances, arcs and triangles against the robot's own CollisionChecker; the lattice's
cells near a tool point against brute force.
"""

import numpy as np
import pytest
from ftplan_testing import SCENES, triangle_points

from ftplan_ros.core import CollisionChecker, load_scene, parse_scene
from ftplan_ros.core.collision.distance_kernels import planar_link_clearances
from ftplan_ros.core.grid.cell_classes import (
    JointLattice,
    _arc_half_width,
    _mark_cells,
    classify_cells,
    disk_arrays,
    link_lever_arms,
    triangle_free,
)
from ftplan_ros.core.grid.tolerant_set import preimage_samples
from ftplan_ros.core.model.robot import PlanarChain

from .references import LINKS, planar_fk, sample_cells, wrapped


def disk_scene(radius=0.0, disks=((1.3, 0.8, 0.25), (-0.5, 1.5, 0.3), (0.9, -1.1, 0.2)),
               height=0.0):
    """A planar 3R arm among spheres whose centres lie `height` [m] off the arm's plane."""
    return parse_scene({
        'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0], 'link_radius': radius},
        'obstacles': [{'type': 'sphere', 'center': [x, y, height], 'radius': r}
                      for x, y, r in disks],
        'task': {'start': [2.0, 0.0], 'goal': [1.0, 0.0]}})


@pytest.mark.parametrize('radius, height', [(0.0, 0.0), (0.05, 0.0), (0.05, 0.15)])
def test_link_clearances_are_the_checkers(radius, height):
    scene = disk_scene(radius, height=height)
    checker = CollisionChecker(scene.robot, scene.obstacles, backend='fcl')  # posed frames
    thetas = np.random.default_rng(5).uniform(-np.pi, np.pi, (3000, 3))
    mine = planar_link_clearances(LINKS, radius, *disk_arrays(scene), thetas)
    assert np.allclose(mine, checker.clearance(thetas), atol=1e-9)
    assert (mine.min(axis=1) < 0).sum() > 100  # collisions among them


@pytest.mark.parametrize('radius', [0.0, 0.05])
def test_triangle_free_never_passes_a_triangle_that_collides_when_sampled(radius):
    scene = disk_scene(radius)
    checker = CollisionChecker(scene.robot, scene.obstacles)
    centers, radii = disk_arrays(scene)
    arms = link_lever_arms(LINKS)
    rng = np.random.default_rng(6)
    passed = refused = refused_colliding = 0
    for _ in range(250):
        corners = rng.uniform(-np.pi, np.pi, 3) + rng.uniform(-0.25, 0.25, (3, 3))
        free = triangle_free(LINKS, radius, centers, radii, arms, corners, 6)
        sampled = checker.min_clearance(triangle_points(corners, 30)).min()
        if free:
            passed += 1
            assert sampled > 0, corners
        else:
            refused += 1
            refused_colliding += sampled <= 0
    assert passed > 50 and refused_colliding > 20
    assert refused - refused_colliding < passed  # not hopelessly conservative


def test_triangle_free_with_a_margin_keeps_the_margin():
    scene = disk_scene()
    checker = CollisionChecker(scene.robot, scene.obstacles)
    centers, radii = disk_arrays(scene, margin=0.1)
    arms = link_lever_arms(LINKS)
    rng = np.random.default_rng(7)
    passed = 0
    for _ in range(150):
        corners = rng.uniform(-np.pi, np.pi, 3) + rng.uniform(-0.2, 0.2, (3, 3))
        if triangle_free(LINKS, 0.0, centers, radii, arms, corners, 5):
            passed += 1
            assert checker.min_clearance(triangle_points(corners, 20)).min() > 0.1
    assert passed > 20


def segment_distances(distance, length, directions):
    """Distances [m] from the point (distance, 0) to segments from the origin (densely)."""
    along = np.linspace(0.0, length, 801)
    x = along[None, :] * np.cos(directions)[:, None] - distance
    y = along[None, :] * np.sin(directions)[:, None]
    return np.sqrt(x * x + y * y).min(axis=1)


def test_the_arc_of_directions_that_reach_a_disk_is_the_sampled_one():
    """Inside the half width every direction comes within reach; outside, none does."""
    rng = np.random.default_rng(21)
    directions = np.linspace(-np.pi, np.pi, 4001)
    kinds = set()
    for _ in range(300):
        distance, length = rng.uniform(0.05, 2.5), rng.uniform(0.2, 1.5)
        reach = rng.uniform(0.0, 0.8)
        width = _arc_half_width(distance, length, reach * reach)
        gaps = segment_distances(distance, length, directions)
        slack = 1e-3 * length  # the segments are sampled every length / 800
        if width < 0.0:
            kinds.add('none')
            assert gaps.min() > reach - slack
            continue
        kinds.add('full' if width >= np.pi else 'arc')
        assert np.all(gaps[np.abs(directions) < width - 1e-3] <= reach + slack)
        assert np.all(gaps[np.abs(directions) > width + 1e-3] > reach - slack)
    assert kinds == {'none', 'full', 'arc'}
    assert _arc_half_width(1.0, 1.0, -0.01) < 0.0  # a sphere that stays off the plane


def test_marked_cells_are_the_cells_whose_direction_lies_in_the_arc():
    rng = np.random.default_rng(22)
    for _ in range(400):
        cells = int(rng.integers(1, 40))
        step = rng.uniform(0.5, 1.5) * 2.0 * np.pi / cells
        base, toward = rng.uniform(-8.0, 8.0), rng.uniform(-4.0, 4.0)
        width = rng.uniform(0.0, 4.0)
        counts = np.zeros(cells + 1, dtype=np.int64)
        _mark_cells(counts, toward, width, base, step)
        marked = np.cumsum(counts)[:cells]
        off = np.abs(wrapped(base + (np.arange(cells) + 0.5) * step - toward))
        assert np.all(marked[off < width - 1e-9] == 1)
        assert np.all(marked[off > width + 1e-9] == 0)


@pytest.mark.parametrize('radius, margin, height, cells', [
    (0.0, 0.0, 0.0, 64), (0.05, 0.0, 0.0, 48), (0.0, 0.08, 0.0, 37), (0.05, 0.0, 0.3, 64)])
def test_cell_classes_hold_for_every_configuration_sampled(radius, margin, height, cells):
    scene = disk_scene(radius, disks=((1.3, 0.8, 0.45), (-0.5, 1.5, 0.3), (0.9, -1.1, 0.4)),
                       height=height)
    checker = CollisionChecker(scene.robot, scene.obstacles, backend='fcl')  # posed frames
    classes = classify_cells(scene, cells, margin=margin)
    rng = np.random.default_rng(8)
    certified = np.argwhere(classes.certified)
    surely_hit = np.argwhere(~classes.possible)
    unsure = np.argwhere(classes.possible & ~classes.certified)
    assert len(certified) > 1000 and len(surely_hit) > 100 and len(unsure) > 100
    inside = sample_cells(classes.lattice, certified[rng.choice(len(certified), 3000)], 4, rng)
    assert checker.min_clearance(inside).min() > margin
    colliding = sample_cells(classes.lattice, surely_hit[rng.choice(len(surely_hit), 2000)], 4,
                             rng)
    assert checker.min_clearance(colliding).max() <= margin
    assert np.all(classes.certified <= classes.possible)


def test_pooled_classes_are_the_blocks_of_eight_and_hold_for_the_configurations_sampled():
    """Pooled 64^3 from 128^3: all of a block certified, any possibly free (the definition
    by reshaping), sound where sampled, sharper than classifying 64^3 itself; odd N refused."""
    scene = disk_scene(0.0, disks=((1.3, 0.8, 0.45), (-0.5, 1.5, 0.3), (0.9, -1.1, 0.4)))
    checker = CollisionChecker(scene.robot, scene.obstacles)
    fine = classify_cells(scene, 128)
    pooled = fine.pooled()
    blocks = (64, 2, 64, 2, 64, 2)
    assert np.array_equal(pooled.certified, fine.certified.reshape(blocks).all(axis=(1, 3, 5)))
    assert np.array_equal(pooled.possible, fine.possible.reshape(blocks).any(axis=(1, 3, 5)))
    direct = classify_cells(scene, 64)
    assert np.allclose(pooled.lattice.step, direct.lattice.step)
    assert np.array_equal(pooled.lattice.lower, direct.lattice.lower)
    assert pooled.possible.sum() < direct.possible.sum()
    assert pooled.certified.sum() > direct.certified.sum()
    rng = np.random.default_rng(9)
    thetas = rng.uniform(-np.pi, np.pi, (20000, 3))
    clearance = checker.min_clearance(thetas)
    cells = pooled.lattice.cell_of(thetas)
    assert pooled.possible[tuple(cells[clearance > 0].T)].all()
    assert (clearance[pooled.certified[tuple(cells.T)]] > 0).all()
    with pytest.raises(ValueError, match='cannot be pooled'):
        classify_cells(scene, 33).pooled()


def test_tool_near_holds_every_configuration_near_the_point():
    scene = load_scene(SCENES / 'fig3a.yaml')
    lattice = JointLattice.over(scene.robot, 64)
    x = np.asarray(scene.task.goal, dtype=float)
    near = lattice.tool_near(scene.robot, x, 0.01)
    rng = np.random.default_rng(11)
    exact = preimage_samples(LINKS, x, 400)
    thetas = np.vstack([exact, exact + rng.uniform(-0.003, 0.003, exact.shape)])
    close = np.linalg.norm(planar_fk(LINKS, thetas) - x, axis=1) <= 0.01
    cells = lattice.cell_of(thetas[close])
    assert near[tuple(cells.T)].all()
    assert near.mean() < 0.05


@pytest.mark.parametrize('lengths, limited', [((1.0, 1.0, 1.0), False), ((1.2, 0.7, 0.4), True),
                                               ((0.5, 1.0, 1.5), False)])
def test_tool_near_holds_every_cell_where_a_sampled_tool_comes_near(lengths, limited):
    """`tool_near` against brute force: cells sampled on a 7^3 lattice of points (corners
    and faces included) whose tool comes within the tolerance must all be marked, and
    every marked cell lies within the lever bound of its centre (Σ_a tip_arm[a] h_a)."""
    rng = np.random.default_rng(31)
    lengths = np.array(lengths)
    robot = PlanarChain(tuple(lengths), ('a', 'b', 'c'))
    for cells in (8, 17, 32):
        lower = np.array([-2.0, -2.5, -3.0]) if limited else np.full(3, -np.pi)
        upper = np.array([2.5, 2.0, 3.0]) if limited else np.full(3, np.pi)
        lattice = JointLattice(cells, lower, (upper - lower) / cells, np.full(3, not limited))
        half = 0.5 * lattice.step
        index = np.stack(np.meshgrid(*(np.arange(cells),) * 3, indexing='ij'), -1).reshape(-1, 3)
        centres = lattice.centres(index)
        for tolerance in (0.0, 0.01, 0.3):
            x = planar_fk(lengths, rng.uniform(-np.pi, np.pi, 3))
            near = lattice.tool_near(robot, x, tolerance)
            if cells % 2 == 0:  # pooled in the kernel as pool_blocks pools the mask
                blocks = near.reshape((cells // 2, 2) * 3).any(axis=(1, 3, 5))
                assert np.array_equal(lattice.tool_near(robot, x, tolerance, pooled=True),
                                      blocks)
            lever = robot.tip_lever_arms() @ half + tolerance + 1e-9
            loose = np.linalg.norm(planar_fk(lengths, centres) - x, axis=1) <= lever
            assert not (near.reshape(-1) & ~loose).any()
            # Brute force over the loose band's cells (the others are far from x).
            band = index[loose]
            band = band[rng.choice(len(band), min(len(band), 400), replace=False)]
            offsets = np.stack(np.meshgrid(*(np.linspace(-1.0, 1.0, 7),) * 3, indexing='ij'),
                               -1).reshape(-1, 3)
            points = lattice.centres(band)[:, None, :] + offsets[None] * half
            closest = np.linalg.norm(planar_fk(lengths, points) - x, axis=2).min(axis=1)
            assert near[tuple(band[closest <= tolerance].T)].all()
        # An exact pre-image point lies in a marked cell at tolerance 0.
        exact = preimage_samples(lengths, x, 64)
        exact = exact[lattice.inside(exact)]
        assert lattice.tool_near(robot, x)[tuple(lattice.cell_of(exact).T)].all()


def test_the_lattice_covers_the_limits():
    robot = parse_scene({'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0],
                                   'joint_limits': [[-1.0, 2.0], None, [-2.5, 0.5]]}}).robot
    lattice = JointLattice.over(robot, 16)
    assert np.allclose(lattice.lower + 16 * lattice.step, robot.limits[:, 1])
    thetas = np.random.default_rng(13).uniform(-4, 4, (500, 3))
    cells = lattice.cell_of(thetas)
    inside = lattice.inside(thetas)
    within = np.all((thetas >= robot.limits[:, 0]) | robot.periodic, axis=1) & \
        np.all((thetas <= robot.limits[:, 1]) | robot.periodic, axis=1)
    assert np.array_equal(inside, within)
    low = lattice.lower + cells * lattice.step
    wrapped_thetas = np.where(robot.periodic, np.mod(thetas - lattice.lower, 2 * np.pi)
                              + lattice.lower, thetas)
    ok = (wrapped_thetas >= low - 1e-12) & (wrapped_thetas <= low + lattice.step + 1e-12)
    assert np.all(ok[inside])
