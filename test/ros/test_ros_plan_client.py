"""PlanClient: outcomes as an Enum with a message, no futures for the caller."""

import numpy as np
from ros_support import wait_for

from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.plan_client import Outcome, PlanClient


def test_without_a_planner_the_client_says_unavailable(ros_context):
    client = PlanClient(context=ros_context)
    try:
        assert not client.wait_until_ready(timeout=0.5)
        motion = client.plan(goal=(1.0, 0.0), timeout=0.5)
        assert motion.result is Outcome.UNAVAILABLE and '/ftplan/plan' in motion.message
        report = client.execute(timeout=0.5)
        assert report.result is Outcome.UNAVAILABLE
        assert client.trigger('/ftplan_sim/reset', timeout=0.2)[0] is False
    finally:
        client.destroy_node()


def test_a_failed_plan_carries_the_planners_reason(ros):
    ros.make(PlannerNode)
    client = PlanClient(context=ros.context)
    try:
        motion = client.plan(goal=(4.0, 0.0), start=(2.0, 0.0))
        assert motion.result is Outcome.FAILED and not motion.succeeded
        assert "out of the arm's reach" in motion.message
        assert motion.theta_s is None and motion.stamp
    finally:
        client.destroy_node()


def test_a_plan_comes_back_as_one_result(ros):
    ros.make(PlannerNode)
    client = PlanClient(context=ros.context)
    try:
        assert client.wait_until_ready(timeout=1.0) is False   # no executor in this test
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), tolerance=0.02)
    finally:
        client.destroy_node()
    assert motion.result is Outcome.SUCCEEDED, motion.message
    assert motion.joint_names == ('joint1', 'joint2', 'joint3')
    assert np.array_equal(motion.trajectory[0], motion.theta_s)
    assert np.array_equal(motion.surface[motion.nominal_index], motion.trajectory)
    assert np.all(np.diff(motion.times) > 0)
    assert np.allclose(motion.path[0, :2], [2.0, 0.0]) and motion.round_trip_s > 0
    assert np.linalg.norm(motion.path[-1, :2] - [1.0, 0.0]) <= 0.02   # the tolerance asked
    assert motion.plan_time_s > 0
    wait_for(lambda: ros.probe.logged('ftplan_planner', 'plan found'))
