"""Braking boxes (core/collision/braking.py) against brute-force sampled braking motions."""

import numpy as np
import pytest
from ftplan_testing import paper_scene

from ftplan_ros.core import CollisionChecker
from ftplan_ros.core.collision.braking import (
    braking_distances,
    lock_point,
    max_safe_speed,
    point_at_level,
    segment_speeds,
)
from ftplan_ros.core.model.motion_limits import default_motion_limits
from ftplan_ros.core.planning.timing import time_within_limits


def braking_motions(positions, speeds, deceleration, s, rng, trials=400, samples=12):
    """Configurations (trials·(2·samples), n) of locks at random points of random segments:
    a random joint locked, the others braking from random velocities within s x `speeds`,
    then the straight move back to the lock point."""
    out = []
    for _ in range(trials):
        k = rng.integers(len(positions) - 1)
        p = positions[k] + rng.random() * (positions[k + 1] - positions[k])
        v = rng.uniform(-1.0, 1.0, p.shape) * s * speeds[k]
        v[rng.integers(len(p))] = 0.0
        stop = np.abs(v) / deceleration
        t = np.linspace(0.0, 1.0, samples)[:, None] * stop[None, :]
        braking = p + np.sign(v) * (np.abs(v) * t - 0.5 * deceleration * t ** 2)
        back = braking[-1] + np.linspace(0.0, 1.0, samples)[:, None] * (p - braking[-1])
        out += [braking, back]
    return np.vstack(out)


def test_every_sampled_braking_motion_within_the_safe_speed_is_clear(fig3a):
    scene, result = fig3a
    limits = default_motion_limits(3)
    timed = time_within_limits(np.asarray(result.nominal_path), limits)
    speeds = segment_speeds(timed.positions, timed.velocities, timed.times)
    checker = CollisionChecker(scene.robot, scene.obstacles)
    s = max_safe_speed(checker, timed.positions, speeds, limits.acceleration, margin=0.05)
    assert 0.0 < s < np.inf
    motions = braking_motions(timed.positions, speeds, limits.acceleration, min(s, 1.0),
                              np.random.default_rng(1))
    assert checker.min_clearance(motions).min() > 0.05


def test_a_tight_box_lowers_the_safe_speed_and_touching_gives_none():
    """A 3R arm passing an obstacle: nearer, slower; with no room left, no speed at all."""
    path = np.array([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0]])
    speeds = np.full((1, 3), 1.0)
    deceleration = np.full(3, 2.0)
    safe = []
    for gap in (0.6, 0.3, 0.15):
        radius = 3.0 + 0.2 + gap
        scene = paper_scene(obstacles=[((radius * np.cos(0.15), radius * np.sin(0.15)), 0.2)])
        safe.append(max_safe_speed(CollisionChecker(scene.robot, scene.obstacles), path,
                                   speeds, deceleration))
    assert safe[0] > safe[1] > safe[2] > 0.0
    scene = paper_scene(obstacles=[((3.0 * np.cos(0.15), 3.0 * np.sin(0.15)), 0.2)])
    assert max_safe_speed(CollisionChecker(scene.robot, scene.obstacles), path, speeds,
                          deceleration) == 0.0


def test_braking_distance_is_v_squared_over_2a():
    assert braking_distances(np.array([2.0, 0.0]), np.array([4.0, 1.0])).tolist() == [0.5, 0.0]


def test_a_path_standing_still_brakes_nowhere():
    scene = paper_scene()
    checker = CollisionChecker(scene.robot, scene.obstacles)
    assert max_safe_speed(checker, np.zeros((1, 3)), np.zeros((0, 3)), np.ones(3)) == np.inf


@pytest.mark.parametrize('scale', [1.0, 3.0])
def test_the_speed_bound_covers_the_points_velocities_and_the_mean(scale):
    positions = np.array([[0.0, 0.0], [0.1, -0.2]])
    velocities = np.array([[0.0, 0.0], [scale, 0.0]])
    speeds = segment_speeds(positions, velocities, np.array([0.0, 0.5]))
    assert speeds.tolist() == [[max(scale, 0.2), 0.4]]


def test_the_plan_reports_the_speed_its_braking_boxes_certify(fig3a):
    """stats['max_safe_speed']: of the robot's full limits, the fraction that brakes certified."""
    scene, result = fig3a
    speed = result.stats['max_safe_speed']
    limits = default_motion_limits(3)
    timed = time_within_limits(np.asarray(result.nominal_path), limits)
    checker = CollisionChecker(scene.robot, scene.obstacles)
    assert 0.0 < speed < 1.0
    assert speed == pytest.approx(max_safe_speed(
        checker, timed.positions, segment_speeds(timed.positions, timed.velocities, timed.times),
        limits.acceleration))


PATH = np.array([[0.0, 0.0, 0.0], [0.1, 0.2, 0.0], [0.2, 0.2, 0.1]])  # joint 1 peaks at 0.2
SPEEDS = np.full((2, 3), 0.5)        # [rad/s]: braking reach 0.0625 rad at 2 rad/s²
DECELERATION = np.full(3, 2.0)


def test_the_lock_point_lies_on_the_path_at_the_locked_angle_nearest_the_stop():
    stop = np.array([0.06, 0.1, 0.01])   # braked past the path's point (0.05, 0.1, 0)
    assert np.allclose(lock_point(PATH, SPEEDS, DECELERATION, stop, 1), [0.05, 0.1, 0.0])


def test_a_brake_holding_past_the_paths_range_of_the_joint_finds_it_within_the_tolerance():
    """A physics brake holds joint 1 at 0.2003 rad, beyond the 0.2 rad the path peaks at:
    without a tolerance no point of the path has that angle (issue 37, MuJoCo drills)."""
    stop = np.array([0.11, 0.2003, 0.01])
    assert lock_point(PATH, SPEEDS, DECELERATION, stop, 1) is None
    p = lock_point(PATH, SPEEDS, DECELERATION, stop, 1, tolerance=1e-3)
    assert p[1] == stop[1]
    assert np.max(np.abs(p - stop)) <= 0.01 + 1e-12
    assert lock_point(PATH, SPEEDS, DECELERATION, stop, 1, tolerance=1e-4) is None


def test_a_stop_outside_every_braking_box_has_no_lock_point():
    stop = np.array([0.3, 0.1, 0.0])     # 0.25 rad from the path in joint 0
    assert lock_point(PATH, SPEEDS, DECELERATION, stop, 1, tolerance=1e-3) is None
    assert np.allclose(point_at_level(PATH, stop, 1, 0.0, 0.3, 0.4), [0.05, 0.1, 0.0])
    assert point_at_level(PATH, stop, 1, 0.0, 0.2, 0.4) is None     # 0.25 rad away
    assert point_at_level(PATH, np.array([0.3, 0.25, 0.0]), 1, 1e-3, 1.0, 0.5) is None


def test_the_point_of_an_angle_the_path_passes_twice_is_the_one_nearest_along_it():
    """Joint 1 goes up to 0.2 and back down: 0.1 rad at a quarter and at three quarters."""
    path = np.array([[0.0, 0.0, 0.0], [0.05, 0.2, 0.0], [0.1, 0.0, 0.0]])
    stop = np.array([0.05, 0.1, 0.0])
    assert np.allclose(point_at_level(path, stop, 1, 0.0, 0.1, 0.2), [0.025, 0.1, 0.0])
    assert np.allclose(point_at_level(path, stop, 1, 0.0, 0.1, 0.8), [0.075, 0.1, 0.0])
