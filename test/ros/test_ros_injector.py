"""The injector: drill parsing, seeded random drills, manual and scheduled events."""

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.parameter import Parameter
from ros_support import wait_for
from sensor_msgs.msg import JointState
from spatial_scenes import JOINTS, TOLERATED, panda_scene
from std_srvs.srv import Trigger

from ftplan_msgs_py import create_diagnostic_array, create_diagnostic_status, read_locked_joint
from ftplan_ros.execution.motion import time_path
from ftplan_ros.nodes.executor import ExecutorNode
from ftplan_ros.nodes.injector import (
    DRILL_TOLERANCE,
    Drill,
    InjectorNode,
    lock_moment,
    parse_drill,
    random_drill,
)
from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.nodes.sim import SimNode
from ftplan_ros.plan_client import Outcome, PlanClient

NAMES = ('joint1', 'joint2', 'joint3')


def test_drills_parse_fractions_and_seconds():
    assert parse_drill('joint2@0.4', NAMES) == Drill('joint2', fraction=0.4)
    assert parse_drill(' joint1 @ 2.5s ', NAMES) == Drill('joint1', seconds=2.5)
    assert parse_drill('joint3@1', NAMES) == Drill('joint3', fraction=1.0)
    assert str(parse_drill('joint1@2.5s', NAMES)) == 'joint1@2.5s'


@pytest.mark.parametrize('text, problem', [
    ('joint9@0.5', "unknown joint 'joint9'"),
    ('joint1@1.5', 'must be in [0, 1]'),
    ('joint1', 'is not JOINT@FRACTION'),
    ('joint1@-0.2', 'is not JOINT@FRACTION'),
    ('joint1@nan', 'is not JOINT@FRACTION'),
])
def test_bad_drills_say_what_is_wrong(text, problem):
    with pytest.raises(ValueError, match=problem.replace('[', r'\[').replace(']', r'\]')):
        parse_drill(text, NAMES)


def test_random_drills_repeat_with_their_seed_and_cover_every_joint():
    def sequence(seed):
        rng = np.random.default_rng(seed)
        return [random_drill(rng, NAMES) for _ in range(10)]
    assert sequence(7) == sequence(7) != sequence(8)
    rng = np.random.default_rng(3)
    drills = [random_drill(rng, NAMES) for _ in range(200)]
    assert {d.joint for d in drills} == set(NAMES)
    assert all(0.0 <= d.fraction <= 1.0 for d in drills)


def test_a_fraction_drill_is_scheduled_when_the_nominal_command_reaches_it():
    """The moment comes from the command's stamp and times, the fraction from the path's
    length: the second segment is twice as long, but its time comes from its largest step."""
    nominal = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.2, 1.6]])  # lengths 1, 2
    times = time_path(nominal, 2.0)                                       # 0, 0.5, 1.3 s
    stamp = 7 * 10**9
    moment = lock_moment(nominal, nominal[1:], times[1:], stamp, 0.5, np.zeros(3, bool))
    assert moment == stamp + 700_000_000                    # a quarter into the second step
    start = lock_moment(nominal, nominal[1:], times[1:], stamp, 0.0, np.zeros(3, bool))
    end = lock_moment(nominal, nominal[1:], times[1:], stamp, 1.0, np.zeros(3, bool))
    assert (start, end) == (stamp, stamp + 1_300_000_000)
    # The arm's lift: whole turns apart on a periodic joint, it is the nominal path still.
    turned = nominal[1:] + [2.0 * np.pi, 0.0, 0.0]
    periodic = np.array([True, False, False])
    assert lock_moment(nominal, turned, times[1:], stamp, 0.5, periodic) == moment
    assert lock_moment(nominal, turned, times[1:], stamp, 0.5, ~periodic) is None
    # Any other command (an approach, a recovery, the nominal from elsewhere) is not it.
    for other in (nominal[1:] + 1e-6, nominal[2:], nominal[:2]):
        assert lock_moment(nominal, other, times[1:len(other) + 1], stamp, 0.5,
                           np.zeros(3, bool)) is None


@pytest.mark.parametrize('drill, locked, phase, landed, missed', [
    ('joint2@0.5', 'joint2', 'nominal', 0.5, ''),
    ('joint2@0.5', 'joint2', 'nominal', 0.519, ''),
    ('joint2@0.5', 'joint2', 'nominal', 0.479, 'lock landed at 47.9%, asked 50.0%'),
    ('joint2@0.5', 'joint2', 'nominal', 0.585, 'lock landed at 58.5%, asked 50.0%'),
    ('joint2@0.9', 'joint2', 'nominal', 1.0, 'lock landed at 100.0%: after the motion, '
                                             'asked 90.0%'),
    ('joint2@0.99', 'joint2', 'nominal', 1.0, ''),
    ('joint2@0.5', '', '', float('nan'), 'no lock during the execution'),
    ('joint2@0.5', 'joint3', 'nominal', 0.5, 'joint3 locked, not joint2'),
    ('joint2@0.0', 'joint2', 'approaching', float('nan'),
     'the lock landed while approaching, not on the nominal path'),
    ('joint2@0.5', 'joint2', 'nominal', float('nan'),
     'the executor did not report where the lock landed'),
    ('joint1@2.5s', 'joint1', 'approaching', float('nan'), ''),
    ('joint1@60s', '', '', float('nan'), 'no lock during the execution'),
])
def test_a_drill_says_how_a_runs_lock_missed_it(drill, locked, phase, landed, missed):
    assert parse_drill(drill, NAMES).missed(locked, phase, landed) == missed


def test_lock_now_publishes_one_event_and_clears_itself(ros):
    injector = ros.make(InjectorNode)
    ros.probe.listen(JointState, '/ftplan/locked_joint')
    wait_for(lambda: injector.lock_publisher.get_subscription_count() > 0)
    result = injector.set_parameters([Parameter('lock_now', value='joint3')])[0]
    assert result.successful
    event = read_locked_joint(wait_for(lambda: ros.probe.received('/ftplan/locked_joint'))[0])
    assert event.name == 'joint3' and event.angle is None
    wait_for(lambda: injector.get_parameter('lock_now').value == '', what='lock_now cleared')
    assert len(ros.probe.received('/ftplan/locked_joint')) == 1
    wait_for(lambda: ros.probe.logged('ftplan_injector', 'locked joint3: manual lock_now'))
    rejected = injector.set_parameters([Parameter('lock_now', value='elbow')])[0]
    assert not rejected.successful and "unknown joint 'elbow'" in rejected.reason
    bad = injector.set_parameters([Parameter('drills', value=['joint1@0.5', 'joint9@0.1'])])[0]
    assert not bad.successful and 'joint9' in bad.reason
    assert injector.queue == []
    assert len(ros.probe.received('/ftplan/locked_joint')) == 1


def test_a_drill_in_seconds_at_the_start_locks_during_the_approach(ros):
    """joint1@0.0s fires as the execution starts: the executor goes on with the joints left."""
    ros.make(PlannerNode)
    # Slow enough (the approach to θ_s takes ~3.5 s) that the injector, which learns of
    # the start from the executor's status, locks joint1 before the approach is over.
    ros.make(ExecutorNode, max_joint_speed=0.2)
    ros.make(SimNode, max_joint_speed=4.0)
    injector = ros.make(InjectorNode, drills=['joint1@0.0s', 'joint2@0.5'])
    wait_for(lambda: injector.lock_publisher.get_subscription_count() >= 2,
             what='the executor and the sim to read /ftplan/locked_joint')
    client = PlanClient(context=ros.context)
    try:
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=60.0)
        assert motion.result is Outcome.SUCCEEDED, motion.message
        first = client.execute(motion, timeout=60.0)
        assert first.result is Outcome.SUCCEEDED, first.message
        assert first.values['locked_joint'] == 'joint1'
        assert first.values['lock_phase'] == 'approaching'
        assert client.trigger('/ftplan_sim/reset')[0]
        assert client.trigger('/ftplan_executor/reset')[0]
        second = client.execute(motion, timeout=60.0)
    finally:
        client.destroy_node()
    assert second.result is Outcome.SUCCEEDED, second.message
    assert second.values['locked_joint'] == 'joint2'
    assert abs(second.number('lock_progress') - 0.5) <= DRILL_TOLERANCE
    wait_for(lambda: ros.probe.logged('ftplan_injector', 'execution 2: drill joint2@0.5'))
    assert ros.probe.call(Trigger, '/ftplan_sim/reset', Trigger.Request()).success


def test_random_drills_lock_only_the_joints_the_plan_tolerates(ros, tmp_path):
    """The executor's status names the plan's tolerated joints; random drills draw from them."""
    injector = ros.make(InjectorNode, panda_scene(tmp_path), random_drills=-1, seed=4)
    ros.probe.advertise(DiagnosticArray, '/diagnostics', readers=1)
    drills = []
    for execution in range(1, 41):
        values = {'state': 'approaching', 'execution': execution, 'plan': '1.0',
                  'tolerated_joints': ','.join(TOLERATED if execution <= 30 else JOINTS[:2])}
        ros.probe.publish(DiagnosticArray, '/diagnostics', create_diagnostic_array(
            [create_diagnostic_status('ftplan_executor: execution', 'OK', 'approaching', values)]))
        wait_for(lambda e=execution: injector.execution == e, what=f'execution {execution}')
        drills.append(injector.drill.joint)
    assert set(drills[:30]) == set(TOLERATED)            # every tolerated joint, elbow never
    assert set(drills[30:]) <= set(JOINTS[:2])


def test_a_drill_the_execution_ends_before_is_dropped_not_fired(ros):
    """The injector learns that the execution reached the goal before it saw the arm at
    the drill's fraction (no joint state here): the drill is dropped with a warning, and
    no lock reaches an executor that is no longer executing (it would refuse executions
    until reset; the injector used to fire then)."""
    injector = ros.make(InjectorNode, drills=['joint2@0.999'])
    ros.probe.listen(JointState, '/ftplan/locked_joint')
    ros.probe.advertise(DiagnosticArray, '/diagnostics', readers=1)
    wait_for(lambda: injector.lock_publisher.get_subscription_count() > 0)
    for state in ('approaching', 'nominal', 'done'):
        values = {'state': state, 'execution': 1, 'plan': '1.0'}
        ros.probe.publish(DiagnosticArray, '/diagnostics', create_diagnostic_array(
            [create_diagnostic_status('ftplan_executor: execution', 'OK', state, values)]))
        wait_for(lambda state=state: injector.state == state, what=f'the injector at {state}')
    wait_for(lambda: ros.probe.logged('ftplan_injector',
                                      'dropped drill joint2@0.999: execution 1 became done first'))
    assert not injector.pending
    assert ros.probe.received('/ftplan/locked_joint') == []
