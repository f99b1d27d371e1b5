"""The self-check: a plan is only called failure-tolerant after its guarantee is proved.

`feasible: true` claims that from every point of the nominal path, with any one
tolerated joint locked there, a collision-free path in that joint's failure hyperplane
reaches the goal. The proof has three parts, each checked here rather than trusted:

1. Every triangle of S_F is collision-free, over the continuum: a triangle is certified
   when every clearance channel at its centroid (each link against the obstacles, each
   self-collision pair; collision.py) exceeds how far that channel can change inside it
   (Σ_a R[c, a] · max |θ_a - centroid_a|, `CollisionChecker.lever_arms`); otherwise it
   is split in four, down to a depth limit.
2. Every point of the goal row (the goal points and the chords between them) is within
   the goal tolerances: the position error sampled plus a second-order bound between
   samples, the orientation error sampled plus a first-order bound (the tool turns at
   most Σ_a |θ̇_a|: every joint axis is a unit vector).
3. A recovery path exists for every lock of a tolerated joint. For the paper's fan (one
   sheet): the nominal path is monotonic in every joint, the bottom row is exactly θ_s
   and the path to θ_{H_i} keeps θ_i = θ_s,i exactly (the argument in `recovery.py`).
   For any other web: the slice of S_F at every level the nominal path takes joins every
   nominal point on it to the goal row, checked at each vertex value of θ_i and between
   each two (`slices.py`). And, as a check of the implementation, `recover` is run at
   sampled moments of the nominal path for every tolerated joint and each path it
   returns is certified collision-free and arriving, like part 1.

A web may hold several sheets (`FailureSurface.cuts`); part 1 covers the triangles of
all of them, part 2 the goal row of each.

Every number that enters is checked to be finite: a NaN or infinity anywhere fails the
check.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numba
import numpy as np

from .collision import CollisionChecker
from .distance_kernels import link_clearance_over_box, planar_joint_points
from .failure_surface import NOT_FINITE, FailureSurface
from .paths import point_at_fraction
from .recovery import recover
from .robot import Robot, task_errors
from .scene import Task
from .slices import slice_problem

# Certified clearance must beat the motion bound by this much [m]: absorbs the rounding
# of the clearance computation (about 1e-8 m near contact).
_ROUNDING = 1e-6
# [rad] the largest joint angle certified: beyond it the forward kinematics rounds by more
# than _ROUNDING (at 1e17 rad the arm's computed pose jumps by whole radians) and sums of
# corners overflow. A web is lifted a few turns at most.
LARGEST_ANGLE = 1e3


@dataclass(frozen=True)
class VerificationOptions:
    """How hard the self-check works."""

    margin: float = 0.0           # clearance [m] every certified configuration must exceed
    max_depth: int = 7            # splits of a simplex before giving up on certifying it
    chord_samples: int = 8        # least samples per goal-row chord for the goal-error bound
    recovery_moments: int = 5     # sampled moments of the nominal path for explicit recovery

    def __post_init__(self):
        if not math.isfinite(self.margin) or self.margin < 0.0:
            raise ValueError(f'margin must be a finite clearance >= 0 [m], got {self.margin}')
        for name, least in (('max_depth', 0), ('chord_samples', 1), ('recovery_moments', 2)):
            if getattr(self, name) < least:
                raise ValueError(f'{name} must be >= {least}, got {getattr(self, name)}')


@dataclass(frozen=True)
class Verdict:
    """Outcome of the self-check; `reason` says what failed when `ok` is False."""

    ok: bool
    reason: str = ''
    min_clearance: float = float('nan')       # [m] smallest clearance sampled on S_F
    recovery_min_clearance: float = float('nan')  # [m] smallest on the sampled recoveries
    max_goal_error: float = float('nan')     # [m] bound on the goal row's distance to x_g
    max_orientation_error: float = float('nan')  # [rad] the same for its orientation
    clearance_samples: int = 0


def certify_simplices(checker: CollisionChecker, corners: np.ndarray, margin: float,
                      max_depth: int) -> tuple[bool, int, float, int]:
    """Certify that every point of each simplex is collision-free.

    `corners` (S, c, n) [rad] are segments (c = 2) or triangles (c = 3) in joint space.
    Returns (ok, index of the first simplex that failed or -1, smallest clearance sampled
    [m], number of clearance samples). A simplex with a corner that is not finite or lies
    beyond `LARGEST_ANGLE` fails unmeasured.
    """
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
        hit, opened, least = _measure_level(checker, corners, arms, margin)
        samples += len(corners)
        smallest = min(smallest, least)
        if hit >= 0:
            return False, int(roots[hit]), float(smallest), samples
        corners, roots = _split(corners[opened]), np.repeat(roots[opened], _pieces(corners))
    if len(corners) == 0:
        return True, -1, float(smallest), samples
    return False, int(roots[0]), float(smallest), samples


def _measure_level(checker: CollisionChecker, corners: np.ndarray, arms: np.ndarray,
                   margin: float) -> tuple[int, np.ndarray, float]:
    """Measure each simplex (S, c, n) of a level at its centroid.

    Returns the first simplex whose centroid is not clear by more than `margin` [m] (-1
    if none), which simplices (S,) bool the lever bound leaves open (to split), and the
    smallest clearance [m]. A planar chain among spheres is measured in one compiled
    pass (`CollisionChecker.planar_disks`).
    """
    if checker.planar_disks is not None:
        checker.checks += len(corners)
        hit, opened, least = _measure_planar(np.ascontiguousarray(corners, dtype=float),
                                             *checker.planar_disks, arms, margin, _ROUNDING)
        return int(hit), opened, float(least)
    centroids = corners.mean(axis=1)
    spread = np.max(np.abs(corners - centroids[:, None, :]), axis=1)  # (S, n)
    motion = spread @ arms.T  # (S, C): how far each channel can change inside the simplex
    clearance = checker.clearance(centroids, needed=margin + motion + _ROUNDING)
    hit = np.flatnonzero(np.any(~(clearance > margin), axis=1))  # NaN counts as a hit
    opened = np.any(~(clearance - margin > motion + _ROUNDING), axis=1)
    return (int(hit[0]) if len(hit) else -1), opened, float(clearance.min())


@numba.njit(cache=True)
def _measure_planar(corners, lengths, link_radius, centres, radii, cap, arms, margin,
                    rounding):
    """`_measure_level` for a planar chain among spheres, compiled: no clearance array.

    A simplex stays open unless every link is clear of every sphere by more than `margin`
    over the box of its spread, by the lever bound or by the fan bound of
    `link_box_clearance` (tighter near the joints), the better per sphere
    (`link_clearance_over_box`). `cap` bounds the clearance of the culled spheres at every
    configuration.
    """
    count, c, n = corners.shape
    smallest = np.inf
    first_hit = -1
    opened = np.zeros(count, dtype=np.bool_)
    points = np.zeros((n + 1, 2))
    centroid = np.empty(n)
    spread = np.empty(n)
    for s in range(count):
        for a in range(n):
            total = 0.0
            for v in range(c):
                total += corners[s, v, a]
            centroid[a] = total / c
        for a in range(n):
            worst = 0.0
            for v in range(c):
                worst = max(worst, abs(corners[s, v, a] - centroid[a]))
            spread[a] = worst
        planar_joint_points(lengths, centroid, points)
        direction = 0.0
        for k in range(n):
            direction += centroid[k]
            motion = rounding
            for a in range(n):
                motion += spread[a] * arms[k, a]
            nearest, clear = link_clearance_over_box(points, k, lengths[k], direction, spread,
                                                     motion, centres, radii,
                                                     link_radius + margin)
            clearance = min(nearest - link_radius, cap)
            smallest = min(smallest, clearance)
            if not clearance > margin and first_hit < 0:  # NaN counts as a hit
                first_hit = s
            if not (cap > margin and clear):
                opened[s] = True
    return first_hit, opened, smallest


def goal_row_error(robot: Robot, task: Task, goal_points: np.ndarray, samples: int,
                   chords: np.ndarray | None = None) -> tuple[float, float]:
    """Bounds ([m], [rad]) on the goal row's distance from the goal, position and orientation.

    The goal row is the polyline through the goal points (K, n), or its chords (k, k+1)
    for k in `chords` (c,) when given (each sheet of a web has a row of its own); a
    point on no chord counts by itself. The errors are evaluated at enough points per
    chord (at least `samples` + 1, and enough that the orientation's first-order term
    stays below a quarter of its tolerance); between two samples of a chord with step δ
    (n,), the tool leaves the linear interpolation of its position by at most
    (1/8) Σ_{a,b} R_tip[max(a, b)] |δ_a| |δ_b| (`Robot.tip_lever_arms`) and turns by at
    most Σ_a |δ_a| / 2 from the nearer sample.
    """
    x_goal = np.asarray(task.goal, dtype=float)
    first = np.arange(len(goal_points) - 1) if chords is None else np.asarray(chords, dtype=int)
    alone = np.ones(len(goal_points), dtype=bool)
    alone[first] = alone[first + 1] = False
    errors = task_errors(robot, x_goal, goal_points[alone])  # (j, 2)
    positions, orientations = [errors[:, 0]], [errors[:, 1]]
    if len(first):
        a, b = goal_points[first], goal_points[first + 1]
        turn = np.abs(b - a).sum(axis=1).max()
        oriented = task.kind in ('axis', 'pose')
        if oriented:
            samples = max(samples, int(np.ceil(2.0 * turn / task.orientation_tolerance)))
        t = np.linspace(0.0, 1.0, samples + 1)
        points = a[:, None, :] + t[None, :, None] * (b - a)[:, None, :]
        errors = task_errors(robot, x_goal, points)  # (c, samples+1, 2)
        step = np.abs(b - a) / samples  # (c, n)
        tip = robot.tip_lever_arms()
        pair_arm = tip[np.maximum.outer(np.arange(len(tip)), np.arange(len(tip)))]
        curvature = np.einsum('ka,ab,kb->k', step, pair_arm, step) / 8.0
        positions.append(errors[..., 0].max(axis=1) + curvature)
        orientations.append(errors[..., 1].max(axis=1) + 0.5 * step.sum(axis=1) if oriented
                            else np.zeros(1))
    # np.max, not max(): a NaN must come out and fail the check
    return float(np.max(np.concatenate(positions))), float(np.max(np.concatenate(orientations)))


def structure_problem(surface: FailureSurface) -> str:
    """Why the web cannot carry the recovery argument, or '' when it can."""
    paths = surface.paths
    theta_s = surface.theta_s
    if surface.cuts.any():
        return 'the web has more than one sheet'
    if not np.all(paths[:, 0] == theta_s):
        return 'the web paths do not all start at θ_s'
    steps = np.diff(surface.nominal_path, axis=0)
    if not np.all(np.all(steps >= 0, axis=0) | np.all(steps <= 0, axis=0)):
        return 'the nominal path is not monotonic in every joint'
    for i, k in zip(surface.tolerated, surface.hit_paths, strict=True):
        if not np.all(paths[k, :, i] == theta_s[i]):
            return f'the path to the H_{i + 1} hit leaves the failure plane'
    return ''


def limits_problem(surface: FailureSurface, robot: Robot) -> str:
    """Say which joint the web takes past a limit (or where it is not finite), or ''.

    The web's triangles and the recovery paths on them lie in the convex hull of its
    vertices, so vertices within the limits keep everything within them.
    """
    if not surface.is_finite:
        return NOT_FINITE
    vertices = surface.vertices
    limits = robot.limits
    outside = ~robot.periodic & ((vertices < limits[:, 0]) | (vertices > limits[:, 1])).any(axis=0)
    if outside.any():
        return f'the web leaves the limits of {robot.joint_names[int(np.argmax(outside))]}'
    return ''


def certify_surface(surface: FailureSurface, checker: CollisionChecker, task: Task,
                    options: VerificationOptions | None = None) -> Verdict:
    """Parts 1, 2 and the structure of part 3 (see the module docstring) for the task's goal."""
    options = options or VerificationOptions()
    problem = limits_problem(surface, checker.robot)
    if not problem and structure_problem(surface):
        problem = slice_problem(surface, surface.tolerated)
    if problem:
        return Verdict(False, problem)
    chords = np.concatenate([np.arange(first, last, dtype=int) for first, last in
                             surface.sheets()])
    position, orientation = goal_row_error(checker.robot, task, surface.goal_points,
                                           options.chord_samples, chords)
    if not (position <= task.goal_tolerance and orientation <= task.orientation_tolerance):
        return Verdict(False, f'the goal row strays {position:.4f} m, {orientation:.4f} rad '
                       f'from the goal (tolerances {task.goal_tolerance} m, '
                       f'{task.orientation_tolerance} rad)', max_goal_error=position,
                       max_orientation_error=orientation)
    triangles = _distinct_triangles(surface)
    if not len(triangles):  # S_F is a single path: its segments are all there is
        triangles = surface.edges[:surface.rung_edge(0, 0)]  # the path edges come first
    corners = np.take(surface.vertices, triangles, axis=0)  # 4x faster than indexing
    ok, failed, smallest, samples = certify_simplices(checker, corners, options.margin,
                                                      options.max_depth)
    if not ok:
        path, waypoint = np.unravel_index(triangles[failed, 0], surface.paths.shape[:2])
        return Verdict(False, f'S_F is not collision-free near path {path}, waypoint '
                       f'{waypoint}', min_clearance=smallest, max_goal_error=position,
                       max_orientation_error=orientation, clearance_samples=samples)
    return Verdict(True, '', smallest, max_goal_error=position,
                   max_orientation_error=orientation, clearance_samples=samples)


def check_recoveries(surface: FailureSurface, checker: CollisionChecker, task: Task,
                     certified: Verdict, options: VerificationOptions | None = None,
                     ) -> Verdict:
    """Part 3's check of the implementation: `recover` at sampled moments, every tolerated joint.

    Each recovery path must exist, be certified collision-free segment by segment and
    end within the goal tolerances. `certified` is the surface's verdict from
    `certify_surface`; the returned verdict extends it.
    """
    options = options or VerificationOptions()
    segments, owners, checks = [], [], []
    for progress in np.linspace(0.0, 1.0, options.recovery_moments):
        theta = point_at_fraction(surface.nominal_path, progress)
        for joint in surface.tolerated:
            rescue = recover(surface, theta, joint)
            where = f'check failed at joint {joint + 1}, progress {progress:.2f}'
            if rescue is None:
                return replace(certified, ok=False, reason=f'{where}: no recovery path')
            arrival = task_errors(checker.robot, task.goal, rescue.path[-1])
            if not task.reached(arrival):
                return replace(certified, ok=False, reason=f'{where}: the recovery path ends '
                               f'{arrival[0]:.4f} m, {arrival[1]:.4f} rad from the goal')
            segments.append(np.stack([rescue.path[:-1], rescue.path[1:]], axis=1))
            owners.append(np.full(len(rescue.path) - 1, len(checks)))
            checks.append(where)
    if not segments:
        return replace(certified, recovery_min_clearance=float('inf'))
    # Every path's segments in one batch; the first that fails names its lock.
    clear, failed, lowest, count = certify_simplices(checker, np.concatenate(segments),
                                                     options.margin, options.max_depth)
    samples = certified.clearance_samples + count
    if not clear:
        where = checks[int(np.concatenate(owners)[failed])]
        return replace(certified, ok=False, clearance_samples=samples,
                       reason=f'{where}: the recovery path collides')
    return replace(certified, recovery_min_clearance=float(lowest), clearance_samples=samples)


def verify_surface(surface: FailureSurface, checker: CollisionChecker, task: Task,
                   options: VerificationOptions | None = None) -> Verdict:
    """Run the whole self-check of S_F for the task: certification, then recoveries."""
    certified = certify_surface(surface, checker, task, options)
    if not certified.ok:
        return certified
    return check_recoveries(surface, checker, task, certified, options)


def _distinct_triangles(surface: FailureSurface) -> np.ndarray:
    """(T', 3) the live triangles of S_F that certification needs, each set of points once.

    A triangle with a repeated point (where a column is padded) is a segment or a point;
    it is left out when it is an edge or a corner of a proper triangle kept: certifying
    that triangle certifies it. Only triangles with a corner whose point another vertex
    shares can repeat a set or be such a segment or point, or hold one, so the others
    (almost all of the paper's fan) are kept without sorting.
    """
    triangles = surface.triangles[surface.live_triangles]
    points = surface.vertex_ids[triangles]
    many = surface.shared_points
    shared = many[points[:, 0]] | many[points[:, 1]] | many[points[:, 2]]
    keep = ~shared
    keep[np.flatnonzero(shared)[_distinct_sets(points[shared])]] = True
    return triangles[keep]


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
