"""`ftplan study` on a real LocalCluster of 2 worker processes: results, resuming, dying workers.

The grids are tiny (a few dozen plans of about 50 ms), so each test takes seconds.
"""

import os
from functools import partial

import numpy as np
import pytest

from ftplan_ros.core import plan
from ftplan_ros.study import ResultStore, StudyError, open_client, run_study, summarize
from ftplan_ros.study.figures import map_figure, sweep_figure
from ftplan_ros.study.results import OUTCOMES
from ftplan_ros.study.tasks import plan_study_task

from .interrupt import Interrupt
from .specs import study_of

# 5 x 4 starts over the fig3a scene: inside and outside the reach, near and in obstacles.
MAP = {'scene': 'fig3a.yaml', 'vary': {'start': {'x': [-3.2, 2.0, 5], 'y': [-1.8, 1.2, 4]}},
       'planner': {'seed': 0}, 'chunk': 3}
SWEEP = {'scene': 'paper_a_free.yaml',
         'vary': {'random': {'tasks': 12, 'seed': 5, 'start': {'radius': [1.8, 2.6]},
                             'goal': {'radius': [0.9, 1.5]},
                             'obstacles': {'count': [0, 3], 'radius': [0.1, 0.3]}}},
         'chunk': 4}
COMPARED = ['task', 'start_x', 'start_y', 'goal_x', 'goal_y', 'random_obstacles',
            'obstacle_centers', 'obstacle_radii', 'feasible', 'outcome', 'reason', 'theta_s',
            'min_clearance', 'method', 'error']   # all but plan_time_s


# [s] how long a new cluster's workers may take to start on 2 shared cores beside the rest
# of the suite (a worker killed by a test was once not back after 180 s: tests that kill
# workers get a cluster of their own)
WORKERS_BACK = 180


@pytest.fixture
def doomed_client():
    """A LocalCluster of its own for a test that kills workers.

    Dask's nanny restarts a killed worker, but under load not always within minutes; the
    module's cluster stays whole for the other tests.
    """
    with open_client(None, workers=2) as client:
        client.wait_for_workers(2, timeout=WORKERS_BACK)
        yield client


@pytest.fixture(scope='module')
def reference():
    """The rows of the MAP study as this process plans them, without Dask."""
    study = study_of(MAP)
    return plan_here(study, range(study.tasks))


def rows(table):
    return table.select(COMPARED).to_pylist()


def plan_here(study, tasks):
    """The rows as this process plans them, without Dask."""
    return [{key: row.get(key) for key in COMPARED}
            for row in (plan_study_task(study, k) for k in tasks)]


def test_a_small_map_on_two_workers(client, reference, tmp_path):
    client.wait_for_workers(2, timeout=WORKERS_BACK)
    study = study_of(MAP)
    store = ResultStore(tmp_path, study)
    run = run_study(study, store, client)
    assert run.complete and run.computed_chunks == study.chunks == 7 and run.skipped_chunks == 0
    assert len({t.worker for t in run.timings}) == 2          # both workers planned
    table = store.read()
    assert table.column('task').to_pylist() == list(range(20))
    assert rows(table) == reference
    outcome = table.column('outcome').to_pylist()
    assert {'failure_tolerant', 'not_failure_tolerant', 'unreachable'} <= set(outcome)
    for row in table.to_pylist():
        start = np.array([row['start_x'], row['start_y']])
        scene = study.task(row['task']).scene
        assert row['error'] is None
        assert (row['method'] in ('paper_surface', 'recovery_sheets')) if row['feasible'] \
            else row['method'] is None
        if np.linalg.norm(start) > 3.0:                      # beyond the links' reach
            assert row['outcome'] == 'unreachable' and row['plan_time_s'] is None
            continue
        result = plan(scene, rng=np.random.default_rng(0))
        assert row['feasible'] == result.feasible and row['plan_time_s'] > 0
        if result.feasible:
            assert np.allclose(row['theta_s'], result.theta_s)
            assert row['min_clearance'] == pytest.approx(result.stats['min_clearance_m'])
        else:
            assert row['theta_s'] is None and row['reason'] == result.reason
    # The summary counts the rows; the figure colours each cell by its row's outcome.
    text = summarize(study, table)
    for name in OUTCOMES:
        assert f'{name:<24}{outcome.count(name):>8}' in text
    (outcome_ax, clearance_ax, *_) = map_figure(study, table).axes
    (cells,) = [a for a in outcome_ax.collections if a.get_gid() == 'outcome']
    codes = np.asarray(cells.get_array()).reshape(4, 5)
    assert codes.ravel().tolist() == [OUTCOMES.index(o) for o in outcome]
    for ax in (outcome_ax, clearance_ax):
        assert sum(p.get_gid() == 'obstacle' for p in ax.patches) == len(study.scene.obstacles)


def test_an_interrupted_study_resumes_where_it_stopped(client, reference, tmp_path):
    study = study_of(MAP)
    store = ResultStore(tmp_path, study)
    with pytest.raises(KeyboardInterrupt):
        run_study(study, store, client, Interrupt(chunks=2))
    kept = {path.name: path.stat() for path in tmp_path.glob('chunk-*.parquet')}
    assert len(kept) == 2
    run = run_study(study, ResultStore(tmp_path, study_of(MAP)), client)
    assert run.skipped_chunks == 2 and run.computed_chunks == study.chunks - 2
    for name, stat in kept.items():                          # the finished chunks stay as they were
        again = (tmp_path / name).stat()
        assert (again.st_ino, again.st_mtime_ns) == (stat.st_ino, stat.st_mtime_ns)
    table = ResultStore(tmp_path, study).read()
    assert table.column('task').to_pylist() == list(range(study.tasks))   # each task once
    assert rows(table) == reference
    assert not [p for p in tmp_path.iterdir() if p.name.startswith('.')]


def test_a_sweep_is_the_same_whatever_the_chunks(client, tmp_path):
    study = study_of(SWEEP)
    rechunked = study_of(SWEEP | {'chunk': 5})
    tables = []
    for spec, folder in ((study, tmp_path / 'a'), (rechunked, tmp_path / 'b')):
        store = ResultStore(folder, spec)
        run_study(spec, store, client)
        tables.append(store.read())
    assert rows(tables[0]) == rows(tables[1])
    table = tables[0]
    counts = table.column('random_obstacles').to_pylist()
    feasible = table.column('feasible').to_pylist()
    assert counts == [k % 4 for k in range(12)]
    figure = sweep_figure(study, table)
    (line,) = [a for a in figure.axes[0].lines if a.get_gid() == 'feasible_rate']
    expected = [np.mean([f for c, f in zip(counts, feasible, strict=True) if c == n])
                for n in range(4)]
    assert np.allclose(line.get_xdata(), range(4)) and np.allclose(line.get_ydata(), expected)
    assert [a for a in figure.axes[0].collections if a.get_gid() == 'wilson_band']


def raise_on_task_2(study, index):
    if index == 2:
        raise ZeroDivisionError('a bug in task 2')
    return plan_study_task(study, index)


def kill_worker_once(study, index, marker):
    """Kill the worker process at task 4 the first time (the marker file records it)."""
    if index == 4 and not marker.exists():
        marker.touch()
        os._exit(1)
    return plan_study_task(study, index)


def kill_worker_at_task_4(study, index):
    if index == 4:
        os._exit(1)
    return plan_study_task(study, index)


def test_a_task_that_raises_becomes_an_error_row(client, tmp_path):
    study = study_of(MAP)
    store = ResultStore(tmp_path, study)
    run_study(study, store, client, plan_task=raise_on_task_2)
    table = store.read()
    error = table.column('error').to_pylist()
    assert error[2].startswith('ZeroDivisionError: a bug in task 2 (at test_runner.py:')
    assert table.column('outcome').to_pylist()[2] == 'error'
    assert table.column('start_x').to_pylist()[2] == study.task(2).start[0]
    assert all(e is None for k, e in enumerate(error) if k != 2)
    assert '1 tasks raised' in summarize(study, table)


def bad_row(study, index):
    return {'task': index, 'feasible': 'perhaps'}   # not a bool: the chunk cannot be stored


def test_a_chunk_that_fails_outside_its_tasks_stops_the_study(client, tmp_path):
    study = study_of(MAP)
    with pytest.raises(StudyError, match='chunk [0-9]+ failed on the workers: Arrow'):
        run_study(study, ResultStore(tmp_path, study), client, plan_task=bad_row)
    assert not list(tmp_path.glob('chunk-*'))


def test_a_worker_that_dies_has_its_chunk_redone(doomed_client, reference, tmp_path):
    client = doomed_client
    study = study_of(MAP)
    marker = tmp_path / 'killed'
    store = ResultStore(tmp_path / 'out', study)
    before = set(client.run(os.getpid).values())
    run = run_study(study, store, client, plan_task=partial(kill_worker_once, marker=marker))
    assert marker.exists()                                   # a worker did die
    assert set(client.run(os.getpid).values()) != before     # and was replaced
    assert run.split_chunks == 0
    table = store.read()
    assert table.column('task').to_pylist() == list(range(study.tasks))
    assert rows(table) == reference


def test_a_task_that_always_kills_its_worker_becomes_an_error_row(doomed_client, reference,
                                                                  tmp_path):
    client = doomed_client
    study = study_of(MAP)
    store = ResultStore(tmp_path, study)

    def give_up_after_one_death(dask_scheduler):
        dask_scheduler.allowed_failures = 0

    client.run_on_scheduler(give_up_after_one_death)
    run = run_study(study, store, client, plan_task=kill_worker_at_task_4)
    assert run.split_chunks >= 1
    table = store.read()
    assert table.column('task').to_pylist() == list(range(study.tasks))
    error = table.column('error').to_pylist()
    assert error[4].startswith('KilledWorker')
    assert [r for r in rows(table) if r['task'] != 4] == [r for r in reference if r['task'] != 4]

