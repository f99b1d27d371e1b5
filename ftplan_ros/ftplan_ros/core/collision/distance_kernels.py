"""Compiled tiers 1 and 2 of checker.py: distances of shapes to obstacles and to each other.

For thousands of configurations, every link shape against every obstacle (and every
self-collision pair of shapes) in one compiled loop. Each pair first gets the cheap
bound of its bounding spheres; where that is below what the caller needs, a tighter
value by the pair's mode:

* one of the two is a sphere: the other's signed distance at its centre, minus its
  radius (exact);
* otherwise each shape is also enclosed by a capsule (a capsule itself, a cylinder's axis
  with its radius, a box's longest axis with the half diagonal across it, a mesh's
  bounding sphere). Two shapes are at least as far apart as one's signed distance is
  along the other's capsule segment, minus that capsule's radius (the signed distance
  of a convex shape is convex: golden-section search finds its minimum on a segment);
  both ways round are tried and the larger bound kept, and two capsules are measured by
  their segments' distance. Exact when one of the two is a capsule, a lower bound
  otherwise.

Shapes are coded by kind (SPHERE ... MESH) with three parameters: sphere (radius, 0, 0),
box (half sizes), cylinder and capsule (radius, half length, 0), mesh (none). Lengths [m].
"""

from __future__ import annotations

import numba
import numpy as np

from ..model.angles import wrap_one

SPHERE, BOX, CYLINDER, CAPSULE, MESH = 0, 1, 2, 3, 4
CODES = {'sphere': SPHERE, 'box': BOX, 'cylinder': CYLINDER, 'capsule': CAPSULE, 'mesh': MESH}

# How a pair is measured (`pair_modes`).
FIRST_IS_SPHERE = 0   # the second shape's signed distance at the first's centre
SECOND_IS_SPHERE = 1  # the first shape's signed distance at the second's centre
ENCLOSING = 2         # enclosing capsules (see the module docstring)

# [m] every clearance bound gives this much away to float rounding
ROUNDING = 1e-9
_GOLDEN_STEPS = 40    # golden-section steps: the segment parameter to 0.618^40 ~ 4e-9


def pair_modes(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Return the modes of pairs of shapes of kind codes `first`, `second` (broadcast)."""
    a, b = np.asarray(first), np.asarray(second)
    return np.where((a == SPHERE) & (b != MESH), FIRST_IS_SPHERE,
                    np.where((b == SPHERE) & (a != MESH), SECOND_IS_SPHERE, ENCLOSING))


def exact_pairs(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Tell whether the distances of pairs of shapes of these kinds are exact (broadcast)."""
    first, second = np.asarray(first), np.asarray(second)
    return ((pair_modes(first, second) != ENCLOSING)
            | ((first == CAPSULE) & (second != MESH)) | ((second == CAPSULE) & (first != MESH)))


def enclosing_capsule(kind: int, parameters: np.ndarray, bound_centre: np.ndarray,
                      bound_radius: float) -> np.ndarray:
    """Return a capsule holding a shape, in its frame: (ends (2, 3) flattened, radius) (7,)."""
    centre, axis, half, radius = np.zeros(3), np.array([0.0, 0.0, 1.0]), 0.0, bound_radius
    if kind in (CYLINDER, CAPSULE):
        half, radius = parameters[1], parameters[0]
    elif kind == BOX:
        longest = int(np.argmax(parameters))
        axis = np.eye(3)[longest]
        half = parameters[longest]
        radius = float(np.linalg.norm(np.delete(parameters, longest)))
    elif kind == MESH:
        centre = bound_centre
    return np.concatenate([centre - half * axis, centre + half * axis, [radius]])


@numba.njit(cache=True, inline='always')
def _signed_distance(kind: int, parameters: np.ndarray, x: float, y: float, z: float) -> float:
    """Signed distance [m] from point (x, y, z), in the shape's frame, to the shape."""
    if kind == SPHERE:
        return np.sqrt(x * x + y * y + z * z) - parameters[0]
    if kind == BOX:
        qx = abs(x) - parameters[0]
        qy = abs(y) - parameters[1]
        qz = abs(z) - parameters[2]
        outside = np.sqrt(max(qx, 0.0) ** 2 + max(qy, 0.0) ** 2 + max(qz, 0.0) ** 2)
        return outside + min(max(qx, max(qy, qz)), 0.0)
    if kind == CYLINDER:
        qr = np.sqrt(x * x + y * y) - parameters[0]
        qz = abs(z) - parameters[1]
        outside = np.sqrt(max(qr, 0.0) ** 2 + max(qz, 0.0) ** 2)
        return outside + min(max(qr, qz), 0.0)
    # CAPSULE: distance to the core segment along z, minus the radius
    along = min(max(z, -parameters[1]), parameters[1])
    return np.sqrt(x * x + y * y + (z - along) ** 2) - parameters[0]


@numba.njit(cache=True, inline='always')
def _distance_in(kind: int, parameters: np.ndarray, frame: np.ndarray, x: float, y: float,
                 z: float) -> float:
    """Signed distance [m] from a world point to a shape posed by `frame` (4, 4)."""
    dx = x - frame[0, 3]
    dy = y - frame[1, 3]
    dz = z - frame[2, 3]
    return _signed_distance(kind, parameters,
                            frame[0, 0] * dx + frame[1, 0] * dy + frame[2, 0] * dz,
                            frame[0, 1] * dx + frame[1, 1] * dy + frame[2, 1] * dz,
                            frame[0, 2] * dx + frame[1, 2] * dy + frame[2, 2] * dz)


@numba.njit(cache=True, inline='always')
def _apply(frame: np.ndarray, local: np.ndarray, out: np.ndarray) -> None:
    """Write the world point of `local` (3,) in `frame` (4, 4) into `out` (3,)."""
    for i in range(3):
        out[i] = frame[i, 0] * local[0] + frame[i, 1] * local[1] + frame[i, 2] * local[2] \
            + frame[i, 3]


@numba.njit(cache=True)
def segment_distance(p1: np.ndarray, q1: np.ndarray, p2: np.ndarray, q2: np.ndarray) -> float:
    """Distance [m] between the segments p1-q1 and p2-q2 (points (3,)).

    The closest points of the two lines, clamped to the segments (Ericson, Real-Time
    Collision Detection, 5.1.9).
    """
    d1 = q1 - p1
    d2 = q2 - p2
    r = p1 - p2
    a = d1 @ d1
    e = d2 @ d2
    f = d2 @ r
    if a <= 1e-24 and e <= 1e-24:
        return np.sqrt(r @ r)
    if a <= 1e-24:
        s, t = 0.0, min(max(f / e, 0.0), 1.0)
    else:
        c = d1 @ r
        if e <= 1e-24:
            s, t = min(max(-c / a, 0.0), 1.0), 0.0
        else:
            b = d1 @ d2
            denominator = a * e - b * b
            s = min(max((b * f - c * e) / denominator, 0.0), 1.0) if denominator > 0.0 else 0.0
            t = (b * s + f) / e
            if t < 0.0:
                s, t = min(max(-c / a, 0.0), 1.0), 0.0
            elif t > 1.0:
                s, t = min(max((b - c) / a, 0.0), 1.0), 1.0
    gap = (p1 + s * d1) - (p2 + t * d2)
    return np.sqrt(gap @ gap)


@numba.njit(cache=True)
def segment_signed_distance(kind: int, parameters: np.ndarray, frame: np.ndarray,
                            start: np.ndarray, end: np.ndarray, enough: float) -> float:
    """Least signed distance [m] of a shape posed by `frame` along the segment start-end.

    The signed distance of a convex shape is convex, so golden-section search finds the
    minimum over the segment (ends included). It is 1-Lipschitz in space, so the
    minimum is at least the smaller inner value minus the segment length times the
    bracket: once that bound reaches `enough` [m] the search stops and returns it.
    """
    low, high = 0.0, 1.0
    ratio = 0.5 * (np.sqrt(5.0) - 1.0)
    d = end - start
    length = np.sqrt(d @ d)
    best = min(_distance_in(kind, parameters, frame, start[0], start[1], start[2]),
               _distance_in(kind, parameters, frame, end[0], end[1], end[2]))
    for _ in range(_GOLDEN_STEPS):
        left = high - ratio * (high - low)
        right = low + ratio * (high - low)
        value_left = _distance_in(kind, parameters, frame, start[0] + left * d[0],
                                  start[1] + left * d[1], start[2] + left * d[2])
        value_right = _distance_in(kind, parameters, frame, start[0] + right * d[0],
                                   start[1] + right * d[1], start[2] + right * d[2])
        best = min(best, value_left, value_right)
        bound = min(value_left, value_right) - length * (high - low)
        if bound >= enough:
            return min(best, bound)
        if value_left < value_right:
            high = right
        else:
            low = left
    return best


@numba.njit(cache=True)
def shape_poses(frames: np.ndarray, links: np.ndarray, placements: np.ndarray) -> np.ndarray:
    """Pose shapes: (N, S, 4, 4) for shapes on links `links` (S,), placed by `placements`.

    `placements` (S, 4, 4) are in the link frames `frames` (N, L, 4, 4).
    """
    count, shapes = frames.shape[0], links.shape[0]
    out = np.empty((count, shapes, 4, 4))
    for n in range(count):
        for s in range(shapes):
            frame = frames[n, links[s]]
            placement = placements[s]
            for i in range(4):
                for j in range(4):
                    out[n, s, i, j] = (frame[i, 0] * placement[0, j] + frame[i, 1] * placement[1, j]
                                       + frame[i, 2] * placement[2, j]
                                       + frame[i, 3] * placement[3, j])
    return out


@numba.njit(cache=True)
def obstacle_distances(poses: np.ndarray, kinds: np.ndarray, parameters: np.ndarray,
                       bounds: np.ndarray, capsules: np.ndarray, obstacle_kinds: np.ndarray,
                       obstacle_parameters: np.ndarray, obstacle_frames: np.ndarray,
                       obstacle_bounds: np.ndarray, obstacle_capsules: np.ndarray,
                       modes: np.ndarray, needed: np.ndarray) -> np.ndarray:
    """Distances or lower bounds (N, S, P) [m] of S posed shapes to P obstacles.

    `poses` (N, S', 4, 4) place the shapes (the first S are measured), `obstacle_frames`
    (P, 4, 4) the obstacles; `bounds` (S, 4) are the shapes' bounding spheres in their
    frames and `obstacle_bounds` (P, 4) the obstacles' in the world, `capsules` (S, 7) and
    `obstacle_capsules` (P, 7) enclosing capsules in their own frames
    (`enclosing_capsule`); `modes` (S, P) say how each pair is measured and `needed`
    (N, S) [m] below which the bounding spheres are not enough.
    """
    count, shapes = poses.shape[0], modes.shape[0]
    obstacles = obstacle_kinds.shape[0]
    out = np.empty((count, shapes, obstacles))
    centre = np.empty(3)
    start = np.empty(3)
    end = np.empty(3)
    obstacle_ends = np.empty((obstacles, 2, 3))
    for p in range(obstacles):
        _apply(obstacle_frames[p], obstacle_capsules[p, :3], obstacle_ends[p, 0])
        _apply(obstacle_frames[p], obstacle_capsules[p, 3:6], obstacle_ends[p, 1])
    for n in range(count):
        for s in range(shapes):
            frame = poses[n, s]
            _apply(frame, bounds[s, :3], centre)
            _apply(frame, capsules[s, :3], start)
            _apply(frame, capsules[s, 3:6], end)
            for p in range(obstacles):
                gap = np.sqrt((centre[0] - obstacle_bounds[p, 0]) ** 2
                              + (centre[1] - obstacle_bounds[p, 1]) ** 2
                              + (centre[2] - obstacle_bounds[p, 2]) ** 2)
                value = gap - bounds[s, 3] - obstacle_bounds[p, 3]
                if value >= needed[n, s]:
                    out[n, s, p] = value
                    continue
                mode = modes[s, p]
                if mode == FIRST_IS_SPHERE:
                    value = _distance_in(obstacle_kinds[p], obstacle_parameters[p],
                                         obstacle_frames[p], frame[0, 3], frame[1, 3],
                                         frame[2, 3]) - parameters[s, 0]
                elif mode == SECOND_IS_SPHERE:
                    value = _distance_in(kinds[s], parameters[s], frame, obstacle_frames[p, 0, 3],
                                         obstacle_frames[p, 1, 3], obstacle_frames[p, 2, 3]) \
                        - obstacle_parameters[p, 0]
                else:
                    enough = needed[n, s]
                    value = max(value, segment_signed_distance(
                        obstacle_kinds[p], obstacle_parameters[p], obstacle_frames[p], start,
                        end, enough + capsules[s, 6]) - capsules[s, 6])
                    if kinds[s] != MESH and value < enough:
                        value = max(value, segment_signed_distance(
                            kinds[s], parameters[s], frame, obstacle_ends[p, 0],
                            obstacle_ends[p, 1], enough + obstacle_capsules[p, 6])
                            - obstacle_capsules[p, 6])
                out[n, s, p] = value
    return out


@numba.njit(cache=True)
def pair_distances(poses: np.ndarray, kinds: np.ndarray, parameters: np.ndarray,
                   bounds: np.ndarray, capsules: np.ndarray, pairs: np.ndarray,
                   modes: np.ndarray, needed: np.ndarray) -> np.ndarray:
    """Measure distances or lower bounds (N, Q) [m] between the shapes of Q pairs (Q, 2).

    `poses` (N, S, 4, 4) place the shapes; `modes` (Q,) say how each pair is measured and
    `needed` (N, Q) [m] below which the bounding spheres are not enough.
    """
    count = poses.shape[0]
    out = np.empty((count, pairs.shape[0]))
    first = np.empty(3)
    second = np.empty(3)
    first_end = np.empty(3)
    second_end = np.empty(3)
    for n in range(count):
        for q in range(pairs.shape[0]):
            a, b = pairs[q, 0], pairs[q, 1]
            _apply(poses[n, a], bounds[a, :3], first)
            _apply(poses[n, b], bounds[b, :3], second)
            value = np.sqrt((first[0] - second[0]) ** 2 + (first[1] - second[1]) ** 2
                            + (first[2] - second[2]) ** 2) - bounds[a, 3] - bounds[b, 3]
            if value < needed[n, q]:
                if modes[q] == FIRST_IS_SPHERE:
                    value = _distance_in(kinds[b], parameters[b], poses[n, b], poses[n, a, 0, 3],
                                         poses[n, a, 1, 3], poses[n, a, 2, 3]) - parameters[a, 0]
                elif modes[q] == SECOND_IS_SPHERE:
                    value = _distance_in(kinds[a], parameters[a], poses[n, a], poses[n, b, 0, 3],
                                         poses[n, b, 1, 3], poses[n, b, 2, 3]) - parameters[b, 0]
                else:
                    _apply(poses[n, a], capsules[a, :3], first)
                    _apply(poses[n, a], capsules[a, 3:6], first_end)
                    _apply(poses[n, b], capsules[b, :3], second)
                    _apply(poses[n, b], capsules[b, 3:6], second_end)
                    enough = needed[n, q]
                    value = max(value, segment_distance(first, first_end, second, second_end)
                                - capsules[a, 6] - capsules[b, 6])
                    if kinds[a] != MESH and value < enough:
                        value = max(value, segment_signed_distance(
                            kinds[a], parameters[a], poses[n, a], second, second_end,
                            enough + capsules[b, 6]) - capsules[b, 6])
                    if kinds[b] != MESH and value < enough:
                        value = max(value, segment_signed_distance(
                            kinds[b], parameters[b], poses[n, b], first, first_end,
                            enough + capsules[a, 6]) - capsules[a, 6])
            out[n, q] = value
    return out


# Planar chains among spheres: the exact tier 1 without frames ----------------------------

@numba.njit(cache=True)
def planar_joint_points(lengths, theta, points):
    """Fill `points` (n+1, 2) [m] with the base, the joints and the tool of a planar chain."""
    phi = 0.0
    for k in range(lengths.shape[0]):
        phi += theta[k]
        points[k + 1, 0] = points[k, 0] + lengths[k] * np.cos(phi)
        points[k + 1, 1] = points[k, 1] + lengths[k] * np.sin(phi)


@numba.njit(cache=True, inline='always')
def segment_gap2(a, b, centre):
    """Squared distance [m²] from a point `centre` (3,) to the segment a-b (2-D, in z = 0)."""
    dx = b[0] - a[0]
    dy = b[1] - a[1]
    length2 = dx * dx + dy * dy
    ex = centre[0] - a[0]
    ey = centre[1] - a[1]
    t = (ex * dx + ey * dy) / length2 if length2 > 0.0 else 0.0
    t = min(1.0, max(0.0, t))
    fx = ex - t * dx
    fy = ey - t * dy
    return fx * fx + fy * fy + centre[2] * centre[2]


@numba.njit(cache=True)
def segment_disk_clearance(a, b, centres, radii):
    """Smallest distance [m] from segment a-b (2-D points in z = 0) to the spheres.

    `centres` (P, 3) [m], `radii` (P,) [m]; negative inside one, +inf without spheres.
    """
    best = np.inf
    for p in range(centres.shape[0]):
        best = min(best, np.sqrt(segment_gap2(a, b, centres[p])) - radii[p])
    return best


@numba.njit(cache=True, inline='always')
def sphere_drift(points, k, cx, cy, half):
    """How far [m] a point (cx, cy) [m] moves relative to link k as joints a < k turn.

    Each turns by at most `half[a]` [rad] about its joint `points[a]` (points (n+1, 2)):
    d_{a+1} = d_a + (|c - p_a| + d_a) h_a.
    """
    drift = 0.0
    for a in range(k):
        drift += (np.sqrt((cx - points[a, 0]) ** 2 + (cy - points[a, 1]) ** 2) + drift) * half[a]
    return drift


@numba.njit(cache=True, inline='always')
def _box_gap(points, k, length, direction, half, centre):
    """Lower bound [m] on the distance from link k's segment to a point over a box.

    See `link_box_clearance`; `centre` (3,) [m] is the point, a sphere's centre.
    """
    cx, cy = centre[0], centre[1]
    drift = sphere_drift(points, k, cx, cy, half)
    dx, dy = cx - points[k, 0], cy - points[k, 1]
    distance = np.sqrt(dx * dx + dy * dy)
    turn = abs(wrap_one(np.arctan2(dy, dx) - direction)) - half[k]
    if turn <= 0.0:
        planar = max(0.0, distance - length)
    elif turn >= 0.5 * np.pi:
        planar = distance
    elif distance * np.cos(turn) <= length:
        planar = distance * np.sin(turn)
    else:  # the tip, by the law of cosines without cancellation
        planar = np.sqrt((distance - length) ** 2
                         + 4.0 * distance * length * np.sin(0.5 * turn) ** 2)
    return np.sqrt(planar * planar + centre[2] * centre[2]) - drift - ROUNDING


@numba.njit(cache=True)
def link_box_clearance(points, k, length, direction, half, centres, radii):
    """Lower bound [m] on the distance from link k's segment to the spheres over a box.

    The box holds joint angles within `half` (n,) [rad] of its centre, where the chain's
    joints are `points` (n+1, 2) [m] and link k (of `length` [m]) points along
    `direction` [rad]. Turning joints a < k moves link k as turning a sphere back about
    the joints p_{k-1}, ..., p_0 would move the sphere: its centre c drifts by at most
    d_k, d_{a+1} = d_a + (|c - p_a| + d_a) h_a. Turning joint k sweeps the segment over a
    fan of half angle h_k about p_k, whose distance to c is exact: the fan's direction
    nearest c's. So each sphere is at least (fan distance) - d_k - radius away.
    """
    best = np.inf
    for p in range(centres.shape[0]):
        best = min(best, _box_gap(points, k, length, direction, half, centres[p]) - radii[p])
    return best


@numba.njit(cache=True)
def link_clearance_over_box(points, k, length, direction, half, motion, centres, radii,
                            reach):
    """Link k's clearance at a box's centre, and whether it stays clear over the box.

    Returns the distance [m] from link k's segment to the nearest sphere at the box's
    centre (`segment_disk_clearance`) and whether the segment clears every sphere by
    more than `reach` [m] over the box of `link_box_clearance`. Per sphere either of two
    lower bounds may show that: the exact distance at the centre less `motion` [m] (a
    bound on how far any point of the link moves in the box: the lever bound), or the fan
    bound of `link_box_clearance`, the dearer, computed only for the spheres the lever
    bound leaves undecided. A NaN anywhere answers not clear.
    """
    nearest = np.inf
    clear = True
    for p in range(centres.shape[0]):
        gap = np.sqrt(segment_gap2(points[k], points[k + 1], centres[p])) - radii[p]
        nearest = min(nearest, gap)
        if clear and not gap - reach > motion:
            clear = _box_gap(points, k, length, direction, half, centres[p]) - radii[p] > reach
    return nearest, clear


@numba.njit(cache=True)
def planar_link_clearances(lengths, link_radius, centres, radii, thetas):
    """Clearance (N, n) [m] of each link's capsule from the nearest sphere, exactly.

    A planar chain of links `lengths` (n,) [m] and capsule radius `link_radius` [m], at
    configurations `thetas` (N, n) [rad]; spheres of `centres` (P, 3) and `radii` (P,).
    A link whose end is not finite (placed by an angle, or a sum of angles, that is not)
    reads NaN, as in the general tiers; without spheres every other entry is +inf.
    """
    count, n = thetas.shape
    out = np.empty((count, n))
    if centres.shape[0] == 0:  # only ends that are not finite to find: no trigonometry
        for q in range(count):
            direction = 0.0
            for k in range(n):
                direction += thetas[q, k]  # once not finite, never finite again
                out[q, k] = np.inf if np.isfinite(direction) else np.nan
        return out
    points = np.zeros((n + 1, 2))
    for q in range(count):
        planar_joint_points(lengths, thetas[q], points)
        for k in range(n):
            out[q, k] = segment_disk_clearance(points[k], points[k + 1], centres,
                                               radii) - link_radius
        # The nearest-sphere min drops a NaN: a link with an end that is not finite (an
        # angle, or a sum of angles, that is not) reads NaN, as in the general tiers.
        for k in range(n):
            if not (np.isfinite(points[k + 1, 0]) and np.isfinite(points[k + 1, 1])):
                out[q, k:] = np.nan
                break
    return out
