"""Covers of triangle meshes by convex pieces, whose union holds every point of the mesh.

A mesh link is measured through its cover (collision/convex_kernels.py): a few convex
pieces, each the convex hull of some of the mesh's triangles. A triangle lies in any
convex set that holds its three corners, so a triangle whose corners all lie in one piece
lies in the cover; `assign_triangles` proves it for every triangle of the mesh (cutting
the ones that no single piece holds into four at their edges' midpoints, whose union is
the triangle) and hands each piece the triangles it holds. The distance to the nearest
piece is then a lower bound on the distance to the mesh.

A convex mesh is one piece, its own hull. The Panda's collision meshes (200-300
triangles each) are a hair off convex: their hulls bulge 0.07-0.41 mm beyond them. A
non-convex mesh (visual meshes reused for collision) is split, the piece that bulges
most first, into clusters of its triangles (cut to `_CLUSTER_EDGE` first, so that
clusters can follow the folds), until no piece bulges more than `TIGHT_PADDING` or
`MAX_PIECES` are made (or three splits in a row did not help).

Padding [m]: how far a piece's hull reaches beyond the mesh, the largest distance from a
point of its surface to the mesh, sampled every `_SAMPLE_SPACING`. A tight piece (at
most `TIGHT_PADDING`) is measured as if it were the mesh, as a primitive model pads its
links; the others are refined by their triangles (collision/checker.py). Lengths are in
the mesh's frame, metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree

# [m] a piece that bulges less is not split, and is measured as if it were the mesh
TIGHT_PADDING = 1e-3
MAX_PIECES = 12
_CLUSTER_EDGE = 0.02  # [m] triangles are cut to this longest edge before clustering
_SAMPLE_SPACING = 0.002  # [m] between samples of a piece's surface, for its padding
_INSIDE = 1e-10  # [m] a corner this close outside a piece's hull counts as in it (rounding)
_MAX_CUTS = 12  # rounds of cutting the triangles no piece holds, at most
_MAX_PENDING = 1 << 20  # triangles left to prove, at most: a cover needing more fails
# Triangles of a mesh to cover, at most: proving the cover holds them costs their corners
# times its facets (a smooth convex mesh of 40,000 takes about 20 s, once: it is cached).
MAX_MESH_TRIANGLES = 50_000
MAX_CUT_TRIANGLES = 1 << 20  # triangles cut to _CLUSTER_EDGE, at most: a larger mesh is refused
_CANDIDATES = 32  # nearest triangles (by centroid) measured per sample of a padding
_STALE_SPLITS = 3  # splits in a row that leave the padding as large end the search


@dataclass(frozen=True, eq=False)
class Cover:
    """Convex pieces whose union holds a mesh (module docstring), in the mesh's frame.

    `pieces[k]` (V_k, 3) are the points whose hull is piece k (its hull's vertices);
    `triangles[k]` (T_k, 3, 3) the mesh's triangles (or quarters of them) it holds,
    which together make up the whole mesh; `padding[k]` [m] how far it bulges beyond the
    mesh (inf when unknown).
    """

    pieces: tuple[np.ndarray, ...]
    triangles: tuple[np.ndarray, ...]
    padding: np.ndarray

    @property
    def largest_padding(self) -> float:
        """The cover's padding [m]: the most any piece bulges beyond the mesh."""
        return float(np.max(self.padding))

    @property
    def tight(self) -> np.ndarray:
        """(K,) bool: pieces that bulge at most TIGHT_PADDING beyond the mesh."""
        return self.padding <= TIGHT_PADDING


def build_cover(vertices: np.ndarray, faces: np.ndarray, target: float = TIGHT_PADDING,
                max_pieces: int = MAX_PIECES) -> Cover:
    """Cover a mesh, vertices (V, 3) [m] and faces (F, 3), by convex pieces.

    Splits the piece that bulges most until none bulges more than `target` [m] or
    `max_pieces` are made, and keeps the cover of least padding met on the way.
    Raises ValueError for a mesh without triangles or with more than MAX_MESH_TRIANGLES,
    or one whose triangles cut to `_CLUSTER_EDGE` would be more than MAX_CUT_TRIANGLES
    (a mesh metres across, or with a vertex that is not finite).
    """
    mesh = np.asarray(vertices, dtype=float)[np.asarray(faces, dtype=np.int64)]
    if mesh.ndim != 3 or len(mesh) == 0:
        raise ValueError('has no triangle: a mesh to cover needs at least one triangle')
    if len(mesh) > MAX_MESH_TRIANGLES:
        raise ValueError(f'has {len(mesh)} triangles, more than the {MAX_MESH_TRIANGLES} a '
                         'collision mesh may have: simplify it (e.g. a convex hull or a '
                         'decimated copy), or use primitives')
    cut = _cut_to(mesh, _CLUSTER_EDGE)
    measured = _Mesh(cut)
    clusters = [np.arange(len(cut))]
    pieces = [_hull_points(cut.reshape(-1, 3))]
    padding = [_padding(pieces[0], measured)]
    best = (list(pieces), list(padding))
    stale = 0  # splits since the padding last fell
    while max(padding) > target and len(pieces) < max_pieces and stale < _STALE_SPLITS:
        worst = int(np.argmax(padding))
        if len(clusters[worst]) < 2:
            break
        clusters[worst:worst + 1] = halves = _split(cut, clusters[worst])
        pieces[worst:worst + 1] = new = [_hull_points(cut[half].reshape(-1, 3))
                                          for half in halves]
        padding[worst:worst + 1] = [_padding(piece, measured) for piece in new]
        stale += 1
        if max(padding) < max(best[1]):
            best, stale = (list(pieces), list(padding)), 0
    pieces, padding = best
    triangles = assign_triangles(mesh, pieces)
    if triangles is None:  # each piece is the hull of its own triangles: never
        raise RuntimeError('a cover built from the mesh misses part of it')
    return Cover(tuple(pieces), tuple(triangles), np.array(padding))


def assign_triangles(mesh: np.ndarray, pieces: list[np.ndarray],
                     hulls: list[np.ndarray | None] | None = None) -> list[np.ndarray] | None:
    """Prove that the pieces hold every triangle (T, 3, 3) [m]: return each piece's triangles.

    A triangle goes to the first piece holding its three corners; one that no piece
    holds is cut into four, up to `_MAX_CUTS` times. Returns None when some part of the
    mesh lies in no piece (a corner outside them all shows it), or when that many cuts
    leave some part unproved. `hulls` are the pieces' halfspaces (`_halfspaces`).
    """
    if hulls is None:
        hulls = [_halfspaces(piece) for piece in pieces]
    assigned: list[list[np.ndarray]] = [[] for _ in pieces]
    pending = np.asarray(mesh, dtype=float)
    for _ in range(_MAX_CUTS + 1):
        if not len(pending):
            return [np.concatenate(parts + [np.zeros((0, 3, 3))]) for parts in assigned]
        corners = np.stack([_holds_points(piece, hull, pending.reshape(-1, 3)) for piece, hull
                            in zip(pieces, hulls, strict=True)], axis=1).reshape(
            len(pending), 3, len(pieces))
        if not corners.any(axis=2).all() or len(pending) > _MAX_PENDING:
            return None
        held = corners.all(axis=1)
        owner = np.where(held.any(axis=1), np.argmax(held, axis=1), -1)
        for k in range(len(pieces)):
            assigned[k].append(pending[owner == k])
        pending = _quarter(pending[owner < 0])
    return None


def _holds_points(piece: np.ndarray, hull: np.ndarray | None, points: np.ndarray,
                  ) -> np.ndarray:
    """(P,) bool: whether the piece holds each point (P, 3) (a flat one: its own points)."""
    points = np.ascontiguousarray(points, dtype=float)
    if hull is not None:
        return inside_halfspaces(points, np.ascontiguousarray(hull), _INSIDE)
    return among_points(points, np.ascontiguousarray(piece, dtype=float))


def _halfspaces(piece: np.ndarray) -> np.ndarray | None:
    """Return the hull's facets (F, 4): unit normal, offset (n · x + d <= 0 in); None if flat."""
    try:
        return ConvexHull(piece).equations
    except (QhullError, ValueError):
        return None


def _hull_points(points: np.ndarray) -> np.ndarray:
    """Return the vertices (V, 3) of the points' hull: all distinct points if they are flat."""
    points = np.unique(points, axis=0)
    try:
        return points[np.sort(ConvexHull(points).vertices)]
    except (QhullError, ValueError):
        return points


def _split(triangles: np.ndarray, cluster: np.ndarray) -> list[np.ndarray]:
    """Split a cluster of triangles (indices) in two by 2-means of their centroids."""
    centroids = triangles[cluster].mean(axis=1)
    middle = centroids.mean(axis=0)
    axis = np.linalg.svd(centroids - middle, full_matrices=False)[2][0]
    side = (centroids - middle) @ axis > 0.0
    for _ in range(30):
        if side.all() or not side.any():
            break
        means = centroids[~side].mean(axis=0), centroids[side].mean(axis=0)
        moved = (np.linalg.norm(centroids - means[1], axis=1)
                 < np.linalg.norm(centroids - means[0], axis=1))
        if np.array_equal(moved, side):
            break
        side = moved
    if side.all() or not side.any():  # all centroids alike: halve by the principal axis
        order = np.argsort((centroids - middle) @ axis, kind='stable')
        side = np.zeros(len(cluster), dtype=bool)
        side[order[len(order) // 2:]] = True
    return [cluster[~side], cluster[side]]


def _quarter(triangles: np.ndarray) -> np.ndarray:
    """Cut triangles (T, 3, 3) into four each at their edges' midpoints: (4T, 3, 3)."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
    return np.stack([np.stack(p, axis=1) for p in ((a, ab, ca), (ab, b, bc), (ca, bc, c),
                                                    (ab, bc, ca))], axis=1).reshape(-1, 3, 3)


def _cut_to(triangles: np.ndarray, longest: float) -> np.ndarray:
    """Quarter the triangles (T, 3, 3) whose longest edge exceeds `longest` [m], repeatedly.

    Raises ValueError before the cut triangles would be more than MAX_CUT_TRIANGLES.
    """
    done = []
    count = 0  # triangles in done
    pending = triangles
    while len(pending):
        edges = np.linalg.norm(pending - np.roll(pending, 1, axis=1), axis=2).max(axis=1)
        short = edges <= longest
        done.append(pending[short])
        count += int(short.sum())
        if count + 4 * int((~short).sum()) > MAX_CUT_TRIANGLES:
            raise ValueError(f'would be cut into more than {MAX_CUT_TRIANGLES} triangles of '
                             f'{100 * longest:g} cm edges for its cover: simplify it, or use '
                             'primitives')
        pending = _quarter(pending[~short])
    return np.concatenate(done)


def _padding(piece: np.ndarray, mesh: _Mesh) -> float:
    """How far [m] a piece's hull reaches from the mesh: the most of its facets' samples.

    Samples are `_SAMPLE_SPACING` apart; inf for a piece too flat to have a hull.
    """
    try:
        facets = piece[ConvexHull(piece).simplices]
    except (QhullError, ValueError):
        return np.inf
    return mesh.largest_distance(_sample_triangles(facets, _SAMPLE_SPACING))


class _Mesh:
    """A mesh's triangles (T, 3, 3) [m], cut to short edges, to measure points against."""

    def __init__(self, triangles: np.ndarray):
        self.triangles = np.ascontiguousarray(triangles)
        self.tree = cKDTree(self.triangles.mean(axis=1))

    def largest_distance(self, points: np.ndarray) -> float:
        """Return the largest of the points' (P, 3) distances [m] to the mesh.

        Each point is first measured against the `_CANDIDATES` triangles whose centroids
        lie nearest it, which can only overestimate; then exactly, the largest estimates
        first, until no estimate left exceeds the largest exact distance.
        """
        count = min(_CANDIDATES, len(self.triangles))
        _, nearest = self.tree.query(points, count)
        points = np.ascontiguousarray(points)
        estimates = candidate_distances(
            points, self.triangles, np.asarray(nearest, dtype=np.int64).reshape(len(points), -1))
        order = np.argsort(-estimates)
        return float(largest_exact_distance(points[order], estimates[order], self.triangles))


def _sample_triangles(triangles: np.ndarray, spacing: float) -> np.ndarray:
    """Points (P, 3) on triangles (T, 3, 3), at most about `spacing` [m] apart.

    Each triangle a, b, c (a opposite its shortest edge) is swept by segments parallel
    to bc, a + u (b - a + w (c - b)) for u, w in [0, 1], `spacing` apart along ab and
    along each segment: slivers get few points.
    """
    samples = []
    for corners in triangles:
        edges = np.linalg.norm(corners - np.roll(corners, -1, axis=0), axis=1)  # ab, bc, ca
        a, b, c = np.roll(corners, -((int(np.argmin(edges)) + 2) % 3), axis=0)
        sweep = np.linspace(0.0, 1.0, int(np.ceil(max(edges) / spacing)) + 1)
        steps = np.ceil(sweep * min(edges) / spacing).astype(np.int64)  # per segment
        u = np.repeat(sweep, steps + 1)
        first = np.repeat(np.cumsum(steps + 1) - (steps + 1), steps + 1)
        w = (np.arange(len(u)) - first) / np.repeat(np.maximum(steps, 1), steps + 1)
        samples.append(a + u[:, None] * ((b - a) + w[:, None] * (c - b)))
    return np.concatenate(samples)


@numba.njit(cache=True, inline='always')
def _triangle_distance2(px: float, py: float, pz: float, triangle: np.ndarray) -> float:
    """Squared distance [m²] from point (px, py, pz) to a triangle (3, 3), without allocating.

    By the triangle's point nearest it (Ericson, Real-Time Collision Detection, 5.1.5).
    """
    ax, ay, az = triangle[0, 0], triangle[0, 1], triangle[0, 2]
    abx, aby, abz = triangle[1, 0] - ax, triangle[1, 1] - ay, triangle[1, 2] - az
    acx, acy, acz = triangle[2, 0] - ax, triangle[2, 1] - ay, triangle[2, 2] - az
    apx, apy, apz = px - ax, py - ay, pz - az
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    s, t = 0.0, 0.0  # the nearest point is a + s ab + t ac
    if d1 <= 0.0 and d2 <= 0.0:
        pass
    else:
        d3 = d1 - (abx * abx + aby * aby + abz * abz)  # ab · (p - b)
        d4 = d2 - (acx * abx + acy * aby + acz * abz)  # ac · (p - b)
        d5 = d1 - (abx * acx + aby * acy + abz * acz)  # ab · (p - c)
        d6 = d2 - (acx * acx + acy * acy + acz * acz)  # ac · (p - c)
        vc = d1 * d4 - d3 * d2
        vb = d5 * d2 - d1 * d6
        va = d3 * d6 - d5 * d4
        if d3 >= 0.0 and d4 <= d3:
            s = 1.0
        elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
            s = d1 / (d1 - d3)
        elif d6 >= 0.0 and d5 <= d6:
            t = 1.0
        elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
            t = d2 / (d2 - d6)
        elif va <= 0.0 and d4 - d3 >= 0.0 and d5 - d6 >= 0.0:
            t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
            s = 1.0 - t
        else:
            scale = 1.0 / (va + vb + vc)
            s, t = vb * scale, vc * scale
    gx = apx - s * abx - t * acx
    gy = apy - s * aby - t * acy
    gz = apz - s * abz - t * acz
    return gx * gx + gy * gy + gz * gz


@numba.njit(cache=True)
def candidate_distances(points: np.ndarray, triangles: np.ndarray, candidates: np.ndarray,
                        ) -> np.ndarray:
    """Distance (P,) [m] from each point (P, 3) to the nearest of its candidate triangles.

    `triangles` (T, 3, 3); `candidates` (P, C) indices into them.
    """
    out = np.empty(points.shape[0])
    for k in range(points.shape[0]):
        best = np.inf
        for t in candidates[k]:
            best = min(best, _triangle_distance2(points[k, 0], points[k, 1], points[k, 2],
                                                 triangles[t]))
        out[k] = np.sqrt(best)
    return out


@numba.njit(cache=True)
def largest_exact_distance(points: np.ndarray, estimates: np.ndarray, triangles: np.ndarray,
                           ) -> float:
    """Return the largest distance [m] from points (P, 3) to the triangles (T, 3, 3).

    `estimates` (P,), in decreasing order, are at least each point's distance: points are
    measured exactly (every triangle) in that order until an estimate is no larger than
    the largest distance found.
    """
    largest = 0.0
    for k in range(points.shape[0]):
        if estimates[k] <= largest:
            break
        best = estimates[k] ** 2
        for t in range(triangles.shape[0]):
            best = min(best, _triangle_distance2(points[k, 0], points[k, 1], points[k, 2],
                                                 triangles[t]))
        largest = max(largest, np.sqrt(best))
    return largest


@numba.njit(cache=True)
def inside_halfspaces(points: np.ndarray, halfspaces: np.ndarray, tolerance: float,
                      ) -> np.ndarray:
    """(P,) bool: whether n · x + d <= tolerance [m] for each point (P, 3) and every facet.

    `halfspaces` (F, 4) are unit normals n and offsets d. A point is measured facet by
    facet until one leaves it out, with no (P, F) array; NaN is outside.
    """
    out = np.empty(points.shape[0], dtype=np.bool_)
    for k in range(points.shape[0]):
        x, y, z = points[k, 0], points[k, 1], points[k, 2]
        inside = True
        for f in range(halfspaces.shape[0]):
            plane = halfspaces[f]
            if not (x * plane[0] + y * plane[1] + z * plane[2] + plane[3] <= tolerance):
                inside = False
                break
        out[k] = inside
    return out


@numba.njit(cache=True)
def among_points(points: np.ndarray, others: np.ndarray) -> np.ndarray:
    """(P,) bool: whether each point (P, 3) equals one of `others` (Q, 3)."""
    out = np.zeros(points.shape[0], dtype=np.bool_)
    for k in range(points.shape[0]):
        for q in range(others.shape[0]):
            if (points[k, 0] == others[q, 0] and points[k, 1] == others[q, 1]
                    and points[k, 2] == others[q, 2]):
                out[k] = True
                break
    return out
