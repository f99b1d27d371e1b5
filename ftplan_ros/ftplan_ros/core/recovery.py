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

from dataclasses import dataclass
from itertools import combinations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import dijkstra

from .errors import InputError
from .failure_surface import FailureSurface
from .paths import path_length

# Each triangle offers up to 7 node slots: 3 vertices, 3 edge crossings and the start.
_SLOT_PAIRS = np.array(list(combinations(range(7), 2)))


@dataclass(frozen=True, eq=False)
class RecoveryPath:
    """How to reach the goal with `joint` locked at `locked_value` [rad].

    `path` (k, n) [rad] runs from the configuration where the joint locked to a goal
    configuration; its component `joint` is `locked_value` throughout.
    """

    joint: int
    locked_value: float
    path: np.ndarray

    @property
    def length(self) -> float:
        """Joint-space length [rad] of the path."""
        return path_length(self.path)


def locate_on_nominal_path(surface: FailureSurface, theta: np.ndarray, joint: int,
                           max_offset: float = 1e-6) -> tuple[int, np.ndarray]:
    """Find the segment w and point (n,) [rad] of the nominal path where joint `joint` = θ_joint.

    Among the nominal segments that reach the locked value, the point nearest θ is taken;
    it must lie within `max_offset` [rad] of θ, or θ is not on the nominal path. A locked
    value up to `max_offset` past either end of the path's range counts as that end.
    """
    path = surface.nominal_path
    level = float(np.clip(theta[joint], path[:, joint].min(), path[:, joint].max()))
    if abs(level - theta[joint]) > max_offset:
        level = theta[joint]  # out of range: reported below
    a, b = path[:-1], path[1:]
    reaches = (np.minimum(a[:, joint], b[:, joint]) <= level) & \
        (level <= np.maximum(a[:, joint], b[:, joint]))
    if not reaches.any():
        raise InputError('theta', 'the lock configuration is not on the nominal path '
                         f'(joint {joint + 1} is out of its range)')
    a, b, segments = a[reaches], b[reaches], np.flatnonzero(reaches)
    rise = b[:, joint] - a[:, joint]
    direction = b - a
    along = np.einsum('sn,sn->s', theta - a, direction) / np.maximum(
        np.einsum('sn,sn->s', direction, direction), 1e-300)
    # A segment along which the joint moves is cut at the level; one along which it hardly
    # moves is projected onto (cutting it would divide rounding errors by a tiny rise).
    steep = np.abs(rise) >= 1e-3 * np.linalg.norm(direction, axis=1)
    t = np.where(steep, (level - a[:, joint]) / np.where(steep, rise, 1.0),
                 np.clip(along, 0.0, 1.0))
    points = a + t[:, None] * direction
    points[:, joint] = level
    gaps = np.linalg.norm(points - theta, axis=1)
    best = int(np.argmin(gaps))
    if gaps[best] > max_offset:
        raise InputError('theta', 'the lock configuration is not on the nominal path '
                         f'({gaps[best]:.3g} rad away)')
    return int(segments[best]), points[best]


def recover(surface: FailureSurface, theta: np.ndarray, joint: int,
            max_offset: float = 1e-6) -> RecoveryPath | None:
    """Recovery path from θ (n,) [rad] on the nominal path with joint `joint` locked there.

    Returns None when the slice of S_F does not connect θ to M_g^F (a verified plan never
    does that). Raises InputError for a joint index out of range or θ off the path.
    """
    theta = np.asarray(theta, dtype=float)
    n_joints = surface.paths.shape[-1]
    if not 0 <= joint < n_joints:
        raise InputError('joint', f'must be in 0..{n_joints - 1}, got {joint}')
    if theta.shape != (n_joints,) or not np.all(np.isfinite(theta)):
        raise InputError('theta', f'must be {n_joints} finite angles')
    segment, start = locate_on_nominal_path(surface, theta, joint, max_offset)
    # S_F is sliced at the locked value moved into the path's range (by at most max_offset).
    points, graph, targets = _slice_graph(surface, joint, float(start[joint]), segment, start)
    source = len(points) - 1
    distance, predecessor = dijkstra(graph, directed=False, indices=source,
                                     return_predecessors=True)
    reachable = targets[np.isfinite(distance[targets])]
    if len(reachable) == 0:
        return None
    node = reachable[np.argmin(distance[reachable])]
    route = [node]
    while route[-1] != source:
        route.append(predecessor[route[-1]])
    path = np.vstack([theta[None, :], points[route[::-1]]])
    level = float(theta[joint])
    path[:, joint] = level
    return RecoveryPath(joint, level, path)


def _slice_graph(surface: FailureSurface, joint: int, level: float, segment: int,
                 start: np.ndarray) -> tuple[np.ndarray, csr_matrix, np.ndarray]:
    """Nodes (N, n), weighted arcs and goal-row node ids of S_F ∩ {θ_joint = level}.

    Nodes are the web's points on the level and strict crossings of its segments, and the
    start point comes last; vertices with equal coordinates are one point, and so are
    segments joining equal points (`FailureSurface.vertex_ids`, `edge_ids`). Vertices with
    θ_joint >= level count as above; a triangle whose corners are all strictly above or
    all below holds no node. Triangles of cut strips are not part of S_F.
    """
    vertices = surface.vertices
    point_of = surface.vertex_ids
    n_points_ = int(point_of.max()) + 1
    segment_of = surface.edge_ids
    edges = surface.edges
    values = vertices[:, joint]
    above = values >= level
    on_level = values == level
    live = surface.live_triangles

    lowest, highest = surface.triangle_ranges
    crossing = live & (lowest[:, joint] <= level) & (highest[:, joint] >= level)
    beside_start = [t for t in surface.triangles_beside_path_edge(surface.nominal, segment)
                    if live[t]]
    crossing[beside_start] = True
    touches_start = np.zeros(len(crossing), dtype=bool)
    touches_start[beside_start] = True
    touches_start = touches_start[crossing]
    triangles = surface.triangles[crossing]
    triangle_edges = surface.triangle_edges[crossing]

    # Crossing node of each edge used: the upper end if it lies on the level, else a new point.
    used = np.unique(triangle_edges)
    lower, upper = edges[used, 0], edges[used, 1]
    mixed = above[lower] != above[upper]
    high = np.where(above[lower], lower, upper)
    low = np.where(above[lower], upper, lower)
    node = np.full(len(used), -1)
    node[mixed & on_level[high]] = point_of[high[mixed & on_level[high]]]
    strict = mixed & ~on_level[high]
    node[strict] = n_points_ + segment_of[used[strict]]

    points = np.full((n_points_ + int(segment_of.max()) + 2, vertices.shape[1]), np.nan)
    points[point_of] = vertices
    lo, hi = vertices[low[strict]], vertices[high[strict]]
    t = (level - lo[:, joint]) / (hi[:, joint] - lo[:, joint])
    points[node[strict]] = lo + t[:, None] * (hi - lo)
    source = len(points) - 1
    points[source] = start
    points[:, joint] = level

    edge_node = node[np.searchsorted(used, triangle_edges)]
    slots = np.concatenate([np.where(on_level[triangles], point_of[triangles], -1), edge_node,
                            np.where(touches_start, source, -1)[:, None]], axis=1)
    u = slots[:, _SLOT_PAIRS[:, 0]].ravel()
    v = slots[:, _SLOT_PAIRS[:, 1]].ravel()
    keep = (u >= 0) & (v >= 0) & (u != v)
    u, v = np.minimum(u[keep], v[keep]), np.maximum(u[keep], v[keep])
    pair_keys = np.unique(u * len(points) + v)  # each arc once, though two triangles share it
    u, v = pair_keys // len(points), pair_keys % len(points)
    # Number the nodes in use 0..N-1 (the start last) so the graph stays small.
    ids, local = np.unique(np.concatenate([u, v, [source]]), return_inverse=True)
    weights = np.linalg.norm(points[u] - points[v], axis=1) + 1e-12
    graph = csr_matrix((weights, (local[:len(u)], local[len(u):-1])), shape=(len(ids), len(ids)))

    n_paths, n_waypoints = surface.paths.shape[:2]
    goal_row = np.zeros(len(points), dtype=bool)
    top = np.arange(n_paths) * n_waypoints + n_waypoints - 1
    goal_row[point_of[top[on_level[top]]]] = True
    strips = np.flatnonzero(~surface.cuts)
    top_rungs = surface.rung_edge(strips, n_waypoints - 1)
    goal_row[n_points_ + segment_of[top_rungs]] = True  # strict crossings on the goal row's chords
    return points[ids], graph, np.flatnonzero(goal_row[ids])
