"""Step 7 and recovery: slice S_F with the failure hyperplane of the locked joint.

When joint i locks at θ_i = v, the arm can only move in H_i = {θ | θ_i = v}. The slice of
the triangulated web with H_i is a graph whose nodes are the points where web edges cross
the level v (and web vertices lying on it) and whose arcs join the nodes that bound one
triangle: a segment between two points of a triangle with θ_i = v lies in the triangle
and in H_i. The recovery path is the shortest path in this graph from the lock
configuration to the web's goal row, an arc of M_g^F. It is collision-free wherever the
web's triangles are (checked in `verification.py`).

Why it exists: the nominal path changes sign against v once (it is monotonic), the
bottom row θ_s and the path to θ_{H_i} sit on one side of v (or on it), so the level
curve leaving the lock point between them can only end on the goal row.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numba
import numpy as np

from ..errors import InputError
from ..model.paths import path_length
from .failure_surface import FailureSurface


@dataclass(frozen=True, eq=False)
class RecoveryPath:
    """How to reach the goal with `joint` locked at `locked_value` [rad].

    `path` (k, n) [rad] runs from the configuration where the joint locked to a goal
    configuration; its component `joint` is `locked_value` throughout. `slip` [rad] is
    how far the joint locked beyond the nominal path's range of it (a brake that slipped
    past a turn of its angle): the path is then S_F's slice at the range's end moved by
    `slip` in that joint, off the certified web, and it ends off the goal row.
    """

    joint: int
    locked_value: float
    path: np.ndarray
    slip: float = 0.0

    @property
    def length(self) -> float:
        """Joint-space length [rad] of the path."""
        return path_length(self.path)


def locate_on_nominal_path(surface: FailureSurface, theta: np.ndarray, joint: int,
                           max_offset: float = 1e-6) -> tuple[int, np.ndarray]:
    """Find the segment w and point (n,) [rad] of the nominal path where joint `joint` = θ_joint.

    Among the nominal segments that reach the locked value, the point nearest θ is taken;
    it must lie within `max_offset` [rad] of θ, or θ is not on the nominal path. A locked
    value up to `max_offset` past a segment's range counts as the segment's nearer end.
    Raises InputError for bad arguments (as `recover`) or a nominal path that is not two
    or more finite points.
    """
    return _locate(surface, _checked_lock(surface, theta, joint, max_offset), joint,
                   max_offset)


def _locate(surface: FailureSurface, theta: np.ndarray, joint: int,
            max_offset: float) -> tuple[int, np.ndarray]:
    """`locate_on_nominal_path` for a lock `_checked_lock` has passed."""
    path = np.ascontiguousarray(surface.nominal_path, dtype=float)
    if len(path) < 2 or not np.all(np.isfinite(path)):
        raise InputError('surface', 'has a nominal path that is not two or more finite points')
    segment, point, gap = _nearest_at_level(path, theta, int(joint), float(max_offset))
    if segment < 0:
        raise InputError('theta', 'the lock configuration is not on the nominal path '
                         f'(joint {joint + 1} is out of its range)')
    if gap > max_offset:
        raise InputError('theta', 'the lock configuration is not on the nominal path '
                         f'({gap:.3g} rad away)')
    return segment, point


def _checked_lock(surface: FailureSurface, theta: np.ndarray, joint: int,
                  max_offset: float) -> np.ndarray:
    """Return θ as n finite angles (C-contiguous); raise InputError for a bad lock."""
    n_joints = surface.paths.shape[-1]
    if isinstance(joint, bool | np.bool_) or not isinstance(joint, int | np.integer) or \
            not 0 <= joint < n_joints:
        raise InputError('joint', f'must be in 0..{n_joints - 1}, got {joint!r}')
    if not (math.isfinite(max_offset) and max_offset >= 0.0):
        raise InputError('max_offset', f'must be a finite distance >= 0 [rad], got {max_offset}')
    theta = np.ascontiguousarray(theta, dtype=float)
    if theta.shape != (n_joints,) or not np.all(np.isfinite(theta)):
        raise InputError('theta', f'must be {n_joints} finite angles')
    return theta


@numba.njit(cache=True)
def _nearest_at_level(path, theta, joint, max_offset):
    """`locate_on_nominal_path` on the path (W+1, n): (segment or -1, point (n,), its gap).

    -1 when no segment reaches the level; the gap [rad] is the point's distance from θ.
    A segment whose range of the joint misses θ's angle by at most `max_offset` reaches
    it at its nearer end: a brake that holds the joint up to that far past a turn of its
    angle is located there, not at a far crossing of the angle.
    """
    n = path.shape[1]
    best, best_gap = -1, np.inf
    best_point = np.empty(n)
    point = np.empty(n)
    for w in range(path.shape[0] - 1):
        a, b = path[w], path[w + 1]
        level = min(max(theta[joint], min(a[joint], b[joint])), max(a[joint], b[joint]))
        if abs(level - theta[joint]) > max_offset:
            continue
        rise = b[joint] - a[joint]
        along, square = 0.0, 0.0
        for k in range(n):
            step = b[k] - a[k]
            along += (theta[k] - a[k]) * step
            square += step * step
        # A segment along which the joint moves is cut at the level; one along which it
        # hardly moves (or a repeated point) is projected onto: cutting it would divide
        # rounding errors by a tiny rise.
        if rise != 0.0 and abs(rise) >= 1e-3 * np.sqrt(square):
            t = (level - a[joint]) / rise
        else:
            t = min(max(along / max(square, 1e-300), 0.0), 1.0)
        for k in range(n):
            point[k] = a[k] + t * (b[k] - a[k])
        point[joint] = level
        gap2 = 0.0
        for k in range(n):
            gap2 += (point[k] - theta[k]) ** 2
        gap = np.sqrt(gap2)
        if gap < best_gap or best < 0:
            best, best_gap = w, gap
            best_point[:] = point
    return best, best_point, best_gap


def recover(surface: FailureSurface, theta: np.ndarray, joint: int,
            max_offset: float = 1e-6) -> RecoveryPath | None:
    """Recovery path from θ (n,) [rad] on the nominal path with joint `joint` locked there.

    Returns None when the slice of S_F does not connect θ to M_g^F (a verified plan never
    does that). Raises InputError for a joint that is not an index in range, θ off the
    path by more than `max_offset` [rad] (finite, >= 0) or a web point that is not finite.
    """
    theta = _checked_lock(surface, theta, joint, max_offset)
    if not surface.is_finite:
        raise InputError('surface', 'has a point that is not finite')
    segment, start = _locate(surface, theta, joint, max_offset)
    # S_F is sliced at the locked value moved into the path's range (by at most max_offset).
    slice_level = float(start[joint])
    point_of, segment_of = surface.vertex_ids, surface.edge_ids
    n_points = surface.point_count
    source = n_points + surface.segment_count  # the start's node id, above all others
    vertices = np.ascontiguousarray(surface.vertices, dtype=float)  # one compiled signature
    values = np.ascontiguousarray(vertices[:, joint])
    top = surface.goal_vertices
    goal = np.unique(np.concatenate([point_of[top[values[top] == slice_level]],
                                     n_points + segment_of[surface.goal_chords]]))
    beside_start = np.array([t for t in surface.triangles_beside_path_edge(surface.nominal,
                                                                           segment)
                             if surface.live_triangles[t]], dtype=np.int64)
    route = _slice_route(values, vertices, surface.triangles,
                         surface.triangle_edges, surface.edges, point_of, segment_of,
                         surface.live_triangles, beside_start, slice_level, joint, start,
                         n_points, source, goal)
    if len(route) == 0:
        return None
    path = np.vstack([theta[None, :], route])
    level = float(theta[joint])
    path[:, joint] = level
    return RecoveryPath(joint, level, path, level - slice_level)


# One piece, as a kernel: the slice's nodes, arcs and Dijkstra share per-call scratch arrays.
@numba.njit(cache=True)
def _slice_route(values, vertices, triangles, triangle_edges, edges, point_of, segment_of,
                 live, beside_start, level, joint, start, n_points, source, goal):
    """Points (k, n) of a shortest path in S_F ∩ {θ_joint = level} from `start` to the goal row.

    Empty when the slice does not join them. The slice is a graph: its nodes are the web's
    points on the level (ids `point_of`) and strict crossings of its segments (ids
    n_points + `segment_of`), and the start (id `source`, the largest); vertices with
    equal coordinates are one point, and so are segments joining equal points. Vertices
    with θ_joint >= level count as above; a triangle whose corners are all strictly above
    or all below holds no node, and the live triangles beside the start's nominal segment
    hold the start. Arcs join the nodes of a triangle, weighted by their distance; the
    path ends at the nearest node whose id is in `goal` (sorted): the goal row's points on
    the level and the strict crossings of its chords. Only the nodes of the triangles the
    level crosses are numbered, so that a call costs little more than a pass over the
    triangles however large the web.
    """
    n = vertices.shape[1]
    beside = np.zeros(triangles.shape[0], dtype=np.bool_)
    for t in beside_start:
        beside[t] = True
    crossing = np.empty(triangles.shape[0], dtype=np.int64)
    count = 0
    for t in range(triangles.shape[0]):
        a, b, c = values[triangles[t, 0]], values[triangles[t, 1]], values[triangles[t, 2]]
        if beside[t] or (live[t] and min(a, b, c) <= level <= max(a, b, c)):
            crossing[count] = t
            count += 1
    # Up to 7 nodes per triangle: its corners on the level, the crossing of each side
    # (its upper end if that lies on the level), the start.
    slots = np.full((count, 7), -1, dtype=np.int64)
    coordinates = np.empty((count, 7, n))
    for c in range(count):
        t = crossing[c]
        for k in range(3):
            corner = triangles[t, k]
            if values[corner] == level:
                slots[c, k] = point_of[corner]
                coordinates[c, k] = vertices[corner]
            side = triangle_edges[t, k]
            high, low = edges[side, 0], edges[side, 1]
            if values[high] < level:
                high, low = low, high
            if values[low] >= level or values[high] < level:
                continue  # both ends on one side
            if values[high] == level:
                slots[c, 3 + k] = point_of[high]
                coordinates[c, 3 + k] = vertices[high]
            else:
                slots[c, 3 + k] = n_points + segment_of[side]
                f = (level - values[low]) / (values[high] - values[low])
                coordinates[c, 3 + k] = vertices[low] + f * (vertices[high] - vertices[low])
        if beside[t]:
            slots[c, 6] = source
            coordinates[c, 6] = start

    # Number the nodes in use 0..N-1 in the order of their ids (the start last).
    used = slots.ravel()
    ids = np.unique(np.append(used[used >= 0], source))
    local = np.searchsorted(ids, slots)  # meaningless where a slot is empty (-1)
    points = np.empty((len(ids), n))
    points[len(ids) - 1] = start
    # Arcs join every two distinct nodes of a triangle; as lists of neighbours (CSR).
    tails = np.empty(count * 42, dtype=np.int64)
    heads = np.empty(count * 42, dtype=np.int64)
    arcs = 0
    for c in range(count):
        for k in range(7):
            if slots[c, k] < 0:
                continue
            points[local[c, k]] = coordinates[c, k]
            for q in range(7):
                if q != k and slots[c, q] >= 0 and slots[c, q] != slots[c, k]:
                    tails[arcs] = local[c, k]
                    heads[arcs] = local[c, q]
                    arcs += 1
    points[:, joint] = level
    first = np.zeros(len(ids) + 1, dtype=np.int64)
    for e in range(arcs):
        first[tails[e] + 1] += 1
    first = np.cumsum(first)
    neighbours = np.empty(arcs, dtype=np.int64)
    filled = first[:-1].copy()
    for e in range(arcs):
        neighbours[filled[tails[e]]] = heads[e]
        filled[tails[e]] += 1

    # Dijkstra from the start, until it settles a goal node: the nearest, and among
    # equally near ones the first in id order (the queue breaks ties by node).
    at = np.minimum(np.searchsorted(goal, ids), max(len(goal) - 1, 0))
    is_goal = np.zeros(len(ids), dtype=np.bool_)
    if len(goal):
        is_goal[:] = goal[at] == ids
    origin = len(ids) - 1
    distance = np.full(len(ids), np.inf)
    previous = np.full(len(ids), -1, dtype=np.int64)
    distance[origin] = 0.0
    queue = [(0.0, origin)]
    best = -1
    while len(queue):
        reached, node = heapq.heappop(queue)
        if reached > distance[node]:
            continue
        if is_goal[node]:
            best = node
            break
        for e in range(first[node], first[node + 1]):
            other = neighbours[e]
            gap2 = 0.0
            for a in range(n):
                gap2 += (points[other, a] - points[node, a]) ** 2
            candidate = reached + np.sqrt(gap2) + 1e-12
            if candidate < distance[other]:
                distance[other] = candidate
                previous[other] = node
                heapq.heappush(queue, (candidate, other))
    if best < 0:
        return np.empty((0, n))
    length = 1
    node = best
    while node != origin:
        node = previous[node]
        length += 1
    route = np.empty((length, n))
    node = best
    for k in range(length - 1, -1, -1):
        route[k] = points[node]
        node = previous[node]
    return route
