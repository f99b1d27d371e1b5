"""Load the compiled kernels before the first plan, so that it does not wait for them.

numba loads (or, on a new machine, compiles) each kernel at its first call in a
process: together about a second from its cache, a minute to compile. The Makefile
calls `load_kernels` at set-up, so the cache is there before the first plan. Running
them takes time too, growing with the robot's collision geometry (9 s for a URDF of
a thousand shapes): a robot warmed once is not warmed again.
"""

from __future__ import annotations

import threading
import weakref

import numpy as np

from ..collision.certification import certify_simplices, certify_web
from ..collision.checker import CollisionChecker
from ..grid.recovery_sheets import load_sheet_kernels
from ..model.robot import PlanarChain, Robot, task_errors, task_residuals
from ..model.scene import Obstacle
from ..paper.failure_planes import FailurePlaneHit, crossing_segments
from ..paper.failure_surface import FailureSurface, choose_hits, smallest_windows
from ..paper.manifolds import ManifoldOptions, trace_self_motion_manifolds
from ..paper.recovery import recover
from .curves import FrozenJoints
from .surface_search import straight_fans

# The robots warmed so far (an equal robot: the same model bound to the same task kind).
_warmed: weakref.WeakSet = weakref.WeakSet()
_warmed_lock = threading.Lock()


def load_kernels(robot: Robot) -> None:
    """Run every compiled kernel the robot's plans use once: tracing, task maps, distances.

    Recovery and, for a planar 3R arm, the recovery sheets' kernels too. A robot equal to
    one warmed before returns at once.
    """
    with _warmed_lock:
        if robot in _warmed:
            return
    _run_kernels(robot)
    with _warmed_lock:
        _warmed.add(robot)


def _run_kernels(robot: Robot) -> None:
    theta = np.clip(np.full(robot.n_joints, 0.5), robot.limits[:, 0], robot.limits[:, 1])
    x = robot.forward_kinematics(theta)
    task_residuals(robot, x, theta)
    task_errors(robot, x, theta)
    redundancy = robot.n_joints - robot.task_dim
    if redundancy >= 1:
        traced = robot if redundancy == 1 else FrozenJoints(
            robot, tuple(range(redundancy - 1)), tuple(theta[:redundancy - 1]))
        # Four seeds: one alone may not converge (the 4-joint arm's), which traces nothing.
        trace_self_motion_manifolds(traced, traced.forward_kinematics(theta[redundancy - 1:]),
                                    np.random.default_rng(0), ManifoldOptions(seeds=4))
    near = tuple(float(v) for v in robot.skeleton(theta)[-1])  # the tool: within reach
    sphere = Obstacle('sphere', near, radius=0.1)
    corners = np.stack([theta, theta + 0.01, theta - 0.01])[None]
    for obstacles in ([sphere, Obstacle('box', near, size=(0.1,) * 3)], [sphere]):
        checker = CollisionChecker(robot, obstacles)  # spheres alone: a planar fast path
        checker.clearance(np.stack([theta, theta]), needed=np.inf)
        certify_simplices(checker, corners, 0.0, 1)
    crossing_segments(np.array([0.0, 1.0]), np.array([0.5]), periodic=True)
    smallest_windows(np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64), np.zeros(1), 1, 1)
    choose_hits([[FailurePlaneHit(0, theta, 0.0)]], (0.0, 0.0))
    straight_fans(theta[None], theta[None, None], 2)
    fan = np.stack([np.stack([theta, theta + 0.1]), np.stack([theta, theta + 0.2])])
    surface = FailureSurface(fan, 0, (), ())
    recover(surface, theta + 0.05, 0)
    certify_web(checker, surface, 0.0, 1)  # in blocks, with the planar fast path
    if isinstance(robot, PlanarChain) and robot.n_joints == 3:
        load_sheet_kernels()  # the recovery sheets' grid, searches and slices
