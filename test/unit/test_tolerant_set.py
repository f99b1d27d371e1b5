"""The failure-tolerant set G on a joint grid (core/tolerant_set.py) against brute force.

Kinematics against circle intersections and numerical root finding; the cell classes,
their arcs and triangles (core/cell_classes.py) against dense sampling with the robot's
own CollisionChecker; the components (core/components.py) against an explicit graph;
the certified (inside) and liberal (outside) sets against configurations a verified plan
passes through and an over-approximating flood fill of each failure plane.
"""

import numpy as np
import pytest
from ftplan_testing import SCENES, paper_scene
from scipy.optimize import least_squares
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from ftplan_ros.core import CollisionChecker, InputError, load_scene, parse_scene, plan, recover
from ftplan_ros.core.collision.distance_kernels import planar_link_clearances
from ftplan_ros.core.grid.cell_classes import (
    JointLattice,
    _arc_half_width,
    _mark_cells,
    classify_cells,
    disk_arrays,
    link_lever_arms,
    supports,
    triangle_free,
)
from ftplan_ros.core.grid.components import components, layer_components, overlap
from ftplan_ros.core.grid.exhaustive import recoverable_in_plane
from ftplan_ros.core.grid.tolerant_set import (
    locked_goal_configurations,
    locked_goal_configurations_at,
    pooled_tolerant_set,
    preimage_samples,
    sub_slab_count,
    tolerant_set,
    two_link_solutions,
)
from ftplan_ros.core.model.paths import densify, point_at_fraction
from ftplan_ros.core.model.robot import PlanarChain
from ftplan_ros.core.model.scene import Obstacle

LINKS = np.array([1.0, 1.0, 1.0])


def wrapped(angles):
    return np.angle(np.exp(1j * np.asarray(angles)))


def same_configurations(a, b, atol=1e-9):
    """Whether the rows of a and b (s, n) [rad] are the same set, modulo whole turns."""
    if len(a) != len(b):
        return False
    return all(np.any(np.all(np.abs(wrapped(b - row)) < atol, axis=1)) for row in a) and \
        all(np.any(np.all(np.abs(wrapped(a - row)) < atol, axis=1)) for row in b)


def planar_fk(lengths, thetas):
    """Tool positions (..., 2) [m] of a planar chain, written out."""
    phi = np.cumsum(thetas, axis=-1)
    return np.stack([np.sum(lengths * np.cos(phi), axis=-1),
                     np.sum(lengths * np.sin(phi), axis=-1)], axis=-1)


def circle_solutions(a, b, target):
    """The 2R arm's solutions (s, 2) [rad]: elbows where the circles |e| = a, |t - e| = b meet."""
    d = float(np.linalg.norm(target))
    if d == 0.0 or d > a + b or d < abs(a - b):
        return np.empty((0, 2))
    along = (d * d + a * a - b * b) / (2.0 * d)
    height = np.sqrt(max(a * a - along * along, 0.0))
    u = target / d
    normal = np.array([-u[1], u[0]])
    out = []
    for sign in (1.0, -1.0) if height > 0 else (1.0,):
        elbow = along * u + sign * height * normal
        first = np.arctan2(elbow[1], elbow[0])
        rest = target - elbow
        out.append((first, np.arctan2(rest[1], rest[0]) - first))
    return np.array(out)


# Kinematics -----------------------------------------------------------------------------

def test_two_link_solutions_are_the_circle_intersections():
    rng = np.random.default_rng(3)
    found = 0
    for _ in range(300):
        a, b = rng.uniform(0.2, 2.0, 2)
        target = rng.uniform(-1.2, 1.2) * (a + b) * np.array([np.cos(t := rng.uniform(-4, 4)),
                                                               np.sin(t)])
        solutions = two_link_solutions(a, b, target)
        expected = circle_solutions(a, b, target)
        assert same_configurations(solutions, expected), (a, b, target)
        if len(solutions):
            found += 1
            assert np.allclose(planar_fk(np.array([a, b]), solutions), target, atol=1e-9)
    assert 100 < found < 300


def test_two_link_solutions_out_of_reach_or_without_a_link_are_none():
    assert two_link_solutions(1.0, 1.0, np.array([2.1, 0.0])).shape == (0, 2)
    assert two_link_solutions(2.0, 1.0, np.array([0.5, 0.0])).shape == (0, 2)
    assert two_link_solutions(0.0, 1.0, np.array([1.0, 0.0])).shape == (0, 2)
    at_full_stretch = two_link_solutions(1.0, 1.0, np.array([0.0, 2.0]))
    assert np.allclose(planar_fk(np.ones(2), at_full_stretch), [0.0, 2.0])


def numerical_locked_solutions(joint, value, x, grid=60):
    """Every configuration with θ_joint = value and the tool at x, by least squares.

    Seeds from a grid over the two free joints; roots with residual below 1e-10 m, once
    each.
    """
    others = [a for a in range(3) if a != joint]

    def residual(free):
        theta = np.empty(3)
        theta[joint], theta[others] = value, free
        return planar_fk(LINKS, theta) - x

    axis = np.linspace(-np.pi, np.pi, grid, endpoint=False)
    seeds = np.stack(np.meshgrid(axis, axis, indexing='ij'), -1).reshape(-1, 2)
    theta = np.empty((len(seeds), 3))
    theta[:, joint], theta[:, others] = value, seeds
    near = seeds[np.linalg.norm(planar_fk(LINKS, theta) - x, axis=1) < 0.2]
    roots = []
    for seed in near:
        fit = least_squares(residual, seed, xtol=1e-15, ftol=1e-15, gtol=1e-15)
        if np.linalg.norm(fit.fun) < 1e-10:
            root = np.empty(3)
            root[joint], root[others] = value, fit.x
            if not any(np.all(np.abs(wrapped(root - r)) < 1e-6) for r in roots):
                roots.append(root)
    return np.array(roots).reshape(-1, 3)


@pytest.mark.parametrize('joint', [0, 1, 2])
def test_locked_goal_configurations_are_all_the_roots(joint):
    rng = np.random.default_rng(10 + joint)
    counts = set()
    for _ in range(6):
        x = rng.uniform(0.4, 2.4) * np.array([np.cos(t := rng.uniform(-4, 4)), np.sin(t)])
        value = rng.uniform(-np.pi, np.pi)
        solutions = locked_goal_configurations(LINKS, x, joint, value)
        assert np.all(solutions[:, joint] == value)
        assert np.allclose(planar_fk(LINKS, solutions), x, atol=1e-9)
        assert same_configurations(solutions, numerical_locked_solutions(joint, value, x),
                                   atol=1e-6)
        counts.add(len(solutions))
        # The vectorised form gives the same configurations, value by value.
        many, which = locked_goal_configurations_at(LINKS, x, joint, np.array([value, 0.3]))
        assert same_configurations(many[which == 0], solutions)
        assert same_configurations(many[which == 1],
                                   locked_goal_configurations(LINKS, x, joint, 0.3))
    assert 2 in counts


def test_preimage_samples_reach_the_point():
    x = np.array([1.3, -0.6])
    samples = preimage_samples(LINKS, x, 64)
    assert len(samples) > 64
    assert np.allclose(planar_fk(LINKS, samples), x, atol=1e-9)
    # The last link's absolute angle takes the sampled values.
    assert len(np.unique(np.round(wrapped(samples.sum(axis=1)), 9))) > 32


def test_half_a_sub_slab_moves_the_tool_within_the_tolerance():
    robot = PlanarChain((1.0, 0.7, 0.4), ('a', 'b', 'c'))
    rng = np.random.default_rng(4)
    thetas = rng.uniform(-np.pi, np.pi, (4000, 3))
    for joint in range(3):
        for step, tolerance in ((0.1, 0.01), (0.05, 0.002), (0.2, 0.05)):
            m = sub_slab_count(robot, step, joint, tolerance)
            moved = thetas.copy()
            moved[:, joint] += step / (2 * m)
            shift = np.linalg.norm(planar_fk(np.array(robot.link_lengths), moved)
                                   - planar_fk(np.array(robot.link_lengths), thetas), axis=1)
            assert shift.max() <= tolerance
            if m > 1:  # and not absurdly many sub-slabs
                assert shift.max() > 0.3 * tolerance


# Clearances -----------------------------------------------------------------------------

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


def dense_triangle_points(corners, count=30):
    """Barycentric grid points (m, n) of a triangle (3, n)."""
    i, j = np.meshgrid(np.arange(count + 1), np.arange(count + 1), indexing='ij')
    keep = i + j <= count
    i, j = i[keep], j[keep]
    k = count - i - j
    return (i[:, None] * corners[0] + j[:, None] * corners[1] + k[:, None] * corners[2]) / count


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
        sampled = checker.min_clearance(dense_triangle_points(corners)).min()
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
            assert checker.min_clearance(dense_triangle_points(corners, 20)).min() > 0.1
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


def sample_cells(lattice, cells, per_cell, rng):
    """Random configurations (c·per_cell, 3) [rad] inside the cells (c, 3)."""
    offsets = rng.random((len(cells), per_cell, 3))
    return (lattice.lower + (cells[:, None, :] + offsets) * lattice.step).reshape(-1, 3)


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


# Components -----------------------------------------------------------------------------

def union_find_labels(mask, structure, periodic):
    """Components of mask under structure, wrapping periodic axes: an explicit graph."""
    shape = np.array(mask.shape)
    index = np.arange(mask.size).reshape(mask.shape)
    u, v = [], []
    for offset in np.argwhere(structure) - 1:
        target = np.argwhere(mask) + offset
        inside = np.all(periodic | ((target >= 0) & (target < shape)), axis=1)
        source = np.argwhere(mask)[inside]
        target = np.mod(target[inside], shape)
        keep = mask[tuple(target.T)]
        u.append(index[tuple(source[keep].T)])
        v.append(index[tuple(target[keep].T)])
    u, v = np.concatenate(u), np.concatenate(v)
    graph = coo_matrix((np.ones(len(u)), (u, v)), shape=(mask.size, mask.size))
    _, label = connected_components(graph, directed=False)
    return label.reshape(mask.shape)


def test_label_components_finds_the_components_round_the_torus():
    """The compiled labelling against the explicit graph: all 26 neighbours, or a layer's 8."""
    rng = np.random.default_rng(12)
    for trial in range(400):
        shape = tuple(rng.integers(1, 8, 3))
        mask = rng.random(shape) < rng.uniform(0.2, 0.8)
        periodic = rng.random(3) < 0.5
        joint = int(rng.integers(3))
        if trial % 2:
            labels, structure = components(mask, periodic).labels(), np.ones((3, 3, 3), bool)
        else:
            labels = layer_components(mask, joint, periodic).labels()
            structure = np.zeros((3, 3, 3), bool)
            structure[(slice(None),) * joint + (1,)] = True  # one layer: index 1 along it
        assert labels.dtype == np.int32
        assert np.all((labels > 0) == mask)
        assert np.array_equal(np.unique(labels[mask]), np.arange(1, labels.max() + 1))
        truth = union_find_labels(mask, structure, periodic)
        a, b = labels[mask], truth[mask]
        # The same partition: equal labels exactly where the referee's are equal.
        assert np.array_equal(a[:, None] == a[None, :], b[:, None] == b[None, :]), trial
        # What the runs answer without labels: the same as the labels say.
        found = components(mask, periodic, (0, 1, 2) if trial % 2 else
                           tuple(a for a in range(3) if a != joint))
        chosen = rng.random(labels.max() + 1) < 0.5
        assert np.array_equal(found.cells(chosen), chosen[labels] & mask)
        cells = np.argwhere(np.ones(shape, bool))
        assert np.array_equal(found.at(cells), labels[tuple(cells.T)])
        seeds = rng.random(shape) < 0.2
        holding = np.zeros(labels.max() + 1, bool)
        holding[labels[seeds & mask]] = True
        assert np.array_equal(found.holding(seeds), holding)
    for shape in ((0, 3, 3), (3, 3, 0)):  # no cell: no component, and no write outside
        assert components(np.zeros(shape, bool), np.ones(3, bool)).labels().shape == shape
    found = components(np.ones((4, 4, 4), bool), np.zeros(3, bool))
    with pytest.raises(ValueError, match='need 2 choices'):
        found.cells(np.array([False]))
    with pytest.raises(ValueError, match='within the grid'):
        found.at(np.array([[0, 4, 0]]))
    with pytest.raises(ValueError, match='must have the shape'):
        found.holding(np.ones((4, 4, 3), bool))
    for cells in (np.zeros((3, 2), int), np.array([[0.9, 0.2, 3.7]])):
        with pytest.raises(ValueError, match=r'integer indices \(k, 3\)'):
            found.at(cells)
    with pytest.raises(ValueError, match='need 2 choices'):
        found.cells(np.bool_(True))
    for across in ((), (-1, 0), (0, 3)):
        with pytest.raises(ValueError, match='across must name axes'):
            components(np.ones((4, 4, 4), bool), np.zeros(3, bool), across)
    with pytest.raises(ValueError, match='3 flags'):
        components(np.ones((4, 4, 4), bool), np.zeros(2, bool))
    with pytest.raises(ValueError, match=r'3-D, got shape \(\)'):
        components(np.bool_(True), np.zeros(3, bool))
    with pytest.raises(ValueError, match='joint must be'):
        layer_components(np.ones((4, 4, 4), bool), 3, np.zeros(3, bool))


def test_label_components_reads_whole_words_of_cells_as_cell_by_cell():
    """Grids of 8 and 16 cells per axis, read eight cells at a time, against the explicit graph.

    The masks are blocky (4-cell blocks, a few cells flipped), so lines and rows hold
    whole words of eight cells in and out of the mask as well as words that change.
    """
    rng = np.random.default_rng(14)
    for trial in range(40):
        shape = tuple(int(v) for v in rng.choice([8, 16], 3))
        blocks = rng.random(tuple(v // 4 for v in shape)) < rng.uniform(0.3, 0.7)
        mask = np.kron(blocks, np.ones((4, 4, 4), bool)).astype(bool)
        mask ^= rng.random(shape) < 0.03
        periodic = rng.random(3) < 0.5
        for joint in (None, 0, 1, 2):
            if joint is None:
                labels, structure = components(mask, periodic).labels(), np.ones((3, 3, 3), bool)
            else:
                labels = layer_components(mask, joint, periodic).labels()
                structure = np.zeros((3, 3, 3), bool)
                structure[(slice(None),) * joint + (1,)] = True
            assert np.all((labels > 0) == mask)
            a, b = labels[mask], union_find_labels(mask, structure, periodic)[mask]
            assert np.array_equal(a[:, None] == a[None, :], b[:, None] == b[None, :]), \
                (trial, joint)


def test_clearing_the_other_components_keeps_the_chosen_ones_cells():
    rng = np.random.default_rng(16)
    for _ in range(30):
        shape = tuple(int(v) for v in rng.integers(1, 12, 3))
        mask = rng.random(shape) < 0.5
        for found in (components(mask, rng.random(3) < 0.5),
                      layer_components(mask, int(rng.integers(0, 3)), rng.random(3) < 0.5)):
            chosen = rng.random(found.count + 1) < 0.5
            out = mask & (rng.random(shape) < 0.7)
            expected = out & found.cells(chosen)
            found.clear_others(chosen, out)
            assert np.array_equal(out, expected)
    with pytest.raises(ValueError, match='C-contiguous'):
        found.clear_others(chosen, np.asfortranarray(np.ones((2, 3, 4), bool)))


def test_overlap_is_whether_two_masks_share_a_cell():
    """Random masks, and disjoint ones but for one cell, in sizes read eight cells at a time."""
    rng = np.random.default_rng(15)
    for trial in range(100):
        shape = tuple(int(v) for v in rng.integers(1, 9, 3)) if trial % 2 else (8, 4, 2)
        a, b = (rng.random(shape) < rng.uniform(0.0, 0.2) for _ in range(2))
        assert overlap(a, b) == bool((a & b).any())
        assert overlap(a, a) == bool(a.any())
        a = rng.random(shape) < 0.5
        b = ~a
        assert not overlap(a, b)
        shared = tuple(int(rng.integers(0, v)) for v in shape)
        a[shared] = b[shared] = True
        assert overlap(a, b)
    with pytest.raises(ValueError, match='shapes'):
        overlap(np.ones((2, 2, 2), bool), np.ones((2, 2, 3), bool))


# G from both sides ----------------------------------------------------------------------

@pytest.fixture(scope='module')
def fig3a():
    scene = load_scene(SCENES / 'fig3a.yaml')
    return scene, tolerant_set(scene, 64), plan(scene)


def test_tool_near_holds_every_configuration_near_the_point(fig3a):
    scene, grid, _ = fig3a
    lattice = grid.lattice
    x = np.asarray(scene.task.goal, dtype=float)
    near = lattice.tool_near(scene.robot, x, 0.01)
    rng = np.random.default_rng(11)
    exact = preimage_samples(LINKS, x, 400)
    thetas = np.vstack([exact, exact + rng.uniform(-0.003, 0.003, exact.shape)])
    close = np.linalg.norm(planar_fk(LINKS, thetas) - x, axis=1) <= 0.01
    cells = lattice.cell_of(thetas[close])
    assert near[tuple(cells.T)].all()
    assert near.mean() < 0.05


def test_a_pooled_grid_takes_its_start_and_goal_cells_from_the_finer_grid(fig3a):
    """The blocks holding a cell of the finer grid's masks: no wider than the pooled
    lattice's own bounds, and holding every exact start and goal configuration."""
    scene, grid, _ = fig3a
    pooled = pooled_tolerant_set(grid)
    task, blocks = scene.task, (32, 2, 32, 2, 32, 2)
    for mine, finer, x, tolerance in ((pooled.near_start, grid.near_start, task.start, 0.0),
                                      (pooled.near_goal, grid.near_goal, task.goal,
                                       task.goal_tolerance)):
        x = np.asarray(x, dtype=float)
        assert np.array_equal(mine, finer.reshape(blocks).any(axis=(1, 3, 5)))
        own = pooled.lattice.tool_near(scene.robot, x, tolerance)
        assert not (mine & ~own).any() and mine.sum() < own.sum()
        exact = preimage_samples(LINKS, x, 400)
        assert mine[tuple(pooled.lattice.cell_of(exact).T)].all()


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


def test_certified_cells_escape_by_the_flood_fill_referee(fig3a):
    """A flood fill of the failure plane (over-approximating) never refutes an escape."""
    scene, grid, _ = fig3a
    checker = CollisionChecker(scene.robot, scene.obstacles)
    rng = np.random.default_rng(12)
    x_goal = np.asarray(scene.task.goal, dtype=float)
    for joint in grid.joints:
        cells = np.argwhere(grid.escape(joint).cells & grid.classes.certified)
        assert len(cells) > 1000
        for theta in sample_cells(grid.lattice, cells[rng.choice(len(cells), 6)], 1, rng):
            assert checker.min_clearance(theta[None])[0] > 0
            assert recoverable_in_plane(checker, theta, joint, x_goal, 180,
                                        goal_tolerance=scene.task.goal_tolerance)
        # Its goal configurations are exact, free and in certified cells.
        goals = grid.escape(joint).goal_points
        assert np.allclose(planar_fk(LINKS, goals), x_goal, atol=1e-9)
        assert checker.min_clearance(goals).min() > 0
        assert grid.escape(joint).cells[tuple(grid.lattice.cell_of(goals).T)].all()


def test_a_verified_plan_stays_in_the_liberal_cells(fig3a):
    """Every point of a plan's motion is in G, so in the over-approximation of G."""
    scene, grid, result = fig3a
    assert result.feasible
    lattice = grid.lattice
    nominal = densify(result.nominal_path, 0.005)
    assert grid.liberal_all[tuple(lattice.cell_of(nominal).T)].all()
    for fraction in np.linspace(0.0, 1.0, 9):
        theta = point_at_fraction(result.nominal_path, fraction)
        for joint in grid.joints:
            path = densify(recover(result.surface, theta, joint).path, 0.005)
            assert grid.liberal_escape(joint)[tuple(lattice.cell_of(path).T)].all()
            assert grid.classes.possible[tuple(lattice.cell_of(path).T)].all()


def test_free_goal_configurations_are_liberal(fig3a):
    scene, grid, _ = fig3a
    checker = CollisionChecker(scene.robot, scene.obstacles)
    goals = preimage_samples(LINKS, np.asarray(scene.task.goal, dtype=float), 720)
    free = goals[checker.min_clearance(goals) > 0]
    assert 100 < len(free) < len(goals)
    assert grid.liberal_all[tuple(grid.lattice.cell_of(free).T)].all()
    assert np.all(grid.certified_all <= grid.liberal_all)


def test_the_grid_takes_planar_3r_arms_among_disks_only():
    assert supports(paper_scene())
    four = parse_scene({'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0, 1.0]},
                        'task': {'start': [2.0, 0.0], 'goal': [1.0, 0.0]}})
    boxed = paper_scene().with_obstacles([Obstacle('box', (1.5, 1.5, 0.0), size=(0.2, 0.2, 0.2))])
    for scene in (four, boxed):
        assert not supports(scene)
        with pytest.raises(InputError, match='planar 3R arms among disks'):
            tolerant_set(scene, 32)


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
