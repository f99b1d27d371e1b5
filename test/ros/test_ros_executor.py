"""The executor with the planner and the sim, in one process: bad inputs and phases."""

import time

import numpy as np
import pytest
import yaml
from ros_support import FIG3A, wait_for
from sensor_msgs.msg import JointState
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory

from ftplan_msgs_py import create_joint_state, create_locked_joint, read_joint_trajectory
from ftplan_ros.core import load_scene
from ftplan_ros.core.io.limits_file import load_joint_limits
from ftplan_ros.core.model.motion_limits import motion_limits_digest, robot_motion_limits
from ftplan_ros.core.model.paths import point_at_fraction
from ftplan_ros.nodes.executor import ExecutorNode
from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.nodes.reporting import parse_vector
from ftplan_ros.nodes.sim import SimNode
from ftplan_ros.plan_client import Outcome, PlanClient

STATUS = 'ftplan_executor: execution'
FAST = 2.0  # [rad/s] the executor's max_joint_speed for most tests
# For tests that must act while a phase is still running: fig3a's approach to θ_s then
# takes ~3.5 s and its nominal path ~7 s, so discovery and callbacks on a loaded machine
# still land in the phase (at FAST the approach is over in ~0.35 s).
SLOW = 0.2


def execution(ros, number):
    """The executor's statuses about execution `number`."""
    return [s for s in ros.probe.statuses(STATUS) if s.values.get('execution') == str(number)]


def state_of(ros, number, state):
    return wait_for(lambda: [s for s in execution(ros, number) if s.values['state'] == state],
                    what=f'execution {number} {state}')[0]


def start_suite(ros, speed: float):
    """Planner, executor and sim (no injector: the test plays the failures)."""
    ros.make(PlannerNode)
    ros.make(ExecutorNode, max_joint_speed=speed)
    ros.make(SimNode, max_joint_speed=4.0)
    return ros


@pytest.fixture
def suite(ros):
    return start_suite(ros, FAST)


@pytest.fixture
def slow_suite(ros):
    return start_suite(ros, SLOW)


def advertise_locks(ros):
    """Have the probe's /ftplan/locked_joint publisher matched by the executor and the sim."""
    ros.probe.advertise(JointState, '/ftplan/locked_joint', readers=2)


def plan(ros):
    client = PlanClient(context=ros.context)
    try:
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=60.0)
    finally:
        client.destroy_node()
    assert motion.result is Outcome.SUCCEEDED, motion.message
    wait_for(lambda: [s for s in ros.probe.statuses(STATUS)
                      if s.values['plan'] == motion.stamp], what='the executor to hold it')
    return motion


def execute(ros):
    response = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    assert response.success, response.message
    return int(response.message.split(':')[0].split()[1])


def reset(ros):
    """Repair the arm: the sim's and the executor's locked joints are forgotten."""
    assert ros.probe.call(Trigger, '/ftplan_sim/reset', Trigger.Request()).success
    assert ros.probe.call(Trigger, '/ftplan_executor/reset', Trigger.Request()).success


def test_execute_without_a_plan_or_while_busy_is_refused(slow_suite):
    ros = slow_suite
    response = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    assert not response.success and 'no plan yet' in response.message
    wait_for(lambda: ros.probe.logged('ftplan_executor', 'execute refused: no plan yet'))
    plan(ros)
    number = execute(ros)
    busy = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    assert not busy.success and 'still' in busy.message
    done = state_of(ros, number, 'done')
    assert float(done.values['goal_error_m']) < 0.01
    assert 'locked_joint' not in done.values
    # Another execution from the goal: back to theta_s, then the same path again.
    assert state_of(ros, execute(ros), 'done')


@pytest.mark.parametrize('planner, executor, scaling', [
    ({'max_velocity_scaling_factor': 0.5}, {}, (0.5, 1.0)),
    ({}, {'joint_limits_file': 'slow_joint2.yaml'}, (1.0, 1.0)),
], ids=['planner scaled', 'executor joint_limits_file'])
def test_a_plan_timed_within_other_motion_limits_is_refused_naming_both(ros, tmp_path, planner,
                                                                        executor, scaling):
    """Issue 36, item 3: the robot digest covers no motion limits; the executor ran a plan
    the planner had timed at half the robot's velocities, or for the robot's limits while
    the executor's joint_limits_file gave others."""
    slow = {'joint_limits': {'joint2': {'has_velocity_limits': True, 'max_velocity': 0.5}}}
    (tmp_path / 'slow_joint2.yaml').write_text(yaml.safe_dump(slow))
    executor = {name: str(tmp_path / value) for name, value in executor.items()}
    ros.make(PlannerNode, **planner)
    ros.make(ExecutorNode, max_joint_speed=FAST, **executor)
    ros.make(SimNode, max_joint_speed=4.0)
    motion = plan(ros)
    refused = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    robot = load_scene(FIG3A).robot
    own = robot_motion_limits(robot)
    planned = motion_limits_digest(own.scaled(*scaling))
    ours = motion_limits_digest(own if not executor else
                                load_joint_limits(tmp_path / 'slow_joint2.yaml',
                                                  robot.joint_names, own))
    assert not refused.success
    assert f'plan {motion.stamp} was timed within motion limits {planned}, but the ' \
        f'executor\'s are {ours} (joint_limits_file, ' in refused.message, refused.message


def test_a_lock_of_an_unknown_joint_is_logged_and_ignored(suite):
    ros = suite
    plan(ros)
    number = execute(ros)
    state_of(ros, number, 'nominal')
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('elbow'))
    wait_for(lambda: ros.probe.logged('ftplan_executor', "ignored lock of unknown joint 'elbow'"))
    done = state_of(ros, number, 'done')
    assert 'locked_joint' not in done.values                 # no recovery was started
    inputs = ros.probe.statuses('ftplan_executor: input')
    assert any(s.level == 'WARN' and 'elbow' in s.message for s in inputs)
    malformed = JointState(name=['joint1', 'joint2'])
    ros.probe.publish(JointState, '/ftplan/locked_joint', malformed)
    wait_for(lambda: ros.probe.logged('ftplan_executor', 'ignored locked-joint event'))


def test_a_lock_while_idle_is_remembered_and_the_locked_joint_is_never_commanded(suite):
    """Issue 10, row 6: a lock while idle was forgotten; the next execution moved joint2."""
    ros = suite
    ros.probe.listen(JointTrajectory, '/ftplan/joint_command')
    plan(ros)
    advertise_locks(ros)
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint2'))
    wait_for(lambda: ros.probe.logged('ftplan_executor', 'joint2 locked while no execution '
                                      'is running: remembered'))
    idle = [s for s in ros.probe.statuses(STATUS) if s.values.get('locked_joints')][-1]
    assert idle.values['state'] == 'idle' and idle.values['locked_joints'] == 'joint2'
    refused = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    assert not refused.success
    assert "['joint2'] locked (joint2 (while idle)) and would be commanded" in refused.message
    time.sleep(0.3)
    assert ros.probe.received('/ftplan/joint_command') == []      # nothing was commanded
    reset(ros)
    number = execute(ros)
    state_of(ros, number, 'done')
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint3'))
    wait_for(lambda: ros.probe.logged('ftplan_executor', 'joint3 locked while no execution'))
    again = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    assert not again.success and 'joint3' in again.message


def test_a_lock_while_approaching_stops_and_goes_on_with_the_joints_left(slow_suite):
    """Not failure-tolerant: stop, report, plan to the goal from there with joint1 held."""
    ros = slow_suite
    plan(ros)
    advertise_locks(ros)
    number = execute(ros)
    state_of(ros, number, 'approaching')
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint1'))
    wait_for(lambda: ros.probe.logged('ftplan_executor', 'joint1 locked while approaching '
                                      'theta_s, before the failure-tolerant nominal path'))
    done = state_of(ros, number, 'done')
    assert done.values['locked_joint'] == 'joint1'
    assert any('with the joints left' in s.message and s.level == 'WARN'
               for s in execution(ros, number))
    locked = np.array(parse_vector(done.values['lock_configuration']))
    final = wait_for(lambda: [s for s in ros.probe.statuses('ftplan_sim: arm')
                              if s.values['goal_reached'] == 'True'])[-1]
    assert np.array(parse_vector(final.values['configuration']))[0] == \
        pytest.approx(locked[0], abs=1e-6)
    assert final.values['collisions'] == '0'
    refused = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    assert not refused.success and f'joint1 (in execution {number})' in refused.message
    reset(ros)
    assert state_of(ros, execute(ros), 'done')


def test_a_lock_during_the_nominal_phase_is_recovered_by_the_core(slow_suite):
    ros = slow_suite
    motion = plan(ros)
    advertise_locks(ros)
    number = execute(ros)
    # At 0.2 rad/s the approach stops at each of its turns back: 10-20 s under load.
    wait_for(lambda: [s for s in execution(ros, number)
                      if s.values['state'] == 'nominal' and float(s.values['progress']) > 0.3],
             timeout=90.0)
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint3'))
    done = state_of(ros, number, 'done')
    assert done.values['locked_joint'] == 'joint3'
    assert 0.3 < float(done.values['lock_progress']) < 1.0
    assert float(done.values['goal_error_m']) < 0.01
    # The arm stopped on the nominal path, and joint3 stayed where it locked.
    locked = np.array(parse_vector(done.values['lock_configuration']))
    gaps = np.linalg.norm(motion.trajectory - locked, axis=1)
    assert gaps.min() < np.abs(np.diff(motion.trajectory, axis=0)).max() * 2
    final = wait_for(lambda: [s for s in ros.probe.statuses('ftplan_sim: arm')
                              if s.values['goal_reached'] == 'True'])[-1]
    q = np.array(parse_vector(final.values['configuration']))
    assert q[2] == pytest.approx(locked[2], abs=1e-6)
    assert final.values['collisions'] == '0'


def test_the_stop_after_a_lock_is_judged_on_joint_states_sent_after_it(ros):
    """Found by the drills on a loaded machine: joint states queued from before a lock,
    where the arm had stood, made the executor recover from there, not from where joint2
    had locked; its recovery command then fought the locked joint until stall_timeout."""
    recovery, theta_s, moved = _recovery_after_a_lock(ros, late=2, still=0)
    assert recovery.positions[:, 1] == pytest.approx(moved[1], abs=1e-9)
    assert abs(moved[1] - theta_s[1]) > 1e-3   # the two places differ in joint2


def test_standing_still_right_after_a_lock_is_not_yet_the_stop(ros):
    """Found by CI on a loaded machine: a controller that had not yet taken up the last
    command stood still for two joint states after the lock, then moved before it took up
    the stop. The executor recovered from where the arm had stood, and its recovery
    command held the locked joint where it no longer was until stall_timeout."""
    recovery, theta_s, moved = _recovery_after_a_lock(ros, late=0, still=2, settle=1.0)
    assert recovery.positions[:, 1] == pytest.approx(moved[1], abs=1e-9)
    assert abs(moved[1] - theta_s[1]) > 1e-3


def _recovery_after_a_lock(ros, late: int, still: int, settle: float = 0.2):
    """Lock joint2 early on the nominal path; return the recovery command, θ_s and the lock point.

    The probe plays the arm: it stands at θ_s, then after the lock sends `late` joint
    states stamped before the lock (at θ_s), `still` fresh ones at θ_s and then, for longer
    than the executor's `stop_settle_time` = `settle` [s], fresh ones where the arm went on
    and locked.
    """
    ros.make(PlannerNode)
    ros.make(ExecutorNode, max_joint_speed=FAST, stop_settle_time=settle)
    ros.probe.listen(JointTrajectory, '/ftplan/joint_command')
    motion = plan(ros)
    names = ('joint1', 'joint2', 'joint3')
    theta_s = motion.trajectory[0]
    ros.probe.advertise(JointState, '/joint_states', readers=2)    # planner and executor
    ros.probe.advertise(JointState, '/ftplan/locked_joint', readers=1)
    number = execute(ros)
    for _ in range(2):                      # the arm stands at θ_s: the nominal path begins
        stood = ros.probe.get_clock().now().to_msg()
        ros.probe.publish(JointState, '/joint_states', create_joint_state(names, theta_s,
                                                                          stamp=stood))
    state_of(ros, number, 'nominal')
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint2'))
    wait_for(lambda: ros.probe.logged('ftplan_executor', 'joint2 locked at about'))
    moved = point_at_fraction(motion.trajectory, 0.02)   # where the arm went on and locked
    states = [(theta_s, stood)] * late + [(theta_s, None)] * still + \
        [(moved, None)] * (int(settle / 0.05) + 10)
    for target, stamp in states:
        ros.probe.publish(JointState, '/joint_states', create_joint_state(
            names, target, stamp=stamp or ros.probe.get_clock().now().to_msg()))
        time.sleep(0.05)

    def after_the_stop():
        """The commands after the executor's stop (an empty command) on the lock."""
        commands = ros.probe.received('/ftplan/joint_command')
        stops = [k for k, command in enumerate(commands) if not command.points]
        return commands[stops[-1] + 1:] if stops else []

    recovery = read_joint_trajectory(wait_for(after_the_stop, what='the recovery command')[0],
                                     names)
    return recovery, theta_s, moved


def test_an_execution_without_joint_states_fails_after_start_timeout(ros):
    ros.make(PlannerNode)
    ros.make(ExecutorNode, start_timeout=0.5)
    plan(ros)
    number = execute(ros)
    failed = state_of(ros, number, 'failed')
    assert 'no joint state' in failed.values['reason']
