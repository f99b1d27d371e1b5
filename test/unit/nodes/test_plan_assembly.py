"""A plan from the latched topics (plan_assembly.py), as the executor and PlanClient read it.

Messages built by hand, no DDS: the four topics of a plan arrive in any order, S_F is
matched to the trajectory by content, and unreadable or disagreeing topics are named.
"""

import itertools

import numpy as np
import pytest
from builtin_interfaces.msg import Time

from ftplan_msgs_py import (
    create_diagnostic_array,
    create_diagnostic_status,
    create_failure_surface,
    create_joint_state,
    create_joint_trajectory,
)
from ftplan_ros.nodes.plan_assembly import PlanTopics

NAMES = ['joint1', 'joint2', 'joint3']
STAMP = Time(sec=12, nanosec=5)
KEY = '12.000000005'
NOMINAL = np.array([[0.0, 0.1, 0.2], [0.1, 0.2, 0.3], [0.2, 0.3, 0.4]])
SURFACE = np.stack([NOMINAL + 0.5, NOMINAL, NOMINAL - 0.5])  # the nominal path is path 1
INFO = {'stamp': KEY, 'robot': 'abc123', 'motion_limits': '123abc', 'obstacle_set': 'def456',
        'task_kind': 'planar', 'start': '[2.0, 0.0]', 'goal': '[1.0, 0.0]', 'tolerance': 0.01,
        'orientation_tolerance': 0.01, 'tolerated_joints': 'joint1,joint3'}


def info(values=INFO, stamp=STAMP, level='OK'):
    return create_diagnostic_array([create_diagnostic_status('ftplan_planner: plan', level,
                                                            'plan found', values)], stamp)


def deliver(topics: PlanTopics, topic: str, msg) -> None:
    if topic == 'info':
        assert topics.add_info(msg) == []
    else:
        getattr(topics, topic).append(msg)


MESSAGES = {
    'starts': create_joint_state(NAMES, NOMINAL[0], stamp=STAMP),
    'trajectories': create_joint_trajectory(NAMES, NOMINAL, [0.0, 1.0, 2.0], STAMP),
    'surfaces': create_failure_surface(SURFACE),
    'info': info(),
}


@pytest.mark.parametrize('order', list(itertools.permutations(MESSAGES)))
def test_a_plan_is_assembled_once_its_four_topics_are_in_whatever_their_order(order):
    topics = PlanTopics()
    for topic in order[:-1]:
        deliver(topics, topic, MESSAGES[topic])
        assert topics.assemble(KEY) is None
    deliver(topics, order[-1], MESSAGES[order[-1]])
    plan = topics.assemble(KEY)
    assert plan.key == KEY and topics.newest_key() == KEY
    assert plan.joint_names == tuple(NAMES) and plan.nominal == 1
    assert np.array_equal(plan.theta_s, NOMINAL[0]) and np.array_equal(plan.trajectory, NOMINAL)
    assert np.array_equal(plan.times, [0.0, 1.0, 2.0])
    assert np.array_equal(plan.surface.nominal_path, NOMINAL)
    assert plan.info.robot == 'abc123' and plan.info.tolerated_joints == ('joint1', 'joint3')


def test_a_plan_for_other_joints_is_named():
    topics = PlanTopics()
    for topic, msg in MESSAGES.items():
        deliver(topics, topic, msg)
    with pytest.raises(ValueError, match='elbow'):
        topics.assemble(KEY, ['joint1', 'joint2', 'elbow'])


def test_another_plans_surface_is_passed_over_for_the_plans_own():
    topics = PlanTopics(kept=3)
    for topic, msg in MESSAGES.items():
        if topic != 'surfaces':
            deliver(topics, topic, msg)
    topics.surfaces.append(create_failure_surface(SURFACE[:, :2]))       # another shape
    topics.surfaces.append(create_failure_surface(SURFACE[[0, 2]]))      # not holding it
    assert topics.assemble(KEY) is None
    topics.surfaces.appendleft(MESSAGES['surfaces'])                     # an older one does
    assert topics.assemble(KEY).nominal == 1


def test_an_unreadable_surface_is_named_unless_another_holds_the_trajectory():
    """Named at once: before the plan status too (the executor reports it, and stays up)."""
    empty = create_failure_surface(np.zeros((1, 1, 3)))
    empty.layout.dim[1].size = 0
    topics = PlanTopics(kept=2)
    for topic in ('starts', 'trajectories'):
        deliver(topics, topic, MESSAGES[topic])
    topics.surfaces.append(empty)
    with pytest.raises(ValueError, match='each must be >= 1'):
        topics.assemble(KEY)
    topics.surfaces.appendleft(MESSAGES['surfaces'])
    assert topics.assemble(KEY) is None                  # the plan status is on its way
    deliver(topics, 'info', MESSAGES['info'])
    assert topics.assemble(KEY).nominal == 1


def test_theta_s_away_from_the_start_of_the_trajectory_is_named():
    topics = PlanTopics()
    for topic, msg in MESSAGES.items():
        deliver(topics, topic, msg)
    topics.starts.append(create_joint_state(NAMES, NOMINAL[0] + 0.1, stamp=STAMP))
    with pytest.raises(ValueError, match='is not where the trajectory starts'):
        topics.assemble(KEY)


def test_plan_statuses_that_describe_no_plan_of_their_stamp_are_refused():
    topics = PlanTopics()
    assert topics.add_info(info(stamp=Time(sec=13))) == [
        'ignored /ftplan/plan/info: it describes no plan stamped 13.000000000']
    assert topics.add_info(info(level='WARN')) == [
        'ignored /ftplan/plan/info: it describes no plan stamped 12.000000005']
    assert topics.add_info(info(dict(INFO, tolerance='nan'))) != []
    assert topics.infos.get(KEY) is None
    assert topics.add_info(info()) == [] and topics.infos.get(KEY).task_kind == 'planar'


def test_only_the_latest_messages_are_kept():
    topics = PlanTopics()
    for topic, msg in MESSAGES.items():
        deliver(topics, topic, msg)
    later = Time(sec=20)
    topics.starts.append(create_joint_state(NAMES, NOMINAL[0], stamp=later))
    assert topics.newest_key() == '20.000000000'
    assert topics.assemble(KEY) is None                  # its θ_s was replaced
