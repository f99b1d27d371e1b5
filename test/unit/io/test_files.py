"""Reading the files a user gives (core/io/files.py): bounded, UTF-8, YAML with its traps closed."""

import pytest
from ftplan_testing import ftplan, one_line_error

from ftplan_ros.core import load_scene


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
