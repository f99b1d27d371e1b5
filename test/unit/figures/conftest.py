"""The plans the figure tests draw, each made once per session."""

import numpy as np
import pytest
from ftplan_testing import SCENES

from ftplan_ros.core import load_scene, parse_scene, plan, recover
from ftplan_ros.core.model.paths import path_until, point_at_fraction


@pytest.fixture(scope='session')
def scene():
    """The scene of Fig. 3(a)."""
    return load_scene(SCENES / 'fig3a.yaml')


@pytest.fixture(scope='session')
def result(scene):
    """Its plan."""
    result = plan(scene)
    assert result.feasible, result.reason
    return result


@pytest.fixture(scope='session')
def drill_motion(result):
    """A drill as `drill_once` runs it: joint 2 locks 45 % along the nominal path."""
    joint, progress = 1, 0.45
    before = path_until(result.nominal_path, progress)
    rescue = recover(result.surface, point_at_fraction(result.nominal_path, progress), joint)
    return np.vstack([before, rescue.path]), len(before) - 1, joint


PANDA_SCENE = {
    'robot': '../robots/panda.yaml',
    'obstacles': [{'type': 'box', 'center': [0.5, 0.0, 0.2], 'size': [0.3, 0.6, 0.02]}],
    'task': {'start': {'position': [0.5, -0.2, 0.4], 'orientation': [1.0, 0.0, 0.0, 0.0]},
             'goal': {'position': [0.5, 0.2, 0.4], 'orientation': [1.0, 0.0, 0.0, 0.0]},
             'goal_tolerance': 0.005, 'orientation_tolerance': 0.01},
    # The elbow keeps its angle along the self-motion of a pose: it cannot be tolerated.
    'tolerate': ['panda_joint1', 'panda_joint2', 'panda_joint3', 'panda_joint5',
                 'panda_joint6', 'panda_joint7'],
}


@pytest.fixture(scope='session')
def panda_scene():
    """The Panda over a box on a pose task, every joint but the elbow tolerated."""
    return parse_scene(PANDA_SCENE, 'panda_box', SCENES)


@pytest.fixture(scope='session')
def panda_result(panda_scene):
    """Its plan."""
    result = plan(panda_scene, rng=np.random.default_rng(0))
    assert result.feasible, result.reason
    return result
