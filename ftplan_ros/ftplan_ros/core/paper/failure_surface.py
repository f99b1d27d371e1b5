"""Steps 5 and 6 of the paper: the failure surface S_F as a web of joint-space paths.

The web fans out from θ_s: path k runs straight (hence monotonically in every joint) from
θ_s to goal point g_k, and goal points follow each other along an arc of M_g^F, so
adjacent paths are joined by straight rungs at equal waypoint index. Every quad of the
web is split into two triangles; the triangles, as patches of joint space, are S_F.

Among the goal points are the exact failure-plane hits θ_{H_i} of every tolerated joint i:
the path to θ_{H_i} keeps θ_i = θ_s,i exactly. That path, the nominal path (monotonic)
and the bottom row (all θ_s) are what make a recovery path exist for every lock of a
tolerated joint (see `recovery.py`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numba
import numpy as np

from ..model.angles import whole_turns
from .failure_planes import FailurePlaneHit

# What the checks of a web say when `FailureSurface.is_finite` is False.
NOT_FINITE = 'the web has a point that is not finite'


@dataclass(frozen=True, eq=False)
class FailureSurface:
    """S_F: `paths` (K, W+1, n) [rad], path k from θ_s (waypoint 0) to goal point k.

    `nominal` is the index of the path the arm follows; `tolerated` are the joints whose
    lock the surface is built for, and `hit_paths[k]` is the path to the failure-plane
    hit of joint `tolerated[k]`, on which that joint stays at its value in θ_s.
    """

    paths: np.ndarray
    nominal: int
    hit_paths: tuple[int, ...]
    tolerated: tuple[int, ...]

    def __post_init__(self):
        # The cached properties (ids, counts, finiteness) describe these points, so the
        # surface holds them read-only: a read-only view of floats, the caller's array as is.
        paths = np.asarray(self.paths, dtype=float).view()
        paths.flags.writeable = False
        object.__setattr__(self, 'paths', paths)

    @property
    def theta_s(self) -> np.ndarray:
        """The start configuration θ_s (n,) [rad]."""
        return self.paths[0, 0]

    @property
    def goal_points(self) -> np.ndarray:
        """The web's points of M_g^F (K, n) [rad], in order along the goal arc."""
        return self.paths[:, -1]

    @property
    def goal_vertices(self) -> np.ndarray:
        """(K,) indices into `vertices` of the goal points (each path's last waypoint)."""
        n_paths, n_points = self.paths.shape[:2]
        return np.arange(n_paths) * n_points + n_points - 1

    @property
    def goal_chords(self) -> np.ndarray:
        """Indices into `edges` of the goal row's chords: the top rungs of S_F's strips."""
        return self.rung_edge(np.flatnonzero(~self.cuts), self.paths.shape[1] - 1)

    @property
    def nominal_path(self) -> np.ndarray:
        """The nominal joint path (W+1, n) [rad] from θ_s to a goal configuration."""
        return self.paths[self.nominal]

    @property
    def vertices(self) -> np.ndarray:
        """All web points (K·(W+1), n) [rad]; vertex k·(W+1) + w is waypoint w of path k."""
        return self.paths.reshape(-1, self.paths.shape[-1])

    @cached_property
    def triangles(self) -> np.ndarray:
        """(T, 3) vertex indices: each quad (k, w)-(k+1, w+1) as two triangles."""
        n_paths, n_points = self.paths.shape[:2]
        k, w = np.meshgrid(np.arange(n_paths - 1), np.arange(n_points - 1), indexing='ij')
        v00 = (k * n_points + w).ravel()
        v10, v01 = v00 + n_points, v00 + 1
        v11 = v10 + 1
        return np.concatenate([np.stack([v00, v10, v11], axis=1),
                               np.stack([v00, v11, v01], axis=1)])

    @cached_property
    def edges(self) -> np.ndarray:
        """(E, 2) vertex-index pairs, lower first: path edges, then rungs, then diagonals.

        Path edge (k, w) joins waypoints w, w+1 of path k; rung (k, w) joins path k and
        k+1 at waypoint w; diagonal (k, w) joins (k, w) and (k+1, w+1).
        """
        n_paths, n_points = self.paths.shape[:2]
        vertex = np.arange(n_paths * n_points).reshape(n_paths, n_points)
        along = np.stack([vertex[:, :-1].ravel(), vertex[:, 1:].ravel()], axis=1)
        rungs = np.stack([vertex[:-1, :].ravel(), vertex[1:, :].ravel()], axis=1)
        diagonals = np.stack([vertex[:-1, :-1].ravel(), vertex[1:, 1:].ravel()], axis=1)
        return np.concatenate([along, rungs, diagonals])

    def path_edge(self, k: np.ndarray | int, w: np.ndarray | int) -> np.ndarray | int:
        """Index into `edges` of the edge from waypoint w to w+1 of path k."""
        return k * (self.paths.shape[1] - 1) + w

    def rung_edge(self, k: np.ndarray | int, w: np.ndarray | int) -> np.ndarray | int:
        """Index into `edges` of the rung from path k to path k+1 at waypoint w."""
        n_paths, n_points = self.paths.shape[:2]
        return n_paths * (n_points - 1) + k * n_points + w

    def diagonal_edge(self, k: np.ndarray | int, w: np.ndarray | int) -> np.ndarray | int:
        """Index into `edges` of the diagonal from (k, w) to (k+1, w+1)."""
        n_paths, n_points = self.paths.shape[:2]
        return n_paths * (n_points - 1) + (n_paths - 1) * n_points + k * (n_points - 1) + w

    def triangles_beside_path_edge(self, k: int, w: int) -> list[int]:
        """List the (one or two) triangles that have path k's edge (w, w+1) as a side."""
        n_paths, n_points = self.paths.shape[:2]
        quads = (n_paths - 1) * (n_points - 1)
        beside = []
        if k >= 1:  # the lower triangle of quad (k-1, w) has it as its side v1v2
            beside.append((k - 1) * (n_points - 1) + w)
        if k <= n_paths - 2:  # the upper triangle of quad (k, w) has it as its side v2v0
            beside.append(quads + k * (n_points - 1) + w)
        return beside

    @cached_property
    def triangle_edges(self) -> np.ndarray:
        """(T, 3) indices into `edges` of each triangle's edges (v0v1, v1v2, v2v0)."""
        n_paths, n_points = self.paths.shape[:2]
        k, w = np.meshgrid(np.arange(n_paths - 1), np.arange(n_points - 1), indexing='ij')
        k, w = k.ravel(), w.ravel()
        lower = np.stack([self.rung_edge(k, w), self.path_edge(k + 1, w),
                          self.diagonal_edge(k, w)], axis=1)
        upper = np.stack([self.diagonal_edge(k, w), self.rung_edge(k, w + 1),
                          self.path_edge(k, w)], axis=1)
        return np.concatenate([lower, upper])

    @cached_property
    def cuts(self) -> np.ndarray:
        """(K-1,) bool: True where no quads join path k to path k+1.

        A path repeated exactly (path k equal to path k-1) closes a sheet: the web goes on
        from path k+1 as a new sheet, joined to the others only where they share points
        (`vertex_ids`). The paper's fan has one sheet.
        """
        paths = self.paths
        cut = np.zeros(max(len(paths) - 1, 0), dtype=bool)
        if len(paths) >= 3:
            cut[1:] = np.all(paths[1:-1] == paths[:-2], axis=(1, 2))
        return cut

    @cached_property
    def live_triangles(self) -> np.ndarray:
        """(T,) bool: the triangles of S_F (those of quads between cut paths are not)."""
        n_points = self.paths.shape[1]
        quads = np.repeat(~self.cuts, n_points - 1)
        return np.concatenate([quads, quads])

    @cached_property
    def vertex_ids(self) -> np.ndarray:
        """(V,) one number per distinct point: vertices with equal coordinates are one point.

        Points are numbered in lexicographic order of their coordinates.
        """
        vertices = self.vertices
        # Sorted by joint 1 alone, only the runs of vertices with equal joint 1 need the
        # other joints: a web has few (θ_s, padding, a joint held still), and sorting them
        # apart is far cheaper than sorting every vertex by every joint.
        order = np.argsort(vertices[:, 0], kind='stable')
        first = vertices[order, 0]
        tied = np.zeros(len(order), dtype=bool)
        tied[1:] = (first[1:] == first[:-1]) | (np.isnan(first[1:]) & np.isnan(first[:-1]))
        tied[:-1] |= tied[1:]
        runs = order[tied]
        order[tied] = runs[np.lexsort(vertices[runs].T[::-1])]
        ordered = vertices[order]
        fresh = np.concatenate([[True], np.any(ordered[1:] != ordered[:-1], axis=1)])
        ids = np.empty(len(vertices), dtype=np.int64)
        ids[order] = np.cumsum(fresh) - 1
        return ids

    @cached_property
    def point_count(self) -> int:
        """Number of distinct points: `vertex_ids` are 0..point_count - 1."""
        return int(self.vertex_ids.max(initial=-1)) + 1

    @cached_property
    def shared_points(self) -> np.ndarray:
        """(P,) bool, by point id (`vertex_ids`): whether several vertices share the point."""
        return np.bincount(self.vertex_ids) > 1

    @cached_property
    def segment_count(self) -> int:
        """Number of distinct segments: `edge_ids` are 0..segment_count - 1."""
        return int(self.edge_ids.max(initial=-1)) + 1

    @cached_property
    def is_finite(self) -> bool:
        """Whether every point of the web is finite."""
        return bool(np.isfinite(self.paths).all())

    @cached_property
    def edge_ids(self) -> np.ndarray:
        """(E,) one number per distinct segment of `edges` (by the points it joins).

        Segments are numbered from 0 without gaps: first those of edges no other edge can
        repeat, in the order of the edges, then the others.
        """
        ids = self.vertex_ids
        a, b = ids[self.edges[:, 0]], ids[self.edges[:, 1]]
        # Two edges join the same points only if one of them has an end whose point
        # another vertex shares: the other edges are distinct segments, numbered in turn.
        shared = self.shared_points
        maybe = shared[a] | shared[b]
        segments = np.empty(len(a), dtype=np.int64)
        alone = int(np.count_nonzero(~maybe))
        segments[~maybe] = np.arange(alone)
        count = len(shared)
        _, repeated = np.unique(np.minimum(a[maybe], b[maybe]) * count +
                                np.maximum(a[maybe], b[maybe]), return_inverse=True)
        segments[maybe] = alone + repeated.reshape(-1)
        return segments

    def sheets(self) -> list[tuple[int, int]]:
        """(first, last) path indices of each sheet, in order."""
        ends = np.flatnonzero(self.cuts)
        firsts = np.concatenate([[0], ends + 1])
        lasts = np.concatenate([ends, [len(self.paths) - 1]])
        return list(zip(firsts.tolist(), lasts.tolist(), strict=True))

    def to_dict(self) -> dict:
        """Return the contract's `failure_surface` JSON object (radians)."""
        return {'paths': self.paths.tolist(), 'nominal': self.nominal,
                'hit_paths': list(self.hit_paths), 'tolerated': list(self.tolerated)}


def lift_goal_arc(theta_s: np.ndarray, arc_points: np.ndarray,
                  hits: list[FailurePlaneHit], periodic: np.ndarray,
                  ) -> tuple[np.ndarray, list[FailurePlaneHit]]:
    """Shift the arc (a, n) and its hits by whole turns so hit i has θ_i = θ_s,i exactly.

    Joint i's shift is set by its own hit alone, so every hit can be met at once; joints
    with limits never shift.
    """
    shift = np.zeros(len(theta_s))
    for hit in hits:
        shift[hit.joint] = whole_turns(theta_s[hit.joint], hit.theta[hit.joint],
                                       periodic[hit.joint])
    lifted = []
    for hit in hits:
        theta = hit.theta + shift
        theta[hit.joint] = theta_s[hit.joint]
        lifted.append(FailurePlaneHit(hit.joint, theta, hit.position))
    return arc_points + shift, lifted


def build_failure_surface(theta_s: np.ndarray, arc_points: np.ndarray,
                          hits: list[FailurePlaneHit], window: tuple[float, float],
                          column_spacing: float, waypoint_spacing: float) -> FailureSurface:
    """Build S_F (Steps 5-6): the web from θ_s (n,) to the lifted arc (a, n) within a window.

    `window` (first, last) are positions along the arc (units of arc points) that contain
    every hit; goal points are the arc points inside it, thinned to about
    `column_spacing` [rad] apart, plus the exact hits, one per tolerated joint. Paths get enough
    waypoints that neighbours are at most `waypoint_spacing` [rad] apart in every joint.
    The nominal path is the one to the goal point nearest the window's middle (the
    planner then replaces it by its own choice, the clearest path).
    """
    first, last = window
    inside = np.arange(int(np.ceil(first)), int(np.floor(last)) + 1)
    if len(hits) == 1:
        # One tolerated joint: its hit alone makes a web without a strip, which no slice
        # can walk; its neighbours on the arc make one.
        w = hits[0].position
        near = {int(np.floor(w)), int(np.ceil(w))} - {w} or {int(w) - 1, int(w) + 1}
        inside = np.array(sorted(k for k in near if 0 <= k < len(arc_points)), dtype=int)
    columns = [(float(k), arc_points[k], None)
               for k in _thin(arc_points, inside, column_spacing)]
    columns += [(hit.position, hit.theta, hit.joint) for hit in hits]
    columns.sort(key=lambda column: column[0])
    goals = np.array([theta for _, theta, _ in columns])
    tolerated = tuple(hit.joint for hit in hits)
    hit_paths = tuple(next(slot for slot, column in enumerate(columns) if column[2] == i)
                      for i in tolerated)
    span = np.max(np.abs(goals - theta_s))
    n_steps = max(1, int(np.ceil(span / waypoint_spacing)))
    fractions = np.arange(n_steps + 1) / n_steps
    paths = theta_s + fractions[None, :, None] * (goals - theta_s)[:, None, :]
    paths[:, 0] = theta_s  # exactly, so the bottom row is one point
    middle = 0.5 * (first + last)
    nominal = min(range(len(columns)), key=lambda slot: abs(columns[slot][0] - middle))
    return FailureSurface(paths, nominal, hit_paths, tolerated)


def smallest_windows(starts: np.ndarray, joints: np.ndarray, positions: np.ndarray,
                     n_starts: int, n_joints: int, lap: float = np.inf,
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each start's minimal arc windows holding a hit of every joint, and the hits to use.

    Hits come flat: the start (H,) in [0, n_starts) and the joint (H,) in [0, n_joints)
    each belongs to, and its position (H,) along the arc [arc points], each start's hits
    of a joint in order along the arc. For every start, the classic two-pointer sweep over
    its hits sorted by (position, joint) finds, for each left hit, the nearest right end
    that completes the set of joints. Windows starting at `lap` or beyond are dropped; the
    rest come start by start, shortest first.

    Returns the owners (W,) (start indices), the windows (W, 2) (first, last) [arc points]
    and, per window and joint, the hit inside it nearest its middle (the first of equally
    near ones): indices (W, n_joints) into the flat arrays.
    """
    starts = np.asarray(starts, dtype=np.int64)
    joints = np.asarray(joints, dtype=np.int64)
    positions = np.asarray(positions, dtype=float)
    order = np.lexsort((joints, positions, starts))
    bounds = np.searchsorted(starts[order], np.arange(n_starts + 1))
    return _sweep_windows(order, joints, positions, bounds, n_joints, float(lap))


@numba.njit(cache=True)
def _sweep_windows(order, joints, positions, bounds, n_joints, lap):
    """`smallest_windows` start by start over the hits in sorted `order`."""
    total = order.shape[0]
    owners = np.empty(total, dtype=np.int64)
    windows = np.empty((total, 2))
    chosen = np.empty((total, n_joints), dtype=np.int64)
    found = 0
    counts = np.zeros(n_joints, dtype=np.int64)
    for start in range(bounds.shape[0] - 1):
        lo, hi = bounds[start], bounds[start + 1]
        first_window = found
        counts[:] = 0
        present = 0
        right = lo
        for left in range(lo, hi):
            while present < n_joints and right < hi:
                joint = joints[order[right]]
                if counts[joint] == 0:
                    present += 1
                counts[joint] += 1
                right += 1
            if present < n_joints:
                break
            first, last = positions[order[left]], positions[order[right - 1]]
            fresh = found == first_window or not (windows[found - 1, 0] == first
                                                  and windows[found - 1, 1] == last)
            if fresh and first < lap:  # equal windows come one after another
                owners[found] = start
                windows[found, 0] = first
                windows[found, 1] = last
                found += 1
            joint = joints[order[left]]
            counts[joint] -= 1
            if counts[joint] == 0:
                present -= 1
        mine = windows[first_window:found].copy()
        shortest = np.argsort(mine[:, 1] - mine[:, 0], kind='mergesort')
        windows[first_window:found] = mine[shortest]
        for w in range(first_window, found):
            _nearest_inside(order[lo:hi], joints, positions, windows[w, 0], windows[w, 1],
                            chosen[w])
    return owners[:found], windows[:found], chosen[:found]


def choose_hits(hits: list[list[FailurePlaneHit]], window: tuple[float, float],
                ) -> list[FailurePlaneHit]:
    """One hit per joint inside the window: the one nearest its middle (the first of equals).

    Raises ValueError when the window holds no hit of some joint.
    """
    flat = [(j, hit) for j, joint_hits in enumerate(hits) for hit in joint_hits]
    chosen = np.empty(len(hits), dtype=np.int64)
    _nearest_inside(np.arange(len(flat)), np.array([j for j, _ in flat], dtype=np.int64),
                    np.array([hit.position for _, hit in flat], dtype=float),
                    float(window[0]), float(window[1]), chosen)
    if np.any(chosen < 0):
        raise ValueError('a window holds no hit of some joint')
    return [flat[k][1] for k in chosen]


@numba.njit(cache=True)
def _nearest_inside(hits, joints, positions, first, last, out):
    """out[j] = the hit of joint j inside [first, last] nearest its middle, else -1.

    `hits` are indices into `joints` and `positions` [arc points], taken in their order:
    of equally near hits the first wins.
    """
    middle = 0.5 * (first + last)
    out[:] = -1
    for hit in hits:
        p = positions[hit]
        if first <= p <= last:
            joint = joints[hit]
            best = out[joint]
            if best < 0 or abs(p - middle) < abs(positions[best] - middle):
                out[joint] = hit


def _thin(points: np.ndarray, indices: np.ndarray, spacing: float) -> np.ndarray:
    """Keep indices from `indices` (consecutive) about `spacing` [rad] apart, ends included."""
    if len(indices) <= 2:
        return indices
    steps = np.max(np.abs(np.diff(points[indices], axis=0)), axis=1)
    travelled = np.concatenate([[0.0], np.cumsum(steps)])
    bucket = np.floor(travelled / spacing)
    keep = np.concatenate([[True], bucket[1:] != bucket[:-1]])
    keep[-1] = True
    return indices[keep]
