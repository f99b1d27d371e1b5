"""Edge cases of input and options that once crashed, passed NaN or rejected a good scene."""

import json

import pytest
from ftplan_testing import SCENES, ftplan, one_line_error

from ftplan_ros.core.io.scene_file import parse_scene

ARM = {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]}
TASK = {'start': [2.0, 0.0], 'goal': [1.0, 0.0]}


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


def test_benchmark_sizes_that_cannot_fit_in_memory_are_refused():
    one_line_error(ftplan('bench', '--cells', 100000), '--cells: must be at most')

