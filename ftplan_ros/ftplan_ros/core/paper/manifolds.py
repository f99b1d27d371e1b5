"""Steps 1 and 2 of the paper: self-motion manifolds and their obstacle-free parts.

For one degree of redundancy (r = n - m = 1) the pre-image f^{-1}(x) is a union of curves
(paper eq. 1). Each curve is traced by null-space continuation: a predictor step along the
null vector of the Jacobian, a corrector that solves f(θ) = x on the hyperplane orthogonal
to it, and step control. Seeds come from inverse-kinematics samples (48 random starting
points by default): a branch is missed only if no sample converges onto it, and the tests
compare the branches with exact inverse kinematics in every failure plane. A branch that
returns to its seed (on the torus of periodic joints) is a closed loop. Where branches
cross at a singular configuration (x a critical value of f, as the paper's x_g = [1, 0]),
continuation passes straight through and each branch is kept as its own curve.

Configurations are (n,) [rad]; a branch's points are lifted (continuous across ±π).
"""

from __future__ import annotations

import logging
from collections import OrderedDict
from dataclasses import dataclass, replace

import numba
import numpy as np

from ..collision.checker import CollisionChecker
from ..model import kinematics
from ..model.angles import configuration_difference, wrap_configuration, wrap_one
from ..model.robot import Robot, task_errors, task_residuals
from .continuation import CLOSED, STALLED, TOO_LONG, trace_curve

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class ManifoldOptions:
    """Continuation settings (steps in joint space [rad], residuals [m])."""

    step_max: float = 0.05
    step_min: float = 1e-5
    max_turn: float = 0.3  # largest tangent turn [rad] accepted in one step
    tolerance: float = 1e-10
    seeds: int = 48               # inverse-kinematics seeds per round
    seed_rounds: int = 4          # rounds at most; one whose second half finds no branch ends
    max_points: int = 50_000


@dataclass(frozen=True, eq=False)
class SelfMotionManifold:
    """One branch of the pre-image of `x` [m].

    `points` (k, n) [rad] are lifted and at most `step_max` apart. A closed branch is a
    loop: `points[0] + period` follows `points[-1]`, and `period` (n,) holds multiples of
    2π for loops that go round a periodic joint. `clearance` (k,) [m] is filled by Step 2.
    """

    x: tuple[float, ...]
    points: np.ndarray
    closed: bool
    period: np.ndarray
    clearance: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.points)

    def free(self, margin: float = 0.0) -> np.ndarray:
        """(k,) bool: points whose clearance exceeds `margin` [m] (Step 2's M^F)."""
        if self.clearance is None:
            raise ValueError('clearance not computed: call mark_obstacle_free first')
        return self.clearance > margin

    def free_arcs(self, margin: float = 0.0) -> list[tuple[int, int]]:
        """Maximal runs of free points as (first, count); on a loop a run may wrap past the end."""
        free = self.free(margin)
        k = len(free)
        if free.all():
            return [(0, k)]
        runs = []
        start = None
        for idx in range(k):
            if free[idx] and start is None:
                start = idx
            if not free[idx] and start is not None:
                runs.append((start, idx - start))
                start = None
        if start is not None:
            runs.append((start, k - start))
        if self.closed and len(runs) > 1 and runs[0][0] == 0 and sum(runs[-1]) == k:
            first, last = runs.pop(0), runs.pop()
            runs.append((last[0], last[1] + first[1]))
        return runs

    def arc_points(self, first: int, count: int) -> np.ndarray:
        """Return lifted points (count, n) [rad] of the run from index `first` (wraps on loops)."""
        idx = np.arange(first, first + count)
        laps = idx // len(self.points)
        if laps.max() > 0 and not self.closed:
            raise IndexError('an open branch has no points past its end')
        return self.points[idx % len(self.points)] + laps[:, None] * self.period


def trace_self_motion_manifolds(robot: Robot, x: np.ndarray, rng: np.random.Generator,
                                options: ManifoldOptions | None = None,
                                ) -> tuple[SelfMotionManifold, ...]:
    """Step 1: trace every branch of the pre-image of the task point x.

    Seeds come in rounds of `options.seeds` random configurations; while no branch is
    found yet, or a round's last new branch came from its second half (the search had not
    settled), another round follows, up to `options.seed_rounds` (arms with joint limits
    have many branches, each cut into arcs by the limits).
    """
    options = options or ManifoldOptions()
    x = np.asarray(x, dtype=float)
    if robot.n_joints - robot.task_dim != 1:
        raise ValueError('self-motion curves need exactly one degree of redundancy')
    limits = robot.limits
    branches: list[SelfMotionManifold] = []
    for _ in range(options.seed_rounds):
        seeds = rng.uniform(limits[:, 0], limits[:, 1], size=(options.seeds, robot.n_joints))
        solved, converged = project_many(robot, x, seeds, options.tolerance)
        found = np.flatnonzero(converged)
        thetas = wrap_configuration(solved[found], robot.periodic)
        covered = np.zeros(len(found), dtype=bool)
        for branch in branches:
            _cover(robot, thetas, covered, branch, options.step_max)
        last_new = -1
        for k in range(len(found)):
            if covered[k]:
                continue
            branch = trace_branch(robot, x, thetas[k], options)
            log.debug('branch %d: %d points, closed=%s', len(branches), len(branch),
                      branch.closed)
            branches.append(branch)
            _cover(robot, thetas, covered, branch, options.step_max)
            last_new = found[k]
        if branches and last_new < options.seeds // 2:
            break
    if not branches:
        log.info('no configuration reaches %s', x)
    return tuple(branches)


class ManifoldCache:
    """Traced branches by (robot, x, options): they do not depend on the obstacles.

    A planner serving many requests for the same task among changing obstacles traces
    M_s and M_g once; the least recently used entries beyond `size` are dropped.
    """

    def __init__(self, size: int = 16):
        self.size = size
        self._entries: OrderedDict = OrderedDict()

    def trace(self, robot: Robot, x: np.ndarray, rng: np.random.Generator,
              options: ManifoldOptions | None = None) -> tuple[SelfMotionManifold, ...]:
        """`trace_self_motion_manifolds`, or its stored answer for the same arguments."""
        options = options or ManifoldOptions()
        key = (robot, tuple(float(v) for v in x), options)
        if key in self._entries:
            self._entries.move_to_end(key)
            return self._entries[key]
        branches = trace_self_motion_manifolds(robot, x, rng, options)
        self._entries[key] = branches
        if len(self._entries) > self.size:
            self._entries.popitem(last=False)
        return branches


def self_motion_path(robot: Robot, x: np.ndarray, theta_from: np.ndarray,
                     theta_to: np.ndarray, options: ManifoldOptions | None = None,
                     ) -> np.ndarray | None:
    """Find a path (k, n) [rad] along the self-motion manifold of x from θ_from to θ_to.

    Both configurations must put the end effector at x (m,) [m]. Continuation runs both
    ways from θ_from until it passes within a step of θ_to (on the torus of periodic
    joints); the shorter way wins, and its last point is θ_to lifted next to it. Returns
    None when θ_to lies on another branch or beyond a joint limit.
    """
    options = options or ManifoldOptions()
    x = np.asarray(x, dtype=float)
    periodic = robot.periodic
    best = None
    for direction in (+1.0, -1.0):
        points, _, _ = _continue(robot, x, np.asarray(theta_from, dtype=float), direction,
                                 options, target=np.asarray(theta_to, dtype=float))
        gap = configuration_difference(theta_to, points[-1], periodic)
        if np.linalg.norm(gap) > options.step_max:
            continue
        path = np.vstack(points + [points[-1] + gap])
        if best is None or len(path) < len(best):
            best = path
    return best


def mark_obstacle_free(manifold: SelfMotionManifold, checker: CollisionChecker,
                       margin: float = 0.0) -> SelfMotionManifold:
    """Step 2: return the branch with the clearance [m] of each of its points.

    The clearances are the checker's cheap lower bounds (no tier 3, checker.py): a
    point within a centimetre or so of an obstacle may be marked colliding, never the
    other way round.
    """
    return replace(manifold, clearance=checker.min_clearance(manifold.points, margin,
                                                             refine=False))


def project_to_preimage(robot: Robot, x: np.ndarray, theta: np.ndarray,
                        tolerance: float = 1e-10, max_iterations: int = 60,
                        fixed_joint: int | None = None) -> np.ndarray | None:
    """Newton (damped least squares) from θ (n,) [rad] to a configuration with f(θ) = x.

    With `fixed_joint` = i the step leaves θ_i alone, so the result lies in the failure
    hyperplane H_i through θ. Returns None when it does not converge.
    """
    solved, converged = project_many(robot, x, np.asarray(theta, dtype=float)[None, :],
                                     tolerance, max_iterations, fixed_joint)
    return solved[0] if converged[0] else None


def project_many(robot: Robot, x: np.ndarray, thetas: np.ndarray, tolerance: float = 1e-10,
                 max_iterations: int = 60, fixed_joint: int | None = None,
                 ) -> tuple[np.ndarray, np.ndarray]:
    """`project_to_preimage` for many starts (S, n) at once: (configurations, converged (S,)).

    Steps are clipped to the joint limits, so a converged configuration is within them.
    """
    thetas = np.array(np.atleast_2d(thetas), dtype=float)
    movable = np.ones(robot.n_joints, dtype=bool)
    if fixed_joint is not None:
        movable[fixed_joint] = False
    limits = robot.limits
    errors = kinematics.project_seeds(robot.kernel_kind, robot.kernel_parameters,
                                   np.asarray(x, dtype=float), thetas, robot.task_dim, movable,
                                   robot.periodic, limits[:, 0].copy(), limits[:, 1].copy(),
                                   tolerance, max_iterations)
    converged = errors < tolerance
    # A tool axis that points exactly away from the goal's also zeroes its residual.
    converged[converged] &= task_errors(robot, x, thetas[converged])[:, 1] < 1e-6
    return thetas, converged


def null_space_tangent(robot: Robot, theta: np.ndarray) -> np.ndarray:
    """Return the unit null vector (n,) of the task Jacobian at θ: the self-motion direction.

    The Jacobian does not depend on the task point for position and pose tasks; for a
    tool axis it is taken across the tool's own axis.
    """
    x = robot.forward_kinematics(theta)
    return np.linalg.svd(task_residuals(robot, x, theta)[1][0])[2][-1]


def trace_branch(robot: Robot, x: np.ndarray, seed: np.ndarray,
                 options: ManifoldOptions) -> SelfMotionManifold:
    """Trace the branch of M(x) through `seed` (n,) [rad] both ways, until it closes."""
    forward, closed, period = _continue(robot, x, seed, +1.0, options)
    if closed:
        return SelfMotionManifold(tuple(x), np.array(forward), True, period)
    backward, _, _ = _continue(robot, x, seed, -1.0, options)
    points = np.array(backward[:0:-1] + forward)
    return SelfMotionManifold(tuple(x), points, False, np.zeros(robot.n_joints))


def _continue(robot: Robot, x: np.ndarray, seed: np.ndarray, direction: float,
              options: ManifoldOptions, target: np.ndarray | None = None,
              ) -> tuple[list[np.ndarray], bool, np.ndarray]:
    """Predictor-corrector from `seed` until the loop closes, a limit or a dead end.

    With a `target`, it also stops as soon as a point comes within a step of it. The
    steps run in the compiled kernel of continuation.py.
    """
    limits = robot.limits
    points, status, period = trace_curve(
        robot.kernel_kind, robot.kernel_parameters, np.asarray(x, dtype=float),
        np.asarray(seed, dtype=float), direction * null_space_tangent(robot, seed),
        robot.periodic, limits[:, 0].copy(), limits[:, 1].copy(), options.step_max,
        options.step_min, options.max_turn, options.tolerance, options.max_points,
        np.zeros(robot.n_joints) if target is None else np.asarray(target, dtype=float),
        target is not None)
    if status == TOO_LONG:
        raise RuntimeError(f'self-motion continuation exceeded {options.max_points} points')
    if status == STALLED:
        log.debug('continuation stalled at %s', points[-1])
    return list(points), status == CLOSED, period


def _cover(robot: Robot, thetas: np.ndarray, covered: np.ndarray, branch: SelfMotionManifold,
           distance: float) -> None:
    """Mark in `covered` (S,) the configurations (S, n) [rad] within `distance` of the branch.

    Only those not yet covered are measured.
    """
    open_ = np.flatnonzero(~covered)
    covered[open_] = _near_points(np.ascontiguousarray(thetas[open_], dtype=float),
                                  np.ascontiguousarray(branch.points, dtype=float),
                                  robot.periodic.astype(np.bool_), float(distance))


@numba.njit(cache=True)
def _near_points(thetas, points, periodic, distance):
    """(S,) bool: whether each configuration (S, n) lies within `distance` of some point (k, n).

    Distances are Euclidean in joint space [rad], the shortest way round periodic joints.
    """
    out = np.zeros(thetas.shape[0], dtype=np.bool_)
    for s in range(thetas.shape[0]):
        for k in range(points.shape[0]):
            total = 0.0
            for a in range(thetas.shape[1]):
                gap = points[k, a] - thetas[s, a]
                if periodic[a]:
                    gap = wrap_one(gap)
                total += gap * gap
            if np.sqrt(total) < distance:
                out[s] = True
                break
    return out
