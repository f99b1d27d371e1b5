"""Independent references for the grid tests.

The paper's arm written out, configurations sampled in cells, and a plan's guarantee
checked without its certificate: locks of every tolerated joint along the nominal path
recovered with `recover` (what the executor runs), each recovery path sampled every half
degree with the robot's own CollisionChecker and ending within the goal tolerance.
"""

import numpy as np

from ftplan_ros.core import CollisionChecker, recover
from ftplan_ros.core.model.paths import densify, point_at_fraction

LINKS = np.array([1.0, 1.0, 1.0])  # [m] the paper's arm


def wrapped(angles):
    """Angles [rad] wrapped to (-π, π] through the complex plane, not as the core wraps them."""
    return np.angle(np.exp(1j * np.asarray(angles)))


def planar_fk(lengths, thetas):
    """Tool positions (..., 2) [m] of a planar chain, written out."""
    phi = np.cumsum(thetas, axis=-1)
    return np.stack([np.sum(lengths * np.cos(phi), axis=-1),
                     np.sum(lengths * np.sin(phi), axis=-1)], axis=-1)


def sample_cells(lattice, cells, per_cell, rng):
    """Random configurations (c·per_cell, 3) [rad] inside the cells (c, 3)."""
    offsets = rng.random((len(cells), per_cell, 3))
    return (lattice.lower + (cells[:, None, :] + offsets) * lattice.step).reshape(-1, 3)


HALF_DEGREE = np.radians(0.5)


def lock_points(result, joint, rng, moments=50, levels=40):
    """Lock configurations on the nominal path, where a lock of the joint may happen.

    `moments` spread by length, every waypoint, and `levels` sampled among the web's
    vertex values of the joint (where the slice's combinatorics change), on every nominal
    segment that takes them.
    """
    path = result.nominal_path
    points = [point_at_fraction(path, f) for f in np.linspace(0.0, 1.0, moments)]
    points += list(path)
    values = np.unique(result.surface.vertices[:, joint])
    low, high = path[:, joint].min(), path[:, joint].max()
    values = values[(values >= low) & (values <= high)]
    for level in rng.choice(values, min(levels, len(values)), replace=False):
        for a, b in zip(path[:-1], path[1:], strict=True):
            if a[joint] != b[joint] and min(a[joint], b[joint]) <= level <= max(a[joint],
                                                                                b[joint]):
                point = a + (level - a[joint]) / (b[joint] - a[joint]) * (b - a)
                point[joint] = level
                points.append(point)
    return points


def assert_every_lock_recovers(scene, result, seed):
    """The plan's motion and every lock of `lock_points` recovered, by brute force."""
    robot, task = scene.robot, scene.task
    checker = CollisionChecker(robot, scene.obstacles)
    goal = np.asarray(task.goal, dtype=float)
    # The motion itself: from M_s, collision-free, to the goal.
    assert np.linalg.norm(robot.forward_kinematics(result.theta_s) - task.start) < 1e-9
    assert np.array_equal(result.nominal_path[0], result.theta_s)
    assert checker.min_clearance(densify(result.nominal_path, HALF_DEGREE)).min() > 0.0
    assert np.linalg.norm(robot.forward_kinematics(result.nominal_path[-1]) - goal) \
        <= task.goal_tolerance
    rng = np.random.default_rng(seed)
    checked = 0
    for joint in scene.tolerated_joints:
        for theta in lock_points(result, joint, rng):
            where = (seed, joint, theta.tolist())
            rescue = recover(result.surface, theta, joint)
            assert rescue is not None, where
            assert np.all(rescue.path[:, joint] == theta[joint]), where
            assert np.allclose(rescue.path[0], theta), where
            assert checker.min_clearance(densify(rescue.path, HALF_DEGREE)).min() > 0.0, where
            assert np.linalg.norm(robot.forward_kinematics(rescue.path[-1]) - goal) \
                <= task.goal_tolerance, where
            checked += 1
    assert checked >= 3 * 60
