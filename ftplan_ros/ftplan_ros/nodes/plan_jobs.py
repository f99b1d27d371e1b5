"""One plan request as a job that plans anywhere: in the planner node or in a plan worker.

A `PlanJob` holds everything a request's plan depends on (the scene with its task and
obstacles, the arm's configuration, the planner's settings and `plan_timeout`), so it
can be pickled to a worker process (plan_pool.py) and planned there exactly as the node
plans it itself. The timeout runs from the moment the job starts planning: time spent
waiting for a worker, or for a new worker to load its kernels, is queueing, like the
wait in the service's queue. No rclpy here: the workers import this module without it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ftplan_ros.core import (
    ManifoldCache,
    PlannerOptions,
    PlanResult,
    Scene,
    VerificationOptions,
    plan,
)
from ftplan_ros.core.model.motion_limits import MotionLimits
from ftplan_ros.core.planning.approach import ApproachOptions
from ftplan_ros.core.planning.reachable import ReachablePlan, plan_from


class PlanTimeout(Exception):  # noqa: N818 - a stop signal, not an error of the caller
    """Raised from the core's progress hook once a request has used up `plan_timeout`."""


@dataclass(frozen=True)
class PlanSettings:
    """The planner node's parameters that shape a plan (see planner.py)."""

    margin: float = 0.0          # [m] clearance the guarantee keeps
    seed: int = 0                # of the inverse-kinematics samples
    approach: bool = True        # plan for the arm where it stands (plan_from)
    approach_time: float = 1.0   # [s] budget of each RRT-Connect attempt of an approach
    proof_cells: int = ApproachOptions().proof_cells  # finest grid of the out-of-reach proof
    motion_limits: MotionLimits | None = None  # plans are timed within (None: the robot's)


@dataclass(frozen=True, eq=False)
class PlanJob:
    """A request ready to plan: `scene` carries its task and tolerated joints.

    `q` (n,) [rad] is the arm's latest configuration (None: none known); `timeout` [s]
    bounds the planning.
    """

    scene: Scene
    q: np.ndarray | None
    settings: PlanSettings
    timeout: float


def run_job(job: PlanJob, cache: ManifoldCache, stopped: Callable[[], bool] = lambda: False,
            ) -> tuple[PlanResult, ReachablePlan | None]:
    """Plan `job`; with a configuration (and `approach` on), for the arm standing there.

    Returns the plan and, for the arm standing there, the answer of `plan_from` (whose
    plan it is).

    `cache` keeps the traced manifolds across jobs of the same seed. Raises PlanTimeout at
    the first stage of the search that starts past the timeout, or once `stopped()`.
    """
    deadline = time.monotonic() + job.timeout

    def progress(line: str) -> None:
        if time.monotonic() > deadline or stopped():
            raise PlanTimeout(line)

    settings = job.settings
    options = PlannerOptions(verification=VerificationOptions(margin=settings.margin),
                             motion_limits=settings.motion_limits)
    rng = np.random.default_rng(settings.seed)
    if job.q is None or not settings.approach:
        return plan(job.scene, options, rng, progress, cache=cache), None
    reachable = plan_from(job.scene, job.q, options, rng, progress, cache, ApproachOptions(
        margin=settings.margin, rrt_time=settings.approach_time,
        proof_cells=settings.proof_cells))
    return reachable.result, reachable
