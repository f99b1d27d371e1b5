"""A chunk of a study planned in this process (study/tasks.py): failures become error rows."""

from ftplan_ros.study.tasks import run_chunk

from .specs import MAP, SWEEP, spec_with, study_of


def test_a_chunk_plans_its_tasks_and_turns_failures_into_error_rows():
    study = study_of(spec_with(MAP, ('vary', 'start'), {'x': [1.0, 3.5, 3], 'y': 0.0}))
    result = run_chunk(study, [0, 1, 2])
    rows = result.table.to_pylist()
    assert [r['task'] for r in rows] == [0, 1, 2] and result.finished >= result.started
    assert rows[0]['outcome'] == 'error' and 'equals task.start' in rows[0]['error']  # the goal
    assert rows[2]['outcome'] == 'unreachable' and 'out of the arm' in rows[2]['reason']
    assert rows[1]['error'] is None and rows[1]['plan_time_s'] > 0


def test_a_task_whose_obstacles_do_not_fit_is_an_error_row():
    crowded = spec_with(SWEEP, ('vary', 'random', 'obstacles'),
                        {'count': [1, 1], 'radius': [0.2, 0.3], 'region': {'radius': [0.0, 0.1]}})
    (row,) = run_chunk(study_of(crowded), [3]).table.to_pylist()
    assert row['task'] == 3 and row['outcome'] == 'error'
    assert row['error'].startswith('InputError: vary.random.obstacles.region: no room')
