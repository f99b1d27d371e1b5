"""Study specs (study/spec.py): the shipped ones, tasks enumerated, digests, bad specs named."""

import math

import numpy as np
import pytest
from ftplan_testing import REPO, SCENES

from ftplan_ros.core import InputError
from ftplan_ros.study import load_study, parse_study
from ftplan_ros.study.spec import OBSTACLE_GAP
from ftplan_ros.study.tasks import run_chunk

from .specs import MAP, SWEEP, spec_with, study_of

STUDIES = REPO / 'config' / 'studies'


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

