"""Shared fixtures: the repository's paths and the paper's robot and tasks."""

from pathlib import Path

import numpy as np
import pytest

from ftplan_ros.core.scene import Scene, load_scene, parse_scene

REPO = Path(__file__).resolve().parents[1]
SCENES = REPO / 'config' / 'scenes'


def paper_scene(start=(2.0, 0.0), obstacles=(), tolerance=0.01) -> Scene:
    """The paper's 3R arm (links of 1 m) moving its tip from `start` to [1, 0]."""
    return parse_scene({
        'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]},
        'obstacles': [{'type': 'sphere', 'center': list(c), 'radius': r} for c, r in obstacles],
        'task': {'start': list(start), 'goal': [1.0, 0.0], 'goal_tolerance': tolerance}})


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(scope='session')
def fig3_scenes():
    return {name: load_scene(SCENES / f'{name}.yaml') for name in ('fig3a', 'fig3b', 'fig3c')}
