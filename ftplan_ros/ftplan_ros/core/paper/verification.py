"""The self-check: a plan is only called failure-tolerant after its guarantee is proved.

`feasible: true` claims that from every point of the nominal path, with any one
tolerated joint locked there, a collision-free path in that joint's failure hyperplane
reaches the goal. The proof has three parts, each checked here rather than trusted:

1. Every triangle of S_F is collision-free, over the continuum (`certification.py`): a
   block of quads of the web, or a triangle, is certified when every clearance channel
   at a point of it (each link against the obstacles, each self-collision pair;
   collision/checker.py) exceeds how far that channel can change inside it (Σ_a R[c, a] ·
   max |θ_a - point_a| over its corners, `CollisionChecker.lever_arms`); otherwise it is
   split in four, a block down to single quads, whose triangles are split down to a
   depth limit.
2. Every point of the goal row (the goal points and the chords between them) is within
   the goal tolerances: the position error sampled plus a second-order bound between
   samples, the orientation error sampled plus a first-order bound (the tool turns at
   most Σ_a |θ̇_a|: every joint axis is a unit vector).
3. A recovery path exists for every lock of a tolerated joint. For the paper's fan (one
   sheet): the nominal path is monotonic in every joint, the bottom row is exactly θ_s
   and the path to θ_{H_i} keeps θ_i = θ_s,i exactly (the argument in `recovery.py`).
   For a joint held still (`held_joints.py`) that path is the nominal path itself, so
   the same exact check proves that the rest of the nominal path, clear by part 1 and
   ending on the goal row by part 2, recovers each of its locks.
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

import numpy as np

from ..collision.certification import certify_polylines, certify_web
from ..collision.checker import CollisionChecker
from ..model.paths import point_at_fraction
from ..model.robot import Robot, task_errors
from ..model.scene import Task
from .failure_surface import NOT_FINITE, FailureSurface
from .recovery import recover
from .slices import slice_problem


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
    ok, (path, waypoint), smallest, samples = certify_web(checker, surface, options.margin,
                                                          options.max_depth)
    if not ok:
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
    rescues, checks = [], []
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
            rescues.append(rescue.path)
            checks.append(where)
    if not rescues:
        return replace(certified, recovery_min_clearance=float('inf'))
    # Every path in one batch; the one that fails names its lock.
    clear, (failed, _), lowest, count = certify_polylines(checker, rescues, options.margin,
                                                          options.max_depth)
    samples = certified.clearance_samples + count
    if not clear:
        where = checks[failed]
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
