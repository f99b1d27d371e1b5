"""Rates and summaries of a study (study/summary.py)."""

import re

import numpy as np
import pytest

from ftplan_ros.study import wilson_interval
from ftplan_ros.study.summary import summarize
from ftplan_ros.study.tasks import run_chunk

from .specs import SWEEP, spec_with, study_of


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


def test_the_summary_of_a_sweep_whose_obstacles_never_fit_counts_every_error():
    crowded = spec_with(SWEEP, ('vary', 'random', 'obstacles'),
                        {'count': [1, 1], 'radius': [0.2, 0.3], 'region': {'radius': [0.0, 0.1]}})
    study = study_of(crowded)
    text = summarize(study, run_chunk(study, [0, 1, 2]).table)
    assert re.search(r'^error\s+3\b', text, re.MULTILINE), text
