"""Angles on the torus (core/model/angles.py): the compiled wraps against numpy's."""

import numpy as np

from ftplan_ros.core.model.angles import configuration_difference, wrap_steps


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
