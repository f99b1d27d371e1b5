"""The planner: the paper's Steps 1-6, then the self-check, then the choice of θ_s.

Candidates θ_s are the obstacle-free points of M_s, one per continuation step (the
manifold's `step_max` sets their spacing). Those passing the necessary condition (eq. 6)
on one free arc of M_g get a failure surface over the smallest windows of that arc that
hold a hit of every joint. Every such surface is built coarsely and scored by the
smallest clearance at its vertices; the best-scored is built at full resolution and
verified, then the next, until one passes. That criterion (recorded in the result's
stats) prefers the start whose whole recovery region stays farthest from obstacles over
the first start found.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from .angles import wrap_configuration
from .collision import CollisionChecker, point_clearance
from .errors import InputError
from .failure_planes import (
    FailurePlaneHit,
    chord_crossings,
    failure_plane_hits,
    goal_free_arcs,
    necessary_condition,
)
from .failure_surface import (
    FailureSurface,
    build_failure_surface,
    choose_hits,
    lift_goal_arc,
    smallest_windows,
)
from .manifolds import (
    ManifoldCache,
    ManifoldOptions,
    SelfMotionManifold,
    mark_obstacle_free,
    project_many,
    project_to_preimage,
)
from .result import PlanResult
from .scene import Scene
from .verification import VerificationOptions, verify_surface

log = logging.getLogger(__name__)

CRITERION = 'largest minimum clearance at the vertices of the failure surface'


@dataclass(frozen=True)
class PlannerOptions:
    """Resolutions [rad] and budgets of the planner."""

    manifold: ManifoldOptions = field(default_factory=ManifoldOptions)
    verification: VerificationOptions = field(default_factory=VerificationOptions)
    column_spacing: float = 0.06      # between the goal points of a web
    waypoint_spacing: float = 0.04    # between the waypoints of a web path, per joint
    coarse_waypoints: int = 8         # waypoints of each path of the ranking fans
    max_verifications: int = 40       # surfaces verified at most
    candidate_refinement: int = 4     # start candidates per manifold step on the retry


def check_plannable(scene: Scene) -> None:
    """Raise InputError when the scene's task cannot be planned (the CLI's exit code 2)."""
    robot, task = scene.robot, scene.task
    if task is None:
        raise InputError('task', 'is missing: planning needs task.start and task.goal')
    redundancy = robot.n_joints - robot.task_dim
    if redundancy < 1:
        raise InputError('robot.link_lengths', f'{robot.n_joints} joints give no redundancy '
                         f'for a {robot.task_dim}-D position task (need more than '
                         f'{robot.task_dim})')
    if redundancy > 1:
        raise InputError('robot.link_lengths', f'degree of redundancy {redundancy}: this '
                         'planner handles exactly one (self-motion curves, paper Sec. V)')
    for name, x in (('task.start', task.start), ('task.goal', task.goal)):
        if not robot.can_reach(np.asarray(x)):
            raise InputError(name, f'{list(x)} is out of the arm\'s reach')
    if np.linalg.norm(np.subtract(task.start, task.goal)) <= task.goal_tolerance:
        raise InputError('task.goal', 'equals task.start (within goal_tolerance): nothing '
                         'to plan')
    if scene.obstacles:
        inside = point_clearance(scene.obstacles, np.zeros(3)) <= robot.link_radius
        if inside.any():
            k = int(np.flatnonzero(inside)[0])
            raise InputError(f'obstacles[{k}]', 'covers the robot base: every configuration '
                             'collides')


def plan(scene: Scene, options: PlannerOptions | None = None,
         rng: np.random.Generator | None = None,
         progress: Callable[[str], None] | None = None,
         start_configuration: np.ndarray | None = None,
         cache: ManifoldCache | None = None) -> PlanResult:
    """Plan a failure-tolerant motion for the scene's task; see the module docstring.

    `rng` seeds the inverse-kinematics samples (default: seed 0, so plans repeat);
    `progress` receives a line per stage. With `start_configuration` (n,) [rad] only that
    θ_s is considered (moved onto M_s by Newton first): the plan says whether it is a
    failure-tolerant start. A `cache` keeps traced manifolds between calls. Raises
    InputError for an unplannable scene.
    """
    options = options or PlannerOptions()
    rng = rng if rng is not None else np.random.default_rng(0)
    report = progress or (lambda line: None)
    started = time.perf_counter()
    check_plannable(scene)
    robot, task = scene.robot, scene.task
    x_s, x_g = np.asarray(task.start), np.asarray(task.goal)
    checker = CollisionChecker(robot, scene.obstacles)
    margin = options.verification.margin

    # Steps 1-2: self-motion manifolds and their obstacle-free parts.
    report('tracing self-motion manifolds')
    cache = cache or ManifoldCache(size=2)
    M_s = tuple(mark_obstacle_free(b, checker)
                for b in cache.trace(robot, x_s, rng, options.manifold))
    M_g = tuple(mark_obstacle_free(b, checker)
                for b in cache.trace(robot, x_g, rng, options.manifold))
    for name, branches in (('task.start', M_s), ('task.goal', M_g)):
        if not branches:
            raise InputError(name, 'no configuration reaches it (inverse kinematics failed)')
    arcs = goal_free_arcs(M_g, margin)
    stats: dict = {'criterion': CRITERION, 'start_branches': len(M_s),
                   'goal_branches': len(M_g), 'goal_free_arcs': len(arcs)}
    arc_points = [M_g[arc.branch].arc_points(arc.first, arc.count) for arc in arcs]
    arc_laps = [arc.lap for arc in arcs]

    # Steps 3-6 and the self-check, over candidates one step apart along M_s and, when
    # that finds nothing, over candidates between them (a narrow band of good starts).
    if start_configuration is not None:
        refinements = [None]
    else:
        refinements = [1, options.candidate_refinement]
    for subdivisions in refinements:
        if subdivisions is None:
            candidates = _given_start(robot, x_s, start_configuration, checker, margin)
        else:
            candidates = _start_candidates(robot, x_s, M_s, subdivisions, checker, margin)
        search = _search(robot, x_g, task.goal_tolerance, candidates, arc_points, arc_laps,
                         checker, options, report)
        stats.update(search.stats, start_candidates=len(candidates),
                     candidate_subdivisions=subdivisions or 1)
        if search.surface is not None or not arcs:
            break
        report(f'no plan from {len(candidates)} starts; trying starts between them')
    stats['collision_checks'] = checker.checks
    stats['plan_time_s'] = time.perf_counter() - started
    log.info('plan %s in %.3f s%s', 'found' if search.surface is not None else 'not found',
             stats['plan_time_s'], f': {search.reason}' if search.reason else '')
    return PlanResult(search.surface is not None, robot.joint_names, search.reason,
                      search.surface, stats, M_s, M_g, search.theta_S, search.proposed,
                      robot.periodic)


@dataclass(frozen=True, eq=False)
class _Search:
    """The outcome of Steps 3-6 and the self-check over one set of start candidates."""

    surface: FailureSurface | None
    reason: str
    stats: dict
    theta_S: np.ndarray | None = None
    proposed: np.ndarray | None = None


def _search(robot, x_g: np.ndarray, goal_tolerance: float, candidates: np.ndarray,
            arc_points: list[np.ndarray], arc_laps: list[int], checker: CollisionChecker,
            options: PlannerOptions, report: Callable[[str], None]) -> _Search:
    """Run Steps 3-6 and the self-check for candidates (c, n) [rad] on the free arcs of M_g."""
    if len(candidates) == 0:
        return _Search(None, 'every start configuration collides (M_s^F is empty)', {})
    if not arc_points:
        return _Search(None, 'every goal configuration collides (M_g^F is empty)', {})

    # Step 3: the necessary condition, on M_g^F as a whole (the paper's Θ_s) and per arc.
    per_arc = np.stack([necessary_condition(robot, candidates, points) for points in arc_points])
    theta_S = candidates[per_arc.any(axis=0).all(axis=1)]
    single_arc = per_arc.all(axis=2)  # (arcs, C)
    stats = {'theta_S': len(theta_S)}
    if len(theta_S) == 0:
        return _Search(None, 'no candidate θ_s passes the necessary condition: some failure '
                       'plane misses M_g^F', stats, theta_S)
    if not single_arc.any():
        return _Search(None, 'the failure planes of every θ_s meet M_g^F only on different '
                       'obstacle-free arcs: no failure surface can join them', stats, theta_S)

    # Steps 4-6: failure surfaces, ranked by the clearance at their vertices.
    report(f'{len(theta_S)} start configurations pass the necessary condition; '
           'building failure surfaces')
    proposals = _rank_proposals(robot, candidates, arc_points, arc_laps, single_arc, checker,
                                options)
    proposed = candidates[sorted({p.candidate for p in proposals})]
    stats['surfaces_proposed'] = len(proposals)
    if not proposals:
        return _Search(None, 'no failure surface: every surface proposed hits an obstacle '
                       'at one of its vertices', stats, theta_S, proposed)

    # Self-check, best-ranked first: the first surface that passes wins.
    last_reason = 'every fine web hits an obstacle at a vertex'
    tried = 0
    for proposal in proposals[:options.max_verifications]:
        surface = _fine_surface(robot, x_g, candidates[proposal.candidate],
                                arc_points[proposal.arc], proposal.window, checker, options)
        if surface is None:
            continue
        tried += 1
        verdict = verify_surface(surface, checker, x_g, goal_tolerance, options.verification)
        if verdict.ok:
            report(f'verified the failure surface of start {tried} in the ranking')
            stats.update(surfaces_tried=tried, criterion_value_m=proposal.score,
                         min_clearance_m=verdict.min_clearance,
                         recovery_min_clearance_m=verdict.recovery_min_clearance,
                         goal_error_bound_m=verdict.max_goal_error,
                         clearance_samples=verdict.clearance_samples)
            return _Search(surface, '', stats, theta_S, proposed)
        last_reason = verdict.reason
        log.debug('surface rejected: %s', verdict.reason)
    stats['surfaces_tried'] = tried
    return _Search(None, f'check failed for all {tried} failure surfaces tried; the last: '
                   f'{last_reason}', stats, theta_S, proposed)


def _given_start(robot, x_s: np.ndarray, theta: np.ndarray, checker: CollisionChecker,
                 margin: float) -> np.ndarray:
    """Move the given start onto M_s: a (1, n) candidate, or (0, n) if it collides."""
    theta = np.asarray(theta, dtype=float)
    if theta.shape != (robot.n_joints,) or not np.all(np.isfinite(theta)):
        raise InputError('start_configuration', f'must be {robot.n_joints} finite angles')
    on_manifold = project_to_preimage(robot, x_s, theta)
    if on_manifold is None or np.max(np.abs(on_manifold - theta)) > 0.1:
        raise InputError('start_configuration', 'does not put the end effector at task.start')
    on_manifold = wrap_configuration(on_manifold, robot.periodic)[None, :]
    if checker.min_clearance(on_manifold)[0] <= margin:
        return np.empty((0, robot.n_joints))
    return on_manifold


def _start_candidates(robot, x_s: np.ndarray, branches: tuple[SelfMotionManifold, ...],
                      subdivisions: int, checker: CollisionChecker, margin: float,
                      ) -> np.ndarray:
    """Obstacle-free configurations (c, n) [rad] of M_s, wrapped, `subdivisions` per step.

    With one subdivision these are the traced points; with more, points between them
    are interpolated and moved back onto M_s by Newton.
    """
    points = []
    for branch in branches:
        if subdivisions == 1:
            points.append(branch.points[branch.free(margin)])
            continue
        ends = np.vstack([branch.points, branch.points[:1] + branch.period]) \
            if branch.closed else branch.points
        t = np.arange(subdivisions)[None, :, None] / subdivisions
        between = (ends[:-1, None] + t * (ends[1:, None] - ends[:-1, None])).reshape(
            -1, ends.shape[1])
        solved, converged = project_many(robot, x_s, between)
        solved = solved[converged]
        points.append(solved[checker.min_clearance(solved) > margin])
    return wrap_configuration(np.vstack(points), robot.periodic)


@dataclass(frozen=True)
class _Proposal:
    """A (θ_s, arc, window) whose coarse web is collision-free at every vertex."""

    score: float          # smallest vertex clearance [m] of the coarse web
    candidate: int
    arc: int
    window: tuple[float, float]


def _rank_proposals(robot, candidates: np.ndarray, arc_points: list[np.ndarray],
                    arc_laps: list[int], single_arc: np.ndarray, checker: CollisionChecker,
                    options: PlannerOptions) -> list[_Proposal]:
    """Score a coarse failure surface for each (θ_s, arc) passing eq. 6; best first.

    A coarse surface is the fan of straight paths from θ_s to its chord crossings (one per
    joint) and to a few points spread over the window, all scored in one clearance batch:
    a cheap screen, never a guarantee.
    """
    n = robot.n_joints
    proposals, fans = [], []
    for a, points in enumerate(arc_points):
        members = np.flatnonzero(single_arc[a])
        hits: list[list[list[FailurePlaneHit]]] = [[[] for _ in range(n)] for _ in members]
        for i in range(n):
            which, positions, thetas = chord_crossings(robot, candidates[members], points, i)
            for slot, position, theta in zip(which, positions, thetas, strict=True):
                hits[slot][i].append(FailurePlaneHit(i, theta, float(position)))
        for slot, c in enumerate(members):
            for window in (w for w in smallest_windows(hits[slot]) if w[0] < arc_laps[a]):
                fans.append(_coarse_fan(candidates[c], points, choose_hits(hits[slot], window),
                                        window, robot.periodic, options.coarse_waypoints))
                proposals.append((int(c), a, window))
    if not fans:
        return []
    clearance = checker.min_clearance(np.vstack(fans)).reshape(len(fans), -1).min(axis=1)
    margin = options.verification.margin
    scored = [_Proposal(float(score), *proposal)
              for score, proposal in zip(clearance, proposals, strict=True) if score > margin]
    return sorted(scored, key=lambda p: -p.score)


def _coarse_fan(theta_s: np.ndarray, arc_points: np.ndarray, hits: list[FailurePlaneHit],
                window: tuple[float, float], periodic: np.ndarray, waypoints: int) -> np.ndarray:
    """Points (m, n) [rad] of straight paths from θ_s to its hits and across the window."""
    lifted, lifted_hits = lift_goal_arc(theta_s, arc_points, hits, periodic)
    spread = np.linspace(window[0], window[1], 5)
    k = np.minimum(spread.astype(int), len(arc_points) - 2)
    t = (spread - k)[:, None]
    goals = np.vstack([[h.theta for h in lifted_hits],
                       lifted[k] + t * (lifted[k + 1] - lifted[k])])
    steps = np.arange(1, waypoints + 1)[:, None, None] / waypoints
    return (theta_s + steps * (goals - theta_s)).reshape(-1, len(theta_s))


def _fine_surface(robot, x_g: np.ndarray, theta_s: np.ndarray, arc_points: np.ndarray,
                  window: tuple[float, float], checker: CollisionChecker,
                  options: PlannerOptions) -> FailureSurface | None:
    """Build the web to verify: exact hits, full resolution, the clearest nominal path."""
    hits = failure_plane_hits(robot, x_g, theta_s, arc_points)
    inside = [[h for h in joint_hits if window[0] - 1 <= h.position <= window[1] + 1]
              for joint_hits in hits]
    if not all(inside):
        return None
    window = (min(h.position for hs in inside for h in hs),
              max(h.position for hs in inside for h in hs))
    chosen = choose_hits(inside, window)
    lifted, lifted_hits = lift_goal_arc(theta_s, arc_points, chosen, robot.periodic)
    surface = build_failure_surface(theta_s, lifted, lifted_hits, window,
                                    options.column_spacing, options.waypoint_spacing)
    clearance = checker.min_clearance(surface.vertices).reshape(surface.paths.shape[:2])
    if clearance.min() <= options.verification.margin:
        return None
    # Nominal path: the clearest, and among equally clear ones the shortest.
    lengths = np.linalg.norm(surface.goal_points - theta_s, axis=1)
    nominal = int(np.lexsort((lengths, -clearance.min(axis=1)))[0])
    return replace(surface, nominal=nominal)
