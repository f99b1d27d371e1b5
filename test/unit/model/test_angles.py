"""Angles on the torus (core/model/angles.py): wrapped to (-π, π], compiled as in numpy."""

import numpy as np
import pytest

from ftplan_ros.core.model.angles import (
    configuration_difference,
    wrap_angle,
    wrap_configuration,
    wrap_steps,
)


def test_compiled_steps_wrap_as_the_configuration_difference():
    """wrap_steps (the trace's and the sheets' compiled wrap) equals the numpy one, bit for
    bit, on one step and on rows of them, joints with and without limits mixed."""
    rng = np.random.default_rng(4)
    periodic = np.array([True, False, True])
    a, b = rng.uniform(-20.0, 20.0, (2, 50, 3))
    a[0, 0] = b[0, 0] + np.pi  # a half turn exactly
    assert np.array_equal(wrap_steps(a - b, periodic), configuration_difference(a, b, periodic))
    assert np.array_equal(wrap_steps(a[3] - b[3], periodic),
                          configuration_difference(a[3], b[3], periodic))


def test_wrapped_angles_lie_in_minus_pi_excluded_to_pi():
    angles = np.array([-np.pi, np.pi, 3 * np.pi, -3 * np.pi, 0.0, 7.0, -7.0, 1e6])
    wrapped = wrap_angle(angles)
    assert np.all((wrapped > -np.pi) & (wrapped <= np.pi))
    assert wrapped[0] == wrapped[1] == np.pi
    assert np.allclose(np.cos(wrapped), np.cos(angles)) and np.allclose(np.sin(wrapped),
                                                                        np.sin(angles), atol=1e-9)
    assert wrap_angle(0.5) == pytest.approx(0.5)


def test_only_periodic_joints_wrap_and_differences_go_round_the_short_way():
    periodic = np.array([True, False])
    assert np.allclose(wrap_configuration([4.0, 4.0], periodic), [4.0 - 2 * np.pi, 4.0])
    assert np.allclose(configuration_difference([3.0, 3.0], [-3.0, -3.0], periodic),
                       [6.0 - 2 * np.pi, 6.0])
