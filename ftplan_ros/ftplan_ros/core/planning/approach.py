"""From where the arm stands to θ_s, and to the goal with the joints a lock leaves.

The paper assumes the arm starts at θ_s. A real arm stands somewhere else, and a lock
before the failure-tolerant nominal path begins leaves it somewhere else again. This
module plans those ordinary motions; none of them is failure-tolerant (issue 10):

- `ApproachPlanner.reachable_arc`: with one degree of redundancy and the tool at x_s,
  the obstacle-free arc of M_s through the arm's configuration q (traced from q by the
  continuation of Step 1, screened as in Step 2). Starts on it are reached by
  self-motion, the tool staying at x_s; `prefer_reachable` turns the arc into the hook
  with which `core.plan` searches them first.
- `ApproachPlanner.approach`: a path from q to θ_s (plus whole turns of periodic
  joints): along that arc, along M_s (`self_motion_path`), by a straight joint move,
  through the certified free cells of a joint grid (planar 3R arms among disks,
  `free_components`), or by an ordinary collision-free joint move planned with OMPL's
  RRT-Connect and its simplifier, the joint limits as bounds and the clearance as
  validity.
- `ApproachPlanner.path_to_goal`: with a joint locked where it stands, a configuration
  reaching the goal in its failure hyperplane (Newton from random seeds) and a path there
  in the remaining joints (straight or RRT-Connect).

`reachable.plan_from` plans for an arm standing at q with these motions. Every path
returned is certified collision-free over the continuum, not only at its samples: its
segments, cut to at most `certify_step` [rad], pass `certification.certify_polylines`
with the margin. Paths are (k, n) [rad], lifted (continuous), starting at q.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import StrEnum
from functools import cached_property

import numpy as np

from ..collision.certification import certify_polylines
from ..collision.checker import CollisionChecker
from ..grid.free_components import GRID_CELLS, START_GRIDS, FreeComponents, proof_grids
from ..model.angles import configuration_difference, whole_turns
from ..model.paths import densify, path_length
from ..model.robot import Robot, task_errors
from ..paper.manifolds import (
    ManifoldOptions,
    mark_obstacle_free,
    project_many,
    self_motion_path,
    trace_branch,
)

log = logging.getLogger(__name__)

# [m] what RRT-Connect's states keep beyond the margin: its motions are checked only at
# samples, so a little room lets the certificate of the segments pass.
_RRT_EXTRA_CLEARANCE = 1e-3
_STRAIGHT_MOVES = 8  # straight moves tried at most (periodic joints: either way round)


class Route(StrEnum):
    """How an approach gets where it goes (the value is what reports say)."""

    THERE = 'already there'
    ALONG_ARC = 'along M_s^F'
    SELF_MOTION = 'along M_s'
    STRAIGHT = 'by a straight joint move'
    THROUGH_CELLS = 'through certified free cells of a joint grid'
    GIVEN = 'by the path given'
    RRT_CONNECT = 'by a joint move planned with RRT-Connect'
    NONE = 'no path'


@dataclass(frozen=True)
class ApproachOptions:
    """Resolutions [rad], budgets [s] and clearance [m] of the approach planner."""

    margin: float = 0.0                 # clearance every point of a path must exceed [m]
    certify_step: float = 0.05          # longest segment handed to the certificate [rad]
    certify_depth: int = 10             # halvings of a segment before it counts as unsafe
    rrt_time: float = 1.0               # OMPL's budget per attempt [s]
    rrt_attempts: int = 3
    rrt_step: float = 0.02              # RRT-Connect's motion check step [rad]
    on_manifold_tolerance: float = 1e-6  # tool errors [m, rad] that still count as at x_s
    arc_tolerance: float = 0.05         # a configuration this close to the arc is on it [rad]
    ik_seeds: int = 64                  # `path_to_goal`: Newton seeds in the failure plane
    goal_candidates: int = 4            # `path_to_goal`: nearest goal configurations tried
    proof_cells: int = START_GRIDS[-1]  # `plan_from`: finest grid of the starts within reach
    reach_starts: int = 6               # `plan_from`: starts within reach planned from at most
    manifold: ManifoldOptions = field(default_factory=ManifoldOptions)

    def __post_init__(self):
        proof_grids(self.proof_cells)  # a size that is not a proof grid is refused here
        if isinstance(self.reach_starts, bool) or not isinstance(self.reach_starts, int) \
                or self.reach_starts < 0:
            raise ValueError(f'reach_starts must be an integer >= 0, got {self.reach_starts!r}')


@dataclass(frozen=True, eq=False)
class Approach:
    """A certified path (k, n) [rad] from the arm's configuration, or why there is none."""

    path: np.ndarray | None
    route: Route
    reason: str = ''

    @property
    def ok(self) -> bool:
        """Whether there is a path."""
        return self.path is not None

    @property
    def length(self) -> float:
        """Joint-space length [rad] of the path (NaN without one)."""
        return float('nan') if self.path is None else path_length(self.path)

    def describe(self) -> str:
        """Say how the arm gets there, e.g. 'along M_s^F (37 points, 1.234 rad)'."""
        if self.path is None:
            return self.reason
        if self.route is Route.THERE:
            return self.route.value
        return f'{self.route.value} ({len(self.path)} points, {path_length(self.path):.3f} rad)'


class ApproachPlanner:
    """Plan the ordinary (not failure-tolerant) motions of the module docstring.

    `checker` holds the robot and the obstacles; `robot` is the same arm bound to the task
    kind (default: the checker's); `rng` seeds the inverse kinematics of `path_to_goal`
    (OMPL draws from its own generator).
    """

    def __init__(self, checker: CollisionChecker, options: ApproachOptions | None = None,
                 rng: np.random.Generator | None = None, robot: Robot | None = None):
        self.checker = checker
        self.robot: Robot = robot if robot is not None else checker.robot
        self.options = options or ApproachOptions()
        self.rng = rng if rng is not None else np.random.default_rng(0)

    # Along M_s ----------------------------------------------------------------------

    def on_manifold(self, x: np.ndarray, q: np.ndarray) -> bool:
        """Whether q (n,) puts the tool at task point x, so that q lies on M(x)."""
        errors = task_errors(self.robot, np.asarray(x, dtype=float), np.asarray(q, dtype=float))
        return bool(np.all(errors <= self.options.on_manifold_tolerance))

    def reachable_arc(self, x_s: np.ndarray, q: np.ndarray) -> np.ndarray | None:
        """Return the obstacle-free arc (k, n) of M_s through q, lifted, q among its points.

        None unless the robot has one degree of redundancy, q puts the tool at x_s and q
        itself is clear. Its points are screened like Step 2's (a lower bound of the
        clearance above the margin), so they are free; the segments between them are
        certified when a path is made of them.
        """
        robot = self.robot
        q = np.asarray(q, dtype=float)
        if robot.n_joints - robot.task_dim != 1 or not self.on_manifold(x_s, q):
            return None
        branch = mark_obstacle_free(trace_branch(robot, np.asarray(x_s, dtype=float), q,
                                                  self.options.manifold),
                                    self.checker, self.options.margin)
        here = int(np.argmin(np.linalg.norm(branch.points - q, axis=1)))
        for first, count in branch.free_arcs(self.options.margin):
            indices = np.arange(first, first + count)
            if branch.closed:
                indices %= len(branch)
            if here in indices:
                arc = branch.arc_points(first, count)
                # Lift the arc so that q is one of its points (a loop's run may wrap past
                # its end, where the points are a period further).
                nearest = arc[int(np.argmin(np.max(np.abs(configuration_difference(
                    arc, q, robot.periodic)), axis=1)))]
                return arc - whole_turns(nearest, q, robot.periodic)
        return None

    def prefer_reachable(self, arc: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
        """Return the hook of `core.plan`: a mask (c,) of the start candidates (c, n) on `arc`."""
        periodic = self.robot.periodic
        tolerance = self.options.arc_tolerance

        def on_arc(candidates: np.ndarray) -> np.ndarray:
            candidates = np.asarray(candidates, dtype=float).reshape(-1, arc.shape[1])
            near = np.zeros(len(candidates), dtype=bool)
            for k in range(0, len(candidates), 64):  # (64, k, n) differences at a time
                gaps = configuration_difference(arc[None], candidates[k:k + 64, None], periodic)
                near[k:k + 64] = np.abs(gaps).max(axis=2).min(axis=1) <= tolerance
            return near

        return on_arc

    def _along_arc(self, arc: np.ndarray, q: np.ndarray, theta: np.ndarray) -> np.ndarray | None:
        """Return the arc's points from q to the one nearest θ, then θ; None if θ is off it."""
        periodic = self.robot.periodic
        gaps = np.max(np.abs(configuration_difference(arc, theta, periodic)), axis=1)
        end = int(np.argmin(gaps))
        if gaps[end] > self.options.arc_tolerance:
            return None
        start = int(np.argmin(np.linalg.norm(arc - q, axis=1)))
        step = 1 if end >= start else -1
        points = arc[start:end + step:step] if end + step >= 0 else arc[start::step]
        last = points[-1] + configuration_difference(theta, points[-1], periodic)
        return np.vstack([q[None, :], points[1:], last[None, :]])

    # Approaches ---------------------------------------------------------------------

    def approach(self, q: np.ndarray, theta_s: np.ndarray, arrival: float = 1e-6,
                 arc: np.ndarray | None = None, rrt: bool = True) -> Approach:
        """Find a certified path from q (n,) to θ_s (n,) plus whole turns; say how it goes.

        Tried in order: q is θ_s already (within `arrival` [rad] per joint, a single
        point); along the arc of M_s^F through q (`reachable_arc`, or `arc` if given);
        along M_s by continuation; then `joint_move` (RRT-Connect only with `rrt`). Only
        the first two keep the tool at x_s.
        """
        robot = self.robot
        q = np.asarray(q, dtype=float)
        theta_s = np.asarray(theta_s, dtype=float)
        nearest = q + configuration_difference(theta_s, q, robot.periodic)
        if np.max(np.abs(nearest - q)) <= arrival:
            return Approach(nearest[None, :], Route.THERE)
        x_s = robot.forward_kinematics(theta_s)
        if robot.n_joints - robot.task_dim == 1 and self.on_manifold(x_s, q):
            arc = arc if arc is not None else self.reachable_arc(x_s, q)
            path = None if arc is None else self._along_arc(arc, q, theta_s)
            if path is not None and self.certify(path):
                return Approach(path, Route.ALONG_ARC)
            path = self_motion_path(robot, x_s, q, theta_s, self.options.manifold)
            if path is not None and self.certify(path):
                return Approach(path, Route.SELF_MOTION)
        return self.joint_move(q, theta_s, rrt=rrt)

    def joint_move(self, q: np.ndarray, target: np.ndarray, locked: int | None = None,
                   rrt: bool = True) -> Approach:
        """Find a certified joint move from q to target (plus whole turns), `locked` held.

        Straight moves first (periodic joints may turn either way), then with no joint
        held through the certified cells of `free_components`, then (with `rrt`)
        RRT-Connect in the other joints, `rrt_attempts` times, towards every end of those
        moves at once; not where `free_components` proves that no joint move exists.
        """
        q = np.asarray(q, dtype=float)
        ends = straight_move_ends(q, np.asarray(target, dtype=float), self.robot.periodic,
                                  held=locked)[:_STRAIGHT_MOVES]
        for end in ends:
            path = np.vstack([q, end])
            if self.certify(path):
                return Approach(path, Route.STRAIGHT)
        ends = [end for end in ends if self._valid(end)]
        if not ends:
            return Approach(None, Route.NONE, 'the target configuration collides')
        walls = self.free_components
        if walls is not None and locked is None:
            found = self.through_cells(q, ends[0], walls)
            if found.ok:
                return found
        if walls is not None and all(walls.separated(q, end, locked) for end in ends):
            return Approach(None, Route.NONE, 'no collision-free joint move exists (proved on '
                            f'a {GRID_CELLS}^3 joint grid: the two configurations lie in '
                            'different components of its possibly free cells)')
        if not rrt:
            return Approach(None, Route.NONE, 'no collision-free joint move found (not '
                            f'straight, not through the certified cells of a {GRID_CELLS}^3 '
                            'joint grid; RRT-Connect not tried)')
        return self._rrt_move(q, ends, locked)

    def through_cells(self, q: np.ndarray, target: np.ndarray,
                      walls: FreeComponents) -> Approach:
        """Find a certified path from q (n,) to target (plus whole turns) through `walls`' cells.

        A chain of touching certified free cells (`FreeComponents.path`), certified again
        as every path is.
        """
        path = walls.path(q, target)
        if path is not None and self.certify(path):
            return Approach(path, Route.THROUGH_CELLS)
        return Approach(None, Route.NONE, 'no chain of certified free cells of the '
                        f'{walls.lattice.cells}^3 joint grid joins them')

    def _rrt_move(self, q: np.ndarray, ends: list[np.ndarray], locked: int | None) -> Approach:
        """RRT-Connect from q towards `ends` (lifts of one target), `locked` held; certified."""
        free = [j for j in range(self.robot.n_joints) if j != locked]
        for attempt in range(self.options.rrt_attempts):
            path = self._rrt_connect(q, ends, free)
            if path is not None and self.certify(path):
                return Approach(path, Route.RRT_CONNECT)
            log.debug('RRT-Connect attempt %d: %s', attempt + 1,
                      'no path' if path is None else 'the path failed its certificate')
        return Approach(None, Route.NONE, 'no collision-free joint move found (not straight, '
                        f'not by RRT-Connect in {self.options.rrt_attempts} x '
                        f'{self.options.rrt_time:g} s)')

    @cached_property
    def free_components(self) -> FreeComponents | None:
        """The grid that proves joint moves impossible, where it applies (else None)."""
        return FreeComponents.where_it_applies(self.checker.robot, self.checker.obstacles,
                                               self.options.margin)

    def path_to_goal(self, q: np.ndarray, x_g: np.ndarray, locked: int) -> Approach:
        """Find a certified path from q to a configuration reaching x_g, joint `locked` held.

        Goal configurations come from Newton in the failure hyperplane of `locked` through
        q, from `ik_seeds` random seeds; the `goal_candidates` nearest collision-free ones
        are tried in turn with `joint_move`.
        """
        robot = self.robot
        q = np.asarray(q, dtype=float)
        limits = robot.limits
        seeds = self.rng.uniform(limits[:, 0], limits[:, 1],
                                 size=(self.options.ik_seeds, robot.n_joints))
        seeds[:, locked] = q[locked]
        solved, converged = project_many(robot, np.asarray(x_g, dtype=float), seeds,
                                         fixed_joint=locked)
        solved = q + configuration_difference(solved[converged], q, robot.periodic)
        solved = solved[self.checker.min_clearance(solved, self.options.margin)
                        > self.options.margin] if len(solved) else solved
        if len(solved) == 0:
            return Approach(None, Route.NONE, f'no collision-free configuration reaches the '
                            f'goal with {robot.joint_names[locked]} locked')
        order = np.argsort(np.linalg.norm(solved - q, axis=1))
        distinct: list[np.ndarray] = []
        for theta in solved[order]:
            if all(np.max(np.abs(theta - other)) > 1e-3 for other in distinct):
                distinct.append(theta)
        reason = ''
        for theta in distinct[:self.options.goal_candidates]:
            move = self.joint_move(q, theta, locked)
            if move.ok:
                return move
            reason = move.reason
        return Approach(None, Route.NONE, f'no path to the goal with '
                        f'{robot.joint_names[locked]} locked: {reason}')

    # Certificate and OMPL -------------------------------------------------------------

    def certify(self, path: np.ndarray) -> bool:
        """Whether every point of the polyline (k, n) [rad] is clear by more than the margin."""
        path = np.asarray(path, dtype=float)
        if not np.all(np.isfinite(path)):
            return False
        dense = densify(path, self.options.certify_step)
        if len(dense) < 2:
            return self._valid(dense[0], 0.0)
        ok, _, _, _ = certify_polylines(self.checker, [dense], self.options.margin,
                                        self.options.certify_depth)
        return bool(ok)

    def _valid(self, theta: np.ndarray, extra: float = _RRT_EXTRA_CLEARANCE) -> bool:
        needed = self.options.margin + extra
        return bool(self.checker.min_clearance(theta[None, :], needed)[0] > needed)

    def _bounds(self, j: int, start: float, goals: list[float]) -> tuple[float, float]:
        """OMPL bounds of joint j [rad]: its limits, or a turn either way from the start.

        The space does not wrap: a periodic joint reaches its target either way round
        through the goals' two lifts, both within a turn of the start.
        """
        if self.robot.periodic[j]:
            return min(start - 2.0 * np.pi, *goals), max(start + 2.0 * np.pi, *goals)
        low, high = self.robot.limits[j]
        return min(low, start, *goals), max(high, start, *goals)

    def _rrt_connect(self, start: np.ndarray, goals: list[np.ndarray], free: list[int],
                     ) -> np.ndarray | None:
        """OMPL's RRT-Connect and its simplifier over the joints `free`; the others held.

        Any of `goals` (lifts of one target) ends the path. A motion is checked in one
        clearance batch of samples at most `rrt_step` apart (per state the checker's fixed
        cost would dominate); the segments of the result are certified by the caller.
        """
        from ompl import base as ob
        from ompl import geometric as og
        from ompl import util as ompl_util
        ompl_util.setLogLevel(ompl_util.LogLevel.LOG_WARN)
        space = ob.RealVectorStateSpace(len(free))
        bounds = ob.RealVectorBounds(len(free))
        for k, j in enumerate(free):
            low, high = self._bounds(j, float(start[j]), [float(g[j]) for g in goals])
            bounds.setLow(k, float(low))
            bounds.setHigh(k, float(high))
        space.setBounds(bounds)
        setup = og.SimpleSetup(space)
        whole = start.copy()

        def configuration(state) -> np.ndarray:
            whole[free] = [state[k] for k in range(len(free))]
            return whole.copy()

        setup.setStateValidityChecker(lambda state: self._valid(configuration(state)))
        information = setup.getSpaceInformation()
        information.setMotionValidator(_batch_motion_validator(
            information, configuration, self._valid_motion))
        def state_of(values: np.ndarray):
            state = space.allocState()
            for k, j in enumerate(free):
                state[k] = float(values[j])
            return state

        setup.setStartState(state_of(start))
        targets = ob.GoalStates(information)
        for goal in goals:
            targets.addState(state_of(goal))
        setup.setGoal(targets)
        setup.setPlanner(og.RRTConnect(information))
        if not (setup.solve(self.options.rrt_time) and setup.haveExactSolutionPath()):
            return None
        setup.simplifySolution()
        solution = setup.getSolutionPath()
        path = np.array([configuration(solution.getState(row))
                         for row in range(solution.getStateCount())])
        path[0] = start
        path[-1] = min(goals, key=lambda goal: float(np.max(np.abs(goal - path[-1]))))
        return path

    def _valid_motion(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether the samples of the segment a-b, `rrt_step` apart, are all clear."""
        needed = self.options.margin + _RRT_EXTRA_CLEARANCE
        samples = densify(np.stack([a, b]), self.options.rrt_step)
        return bool(self.checker.min_clearance(samples, needed).min() > needed)


def straight_move_ends(q: np.ndarray, target: np.ndarray, periodic: np.ndarray,
                       held: int | None = None) -> list[np.ndarray]:
    """Return the ends (n,) of the straight joint moves from q to target, shortest first.

    A periodic joint may reach its target turning either way, so an end may differ from
    `target` by whole turns; joint `held` keeps q's angle's nearest lift.
    """
    q = np.asarray(q, dtype=float)
    nearest = q + configuration_difference(target, q, periodic)
    options = []
    for j in range(len(q)):
        if periodic[j] and nearest[j] != q[j] and j != held:
            options.append((nearest[j], nearest[j] - np.sign(nearest[j] - q[j]) * 2.0 * np.pi))
        else:
            options.append((nearest[j],))
    ends = [np.array(choice) for choice in itertools.product(*options)]
    return sorted(ends, key=lambda end: float(np.linalg.norm(end - q)))


def _batch_motion_validator(information, configuration: Callable[[object], np.ndarray],
                            valid_motion: Callable[[np.ndarray, np.ndarray], bool]):
    """Return an OMPL MotionValidator that checks a motion with `valid_motion` in one go.

    RRT-Connect and the path simplifier call the two-state overload only; OMPL's own
    validators check a motion state by state, each a clearance call of its own.
    """
    from ompl import base as ob

    class BatchMotionValidator(ob.MotionValidator):
        def checkMotion(self, first, second, *last_valid) -> bool:  # noqa: N802 - OMPL's name
            return bool(valid_motion(configuration(first), configuration(second)))

    return BatchMotionValidator(information)
