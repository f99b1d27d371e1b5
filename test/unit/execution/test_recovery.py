"""After a lock (recovery.py, through the executor): stop, then the way on, or why none."""

import numpy as np
import pytest

from ftplan_ros.core import FailureSurface, task_errors
from ftplan_ros.core.collision.braking import point_at_level
from ftplan_ros.core.model.paths import point_at_fraction
from ftplan_ros.execution.actions import Stop
from ftplan_ros.execution.motion import progress_along
from ftplan_ros.execution.state import State

from .rig import commands, failure, final


def lock_on_nominal(rig, joint: int = 1, fraction: float = 0.4):
    """Run the plan to `fraction` of the nominal path and lock `joint` there; return the actions."""
    rig.follow(rig.nominal(), until=fraction)
    return rig.lock(joint)


def single_path(result) -> FailureSurface:
    """S_F cut down to its nominal path: a web that holds no recovery path at all."""
    surface = result.surface
    return FailureSurface(surface.paths[[surface.nominal]], 0, (), ())


def test_a_lock_on_the_nominal_path_stops_the_arm_then_recovers_within_s_f(rig):
    actions = lock_on_nominal(rig)
    assert isinstance(actions[0], Stop)
    stopping = final(actions)
    assert stopping.state == State.RECOVERING and stopping.level == 'OK'
    assert stopping.message == 'joint2 locked at about 40.0% of the nominal path: stopping'
    assert stopping.execution.lock_phase == State.NOMINAL
    locked = rig.q.copy()
    actions = rig.stand()
    [recovery] = commands(actions)
    assert np.array_equal(recovery.path[0], locked)
    assert np.all(recovery.path[:, 1] == locked[1])           # joint2 stays where it locked
    assert final(actions).message.startswith(
        'joint2 locked at 40.0% of the nominal path: following the recovery path (')
    done = final(rig.follow(recovery))
    assert done.state == State.DONE and done.message.startswith('reached the goal (recovered)')
    assert done.execution.lock_progress == pytest.approx(0.4)
    assert np.array_equal(done.execution.lock_configuration, locked)
    assert done.execution.goal_error < rig.scene.task.goal_tolerance


def test_standing_still_right_after_the_lock_is_not_yet_the_stop(rig):
    """Found by CI on a loaded machine: a controller that had not yet taken up the last
    command stood still, then moved before it took up the stop (stop_settle_time)."""
    nominal = rig.nominal()
    rig.follow(nominal, until=0.4)
    rig.lock(1)
    assert rig.at(rig.q) == [] and rig.at(rig.q) == []       # standing, not yet settled
    moved_on = point_at_fraction(nominal.path, 0.42)
    rig.wait(0.3)
    assert rig.at(moved_on) == []                             # it moved after all
    [recovery] = commands(rig.at(moved_on))
    assert np.array_equal(recovery.path[0], moved_on)


def test_the_stop_is_judged_on_joint_states_sent_after_the_lock(rig):
    """Found by the drills: joint states queued from before the lock made the executor
    recover from where the arm had been, not from where it locked."""
    nominal = rig.nominal()
    rig.follow(nominal, until=0.4)
    before = rig.ros_ns - 1                                   # stamped before the lock
    locked = rig.q.copy()
    rig.lock(1)
    earlier = point_at_fraction(nominal.path, 0.2)
    rig.wait(0.3)
    assert rig.at(earlier, stamp_ns=before) == [] and rig.at(earlier, stamp_ns=before) == []
    assert rig.at(locked) == []                               # not standing yet: it moved
    [recovery] = commands(rig.at(locked))
    assert np.array_equal(recovery.path[0], locked)


def test_a_second_lock_stops_the_arm_and_fails_the_run(rig):
    lock_on_nominal(rig)
    actions = rig.lock(2)
    assert isinstance(actions[0], Stop)
    assert failure(actions) == ('joint3 locked after joint2: a second failure is beyond the '
                                'single-failure guarantee; the arm is stopped safely where it is')
    assert final(actions).locked_joints == ('joint2', 'joint3')


def test_an_untolerated_joint_with_a_recovery_path_in_s_f_follows_it(make_rig):
    rig = make_rig(tolerated=('joint1', 'joint3'))
    lock_on_nominal(rig)
    actions = rig.stand()
    assert commands(actions)
    assert final(actions).message.startswith(
        'joint2 locked at 40.0% of the nominal path (not tolerated by this plan, but S_F holds '
        'a recovery path): following the recovery path (')


def test_an_untolerated_joint_without_a_recovery_path_fails_naming_it(make_rig, fig3a):
    rig = make_rig(tolerated=('joint1', 'joint3'), surface=single_path(fig3a[1]))
    lock_on_nominal(rig)
    assert failure(rig.stand()) == (
        'joint joint2 is not tolerated by this plan (it tolerates joint1, joint3): S_F holds no '
        'recovery path from where it locked, at 40.0% of the nominal path; the arm is stopped '
        'there')


def test_a_tolerated_joint_without_a_recovery_path_says_the_guarantee_is_broken(make_rig, fig3a):
    rig = make_rig(surface=single_path(fig3a[1]))
    lock_on_nominal(rig)
    assert failure(rig.stand()) == ('S_F holds no recovery path for joint2 locked at 40.0% of '
                                    'the nominal path: the plan\'s guarantee is broken, please '
                                    'report')


def test_an_arm_stopped_off_the_nominal_path_cannot_recover(rig):
    """Outside every braking box and farther than max_path_offset from the path, the core
    refuses to recover from it."""
    lock_on_nominal(rig)
    rig.q = rig.q + [0.5, 0.0, 0.0]
    message = failure(rig.stand())
    assert message.startswith('cannot recover from joint2 locked at ')
    assert message.endswith('; the arm is stopped there')


def test_a_lock_on_the_approach_goes_on_to_the_goal_with_the_joints_left(rig):
    """Not failure-tolerant: stop, say so (WARN), plan a path to the goal with joint1 held."""
    rig.follow(rig.approach([0.0, 0.0, 1.0]), until=0.5)
    actions = rig.lock(0)
    assert isinstance(actions[0], Stop)
    stopping = final(actions)
    assert stopping.level == 'WARN' and stopping.execution.lock_phase == State.APPROACHING
    assert stopping.message == ('joint1 locked while approaching theta_s, before the '
                                'failure-tolerant nominal path began: stopping, then planning a '
                                'path to the goal with the joints left (not failure-tolerant)')
    locked = rig.q.copy()
    actions = rig.stand()
    [onward] = commands(actions)
    assert np.all(onward.path[:, 0] == locked[0])
    assert final(actions).level == 'WARN'
    assert final(actions).message.startswith('joint1 locked while approaching theta_s: following '
                                             'a path to the goal with the joints left, ')
    assert final(actions).message.endswith(' (not failure-tolerant)')
    done = final(rig.follow(onward))
    assert done.state == State.DONE and done.message.startswith('reached the goal (recovered)')


def test_a_lock_on_the_approach_without_a_way_to_the_goal_fails(make_rig):
    """A goal out of reach with joint1 locked near -1.32 rad: 2.82 m from joint2."""
    rig = make_rig(goal=(2.9, 0.0))
    rig.follow(rig.approach([0.0, 0.0, 1.0]), until=0.5)
    rig.lock(0)
    assert failure(rig.stand()) == (
        'joint1 locked while approaching theta_s (not failure-tolerant) and no collision-free '
        'configuration reaches the goal with joint1 locked; the arm is stopped where it is')


def test_an_arm_braked_off_the_path_inside_its_box_goes_back_to_the_lock_point_first(rig):
    """Issue 36, item 3: braking leaves the path (within the certified box); the recovery
    goes straight back to where the joint locked, then on in S_F."""
    lock_on_nominal(rig)
    locked_at = rig.q.copy()
    rig.q = rig.q + [0.002, 0.0, -0.002]
    [command] = commands(rig.stand())
    assert np.allclose(command.path[0], rig.q, atol=1e-12)
    assert np.allclose(command.path[1], locked_at, atol=1e-9)
    assert np.all(command.path[:, 1] == locked_at[1])


def test_an_arm_stopped_ahead_of_its_locked_joints_angle_goes_back_where_the_move_is_clear(rig):
    """Issue 37, MuJoCo drills: the locked joint lags its command, so the arm stands
    where the free joints were sent, 0.02-0.04 rad along the path beyond the point of the
    locked angle, outside every braking box. The move back there is certified now, and
    the run recovers instead of refusing ("not on the nominal path")."""
    lock_on_nominal(rig)
    locked_at = rig.q.copy()
    ahead = point_at_fraction(rig.plan.surface.nominal_path, 0.45)
    rig.q = np.where(np.arange(3) == 1, locked_at, ahead)
    assert 0.02 < np.max(np.abs(rig.q - locked_at)) < 0.1    # off the path, within path_tolerance
    [command] = commands(rig.stand())
    back = int(np.argmin(np.max(np.abs(command.path - locked_at), axis=1)))
    assert np.allclose(command.path[back], locked_at, atol=1e-6)   # straight back there
    way = locked_at - rig.q
    along = (command.path[:back + 1] - rig.q) @ way / np.sum(way ** 2)
    assert np.allclose(command.path[:back + 1], rig.q + along[:, None] * way)
    assert np.all(command.path[:, 1] == locked_at[1])


def test_a_lock_located_past_the_paths_range_of_its_angle_still_ends_on_the_goal(make_rig):
    """Issue 37, MuJoCo drills on fig3a: joint2 lagged its command, the free joints
    stood ahead, and the nearest point of the path within max_path_offset of joint2's
    angle was a segment's end 0.008 rad beyond it. S_F's recovery path, moved that far,
    ended 1.4 cm from the goal (tolerance 1 cm). It now goes on to the goal with joint2
    held, certified."""
    rig = make_rig(max_path_offset=0.02)
    lock_on_nominal(rig)
    locked_at = rig.q.copy()
    rig.q = np.where(np.arange(3) == 1, locked_at,
                     point_at_fraction(rig.plan.surface.nominal_path, 0.42))
    [command] = commands(rig.stand())
    assert np.all(command.path[:, 1] == locked_at[1])
    assert task_errors(rig.plan.robot, rig.plan.goal, command.path[-1])[0] < 1e-6


def test_a_stop_off_the_path_whose_way_onto_it_is_blocked_stays_there(make_rig):
    """A review of issue 37's fixes: stopped 0.015 rad off the path in joint3, outside
    every braking box, with a 0.5 mm obstacle where the tool passes on the way back: the
    move back was refused, yet the command stepped from there onto S_F uncertified."""
    rig = make_rig(max_path_offset=0.02)
    lock_on_nominal(rig)
    stop = rig.q + [0.0, 0.0, -0.015]
    sent = rig.executor.execution.nominal_command.path
    on_path = point_at_level(sent, stop, 1, 0.02, 0.1, progress_along(sent, stop)[0])
    halfway = rig.scene.robot.skeleton((0.5 * (stop + on_path))[None, :])[0][-1]
    rig.add_obstacle(halfway[:2], 0.0005)
    rig.q = stop
    assert failure(rig.stand()).endswith('the move onto it is not certified clear; the arm is '
                                         'stopped there')
