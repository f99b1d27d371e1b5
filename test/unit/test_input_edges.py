"""Edge cases of input and options that once crashed, passed NaN or rejected a good scene."""

import json
import subprocess
import sys

import pytest
from ftplan_testing import SCENES

from ftplan_ros.core import load_scene
from ftplan_ros.core.io.scene_file import parse_scene

ARM = {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]}
TASK = {'start': [2.0, 0.0], 'goal': [1.0, 0.0]}


def ftplan(*args):
    return subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def one_line_error(run, field):
    """The CLI's bad-input answer: exit 2 and one line naming the field, no traceback."""
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('ftplan: error: ') and field in lines[0], \
        run.stderr


def test_a_scene_that_is_not_utf8_is_one_line_of_error(tmp_path):
    scene = tmp_path / 'latin1.yaml'
    scene.write_bytes('robot: {type: planar}  # café\n'.encode('latin-1'))
    one_line_error(ftplan('plan', scene), 'UTF-8')


def test_a_number_too_big_for_a_float_is_one_line_of_error(tmp_path):
    scene = tmp_path / 'big.yaml'
    scene.write_text(f'robot: {{type: planar, link_lengths: [1.0, 1{"0" * 400}, 1.0]}}\n')
    one_line_error(ftplan('plan', scene), 'robot.link_lengths[1]')


def test_numbers_beyond_the_rounding_allowance_are_refused():
    with pytest.raises(ValueError, match=r'obstacles\[0\].radius'):
        parse_scene({'robot': ARM, 'task': TASK,
                     'obstacles': [{'type': 'sphere', 'center': [5.0, 0.0], 'radius': 1e10}]})


@pytest.mark.parametrize('args, field', [
    (['plan', SCENES / 'fig3a.yaml', '--png', 'figure.jpg'], '--png'),
    (['plan', SCENES / 'fig3a.yaml', '--seed', '-1'], '--seed'),
    (['drill', SCENES / 'fig3a.yaml', '--trials', '0'], '--trials'),
    (['bench', '--scenes', '0'], '--scenes'),
    (['bench', '--cells', '0'], '--cells'),
    (['bench', '--grid-baseline', '8'], '--grid-baseline'),
    (['bench', '--robot', 'panda', '--grid-baseline', '180'], '--grid-baseline'),
    (['bench', '--robot', 'iiwa14', '--cells', '64'], '--cells: sets the planar3r benchmark'),
    (['bench', '--robot', 'panda', '--crowded-cells', '64'], '--crowded-cells'),
])
def test_bad_flags_are_refused_before_any_work(tmp_path, args, field):
    out = tmp_path / 'plan.json'
    run = ftplan(*args, '--json', out) if args[0] == 'plan' else ftplan(*args)
    one_line_error(run, field)
    assert 'tracing' not in run.stderr and not out.exists()


def test_the_plan_json_has_no_infinity_without_obstacles(tmp_path):
    out = tmp_path / 'plan.json'
    assert ftplan('plan', SCENES / 'paper_a_free.yaml', '--json', out).returncode == 0

    def refuse(constant):
        raise AssertionError(f'{constant} is not JSON')
    data = json.loads(out.read_text(), parse_constant=refuse)
    assert data['feasible'] is True
    assert data['stats']['min_clearance_m'] is None  # infinite: no obstacle anywhere


@pytest.mark.parametrize('limits', [[-1000.0, 1000.0], [-7.0, 0.0]])
def test_joint_limits_wider_than_a_turn_either_way_are_refused(limits):
    with pytest.raises(ValueError, match=r'robot\.joint_limits\[1\]: limits must be within ±2π'):
        parse_scene({'robot': dict(ARM, joint_limits=[None, limits, None]), 'task': TASK})


def test_yaml_reads_exponent_floats_and_refuses_duplicate_keys(tmp_path):
    good = tmp_path / 'tight.yaml'
    good.write_text('robot: {type: planar, link_lengths: [1.0, 1.0, 1.0]}\n'
                    'task: {start: [2.0, 0.0], goal: [1.0, 0.0], goal_tolerance: 1e-3}\n')
    assert load_scene(good).task.goal_tolerance == pytest.approx(1e-3)
    twice = tmp_path / 'twice.yaml'
    twice.write_text('robot: {type: planar, link_lengths: [1.0, 1.0, 1.0]}\n'
                     'task: {start: [2.0, 0.0], goal: [1.0, 0.0], start: [1.5, 0.0]}\n')
    one_line_error(ftplan('plan', twice), "duplicate key 'start'")


@pytest.mark.parametrize('path', ['/dev/zero', '/'])
def test_a_path_that_is_not_a_regular_file_is_refused_without_reading_it(path):
    one_line_error(ftplan('plan', path), 'is not a regular file')


def test_benchmark_sizes_that_cannot_fit_in_memory_are_refused():
    one_line_error(ftplan('bench', '--cells', 100000), '--cells: must be at most')

