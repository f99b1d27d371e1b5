"""Step 7: recovery by slicing S_F, checked at every combinatorially distinct lock."""

from dataclasses import replace

import numpy as np
import pytest
from ftplan_testing import SCENES, paper_scene

from ftplan_ros.core import (
    CollisionChecker,
    InputError,
    load_scene,
    locate_on_nominal_path,
    plan,
    recover,
)
from ftplan_ros.core.model.paths import densify
from ftplan_ros.core.paper.failure_surface import FailureSurface


@pytest.fixture(scope='module')
def plans():
    out = {}
    for name in ('fig3a', 'fig3c'):
        scene = load_scene(SCENES / f'{name}.yaml')
        out[name] = (scene, plan(scene))
    scene = paper_scene()
    out['free'] = (scene, plan(scene))
    return out


def lock_points(surface, joint):
    """A lock on the nominal path at every level where the slice's combinatorics can change.

    The slice graph only changes when the level passes a web vertex value, so the vertex
    values in the nominal range and the midpoints between them cover every case.
    """
    nominal = surface.nominal_path
    values = np.unique(surface.vertices[:, joint])
    low, high = sorted((nominal[0, joint], nominal[-1, joint]))
    critical = values[(values >= low) & (values <= high)]
    levels = np.unique(np.concatenate([critical, (critical[1:] + critical[:-1]) / 2]))
    start, end = nominal[0], nominal[-1]
    if start[joint] == end[joint]:  # the nominal path is this joint's hit path: any point
        return [start + t * (end - start) for t in np.linspace(0, 1, 7)]
    points = []
    for level in levels:
        t = (level - start[joint]) / (end[joint] - start[joint])
        point = start + t * (end - start)
        point[joint] = level
        points.append(point)
    return points


@pytest.mark.parametrize('name', ['fig3a', 'fig3c', 'free'])
def test_every_lock_on_the_nominal_path_recovers(plans, name):
    scene, result = plans[name]
    surface = result.surface
    goal = np.asarray(scene.task.goal)
    tried = 0
    for joint in range(3):
        for theta in lock_points(surface, joint):
            rescue = recover(surface, theta, joint)
            assert rescue is not None, (joint, np.degrees(theta))
            assert np.all(rescue.path[:, joint] == theta[joint])
            assert np.allclose(rescue.path[0], theta)
            assert np.linalg.norm(scene.robot.forward_kinematics(rescue.path[-1]) - goal) \
                <= scene.task.goal_tolerance
            tried += 1
    assert tried > 300


@pytest.mark.parametrize('name', ['fig3a', 'fig3c'])
def test_recovery_paths_are_collision_free_when_sampled_densely(plans, name):
    scene, result = plans[name]
    checker = CollisionChecker(scene.robot, scene.obstacles)
    for progress in np.linspace(0, 1, 9):
        theta = result.nominal_path[0] + progress * (result.nominal_path[-1]
                                                     - result.nominal_path[0])
        for joint in range(3):
            path = recover(result.surface, theta, joint).path
            assert checker.min_clearance(densify(path, 0.002)).min() > 0


def test_locks_at_the_ends(plans):
    scene, result = plans['fig3a']
    for joint in range(3):
        at_start = recover(result.surface, result.theta_s, joint)
        assert at_start is not None
        at_goal = recover(result.surface, result.nominal_path[-1], joint)
        assert at_goal.length == pytest.approx(0.0, abs=1e-9)


def test_a_lock_a_hair_past_either_end_of_the_path_recovers(plans):
    _, result = plans['fig3a']
    path = result.nominal_path
    for end, outward in ((path[0], path[0] - path[1]), (path[-1], path[-1] - path[-2])):
        for joint in range(3):
            theta = end.copy()
            theta[joint] += 1e-9 * np.sign(outward[joint] or 1.0)
            rescue = recover(result.surface, theta, joint)
            assert rescue is not None and rescue.path[0, joint] == theta[joint]


def test_the_hit_path_keeps_its_joint_fixed(plans):
    _, result = plans['fig3a']
    surface = result.surface
    for joint, k in enumerate(surface.hit_paths):
        assert np.all(surface.paths[k, :, joint] == result.theta_s[joint])


def test_bad_locks_are_rejected(plans):
    _, result = plans['free']
    theta = result.nominal_path[3]
    for joint in (3, -1, 1.0, True, np.bool_(False)):
        with pytest.raises(InputError, match='joint: must be in 0..2'):
            recover(result.surface, theta, joint)
    assert recover(result.surface, theta, np.int64(1)) is not None
    for offset in (np.inf, np.nan, -1e-6):
        with pytest.raises(InputError, match='max_offset: must be a finite distance'):
            recover(result.surface, theta, 0, max_offset=offset)
    with pytest.raises(InputError, match='theta: must be 3 finite angles'):
        recover(result.surface, np.array([np.nan, 0.0, 0.0]), 0)
    with pytest.raises(InputError, match='not on the nominal path'):
        recover(result.surface, theta + np.array([0.0, 0.1, 0.0]), 0)
    with pytest.raises(InputError, match='not on the nominal path'):
        recover(result.surface, theta + 10.0, 1)
    paths = result.surface.paths.copy()
    paths[-1, -1, 2] = np.inf
    with pytest.raises(InputError, match='surface: has a point that is not finite'):
        recover(replace(result.surface, paths=paths), theta, 0)
    # What recover has learned of a surface (ids, counts, finiteness) cannot go stale.
    with pytest.raises(ValueError, match='read-only'):
        result.surface.paths[-1, -1, 2] = np.nan


def test_a_repeated_waypoint_on_the_lock_level_gives_the_lock_point_itself():
    """A zero-length nominal segment is projected onto, never cut (0/0 gave NaN points)."""
    nominal = np.array([[0.0, 0.0, 0.0], [0.5, 0.2, 0.1], [0.5, 0.2, 0.1], [1.0, 0.4, 0.2]])
    surface = FailureSurface(np.stack([nominal, nominal + [0.0, 0.0, 0.3]]), 0, (), (0,))
    for theta in (nominal[1], nominal[1] + [0.0, 1e-8, 0.0]):
        segment, point = locate_on_nominal_path(surface, theta, 0)
        assert segment in (0, 1, 2) and np.all(np.isfinite(point))
        assert np.linalg.norm(point - theta) <= 1e-6 and point[0] == theta[0]


def test_locating_a_lock_checks_its_arguments_before_the_compiled_search(plans):
    """locate_on_nominal_path is public: out-of-range joints must never reach the kernel."""
    _, result = plans['free']
    surface, theta = result.surface, result.nominal_path[3]
    for joint in (3, -1, 10**20, 1.0, True):
        with pytest.raises(InputError, match='joint: must be in 0..2'):
            locate_on_nominal_path(surface, theta, joint)
    for bad in (theta[:2], np.append(theta, 0.0), theta[None], np.array([np.nan, 0.0, 0.0])):
        with pytest.raises(InputError, match='theta: must be 3 finite angles'):
            locate_on_nominal_path(surface, bad, 0)
    for paths in (surface.paths[:, :1], np.where(np.isnan(surface.paths), 0.0, np.nan)):
        with pytest.raises(InputError, match='nominal path that is not two or more finite'):
            locate_on_nominal_path(replace(surface, paths=paths), theta, 0)
    assert locate_on_nominal_path(surface, theta, np.int64(1))[0] >= 0


def test_a_lock_slipped_past_a_turn_of_its_angle_is_located_at_the_turn():
    """Issue 37: a physics brake held joint 2 0.003 rad past where its angle peaks on the
    nominal path. The lock was located at a far crossing of that angle (0.1 rad away), and
    the recovery refused it as 'not on the nominal path'."""
    nominal = np.array([[0.0, 0.0, 0.0], [0.2, 0.5, 0.0], [0.4, 0.4, 0.0], [1.0, 0.6, 0.0]])
    surface = FailureSurface(np.stack([nominal, nominal + [0.0, 0.0, 0.3]]), 0, (), (0,))
    slipped = nominal[1] + [0.0, 0.003, 0.0]          # past the peak of 0.5, at 0.2 rad
    segment, point = locate_on_nominal_path(surface, slipped, 1, max_offset=0.02)
    assert segment in (0, 1) and np.allclose(point, nominal[1])
    with pytest.raises(InputError, match=r'not on the nominal path \(0\.509 rad away\)'):
        locate_on_nominal_path(surface, slipped, 1, max_offset=0.002)  # a slip beyond it
