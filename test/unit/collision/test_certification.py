"""Certifying webs and polylines in blocks: against dense sampling, and triangle by triangle."""

import numpy as np
import pytest
from ftplan_testing import triangle_points

from ftplan_ros.core import CollisionChecker
from ftplan_ros.core.collision.certification import (
    LARGEST_ANGLE,
    _distinct_triangles,
    certify_polylines,
    certify_simplices,
    certify_web,
)
from ftplan_ros.core.model.robot import PlanarChain
from ftplan_ros.core.model.scene import Obstacle
from ftplan_ros.core.paper.failure_surface import FailureSurface

ARM = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'), link_radius=0.05)
BARE_ARM = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'))  # the paper's arm: links of no radius


def random_web(rng, paths=12, waypoints=20):
    """A fan as the paper builds it: straight paths from θ_s to the points of a curved arc."""
    theta_s = rng.uniform(-np.pi, np.pi, 3)
    t = np.linspace(0.0, 1.0, paths)[:, None]
    arc = theta_s + rng.uniform(-1.0, 1.0, 3) + t * rng.uniform(-0.8, 0.8, 3) + \
        t ** 2 * rng.uniform(-0.4, 0.4, 3)
    fractions = np.linspace(0.0, 1.0, waypoints)[None, :, None]
    web = theta_s + fractions * (arc - theta_s)[:, None, :]
    web[:, 0] = theta_s
    return web


def random_disks(rng, count=3):
    return [Obstacle('sphere', (*rng.uniform(-2.5, 2.5, 2), 0.0), radius=rng.uniform(0.1, 0.4))
            for _ in range(count)]


def live_corners(surface):
    triangles = surface.triangles[surface.live_triangles]
    return surface.vertices[triangles]


@pytest.mark.parametrize('backend', ['auto', 'fcl'])
def test_a_certified_web_never_collides_and_blocks_lose_nothing(backend):
    """Sound against dense sampling; certifies every web that triangle by triangle does.

    Triangle by triangle (the certificate before blocks) is run on every live triangle.
    Blocks can only add certified webs: a block that is not certified is split down to
    the same triangles, and a block stops the check only at a vertex that is not clear,
    which no triangle through it can certify. The fcl backend measures the general way,
    triangle by triangle from the start.
    """
    rng = np.random.default_rng(21)
    outcomes, blocked = set(), 0
    for trial in range(60):
        checker = CollisionChecker(ARM, random_disks(rng), backend=backend)
        assert (checker.planar_disks is None) == (backend == 'fcl')
        paths = random_web(rng)
        if trial % 3 == 0:  # padded columns: quads that are segments, beside proper ones
            for k in rng.choice(len(paths), 4, replace=False):
                end = int(rng.integers(2, paths.shape[1]))
                paths[k, end:] = paths[k, end - 1]
        surface = FailureSurface(paths, 0, (), (0,))
        margin = 0.0 if trial % 2 else 0.05
        depth = 5 if trial % 4 else 2
        ok, where, smallest, samples = certify_web(checker, surface, margin, depth)
        corners = live_corners(surface)
        # The certificate before blocks: every distinct live triangle, with the same depth.
        by_triangle = certify_simplices(checker, surface.vertices[_distinct_triangles(
            surface, np.flatnonzero(surface.live_triangles))], margin, depth)
        assert ok or not by_triangle[0], trial
        if ok:
            assert checker.min_clearance(triangle_points(corners, 12)).min() > margin, trial
            assert where == (-1, -1) and np.isfinite(smallest) and smallest > margin
            blocked += backend == 'auto' and samples < len(corners)
        else:
            path, waypoint = where
            assert 0 <= path < surface.paths.shape[0] and 0 <= waypoint < surface.paths.shape[1]
        outcomes.add(ok)
    assert outcomes == {True, False} and (blocked > 5) == (backend == 'auto')


def test_a_web_refusal_names_a_vertex_near_the_collision():
    """A disk on the elbow at one vertex: the vertex named is at a triangle that hits it."""
    rng = np.random.default_rng(4)
    for trial in range(10):
        surface = FailureSurface(random_web(rng), 0, (), (0,))
        elbow = ARM.joint_positions(surface.paths[rng.integers(12), rng.integers(20)])[2]
        checker = CollisionChecker(ARM, [Obstacle('sphere', (*elbow, 0.0), radius=0.1)])
        ok, (path, waypoint), smallest, _ = certify_web(checker, surface, 0.0, 5)
        assert not ok and smallest < 0.0, trial
        vertex = path * surface.paths.shape[1] + waypoint
        around = surface.triangles[np.any(surface.triangles == vertex, axis=1)]
        nearest = checker.min_clearance(triangle_points(surface.vertices[around], 12)).min()
        assert nearest < 0.01, trial


def test_a_web_with_cut_strips_and_padding_is_covered():
    """Repeated paths (cuts) and padded columns: every live triangle is certified or refused.

    A web with a cut is certified triangle by triangle; one with padding only, in blocks.

    A disk placed on a live triangle's centroid must make the web fail; placed on a
    triangle of a dead strip only (between a repeated path and the next), the web may pass.
    """
    rng = np.random.default_rng(9)
    for trial in range(30):
        paths = random_web(rng, paths=14, waypoints=18)
        if trial % 2:
            paths[5] = paths[4]  # a cut: no quads join path 5 to path 6 (then no blocks)
        paths[10, 12:] = paths[10, 11]  # a padded column
        surface = FailureSurface(paths, 0, (), (0,))
        triangles = np.flatnonzero(surface.live_triangles)
        target = surface.vertices[surface.triangles[rng.choice(triangles)]].mean(axis=0)
        tip = ARM.joint_positions(target)[-1]
        checker = CollisionChecker(ARM, [Obstacle('sphere', (*tip, 0.0), radius=0.05)])
        assert not certify_web(checker, surface, 0.0, 5)[0], trial


def test_polylines_are_sound_and_the_refusal_names_the_polyline():
    rng = np.random.default_rng(5)
    obstacles = random_disks(rng, 4)
    checker = CollisionChecker(ARM, obstacles)
    outcomes = set()
    for trial in range(60):
        lines = [np.cumsum(np.vstack([rng.uniform(-np.pi, np.pi, 3),
                                      rng.uniform(-0.05, 0.05, (int(rng.integers(1, 40)), 3))]),
                           axis=0) for _ in range(int(rng.integers(1, 5)))]
        ok, (line, point), smallest, samples = certify_polylines(checker, lines, 0.0, 6)
        segments = [np.stack([p[:-1], p[1:]], axis=1) for p in lines if len(p) > 1]
        singles = [np.stack([p, p], axis=1) for p in lines if len(p) == 1]
        corners = np.concatenate(segments + singles)
        assert ok or not certify_simplices(checker, corners, 0.0, 6)[0], trial
        if ok:
            dense = corners[:, :1] + np.linspace(0.0, 1.0, 30)[None, :, None] * \
                (corners[:, 1:] - corners[:, :1])
            assert checker.min_clearance(dense.reshape(-1, 3)).min() > 0.0, trial
        else:
            assert 0 <= line < len(lines) and 0 <= point < len(lines[line])
        outcomes.add(ok)
    assert outcomes == {True, False}


def test_the_polyline_that_collides_is_the_one_named():
    clear = np.array([[0.0, 0.0, 0.0], [0.2, 0.1, 0.0], [0.4, 0.2, 0.1]])
    through = np.array([[1.0, 0.5, 0.0], [1.5, 0.5, 0.0], [2.0, 0.5, 0.0]])
    tip = ARM.joint_positions(through[1])[-1]
    checker = CollisionChecker(ARM, [Obstacle('sphere', (*tip, 0.0), radius=0.05)])
    assert certify_polylines(checker, [clear, clear], 0.0, 6)[0]
    ok, (line, point), _, _ = certify_polylines(checker, [clear, through, clear], 0.0, 6)
    assert not ok and line == 1 and point in (0, 1, 2)
    # A polyline of one point is that point; the junction between two polylines is not a
    # segment of either, so it is never measured.
    assert not certify_polylines(checker, [clear, through[1:2]], 0.0, 6)[0]
    assert certify_polylines(checker, [through[:1], through[2:]], 0.0, 6)[0] == \
        certify_simplices(checker, np.stack([through[[0, 2]], through[[0, 2]]], axis=1),
                          0.0, 6)[0]
    assert certify_polylines(checker, [], 0.0, 6) == (True, (-1, -1), np.inf, 0)


@pytest.mark.parametrize('bad', [np.nan, np.inf, 2.0 * LARGEST_ANGLE])
def test_points_that_are_not_finite_or_too_large_fail_unmeasured(bad):
    checker = CollisionChecker(ARM, [])
    paths = random_web(np.random.default_rng(1))
    paths[3, 7, 1] = bad
    ok, where, smallest, samples = certify_web(checker, FailureSurface(paths, 0, (), (0,)),
                                               0.0, 5)
    assert not ok and where == (3, 7) and np.isnan(smallest) and samples == 0
    line = np.zeros((5, 3))
    line[2, 0] = bad
    ok, where, _, samples = certify_polylines(checker, [np.ones((2, 3)), line], 0.0, 5)
    assert not ok and where == (1, 2) and samples == 0


def test_a_web_of_one_path_or_of_single_points_is_certified_along_what_it_has():
    path = np.array([0.0, 0.5, 0.5]) + np.linspace(0.0, 1.0, 30)[:, None] * [0.0, 0.5, 0.7]
    elbow = ARM.joint_positions(path[20])[2]
    blocked = CollisionChecker(ARM, [Obstacle('sphere', (*elbow, 0.0), radius=0.1)])
    ok, (k, w), _, _ = certify_web(blocked, FailureSurface(path[None], 0, (0,), (0,)), 0.0, 5)
    segment = path[w] + np.linspace(0.0, 1.0, 50)[:, None] * (path[w + 1] - path[w])
    assert not ok and k == 0 and blocked.min_clearance(segment).min() < 0.01
    assert certify_web(CollisionChecker(ARM, []), FailureSurface(path[None], 0, (0,), (0,)),
                       0.0, 5)[0]
    points = path[::10, None, :]  # three paths of one waypoint each
    ok, where, _, _ = certify_web(blocked, FailureSurface(points, 0, (0,), (0,)), 0.0, 5)
    hit = blocked.min_clearance(points[:, 0]) <= 0.0
    assert ok == (not hit.any())


def test_the_triangles_kept_among_some_are_those_the_whole_web_keeps():
    """Dedupe is over the whole web, then restricted: what blocks leave keeps no extra copy.

    A copy or a segment whose covering triangle lies in a certified block is left out,
    as it was when every triangle was certified one by one (a helper found a web the
    certificate rejected because a block's leftovers were deduped among themselves only).
    """
    rng = np.random.default_rng(2)
    for trial in range(40):
        paths = random_web(rng, paths=10, waypoints=8)
        paths[int(rng.integers(2, 10))] = paths[int(rng.integers(1, 9))]
        paths[int(rng.integers(10)), 5:] = paths[0, 4]
        surface = FailureSurface(paths, 0, (), (0,))
        live = np.flatnonzero(surface.live_triangles)
        whole = {tuple(t) for t in _distinct_triangles(surface, live)}
        chosen = rng.choice(live, len(live) // 3, replace=False)
        kept = [tuple(t) for t in _distinct_triangles(surface, chosen)]
        assert kept == [tuple(t) for t in surface.triangles[chosen] if tuple(t) in whole], trial
    assert len(_distinct_triangles(surface, np.zeros(0, dtype=np.int64))) == 0


def test_empty_polylines_hold_nothing_and_hide_nothing():
    """A polyline of no points certifies nothing, and the others are still checked."""
    through = np.array([[1.0, 0.5, 0.0], [1.5, 0.5, 0.0], [2.0, 0.5, 0.0]])
    tip = ARM.joint_positions(through[1])[-1]
    checker = CollisionChecker(ARM, [Obstacle('sphere', (*tip, 0.0), radius=0.05)])
    empty = np.zeros((0, 3))
    assert certify_polylines(checker, [empty], 0.0, 6)[0]
    for lines, named in (([empty, through], 1), ([through, empty], 0),
                         ([empty, through[:1], empty, through], 3)):
        ok, (line, _), _, _ = certify_polylines(checker, lines, 0.0, 6)
        assert not ok and line == named, lines


@pytest.mark.parametrize('shape', [(4, 5, 2), (4, 5, 4), (4, 0, 3), (0, 5, 3)])
def test_a_web_of_the_wrong_shape_is_refused(shape):
    """Angles for another arm would be read past their end by the compiled pass."""
    with pytest.raises(ValueError, match='web'):
        certify_web(CollisionChecker(ARM, random_disks(np.random.default_rng(0))),
                    FailureSurface(np.zeros(shape), 0, (), (0,)), 0.0, 5)


@pytest.mark.parametrize('line', [np.zeros(3), np.zeros((4, 2)), np.zeros((2, 4, 3))])
def test_a_polyline_or_simplices_of_the_wrong_shape_are_refused(line):
    checker = CollisionChecker(ARM, random_disks(np.random.default_rng(0)))
    with pytest.raises(ValueError, match='polyline'):
        certify_polylines(checker, [line], 0.0, 5)
    for corners in (np.zeros((2, 2, 2)), np.zeros((2, 1, 3)), np.zeros((2, 4, 3))):
        with pytest.raises(ValueError, match='corners'):
            certify_simplices(checker, corners, 0.0, 5)


def test_the_lever_arms_a_caller_changes_are_its_own():
    """Certification relies on the checker's lever arms: a caller's copy cannot change them."""
    through = np.array([[[1.0, 0.3, 0.0], [1.0, 0.7, 0.0]]])
    tip = ARM.joint_positions(through[0].mean(axis=0))[-1]
    checker = CollisionChecker(ARM, [Obstacle('sphere', (*tip, 0.0), radius=0.05)])
    expected = checker.lever_arms()
    arms = checker.lever_arms()
    arms[:] = 0.0
    assert np.array_equal(checker.lever_arms(), expected) and expected.max() > 0.0
    assert not certify_simplices(checker, through, 0.0, 6)[0]


def test_certified_triangles_never_collide_under_dense_sampling():
    rng = np.random.default_rng(8)
    checker = CollisionChecker(BARE_ARM, [Obstacle('sphere', (1.3, 0.8, 0.0), radius=0.25),
                                     Obstacle('sphere', (-0.5, 1.5, 0.0), radius=0.3)])
    certified = refused = 0
    for _ in range(60):
        center = rng.uniform(-np.pi, np.pi, 3)
        corners = center + rng.uniform(-0.15, 0.15, (3, 3))
        ok, _, _, _ = certify_simplices(checker, corners[None], 0.0, max_depth=6)
        sampled = checker.min_clearance(triangle_points(corners, 40)).min()
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
    compiled = CollisionChecker(ARM, obstacles)
    general = CollisionChecker(ARM, obstacles, backend='fcl')
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
            points = triangle_points(corners[:, [0, 1, -1]], 40)  # two corners: a segment
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
    tip = BARE_ARM.joint_positions(theta)[-1]
    checker = CollisionChecker(BARE_ARM, [Obstacle('sphere', (tip[0], tip[1], 0.0), radius=0.3)])
    assert checker.min_clearance(theta[None])[0] < 0.0
    for corners in ([theta, theta + [0, 0, 0.01], theta - [0, 0, 0.01]],
                    [theta, theta + [0, 0, 0.01]]):
        ok, failed, _, _ = certify_simplices(checker, np.array([corners]), 0.0, 7)
        assert not ok and failed == 0
    moderate = np.array([LARGEST_ANGLE, -LARGEST_ANGLE, 0.0])  # the largest still measured
    assert certify_simplices(CollisionChecker(BARE_ARM, []),
                             np.array([[moderate, moderate - [0.01, -0.01, 0.01]]]), 0.0, 7)[0]


def test_a_triangle_through_an_obstacle_is_refused_and_the_margin_counts():
    checker = CollisionChecker(BARE_ARM, [Obstacle('sphere', (1.5, 0.0, 0.0), radius=0.1)])
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

