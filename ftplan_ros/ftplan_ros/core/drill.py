"""Failure drills: lock a random joint at a random moment and see the arm still arrive.

A drill follows the nominal path to the moment of failure, locks the joint where it is,
asks `recover` for the way on (exactly what the executor does) and then checks the whole
motion on its own terms, by dense sampling rather than by the planner's certificate:
every sampled configuration must be collision-free and the last one within the goal
tolerance of x_g.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from .collision import CollisionChecker
from .paths import densify, path_length, path_until, point_at_fraction
from .recovery import recover
from .result import PlanResult
from .scene import Scene

SAMPLE_STEP = 0.002  # [rad] largest joint step between the drill's collision samples


@dataclass(frozen=True)
class DrillTrial:
    """One locked-joint failure and what became of it (angles [rad], distances [m])."""

    joint: int
    progress: float          # fraction of the nominal path's length done when it locked
    locked_value: float
    recovered: bool          # `recover` returned a path
    collision_free: bool     # every sample of the executed motion was collision-free
    min_clearance: float
    goal_error: float
    recovery_length: float
    tolerance: float         # the task's goal tolerance

    @property
    def ok(self) -> bool:
        """Whether the arm reached the goal without a collision."""
        return self.recovered and self.collision_free and self.goal_error <= self.tolerance


def drilled_motion(result: PlanResult, joint: int, progress: float,
                   ) -> tuple[np.ndarray, int, float] | None:
    """Return a drill's motion (k, n) [rad], the index where the joint locked, its value [rad].

    The arm follows the nominal path for `progress` (0..1) of its length, `joint` locks
    there, and `recover` gives the rest. None when there is no recovery path.
    """
    before = path_until(result.nominal_path, progress)
    rescue = recover(result.surface, before[-1], joint)
    if rescue is None:
        return None
    return np.vstack([before, rescue.path[1:]]), len(before) - 1, rescue.locked_value


def drill_once(scene: Scene, result: PlanResult, checker: CollisionChecker, joint: int,
               progress: float) -> DrillTrial:
    """Lock `joint` after `progress` (0..1) of the nominal path and check the motion."""
    tolerance = scene.task.goal_tolerance
    drilled = drilled_motion(result, joint, progress)
    if drilled is None:
        locked = float(point_at_fraction(result.nominal_path, progress)[joint])
        return DrillTrial(joint, progress, locked, False, False, np.nan, np.inf, np.nan,
                          tolerance)
    motion, lock_index, locked = drilled
    clearance = float(checker.min_clearance(densify(motion, SAMPLE_STEP)).min())
    error = float(np.linalg.norm(scene.robot.forward_kinematics(motion[-1])
                                 - np.asarray(scene.task.goal)))
    return DrillTrial(joint, progress, locked, True, clearance > 0.0, clearance, error,
                      path_length(motion[lock_index:]), tolerance)


def run_drill(scene: Scene, result: PlanResult, trials: int, rng: np.random.Generator,
              progress: Callable[[int, int], None] | None = None) -> list[DrillTrial]:
    """Monte Carlo drill: `trials` failures at a random joint and a uniform random moment."""
    if not result.feasible:
        raise ValueError('a drill needs a feasible plan')
    checker = CollisionChecker(scene.robot, scene.obstacles)
    out = []
    for k in range(trials):
        joint = int(rng.integers(scene.robot.n_joints))
        out.append(drill_once(scene, result, checker, joint, float(rng.uniform())))
        if progress is not None:
            progress(k + 1, trials)
    return out


def summarize_drill(trials: Sequence[DrillTrial], joint_names: Sequence[str]) -> str:
    """Tabulate trials, successes, worst clearance and goal error per joint and in total."""
    header = (f'{"joint":<10}{"trials":>7}{"reached":>9}{"min clear [m]":>15}'
              f'{"max goal err [m]":>18}{"recovery p50/p95 [rad]":>24}')
    rows = [header, '-' * len(header)]
    groups = [(name, [t for t in trials if t.joint == j]) for j, name in enumerate(joint_names)]
    groups.append(('all', list(trials)))
    for name, group in groups:
        if not group:
            continue
        lengths = np.array([t.recovery_length for t in group if t.recovered])
        spread = (f'{np.percentile(lengths, 50):.3f} / {np.percentile(lengths, 95):.3f}'
                  if len(lengths) else '-')
        rows.append(f'{name:<10}{len(group):>7}{sum(t.ok for t in group):>9}'
                    f'{np.nanmin([t.min_clearance for t in group]):>15.4f}'
                    f'{np.nanmax([t.goal_error for t in group]):>18.2e}{spread:>24}')
    return '\n'.join(rows)
