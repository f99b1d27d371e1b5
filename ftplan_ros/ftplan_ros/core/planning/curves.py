"""Redundancy r >= 2: choose a curve on each self-motion manifold, then plan as for r = 1.

The paper: "for kinematic redundancy of two or more ... the algorithm would first choose
a curve along the hypersurface ... once a hypercurve is chosen, [it] would proceed in the
same manner as in the case of a single degree of redundancy". The curves chosen here are
the manifolds' slices θ_F = c: r - 1 joints F are frozen at angles c, the same for M_s
and M_g, which leaves a chain with one degree of redundancy (`FrozenJoints`). The arm
never moves a frozen joint, so a lock of one leaves it on the nominal path, which still
reaches the goal: the plan tolerates frozen joints for free, and the self-check proves
it like every other lock, on the lifted surface in the whole joint space.

Criterion: candidate (F, c) come from collision-free inverse-kinematics samples of x_s
(c = their angles on F); F holds the joints that move the tool least (smallest mean
Jacobian column over the samples), and the candidates are ranked by the smaller
clearance of the start sample and of the clearest goal configuration on the same slice.
The best `PlannerOptions.curves` are planned in turn; the first verified plan wins, and
the result's stats name its curve.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property
from itertools import combinations

import numpy as np

from ..collision.checker import CollisionChecker
from ..model import kinematics
from ..model.robot import LinkShape, Robot, task_residuals
from ..model.scene import Scene
from ..paper.failure_surface import FailureSurface
from ..paper.manifolds import ManifoldCache, SelfMotionManifold, project_many
from ..paper.options import PlannerOptions
from ..paper.result import PlanResult
from ..paper.verification import verify_surface
from .surface_search import SurfaceSearch

CURVE_CRITERION = ('slice θ_F = c of M_s and M_g; F: the joints that move the tool least; '
                   'c: the clearest inverse-kinematics sample of x_s whose slice reaches '
                   'x_g clear of obstacles')
_FREEZE_SETS = 3  # frozen joint sets tried, least influential first


@dataclass(frozen=True)
class FrozenJoints:
    """`robot` with joints `frozen` held at `values` [rad]: a `Robot` of the other joints."""

    robot: Robot
    frozen: tuple[int, ...]
    values: tuple[float, ...]

    @cached_property
    def free(self) -> np.ndarray:
        """Indices (n',) of the joints left to move."""
        return np.array([j for j in range(self.robot.n_joints) if j not in self.frozen])

    def expand(self, thetas: np.ndarray) -> np.ndarray:
        """Whole configurations (..., n) of configurations (..., n') of the free joints."""
        thetas = np.asarray(thetas, dtype=float)
        out = np.empty(thetas.shape[:-1] + (self.robot.n_joints,))
        out[..., self.free] = thetas
        out[..., list(self.frozen)] = self.values
        return out

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The free joints' names."""
        return tuple(self.robot.joint_names[j] for j in self.free)

    @property
    def n_joints(self) -> int:
        """Number of free joints n'."""
        return len(self.free)

    @property
    def joint_chain_index(self) -> np.ndarray:
        """(n',) the free joints' places in the whole chain."""
        return np.asarray(self.robot.joint_chain_index)[self.free]

    @property
    def task_kind(self) -> str:
        """The whole robot's task kind."""
        return self.robot.task_kind

    @property
    def task_dim(self) -> int:
        """The whole robot's task dimension m."""
        return self.robot.task_dim

    @cached_property
    def periodic(self) -> np.ndarray:
        """(n',) bool of the free joints."""
        return self.robot.periodic[self.free]

    @cached_property
    def limits(self) -> np.ndarray:
        """(n', 2) limits [rad] of the free joints."""
        return self.robot.limits[self.free]

    def forward_kinematics(self, thetas: np.ndarray) -> np.ndarray:
        """Task points of configurations (..., n') of the free joints."""
        return self.robot.forward_kinematics(self.expand(thetas))

    @property
    def kernel_kind(self) -> int:
        """The whole robot's task map with frozen joints (kinematics.FROZEN)."""
        return kinematics.FROZEN + self.robot.kernel_kind

    @cached_property
    def kernel_parameters(self) -> np.ndarray:
        """The free mask, the frozen values and the whole robot's parameters."""
        free = np.zeros(self.robot.n_joints, dtype=bool)
        free[self.free] = True
        return kinematics.frozen_parameters(free, self.expand(np.zeros(self.n_joints)),
                                         self.robot.kernel_parameters)

    @property
    def link_names(self) -> tuple[str, ...]:
        """The whole robot's links."""
        return self.robot.link_names

    def link_frames(self, thetas: np.ndarray) -> np.ndarray:
        """Link frames (..., L, 4, 4) of configurations (..., n') of the free joints."""
        return self.robot.link_frames(self.expand(thetas))

    @property
    def collision_shapes(self) -> tuple[LinkShape, ...]:
        """The whole robot's collision geometry."""
        return self.robot.collision_shapes

    @property
    def self_collision_pairs(self) -> tuple[tuple[int, int], ...]:
        """The whole robot's self-collision pairs."""
        return self.robot.self_collision_pairs

    @property
    def exempt_urdf_pairs(self) -> frozenset[frozenset[str]]:
        """The whole robot's exempt URDF link pairs."""
        return self.robot.exempt_urdf_pairs

    def frame_lever_arms(self) -> np.ndarray:
        """(L, n') [m]: the whole robot's arms for the free joints (frozen ones never turn)."""
        return self.robot.frame_lever_arms()[:, self.free]

    def tip_lever_arms(self) -> np.ndarray:
        """(n',) [m] of the free joints."""
        return self.robot.tip_lever_arms()[self.free]

    def skeleton(self, thetas: np.ndarray) -> np.ndarray:
        """Return the whole robot's skeleton at configurations (..., n') of the free joints."""
        return self.robot.skeleton(self.expand(thetas))

    def can_reach(self, x: np.ndarray) -> bool:
        """Run the whole robot's quick reach check."""
        return self.robot.can_reach(x)


def plan_on_curves(scene: Scene, options: PlannerOptions, rng: np.random.Generator,
                   report: Callable[[str], None], cache: ManifoldCache,
                   start_configuration: np.ndarray | None = None) -> PlanResult:
    """Plan a scene of redundancy r >= 2 on chosen curves (see the module docstring)."""
    robot = scene.robot
    candidates = curve_candidates(scene, options, rng, start_configuration)
    report(f'redundancy {robot.n_joints - robot.task_dim}: {len(candidates)} curves to try')
    result = None
    for number, (frozen, values, score) in enumerate(candidates[:options.curves], start=1):
        reduced = FrozenJoints(robot, frozen, values)
        free_names = set(reduced.joint_names)
        tolerated = [robot.joint_names[j] for j in scene.tolerated_joints
                     if robot.joint_names[j] in free_names]
        reduced_scene = replace(scene, robot=reduced, tolerate=tuple(tolerated))
        start = None if start_configuration is None else \
            np.asarray(start_configuration, dtype=float)[reduced.free]
        attempt = SurfaceSearch(reduced_scene, options, rng, report, cache).run(start)
        curve = {'frozen_joints': [robot.joint_names[j] for j in frozen],
                 'frozen_values_rad': list(values), 'criterion': CURVE_CRITERION,
                 'criterion_value_m': score, 'curves_tried': number}
        result = _lift(scene, reduced, attempt, curve, options)
        if result.feasible:
            return result
    if result is None:
        stats = {'curves_tried': 0, 'tolerated_joints': [robot.joint_names[j]
                                                         for j in scene.tolerated_joints]}
        return PlanResult(False, robot.joint_names, 'no curve: no obstacle-free inverse '
                          'kinematics of x_s whose slice reaches x_g clear of obstacles',
                          stats=stats, periodic=robot.periodic)
    return replace(result, reason=f'no plan on the {min(len(candidates), options.curves)} '
                   f'curves tried; the last: {result.reason}')


def curve_candidates(scene: Scene, options: PlannerOptions, rng: np.random.Generator,
                     start_configuration: np.ndarray | None = None,
                     ) -> list[tuple[tuple[int, ...], tuple[float, ...], float]]:
    """Rank (frozen joints F, values c [rad], score [m]) by the module's criterion.

    The best candidate of every frozen set comes first, then the second best of each,
    and so on, so that the curves tried differ in their frozen joints.
    """
    robot, task = scene.robot, scene.task
    checker = CollisionChecker(robot, scene.obstacles)
    margin = options.verification.margin
    if start_configuration is not None:
        starts = np.asarray(start_configuration, dtype=float)[None, :]
    else:
        starts = _free_samples(robot, np.asarray(task.start), checker, margin, rng,
                               options.curve_samples)
    if len(starts) == 0:
        return []
    clear_starts = checker.min_clearance(starts, margin + 0.1, refine=False)
    order = np.argsort(-_tied(clear_starts), kind='stable')[:8]
    per_set = []
    for frozen in _freeze_sets(robot, starts, robot.n_joints - robot.task_dim - 1,
                               scene.tolerated_joints):
        ranked = []
        for k in order:
            values = tuple(float(v) for v in starts[k, list(frozen)])
            goals = _free_samples(FrozenJoints(robot, frozen, values), np.asarray(task.goal),
                                  checker, margin, rng, 16, expand=True)
            if len(goals):
                goal_clearance = checker.min_clearance(goals, margin + 0.1, refine=False).max()
                ranked.append((frozen, values, float(min(clear_starts[k], goal_clearance))))
        per_set.append(sorted(ranked, key=lambda candidate: -_tied(candidate[2])))
    rounds = [[ranked[k] for ranked in per_set if k < len(ranked)]
              for k in range(max(map(len, per_set), default=0))]
    return [candidate for one_round in rounds
            for candidate in sorted(one_round, key=lambda candidate: -_tied(candidate[2]))]


def _tied(clearance):
    """Clearances [m] rounded to a nanometre: equal ones keep their order when sorted.

    Every candidate often shares one score (the tool's own clearance at x_s, the same for
    every configuration), and rounding noise must not reorder them.
    """
    return np.round(clearance, 9)


def _free_samples(robot, x: np.ndarray, checker: CollisionChecker, margin: float,
                  rng: np.random.Generator, count: int, expand: bool = False) -> np.ndarray:
    """Collision-free inverse-kinematics solutions (k, n) [rad] of x within the limits."""
    limits = robot.limits
    seeds = rng.uniform(limits[:, 0], limits[:, 1], size=(count, robot.n_joints))
    solved, converged = project_many(robot, x, seeds)
    inside = np.all((solved >= limits[:, 0]) & (solved <= limits[:, 1]) | robot.periodic,
                    axis=1)
    solved = solved[converged & inside]
    whole = robot.expand(solved) if expand else solved
    return whole[checker.min_clearance(whole, margin, refine=False) > margin]


def _freeze_sets(robot: Robot, samples: np.ndarray, size: int, tolerated: tuple[int, ...],
                 ) -> list[tuple[int, ...]]:
    """Choose sets of `size` joints to freeze, the ones that move the tool least first.

    Only sets that leave every tolerated joint moving along the curve count; the
    influence of a joint is its Jacobian column's norm averaged over the samples.

    A joint whose null-space component is zero on the slice at two samples keeps its
    angle along the whole self-motion (an elbow between a spherical shoulder and the
    tool): locked, it could only reach a goal at that same angle.
    """
    _, jacobians = task_residuals(robot, robot.forward_kinematics(samples[0]), samples)
    influence = np.linalg.norm(jacobians, axis=1).mean(axis=0)  # (n,)
    kept = []
    for frozen in combinations(range(robot.n_joints), size):
        free = [j for j in range(robot.n_joints) if j not in frozen]
        moving = np.zeros(len(free), dtype=bool)
        for sample in samples[:2]:
            null = np.linalg.svd(task_residuals(robot, robot.forward_kinematics(sample),
                                                sample)[1][0][:, free])[2][-1]
            moving |= np.abs(null) > 1e-6
        if all(moving[free.index(j)] for j in tolerated if j in free):
            kept.append(frozen)
    kept.sort(key=lambda joints: influence[list(joints)].sum())
    return kept[:_FREEZE_SETS]


def _lift(scene: Scene, reduced: FrozenJoints, attempt: PlanResult, curve: dict,
          options: PlannerOptions) -> PlanResult:
    """Return the reduced chain's plan in the whole joint space, checked again there."""
    robot = scene.robot
    stats = dict(attempt.stats, curve=curve,
                 tolerated_joints=[robot.joint_names[j] for j in scene.tolerated_joints])
    lifted = dict(start_manifolds=_lift_manifolds(reduced, attempt.start_manifolds),
                  goal_manifolds=_lift_manifolds(reduced, attempt.goal_manifolds),
                  necessary_starts=None if attempt.necessary_starts is None
                  else reduced.expand(attempt.necessary_starts),
                  proposed_starts=None if attempt.proposed_starts is None
                  else reduced.expand(attempt.proposed_starts), periodic=robot.periodic,
                  goal_free_arcs=attempt.goal_free_arcs, blocked_joints=attempt.blocked_joints)
    if not attempt.feasible:
        return PlanResult(False, robot.joint_names, attempt.reason, None, stats, **lifted)
    surface = _lift_surface(reduced, attempt.surface, scene.tolerated_joints)
    verdict = verify_surface(surface, CollisionChecker(robot, scene.obstacles), scene.task,
                             options.verification)
    if not verdict.ok:
        return PlanResult(False, robot.joint_names, f'the lifted surface fails its check: '
                          f'{verdict.reason}', None, stats, **lifted)
    stats.update(min_clearance_m=verdict.min_clearance,
                 recovery_min_clearance_m=verdict.recovery_min_clearance,
                 clearance_samples=verdict.clearance_samples)
    return PlanResult(True, robot.joint_names, '', surface, stats, **lifted)


def _lift_surface(reduced: FrozenJoints, surface: FailureSurface,
                  tolerated: tuple[int, ...]) -> FailureSurface:
    """S_F in the whole joint space; a frozen joint's hit path is the nominal path."""
    free = [int(j) for j in reduced.free]
    hit_of = {free[i]: k for i, k in zip(surface.tolerated, surface.hit_paths, strict=True)}
    hit_paths = tuple(hit_of.get(j, surface.nominal) for j in tolerated)
    return FailureSurface(reduced.expand(surface.paths), surface.nominal, hit_paths, tolerated)


def _lift_manifolds(reduced: FrozenJoints, branches: tuple[SelfMotionManifold, ...],
                    ) -> tuple[SelfMotionManifold, ...]:
    period = np.zeros(reduced.robot.n_joints)
    lifted = []
    for branch in branches:
        whole_period = period.copy()
        whole_period[reduced.free] = branch.period
        lifted.append(replace(branch, points=reduced.expand(branch.points), period=whole_period))
    return tuple(lifted)
