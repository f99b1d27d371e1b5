"""Reading the files a user gives (core/io/files.py): bounded, UTF-8, YAML with its traps closed."""

import pytest
from ftplan_testing import ftplan, one_line_error

from ftplan_ros.core import load_scene
from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.files import LARGEST_FILE, load_yaml, read_text


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


def test_a_file_is_read_only_if_it_is_a_regular_utf8_file_of_bounded_size(tmp_path):
    scene = tmp_path / 'scene.yaml'
    scene.write_text('robot: arm.yaml  # é\n', encoding='utf-8')
    assert read_text(scene, 'scene') == 'robot: arm.yaml  # é\n'
    refused = {tmp_path / 'nope.yaml': 'cannot read nope.yaml (no such file)',
               tmp_path: 'is not a regular file',
               tmp_path / 'latin1.yaml': 'latin1.yaml is not UTF-8 text',
               tmp_path / 'huge.yaml': f'huge.yaml is {LARGEST_FILE + 1} bytes, more than'}
    (tmp_path / 'latin1.yaml').write_bytes('# café\n'.encode('latin-1'))
    with open(tmp_path / 'huge.yaml', 'wb') as huge:
        huge.truncate(LARGEST_FILE + 1)  # sparse: no 10 MB written
    for path, problem in refused.items():
        with pytest.raises(InputError) as caught:
            read_text(path, 'robot.file')
        assert caught.value.field == 'robot.file' and problem in caught.value.problem


def test_yaml_reads_floats_as_yaml_1_2_does_and_names_the_line_of_a_problem():
    data = load_yaml('a: 1e-9\nb: .5E3\nc: -2e+2\nd: 7\ne: 1.5\nf: [1e3, "1e3"]\n', 'scene')
    assert data == {'a': 1e-9, 'b': 500.0, 'c': -200.0, 'd': 7, 'e': 1.5, 'f': [1000.0, '1e3']}
    assert isinstance(data['d'], int)
    with pytest.raises(InputError, match=r"^scene: malformed YAML at line 3, column 1: "
                                         r"duplicate key 'a'"):
        load_yaml('a: 1\nb: 2\na: 3\n', 'scene')
    with pytest.raises(InputError, match='^scene: malformed YAML at line 2'):
        load_yaml('a: [1, 2\nb: 3\n', 'scene')
