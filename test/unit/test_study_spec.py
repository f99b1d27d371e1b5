"""Study specs, the results folder, rates and progress: everything of `ftplan study` but Dask."""

import io
import json
import math
import re
import socket
import subprocess
import sys
import threading

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml
from ftplan_testing import REPO, SCENES

from ftplan_ros.cli import Progress
from ftplan_ros.core import InputError
from ftplan_ros.study import ResultStore, load_study, parse_study, wilson_interval
from ftplan_ros.study.results import rows_to_table
from ftplan_ros.study.spec import OBSTACLE_GAP
from ftplan_ros.study.summary import summarize
from ftplan_ros.study.tasks import run_chunk, task_inputs

STUDIES = REPO / 'config' / 'studies'
MAP = {'scene': 'fig3a.yaml', 'vary': {'start': {'x': [-3.0, 3.0, 7], 'y': [-1.0, 1.0, 3]}},
       'chunk': 4}
SWEEP = {'scene': 'paper_a_free.yaml',
         'vary': {'random': {'tasks': 40, 'seed': 3, 'start': {'radius': [1.8, 2.6]},
                             'goal': {'x': [0.5, 1.5], 'y': [-1.0, 1.0]},
                             'obstacles': {'count': [1, 4], 'radius': [0.1, 0.3]}}},
         'planner': {'seed': 0, 'margin': 0.0}, 'chunk': 7}


def spec_with(base, path, value):
    """A copy of the spec `base` with the item at `path` set to `value` (KeyError: deleted)."""
    data = json.loads(json.dumps(base))
    node = data
    for key in path[:-1]:
        node = node[key]
    if value is KeyError:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return data


def study_of(data, name='test'):
    return parse_study(data, name=name, directory=SCENES)


# --- the shipped specs and the enumeration -----------------------------------------------------

def test_the_paper_map_covers_the_reachable_disk_with_the_goal_of_the_paper():
    study = load_study(STUDIES / 'paper_map.yaml')
    assert study.kind == 'map' and study.vary.endpoint == 'start'
    assert study.scene.task.goal == (1.0, 0.0) and len(study.scene.obstacles) > 0
    reach = sum(study.scene.robot.link_lengths)
    for values in study.vary.axes:
        assert min(values) <= -reach and max(values) >= reach
    assert study.tasks == math.prod(len(v) for v in study.vary.axes)
    assert study.chunks == math.ceil(study.tasks / study.chunk)


def test_the_obstacle_sweep_varies_the_obstacle_count_of_the_planar_3r():
    study = load_study(STUDIES / 'obstacle_sweep.yaml')
    assert study.kind == 'sweep' and study.scene.robot.n_joints == 3
    low, high = study.vary.obstacles.count
    counts = [len(study.task(k).added_obstacles) for k in range(3 * (high - low + 1))]
    assert sorted(set(counts)) == list(range(low, high + 1))
    assert all(counts.count(c) == 3 for c in set(counts))   # every count equally often


def test_map_tasks_run_x_fastest_and_keep_the_scene_goal():
    study = study_of(MAP)
    xs, ys = study.vary.axes
    assert study.tasks == 21 and study.chunks == 6
    assert list(study.chunk_tasks(5)) == [20]
    for k in range(study.tasks):
        task = study.task(k)
        assert task.start == (xs[k % 7], ys[k // 7])
        assert task.goal == (1.0, 0.0) and task.scene.task.start == task.start
        assert task.scene.obstacles == study.scene.obstacles
    with pytest.raises(IndexError):
        study.task(21)


def test_a_goal_map_keeps_the_scene_start_and_a_fixed_axis_is_a_slice():
    study = study_of(spec_with(MAP, ('vary',), {'goal': {'x': [0.5, 1.5, 3], 'y': 0.25}}))
    assert study.vary.shape == (3, 1)
    assert [study.task(k).goal for k in range(3)] == [(0.5, 0.25), (1.0, 0.25), (1.5, 0.25)]
    assert {study.task(k).start for k in range(3)} == {(2.0, 0.0)}


def test_random_tasks_depend_on_the_seed_and_the_index_only():
    study = study_of(SWEEP)
    other_chunks = study_of(spec_with(SWEEP, ('chunk',), 3))
    reseeded = study_of(spec_with(SWEEP, ('vary', 'random', 'seed'), 4))
    for k in (0, 17, 39):
        assert study.task(k) == other_chunks.task(k)
        assert study.task(k).start != reseeded.task(k).start
    assert study.digest() != other_chunks.digest()    # chunk files would not line up


def test_random_tasks_fall_in_their_regions_and_obstacles_keep_clear():
    study = study_of(SWEEP)
    for k in range(study.tasks):
        task = study.task(k)
        assert 1.8 <= np.linalg.norm(task.start) <= 2.6
        assert 0.5 <= task.goal[0] <= 1.5 and -1.0 <= task.goal[1] <= 1.0
        assert len(task.added_obstacles) == 1 + k % 4
        for obstacle in task.added_obstacles:
            assert 0.1 <= obstacle.radius <= 0.3 and obstacle.center[2] == 0.0
            centre = np.array(obstacle.center[:2])
            assert np.linalg.norm(centre) <= 3.0   # default region: within the arm's reach
            for point in ((0.0, 0.0), task.start, task.goal):
                assert np.linalg.norm(centre - point) > obstacle.radius + OBSTACLE_GAP
        assert task.scene.obstacles == task.added_obstacles   # the base scene has none


def test_the_digest_follows_the_scene_content_not_its_path(tmp_path):
    copy = tmp_path / 'fig3a.yaml'
    robot = str(REPO / 'config' / 'robots' / 'planar3r.yaml')
    copy.write_text((SCENES / 'fig3a.yaml').read_text().replace('../robots/planar3r.yaml', robot))
    moved = parse_study(spec_with(MAP, ('scene',), 'fig3a.yaml'), directory=tmp_path)
    assert moved.digest() == study_of(MAP).digest()
    copy.write_text(copy.read_text().replace('radius: 0.2', 'radius: 0.21', 1))
    changed = parse_study(spec_with(MAP, ('scene',), 'fig3a.yaml'), directory=tmp_path)
    assert changed.digest() != study_of(MAP).digest()


def test_the_spatial_sweep_plans_3d_tasks_of_the_4_dof_arm_with_spheres_in_reach():
    study = load_study(STUDIES / 'arm4_sweep.yaml')
    assert study.kind == 'sweep' and study.dim == 3 and study.scene.robot.n_joints == 4
    tasks = [study.task(k) for k in range(14)]
    assert all(len(t.start) == len(t.goal) == 3 for t in tasks)
    assert {len(t.added_obstacles) for t in tasks} == set(range(7))
    # The base column stands on the z axis, 0.04 m thick: no random sphere touches it.
    for task in (study.task(k) for k in range(study.tasks)):
        assert all(ob.center[0] - ob.radius > 0.04 for ob in task.added_obstacles), task.index
    rows = run_chunk(study, [0, 1, 2, 3]).table.to_pylist()
    assert [r['error'] for r in rows] == [None] * 4
    assert all(r['goal_z'] == tasks[r['task']].goal[2] for r in rows)
    assert any(r['feasible'] for r in rows)   # the base scene's task region has plans


def test_a_spatial_digest_follows_the_robot_geometry(tmp_path):
    robots = REPO / 'config' / 'robots'
    arm = (robots / 'arm4.yaml').read_text()
    scene = (SCENES / 'arm4_spheres.yaml').read_text()
    spec = {'scene': 'arm4_spheres.yaml',
            'vary': {'goal': {'x': [0.3, 0.4, 2], 'y': 0.1, 'z': 0.3}}}
    (tmp_path / 'arm4_spheres.yaml').write_text(scene.replace('../robots/arm4.yaml', 'arm4.yaml'))
    (tmp_path / 'arm4.yaml').write_text(arm)
    same = parse_study(spec, directory=tmp_path).digest()
    assert same == parse_study(spec, directory=SCENES).digest()
    (tmp_path / 'arm4.yaml').write_text(arm.replace('link_radius: 0.04', 'link_radius: 0.05'))
    assert parse_study(spec, directory=tmp_path).digest() != same

# --- validation ------------------------------------------------------------------------------

BAD_SPECS = [
    (MAP, ('vary',), KeyError, 'study.vary', 'is missing'),
    (MAP, ('planer',), {'seed': 1}, 'study.planer', 'unknown key'),
    (MAP, ('vary',), {'start': {'x': 1.0, 'y': 1.0}, 'goal': {'x': 1.0, 'y': 1.0}}, 'vary',
     'exactly one'),
    (MAP, ('vary', 'start', 'z'), [0.0, 1.0, 2], 'vary.start.z', '2-D'),
    (MAP, ('vary', 'start', 'y'), KeyError, 'vary.start.y', 'is missing'),
    (MAP, ('vary', 'start', 'x'), [-3.0, 3.0, 0], 'vary.start.x[2]', 'integer >= 1'),
    (MAP, ('vary', 'start', 'x'), [-3.0, 3.0, 2.5], 'vary.start.x[2]', 'integer'),
    (MAP, ('vary', 'start', 'x'), [3.0, -3.0, 5], 'vary.start.x', 'above'),
    (MAP, ('vary', 'start', 'x'), [-3.0, 3.0], 'vary.start.x', '[low, high, count]'),
    (MAP, ('vary', 'start', 'x'), [float('nan'), 3.0, 5], 'vary.start.x[0]', 'finite'),
    (MAP, ('vary', 'start', 'x'), [-3.0, 3.0, 10_000_000], 'vary.start', 'at most'),
    (MAP, ('vary', 'start', 'x'), 'wide', 'vary.start.x', 'number'),
    (MAP, ('chunk',), 0, 'chunk', '>= 1'),
    (MAP, ('chunk',), True, 'chunk', 'integer'),
    (MAP, ('planner',), {'methods': ['rrt']}, 'planner.methods', 'paper_surface'),
    (MAP, ('planner',), {'methods': ['recovery_sheets']}, 'planner.methods', 'comes first'),
    (MAP, ('planner',), {'margin': -0.1}, 'planner.margin', '>= 0'),
    (MAP, ('planner',), {'seed': -1}, 'planner.seed', '>= 0'),
    (MAP, ('scene',), 'no_such_scene.yaml', 'scene', 'cannot read'),
    (MAP, ('scene',), 3, 'scene', 'path'),
    (SWEEP, ('vary', 'random', 'tasks'), 0, 'vary.random.tasks', '>= 1'),
    (SWEEP, ('vary', 'random', 'seed'), 'one', 'vary.random.seed', 'integer'),
    (SWEEP, ('vary', 'random', 'start'), {'radius': [2.6, 1.8]}, 'vary.random.start.radius',
     'above'),
    (SWEEP, ('vary', 'random', 'start'), {'radius': [-1.0, 1.8]}, 'vary.random.start.radius',
     '>= 0'),
    (SWEEP, ('vary', 'random', 'start'), {'radius': [1.0, 2.0], 'x': [0.0, 1.0]},
     'vary.random.start.x', 'unknown key'),
    (SWEEP, ('vary', 'random', 'goal', 'x'), [0.5, 1.5, 3], 'vary.random.goal.x', '[low, high]'),
    (SWEEP, ('vary', 'random', 'obstacles', 'count'), [0, 2.5], 'vary.random.obstacles.count[1]',
     'integer'),
    (SWEEP, ('vary', 'random', 'obstacles', 'count'), [-1, 2], 'vary.random.obstacles.count',
     '[0, 1000]'),
    (SWEEP, ('vary', 'random', 'obstacles', 'radius'), [0.0, 0.2],
     'vary.random.obstacles.radius', '> 0'),
    (SWEEP, ('vary', 'random', 'obstacles', 'shape'), 'cube', 'vary.random.obstacles.shape',
     'unknown key'),
    (SWEEP, ('vary', 'random'), {'tasks': 10}, 'vary.random', 'varies nothing'),
]


@pytest.mark.parametrize(('base', 'path', 'value', 'field', 'problem'), BAD_SPECS,
                         ids=[f'{"-".join(map(str, b[1]))}={b[2]!r}' for b in BAD_SPECS])
def test_a_bad_spec_names_its_field(base, path, value, field, problem):
    with pytest.raises(InputError) as caught:
        study_of(spec_with(base, path, value))
    assert caught.value.field == field
    assert problem in caught.value.problem


def test_a_bad_base_scene_is_named_with_its_field(tmp_path):
    (tmp_path / 'bad.yaml').write_text('robot: {type: planar, link_lengths: [1.0, -1.0, 1.0]}\n'
                                       'task: {start: [1.5, 0.0], goal: [1.0, 0.0]}\n')
    with pytest.raises(InputError, match=r'^scene bad.yaml: robot.link_lengths\[1\]: must be > 0'):
        parse_study(spec_with(MAP, ('scene',), 'bad.yaml'), directory=tmp_path)


def test_a_map_needs_the_scene_task(tmp_path):
    (tmp_path / 'no_task.yaml').write_text('robot: {type: planar, link_lengths: [1, 1, 1]}\n')
    with pytest.raises(InputError) as caught:
        parse_study(spec_with(MAP, ('scene',), 'no_task.yaml'), directory=tmp_path)
    assert caught.value.field == 'vary.start' and 'task.goal' in caught.value.problem


def test_the_cli_rejects_a_bad_spec_in_one_line_before_starting_a_cluster(tmp_path):
    spec = tmp_path / 'spec.yaml'
    spec.write_text(yaml.safe_dump(spec_with(MAP, ('scene',), str(SCENES / 'fig3a.yaml')) |
                                   {'chunk': -5}))
    for extra, field in (((), 'chunk:'), (('--workers', '0'), '--workers:'),
                         (('--workers', '100000'), '--workers:'),
                         (('--workers', '2', '--scheduler', 'tcp://127.0.0.1:1'), '--workers:')):
        run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out',
                              tmp_path / 'out', *extra], capture_output=True, text=True,
                             timeout=120)
        assert run.returncode == 2, run.stderr
        lines = run.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f'ftplan: error: {field}'), run.stderr
    assert not (tmp_path / 'out').exists()
    spec.write_text('scene: [unclosed\n')
    run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out',
                          tmp_path / 'out'], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2 and 'malformed YAML at line' in run.stderr



@pytest.mark.parametrize('address', ['tls://127.0.0.1:1'])  # a TypeError in Dask
def test_a_scheduler_that_cannot_be_reached_is_one_line_naming_the_flag(tmp_path, address):
    spec = tmp_path / 'spec.yaml'
    spec.write_text(yaml.safe_dump(spec_with(MAP, ('scene',), str(SCENES / 'fig3a.yaml'))))
    run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out',
                          tmp_path / 'out', '--scheduler', address], capture_output=True,
                         text=True, timeout=120)
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    assert lines[0].startswith('ftplan: error: --scheduler: cannot connect'), run.stderr


def test_a_server_that_accepts_but_never_answers_is_given_up_naming_the_flag(tmp_path):
    """Issue 11's note: Dask's handshake has no deadline, so this hung the study for good."""
    server = socket.create_server(('127.0.0.1', 0))
    accepted = []
    threading.Thread(target=lambda: accepted.append(server.accept()), daemon=True).start()
    spec = tmp_path / 'spec.yaml'
    spec.write_text(yaml.safe_dump(spec_with(MAP, ('scene',), str(SCENES / 'fig3a.yaml'))))
    with server:
        run = subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', 'study', spec, '--out',
                              tmp_path / 'out', '--scheduler',
                              f'tcp://127.0.0.1:{server.getsockname()[1]}'],
                             capture_output=True, text=True, timeout=120)
    lines = run.stderr.strip().splitlines()
    assert accepted and run.returncode == 2 and len(lines) == 1, run.stderr
    assert lines[0].startswith('ftplan: error: --scheduler: cannot connect') and \
        'no Dask scheduler answered' in lines[0], run.stderr

# --- the results folder ---------------------------------------------------------------------------

def rows_of(study, chunk, **columns):
    return rows_to_table([task_inputs(study, study.task(k)) | columns
                          for k in study.chunk_tasks(chunk)], study.dim)


def test_chunks_are_written_whole_and_found_again(tmp_path):
    study = study_of(MAP)
    store = ResultStore(tmp_path / 'out', study)
    store.open()
    assert store.finished_chunks() == set()
    store.write(2, rows_of(study, 2, feasible=True, outcome='failure_tolerant'))
    store.write(5, rows_of(study, 5, feasible=False, outcome='unreachable'))
    assert store.finished_chunks() == {2, 5}
    assert sorted(p.name for p in (tmp_path / 'out').iterdir()) == [
        'chunk-000002.parquet', 'chunk-000005.parquet', 'study.json']
    table = store.read()
    assert table.column('task').to_pylist() == [8, 9, 10, 11, 20]
    assert table.column('outcome').to_pylist() == ['failure_tolerant'] * 4 + ['unreachable']
    assert pq.read_table(store.chunk_path(5)).column('start_x').to_pylist() == [3.0]
    manifest = json.loads((tmp_path / 'out' / 'study.json').read_text())
    assert manifest['digest'] == study.digest() and manifest['tasks'] == 21
    # Reopening (a rerun) keeps the chunks and removes what a killed writer left.
    (tmp_path / 'out' / '.chunk-000003.parquet.tmp-12345').write_bytes(b'PAR1 half')
    again = ResultStore(tmp_path / 'out', study_of(MAP))
    again.open()
    assert again.finished_chunks() == {2, 5}
    assert not list((tmp_path / 'out').glob('.*'))


def test_a_chunk_with_the_wrong_tasks_is_refused(tmp_path):
    study = study_of(MAP)
    store = ResultStore(tmp_path, study)
    store.open()
    with pytest.raises(ValueError, match='chunk 1 must hold tasks 4..7'):
        store.write(1, rows_of(study, 0))
    assert store.finished_chunks() == set()


def test_a_folder_of_another_study_is_refused(tmp_path):
    ResultStore(tmp_path, study_of(MAP)).open()
    other = study_of(spec_with(MAP, ('planner',), {'margin': 0.01}))
    with pytest.raises(InputError) as caught:
        ResultStore(tmp_path, other).open()
    assert caught.value.field == '--out' and 'another study' in caught.value.problem
    stray = tmp_path / 'stray'
    stray.mkdir()
    (stray / 'chunk-000000.parquet').write_bytes(b'')
    with pytest.raises(InputError, match='no study.json'):
        ResultStore(stray, other).open()


# --- rates and progress ------------------------------------------------------------------------

def test_wilson_interval_bounds_and_known_values():
    z2 = 1.959963984540054 ** 2
    low, high = wilson_interval(0, 10)
    assert low == 0.0 and high == pytest.approx(z2 / (10 + z2))    # closed form for k = 0
    low, high = wilson_interval(10, 10)
    assert high == pytest.approx(1.0) and low == pytest.approx(10 / (10 + z2))
    k = np.array([1, 5, 13, 40])
    n = np.array([10, 10, 50, 40])
    low, high = wilson_interval(k, n)
    mirror_low, mirror_high = wilson_interval(n - k, n)
    assert np.allclose(low, 1 - mirror_high) and np.allclose(high, 1 - mirror_low)
    assert np.all((low <= k / n) & (k / n <= high))
    narrow = wilson_interval(50, 100)
    wide = wilson_interval(5, 10)
    assert narrow[1] - narrow[0] < wide[1] - wide[0]
    assert tuple(wilson_interval(0, 0)) == (0.0, 1.0)


def test_progress_prints_rate_and_eta_at_most_once_a_second():
    now = [100.0]
    stream = io.StringIO()
    progress = Progress(stream, clock=lambda: now[0])
    progress.begin(200)                       # 200 done by an earlier run
    now[0] = 110.0
    progress.count(300, 1200, 'tasks')        # 100 in 10 s: 10/s, 900 left: 90 s
    now[0] = 110.5
    progress.count(305, 1200, 'tasks')        # within the second: quiet
    now[0] = 190.0
    progress.count(1200, 1200, 'tasks')       # the end always prints
    lines = stream.getvalue().splitlines()
    assert len(lines) == 2
    assert lines[0].endswith('300/1200 tasks, 10.0 tasks/s, ETA 90 s')
    assert lines[1].endswith('1200/1200 tasks, 11.1 tasks/s')


# --- a chunk, planned in this process ------------------------------------------------------------

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


def test_the_summary_of_a_sweep_whose_obstacles_never_fit_counts_every_error():
    crowded = spec_with(SWEEP, ('vary', 'random', 'obstacles'),
                        {'count': [1, 1], 'radius': [0.2, 0.3], 'region': {'radius': [0.0, 0.1]}})
    study = study_of(crowded)
    text = summarize(study, run_chunk(study, [0, 1, 2]).table)
    assert re.search(r'^error\s+3\b', text, re.MULTILINE), text
