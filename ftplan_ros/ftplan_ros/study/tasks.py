"""What a worker does: plan a chunk of a study's tasks into rows of the results table.

Every task is planned exactly as `ftplan plan` plans a scene: `plan(scene, options,
default_rng(planner.seed))`, with no state carried from one task to the next, so a row
depends on the spec alone, not on the chunk, the worker or the order. A task that raises
becomes a row with outcome 'error' and the exception in `error`; the chunk goes on.

Outcomes: 'failure_tolerant' (a verified plan), 'not_failure_tolerant' (a collision-free
configuration reaches both the start and the goal, but there is no failure-tolerant plan),
'unreachable' (the start or the goal is out of reach, or every configuration reaching it
collides), 'error'.
"""

from __future__ import annotations

import os
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pyarrow as pa

from ..core import InputError, plan
from .results import rows_to_table
from .spec import AXES, Study, StudyTask


@dataclass(frozen=True)
class ChunkResult:
    """A chunk's rows and when and where it ran (wall-clock seconds since the epoch)."""

    table: pa.Table
    worker: str
    started: float
    finished: float


def run_chunk(study: Study, tasks: Sequence[int],
              plan_task: Callable[[Study, int], dict] | None = None) -> ChunkResult:
    """Plan `tasks` (indices) one after the other; the Dask task of a study."""
    plan_task = plan_task or plan_study_task
    started = time.time()
    rows = []
    for index in tasks:
        try:
            rows.append(plan_task(study, index))
        except Exception as error:  # a task that raises is a result, not the end of the study
            rows.append(error_row(study, index, _describe_error(error)))
    finished = time.time()
    return ChunkResult(rows_to_table(rows, study.dim), _worker_name(), started, finished)


def plan_study_task(study: Study, index: int) -> dict:
    """Plan task `index` of the study; return its row (a dict of `result_schema` columns)."""
    task = study.task(index)
    return task_inputs(study, task) | _plan(study, task)


def error_row(study: Study, index: int, error: str) -> dict:
    """Make the row of task `index`, which failed with the message `error`."""
    try:
        row = task_inputs(study, study.task(index))
    except Exception:  # the inputs cannot be drawn: the row keeps its index only
        row = {'task': index}
    return row | {'feasible': False, 'outcome': 'error', 'error': error}


def task_inputs(study: Study, task: StudyTask) -> dict:
    """Return the columns that say what the task is: index, positions, added obstacles."""
    dim = study.dim
    row: dict = {'task': task.index}
    for end, point in (('start', task.start), ('goal', task.goal)):
        row.update({f'{end}_{axis}': value for axis, value in zip(AXES, point, strict=False)})
    row['random_obstacles'] = len(task.added_obstacles)
    row['obstacle_centers'] = [list(ob.center[:dim]) for ob in task.added_obstacles]
    row['obstacle_radii'] = [ob.radius for ob in task.added_obstacles]
    return row


def _plan(study: Study, task: StudyTask) -> dict:
    """Plan the task; return the outcome columns."""
    robot = task.scene.robot
    for name, x in (('task.start', task.start), ('task.goal', task.goal)):
        if not robot.can_reach(np.asarray(x)):
            return {'feasible': False, 'outcome': 'unreachable',
                    'reason': f'{name} {list(x)} is out of the arm\'s reach'}
    settings = study.planner
    try:
        result = plan(task.scene, settings.options(), np.random.default_rng(settings.seed))
    except InputError as error:
        # The planner names the position its inverse kinematics cannot reach; the same
        # field also says that start and goal coincide, which is no question of reach.
        apart = np.linalg.norm(np.subtract(task.start, task.goal)) > \
            task.scene.task.goal_tolerance
        if error.field in ('task.start', 'task.goal') and apart:
            return {'feasible': False, 'outcome': 'unreachable', 'reason': str(error)}
        raise
    if result.feasible:
        outcome = 'failure_tolerant'
    else:
        reached = all(any(branch.free(settings.margin).any() for branch in branches)
                      for branches in (result.start_manifolds, result.goal_manifolds))
        outcome = 'not_failure_tolerant' if reached else 'unreachable'
    stats = result.stats
    return {'feasible': result.feasible, 'outcome': outcome, 'reason': result.reason,
            'theta_s': None if result.theta_s is None else result.theta_s.tolist(),
            'plan_time_s': stats.get('plan_time_s'),
            'method': stats.get('method') if result.feasible else None,
            'min_clearance': stats.get('min_clearance_m') if result.feasible else None}


def _describe_error(error: Exception) -> str:
    """'Type: message (at file.py:line)', the line being where it was raised."""
    frames = traceback.extract_tb(error.__traceback__)
    where = f' (at {os.path.basename(frames[-1].filename)}:{frames[-1].lineno})' \
        if frames else ''
    return f'{type(error).__name__}: {error}{where}'


def _worker_name() -> str:
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return f'pid {os.getpid()}'
