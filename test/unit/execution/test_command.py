"""A command under way (command.py): where on it the arm is, by position, not by clock."""

import numpy as np
import pytest

from ftplan_ros.execution.command import Command

# Two steps of 1 rad in joint 1, then 1 rad in joint 2; 1 s and 3 s long.
PATH = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]])
COMMAND = Command(PATH, np.array([0.0, 1.0, 4.0]), stamp_ns=10**9)


def at(seconds: float) -> int:
    """ROS time [ns] `seconds` after the command's stamp."""
    return 10**9 + round(seconds * 1e9)


def test_the_fraction_commanded_by_a_moment_follows_the_timing():
    assert COMMAND.fraction_at(at(0.5)) == pytest.approx(0.25)
    assert COMMAND.fraction_at(at(2.5)) == pytest.approx(0.75)
    assert COMMAND.fraction_at(at(-1.0)) == 0.0 and COMMAND.fraction_at(at(9.0)) == 1.0


def test_a_moment_is_reached_when_the_arm_is_there_whenever_that_is():
    assert not COMMAND.reached(at(2.5), np.array([1.0, 0.4]))
    assert COMMAND.reached(at(2.5), np.array([1.0, 0.5]))
    assert COMMAND.reached(at(2.5), np.array([1.0, 0.5 - 1e-9]))  # stamps round to ns


def test_the_rest_starts_where_the_arm_is_and_keeps_the_corners():
    rest = COMMAND.rest(np.array([0.5, 0.0]))
    assert np.array_equal(rest, [[0.5, 0.0], [1.0, 0.0], [1.0, 1.0]])
    assert np.array_equal(COMMAND.rest(np.array([1.0, 0.5])), [[1.0, 0.5], [1.0, 1.0]])
    assert Command(PATH[:1], np.zeros(1), 0).rest(PATH[0]) is None


def test_deviation_and_arrival():
    assert COMMAND.deviation(np.array([0.5, 0.2])) == pytest.approx(0.2)
    assert COMMAND.ends_at(np.array([1.0, 1.0 - 1e-7]), 1e-6)
    assert not COMMAND.ends_at(np.array([1.0, 1.0 - 1e-5]), 1e-6)
