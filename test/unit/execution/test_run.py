"""A run's phases (run.py, through the executor): approach, tracking, locks on time, obstacles."""

import numpy as np

from ftplan_ros.core.model.paths import densify, point_at_fraction
from ftplan_ros.execution.actions import Stop
from ftplan_ros.execution.motion import time_at_fraction
from ftplan_ros.execution.run import surface_meets_obstacle
from ftplan_ros.execution.state import State

from .rig import commands, failure, final, statuses, stops

FULL_SET_FIX = 'publish a full set (a MarkerArray whose first marker is DELETEALL)'


def test_a_scheduled_lock_lands_where_the_command_puts_the_arm_at_its_stamp(rig):
    """Issue 33: a drill's lock, stamped ahead on the command's timeline, takes effect when
    the joint states show the arm there: not before, and not when the event arrives."""
    nominal = rig.nominal()
    halfway = nominal.stamp_ns + round(time_at_fraction(nominal.path, nominal.times, 0.5) * 1e9)
    actions = rig.lock(1, stamp_ns=halfway)
    assert stops(actions) == 0
    assert final(actions).message == ('joint2 locks at 50.0% of the command under way '
                                      '(nominal): scheduled')
    assert stops(rig.follow(nominal, until=0.45)) == 0
    actions = rig.at(point_at_fraction(nominal.path, 0.5))
    assert isinstance(actions[0], Stop)
    assert final(actions).message == 'joint2 locked at about 50.0% of the nominal path: stopping'


def test_a_lock_stamped_in_the_past_takes_effect_at_once(rig):
    rig.follow(rig.nominal(), until=0.3)
    actions = rig.lock(1, stamp_ns=rig.ros_ns - 10**9)
    assert isinstance(actions[0], Stop) and final(actions).state == State.RECOVERING


def test_an_arm_away_from_the_commanded_path_is_a_tracking_error(rig):
    nominal = rig.nominal()
    rig.follow(nominal, until=0.3)
    actions = rig.at(rig.q + [0.3, 0.0, 0.0])
    assert isinstance(actions[0], Stop)
    failed = final(actions)
    assert failed.state == State.FAILED and failed.level == 'ERROR'
    assert failed.message.startswith('tracking error: the arm is ')
    assert failed.message.endswith(' rad from the commanded path while nominal')


def test_a_path_that_would_move_a_locked_joint_is_never_commanded(rig):
    """A guard against a bug of the executor: here the lock list is changed behind its back."""
    approach = rig.approach([0.0, 0.0, 1.0])
    rig.executor.locks.lock(2, float(approach.path[0, 2]), 1)
    message = failure(rig.follow(approach))
    assert message.startswith('refused to command a path that moves locked joint joint3 by ')
    assert message.endswith(': the arm is stopped (please report)')


def test_an_arm_whole_turns_from_theta_s_follows_s_f_shifted_by_them(rig):
    """Joint 1 wraps: θ_s + 2π is θ_s, and the arm goes on in its own lift."""
    assert rig.start().success
    turned = rig.result.theta_s + [2 * np.pi, 0.0, 0.0]
    [nominal] = commands(rig.at(turned))
    assert np.allclose(nominal.path, rig.result.nominal_path + [2 * np.pi, 0.0, 0.0],
                       atol=1e-12, rtol=0)
    assert final(rig.follow(nominal)).state == State.DONE


def test_without_a_collision_free_approach_the_run_fails_where_the_arm_stands(make_rig):
    """Link 1 through the disk at (0.801, 0.445): no move out of it is collision-free."""
    rig = make_rig(approach_time=0.05)
    assert rig.start().success
    actions = rig.at([0.507, 0.0, 0.0])
    assert commands(actions) == [] and stops(actions) == 0
    assert final(actions).message.startswith('no collision-free approach to theta_s from where '
                                             'the arm stands: ')


def test_lost_obstacle_updates_during_a_run_stop_the_arm_and_fail_it(rig):
    rig.follow(rig.nominal(), until=0.3)
    rig.obstacles.lost = 'obstacle updates were lost (update 3 was not received)'
    actions = rig.executor.on_obstacles(rig.now())
    assert isinstance(actions[0], Stop)
    assert final(actions).message == (
        'obstacle updates were lost (update 3 was not received) while nominal: an obstacle may '
        f'be in the way unseen, so the arm is stopped where it is; {FULL_SET_FIX}, then plan '
        'again')


def test_an_obstacle_on_the_rest_of_the_nominal_path_stops_the_arm_there(rig):
    nominal = rig.nominal()
    rig.follow(nominal, until=0.3)
    rig.add_obstacle(rig.scene.robot.forward_kinematics(point_at_fraction(nominal.path, 0.8)),
                     0.02)
    actions = rig.executor.on_obstacles(rig.now())
    assert isinstance(actions[0], Stop) and final(actions).state == State.FAILED
    assert final(actions).message == ('an obstacle that arrived meets the rest of the motion '
                                      '(nominal, 30.0% of the nominal path): stopped there; plan '
                                      'again')


def test_an_obstacle_on_s_f_alone_stops_the_arm_on_the_nominal_path(rig):
    """At x_s: clear of the rest of the nominal path, but on S_F (θ_s is a vertex)."""
    nominal = rig.nominal()
    rig.follow(nominal, until=0.3)
    rig.add_obstacle(rig.scene.robot.forward_kinematics(rig.result.theta_s), 0.05)
    rest = densify(nominal.rest(rig.q), 0.01)
    assert rig.obstacles.checker.min_clearance(rest).min() > 0.0
    actions = rig.executor.on_obstacles(rig.now())
    assert isinstance(actions[0], Stop)
    assert final(actions).message == (
        'an obstacle that arrived meets the failure surface S_F: the rest of the motion would '
        'not be failure-tolerant (nominal, 30.0% of the nominal path): stopped there; plan again')


def test_an_obstacle_on_the_rest_of_the_approach_stops_the_arm_and_approaches_again(rig):
    approach = rig.approach([0.0, 0.0, 1.0])
    rig.follow(approach, until=0.2)
    tool = rig.scene.robot.forward_kinematics(point_at_fraction(approach.path, 0.5))
    rig.add_obstacle(tool, 0.02)
    assert not surface_meets_obstacle(rig.obstacles, rig.plan.surface)
    actions = rig.executor.on_obstacles(rig.now())
    assert isinstance(actions[0], Stop) and commands(actions) == []
    again = final(actions)
    assert again.state == State.APPROACHING and again.level == 'WARN'
    assert again.message == ('an obstacle that arrived meets the rest of the motion while '
                             'approaching theta_s: stopped; approaching again from where the arm '
                             'stands')
    [detour] = commands(rig.stand())
    assert np.array_equal(detour.path[0], rig.q)
    assert rig.obstacles.checker.min_clearance(densify(detour.path, 0.001)).min() > 0.0
    assert [s.state for s in statuses(rig.follow(detour))][-1] == State.NOMINAL


def test_obstacles_clear_of_the_motion_change_nothing(rig):
    rig.follow(rig.nominal(), until=0.3)
    rig.add_obstacle((-2.5, -2.5), 0.1)
    assert rig.executor.on_obstacles(rig.now()) == []
    assert rig.executor.state == State.NOMINAL
