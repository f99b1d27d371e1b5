"""A plan worker process: it plans the jobs that come on its connection (plan_pool.py).

It holds the robots it was sent by the pool's keys (its own copies, so that its
ManifoldCache finds what it traced for the same robot), loads a robot's kernels before
it first plans with it, and stops planning when the node hangs up. No rclpy here: the
fork server imports this module, and the workers are forked from it.
"""

from __future__ import annotations

import logging
import signal
import traceback
from collections import OrderedDict
from dataclasses import replace
from multiprocessing.connection import Connection

from ftplan_ros.core import InputError, ManifoldCache, Robot, load_kernels

from .plan_jobs import PlanJob, PlanTimeout, run_job

ROBOTS_KEPT = 4  # robots a worker keeps, the most recently used
_log = logging.getLogger(__name__)


class _Planner:
    """A worker's state: the robots it holds by key, its manifold cache and the seed."""

    def __init__(self, connection: Connection):
        self.connection = connection
        self.robots: OrderedDict[int, Robot] = OrderedDict()
        self.cache = ManifoldCache()
        self.seed: int | None = None

    def robot(self, key: int, robot: Robot) -> Robot:
        """Return the worker's robot of `key` (`robot` the first time, its kernels loaded)."""
        if key not in self.robots:
            try:
                load_kernels(robot)
            except Exception:  # noqa: BLE001 - a warm-up that fails only costs time
                _log.warning(f'loading the kernels failed:\n{traceback.format_exc()}')
            self.robots[key] = robot
            if len(self.robots) > ROBOTS_KEPT:
                self.robots.popitem(last=False)
        self.robots.move_to_end(key)
        return self.robots[key]

    def plan(self, key: int, job: PlanJob) -> tuple:
        """Plan `job` with the worker's own robot of `key`; return the reply."""
        robot = self.robot(key, job.scene.robot)
        if job.settings.seed != self.seed:  # the cached manifolds were traced with the old one
            self.cache, self.seed = ManifoldCache(), job.settings.seed
        job = replace(job, scene=replace(job.scene, robot=robot))
        try:
            result, reachable = run_job(job, self.cache, self.connection.poll)
        except PlanTimeout as stop:
            return ('timeout', str(stop))
        except InputError as error:
            return ('refused', error.field, error.problem)
        except Exception as error:  # noqa: BLE001 - the node answers with it
            return ('error', repr(error), traceback.format_exc())
        return ('done', result, reachable)


def serve(connection: Connection) -> None:
    """Plan the jobs that come on `connection` until it closes (a worker process's main).

    Each message has one reply: ('warm', key, robot) loads the robot's kernels and is
    answered ('ready',); ('plan', key, job) is answered ('done', result, reachable),
    ('timeout', line), ('refused', field, problem) or ('error', repr, traceback). The
    pool sends a message only when the worker is idle, so anything readable while it
    plans is the node hanging up (`connection.poll()` is true at EOF too): the search
    stops at its next stage.
    """
    # Ctrl-C in a terminal reaches the whole process group: the node stops its workers.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    planner = _Planner(connection)
    try:
        while True:
            kind, key, payload = connection.recv()
            if kind == 'warm':
                planner.robot(key, payload)
                connection.send(('ready',))
            else:
                connection.send(planner.plan(key, payload))
    except (EOFError, OSError):  # the node closed the connection, or died
        return
