"""The planner's answer (core/paper/result.py) as the contract's JSON: finite and complete."""

import json
import math

import numpy as np
from ftplan_testing import paper_scene

from ftplan_ros.core import plan
from ftplan_ros.core.paper.result import PlanResult


def strict_json(data):
    """`data` through JSON that refuses NaN and Infinity (as CONTRACT.md's readers may)."""
    return json.loads(json.dumps(data, allow_nan=False))


def test_a_plan_among_no_obstacles_gives_null_for_its_infinite_clearance():
    result = plan(paper_scene())
    assert math.isinf(result.stats['min_clearance_m'])
    data = strict_json(result.to_json())
    assert data['stats']['min_clearance_m'] is None
    assert data['feasible'] is True and 'reason' not in data
    assert data['tolerated_joints'] == ['joint1', 'joint2', 'joint3']
    hits = np.array(data['failure_plane_hits'])
    assert hits.shape == (3, 3) and np.all((hits > -np.pi) & (hits <= np.pi))  # wrapped
    lower, upper = (np.array(data['hypercube'][key]) for key in ('lower', 'upper'))
    vertices = np.array(data['failure_surface']['paths']).reshape(-1, 3)
    assert np.all((lower <= vertices) & (vertices <= upper))


def test_a_refusal_keeps_its_reason_and_nulls_every_statistic_that_is_not_finite():
    refused = PlanResult(False, ('a', 'b', 'c'), reason='no start passes', stats={
        'time_s': 0.5, 'clearance': -math.inf, 'per_joint': (1.0, math.nan),
        'nested': {'bound': math.inf, 'count': 3}, 'tolerated_joints': ['b']})
    assert strict_json(refused.to_json()) == {
        'feasible': False, 'joint_names': ['a', 'b', 'c'], 'tolerated_joints': ['b'],
        'stats': {'time_s': 0.5, 'clearance': None, 'per_joint': [1.0, None],
                  'nested': {'bound': None, 'count': 3}},
        'reason': 'no start passes'}
    assert PlanResult(False, ('a', 'b')).to_json()['tolerated_joints'] == []
