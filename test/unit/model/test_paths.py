"""Joint-space polylines (core/model/paths.py) against their definitions."""

import numpy as np
import pytest

from ftplan_ros.core.model.paths import (
    cumulative_fractions,
    densify,
    path_length,
    path_until,
    point_at_fraction,
)

PATH = np.array([[0.0, 0.0], [3.0, 4.0], [3.0, 4.0], [3.0, 10.0]])  # segments of 5, 0 and 6


def test_length_and_fractions_count_a_repeated_point_as_no_length():
    assert path_length(PATH) == pytest.approx(11.0)
    assert np.allclose(cumulative_fractions(PATH), [0.0, 5 / 11, 5 / 11, 1.0])
    still = np.zeros((3, 2))  # no length: the fractions spread evenly, not 0 / 0
    assert path_length(still) == 0.0
    assert np.array_equal(cumulative_fractions(still), [0.0, 0.5, 1.0])


@pytest.mark.parametrize('fraction, point', [
    (0.0, [0.0, 0.0]), (2.5 / 11, [1.5, 2.0]), (5 / 11, [3.0, 4.0]), (8 / 11, [3.0, 7.0]),
    (1.0, [3.0, 10.0]), (-0.5, [0.0, 0.0]), (1.5, [3.0, 10.0])])
def test_the_point_at_a_fraction_of_the_length(fraction, point):
    assert np.allclose(point_at_fraction(PATH, fraction), point)


def test_the_path_until_a_fraction_ends_at_the_point_at_that_fraction():
    part = path_until(PATH, 8 / 11)
    assert np.allclose(part, [[0.0, 0.0], [3.0, 4.0], [3.0, 4.0], [3.0, 7.0]])
    assert path_length(part) == pytest.approx(8.0)
    assert np.allclose(path_until(PATH, 0.0), [[0.0, 0.0]])


def test_dense_points_keep_every_vertex_and_step_at_most_the_bound():
    rng = np.random.default_rng(1)
    path = np.cumsum(rng.normal(0.0, 0.5, (6, 3)), axis=0)
    path = np.vstack([path[:3], path[2:]])  # a repeated vertex too
    dense = densify(path, 0.05)
    assert np.max(np.abs(np.diff(dense, axis=0))) <= 0.05 + 1e-12
    steps = [max(1, int(np.ceil(np.max(np.abs(b - a)) / 0.05)))
             for a, b in zip(path[:-1], path[1:], strict=True)]
    assert len(dense) == 1 + sum(steps)  # no more points than the bound needs
    vertices = np.concatenate([[0], np.cumsum(steps)])
    assert np.allclose(dense[vertices], path)
    assert path_length(dense) == pytest.approx(path_length(path))  # on the segments, in order
