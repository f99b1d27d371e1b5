"""Failure drills: lock a random joint at a random moment and see the arm still arrive.

A drill follows the nominal path to the moment of failure, locks a tolerated joint
where it is, asks `recover` for the way on (exactly what the executor does) and then
checks the whole motion on its own terms, by dense sampling rather than by the
planner's certificate: every sampled configuration must be collision-free and the last
one within the goal tolerances. `drill_json` writes every trial's motion so that
another tool can check it again.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..collision.checker import CollisionChecker
from ..model.paths import densify, path_length, path_until, point_at_fraction
from ..model.robot import task_errors
from ..model.scene import Scene
from ..paper.recovery import recover
from ..paper.result import PlanResult

SAMPLE_STEP = 0.002  # [rad] largest joint step between the drill's collision samples
MOTION_STEP = 0.04  # [rad] largest joint step between the points of a drilled motion
EXACT_BELOW = 0.02  # [m] clearances reported exactly below this, as lower bounds above


@dataclass(frozen=True)
class DrillTrial:
    """One locked-joint failure and what became of it (angles [rad], distances [m])."""

    joint: int
    progress: float          # fraction of the nominal path's length done when it locked
    locked_value: float
    recovered: bool          # `recover` returned a path
    collision_free: bool     # every sample of the executed motion was collision-free
    min_clearance: float     # [m] exact below EXACT_BELOW, a lower bound above
    goal_error: float        # [m] of the position
    recovery_length: float
    reached: bool            # the motion ends within the task's tolerances
    orientation_error: float = 0.0  # [rad] for pose and axis tasks
    lock_index: int = -1     # index in `path` of the configuration where the joint locked
    path: np.ndarray | None = None  # (k, n) the whole motion: nominal to the lock, recovery

    @property
    def ok(self) -> bool:
        """Whether the arm reached the goal without a collision."""
        return self.recovered and self.collision_free and self.reached

    def to_json(self, joint_names) -> dict:
        """Return the trial as the drill JSON of CONTRACT.md (radians, metres)."""
        return {'joint': joint_names[self.joint], 'progress': self.progress,
                'lock_index': self.lock_index,
                'path': [] if self.path is None else self.path.tolist(),
                'reached': bool(self.ok), 'goal_error': _finite_or_none(self.goal_error),
                'orientation_error': _finite_or_none(self.orientation_error),
                'min_clearance': _finite_or_none(self.min_clearance)}


def drilled_motion(result: PlanResult, joint: int, progress: float,
                   ) -> tuple[np.ndarray, int, float] | None:
    """Return a drill's motion (k, n) [rad], the index where the joint locked, its value [rad].

    The arm follows the nominal path for `progress` (0..1) of its length, `joint` locks
    there, and `recover` gives the rest. Points are at most MOTION_STEP apart in every
    joint. None when there is no recovery path.
    """
    before = densify(path_until(result.nominal_path, progress), MOTION_STEP)
    rescue = recover(result.surface, before[-1], joint)
    if rescue is None:
        return None
    return (np.vstack([before, densify(rescue.path, MOTION_STEP)[1:]]), len(before) - 1,
            rescue.locked_value)


def drill_once(scene: Scene, result: PlanResult, checker: CollisionChecker, joint: int,
               progress: float) -> DrillTrial:
    """Lock `joint` after `progress` (0..1) of the nominal path and check the motion."""
    drilled = drilled_motion(result, joint, progress)
    if drilled is None:
        locked = float(point_at_fraction(result.nominal_path, progress)[joint])
        return DrillTrial(joint, progress, locked, False, False, np.nan, np.inf, np.nan,
                          False, np.inf)
    motion, lock_index, locked = drilled
    clearance = float(checker.min_clearance(densify(motion, SAMPLE_STEP), EXACT_BELOW).min())
    errors = task_errors(scene.robot, scene.task.goal, motion[-1])
    return DrillTrial(joint, progress, locked, True, clearance > 0.0, clearance,
                      float(errors[0]), path_length(motion[lock_index:]),
                      bool(scene.task.reached(errors)), float(errors[1]), lock_index, motion)


def run_drill(scene: Scene, result: PlanResult, trials: int, rng: np.random.Generator,
              progress: Callable[[int, int], None] | None = None) -> list[DrillTrial]:
    """Run a Monte Carlo drill: `trials` failures of random tolerated joints.

    Each locks at a uniform random moment of the nominal path.
    """
    if not result.feasible:
        raise ValueError('a drill needs a feasible plan')
    checker = CollisionChecker(scene.robot, scene.obstacles)
    joints = result.tolerated_joints
    out = []
    for k in range(trials):
        joint = int(joints[rng.integers(len(joints))])
        out.append(drill_once(scene, result, checker, joint, float(rng.uniform())))
        if progress is not None:
            progress(k + 1, trials)
    return out


def summarize_drill(trials: Sequence[DrillTrial], joint_names: Sequence[str]) -> str:
    """Tabulate trials, successes, worst clearance and goal errors per joint and in total."""
    width = max(10, max(map(len, joint_names)) + 2)
    header = (f'{"joint":<{width}}{"trials":>7}{"reached":>9}{"min clear [m]":>15}'
              f'{"max goal err [m]":>18}{"[rad]":>10}{"recovery p50/p95 [rad]":>24}')
    rows = [header, '-' * len(header)]
    groups = [(name, [t for t in trials if t.joint == j]) for j, name in enumerate(joint_names)]
    groups.append(('all', list(trials)))
    for name, group in groups:
        if not group:
            continue
        lengths = np.array([t.recovery_length for t in group if t.recovered])
        spread = (f'{np.percentile(lengths, 50):.3f} / {np.percentile(lengths, 95):.3f}'
                  if len(lengths) else '-')
        rows.append(f'{name:<{width}}{len(group):>7}{sum(t.ok for t in group):>9}'
                    f'{_clearance_text(np.nanmin([t.min_clearance for t in group])):>15}'
                    f'{np.nanmax([t.goal_error for t in group]):>18.2e}'
                    f'{np.nanmax([t.orientation_error for t in group]):>10.1e}{spread:>24}')
    return '\n'.join(rows)


def drill_json(trials: Sequence[DrillTrial], joint_names: Sequence[str]) -> dict:
    """Return the drill JSON of CONTRACT.md: every trial, re-checkable, and a summary."""
    return {'joint_names': list(joint_names),
            'trials': [trial.to_json(joint_names) for trial in trials],
            'summary': {'trials': len(trials), 'reached': sum(t.ok for t in trials),
                        'min_clearance': _finite_or_none(
                            np.nanmin([t.min_clearance for t in trials])),
                        'max_goal_error': _finite_or_none(max(t.goal_error for t in trials)),
                        'max_orientation_error': _finite_or_none(
                            max(t.orientation_error for t in trials))}}


def _clearance_text(value: float) -> str:
    """Format a drill clearance [m]: exact below EXACT_BELOW, bounded from below above it."""
    return f'>= {EXACT_BELOW:.3f}' if value >= EXACT_BELOW else f'{value:.4f}'


def _finite_or_none(value: float) -> float | None:
    value = float(value)
    return value if np.isfinite(value) else None
