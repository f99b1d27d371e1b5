"""The kinematic arm (simulation/kinematic.py) without ROS: commands, locks, braking, reset.

The test steps the arm by hand at 100 Hz; ROS times are nanoseconds from 1000 s.
"""

import numpy as np
import pytest

from ftplan_ros.core import PlanarChain
from ftplan_ros.simulation.arm import ArmOptions, HeldJoint, Locked, Refused, Scheduled
from ftplan_ros.simulation.kinematic import KinematicArm

ROBOT = PlanarChain((1.0, 1.0, 1.0), ('joint1', 'joint2', 'joint3'))  # joints wrap
NOW = 1_000_000_000_000  # [ns] ROS time when the command arrives
DT = 0.01                # [s] a step at 100 Hz


def arm(q=(0.0, 0.0, 0.0), **options) -> KinematicArm:
    return KinematicArm(ROBOT, np.array(q), ArmOptions(**options))


def run(sim: KinematicArm, seconds: float) -> list:
    """Step the arm for `seconds`; return the steps."""
    return [sim.step(DT) for _ in range(round(seconds / DT))]


def at(seconds: float) -> int:
    return NOW + round(seconds * 1e9)


def test_the_arm_follows_a_command_through_its_points_at_their_times():
    sim = arm()
    following = sim.follow(np.array([[0.5, 0.0, 0.0], [0.5, 0.5, 0.0]]), np.array([0.5, 1.0]),
                           NOW, NOW)
    assert following.held == () and following.slowdown == 1.0
    run(sim, 0.25)
    assert np.allclose(sim.q, [0.25, 0.0, 0.0], atol=1e-12, rtol=0) and sim.moving
    run(sim, 0.5)
    assert np.allclose(sim.q, [0.5, 0.25, 0.0], atol=1e-12, rtol=0)
    run(sim, 0.26)
    assert np.array_equal(sim.q, [0.5, 0.5, 0.0]) and not sim.moving


def test_a_step_sweeps_the_corners_it_passes():
    """A command that turns within one step: the sweep holds the corner, not the chord."""
    sim = arm()
    sim.follow(np.array([[0.004, 0.0, 0.0], [0.004, 0.004, 0.0]]), np.array([0.004, 0.008]),
               NOW, NOW)
    swept = sim.step(DT).swept
    assert np.array_equal(np.unique(swept, axis=0),
                          [[0.0, 0.0, 0.0], [0.004, 0.0, 0.0], [0.004, 0.004, 0.0]])


def test_a_command_too_fast_is_slowed_down_to_the_speed_limit():
    sim = arm(max_joint_speed=2.0)
    following = sim.follow(np.array([[1.0, 0.0, 0.0]]), np.array([0.1]), NOW, NOW)  # 10 rad/s
    assert following.slowdown == pytest.approx(5.0)
    steps = [step.swept[-1] - step.swept[0] for step in run(sim, 0.6) if step.swept is not None]
    assert max(np.abs(steps).max(axis=1)) <= 2.0 * DT * (1 + 1e-9)
    assert np.array_equal(sim.q, [1.0, 0.0, 0.0])


def test_a_command_stamped_ahead_starts_at_its_stamp():
    sim = arm()
    sim.follow(np.array([[1.0, 0.0, 0.0]]), np.array([1.0]), at(0.5), NOW)
    run(sim, 0.49)
    assert np.array_equal(sim.q, [0.0, 0.0, 0.0])
    run(sim, 0.51)
    assert np.allclose(sim.q, [0.5, 0.0, 0.0], atol=1e-12, rtol=0)


def test_a_lock_brakes_the_arm_within_the_acceleration_limits_and_later_commands_hold_it():
    """Issue 36: at 2 rad/s, braking at the default 2 rad/s² takes 1 s and 1 rad."""
    sim = arm()
    sim.follow(np.array([[3.0, 3.0, 3.0]]), np.array([1.5]), NOW, NOW)
    run(sim, 0.5)
    outcome = sim.lock(1, None, 0)
    assert isinstance(outcome, Locked) and outcome.jump is None
    assert outcome.angle == pytest.approx(1.0)
    assert sim.moving and sim.locked == {1: outcome.angle}  # braking
    run(sim, 0.5)
    assert np.allclose(sim.q, [1.75, 1.0, 1.75], atol=1e-2)  # 2 t - t², sampled
    run(sim, 0.6)
    assert not sim.moving and np.allclose(sim.q, [2.0, 1.0, 2.0])
    stopped = sim.q.copy()
    following = sim.follow(np.array([[0.0, 0.0, 0.0]]), np.array([2.0]), NOW, NOW)
    assert following.held == (HeldJoint(1, pytest.approx(1.0), outcome.angle),)
    run(sim, 2.1)
    assert np.array_equal(sim.q, [0.0, stopped[1], 0.0])
    assert sim.lock(1, None, 0) is None                     # locked already


def test_without_brake_on_lock_the_free_joints_go_on():
    sim = arm(brake_on_lock=False)
    sim.follow(np.array([[1.0, 1.0, 1.0]]), np.array([1.0]), NOW, NOW)
    run(sim, 0.5)
    sim.lock(0, None, 0)
    run(sim, 0.6)
    assert np.allclose(sim.q, [0.5, 1.0, 1.0], atol=1e-12, rtol=0)


def test_a_scheduled_lock_lands_exactly_where_the_command_puts_the_arm_at_its_stamp():
    """Issue 33: between two steps too, however early the event arrives."""
    sim = arm()
    start = at(0.3)
    sim.follow(np.array([[1.0, 0.0, 0.0], [1.0, 1.0, 0.5]]), np.array([0.5, 1.0]), start, NOW)
    outcome = sim.lock(1, None, start + round(0.6537e9))   # 0.1537 s into the second step
    assert outcome == Scheduled(1, pytest.approx(0.9537))
    assert sim.lock(1, None, 0) is None                     # scheduled already
    steps = run(sim, 1.5)
    [(step, locked)] = [(step, lock) for step in steps for lock in step.locks]
    assert isinstance(locked, Locked) and locked.angle == pytest.approx(0.3074, abs=1e-12)
    assert np.allclose(step.swept[-1], [1.0, 0.3074, 0.1537], atol=1e-12, rtol=0)
    assert np.allclose(sim.q, [1.0, 0.3074, 0.1537 + 0.25])  # braked from 1 rad/s at 2 rad/s²
    assert not sim.moving


def test_a_lock_scheduled_on_a_command_that_started_late_lands_late_with_it():
    """The command came 0.2 s after its stamp: its timeline, the lock's too, starts now."""
    sim = arm()
    stamp = at(-0.2)
    sim.follow(np.array([[1.0, 0.0, 0.0]]), np.array([1.0]), stamp, NOW)
    sim.lock(2, None, stamp + round(0.5e9))
    run(sim, 0.45)
    assert sim.locked == {}
    [step] = [step for step in run(sim, 0.1) if step.locks]
    assert sim.locked == {2: 0.0}
    assert np.allclose(step.swept[-1], [0.5, 0.0, 0.0], atol=1e-12, rtol=0)


def test_a_lock_stamped_on_a_command_that_comes_after_it_lands_on_that_command():
    """A drill's lock, stamped 0.5 s into the nominal command, reached the sim before the
    command did, while the arm stood at θ_s: it locked the joint at once, at θ_s, and the
    command then moved the locked joint (a tracking error, a stall or a collision)."""
    sim = arm()
    outcome = sim.lock(0, None, at(0.55), NOW)
    assert outcome == Scheduled(0, pytest.approx(0.55)) and sim.locked == {}
    run(sim, 0.02)
    sim.follow(np.array([[1.0, 0.0, 0.0]]), np.array([1.0]), at(0.05), at(0.02))
    run(sim, 0.5)
    assert sim.locked == {}
    [step] = [step for step in run(sim, 0.1) if step.locks]
    assert sim.locked == {0: pytest.approx(0.5)}
    assert isinstance(arm().lock(0, None, at(0.55)), Locked)  # without the ROS time: at once


def test_a_lock_stamped_past_the_end_of_the_command_there_waits_for_its_own():
    """The same, with the approach to θ_s still under way in the sim (its clock behind
    the executor's on a loaded machine): the lock, stamped past the approach's end,
    locked joint2 when the approach ended, at θ_s (a MuJoCo drill on
    crowded_sheets_100 failed so, with a tracking error)."""
    sim = arm()
    sim.follow(np.array([[0.2, 0.0, 0.0]]), np.array([0.2]), NOW, NOW)   # the approach
    run(sim, 0.1)
    outcome = sim.lock(1, None, at(0.85), at(0.1))
    assert outcome == Scheduled(1, pytest.approx(0.75)) and sim.locked == {}
    run(sim, 0.22)
    sim.follow(np.array([[0.2, 1.0, 0.0]]), np.array([1.0]), at(0.35), at(0.32))
    run(sim, 0.5)
    assert sim.locked == {}
    [step] = [step for step in run(sim, 0.1) if step.locks]
    assert sim.locked == {1: pytest.approx(0.5)}


def test_a_lock_stamped_now_past_the_end_of_a_lagging_command_waits_for_its_end():
    """The sim's clock behind ROS time: a lock stamped now (lock_now) is past the end of
    the command the arm is still on. It lands at that end, where the executor expects
    the arm, not midway (the executor would then wait for a command that never ends)."""
    sim = arm()
    sim.follow(np.array([[1.0, 0.0, 0.0]]), np.array([1.0]), NOW, NOW)
    run(sim, 0.5)
    assert sim.lock(0, None, at(1.2), at(1.2)) == Scheduled(0, pytest.approx(0.5))
    run(sim, 0.6)
    assert sim.locked == {0: pytest.approx(1.0)}


def test_a_scheduled_lock_takes_effect_at_once_when_the_command_is_stopped():
    sim = arm()
    sim.follow(np.array([[1.0, 0.0, 0.0]]), np.array([1.0]), NOW, NOW)
    run(sim, 0.2)
    sim.lock(0, None, at(0.8))
    sim.stop()
    [step] = run(sim, DT)
    [locked] = step.locks
    assert step.swept is None and isinstance(locked, Locked)
    assert locked.angle == pytest.approx(0.2) and sim.locked == {0: locked.angle}


def test_a_lock_at_an_angle_jumps_the_joint_there_within_the_tolerance():
    sim = arm(q=(0.0, 0.5, 0.0), lock_angle_tolerance=0.1)
    outcome = sim.lock(1, 0.55 + 2 * np.pi, 0)                # whole turns apart: the same
    assert np.allclose(outcome.jump, [[0.0, 0.5, 0.0], [0.0, 0.55, 0.0]], atol=1e-12, rtol=0)
    assert sim.q[1] == pytest.approx(0.55)
    refused = sim.lock(0, 1.0, 0)
    assert isinstance(refused, Refused) and refused.joint == 0
    assert refused.problem.startswith('joint1 would lock at 1 rad, +1 rad from where it is')
    assert 0 not in sim.locked


def test_reset_stands_the_arm_at_a_configuration_with_every_joint_free():
    sim = arm()
    sim.follow(np.array([[1.0, 1.0, 1.0]]), np.array([1.0]), NOW, NOW)
    run(sim, 0.3)
    sim.lock(0, None, 0)
    sim.follow(np.array([[1.0, 1.0, 1.0]]), np.array([1.0]), NOW, NOW)
    sim.lock(1, None, at(0.9))
    sim.reset(np.array([0.1, 0.2, 0.3]))
    assert np.array_equal(sim.q, [0.1, 0.2, 0.3]) and sim.locked == {} and not sim.moving
    assert all(step.locks == [] for step in run(sim, 1.0))  # the scheduled lock is gone
    assert isinstance(sim.lock(0, None, 0), Locked)
