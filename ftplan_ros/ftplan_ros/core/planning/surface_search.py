"""The paper's Steps 1-6 and the self-check, for one degree of redundancy (r = n - m = 1).

Candidates θ_s are the obstacle-free points of M_s, one per continuation step (the
manifold's `step_max` sets their spacing). Those passing the necessary condition (eq. 6)
for every tolerated joint on one free arc of M_g get a failure surface over the smallest
windows of that arc that hold a hit of every tolerated joint. Every such surface is
built coarsely and scored by the smallest clearance at its vertices; the best-scored is
built at full resolution and verified, then the next, until one passes. That criterion
(recorded in the result's stats) prefers the start whose whole recovery region stays
farthest from obstacles over the first start found.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numba
import numpy as np

from ..collision.blocking import find_blocking
from ..collision.checker import CollisionChecker
from ..errors import InputError
from ..model.angles import whole_turns, wrap_configuration
from ..model.scene import Scene
from ..paper.failure_planes import (
    chord_crossings,
    failure_plane_hits,
    goal_free_arcs,
    necessary_condition,
)
from ..paper.failure_surface import (
    FailureSurface,
    build_failure_surface,
    choose_hits,
    lift_goal_arc,
    smallest_windows,
)
from ..paper.held_joints import HELD_TOLERANCE, held_joints, same_angle
from ..paper.manifolds import (
    ManifoldCache,
    SelfMotionManifold,
    mark_obstacle_free,
    project_many,
    project_to_preimage,
)
from ..paper.options import PlannerOptions
from ..paper.result import PlanResult
from ..paper.verification import verify_surface

log = logging.getLogger(__name__)

CRITERION = 'largest minimum clearance at the vertices of the failure surface'
# [m] the ranking's clearances are cheap lower bounds (checker.py), tight below this
_RANKING_CLEARANCE = 0.1
# [rad] how far a start between two traced points of M_s may take a joint past both: a
# whole continuation step (ManifoldOptions.step_max), where Newton moves it by far less
_FINER_SLACK = 0.05


@dataclass(frozen=True, eq=False)
class _Search:
    """The outcome of Steps 3-6 and the self-check over one set of start candidates."""

    surface: FailureSurface | None
    reason: str
    stats: dict = field(default_factory=dict)
    necessary_starts: np.ndarray | None = None
    proposed: np.ndarray | None = None
    blocked_joints: tuple[tuple[str, ...], ...] = ()  # as PlanResult's
    start_preferred: bool = False


@dataclass(frozen=True)
class _Proposal:
    """A (θ_s, arc, window) whose coarse web is collision-free at every vertex."""

    score: float          # smallest vertex clearance [m] of the coarse web
    candidate: int
    arc: int
    window: tuple[float, float]


@dataclass(frozen=True, eq=False)
class _Ranking:
    """Proposals as arrays, best first.

    Scores (P,) [m] (as `_Proposal.score`), candidates (P,), arcs (P,), windows (P, 2).
    """

    scores: np.ndarray
    candidates: np.ndarray
    arcs: np.ndarray
    windows: np.ndarray

    def best(self, count: int) -> list[_Proposal]:
        """Return the first `count` proposals."""
        return [_Proposal(float(self.scores[k]), int(self.candidates[k]), int(self.arcs[k]),
                          (float(self.windows[k, 0]), float(self.windows[k, 1])))
                for k in range(min(count, len(self.scores)))]


class SurfaceSearch:
    """Plan a scene whose robot has one degree of redundancy (see the module docstring).

    `scene.tolerated_joints` are the joints whose locks the surface is built for; the
    others may block the way to the goal when they lock. A `checker` for the scene's
    robot and obstacles may be passed in to share it. `prefer_starts` maps start
    candidates (c, n) to a mask (c,) of those to search first (issue 10: approach.py's
    starts reachable from the arm along M_s^F); all of them are searched only when none
    of those plans.
    """

    def __init__(self, scene: Scene, options: PlannerOptions, rng: np.random.Generator,
                 report: Callable[[str], None], cache: ManifoldCache,
                 checker: CollisionChecker | None = None,
                 prefer_starts: Callable[[np.ndarray], np.ndarray] | None = None):
        self.scene = scene
        self.robot = scene.robot
        self.task = scene.task
        self.options = options
        self.rng = rng
        self.report = report
        self.cache = cache
        self.joints = scene.tolerated_joints
        # Tolerated joints held still over the web (held_joints.py) and the others, whose
        # failure planes cross M_g^F; set once the manifolds are traced.
        self.held: tuple[int, ...] = ()
        self.moving = self.joints
        self._manifolds: tuple | None = None
        self.margin = options.verification.margin
        self.checker = checker or CollisionChecker(self.robot, scene.obstacles)
        self.prefer_starts = prefer_starts
        self.x_s = np.asarray(self.task.start, dtype=float)
        self.x_g = np.asarray(self.task.goal, dtype=float)

    def run(self, start_configuration: np.ndarray | None = None,
            subdivisions: tuple[int, ...] | None = None) -> PlanResult:
        """Run Steps 1-6 and the self-check; with a start configuration, only that θ_s.

        Start candidates come in rounds of `subdivisions` per manifold step, each round
        only when the ones before found nothing: by default one, then
        `options.candidate_refinement`.
        """
        M_s, M_g = self.manifolds()
        self._hold_still(M_s, M_g)
        arcs = goal_free_arcs(M_g, self.margin)
        stats: dict = {'criterion': CRITERION, 'start_branches': len(M_s),
                       'goal_branches': len(M_g), 'goal_free_arcs': len(arcs)}
        if self.held:
            stats['held_joints'] = [self.robot.joint_names[j] for j in self.held]
        arc_points = [M_g[arc.branch].arc_points(arc.first, arc.count) for arc in arcs]
        arc_laps = [arc.lap for arc in arcs]
        # Candidates one step apart along M_s and, when that finds nothing, between them
        # (a narrow band of good starts).
        refinements = [None] if start_configuration is not None else \
            list(subdivisions or (1, self.options.candidate_refinement))
        blocked: tuple[tuple[str, ...], ...] = ()
        for per_step in refinements:
            if per_step is None:
                candidates = self._given_start(start_configuration)
            else:
                candidates = self._start_candidates(M_s, per_step)
            search = self._search_preferred(candidates, arc_points, arc_laps)
            stats.update(search.stats, start_candidates=len(candidates),
                         candidate_subdivisions=per_step or 1)
            # A round whose starts pass eq. 6 keeps the joints that blocked the one before
            # (as stats does).
            blocked = search.blocked_joints or blocked
            if search.surface is not None or not arcs:
                break
            beyond = self._out_of_reach_of_every_arc(M_s, arc_points)
            if beyond:
                self.report(f'no start between them can pass eq. (6) either: {beyond}')
                break
            self.report(f'no plan from {len(candidates)} starts; trying starts between them')
        if search.surface is None and start_configuration is None:
            search = self._explain_nothing_free(search, M_s, M_g, len(candidates), len(arcs))
            stats.update(search.stats)
        stats['collision_checks'] = self.checker.checks
        stats['tolerated_joints'] = [self.robot.joint_names[i] for i in self.joints]
        return PlanResult(search.surface is not None, self.robot.joint_names, search.reason,
                          search.surface, stats, M_s, M_g, search.necessary_starts, search.proposed,
                          self.robot.periodic, goal_free_arcs=len(arcs), blocked_joints=blocked,
                          start_preferred=search.start_preferred)

    def for_joints(self, names: list[str]) -> SurfaceSearch:
        """Return a search of the same task tolerating the named joints.

        It shares this search's checker and, once traced, its manifolds with their
        clearances (the task and the obstacles are the same).
        """
        other = SurfaceSearch(self.scene.with_tolerated(names), self.options, self.rng,
                              self.report, self.cache, self.checker)
        other._manifolds = self._manifolds
        return other

    def count_feasible_starts(self, start_configuration: np.ndarray | None = None) -> int:
        """Run Steps 1-3 alone: how many start candidates pass eq. 6 on one free arc of M_g^F.

        Candidates as `run`'s first round (or the given start alone). The curves of
        redundancy r >= 2 are ranked by it (curves.py).
        """
        M_s, M_g = self.manifolds()
        self._hold_still(M_s, M_g)
        candidates = self._start_candidates(M_s, 1) if start_configuration is None \
            else self._given_start(start_configuration)
        passing = np.zeros(len(candidates), dtype=bool)
        for arc in goal_free_arcs(M_g, self.margin):
            points = M_g[arc.branch].arc_points(arc.first, arc.count)
            passing |= self._necessary_condition(candidates, points).all(axis=1)
        return int(passing.sum())

    def manifolds(self) -> tuple[tuple[SelfMotionManifold, ...], tuple[SelfMotionManifold, ...]]:
        """Trace M_s and M_g with the clearance of their points (Steps 1-2), once per search."""
        if self._manifolds is None:
            self._manifolds = self._trace_manifolds()
        return self._manifolds

    def _trace_manifolds(self):
        """Trace the branches of M_s and M_g and mark their obstacle-free points."""
        self.report('tracing self-motion manifolds')
        manifolds = []
        for name, x in (('task.start', self.x_s), ('task.goal', self.x_g)):
            branches = self.cache.trace(self.robot, x, self.rng, self.options.manifold)
            if not branches:
                raise InputError(name, 'no configuration reaches it (inverse kinematics '
                                 'failed)')
            manifolds.append(tuple(mark_obstacle_free(b, self.checker, self.margin)
                                   for b in branches))
        return manifolds[0], manifolds[1]

    def _out_of_reach_of_every_arc(self, M_s: tuple[SelfMotionManifold, ...],
                                   arc_points: list[np.ndarray]) -> str:
        """Say which moving joint's angles along M_s miss those of every free arc, or ''.

        Eq. 6 for joint i needs θ_s,i between two neighbouring values θ_i of a free arc.
        The finer round's starts lie between neighbouring points of M_s, moved back onto
        it by Newton (by far less than `_FINER_SLACK`), so their θ_i stay within the
        branch's range widened by that slack: when that misses every arc's range, none of
        them passes and the round is skipped. Periodic joints are not screened.
        """
        for j in self.moving:
            if self.robot.periodic[j]:
                continue
            starts = [(b.points[:, j].min() - _FINER_SLACK, b.points[:, j].max() + _FINER_SLACK)
                      for b in M_s]
            if not any(low <= points[:, j].max() and points[:, j].min() <= high
                       for low, high in starts for points in arc_points):
                return (f'the angles of {self.robot.joint_names[j]} along M_s miss those of '
                        'every free arc of M_g')
        return ''

    def _hold_still(self, M_s: tuple[SelfMotionManifold, ...],
                    M_g: tuple[SelfMotionManifold, ...]) -> None:
        """Split the tolerated joints into those held still and those that move.

        A joint is held when its angle is one value along every branch of M_s and M_g
        (held_joints.py) and some other tolerated joint moves: the web of those is what
        carries the plan.
        """
        held = held_joints(M_s, M_g, self.joints)
        if len(held) < len(self.joints):
            self.held = held
            self.moving = tuple(j for j in self.joints if j not in held)

    def _search_preferred(self, candidates: np.ndarray, arc_points: list[np.ndarray],
                          arc_laps: list[int]) -> _Search:
        """Run `_search` on the candidates `prefer_starts` marks, then on all of them."""
        if self.prefer_starts is not None:
            preferred = candidates[np.asarray(self.prefer_starts(candidates), dtype=bool)]
            search = self._search(preferred, arc_points, arc_laps) if len(preferred) else None
            if search is not None and search.surface is not None:
                return replace(search, stats=dict(search.stats, preferred_starts=len(preferred),
                                                  start_preferred=True), start_preferred=True)
        search = self._search(candidates, arc_points, arc_laps)
        if self.prefer_starts is not None:
            search = replace(search, stats=dict(search.stats, start_preferred=False))
        return search

    def _explain_nothing_free(self, search: _Search, M_s: tuple[SelfMotionManifold, ...],
                              M_g: tuple[SelfMotionManifold, ...], starts: int,
                              arcs: int) -> _Search:
        """Say what blocks M_s (or M_g) when none of it is free: collision/blocking.py."""
        if starts:
            if arcs:
                return search
            which, branches = 'goal', M_g
        else:
            which, branches = 'start', M_s
        blocking = find_blocking(self.checker, np.vstack([b.points for b in branches]),
                                 self.margin)
        return replace(search, reason=f'{search.reason}: {blocking.describe(which)}',
                       stats=dict(search.stats, nothing_free={'manifold': which,
                                                              **blocking.to_json()}))

    # Steps 3-6 ----------------------------------------------------------------------

    def _search(self, candidates: np.ndarray, arc_points: list[np.ndarray],
                arc_laps: list[int]) -> _Search:
        """Run Steps 3-6 and the self-check for candidates (c, n) [rad] on the free arcs."""
        if len(candidates) == 0:
            return _Search(None, 'every start configuration collides (M_s^F is empty)')
        if not arc_points:
            return _Search(None, 'every goal configuration collides (M_g^F is empty)')

        # Step 3: the necessary condition, on M_g^F as a whole (the paper's Θ_s) and per arc.
        per_arc = np.stack([self._necessary_condition(candidates, points)
                            for points in arc_points])  # (arcs, C, J)
        necessary_starts = candidates[per_arc.any(axis=0).all(axis=1)]
        single_arc = per_arc.all(axis=2)  # (arcs, C)
        stats: dict = {'theta_S': len(necessary_starts)}
        if len(necessary_starts) == 0:
            options = _blocking_joints(per_arc.any(axis=0), self.joints)
            blocked = tuple(tuple(self.robot.joint_names[j] for j in joints)
                            for joints in options)
            stats['blocked_joints'] = [list(names) for names in blocked]
            everywhere = not per_arc.any(axis=(0, 1))[self.joints.index(options[0][0])]
            reason = _necessary_condition_reason(self.robot.joint_names, options, everywhere,
                                                 arc_points)
            return _Search(None, reason, stats, necessary_starts, blocked_joints=blocked)
        if not single_arc.any():
            return _Search(None, 'the failure planes of every θ_s meet M_g^F only on '
                           'different obstacle-free arcs: no failure surface can join them',
                           stats, necessary_starts)

        # Steps 4-6: failure surfaces, ranked by the clearance at their vertices.
        self.report(f'{len(necessary_starts)} start configurations pass the necessary condition; '
                    'building failure surfaces')
        ranking = self._rank_proposals(candidates, arc_points, arc_laps, single_arc)
        proposed = candidates[np.unique(ranking.candidates)]
        stats['surfaces_proposed'] = len(ranking.scores)
        if not len(ranking.scores):
            return _Search(None, 'no failure surface: every surface proposed hits an obstacle '
                           'at one of its vertices', stats, necessary_starts, proposed)
        return self._verify_best(candidates, arc_points, ranking, stats, necessary_starts, proposed)

    def _necessary_condition(self, candidates: np.ndarray, points: np.ndarray) -> np.ndarray:
        """Test eq. 6 on one free arc (a, n): (C, J) bool over the tolerated joints.

        A moving joint's failure plane must cross the arc; a held joint's must hold it.
        """
        passing = np.empty((len(candidates), len(self.joints)), dtype=bool)
        moving = [self.joints.index(j) for j in self.moving]
        passing[:, moving] = necessary_condition(self.robot, candidates, points, self.moving)
        for j in self.held:
            passing[:, self.joints.index(j)] = same_angle(candidates, points, j,
                                                          bool(self.robot.periodic[j]))
        return passing

    def _verify_best(self, candidates: np.ndarray, arc_points: list[np.ndarray],
                     ranking: _Ranking, stats: dict, necessary_starts: np.ndarray,
                     proposed: np.ndarray) -> _Search:
        """Self-check, best-ranked first: the first surface that passes wins."""
        last_reason = ''
        tried = 0
        ranked = ranking.best(self.options.max_verifications)
        for rank, proposal in enumerate(ranked, start=1):
            surface = self._fine_surface(candidates[proposal.candidate],
                                         arc_points[proposal.arc], proposal.window)
            if surface is None:
                continue
            tried += 1
            # A line per surface: one near an obstacle may take seconds to certify, and a
            # caller's deadline (the planner node's plan_timeout) is checked at each line.
            self.report(f'self-check of failure surface {rank} of {len(ranked)}')
            verdict = verify_surface(surface, self.checker, self.task,
                                     self.options.verification)
            if verdict.ok:
                self.report(f'verified the failure surface of start {tried} in the ranking')
                stats.update(surfaces_tried=tried, criterion_value_m=proposal.score,
                             min_clearance_m=verdict.min_clearance,
                             recovery_min_clearance_m=verdict.recovery_min_clearance,
                             goal_error_bound_m=verdict.max_goal_error,
                             orientation_error_bound_rad=verdict.max_orientation_error,
                             clearance_samples=verdict.clearance_samples)
                return _Search(surface, '', stats, necessary_starts, proposed)
            last_reason = verdict.reason
            log.debug('surface rejected: %s', verdict.reason)
        stats['surfaces_tried'] = tried
        if not tried:
            return _Search(None, f'none of the {len(ranked)} best failure surfaces proposed '
                           'reached the self-check: at full resolution each web hits an '
                           'obstacle at a vertex or misses the failure plane of a joint',
                           stats, necessary_starts, proposed)
        return _Search(None, f'check failed for all {tried} failure surfaces tried; the last: '
                       f'{last_reason}', stats, necessary_starts, proposed)

    def _given_start(self, theta: np.ndarray) -> np.ndarray:
        """Move the given start onto M_s: a (1, n) candidate, or (0, n) if it collides."""
        robot = self.robot
        theta = np.asarray(theta, dtype=float)
        if theta.shape != (robot.n_joints,) or not np.all(np.isfinite(theta)):
            raise InputError('start_configuration', f'must be {robot.n_joints} finite angles')
        on_manifold = project_to_preimage(robot, self.x_s, theta)
        if on_manifold is None or np.max(np.abs(on_manifold - theta)) > 0.1:
            raise InputError('start_configuration', 'does not put the tool at task.start')
        on_manifold = wrap_configuration(on_manifold, robot.periodic)[None, :]
        if not self.checker.min_clearance(on_manifold, self.margin)[0] > self.margin:  # or NaN
            return np.empty((0, robot.n_joints))
        return on_manifold

    def _start_candidates(self, branches: tuple[SelfMotionManifold, ...],
                          subdivisions: int) -> np.ndarray:
        """Obstacle-free configurations (c, n) [rad] of M_s, wrapped, `subdivisions` per step.

        With one subdivision these are the traced points; with more, points between them
        are interpolated and moved back onto M_s by Newton.
        """
        points = [np.empty((0, self.robot.n_joints))]
        for branch in branches:
            if subdivisions == 1:
                points.append(branch.points[branch.free(self.margin)])
                continue
            ends = np.vstack([branch.points, branch.points[:1] + branch.period]) \
                if branch.closed else branch.points
            t = np.arange(subdivisions)[None, :, None] / subdivisions
            between = (ends[:-1, None] + t * (ends[1:, None] - ends[:-1, None])).reshape(
                -1, ends.shape[1])
            solved, converged = project_many(self.robot, self.x_s, between)
            solved = solved[converged & _within_limits(self.robot, solved)]
            clear = self.checker.min_clearance(solved, self.margin, refine=False)
            points.append(solved[clear > self.margin])
        return wrap_configuration(np.vstack(points), self.robot.periodic)

    def _rank_proposals(self, candidates: np.ndarray, arc_points: list[np.ndarray],
                        arc_laps: list[int], single_arc: np.ndarray) -> _Ranking:
        """Score a coarse failure surface for each (θ_s, arc) passing eq. 6; best first.

        A coarse surface is the fan of straight paths from θ_s to its chord crossings (one
        per tolerated joint) and to a few points spread over the window, all scored in one
        clearance batch: a cheap screen, never a guarantee.
        """
        owners, arcs, windows, fans = [], [], [], []
        for a, points in enumerate(arc_points):
            members = np.flatnonzero(single_arc[a])
            crossings = [chord_crossings(self.robot, candidates[members], points, i)
                         for i in self.moving]
            slots, spans, chosen = smallest_windows(
                np.concatenate([which for which, _, _ in crossings]),
                np.concatenate([np.full(len(which), k) for k, (which, _, _) in
                                enumerate(crossings)]),
                np.concatenate([positions for _, positions, _ in crossings]),
                len(members), len(self.moving), arc_laps[a])
            fans.append(np.concatenate([thetas for _, _, thetas in crossings])[chosen])
            owners.append(members[slots])
            arcs.append(np.full(len(slots), a))
            windows.append(spans)
        owners, arcs, windows = (np.concatenate(v) if v else np.zeros(0, dtype=np.int64)
                                 for v in (owners, arcs, windows))
        if not len(owners):
            return _Ranking(np.zeros(0), owners, arcs, np.zeros((0, 2)))
        fans = _coarse_fans(candidates, arc_points, owners, arcs, windows, np.concatenate(fans),
                            self.moving, self.robot.periodic, self.options.coarse_waypoints)
        clearance = self.checker.min_clearance(fans.reshape(-1, fans.shape[-1]),
                                               self.margin + _RANKING_CLEARANCE,
                                               refine=False).reshape(len(fans), -1).min(axis=1)
        kept = np.flatnonzero(clearance > self.margin)
        kept = kept[np.argsort(-clearance[kept], kind='stable')]  # best first, ties in order
        return _Ranking(clearance[kept], owners[kept], arcs[kept], windows[kept])

    def _fine_surface(self, theta_s: np.ndarray, arc_points: np.ndarray,
                      window: tuple[float, float]) -> FailureSurface | None:
        """Build the web to verify: exact hits, full resolution, the clearest nominal path."""
        hits = failure_plane_hits(self.robot, self.x_g, theta_s, arc_points, self.moving)
        inside = [[h for h in joint_hits if window[0] - 1 <= h.position <= window[1] + 1]
                  for joint_hits in hits]
        if not all(inside):
            return None
        window = (min(h.position for hs in inside for h in hs),
                  max(h.position for hs in inside for h in hs))
        chosen = choose_hits(inside, window)
        lifted, lifted_hits = lift_goal_arc(theta_s, arc_points, chosen, self.robot.periodic)
        surface = self._hold(build_failure_surface(theta_s, lifted, lifted_hits, window,
                                                   self.options.column_spacing,
                                                   self.options.waypoint_spacing))
        clearance = self.checker.min_clearance(surface.vertices, self.margin).reshape(
            surface.paths.shape[:2])
        if not clearance.min() > self.margin:  # or NaN
            return None
        # Nominal path: the clearest, and among equally clear ones the shortest.
        lengths = np.linalg.norm(surface.goal_points - theta_s, axis=1)
        nominal = int(np.lexsort((lengths, -clearance.min(axis=1)))[0])
        hit_of = dict(zip(surface.tolerated, surface.hit_paths, strict=True))
        return FailureSurface(surface.paths, nominal,
                              tuple(hit_of.get(j, nominal) for j in self.joints), self.joints)

    def _hold(self, surface: FailureSurface) -> FailureSurface:
        """Return the web with every held joint at its θ_s value exactly (held_joints.py).

        Its goal points had that value to within the rounding of Newton's method (their
        task errors are checked again with the web).
        """
        if not self.held:
            return surface
        paths = np.array(surface.paths)
        held = list(self.held)
        paths[..., held] = surface.theta_s[held]
        return replace(surface, paths=paths)


def _blocking_joints(passing: np.ndarray, joints: tuple[int, ...]) -> list[list[int]]:
    """Find the sets of joints whose failure planes keep the candidates from eq. 6.

    `passing` (C, J) says from which candidate the failure plane of which tolerated joint
    (`joints`, J) meets M_g^F. Joints that no candidate passes block every plan: they are
    the one set. Otherwise the sets missed by the candidates that miss the fewest joints
    are the options, the most common first (`plan` tries the others' plans in turn).
    """
    never = [j for k, j in enumerate(joints) if not passing[:, k].any()]
    if never:
        return [never]
    misses = ~passing
    count = misses.sum(axis=1)
    sets, counts = np.unique(misses[count == count.min()], axis=0, return_counts=True)
    return [[j for k, j in enumerate(joints) if row[k]]
            for row in sets[np.argsort(-counts, kind='stable')]]


def _necessary_condition_reason(names: tuple[str, ...], options: list[list[int]],
                                everywhere: bool, arc_points: list[np.ndarray]) -> str:
    """Say which joints' failure planes miss M_g^F, and why when a joint never moves.

    `everywhere`: the first option's joints miss from every start (else each start
    misses some joint, the nearest ones one of the options).
    """
    if everywhere:
        reason = ('no candidate θ_s passes the necessary condition: the failure plane of '
                  f'{", ".join(names[j] for j in options[0])} misses M_g^F from every start')
    else:
        sets = ' or '.join(', '.join(names[j] for j in joints) for joints in options[:3])
        reason = ('no candidate θ_s passes the necessary condition for every joint at '
                  f'once: the starts nearest to it miss the failure planes of {sets}')
    for j in options[0] if everywhere else ():
        if all(np.ptp(points[:, j]) < HELD_TOLERANCE for points in arc_points):
            angles = sorted({round(float(points[0, j]), 4) for points in arc_points})
            reason += (f'. {names[j]} keeps its angle along each branch of the goal\'s '
                       f'self-motion ({", ".join(map(str, angles))} rad: the self-motion '
                       'does not move it): locked at any other angle it can never reach the '
                       'goal')
    return reason


def _within_limits(robot, thetas: np.ndarray) -> np.ndarray:
    """(N,) bool: configurations (N, n) inside the joint limits (periodic joints always)."""
    limits = robot.limits
    inside = (thetas >= limits[:, 0]) & (thetas <= limits[:, 1])
    return np.all(inside | robot.periodic, axis=1)


def _coarse_fans(candidates: np.ndarray, arc_points: list[np.ndarray], owners: np.ndarray,
                 arcs: np.ndarray, windows: np.ndarray, hits: np.ndarray,
                 joints: tuple[int, ...], periodic: np.ndarray, waypoints: int) -> np.ndarray:
    """Points (P, m, n) [rad] of straight paths from each θ_s to its hits and across its window.

    Proposal p is candidate `owners[p]` on arc `arcs[p]` with its window (2,) [arc points];
    `hits` (P, J, n) are the chosen hit of each tolerated joint. The arc and the hits are
    lifted as `lift_goal_arc` does.
    """
    theta_s = candidates[owners]  # (P, n)
    count = len(owners)
    joints = np.asarray(joints)
    rows = np.arange(count)[:, None]
    shift = np.zeros_like(theta_s)
    shift[:, joints] = whole_turns(theta_s[:, joints], hits[rows, np.arange(len(joints)), joints],
                                   periodic[joints])
    lifted = hits + shift[:, None, :]
    lifted[rows, np.arange(len(joints)), joints] = theta_s[:, joints]
    spread = np.empty((count, 5, theta_s.shape[1]))
    for a, points in enumerate(arc_points):
        mine = arcs == a
        if not mine.any():
            continue
        at = windows[mine, :1] + np.linspace(0.0, 1.0, 5)[None, :] * (
            windows[mine, 1:] - windows[mine, :1])
        k = np.minimum(at.astype(int), len(points) - 2)
        t = (at - k)[..., None]
        spread[mine] = points[k] + t * (points[k + 1] - points[k])
    goals = np.concatenate([lifted, spread + shift[:, None, :]], axis=1)  # (P, J+5, n)
    return straight_fans(theta_s, goals, waypoints).reshape(count, -1, theta_s.shape[1])


@numba.njit(cache=True)
def straight_fans(starts, goals, waypoints):
    """Points (P, W, G, n) [rad] w/W of the way from each start (P, n) to its goals (P, G, n).

    w = 1..W. Compiled: numpy's broadcasting over rows of n = 3 angles took ten times as long.
    """
    count, targets, n = goals.shape
    out = np.empty((count, waypoints, targets, n))
    for p in range(count):
        for w in range(waypoints):
            step = (w + 1) / waypoints
            for g in range(targets):
                for a in range(n):
                    out[p, w, g, a] = starts[p, a] + step * (goals[p, g, a] - starts[p, a])
    return out
