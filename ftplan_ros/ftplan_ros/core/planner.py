"""The planner: the paper's Steps 1-6, then the self-check, then the choice of θ_s.

Candidates θ_s are the obstacle-free points of M_s (thinned). Those passing the necessary
condition (eq. 6) on one free arc of M_g get a failure surface over the smallest windows
of that arc holding a hit of every joint. Surfaces are ranked by the smallest clearance
at their vertices and verified in that order; among the first few that pass, the one
whose certified S_F keeps the largest minimum clearance wins. That criterion, recorded
in the result's stats, prefers starts whose whole recovery region stays far from
obstacles over the first start found.
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
    project_to_preimage,
)
from .result import PlanResult
from .scene import Scene
from .verification import Verdict, VerificationOptions, certify_surface, check_recoveries

log = logging.getLogger(__name__)

CRITERION = 'largest minimum clearance over the certified failure surface'


@dataclass(frozen=True)
class PlannerOptions:
    """Resolutions [rad] and budgets of the planner."""

    manifold: ManifoldOptions = field(default_factory=ManifoldOptions)
    verification: VerificationOptions = field(default_factory=VerificationOptions)
    candidate_spacing: float = 0.02   # between θ_s candidates along M_s^F
    column_spacing: float = 0.06      # between the goal points of a web
    waypoint_spacing: float = 0.04    # between the waypoints of a web path, per joint
    coarse_spacing: float = 0.25      # column and waypoint spacing of the ranking webs
    windows_per_candidate: int = 2    # hit windows tried for each θ_s and arc
    surfaces_to_compare: int = 3      # verified surfaces compared before choosing
    max_verifications: int = 40       # surfaces verified at most


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
    stats: dict = {'criterion': CRITERION}

    def finish(surface: FailureSurface | None, reason: str = '', **extra) -> PlanResult:
        stats.update(extra)
        stats['collision_checks'] = checker.checks
        stats['plan_time_s'] = time.perf_counter() - started
        log.info('plan %s in %.3f s%s', 'found' if surface is not None else 'not found',
                 stats['plan_time_s'], f': {reason}' if reason else '')
        proposed = None if proposals is None else candidates[
            sorted({proposal.candidate for proposal in proposals})]
        return PlanResult(surface is not None, robot.joint_names, reason, surface, stats,
                          M_s, M_g, theta_S, proposed, robot.periodic)

    # Steps 1-2: self-motion manifolds and their obstacle-free parts.
    report('tracing self-motion manifolds')
    cache = cache or ManifoldCache(size=2)
    M_s = tuple(mark_obstacle_free(b, checker)
                for b in cache.trace(robot, x_s, rng, options.manifold))
    M_g = tuple(mark_obstacle_free(b, checker)
                for b in cache.trace(robot, x_g, rng, options.manifold))
    theta_S = proposals = None
    for name, branches in (('task.start', M_s), ('task.goal', M_g)):
        if not branches:
            raise InputError(name, 'no configuration reaches it (inverse kinematics failed)')
    if start_configuration is None:
        candidates = _start_candidates(M_s, margin, options.candidate_spacing, robot.periodic)
    else:
        candidates = _given_start(robot, x_s, start_configuration, checker, margin)
    arcs = goal_free_arcs(M_g, margin)
    stats.update(start_branches=len(M_s), goal_branches=len(M_g),
                 start_candidates=len(candidates), goal_free_arcs=len(arcs))
    if len(candidates) == 0:
        return finish(None, 'every start configuration collides (M_s^F is empty)')
    if not arcs:
        return finish(None, 'every goal configuration collides (M_g^F is empty)')

    # Step 3: the necessary condition, on M_g^F as a whole (the paper's Θ_s) and per arc.
    arc_points = [M_g[arc.branch].arc_points(arc.first, arc.count) for arc in arcs]
    per_arc = np.stack([necessary_condition(robot, candidates, points) for points in arc_points])
    theta_S = candidates[per_arc.any(axis=0).all(axis=1)]
    single_arc = per_arc.all(axis=2)  # (arcs, C)
    stats['theta_S'] = len(theta_S)
    if len(theta_S) == 0:
        return finish(None, 'no candidate θ_s passes the necessary condition: some failure '
                      'plane misses M_g^F')
    if not single_arc.any():
        return finish(None, 'the failure planes of every θ_s meet M_g^F only on different '
                      'obstacle-free arcs: no failure surface can join them')

    # Steps 4-6: failure surfaces, ranked by the clearance at their vertices.
    report(f'{len(theta_S)} start configurations pass the necessary condition; '
           'building failure surfaces')
    proposals = _rank_proposals(robot, x_g, candidates, arc_points, single_arc, checker,
                                options)
    stats['surfaces_proposed'] = len(proposals)
    if not proposals:
        return finish(None, 'no failure surface: every surface proposed hits an obstacle '
                      'at one of its vertices')

    # Self-check, best-ranked first: certify a few surfaces, then the clearest one must
    # also pass the explicit recovery checks (or the next clearest is taken).
    certified: list[tuple[FailureSurface, Verdict]] = []
    last_reason = 'every fine web hits an obstacle at a vertex'
    tried = 0
    for proposal in proposals:
        if tried >= options.max_verifications or len(certified) >= options.surfaces_to_compare:
            break
        surface = _fine_surface(robot, x_g, candidates[proposal.candidate],
                                arc_points[proposal.arc], proposal.window, checker, options)
        if surface is None:
            continue
        tried += 1
        verdict = certify_surface(surface, checker, x_g, task.goal_tolerance,
                                  options.verification)
        if verdict.ok:
            certified.append((surface, verdict))
            report(f'certified failure surface {len(certified)} '
                   f'(clearance {verdict.min_clearance:.3f} m)')
        else:
            last_reason = verdict.reason
            log.debug('surface rejected: %s', verdict.reason)
    stats['surfaces_certified'] = len(certified)
    stats['surfaces_tried'] = tried
    for surface, verdict in sorted(certified, key=lambda item: -item[1].min_clearance):
        verdict = check_recoveries(surface, checker, x_g, task.goal_tolerance, verdict,
                                   options.verification)
        if verdict.ok:
            return finish(surface, min_clearance_m=verdict.min_clearance,
                          recovery_min_clearance_m=verdict.recovery_min_clearance,
                          goal_error_bound_m=verdict.max_goal_error,
                          clearance_samples=verdict.clearance_samples)
        last_reason = verdict.reason
        log.error('a certified surface failed its recovery check: %s', verdict.reason)
    return finish(None, f'check failed for all {tried} failure surfaces tried; the last: '
                  f'{last_reason}')


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


def _start_candidates(branches: tuple[SelfMotionManifold, ...], margin: float,
                      spacing: float, periodic: np.ndarray) -> np.ndarray:
    """Obstacle-free points of M_s (c, n) [rad], wrapped, about `spacing` apart."""
    chosen = []
    for branch in branches:
        free = branch.free(margin)
        last = None
        for theta, ok in zip(branch.points, free, strict=True):
            if ok and (last is None or np.max(np.abs(theta - last)) >= spacing):
                chosen.append(theta)
                last = theta
    if not chosen:
        return np.empty((0, len(periodic)))
    return wrap_configuration(np.array(chosen), periodic)


@dataclass(frozen=True)
class _Proposal:
    """A (θ_s, arc, window) whose coarse web is collision-free at every vertex."""

    score: float          # smallest vertex clearance [m] of the coarse web
    candidate: int
    arc: int
    window: tuple[float, float]


def _rank_proposals(robot, x_g: np.ndarray, candidates: np.ndarray, arc_points: list[np.ndarray],
                    single_arc: np.ndarray, checker: CollisionChecker, options: PlannerOptions,
                    ) -> list[_Proposal]:
    """Coarse webs for each (θ_s, arc) passing eq. 6, scored in one batch; best first.

    The coarse web uses the chord points of the failure-plane crossings (no Newton) and
    a few columns and waypoints: a cheap screen, never a guarantee.
    """
    proposals, webs = [], []
    for a, c in zip(*np.nonzero(single_arc), strict=True):
        theta_s = candidates[c]
        hits = failure_plane_hits(robot, x_g, theta_s, arc_points[a], refine=False)
        for window in smallest_windows(hits)[:options.windows_per_candidate]:
            chosen = choose_hits(hits, window)
            lifted, lifted_hits = lift_goal_arc(theta_s, arc_points[a], chosen, robot.periodic)
            web = build_failure_surface(theta_s, lifted, lifted_hits, window,
                                        options.coarse_spacing, options.coarse_spacing)
            proposals.append((int(c), int(a), window))
            webs.append(web.vertices)
    if not webs:
        return []
    clearance = checker.min_clearance(np.vstack(webs))
    bounds = np.cumsum([0] + [len(web) for web in webs])
    scored = [_Proposal(float(clearance[lo:hi].min()), *proposal)
              for proposal, lo, hi in zip(proposals, bounds[:-1], bounds[1:], strict=True)]
    margin = options.verification.margin
    return sorted((p for p in scored if p.score > margin), key=lambda p: -p.score)


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
