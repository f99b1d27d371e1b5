"""The executor's verbs without ROS: runs accepted and refused, locks while idle, reset."""

import numpy as np
import pytest

from ftplan_ros.core import PlanarChain
from ftplan_ros.core.model.motion_limits import motion_limits_digest, robot_motion_limits
from ftplan_ros.core.model.paths import point_at_fraction
from ftplan_ros.execution.actions import Rejected, Stop
from ftplan_ros.execution.executor import Executor
from ftplan_ros.execution.options import ExecutorOptions
from ftplan_ros.execution.state import State

from .rig import INTERFACES, PLAN_KEY, commands, final, statuses, stops


def test_a_run_approaches_theta_s_then_follows_the_nominal_path_to_the_goal(rig):
    answer = rig.start()
    assert answer.success and answer.message == f'execution 1: plan {PLAN_KEY} accepted'
    assert final(answer.actions).state == State.APPROACHING
    aside = rig.result.theta_s + [0.0, 0.0, 0.05]
    actions = rig.at(aside)
    [approach] = commands(actions)
    assert np.array_equal(approach.path[0], aside)
    assert np.array_equal(approach.path[-1], rig.result.theta_s)
    assert approach.stamp_ns == rig.ros_ns  # it starts now
    assert final(actions).message.startswith('approaching theta_s ')
    actions = rig.follow(approach)
    [nominal] = commands(actions)
    assert np.array_equal(nominal.path, rig.result.nominal_path)
    assert nominal.stamp_ns == rig.ros_ns + round(0.05e9)  # nominal_lead
    assert np.all(np.diff(nominal.times) > 0.0)
    assert final(actions).state == State.NOMINAL
    done = final(rig.follow(nominal))
    assert done.state == State.DONE and done.level == 'OK'
    assert done.message.startswith('reached the goal (nominal path), error ')
    assert done.execution.goal_error < rig.scene.task.goal_tolerance


def test_joint_states_stamped_before_the_request_do_not_start_the_motion(rig):
    """They may show the arm before a reset that came just before the request."""
    stamp = rig.ros_ns
    rig.wait(0.5)
    assert rig.start().success
    assert rig.at(rig.result.theta_s, stamp_ns=stamp) == []
    assert commands(rig.at(rig.result.theta_s))


def test_execute_is_refused_without_a_plan_and_while_a_run_is_under_way(rig, fig3a):
    scene, _ = fig3a
    empty = Executor(rig.obstacles, ExecutorOptions(), INTERFACES)
    empty.use_robot(scene.robot, rig.now())
    refused = empty.start(rig.now())
    assert not refused.success and refused.actions == []
    assert refused.message == 'no plan yet: call the plan service (/ftplan/plan) first'
    assert rig.start().success
    busy = rig.start()
    assert not busy.success and busy.message == 'execution 1 is still approaching'


def test_a_lock_while_idle_is_remembered_and_refuses_runs_until_reset(rig):
    """Issue 10, row 6: a lock while idle was forgotten; the next run moved the joint."""
    rig.at(rig.result.theta_s)
    warned = final(rig.lock(1))
    assert warned.level == 'WARN' and warned.log and warned.state == State.IDLE
    assert warned.message == ('joint2 locked while no execution is running: remembered; '
                              'executions are refused until ftplan_executor/reset declares it '
                              'repaired')
    assert warned.locked_joints == ('joint2',)
    refused = rig.start()
    assert not refused.success
    assert refused.message == ("['joint2'] locked (joint2 (while idle)) and would be commanded: "
                               'call ftplan_executor/reset once repaired')
    assert rig.lock(1) == []  # the same failure reported again
    repaired = rig.executor.reset(rig.now())
    assert repaired.success and repaired.message == "repaired: ['joint2']"
    assert final(repaired.actions).message == "reset: repaired: ['joint2']"
    assert rig.start().success


def test_reset_is_refused_during_a_run(rig):
    rig.nominal()
    refused = rig.executor.reset(rig.now())
    assert not refused.success and refused.message == 'execution 1 is nominal'


def test_lost_obstacle_updates_refuse_a_run(rig):
    rig.obstacles.lost = 'obstacle updates were lost (update 3 was not received)'
    refused = rig.start()
    assert not refused.success
    assert refused.message == ('obstacle updates were lost (update 3 was not received): publish '
                               'a full set (a MarkerArray whose first marker is DELETEALL), then '
                               'execute again')


def test_a_plan_for_another_robot_is_refused(make_rig):
    """The robot digest of its plan status differs from the robot's now."""
    rig = make_rig(digest='0123456789ab')
    refused = rig.start()
    assert not refused.success
    assert refused.message.startswith(f'plan {PLAN_KEY} was made for robot 0123456789ab, but '
                                      'the robot is now ')
    assert refused.message.endswith(' (from /robot_description): plan again')


def test_a_plan_timed_within_other_motion_limits_is_refused_naming_both_digests(make_rig):
    """Issue 36, item 3: the plan status's motion_limits digest differs from the executor's
    (the robot's limits times its scaling factors)."""
    rig = make_rig(limits_digest='0123456789ab', max_velocity_scaling_factor=0.5)
    ours = motion_limits_digest(robot_motion_limits(rig.scene.robot).scaled(0.5, 1.0))
    refused = rig.start()
    assert not refused.success
    assert refused.message == (
        f'plan {PLAN_KEY} was timed within motion limits 0123456789ab, but the executor\'s are '
        f'{ours} (joint_limits_file, max_velocity_scaling_factor, '
        'max_acceleration_scaling_factor): give the planner the same, plan again')
    assert make_rig(max_velocity_scaling_factor=0.5).start().success


def test_obstacles_on_the_failure_surface_refuse_a_run(rig):
    rig.add_obstacle(rig.scene.robot.forward_kinematics(rig.result.theta_s), 0.05)
    refused = rig.start()
    assert not refused.success
    assert refused.message == (f'the obstacles changed since plan {PLAN_KEY}: its failure '
                               'surface now meets one; plan again')


def test_a_new_robot_during_a_run_stops_and_fails_it(rig):
    nominal = rig.nominal()
    rig.follow(nominal, until=0.3)
    actions = rig.executor.use_robot(rig.scene.robot, rig.now())
    assert isinstance(actions[0], Stop) and stops(actions) == 1
    failed = final(actions)
    assert failed.state == State.FAILED and failed.level == 'ERROR'
    assert failed.message == '/robot_description changed during the execution: stopped'
    assert rig.executor.plan is rig.plan  # the same joints: the plan stays
    other = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'))
    assert rig.executor.use_robot(other, rig.now()) == []
    assert rig.executor.plan is None and rig.executor.state == State.IDLE
    assert rig.executor.start(rig.now()).message.startswith('no plan yet')


def test_an_internal_error_stops_and_fails_the_run_with_the_actions_decided_before(rig):
    rig.nominal()
    rig.executor.report('a status decided before the error', rig.now())
    actions = rig.executor.abort('internal executor error: KeyError(1)', rig.now())
    assert [s.message for s in statuses(actions)] == [
        'a status decided before the error', 'internal executor error: KeyError(1)']
    assert stops(actions) == 1 and final(actions).state == State.FAILED
    assert rig.executor.abort('again', rig.now()) == []  # no run under way: nothing to stop


def test_a_lock_angle_away_from_the_joint_is_rejected_and_not_remembered(rig):
    rig.at(rig.result.theta_s)
    [rejected] = rig.lock(0, angle=float(rig.result.theta_s[0]) + 1.0)
    assert isinstance(rejected, Rejected) and rejected.joint == 'joint1'
    assert rejected.message.startswith('ignored locked-joint event: joint1 would lock at ')
    assert 'a joint locks where it stands' in rejected.message
    assert len(rig.executor.locks) == 0 and rig.start().success


def test_a_lock_angle_before_any_joint_state_is_rejected(rig):
    [rejected] = rig.lock(2, angle=0.1)
    assert rejected.message == ('ignored locked-joint event: joint3 locks at 0.1 rad, but its '
                                'current angle is not known yet')


def test_the_status_names_the_run_the_locks_and_the_tolerated_joints(make_rig):
    rig = make_rig(tolerated=('joint1', 'joint3'))
    nominal = rig.nominal()
    rig.at(point_at_fraction(nominal.path, 0.5))
    status = final(rig.tick())
    assert status.state == State.NOMINAL and status.message == 'nominal'
    assert status.plan == PLAN_KEY and status.execution.number == 1
    assert status.execution.progress == pytest.approx(0.5)
    assert status.tolerated_joints == ('joint1', 'joint3')
    assert status.names == ('joint1', 'joint2', 'joint3')


def test_idle_the_status_is_reported_once_a_second(rig):
    assert final(rig.tick(1.0)).message == 'idle'
    assert rig.tick(0.5) == []
    assert final(rig.tick(0.5)).message == 'idle'
