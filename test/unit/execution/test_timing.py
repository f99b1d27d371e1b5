"""Timing within the motion limits (execution/timing.py), replayed point by point."""

import numpy as np
import pytest
from trajectory_replay import limit_violations

from ftplan_ros.core.model.motion_limits import MotionLimits, default_motion_limits
from ftplan_ros.core.model.paths import point_at_fraction
from ftplan_ros.core.planning.timing import (
    TimedPath,
    at_speed,
    at_vertices,
    braking_speed_scaling,
    time_within_limits,
)

from .rig import commands

PANDA_LIKE = MotionLimits([2.0, 1.0, 3.0], [15.0, 7.5, 10.0], [7500.0, 3750.0, 5000.0])
ZIGZAG = np.array([[0.0, 0.0, 0.0], [0.4, 0.3, -0.2], [0.4, -0.5, 0.1], [1.2, -0.5, 0.1],
                   [1.1, 0.2, 0.6], [1.1, 0.2, 0.6], [0.0, 0.0, 0.0]])
FREE = np.array([[-np.pi, np.pi]] * 3)


def replayed(path, limits, max_step=0.05):
    timed = time_within_limits(path, limits, max_step)
    return timed, limit_violations(timed.positions, timed.velocities, timed.accelerations,
                                   timed.times, limits, FREE, path, max_step)


@pytest.mark.parametrize('limits', [default_motion_limits(3), PANDA_LIKE,
                                    PANDA_LIKE.scaled(0.3, 0.1)])
def test_a_path_with_sharp_corners_is_timed_on_the_path_within_every_limit(limits):
    timed, problems = replayed(ZIGZAG, limits)
    assert problems == []
    assert np.array_equal(timed.positions[0], ZIGZAG[0])
    assert np.array_equal(timed.positions[-1], ZIGZAG[-1])


def test_a_path_that_turns_back_stops_there_instead_of_crawling():
    """The end of a recovery on crowded_sheets_100 (joint1 locked at 6 %): the path turns
    back for its last 0.03 rad. TOPP-RA on a spline through the turn crawled over the
    last step, 190 s of a 196 s command, and the drill timed out."""
    end = np.array([[1.339393, -4.074282, 0.834513], [1.339393, -4.115178, 0.87541],
                    [1.339393, -4.156075, 0.916307], [1.339393, -4.196971, 0.957204],
                    [1.339393, -4.181259, 0.94914], [1.339393, -4.167548, 0.939686]]) + \
        [0.0, 2.0 * np.pi, 0.0]                            # within FREE, the same turn
    timed, problems = replayed(end, default_motion_limits(3))
    assert problems == []
    turn = int(np.flatnonzero(np.all(timed.positions == end[3], axis=1))[0])
    assert np.all(timed.velocities[turn] == 0.0)          # it stops to turn back
    assert timed.times[-1] < 2.0                           # 0.16 rad: not minutes


def test_vertices_close_together_after_sharp_turns_are_timed_without_crawling():
    """The end of a recovery on crowded_sheets_100 (joint1 locked at 14.1 %): two sharp
    turns 0.007 and 0.004 rad apart. TOPP-RA's spline through them bent so much that it
    crawled over the last 0.003 rad for 36 s: the arm moved 1e-4 rad/s, and the
    executor's watchdog took it for a stall."""
    end = np.array([[1.36267, -3.80327, 0.5635], [1.36267, -3.85135, 0.61159],
                    [1.36267, -3.89944, 0.65967], [1.36267, -3.94752, 0.70776],
                    [1.36267, -3.99561, 0.75584], [1.36267, -4.03588, 0.79611],
                    [1.36267, -4.07615, 0.83639], [1.36267, -4.11643, 0.87666],
                    [1.36267, -4.1567, 0.91693], [1.36267, -4.19697, 0.9572],
                    [1.36267, -4.1965, 0.96402], [1.36267, -4.19337, 0.96684]]) + \
        [0.0, 2.0 * np.pi, 0.0]                            # within FREE, the same turns
    timed, problems = replayed(end, default_motion_limits(3))
    assert problems == []
    assert timed.times[-1] < 3.0                           # 0.4 rad at 1 rad/s: seconds
    assert np.all(np.diff(timed.times) < 0.5)              # no step crawls
    stops = np.flatnonzero(np.all(timed.velocities == 0.0, axis=1))
    assert len(stops) <= 3                                 # the ends, and where it crawled
    # Cut where it crawls: a last step of 4e-9 rad, a part of its own, keeps its vertex.
    for tail in ([0.0, 4e-9, 0.0], [3e-9, 0.0, 0.0], [0.0, 0.0, 5e-9]):
        longer = np.vstack([end[[0, 9, 10, 11]], end[-1] + tail])
        timed = time_within_limits(longer, default_motion_limits(3))
        assert len(at_vertices(timed, longer).times) == len(longer)


def test_points_a_rounding_error_apart_are_one_point():
    """The end of a recovery of the iiwa (iiwa_joint_1 locked at 68.6 % of iiwa_table's
    nominal path) repeats a point to within 2e-11 rad: TOPP-RA's spline through it gave
    the last step 90 s of a 94 s command."""
    end = np.array([[-0.509185694038, -0.932781954397, 1.487635225741, 0.412723069521],
                    [-0.508035981554, -0.929485274213, 1.487577984307, 0.410809919801],
                    [-0.508035981551, -0.929485274205, 1.487577984306, 0.410809919796],
                    [-0.508035981545, -0.929485274186, 1.487577984303, 0.410809919785],
                    [-0.49953227174, -0.90345426981, 1.487112378303, 0.396156145922]])
    timed = time_within_limits(end, default_motion_limits(4))
    assert timed.times[-1] < 1.0                           # 0.03 rad: not a minute


def test_jerk_limits_are_kept_by_slowing_down():
    """TOPP-RA bounds no jerk: the uniform slow-down does; without it the jerk limit breaks."""
    tight = MotionLimits(PANDA_LIKE.velocity, PANDA_LIKE.acceleration, [20.0, 20.0, 20.0])
    timed, problems = replayed(ZIGZAG, tight)
    assert problems == []
    unbounded = MotionLimits(PANDA_LIKE.velocity, PANDA_LIKE.acceleration, [np.inf] * 3)
    free = time_within_limits(ZIGZAG, unbounded)
    assert any('jerk' in problem for problem in limit_violations(
        free.positions, free.velocities, free.accelerations, free.times, tight, FREE))
    assert timed.times[-1] > free.times[-1]


def test_scaling_slows_the_trajectory_down():
    fast, _ = replayed(ZIGZAG, PANDA_LIKE)
    slow, problems = replayed(ZIGZAG, PANDA_LIKE.scaled(0.5, 0.5))
    assert problems == [] and slow.times[-1] > 1.5 * fast.times[-1]


def test_a_path_of_one_short_step_is_timed_too():
    """An approach of 2 points 0.012 rad apart was timed 1e298 s long (no grid point
    between its ends at rest)."""
    timed, problems = replayed(np.array([[0.0, 0.0, 0.0], [0.012, -0.004, 0.0]]), PANDA_LIKE)
    assert problems == [] and 0.0 < timed.times[-1] < 1.0


def test_a_path_of_one_point_is_a_command_to_stay():
    timed, problems = replayed(ZIGZAG[:1], PANDA_LIKE)
    assert problems == [] and timed.times.tolist() == [0.0]


@pytest.mark.parametrize('max_step', [0.05, 0.01])
def test_the_fig3a_nominal_path_is_timed_within_the_default_limits(fig3a, max_step):
    _, result = fig3a
    _, problems = replayed(np.asarray(result.nominal_path), default_motion_limits(3), max_step)
    assert problems == []


def test_a_planned_path_is_timed_at_its_own_vertices_within_every_limit(fig3a):
    """Issue 36, item 2: the planner's latched trajectory is the nominal path's very numbers
    (S_F holds it), timed as the executor times its command, at the braking-safe speed."""
    _, result = fig3a
    path = np.asarray(result.nominal_path)
    limits = PANDA_LIKE.capped(0.8)
    full = time_within_limits(path, limits)
    timed = at_vertices(at_speed(full, 0.5), path)
    assert np.array_equal(timed.positions, path)
    assert limit_violations(timed.positions, timed.velocities, timed.accelerations, timed.times,
                            limits, FREE, max_step=None) == []
    assert timed.times[-1] == pytest.approx(2.0 * full.times[-1])
    assert at_speed(full, 1.0) is full
    with pytest.raises(ValueError, match='speed must be in'):
        at_speed(full, 0.0)
    with pytest.raises(ValueError, match='is not among the timed points'):
        at_vertices(full, path + 1e-6)


def test_every_command_of_a_run_with_a_lock_replays_within_the_limits(make_rig):
    """Through the executor: the approach, the nominal path and the recovery."""
    rig = make_rig(max_joint_speed=10.0, max_velocity_scaling_factor=0.8,
                   max_acceleration_scaling_factor=0.5)
    limits = rig.executor.commanded_limits()
    assert np.allclose(limits.velocity, 0.8) and np.allclose(limits.acceleration, 1.0)
    sent = [rig.approach([0.3, -0.2, 0.4])]
    [nominal] = commands(rig.follow(sent[0]))
    sent.append(nominal)
    rig.follow(nominal, until=0.4)
    rig.lock(1)
    sent += commands(rig.stand())
    assert len(sent) == 3, 'approach, nominal path, recovery'
    assert np.allclose(nominal.path[0], rig.result.theta_s)
    for command, start in zip(sent, [rig.result.theta_s + [0.3, -0.2, 0.4], rig.result.theta_s,
                                     point_at_fraction(nominal.path, 0.4)], strict=True):
        assert np.allclose(command.path[0], start, atol=1e-9)
        certified = np.asarray(rig.result.nominal_path) if command is nominal else None
        assert limit_violations(command.path, command.velocities, command.accelerations,
                                command.times, limits, rig.scene.robot.limits, certified) == []


def test_the_nominal_command_is_slowed_until_a_lock_on_it_brakes_certified(rig):
    """Issue 36, item 3: at the full limits the boxes do not certify (speed < 1 below); the
    command sent does."""
    limits = rig.executor.commanded_limits()
    checker = rig.obstacles.checker
    full = time_within_limits(np.asarray(rig.result.nominal_path), limits)
    assert braking_speed_scaling(checker, full, limits.acceleration) < 0.9
    nominal = rig.nominal()
    sent = TimedPath(nominal.path, nominal.velocities, nominal.accelerations, nominal.times)
    assert braking_speed_scaling(checker, sent, limits.acceleration) == 1.0
    assert nominal.times[-1] > full.times[-1]
