"""The reach benchmark (ftplan_ros/bench/reach.py): its independent check, its check of an
approach and its table."""

from dataclasses import replace

import numpy as np
from ftplan_testing import SCENES, clearest_start

from ftplan_ros.bench.reach import (
    ReachRun,
    approach_checks,
    independent_reach,
    summarize_reach,
)
from ftplan_ros.core import load_scene
from ftplan_ros.core.planning.approach import Approach, Route
from ftplan_ros.core.planning.reachable import Outcome, plan_from


def test_the_independent_check_finds_the_tolerant_starts_of_fig3a_within_reach():
    scene = load_scene(SCENES / 'fig3a.yaml')
    q = clearest_start(scene)
    found = independent_reach(scene, q, cells=96, plane_cells=120, samples=360,
                              stop_at_first=False)
    assert not found.none and 0 < found.maybe_tolerant < found.starts_in_reach


def test_an_approach_through_a_disk_or_ending_beside_theta_s_fails_the_check():
    scene = load_scene(SCENES / 'fig3a.yaml')
    q = clearest_start(scene)
    answer = plan_from(scene, q)
    assert answer.ok and approach_checks(scene, q, answer)
    theta_s = answer.result.theta_s
    through = np.array([q, [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], theta_s])  # sweeps a disk
    short = np.vstack([answer.approach.path[:-1], answer.approach.path[-1] + 0.01])
    for path in (through, short):
        moved = replace(answer, approach=Approach(path, Route.GIVEN))
        assert not approach_checks(scene, q, moved)


def _run(index, outcome, plan_s, none, route=''):
    return ReachRun(index, outcome.value, plan_s, none, 10, 2.0, True,
                    outcome is Outcome.PLANNED and none, route, '', '')


def test_the_table_counts_outcomes_against_the_independent_check():
    runs = [_run(0, Outcome.PLANNED, 0.1, False, 'along M_s^F'),
            _run(1, Outcome.PLANNED, 0.3, False, 'along M_s^F'),
            _run(2, Outcome.NONE_REACHABLE, 0.5, True),
            _run(3, Outcome.NONE_FOUND, 2.0, False),
            _run(4, Outcome.PLANNED, 0.2, True, 'by a straight joint move')]
    text = summarize_reach(runs).splitlines()
    assert text[1].split()[-6:] == ['3', '1', '2', '0.20', '0.29', '0.30']
    assert text[2].split()[-6:] == ['1', '1', '0', '0.50', '0.50', '0.50']
    assert text[3].split()[-6:] == ['1', '0', '1', '2.00', '2.00', '2.00']
    assert text[4].endswith('contradictions: 1')
    assert text[5] == 'approaches: along M_s^F 2, by a straight joint move 1'
