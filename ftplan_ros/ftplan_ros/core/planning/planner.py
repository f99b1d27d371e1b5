"""The planner: check the scene, then the paper's method for its degree of redundancy.

With one degree of redundancy (r = n - m = 1: the paper's planar 3R, a 7-joint arm and
a 6-D pose) the self-motion manifolds are curves and `SurfaceSearch` runs Steps 1-6 and
the self-check; where it finds no plan for a planar 3R arm among disks, recovery sheets
over the failure-tolerant set take over (`grid/recovery_sheets.py`; stats['method'] says which
produced the plan). With more (a 7-joint arm and a 3-D position, a planar 4R), the paper
chooses a curve on each manifold and proceeds as for r = 1: `plan_on_curves` does that.
When no plan survives the lock of every tolerated joint because some joints' failure
planes miss M_g^F from every start, the planner says which, and whether a plan exists
for the others.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..collision.checker import CollisionChecker
from ..errors import InputError
from ..grid.recovery_sheets import (
    PAPER_METHOD,
    RecoverySheets,
    past_the_paper,
    sheets_apply,
    with_sheets,
)
from ..model.motion_limits import robot_motion_limits
from ..model.robot import PlanarChain
from ..model.scene import Scene
from ..model.task_space import point_position
from ..paper.manifolds import ManifoldCache
from ..paper.options import PlannerOptions
from ..paper.result import PlanResult
from .curves import plan_on_curves
from .surface_search import SurfaceSearch
from .timing import braking_speed_scaling, time_within_limits

log = logging.getLogger(__name__)


def check_plannable(scene: Scene, checker: CollisionChecker | None = None) -> None:
    """Raise InputError when the scene's task cannot be planned (the CLI's exit code 2).

    `checker`: the scene's, if the caller has one already.
    """
    robot, task = scene.robot, scene.task
    if task is None:
        raise InputError('task', 'is missing: planning needs task.start and task.goal')
    if task.kind != robot.task_kind:
        raise InputError('task', f'is a {task.kind} task but the robot is bound to '
                         f'{robot.task_kind} tasks')
    redundancy = robot.n_joints - robot.task_dim
    if redundancy < 1:
        field = 'robot.link_lengths' if isinstance(robot, PlanarChain) else 'robot'
        raise InputError(field, f'{robot.n_joints} joints give no redundancy for a '
                         f'{robot.task_dim}-D {task.kind} task (need more than '
                         f'{robot.task_dim})')
    for name, x in (('task.start', task.start), ('task.goal', task.goal)):
        if not robot.can_reach(np.asarray(x)):
            where = [round(float(v), 6) for v in point_position(x)]
            raise InputError(name, f'{where} is out of the arm\'s reach')
    if _same_task_point(task):
        raise InputError('task.goal', 'equals task.start (within the goal tolerances): '
                         'nothing to plan')
    checker = checker or CollisionChecker(robot, scene.obstacles)
    for k, clearance in enumerate(checker.base_clearance()):
        if not clearance > 0.0:
            raise InputError(f'obstacles[{k}]', 'covers the robot base: every configuration '
                             'collides')
    scene.tolerated_joints  # noqa: B018 - raises for joint names the robot does not have


def plan(scene: Scene, options: PlannerOptions | None = None,
         rng: np.random.Generator | None = None,
         progress: Callable[[str], None] | None = None,
         start_configuration: np.ndarray | None = None,
         cache: ManifoldCache | None = None,
         prefer_starts: Callable[[np.ndarray], np.ndarray] | None = None) -> PlanResult:
    """Plan a failure-tolerant motion for the scene's task; see the module docstring.

    `rng` seeds the inverse-kinematics samples (default: seed 0, so plans repeat);
    `progress` receives a line per stage. With `start_configuration` (n,) [rad] only that
    θ_s is considered (moved onto M_s by Newton first): the plan says whether it is a
    failure-tolerant start. A `cache` keeps traced manifolds between calls. Raises
    InputError for an unplannable scene. With one degree of redundancy, `prefer_starts`
    maps start candidates (c, n) to a mask (c,) of the ones to search first (issue 10:
    `approach.ApproachPlanner.prefer_reachable`, the starts the arm reaches along M_s^F).
    """
    options = options or PlannerOptions()
    rng = rng if rng is not None else np.random.default_rng(0)
    report = progress or (lambda line: None)
    cache = cache or ManifoldCache(size=2)
    started = time.perf_counter()
    checker = CollisionChecker(scene.robot, scene.obstacles)  # one for every stage
    check_plannable(scene, checker)
    if scene.robot.n_joints - scene.robot.task_dim == 1:
        search = SurfaceSearch(scene, options, rng, report, cache, checker, prefer_starts)
        result = _paper_then_sheets(search, scene, options, report, start_configuration,
                                    prefer_starts)
        if not result.feasible and start_configuration is None and options.coverage_attempts:
            result = _with_coverage(search, result, report, options.coverage_attempts)
    else:
        result = plan_on_curves(scene, options, rng, report, cache, start_configuration)
    if result.feasible:
        result = replace(result, stats=dict(result.stats, max_safe_speed=_max_safe_speed(
            scene, checker, result.nominal_path, options)))
    stats = {'method': PAPER_METHOD} | dict(result.stats, plan_time_s=time.perf_counter() - started)
    log.info('plan %s in %.3f s%s', 'found' if result.feasible else 'not found',
             stats['plan_time_s'], f': {result.reason}' if result.reason else '')
    return replace(result, stats=stats)


def _paper_then_sheets(search: SurfaceSearch, scene: Scene, options: PlannerOptions,
                       report: Callable[[str], None], start_configuration: np.ndarray | None,
                       prefer_starts: Callable[[np.ndarray], np.ndarray] | None,
                       ) -> PlanResult:
    """Run the paper's search, then the recovery sheets where it plans nothing.

    Where the sheets apply (`past_the_paper`), the paper's second round of starts
    (`candidate_refinement` per manifold step) waits for them. It runs at once only when
    no start of the first round passes the necessary condition, as it then decides
    whether the sheets run at all; otherwise only when the sheets neither plan nor prove
    that no plan exists. On the 120 scenes of three bench seeds that round never planned,
    and it took up to 0.17 s of scenes that the sheets then planned.
    """
    checker = search.checker
    if start_configuration is not None or not sheets_apply(scene, options):
        return past_the_paper(scene, search.run(start_configuration), options, report,
                              start_configuration, prefer_starts, checker)
    finer = (options.candidate_refinement,)
    first = search.run(subdivisions=(1,))
    if first.feasible or not first.goal_free_arcs:  # no second round, as before
        return past_the_paper(scene, first, options, report, None, prefer_starts, checker)
    if first.necessary_starts is None or len(first.necessary_starts) == 0:
        return past_the_paper(scene, search.run(subdivisions=finer), options, report, None,
                              prefer_starts, checker)
    sheets = RecoverySheets(scene, options, report, None, prefer_starts,
                            checker).run(previous=first)
    if sheets.feasible or sheets.proved_infeasible:
        return with_sheets(first, sheets)
    return with_sheets(search.run(subdivisions=finer), sheets)


def _with_coverage(search: SurfaceSearch, result: PlanResult,
                   report: Callable[[str], None], attempts: int) -> PlanResult:
    """Add to a failed result the largest set of joints a plan could still tolerate.

    When some joints' failure planes keep every start from the necessary condition
    (`result.blocked_joints`, likeliest set first), the others are planned for, set by
    set, up to `attempts` sets, on the manifolds `search` traced and with its first round
    of starts only (a report, not the answer: it costs the failed plan no more than a
    search of its own); the first that plans is reported as `coverable_joints`.
    """
    robot = search.robot
    requested = [robot.joint_names[i] for i in search.joints]
    reason = ''
    for blocked in result.blocked_joints[:attempts]:
        others = [name for name in requested if name not in blocked]
        if not others:
            continue
        report(f'no plan tolerates {", ".join(blocked)}: trying the other joints')
        partial = search.for_joints(others).run(subdivisions=(1,))
        if partial.feasible:
            return replace(result, stats=dict(result.stats, coverable_joints=others),
                           reason=result.reason + f'; a plan tolerates the locks of '
                           f'{", ".join(others)}: give them as `tolerate` to get it')
        reason = f'; no plan tolerates even the joints but {", ".join(blocked)}: {partial.reason}'
    return replace(result, reason=result.reason + reason,
                   stats=dict(result.stats, coverable_joints=[]))


def _same_task_point(task) -> bool:
    """Whether start and goal coincide within the goal tolerances."""
    start, goal = np.asarray(task.start, dtype=float), np.asarray(task.goal, dtype=float)
    if np.linalg.norm(point_position(start) - point_position(goal)) > task.goal_tolerance:
        return False
    if task.kind == 'pose':
        angle = 2.0 * np.arccos(min(1.0, abs(float(start[3:] @ goal[3:]))))
    elif task.kind == 'axis':
        angle = np.arccos(np.clip(float(start[3:] @ goal[3:]), -1.0, 1.0))
    else:
        return True
    return bool(angle <= task.orientation_tolerance)


def _max_safe_speed(scene: Scene, checker: CollisionChecker, nominal_path,
                    options: PlannerOptions) -> float:
    """Return the fraction (0..1] of the time-optimal speed that brakes inside certified boxes.

    Of the options' motion limits (else the robot's) along the nominal path, at which a
    lock anywhere on it brakes inside a certified box (timing.py); 0: no speed does.
    """
    limits = options.motion_limits or robot_motion_limits(scene.robot)
    timed = time_within_limits(np.asarray(nominal_path, dtype=float), limits)
    return braking_speed_scaling(checker, timed, limits.acceleration,
                                 options.verification.margin)
