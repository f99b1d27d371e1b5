"""Certify that pieces of joint space are collision-free, over the continuum.

A piece is certified when every clearance channel (each link against the obstacles, each
self-collision pair; checker.py) measured at a point of it exceeds how far that
channel can change inside the piece: Σ_a R[c, a] · max |θ_a - point_a| over the piece's
corners (`CollisionChecker.lever_arms`; a planar chain among spheres also has a tighter
fan bound near its joints). A piece that is not certified is split, down to a depth
limit; a measured point that is not clear fails the certificate.

* `certify_simplices`: segments or triangles, measured at their centroids, each split in
  two or four.
* `certify_web`: every triangle of a failure surface's web. Its quads form a grid
  (path by waypoint), so blocks of 8 x 8 quads are measured first, at a vertex of the web
  in the block's middle against the box of the block's vertices, and split into four
  until single quads are left, whose triangles go to `certify_simplices`. Most of a web
  is far from every obstacle and is certified in a few blocks; every vertex is then
  measured exactly, for the smallest clearance reported. Only for a web of one sheet and
  a planar chain among spheres, whose clearance is one cheap exact pass (see
  `certify_web`); otherwise triangle by triangle from the start.
* `certify_polylines`: every segment of some polylines (recovery paths, moves).
"""

from __future__ import annotations

from typing import Protocol

import numba
import numpy as np

from .checker import CollisionChecker
from .distance_kernels import link_clearance_over_box, planar_joint_points

# Certified clearance must beat the motion bound by this much [m]: absorbs the rounding
# of the clearance computation (about 1e-8 m near contact).
_ROUNDING = 1e-6
# [rad] the largest joint angle certified: beyond it the forward kinematics rounds by more
# than _ROUNDING (at 1e17 rad the arm's computed pose jumps by whole radians) and sums of
# corners overflow. A web is lifted a few turns at most.
LARGEST_ANGLE = 1e3
# Quads a side of a web's first blocks: a power of two, halved at each level.
_FIRST_BLOCK = 8


class Web(Protocol):
    """A triangulated web of joint paths, as `paper.failure_surface.FailureSurface` is.

    `paths` (K, W+1, n) [rad]; `vertices` (K·(W+1), n) and `triangles` (T, 3) indices into
    them, two per quad of the path-by-waypoint grid; `cuts` (K-1,) where consecutive paths
    are not joined; `live_triangles` (T,) bool; `vertex_ids` (K·(W+1),) one id per
    distinct point and `shared_points` (ids,) bool for points several vertices share.
    """

    paths: np.ndarray
    vertices: np.ndarray
    triangles: np.ndarray
    cuts: np.ndarray
    live_triangles: np.ndarray
    vertex_ids: np.ndarray
    shared_points: np.ndarray


def certify_simplices(checker: CollisionChecker, corners: np.ndarray, margin: float,
                      max_depth: int) -> tuple[bool, int, float, int]:
    """Certify that every point of each simplex is collision-free.

    `corners` (S, c, n) [rad] are segments (c = 2) or triangles (c = 3) in joint space.
    Returns (ok, index of the first simplex that failed or -1, smallest clearance sampled
    [m], number of clearance samples). A simplex with a corner that is not finite or lies
    beyond `LARGEST_ANGLE` fails unmeasured. Raises ValueError for corners that are not
    (S, c, n), c = 2 or 3, with n the robot's joints.
    """
    corners = _checked(checker, corners, 3, 'corners')
    if corners.shape[1] not in (2, 3):  # a split would drop the corners past the third
        raise ValueError(f'corners must be segments or triangles, got {corners.shape[1]} '
                         'corners a simplex')
    arms = checker.lever_arms()
    roots = np.arange(len(corners))
    smallest = np.inf
    samples = 0
    measurable = np.all(np.abs(corners) <= LARGEST_ANGLE, axis=(1, 2))  # False for NaN too
    if not measurable.all():
        return False, int(np.flatnonzero(~measurable)[0]), np.nan, 0
    for _ in range(max_depth + 1):
        if len(corners) == 0:
            return True, -1, float(smallest), samples
        centroids = corners.mean(axis=1)
        spread = np.max(np.abs(corners - centroids[:, None, :]), axis=1)
        hit, opened, least = _measure(checker, centroids, spread, arms, margin)
        samples += len(corners)
        smallest = min(smallest, least)
        if hit >= 0:
            return False, int(roots[hit]), float(smallest), samples
        corners, roots = _split(corners[opened]), np.repeat(roots[opened], _pieces(corners))
    if len(corners) == 0:
        return True, -1, float(smallest), samples
    return False, int(roots[0]), float(smallest), samples


def certify_web(checker: CollisionChecker, surface: Web, margin: float,
                max_depth: int) -> tuple[bool, tuple[int, int], float, int]:
    """Certify that every live triangle of the web (`FailureSurface.triangles`) is clear.

    Blocks of quads first where they pay, then the triangles of the quads left (module
    docstring); each triangle may still be split `max_depth` times. Returns (ok, (path,
    waypoint) of a vertex where it failed or (-1, -1), smallest clearance measured [m],
    number of clearance samples). Every point measured lies on the web; with blocks, every
    vertex is measured too (one that is not clear fails the web), so that the smallest
    clearance is taken as densely as the triangles alone would take it. A web with a
    point that is not finite or lies beyond `LARGEST_ANGLE` fails unmeasured. A web
    without quads is certified along its one path, or at its points (one waypoint per
    path). Raises ValueError for a web that is not (K, W+1, n), K, W+1 >= 1, with n the
    robot's joints.
    """
    paths = _checked(checker, surface.paths, 3, 'the web')
    if not paths.shape[0] or not paths.shape[1]:
        raise ValueError(f'the web must have a path and a waypoint, got shape {paths.shape}')
    if not _measurable(paths):
        beyond = ~np.all(np.abs(paths) <= LARGEST_ANGLE, axis=2)  # True for NaN too
        return False, tuple(int(i) for i in np.argwhere(beyond)[0]), np.nan, 0
    if paths.shape[1] == 1 or len(paths) == 1:  # paths of one point, or one path
        return certify_polylines(checker, list(paths), margin, max_depth)
    rows, columns = paths.shape[0] - 1, paths.shape[1] - 1  # quads of the grid
    smallest, samples = np.inf, 0
    # Blocks pay for a planar chain among spheres, measured in one exact compiled pass:
    # elsewhere a block's large spread asks for exact distances of many more pairs (fcl)
    # than a triangle's (the Panda's self-check took 3x as long). And not on a web of
    # several sheets: it pads columns and repeats paths, so most of its quads are copies
    # or segments (seed 1's crowded 0: 23,108 live triangles, 3,000 distinct point sets)
    # that the triangles' dedupe drops and blocks would measure.
    if checker.planar_disks is not None and not surface.cuts.any():
        where, (top, left), smallest, samples = _certify_blocks(checker, paths, margin)
        if where[0] >= 0:
            return False, where, smallest, samples
        at_vertices = checker.min_clearance(surface.vertices)
        smallest = min(smallest, float(np.min(at_vertices)))
        samples += len(at_vertices)
        hits = np.flatnonzero(~(at_vertices > margin))  # NaN counts as a hit
        if len(hits):
            return False, tuple(int(i) for i in np.unravel_index(hits[0], paths.shape[:2])), \
                smallest, samples
    else:
        top, left = (corner.ravel() for corner in np.meshgrid(
            np.arange(rows), np.arange(columns), indexing='ij'))
    live = ~surface.cuts[top]
    quads = top[live] * columns + left[live]
    triangles = _distinct_triangles(surface, np.concatenate([quads, rows * columns + quads]))
    ok, failed, least, count = certify_simplices(
        checker, np.take(surface.vertices, triangles, axis=0), margin, max_depth)
    where = (-1, -1) if ok else tuple(int(i) for i in np.unravel_index(
        triangles[failed, 0], paths.shape[:2]))
    return ok, where, float(min(smallest, least)), samples + count


def certify_polylines(checker: CollisionChecker, polylines: list[np.ndarray], margin: float,
                      max_depth: int) -> tuple[bool, tuple[int, int], float, int]:
    """Certify that every point of each polyline (k_i, n) [rad] is collision-free.

    Segment by segment (`certify_simplices`); a polyline of one point is that point, and
    one of none has nothing to certify. Returns (ok, (polyline, point) where it failed or
    (-1, -1), smallest clearance sampled [m], number of clearance samples). A polyline
    with a point that is not finite or lies beyond `LARGEST_ANGLE` fails unmeasured.
    Raises ValueError for a polyline that is not (k, n) with n the robot's joints.
    """
    lines = [_checked(checker, line, 2, 'a polyline') for line in polylines]
    pieces = [np.stack([line[:-1], line[1:]], axis=1) if len(line) > 1 else
              np.stack([line, line], axis=1) for line in lines]
    owners = np.repeat(np.arange(len(pieces)), [len(piece) for piece in pieces])
    corners = np.concatenate(pieces + [np.zeros((0, 2, checker.robot.n_joints))])
    ok, failed, smallest, samples = certify_simplices(checker, corners, margin, max_depth)
    if ok:
        return True, (-1, -1), smallest, samples
    line = int(owners[failed])
    point = failed - int(np.searchsorted(owners, line))  # the segment's first point
    if _measurable(corners[failed, 0]) and not _measurable(corners[failed, 1]):
        point = min(point + 1, len(lines[line]) - 1)
    return False, (line, int(point)), smallest, samples


def _checked(checker: CollisionChecker, points, dimensions: int, what: str) -> np.ndarray:
    """Return `points` as a float array of `dimensions` axes, the last the robot's joints."""
    points = np.asarray(points, dtype=float)
    if points.ndim != dimensions or points.shape[-1] != checker.robot.n_joints:
        raise ValueError(f'{what} must be {dimensions}-dimensional with '
                         f'{checker.robot.n_joints} joint angles last, got shape {points.shape}')
    return points


def _measurable(points: np.ndarray) -> bool:
    """Whether every angle [rad] is finite and within `LARGEST_ANGLE`."""
    return bool(np.abs(points).max(initial=0.0) <= LARGEST_ANGLE)  # False for NaN


def _certify_blocks(checker: CollisionChecker, paths: np.ndarray, margin: float,
                    ) -> tuple[tuple[int, int], tuple[np.ndarray, np.ndarray], float, int]:
    """Certify the quads of a web's grid of points (K, W+1, n) [rad] in blocks.

    Quad (k, w) has corners (k, w) and (k+1, w+1). Blocks of `_FIRST_BLOCK` quads a side
    are measured at their middle vertex, against the box of their vertices, and the
    blocks left open are split in four until single quads are left. Returns the (path,
    waypoint) of a measured vertex that is not clear by more than `margin` [m] (else
    (-1, -1)), the (path, waypoint) of the quads left, the smallest clearance measured [m]
    and the number of measurements.
    """
    arms = checker.lever_arms()
    rows, columns = paths.shape[0] - 1, paths.shape[1] - 1
    size = _FIRST_BLOCK
    top, left = (corner.ravel() for corner in np.meshgrid(
        np.arange(0, rows, size), np.arange(0, columns, size), indexing='ij'))
    smallest, samples = np.inf, 0
    while size > 1:
        bottom, right = np.minimum(top + size, rows), np.minimum(left + size, columns)
        middle_row, middle_column = (top + bottom) // 2, (left + right) // 2
        at = paths[middle_row, middle_column]
        spread = _block_spread(paths, top, left, bottom, right, at)
        hit, opened, least = _measure(checker, at, spread, arms, margin)
        samples += len(top)
        smallest = min(smallest, least)
        if hit >= 0:
            return (int(middle_row[hit]), int(middle_column[hit])), (top, left), \
                float(smallest), samples
        size //= 2
        top = (top[opened][:, None] + [0, 0, size, size]).ravel()
        left = (left[opened][:, None] + [0, size, 0, size]).ravel()
        inside = (top < rows) & (left < columns)
        top, left = top[inside], left[inside]
    return (-1, -1), (top, left), float(smallest), samples


@numba.njit(cache=True)
def _block_spread(paths, top, left, bottom, right, at):
    """(S, n) [rad] how far each block's vertices reach from its point `at` (S, n), per joint.

    Block s holds the vertices of paths top[s]..bottom[s], waypoints left[s]..right[s].
    """
    spread = np.zeros(at.shape)
    for s in range(at.shape[0]):
        for k in range(top[s], bottom[s] + 1):
            for w in range(left[s], right[s] + 1):
                for a in range(at.shape[1]):
                    spread[s, a] = max(spread[s, a], abs(paths[k, w, a] - at[s, a]))
    return spread


def _measure(checker: CollisionChecker, at: np.ndarray, spread: np.ndarray,
             arms: np.ndarray, margin: float) -> tuple[int, np.ndarray, float]:
    """Measure pieces at points `at` (S, n) [rad], each reaching `spread` (S, n) [rad] from it.

    Returns the first piece whose point is not clear by more than `margin` [m] (-1 if
    none), which pieces (S,) bool the bounds leave open (to split), and the smallest
    clearance [m]. A planar chain among spheres is measured in one compiled pass
    (`CollisionChecker.planar_disks`).
    """
    if checker.planar_disks is not None:
        checker.checks += len(at)
        hit, opened, least = _measure_planar(np.ascontiguousarray(at),
                                             np.ascontiguousarray(spread),
                                             *checker.planar_disks, arms, margin, _ROUNDING)
        return int(hit), opened, float(least)
    motion = spread @ arms.T  # (S, C): how far each channel can change inside the piece
    clearance = checker.clearance(at, needed=margin + motion + _ROUNDING)
    hit = np.flatnonzero(np.any(~(clearance > margin), axis=1))  # NaN counts as a hit
    opened = np.any(~(clearance - margin > motion + _ROUNDING), axis=1)
    return (int(hit[0]) if len(hit) else -1), opened, float(clearance.min())


@numba.njit(cache=True)
def _measure_planar(at, spread, lengths, link_radius, centres, radii, cap, arms, margin,
                    rounding):
    """`_measure` for a planar chain among spheres, compiled: no clearance array.

    A piece stays open unless every link is clear of every sphere by more than `margin`
    over the box `at` ± `spread`, by the lever bound or by the fan bound of
    `link_box_clearance` (tighter near the joints), the better per sphere
    (`link_clearance_over_box`). `cap` bounds the clearance of the culled spheres at every
    configuration.
    """
    count, n = at.shape
    smallest = np.inf
    first_hit = -1
    opened = np.zeros(count, dtype=np.bool_)
    points = np.zeros((n + 1, 2))
    for s in range(count):
        planar_joint_points(lengths, at[s], points)
        direction = 0.0
        for k in range(n):
            direction += at[s, k]
            motion = rounding
            for a in range(n):
                motion += spread[s, a] * arms[k, a]
            nearest, clear = link_clearance_over_box(points, k, lengths[k], direction, spread[s],
                                                     motion, centres, radii,
                                                     link_radius + margin)
            clearance = min(nearest - link_radius, cap)
            smallest = min(smallest, clearance)
            if not clearance > margin and first_hit < 0:  # NaN counts as a hit
                first_hit = s
            if not (cap > margin and clear):
                opened[s] = True
    return first_hit, opened, smallest


def _distinct_triangles(surface: Web, chosen: np.ndarray) -> np.ndarray:
    """Vertex indices (T', 3) of the triangles among `chosen` that certification needs.

    `chosen` are indices into `surface.triangles`, live ones. Of the live triangles with
    one point set, the first is kept; a triangle with a repeated point (where a column is
    padded) is a segment or a point, left out when it is an edge or a corner of a proper
    triangle kept: certifying that triangle certifies it. This is done over every live
    triangle of the web, then the kept ones among `chosen` are returned: one left out here
    is covered by one kept, chosen or not (then certified in a block). Only triangles with
    a corner whose point another vertex shares can repeat a set or be such a segment or
    point, or hold one, so the others (almost all of the paper's fan) are kept without
    sorting.
    """
    if not len(chosen):
        return np.zeros((0, 3), dtype=surface.triangles.dtype)
    live = np.flatnonzero(surface.live_triangles)
    points = surface.vertex_ids[surface.triangles[live]]
    many = surface.shared_points
    shared = many[points[:, 0]] | many[points[:, 1]] | many[points[:, 2]]
    keep = ~shared
    keep[np.flatnonzero(shared)[_distinct_sets(points[shared])]] = True
    kept = np.zeros(len(surface.triangles), dtype=bool)
    kept[live[keep]] = True
    return surface.triangles[chosen[kept[chosen]]]


def _distinct_sets(points: np.ndarray) -> np.ndarray:
    """Return the indices, in order, of the first triangle (T, 3) of ids with each point set.

    A set with a repeated point is left out when it is an edge or a corner of a proper
    set (three distinct points) kept.
    """
    keys = np.sort(points, axis=1).astype(np.int64)
    base = int(keys.max(initial=0)) + 1
    if base ** 3 < 2 ** 63:  # one integer per set: far faster than unique rows
        codes = (keys[:, 0] * base + keys[:, 1]) * base + keys[:, 2]
        _, first = np.unique(codes, return_index=True)
    else:
        _, first = np.unique(keys, axis=0, return_index=True)
    first = np.sort(first)
    keys = keys[first]
    proper = (keys[:, 0] != keys[:, 1]) & (keys[:, 1] != keys[:, 2])
    covered = np.zeros(len(keys), dtype=bool)
    covered[~proper] = _within_proper(keys[~proper], keys[proper], base)
    return first[~covered]


def _within_proper(keys: np.ndarray, proper: np.ndarray, base: int) -> np.ndarray:
    """(T,) bool: whether each sorted point set (T, 3) is an edge or corner of a proper one.

    `proper` (P, 3) are sorted sets of three distinct points; ids are below `base`.
    """
    if base ** 2 >= 2 ** 63:  # too many points to pair in one integer: none is left out
        return np.zeros(len(keys), dtype=bool)
    edges = np.concatenate([proper[:, 0] * base + proper[:, 1],
                            proper[:, 1] * base + proper[:, 2],
                            proper[:, 0] * base + proper[:, 2]])
    low, high = keys[:, 0], keys[:, 2]
    return _found_in(low * base + high, edges) | ((low == high) & _found_in(low, proper))


def _found_in(values: np.ndarray, pool: np.ndarray) -> np.ndarray:
    """(V,) bool: whether each of a few integers `values` occurs in the large array `pool`.

    The pool is searched in the sorted values, not sorted itself: np.isin would sort the
    pool or build a table over its range, either far slower for a handful of values.
    """
    wanted = np.unique(values)
    if not len(wanted):
        return np.zeros(len(values), dtype=bool)
    pool = pool.ravel()
    at = np.minimum(np.searchsorted(wanted, pool), len(wanted) - 1)
    present = np.zeros(len(wanted), dtype=bool)
    present[at[wanted[at] == pool]] = True
    return present[np.searchsorted(wanted, values)]


def _pieces(corners: np.ndarray) -> int:
    return 2 if corners.shape[1] == 2 else 4


def _split(corners: np.ndarray) -> np.ndarray:
    """Halve segments (S, 2, n) or quarter triangles (S, 3, n) at their edge midpoints."""
    if corners.shape[1] == 2:
        a, b = corners[:, 0], corners[:, 1]
        m = 0.5 * (a + b)
        return np.stack([np.stack([a, m], 1), np.stack([m, b], 1)], 1).reshape(-1, 2, a.shape[-1])
    a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
    ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
    pieces = [np.stack(p, 1) for p in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))]
    return np.stack(pieces, 1).reshape(-1, 3, a.shape[-1])
