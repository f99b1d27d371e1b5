"""Scenes as data (core/model/scene.py): obstacles checked whatever their source, copies."""

import math

import numpy as np
import pytest
from ftplan_testing import SCENES, paper_scene

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.scene_file import load_scene
from ftplan_ros.core.model.scene import Obstacle, Task


def test_obstacles_beyond_the_bounds_are_refused_whatever_their_source():
    """A sphere at 1e200 of radius 2e200 once overflowed the distances to +inf (issue 10)."""
    with pytest.raises(InputError, match=r'obstacle\.center: must be finite and within'):
        Obstacle('sphere', (1e200, 0.0, 0.0), radius=2e200)
    with pytest.raises(InputError, match=r'obstacle\.center'):
        Obstacle('box', (1e155, 0.0, 0.0), size=(1.0, 1.0, 1.0))
    with pytest.raises(InputError, match=r'obstacle\.size'):
        Obstacle('box', (1.0, 0.0, 0.0), size=(math.nan, 1.0, 1.0))
    with pytest.raises(InputError, match=r'obstacle\.radius: must be > 0'):
        Obstacle('cylinder', (1.0, 0.0, 0.0), radius=0.0, length=1.0)


def test_with_obstacles_keeps_the_rest():
    scene = paper_scene(obstacles=[((1.2, 0.6), 0.2)])
    more = scene.with_obstacles(scene.obstacles)
    assert len(more.obstacles) == 2 and more.task == scene.task
    assert np.allclose(more.obstacles[1].center, scene.obstacles[0].center)


def test_with_task_rebinds_a_spatial_arm():
    scene = load_scene(SCENES / 'panda_shelf.yaml')
    moved = scene.with_task(Task((0.4, 0.0, 0.5), (0.4, 0.1, 0.5)))
    assert moved.robot.task_kind == 'position' and moved.robot.model is scene.robot.model
    assert moved.obstacles == scene.obstacles and moved.tolerate == scene.tolerate
