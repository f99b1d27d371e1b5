"""Part 3 of the self-check on any web (core/paper/slices.py) against a brute-force slice.

The referee here knows nothing of the sweep: for each level it intersects every live
triangle of the web with the plane {θ_i = level} (a convex set: the hull of its edges'
intersections), merges equal points, and asks scipy whether each nominal point on the
level shares a component with the goal row. Levels are every web vertex value in the
nominal path's range, the midpoints between them, and dense samples of the nominal path.
"""

import re
from dataclasses import replace

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ftplan_ros.core.paper.failure_surface import FailureSurface
from ftplan_ros.core.paper.recovery import recover
from ftplan_ros.core.paper.slices import slice_problem

SAME = 1e-10  # [rad] points closer than this are one point
NEAR_VERTEX = 1e-7  # [rad] sampled levels keep this far from vertex values


# The referee ----------------------------------------------------------------------------

def live_triangles(paths):
    """Corners (T, 3, n) of S_F from its definition: quads split along (k, w)-(k+1, w+1).

    A path equal to the one before it closes a sheet: no quads join it to the next path.
    """
    out = []
    for k in range(len(paths) - 1):
        if k >= 1 and np.array_equal(paths[k], paths[k - 1]):
            continue
        for w in range(paths.shape[1] - 1):
            a, b = paths[k, w], paths[k + 1, w]
            c, d = paths[k + 1, w + 1], paths[k, w + 1]
            out += [(a, b, c), (a, c, d)]
    return np.array(out)


def top_chords(paths):
    """Segments (c, 2, n) of the goal row: top points of neighbouring paths of a sheet."""
    return np.array([(paths[k, -1], paths[k + 1, -1]) for k in range(len(paths) - 1)
                     if not (k >= 1 and np.array_equal(paths[k], paths[k - 1]))])


def segment_meets(p, q, joint, level):
    """Points where the segments p-q (s, n) meet the level, and which segment (m,) each is."""
    a, b = p[:, joint] - level, q[:, joint] - level
    on_p, on_q, across = a == 0, b == 0, a * b < 0
    t = np.where(across, a / np.where(across, a - b, 1.0), 0.0)
    crossing = p + t[:, None] * (q - p)
    crossing[:, joint] = level
    points = np.concatenate([p[on_p], q[on_q], crossing[across]])
    owner = np.concatenate([np.flatnonzero(on_p), np.flatnonzero(on_q), np.flatnonzero(across)])
    return points, owner


def slice_failures(paths, nominal, joint, level):
    """Nominal points on the level (m, n) whose slice component misses the goal row."""
    triangles = live_triangles(paths)
    pieces, owners = [], []
    for e in range(3):
        points, owner = segment_meets(triangles[:, e], triangles[:, (e + 1) % 3], joint, level)
        pieces.append(points)
        owners.append(owner)
    points, owner = np.concatenate(pieces), np.concatenate(owners)
    sources = segment_meets(paths[nominal][:-1], paths[nominal][1:], joint, level)[0]
    if not len(sources):
        return sources
    if not len(points):
        return sources
    # Arcs: every point to the first point of its triangle, and between equal points.
    order = np.argsort(owner, kind='stable')
    first = np.zeros(len(triangles), dtype=np.int64)
    first[owner[order][::-1]] = order[::-1]
    u, v = [np.arange(len(points))], [first[owner]]
    tree = cKDTree(points)
    pairs = tree.query_pairs(SAME, output_type='ndarray')
    u.append(pairs[:, 0])
    v.append(pairs[:, 1])
    u, v = np.concatenate(u), np.concatenate(v)
    graph = coo_matrix((np.ones(len(u)), (u, v)), shape=(len(points), len(points)))
    _, label = connected_components(graph, directed=False)
    chords = top_chords(paths)
    goals = np.concatenate([paths[:, -1][paths[:, -1, joint] == level]]
                           + ([segment_meets(chords[:, 0], chords[:, 1], joint, level)[0]]
                              if len(chords) else []))
    good = set()
    for hits in tree.query_ball_point(goals, SAME) if len(goals) else []:
        good.update(label[hits].tolist())
    failed = []
    for source, hits in zip(sources, tree.query_ball_point(sources, SAME), strict=True):
        if not good.intersection(label[hits].tolist()):
            failed.append(source)
    return np.array(failed).reshape(-1, paths.shape[-1])


def lock_levels(paths, nominal, joint, per_segment=12):
    """Levels where a lock of the joint on the nominal path can happen, densely.

    Every vertex value in the nominal range and the midpoints between them, plus
    `per_segment` points of each nominal segment (kept off vertex values).
    """
    path = paths[nominal]
    low, high = path[:, joint].min(), path[:, joint].max()
    values = np.unique(paths[..., joint])
    values = values[(values >= low) & (values <= high)]
    t = (np.arange(per_segment) + 0.5) / per_segment
    dense = (path[:-1, None, joint] + t[None, :] * (path[1:, None, joint]
                                                    - path[:-1, None, joint])).ravel()
    gap = np.abs(dense[:, None] - values[None, :]).min(axis=1)
    dense = dense[gap > NEAR_VERTEX]
    middles = 0.5 * (values[1:] + values[:-1])
    return np.unique(np.concatenate([values, middles, dense]))


def referee(paths, nominal, joint, first_only=False):
    """(level, point) of every unrecoverable lock found over `lock_levels` (or the first)."""
    failures = []
    for level in lock_levels(paths, nominal, joint):
        failures += [(level, point) for point in slice_failures(paths, nominal, joint, level)]
        if failures and first_only:
            break
    return failures


def named_level(message):
    """The locked value [rad] a slice_problem message names."""
    return float(re.search(r'= (-?\d+\.\d+) rad', message).group(1))


def assert_agrees(surface, joint, first_only=False):
    """slice_problem for one joint says '' exactly when the referee finds no failure."""
    paths = surface.paths
    failures = referee(paths, surface.nominal, joint, first_only)
    problem = slice_problem(surface, (joint,))
    assert (problem == '') == (not failures), (joint, problem, failures[:3])
    if problem:
        assert f'θ_{joint + 1} = ' in problem
        level = named_level(problem)
        values = np.unique(paths[..., joint])
        near = values[np.abs(values - level) < 2e-6]
        candidates = np.concatenate([[level], near, 0.5 * (near[1:] + near[:-1])])
        assert any(len(slice_failures(paths, surface.nominal, joint, v)) for v in candidates), \
            problem
    return failures


# Webs -----------------------------------------------------------------------------------

THETA_S = np.array([0.3, -0.2, 0.5])


def fan(goals, waypoints=6, nominal=2, hit_paths=(), tolerated=()):
    """The paper's web: straight paths from θ_s to each goal point (K, 3)."""
    t = np.linspace(0.0, 1.0, waypoints + 1)[None, :, None]
    paths = THETA_S + t * (np.asarray(goals) - THETA_S)[:, None, :]
    paths[:, 0] = THETA_S
    return FailureSurface(paths, nominal, tuple(hit_paths), tuple(tolerated))


def paper_goals():
    """Goal points along a curved arc that crosses θ_s,i for each joint i once."""
    s = np.linspace(0.0, 1.0, 5)
    offsets = np.stack([s - 0.25, 0.5 - s, (s - 0.75) * (1.0 + s)], axis=1)
    return THETA_S + offsets  # hit of joint i on path i + 1


def test_the_paper_fan_recovers_every_lock():
    surface = fan(paper_goals(), hit_paths=(1, 2, 3), tolerated=(0, 1, 2))
    for joint in range(3):
        assert surface.paths[joint + 1, -1, joint] == THETA_S[joint]
        assert assert_agrees(surface, joint) == []
    assert slice_problem(surface, (0, 1, 2)) == ''
    for bad in (np.nan, np.inf):
        paths = surface.paths.copy()
        paths[2, 3, 1] = bad
        assert slice_problem(replace(surface, paths=paths), (0,)) == \
            'the web has a point that is not finite'


def test_a_fan_without_a_strip_names_the_level_it_cannot_recover():
    """Joint 1's goal values [0.2, 0.6, 1.0, 0.7, 0.0] (nominal: the top); strip 2-3 cut.

    Locks above 0.2 still leave through the goal row between paths 0 and 2; locks in
    (0, 0.2) run into path 0, the web's edge: stuck.
    """
    goals = np.tile(THETA_S, (5, 1))
    goals[:, 0] += [0.2, 0.6, 1.0, 0.7, 0.0]
    goals[:, 1] += [0.5, 0.3, 0.1, -0.2, -0.4]
    goals[:, 2] += [-0.3, -0.1, 0.2, 0.3, 0.6]
    whole = fan(goals)
    assert assert_agrees(whole, 0) == []
    paths = np.insert(whole.paths, 3, whole.paths[2], axis=0)  # path 2 twice: a cut
    cut = FailureSurface(paths, 2, (), ())
    assert cut.cuts.tolist() == [False, False, False, True, False]
    failures = assert_agrees(cut, 0)
    levels = np.array([level for level, _ in failures]) - THETA_S[0]
    assert levels.min() > 0.0 and levels.max() < 0.2 + 1e-12
    assert len(levels) > 5
    problem = slice_problem(cut, (0,))
    assert 0.0 < named_level(problem) - THETA_S[0] < 0.2
    assert 'nominal segment' in problem or 'nominal waypoint' in problem
    # The recovery itself agrees: stuck at 0.1, free at 0.5.
    for fraction, stuck in ((0.1, True), (0.5, False)):
        theta = THETA_S + fraction * (goals[2] - THETA_S)
        assert (recover(cut, theta, 0) is None) == stuck


def sheet_columns(gamma, joint, route, tops):
    """Columns (W+1, L, 3): γ(j), the route (L-2, 2) at level γ_joint(j), the top j."""
    others = [a for a in range(3) if a != joint]
    columns = np.empty((len(gamma), len(route) + 2, 3))
    columns[:, 0] = gamma
    columns[:, 1:-1, joint] = gamma[:, None, joint]
    columns[:, 1:-1][..., others] = route[None]
    columns[:, -1] = tops
    columns[:, -1, joint] = gamma[:, joint]
    return columns


def sheet_web(gamma, sheets):
    """The recovery-sheet layout: γ twice (the nominal sheet), then each sheet, closed."""
    paths = [gamma, gamma]
    for columns in sheets:
        paths += list(columns) + [columns[-1]]
    return FailureSurface(np.array(paths[:-1]), 0, (), ())


# A nominal path that goes back and forth in joint 1 and is flat in it on segment 3.
GAMMA = np.array([[0.0, 0.0, 0.0], [0.4, 0.1, 0.2], [0.9, 0.3, 0.1], [0.6, 0.5, 0.3],
                  [0.6, 0.8, 0.2], [1.2, 0.9, 0.5], [1.0, 1.1, 0.7]])


def joint0_sheet(rng):
    route = np.array([[1.0, 0.5], [1.5, 0.9], [1.7, 1.6], [2.2, 1.8], [2.5, 2.5]])
    tops = np.array([2.7, 2.6]) + 0.05 * rng.standard_normal((len(GAMMA), 2))
    return sheet_columns(GAMMA, 0, route, np.insert(tops, 0, 0.0, axis=1))


def test_a_web_of_recovery_sheets_recovers_every_lock_of_its_joint():
    surface = sheet_web(GAMMA, [joint0_sheet(np.random.default_rng(1))])
    assert surface.sheets() == [(0, 1), (2, len(GAMMA) + 1)]  # γ, γ, then the columns
    assert assert_agrees(surface, 0) == []
    assert slice_problem(surface, (0,)) == ''
    # No sheet for joint 2: the nominal sheet alone recovers no lock of it.
    assert assert_agrees(surface, 1)
    assert 'θ_2' in slice_problem(surface, (0, 1))


@pytest.mark.parametrize('gap', [1, 2, 4])
def test_a_sheet_cut_between_two_columns_leaves_that_segment_unrecoverable(gap):
    columns = joint0_sheet(np.random.default_rng(1))
    broken = np.insert(columns, gap + 1, columns[gap], axis=0)  # no strip gap to gap + 1
    surface = sheet_web(GAMMA, [broken])
    assert len(surface.sheets()) == 3
    failures = assert_agrees(surface, 0)
    low, high = sorted(GAMMA[gap:gap + 2, 0])
    # Exactly the locks strictly inside segment `gap` fail.
    for level, point in failures:
        assert low < level < high
        a, b = GAMMA[gap], GAMMA[gap + 1]
        t = (level - a[0]) / (b[0] - a[0])
        assert np.allclose(point, a + t * (b - a))
    assert len(failures) > 5
    problem = slice_problem(surface, (0,))
    assert f'nominal segment {gap} ' in problem and low < named_level(problem) < high


def test_a_cut_beside_a_flat_segment_costs_nothing():
    """γ is flat in joint 1 on segment 3: the cut strip lies in one plane, its ends recover."""
    columns = joint0_sheet(np.random.default_rng(1))
    surface = sheet_web(GAMMA, [np.insert(columns, 4, columns[3], axis=0)])
    assert assert_agrees(surface, 0) == []
    assert slice_problem(surface, (0,)) == ''


def random_web(rng):
    """A web of recovery sheets for random joints, with random cuts and bent columns."""
    W = int(rng.integers(3, 7))
    gamma = np.cumsum(rng.uniform(-0.3, 0.5, (W + 1, 3)), axis=0)
    sheets = []
    for joint in rng.choice(3, size=int(rng.integers(1, 3)), replace=False):
        route = gamma[-1, [a for a in range(3) if a != joint]] + np.cumsum(
            rng.uniform(0.1, 0.4, (W - 1, 2)), axis=0)
        tops = route[-1] + rng.uniform(0.1, 0.3, (W + 1, 2))
        columns = sheet_columns(gamma, int(joint), route, np.insert(tops, joint, 0.0, axis=1))
        if rng.random() < 0.5:  # bend a column off its level
            j, r = rng.integers(W + 1), rng.integers(1, W)
            columns[j, r, joint] += rng.uniform(-0.4, 0.4)
        if rng.random() < 0.5:  # cut the sheet
            j = int(rng.integers(W))
            columns = np.insert(columns, j + 1, columns[j], axis=0)
        sheets.append(columns)
    return sheet_web(gamma, sheets)


def test_random_webs_agree_with_the_referee_and_with_recover():
    rng = np.random.default_rng(2024)
    outcomes = {True: 0, False: 0}
    for _ in range(24):
        surface = random_web(rng)
        for joint in range(3):
            failures = assert_agrees(surface, joint, first_only=True)
            outcomes[not failures] += 1
            # `recover` walks the same slice: it finds a path exactly where the referee does.
            path = surface.nominal_path
            for level in lock_levels(surface.paths, 0, joint, per_segment=2)[::7]:
                stuck = slice_failures(surface.paths, 0, joint, level)
                for point in segment_meets(path[:-1], path[1:], joint, level)[0]:
                    is_stuck = any(np.allclose(point, s, atol=SAME) for s in stuck)
                    assert (recover(surface, point, joint) is None) == is_stuck
    assert outcomes[True] >= 8 and outcomes[False] >= 8, outcomes

