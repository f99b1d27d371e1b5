"""Compiled lower bounds on the distance between convex pieces, by GJK: mesh links' covers.

A mesh link is measured through its cover (model/cover.py): convex pieces, each the hull
of a set of points, whose union holds the mesh. Against an obstacle, or another link's
piece or primitive, each piece gets a lower bound on its distance from the GJK algorithm
(Gilbert, Johnson, Keerthi 1988; van den Bergen, Collision Detection in Interactive 3D
Environments, 2003, ch. 4): the mesh's value is the least over its pieces.

The bound is sound whatever GJK's state: for any unit direction u, the support
functions h give min over the pair of u · (b - a) = -h_B(-u) - h_A(u), which no two
points of the pieces beat. GJK only steers u towards the nearest points, where this
separation is the distance: it stops once the separation is within `_TOLERANCE` of the
distance of the nearest point of its simplex (an upper bound), or reaches what the
caller needs. Spheres and capsules are measured by their cores (a point, a segment),
the radii subtracted after. Pieces that overlap get a bound <= 0. Every bound gives
`ROUNDING` away to float rounding.

Pieces are coded as in distance_kernels.py, plus HULL (the hull of `vertices`, in the
piece's frame). Lengths [m]; frames (4, 4) pose the pieces in the world.
"""

from __future__ import annotations

import numba
import numpy as np

from .distance_kernels import BOX, CAPSULE, CYLINDER, ROUNDING, SPHERE

HULL = 5
_TOLERANCE = 1e-9     # [m] GJK stops when its bound is this close to the distance
_ITERATIONS = 64      # at most; a bound is sound at every one


@numba.njit(cache=True, inline='always')
def _support(kind: int, parameters: np.ndarray, frame: np.ndarray, vertices: np.ndarray,
             ux: float, uy: float, uz: float, out: np.ndarray) -> None:
    """Write the point of a posed piece's core farthest along (ux, uy, uz) into `out` (3,)."""
    lx = frame[0, 0] * ux + frame[1, 0] * uy + frame[2, 0] * uz
    ly = frame[0, 1] * ux + frame[1, 1] * uy + frame[2, 1] * uz
    lz = frame[0, 2] * ux + frame[1, 2] * uy + frame[2, 2] * uz
    x = y = z = 0.0
    if kind == BOX:
        x = parameters[0] if lx >= 0.0 else -parameters[0]
        y = parameters[1] if ly >= 0.0 else -parameters[1]
        z = parameters[2] if lz >= 0.0 else -parameters[2]
    elif kind == CYLINDER:
        z = parameters[1] if lz >= 0.0 else -parameters[1]
        radial = np.sqrt(lx * lx + ly * ly)
        if radial > 0.0:
            x = parameters[0] * lx / radial
            y = parameters[0] * ly / radial
    elif kind == CAPSULE:
        z = parameters[1] if lz >= 0.0 else -parameters[1]
    elif kind == HULL:
        best = -np.inf
        for k in range(vertices.shape[0]):
            along = vertices[k, 0] * lx + vertices[k, 1] * ly + vertices[k, 2] * lz
            if along > best:
                best = along
                x, y, z = vertices[k, 0], vertices[k, 1], vertices[k, 2]
    for i in range(3):
        out[i] = frame[i, 0] * x + frame[i, 1] * y + frame[i, 2] * z + frame[i, 3]


@numba.njit(cache=True, inline='always')
def core_radius(kind: int, parameters: np.ndarray) -> float:
    """Return the radius [m] a piece adds around its core: spheres' and capsules', else 0."""
    return parameters[0] if kind == SPHERE or kind == CAPSULE else 0.0


@numba.njit(cache=True, inline='always')
def _copy(source: np.ndarray, target: np.ndarray) -> None:
    target[0], target[1], target[2] = source[0], source[1], source[2]


@numba.njit(cache=True)
def _closest_on_segment(simplex: np.ndarray, i: int, j: int, out: np.ndarray) -> int:
    """Write the point of segment simplex[i]-simplex[j] nearest the origin; return its vertices."""
    a, b = simplex[i], simplex[j]
    ab = b - a
    length2 = ab @ ab
    t = -(a @ ab)
    if t <= 0.0 or length2 <= 0.0:
        _copy(a, out)
        return 1 << i
    if t >= length2:
        _copy(b, out)
        return 1 << j
    t /= length2
    for k in range(3):
        out[k] = a[k] + t * ab[k]
    return (1 << i) | (1 << j)


@numba.njit(cache=True)
def _closest_on_triangle(simplex: np.ndarray, i: int, j: int, k: int, out: np.ndarray) -> int:
    """Write the point of triangle i, j, k of the simplex nearest the origin into `out`.

    Returns the bits of the vertices it uses (Ericson, Real-Time Collision Detection, 5.1.5).
    """
    a, b, c = simplex[i], simplex[j], simplex[k]
    ab, ac = b - a, c - a
    d1, d2 = -(ab @ a), -(ac @ a)
    if d1 <= 0.0 and d2 <= 0.0:
        _copy(a, out)
        return 1 << i
    d3, d4 = -(ab @ b), -(ac @ b)
    if d3 >= 0.0 and d4 <= d3:
        _copy(b, out)
        return 1 << j
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        out[:] = a + d1 / (d1 - d3) * ab
        return (1 << i) | (1 << j)
    d5, d6 = -(ab @ c), -(ac @ c)
    if d6 >= 0.0 and d5 <= d6:
        _copy(c, out)
        return 1 << k
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        out[:] = a + d2 / (d2 - d6) * ac
        return (1 << i) | (1 << k)
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
        out[:] = b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b)
        return (1 << j) | (1 << k)
    scale = 1.0 / (va + vb + vc)
    out[:] = a + ab * (vb * scale) + ac * (vc * scale)
    return (1 << i) | (1 << j) | (1 << k)


@numba.njit(cache=True, inline='always')
def _origin_with(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> bool:
    """Whether the origin lies strictly on the same side of plane a, b, c as d."""
    normal = np.cross(b - a, c - a)
    return -(normal @ a) * (normal @ (d - a)) > 0.0


@numba.njit(cache=True)
def _reduce(simplex: np.ndarray, count: int, nearest: np.ndarray, scratch: np.ndarray) -> int:
    """Write the simplex's point nearest the origin into `nearest`; keep the vertices it uses.

    Returns the vertices kept, 0 when a tetrahedron holds the origin strictly inside (a
    flat one never does: its nearest face is kept).
    """
    if count == 1:
        _copy(simplex[0], nearest)
        return 1
    if count == 2:
        used = _closest_on_segment(simplex, 0, 1, nearest)
    elif count == 3:
        used = _closest_on_triangle(simplex, 0, 1, 2, nearest)
    else:
        used, best, inside = 0, np.inf, True
        for i, j, k, other in ((0, 1, 2, 3), (0, 1, 3, 2), (0, 2, 3, 1), (1, 2, 3, 0)):
            if not _origin_with(simplex[i], simplex[j], simplex[k], simplex[other]):
                inside = False
            bits = _closest_on_triangle(simplex, i, j, k, scratch)
            if scratch @ scratch < best:
                best = scratch @ scratch
                used = bits
                _copy(scratch, nearest)
        if inside:
            return 0
    kept = 0
    for i in range(count):
        if used >> i & 1:
            if kept != i:
                _copy(simplex[i], simplex[kept])
            kept += 1
    return kept


@numba.njit(cache=True)
def convex_lower_bound(kind_a: int, parameters_a: np.ndarray, frame_a: np.ndarray,
                       vertices_a: np.ndarray, kind_b: int, parameters_b: np.ndarray,
                       frame_b: np.ndarray, vertices_b: np.ndarray, enough: float) -> float:
    """Lower bound [m] on the distance between two posed convex pieces (module docstring).

    Stops early once the bound reaches `enough` [m]. <= 0 when the pieces overlap.
    """
    radii = core_radius(kind_a, parameters_a) + core_radius(kind_b, parameters_b)
    simplex = np.empty((4, 3))
    on_a, on_b, nearest, scratch = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    ux, uy, uz = (frame_a[0, 3] - frame_b[0, 3], frame_a[1, 3] - frame_b[1, 3],
                  frame_a[2, 3] - frame_b[2, 3])
    _support(kind_a, parameters_a, frame_a, vertices_a, -ux, -uy, -uz, on_a)
    _support(kind_b, parameters_b, frame_b, vertices_b, ux, uy, uz, on_b)
    simplex[0] = on_a - on_b  # points of A - B: the distance is its nearest to the origin
    count = 1
    _copy(simplex[0], nearest)
    bound = -np.inf
    touching = False
    for _ in range(_ITERATIONS):
        size = np.sqrt(nearest @ nearest)
        if not size > 1e-12:  # touching cores, or a point that is not finite
            touching = True
            break
        ux, uy, uz = nearest[0] / size, nearest[1] / size, nearest[2] / size
        _support(kind_a, parameters_a, frame_a, vertices_a, -ux, -uy, -uz, on_a)
        _support(kind_b, parameters_b, frame_b, vertices_b, ux, uy, uz, on_b)
        separation = ux * (on_a[0] - on_b[0]) + uy * (on_a[1] - on_b[1]) + \
            uz * (on_a[2] - on_b[2])
        bound = max(bound, separation)
        if bound - radii >= enough or size - bound <= _TOLERANCE:
            break
        simplex[count] = on_a - on_b
        count = _reduce(simplex, count + 1, nearest, scratch)
        if count == 0:  # the cores overlap
            touching = True
            break
    if touching:  # every separation is <= 0, the distance too
        bound = min(bound, 0.0) if bound > -np.inf else 0.0
    return bound - radii - ROUNDING


# A table of pieces, as the kernels below take it: a tuple (kinds (K,), parameters (K, 3),
# bounds (K, 4): bounding spheres in the frame of the piece's shape, vertex_start (K+1,)
# and vertices (V, 3): a HULL's points, triangle_start (K+1,) and triangles (T, 3, 3): the
# mesh's triangles a HULL holds, exact (K,): whether the piece itself is what is measured
# (a primitive, or a tight hull: model/cover.py)). Shape s of a table is
# pieces piece_start[s]..piece_start[s+1]-1, all posed by the shape's frame.


@numba.njit(cache=True, inline='always')
def _sphere_gap(table_a, k: int, frame_a: np.ndarray, table_b, m: int,
                frame_b: np.ndarray) -> float:
    """Lower bound [m] on the distance of piece k of table_a and piece m of table_b, posed."""
    bound_a, bound_b = table_a[2][k], table_b[2][m]
    gap = 0.0
    for i in range(3):
        gap += (frame_a[i, 0] * bound_a[0] + frame_a[i, 1] * bound_a[1]
                + frame_a[i, 2] * bound_a[2] + frame_a[i, 3]
                - frame_b[i, 0] * bound_b[0] - frame_b[i, 1] * bound_b[1]
                - frame_b[i, 2] * bound_b[2] - frame_b[i, 3]) ** 2
    return np.sqrt(gap) - bound_a[3] - bound_b[3]


@numba.njit(cache=True, inline='always')
def _hull_bound(table_a, k: int, frame_a: np.ndarray, table_b, m: int, frame_b: np.ndarray,
                enough: float) -> float:
    """`convex_lower_bound` of piece k of table_a and piece m of table_b."""
    return convex_lower_bound(
        table_a[0][k], table_a[1][k], frame_a, table_a[4][table_a[3][k]:table_a[3][k + 1]],
        table_b[0][m], table_b[1][m], frame_b, table_b[4][table_b[3][m]:table_b[3][m + 1]],
        enough)


@numba.njit(cache=True)
def pieces_lower_bound(table_a, first_a: int, last_a: int, frame_a: np.ndarray, table_b,
                       first_b: int, last_b: int, frame_b: np.ndarray, enough: float) -> float:
    """Least lower bound [m] over pairs of pieces first_a..last_a-1 and first_b..last_b-1.

    A pair whose bounding spheres lie at least as far apart as the least so far or as
    `enough` [m] keeps the spheres' bound; the others are measured (GJK) as far as
    either asks.
    """
    best = np.inf
    for k in range(first_a, last_a):
        for m in range(first_b, last_b):
            gap = _sphere_gap(table_a, k, frame_a, table_b, m, frame_b)
            limit = min(best, enough)
            if gap < limit:
                gap = max(gap, _hull_bound(table_a, k, frame_a, table_b, m, frame_b, limit))
            best = min(best, gap)
    return best


@numba.njit(cache=True, inline='always')
def _parts(table, k: int) -> int:
    """How many parts piece k is measured by: itself if exact, else its triangles."""
    return 1 if table[7][k] else table[5][k + 1] - table[5][k]


@numba.njit(cache=True, inline='always')
def _part_bound(table_a, k: int, i: int, frame_a: np.ndarray, table_b, m: int, j: int,
                frame_b: np.ndarray, enough: float) -> float:
    """Lower bound [m] on the distance of part i of piece k and part j of piece m (`_parts`).

    j = -1 takes piece m whole.
    """
    no_parameters = np.zeros(3)
    if table_a[7][k]:
        kind_a, parameters_a = table_a[0][k], table_a[1][k]
        vertices_a = table_a[4][table_a[3][k]:table_a[3][k + 1]]
    else:
        kind_a, parameters_a, vertices_a = HULL, no_parameters, table_a[6][table_a[5][k] + i]
    if j < 0 or table_b[7][m]:
        kind_b, parameters_b = table_b[0][m], table_b[1][m]
        vertices_b = table_b[4][table_b[3][m]:table_b[3][m + 1]]
    else:
        kind_b, parameters_b, vertices_b = HULL, no_parameters, table_b[6][table_b[5][m] + j]
    return convex_lower_bound(kind_a, parameters_a, frame_a, vertices_a, kind_b,
                              parameters_b, frame_b, vertices_b, enough)


@numba.njit(cache=True)
def refined_distance(table_a, first_a: int, last_a: int, frame_a: np.ndarray, table_b,
                     first_b: int, last_b: int, frame_b: np.ndarray) -> float:
    """Lower bound [m] on the distance between two covered shapes, exact up to rounding.

    Shape a is pieces first_a..last_a-1 of table_a posed by frame_a, b likewise. An exact
    piece is measured whole; any other by the triangles it holds, each against the other
    piece whole first and, where that is not already farther than the least so far,
    against its triangles. Pieces are taken only where their hulls are nearer than the
    least so far. Contact (a bound <= 0) ends the search: a clearance <= 0 says no more
    (checker.py).
    """
    best = np.inf
    for k in range(first_a, last_a):
        for m in range(first_b, last_b):
            if _sphere_gap(table_a, k, frame_a, table_b, m, frame_b) >= best:
                continue
            hulls = _hull_bound(table_a, k, frame_a, table_b, m, frame_b, best)
            if hulls >= best:
                continue
            if table_a[7][k] and table_b[7][m]:
                best = hulls
            else:
                best = min(best, max(hulls, _parts_distance(table_a, k, frame_a, table_b, m,
                                                            frame_b, best)))
            if best <= 0.0:
                return best
    return best


@numba.njit(cache=True)
def _parts_distance(table_a, k: int, frame_a: np.ndarray, table_b, m: int,
                    frame_b: np.ndarray, best: float) -> float:
    """Least lower bound [m] over the parts of pieces k and m (`_parts`).

    `best` [m] if none is nearer; stops at contact.
    """
    for i in range(_parts(table_a, k)):
        if not table_b[7][m] and _part_bound(table_a, k, i, frame_a, table_b, m, -1, frame_b,
                                             best) >= best:
            continue
        for j in range(_parts(table_b, m)):
            best = min(best, _part_bound(table_a, k, i, frame_a, table_b, m, j, frame_b, best))
            if best <= 0.0:
                return best
    return best


@numba.njit(cache=True)
def cover_obstacle_distances(poses: np.ndarray, items: np.ndarray, piece_start: np.ndarray,
                             table, obstacle_frames: np.ndarray, obstacles,
                             needed: np.ndarray) -> np.ndarray:
    """Lower bounds (N, M, P) [m] on the distances of M covered shapes to P obstacles.

    Shape items[m] (an index into poses (N, S, 4, 4)) is pieces
    piece_start[items[m]].. of `table`; obstacle p is piece p of `obstacles`, posed by
    obstacle_frames[p]. Each value is the least over the shape's pieces, measured as far
    as `needed[n, m]` [m] asks (`pieces_lower_bound`).
    """
    count, shapes, obstacle_count = poses.shape[0], items.shape[0], obstacle_frames.shape[0]
    out = np.empty((count, shapes, obstacle_count))
    for n in range(count):
        for m in range(shapes):
            s = items[m]
            for p in range(obstacle_count):
                out[n, m, p] = pieces_lower_bound(
                    table, piece_start[s], piece_start[s + 1], poses[n, s], obstacles, p, p + 1,
                    obstacle_frames[p], needed[n, m])
    return out


@numba.njit(cache=True)
def cover_pair_distances(poses: np.ndarray, pairs: np.ndarray, piece_start: np.ndarray, table,
                         needed: np.ndarray) -> np.ndarray:
    """Lower bounds (N, Q) [m] on the distances between the shapes of Q pairs (Q, 2).

    Shapes index poses (N, S, 4, 4) and `piece_start` into `table`; each value is the
    least over pairs of pieces, measured as far as `needed` (N, Q) [m] asks.
    """
    count = poses.shape[0]
    out = np.empty((count, pairs.shape[0]))
    for n in range(count):
        for q in range(pairs.shape[0]):
            a, b = pairs[q, 0], pairs[q, 1]
            out[n, q] = pieces_lower_bound(table, piece_start[a], piece_start[a + 1],
                                           poses[n, a], table, piece_start[b],
                                           piece_start[b + 1], poses[n, b], needed[n, q])
    return out
