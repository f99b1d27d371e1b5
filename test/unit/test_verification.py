"""The self-check: its certificates against brute force, and its refusals."""

from dataclasses import replace

import numpy as np
import pytest
from ftplan_testing import paper_scene

from ftplan_ros.core import CollisionChecker, plan
from ftplan_ros.core.collision.certification import (
    LARGEST_ANGLE,
    _distinct_triangles,
    certify_simplices,
)
from ftplan_ros.core.model.robot import PlanarChain
from ftplan_ros.core.model.scene import Obstacle, Task
from ftplan_ros.core.paper.failure_surface import FailureSurface
from ftplan_ros.core.paper.verification import (
    certify_surface,
    goal_row_error,
    structure_problem,
    verify_surface,
)

ARM = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'))
X_GOAL = np.array([1.0, 0.0])
GOAL_TASK = Task((2.0, 0.0), (1.0, 0.0), 0.01)


def dense_triangle_points(corners, count=40):
    """Barycentric grid points (m, n) of a triangle (3, n)."""
    out = []
    for i in range(count + 1):
        for j in range(count + 1 - i):
            k = count - i - j
            out.append((i * corners[0] + j * corners[1] + k * corners[2]) / count)
    return np.array(out)


def test_certified_triangles_never_collide_under_dense_sampling():
    rng = np.random.default_rng(8)
    checker = CollisionChecker(ARM, [Obstacle('sphere', (1.3, 0.8, 0.0), radius=0.25),
                                     Obstacle('sphere', (-0.5, 1.5, 0.0), radius=0.3)])
    certified = refused = 0
    for _ in range(60):
        center = rng.uniform(-np.pi, np.pi, 3)
        corners = center + rng.uniform(-0.15, 0.15, (3, 3))
        ok, _, _, _ = certify_simplices(checker, corners[None], 0.0, max_depth=6)
        sampled = checker.min_clearance(dense_triangle_points(corners)).min()
        if ok:
            certified += 1
            assert sampled > 0
        else:
            refused += 1
    assert certified > 10 and refused > 3  # both outcomes exercised


@pytest.mark.parametrize('corner_count', [2, 3])
def test_the_compiled_planar_certificate_is_sound_and_at_least_the_general_one(corner_count):
    """The compiled pass adds a tighter bound (link_box_clearance) to the general one's."""
    obstacles = [Obstacle('sphere', (1.3, 0.8, 0.0), radius=0.25),
                 Obstacle('sphere', (-0.5, 1.5, 0.1), radius=0.3),
                 Obstacle('sphere', (30.0, 0.0, 0.0), radius=1.0)]  # culled: caps the clearance
    compiled = CollisionChecker(replace(ARM, link_radius=0.05), obstacles)
    general = CollisionChecker(replace(ARM, link_radius=0.05), obstacles, backend='fcl')
    assert compiled.planar_disks is not None and general.planar_disks is None
    rng = np.random.default_rng(12)
    outcomes, fewer = set(), 0
    for trial in range(80):
        centres = rng.uniform(-np.pi, np.pi, (6, 1, 3))
        corners = centres + rng.uniform(-0.2, 0.2, (6, corner_count, 3))
        margin = 0.0 if trial % 2 else 0.05
        ok, _, smallest, samples = certify_simplices(compiled, corners, margin, 5)
        expected = certify_simplices(general, corners, margin, 5)
        assert ok or not expected[0]
        assert samples <= expected[3] and smallest >= expected[2] - 1e-12
        fewer += samples < expected[3]
        if ok:
            points = np.vstack([dense_triangle_points(np.vstack([c, c[-1:]])) for c in corners])
            assert general.min_clearance(points).min() > margin
        outcomes.add(ok)
    assert outcomes == {True, False} and fewer > 10


def test_the_triangles_certified_cover_every_triangle_of_the_web():
    """Every live triangle is certified, or is an edge or a corner of a proper one that is.

    Webs with padded columns (a repeated last point), repeated paths and shared points,
    as the recovery sheets build them, on a coarse lattice so that points coincide; in
    half of them most points are moved off it, so that most triangles share no point.
    """
    rng = np.random.default_rng(3)
    for trial in range(200):
        paths = rng.integers(0, 4, (int(rng.integers(2, 8)), int(rng.integers(2, 7)), 3)) * 0.5
        if trial % 2:
            paths = paths + rng.uniform(0.0, 0.01, paths.shape) * (rng.random(paths.shape) < 0.7)
        for k in range(len(paths)):
            if rng.random() < 0.5:  # padded: the column ends early
                end = int(rng.integers(1, paths.shape[1]))
                paths[k, end:] = paths[k, end - 1]
        paths[:, 0] = paths[0, 0]
        if len(paths) > 2 and rng.random() < 0.5:
            paths[2] = paths[1]  # a cut: a repeated path
        surface = FailureSurface(paths, 0, (), (0,))
        ids = surface.vertex_ids
        kept = [frozenset(ids[t]) for t in _distinct_triangles(
            surface, np.flatnonzero(surface.live_triangles))]
        proper = [k for k in kept if len(k) == 3]
        assert len(proper) == len(set(proper)), trial
        for triangle in surface.triangles[surface.live_triangles]:
            points = frozenset(ids[triangle])
            assert points in kept or (len(points) < 3 and any(points <= k for k in proper)), \
                (trial, sorted(points))


@pytest.mark.parametrize('angle', [1e17, 6e307, 1e308])
def test_huge_finite_angles_fail_closed(angle):
    """Angles whose kinematics round by radians, or whose corner sums overflow, are refused.

    (Both used to be certified: a corner sum of inf gave NaN distances that min() dropped.)
    A disk on the tool at the middle corner: each simplex collides there.
    """
    theta = np.array([angle, -angle, 0.0])
    tip = ARM.joint_positions(theta)[-1]
    checker = CollisionChecker(ARM, [Obstacle('sphere', (tip[0], tip[1], 0.0), radius=0.3)])
    assert checker.min_clearance(theta[None])[0] < 0.0
    for corners in ([theta, theta + [0, 0, 0.01], theta - [0, 0, 0.01]],
                    [theta, theta + [0, 0, 0.01]]):
        ok, failed, _, _ = certify_simplices(checker, np.array([corners]), 0.0, 7)
        assert not ok and failed == 0
    moderate = np.array([LARGEST_ANGLE, -LARGEST_ANGLE, 0.0])  # the largest still measured
    assert certify_simplices(CollisionChecker(ARM, []),
                             np.array([[moderate, moderate - [0.01, -0.01, 0.01]]]), 0.0, 7)[0]


def test_a_web_of_one_path_is_certified_along_its_segments():
    """No triangle: S_F is the path itself, and a disk across it fails the certificate."""
    path = np.array([0.0, 0.5, 0.5]) + np.linspace(0.0, 1.0, 8)[:, None] * [0.0, 0.5, 0.7]
    surface = FailureSurface(path[None], 0, (0,), (0,))
    middle = ARM.joint_positions(path[4])[2]
    task = Task(tuple(ARM.joint_positions(path[0])[-1]), tuple(ARM.joint_positions(path[-1])[-1]))
    blocked = CollisionChecker(ARM, [Obstacle('sphere', (middle[0], middle[1], 0.0), radius=0.3)])
    assert not certify_surface(surface, blocked, task).ok
    assert certify_surface(surface, CollisionChecker(ARM, []), task).ok


def test_a_triangle_through_an_obstacle_is_refused_and_the_margin_counts():
    checker = CollisionChecker(ARM, [Obstacle('sphere', (1.5, 0.0, 0.0), radius=0.1)])
    through = np.array([[[0.0, 0.3, 0.0], [0.0, -0.3, 0.0], [0.05, 0.0, 0.0]]])
    assert not certify_simplices(checker, through, 0.0, 6)[0]
    clear = np.array([[[2.0, 0.0, 0.0], [2.1, 0.0, 0.0], [2.0, 0.1, 0.0]]])
    ok, _, smallest, _ = certify_simplices(checker, clear, 0.0, 6)
    assert ok
    # `smallest` may be a lower bound (clearances well above what is needed are bounds):
    # a margin above the exact clearance at the centroid must be refused.
    at_centroid = checker.min_clearance(clear.mean(axis=1)).min()
    assert smallest <= at_centroid
    assert not certify_simplices(checker, clear, at_centroid + 0.01, 6)[0]
    segment = np.array([[[0.0, 0.3, 0.0], [0.0, -0.3, 0.0]]])
    assert not certify_simplices(checker, segment, 0.0, 6)[0]


def test_goal_row_bound_holds_against_dense_sampling():
    # The branches for [1, 0] are straight lines in joint space; the one for [2, 0] curves.
    from ftplan_ros.core.paper.manifolds import trace_self_motion_manifolds
    curved = 0
    for x in (X_GOAL, np.array([2.0, 0.0])):
        for branch in trace_self_motion_manifolds(ARM, x, np.random.default_rng(1)):
            for stride in (1, 5, 20):
                points = branch.points[::stride]
                bound = goal_row_error(ARM, Task(tuple(x), tuple(x)), points, samples=4)[0]
                t = np.linspace(0, 1, 200)[None, :, None]
                chords = points[:-1, None] + t * (points[1:, None] - points[:-1, None])
                true = np.linalg.norm(ARM.forward_kinematics(chords) - x, axis=-1).max()
                assert true <= bound
                if true > 1e-4:  # a curved branch: the bound is not uselessly loose
                    curved += 1
                    assert bound < 3 * true
    assert curved >= 2


def test_a_goal_row_of_several_sheets_leaves_the_chords_between_them_out():
    """Chords given: the bound over them is the largest of each sheet's own, a point on
    no chord counts alone, the chord between two sheets does not count, and a point
    that is not finite makes the bound NaN (the check then fails)."""
    x = np.asarray(X_GOAL, dtype=float)
    task = Task(tuple(x), tuple(x))
    rng = np.random.default_rng(4)
    for _ in range(50):
        points = rng.uniform(-np.pi, np.pi, (7, 3))
        sheets = [(0, 2), (3, 3), (4, 6)]
        chords = np.array([0, 1, 4, 5])
        each = max(goal_row_error(ARM, task, points[first:last + 1], 4)[0]
                   for first, last in sheets)
        assert goal_row_error(ARM, task, points, 4, chords)[0] == each
        # With the chords between the sheets too, the bound is no smaller.
        assert goal_row_error(ARM, task, points, 4)[0] >= each
    points[3, 1] = np.nan
    assert np.isnan(goal_row_error(ARM, task, points, 4, chords)[0])


@pytest.fixture(scope='module')
def free_plan():
    scene = paper_scene()
    return scene, plan(scene)


def test_structure_problems_are_named(free_plan):
    _, result = free_plan
    surface = result.surface
    assert structure_problem(surface) == ''
    bent = surface.paths.copy()
    bent[surface.nominal, 5, 0] += 0.5
    assert 'not monotonic' in structure_problem(replace(surface, paths=bent))
    off_plane = surface.paths.copy()
    k = surface.hit_paths[2]
    off_plane[k, 3, 2] += 1e-9
    assert 'H_3 hit leaves the failure plane' in structure_problem(replace(surface,
                                                                             paths=off_plane))
    moved = surface.paths.copy()
    moved[4, 0, 1] += 1e-12
    assert 'start at θ_s' in structure_problem(replace(surface, paths=moved))


def test_an_obstacle_across_the_surface_fails_the_check(free_plan):
    scene, result = free_plan
    surface = result.surface
    middle = surface.paths[len(surface.paths) // 2, surface.paths.shape[1] // 2]
    elbow = ARM.joint_positions(middle)[2]
    checker = CollisionChecker(ARM, [Obstacle('sphere', (elbow[0], elbow[1], 0.0), radius=0.05)])
    verdict = verify_surface(surface, checker, GOAL_TASK)
    assert not verdict.ok and 'not collision-free' in verdict.reason
    assert verify_surface(surface, CollisionChecker(ARM, []), GOAL_TASK).ok


def test_a_goal_row_off_the_goal_fails_the_check(free_plan):
    _, result = free_plan
    verdict = certify_surface(result.surface, CollisionChecker(ARM, []),
                              Task((2.0, 0.0), tuple(X_GOAL + [0.05, 0.0]), 0.01))
    assert not verdict.ok and 'goal row strays' in verdict.reason
