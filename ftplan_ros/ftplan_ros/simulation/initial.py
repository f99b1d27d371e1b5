"""Where the simulated arm starts: the clearest configuration with the tool at the task start."""

from __future__ import annotations

import numpy as np

from ftplan_ros.core import CollisionChecker, Scene
from ftplan_ros.core.model.angles import wrap_configuration
from ftplan_ros.core.paper.manifolds import project_many, trace_self_motion_manifolds

from .clearance import CLOSEST_SAMPLES

IK_SEEDS = 64  # random seeds of the inverse kinematics for a default start (r >= 2)


def default_initial_configuration(scene: Scene, rng: np.random.Generator | None = None,
                                  ) -> np.ndarray:
    """Return the clearest configuration (n,) [rad] found with the tool at the task start.

    With one degree of redundancy the candidates are the points of the traced start
    manifold M_s; with more, Newton solutions from `IK_SEEDS` random seeds. Both stay
    within the joint limits, and periodic joints are wrapped. Without a task, or when
    nothing reaches the start, the zero configuration moved into the limits.
    """
    robot = scene.robot
    fallback = np.clip(np.zeros(robot.n_joints), robot.limits[:, 0], robot.limits[:, 1])
    redundancy = robot.n_joints - robot.task_dim
    if scene.task is None or redundancy < 1:
        return fallback
    rng = rng if rng is not None else np.random.default_rng(0)
    x_s = np.asarray(scene.task.start, dtype=float)
    if redundancy == 1:
        branches = trace_self_motion_manifolds(robot, x_s, rng)
        points = np.vstack([b.points for b in branches]) if branches else np.zeros((0, 1))
    else:
        seeds = rng.uniform(robot.limits[:, 0], robot.limits[:, 1],
                            size=(IK_SEEDS, robot.n_joints))
        solved, converged = project_many(robot, x_s, seeds)
        points = solved[converged]
    if not len(points):
        return fallback
    return wrap_configuration(_clearest(CollisionChecker(robot, scene.obstacles), points),
                              robot.periodic)


def _clearest(checker: CollisionChecker, points: np.ndarray) -> np.ndarray:
    """Return the clearest of the points (k, n): screened cheaply, the best measured exactly."""
    bounds = checker.min_clearance(points, refine=False)
    best = np.argsort(-bounds)[:CLOSEST_SAMPLES]
    exact = checker.min_clearance(points[best])
    return points[best[int(np.argmax(exact))]].copy()
