"""Part 3 of the self-check on any web: every lock's slice reaches the goal row.

When joint i locks at a point p of the nominal path, `recover` walks the slice of S_F
with the failure plane {θ_i = p_i}: the graph whose nodes are the web's points on that
level and the strict crossings of its segments, joined when they bound one triangle
(each triangle meets the plane in a convex set holding them all), with equal points
counted once (`FailureSurface.vertex_ids`, `edge_ids`). A recovery exists exactly when
p's node and a node of the goal row (a top vertex on the level, or a crossing of a live
top chord) are connected.

As the level v moves between two consecutive values that web vertices take in θ_i, no
vertex is on the level and every segment keeps the side of v it crosses from: the
graph, and which nominal segments cross, stay the same. So the property holds for every
point of the nominal path once it holds

* at each vertex value (for the nominal vertices on that level and the nominal segments
  crossing it), and
* at one level strictly between each two consecutive vertex values (for the nominal
  segments crossing it).

A flat nominal segment lies in its level's plane and is joined to its ends there. This
module checks exactly those finitely many levels, with a union-find per level over the
triangles that span it (swept in order of their lowest corner); degenerate triangles,
repeated points and levels through vertices are handled like any other, as `recover`
does.
"""

from __future__ import annotations

import numba
import numpy as np

from .failure_surface import NOT_FINITE, FailureSurface


def slice_problem(surface: FailureSurface, joints) -> str:
    """Say where a lock of a joint in `joints` has no slice to the goal row, or ''."""
    if not surface.is_finite:  # comparisons with NaN would join nothing and find nothing
        return NOT_FINITE
    tables = _web_tables(surface)
    for joint in joints:
        level, where = _check_joint(surface.vertices[:, joint], *tables)
        if where >= 0:
            kind = 'waypoint' if where < tables[-2].shape[0] else 'segment'
            index = where if kind == 'waypoint' else where - tables[-2].shape[0]
            return (f'the slice of S_F at θ_{joint + 1} = {level:.6f} rad does not join '
                    f'nominal {kind} {index} to the goal row')
    return ''


def _web_tables(surface: FailureSurface) -> tuple:
    """Distinct points and segments of the live triangles, goal marks, nominal sources."""
    point_of = surface.vertex_ids
    segment_of = surface.edge_ids
    n_points = surface.point_count
    live = surface.live_triangles
    corners = point_of[surface.triangles[live]]
    sides = segment_of[surface.triangle_edges[live]]
    # One row per distinct triangle.
    keys = np.sort(corners, axis=1)
    _, first = np.unique(keys[:, 0] * n_points * n_points + keys[:, 1] * n_points + keys[:, 2],
                         return_index=True)
    corners, sides = corners[first], sides[first]
    segment_ends = np.zeros((surface.segment_count, 2), dtype=np.int64)
    segment_ends[segment_of] = point_of[surface.edges]
    n_waypoints = surface.paths.shape[1]
    goal_point = np.zeros(n_points, dtype=np.bool_)
    goal_point[point_of[surface.goal_vertices]] = True
    goal_segment = np.zeros(len(segment_ends), dtype=np.bool_)
    goal_segment[segment_of[surface.goal_chords]] = True
    nominal = surface.nominal * n_waypoints + np.arange(n_waypoints)
    nominal_points = point_of[nominal]
    nominal_segments = segment_of[surface.path_edge(surface.nominal, np.arange(n_waypoints - 1))]
    # The vertex values index points: take one vertex per point.
    representative = np.zeros(n_points, dtype=np.int64)
    representative[point_of] = np.arange(len(point_of))
    return (representative, corners.astype(np.int64), sides.astype(np.int64), segment_ends,
            goal_point, goal_segment, nominal_points.astype(np.int64),
            nominal_segments.astype(np.int64))


def _check_joint(values, representative, corners, sides, segment_ends, goal_point,
                 goal_segment, nominal_points, nominal_segments) -> tuple[float, int]:
    """Return (level, index) of the first unrecoverable nominal waypoint or segment, or -1."""
    phi = np.ascontiguousarray(values[representative], dtype=float)
    used = np.unique(np.concatenate([corners.ravel(), nominal_points]))
    critical = np.unique(phi[used])
    span = phi[nominal_points]  # levels no nominal point takes need no check
    critical = critical[(critical >= span.min()) & (critical <= span.max())]
    levels = np.empty(2 * len(critical) - 1)
    levels[0::2] = critical
    levels[1::2] = 0.5 * (critical[1:] + critical[:-1])
    return _sweep(phi, corners, sides, segment_ends, goal_point, goal_segment,
                  nominal_points, nominal_segments, levels)


@numba.njit(cache=True)
def _find(parent, a):
    root = a
    while parent[root] != root:
        root = parent[root]
    while parent[a] != root:
        parent[a], a = root, parent[a]
    return root


# One piece, as a kernel: one sweep of the levels keeps the union-find and active triangles.
@numba.njit(cache=True)
def _sweep(phi, corners, sides, segment_ends, goal_point, goal_segment, nominal_points,
           nominal_segments, levels):
    """Union-find per level over the triangles that span it (see the module docstring)."""
    n_points = phi.shape[0]
    n_nodes = n_points + segment_ends.shape[0]
    parent = np.arange(n_nodes)
    good = np.zeros(n_nodes, dtype=np.bool_)
    touched = np.empty(n_nodes, dtype=np.int64)
    is_touched = np.zeros(n_nodes, dtype=np.bool_)
    count = corners.shape[0]
    low = np.empty(count)
    high = np.empty(count)
    for t in range(count):
        a, b, c = phi[corners[t, 0]], phi[corners[t, 1]], phi[corners[t, 2]]
        low[t] = min(a, min(b, c))
        high[t] = max(a, max(b, c))
    order = np.argsort(low)
    active = np.empty(count, dtype=np.int64)
    n_active = 0
    added = 0
    nodes = np.empty(6, dtype=np.int64)
    for level_index in range(levels.shape[0]):
        level = levels[level_index]
        while added < count and low[order[added]] <= level:
            active[n_active] = order[added]
            n_active += 1
            added += 1
        kept = 0
        n_touched = 0
        for slot in range(n_active):
            t = active[slot]
            if high[t] < level:
                continue
            active[kept] = t
            kept += 1
            k = 0
            for c in range(3):
                p = corners[t, c]
                if phi[p] == level:
                    nodes[k] = p
                    k += 1
            for c in range(3):
                s = sides[t, c]
                u, v = phi[segment_ends[s, 0]], phi[segment_ends[s, 1]]
                if (u < level < v) or (v < level < u):
                    nodes[k] = n_points + s
                    k += 1
            for m in range(k):
                if not is_touched[nodes[m]]:
                    is_touched[nodes[m]] = True
                    touched[n_touched] = nodes[m]
                    n_touched += 1
                if (nodes[m] < n_points and goal_point[nodes[m]]) or \
                        (nodes[m] >= n_points and goal_segment[nodes[m] - n_points]):
                    good[nodes[m]] = True
            for m in range(1, k):
                ra, rb = _find(parent, nodes[0]), _find(parent, nodes[m])
                if ra != rb:
                    parent[rb] = ra
                    good[ra] = good[ra] or good[rb]
        n_active = kept
        # A root is good when any node of its component is a goal node.
        for m in range(n_touched):
            node = touched[m]
            if good[node]:
                good[_find(parent, node)] = True
        failed = -1
        for w in range(nominal_points.shape[0]):
            p = nominal_points[w]
            if phi[p] == level and not good[_find(parent, p)]:
                failed = w
                break
        if failed < 0:
            for w in range(nominal_segments.shape[0]):
                s = nominal_segments[w]
                u, v = phi[segment_ends[s, 0]], phi[segment_ends[s, 1]]
                if ((u < level < v) or (v < level < u)) and \
                        not good[_find(parent, n_points + s)]:
                    failed = nominal_points.shape[0] + w
                    break
        for m in range(n_touched):
            parent[touched[m]] = touched[m]
            good[touched[m]] = False
            is_touched[touched[m]] = False
        for w in range(nominal_points.shape[0]):
            parent[nominal_points[w]] = nominal_points[w]
        if failed >= 0:
            return level, failed
    return 0.0, -1
