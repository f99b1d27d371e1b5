"""The timeouts of a run (watchdog.py, through the executor's tick) and the joint-state watch."""

import numpy as np

from ftplan_ros.execution.actions import Stop
from ftplan_ros.execution.state import State
from ftplan_ros.execution.watchdog import JointStates

from .rig import final, stops


def test_a_run_without_a_joint_state_since_the_request_fails_after_start_timeout(rig):
    assert rig.start().success
    assert final(rig.tick(4.9)).state == State.APPROACHING
    actions = rig.tick(0.2)
    assert stops(actions) == 0                                # nothing was commanded
    failed = final(actions)
    assert failed.state == State.FAILED
    assert failed.message == 'no joint state on /joint_states since the request (start_timeout)'


def test_an_arm_that_does_not_stop_after_a_lock_fails_after_stop_timeout(rig):
    nominal = rig.nominal()
    rig.follow(nominal, until=0.3)
    rig.lock(1)
    actions = rig.tick(5.1)
    assert isinstance(actions[0], Stop)                       # once more: the first may be lost
    assert final(actions).message == ('the arm did not stop after the lock (no two equal joint '
                                      'states within stop_timeout)')


def test_joint_states_that_stop_during_a_run_trip_the_watchdog(rig):
    rig.follow(rig.nominal(), until=0.3)
    assert final(rig.tick(1.9)).state == State.NOMINAL
    actions = rig.tick(0.2)
    assert isinstance(actions[0], Stop)
    assert final(actions).message == ('watchdog: no joint state for more than 2.0 s '
                                      '(joint_state_timeout) while the arm was commanded: stop '
                                      'commanded')


def test_the_watchdog_waits_for_the_first_command(rig):
    """Before the arm moves, silence is start_timeout's case."""
    rig.at(rig.result.theta_s)
    assert rig.start().success
    assert final(rig.tick(3.0)).state == State.APPROACHING


def test_an_arm_standing_short_of_the_end_of_its_command_fails_after_stall_timeout(rig):
    rig.follow(rig.nominal(), until=0.3)
    for _ in range(9):                                        # 4.6 s of joint states, all equal
        rig.wait(0.5)
        rig.at(rig.q)
        assert final(rig.tick()).state == State.NOMINAL
    actions = rig.tick(0.5)
    assert isinstance(actions[0], Stop)
    assert final(actions).message == ('the arm stands still short of the end of the command '
                                      'while nominal (stall_timeout): stopped there')


def test_two_equal_joint_states_show_the_arm_standing():
    arm = JointStates()
    arm.take(np.zeros(3), 1.0, 1e-9)
    assert not arm.standing(1e-9) and arm.moved == 1.0        # one state says nothing yet
    arm.take(np.zeros(3), 2.0, 1e-9)
    assert arm.standing(1e-9) and arm.received == 2.0 and arm.moved == 1.0
    arm.take(np.array([0.0, 1e-6, 0.0]), 3.0, 1e-9)
    assert not arm.standing(1e-9) and arm.moved == 3.0
    arm.forget()
    assert arm.q is None and not arm.standing(1e-9)
