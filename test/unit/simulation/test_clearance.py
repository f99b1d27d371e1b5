"""The sim's clearance watch (simulation/clearance.py): exact collisions, counted once each."""

from dataclasses import dataclass

import numpy as np
import pytest
from ftplan_testing import SCENES

from ftplan_ros.core import CollisionChecker, load_scene
from ftplan_ros.simulation.clearance import CLOSEST_SAMPLES, ClearanceMonitor

SCENE = load_scene(SCENES / 'fig3a.yaml')
CHECKER = CollisionChecker(SCENE.robot, SCENE.obstacles)


@dataclass
class Obstacles:
    checker: CollisionChecker
    lost: str = ''


def sweep(start: float, end: float, count: int = 200) -> np.ndarray:
    """The stretched arm turning joint 1 from `start` to `end` [rad]: (count, 3)."""
    return np.column_stack([np.linspace(start, end, count), np.zeros(count), np.zeros(count)])


def test_a_collision_counts_once_until_the_arm_is_clear_again():
    monitor = ClearanceMonitor(Obstacles(CHECKER))
    into = sweep(0.0, 0.6)                          # link 1 through the disk at 0.51 rad
    assert CHECKER.min_clearance(into).min() < 0.0
    collision = monitor.check(into)
    assert collision is not None and collision.clearance < 0.0
    assert CHECKER.min_clearance(collision.configuration[None])[0] == \
        pytest.approx(collision.clearance)
    assert monitor.collisions == 1 and monitor.min_clearance == collision.clearance
    assert monitor.check(sweep(0.6, 0.5, 5)) is None   # still inside: the same collision
    assert monitor.check(sweep(0.9, 1.0, 5)) is None   # clear again
    assert monitor.check(sweep(0.45, 0.55)) is not None and monitor.collisions == 2


def test_the_smallest_clearance_is_measured_exactly_at_the_closest_samples():
    monitor = ClearanceMonitor(Obstacles(CHECKER))
    clear = sweep(-0.2, 0.2, 400)
    assert CHECKER.min_clearance(clear).min() > 0.0
    assert monitor.check(clear) is None and monitor.min_clearance == float('inf')
    monitor.measure_closest()
    assert monitor.min_clearance == pytest.approx(CHECKER.min_clearance(clear).min(), abs=1e-12)
    assert len(clear) > CLOSEST_SAMPLES                  # only a few were measured exactly
    monitor.measure_closest()                            # nothing new: nothing changes
    assert monitor.min_clearance == pytest.approx(CHECKER.min_clearance(clear).min(), abs=1e-12)


def test_the_checker_of_the_moment_is_used_and_clear_starts_afresh():
    obstacles = Obstacles(CollisionChecker(SCENE.robot, ()))
    monitor = ClearanceMonitor(obstacles)
    assert monitor.check(sweep(0.0, 0.6)) is None        # no obstacle yet
    obstacles.checker = CHECKER                          # the obstacle topic brought them
    assert monitor.check(sweep(0.0, 0.6)) is not None
    monitor.clear()
    assert monitor.collisions == 0 and monitor.min_clearance == float('inf')


def test_the_braking_clearance_is_the_smallest_from_a_lock_to_the_next_stop():
    monitor = ClearanceMonitor(Obstacles(CHECKER))
    before, braking, after = sweep(0.1, 0.22, 50), sweep(-0.1, 0.05, 50), sweep(-0.2, -0.28, 50)
    exact = [CHECKER.min_clearance(part).min() for part in (before, braking, after)]
    assert exact[1] > max(exact[0], exact[2]) and min(exact) > 0.0  # braking: the clearest
    monitor.check(before)
    monitor.begin_braking()
    monitor.check(braking)
    monitor.measure_closest()                                # the arm stands: braking over
    monitor.check(after)
    monitor.measure_closest()
    assert monitor.braking_clearance == pytest.approx(exact[1], abs=1e-12)
    assert monitor.min_clearance == pytest.approx(min(exact), abs=1e-12)
    monitor.clear()
    assert monitor.braking_clearance == float('inf')
