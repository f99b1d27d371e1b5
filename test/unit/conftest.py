"""Fixtures of the unit tests in more than one folder."""

import pytest
from ftplan_testing import SCENES

from ftplan_ros.core import load_scene, plan


@pytest.fixture(scope='session')
def fig3a():
    """The scene of Fig. 3(a) and its plan."""
    scene = load_scene(SCENES / 'fig3a.yaml')
    return scene, plan(scene)
