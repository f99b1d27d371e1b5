"""Crowded scenes (bench/crowded.py): they repeat, keep their disks clear and have a plan."""

import numpy as np
import pytest
from ftplan_testing import CROWDED, make_crowded

from ftplan_ros.bench.crowded import RADII, crowded_scene
from ftplan_ros.core.grid.existence import Existence, decide_existence


def test_crowded_scenes_repeat_and_keep_their_disks_clear():
    few = {'disks': 2, 'attempts': 4, 'cells': 64}
    again = crowded_scene(np.random.default_rng(20), **few)
    assert again == crowded_scene(np.random.default_rng(20), **few)
    assert again.obstacles == make_crowded(20).obstacles[:len(again.obstacles)]
    first = make_crowded(20)
    x_s, x_g = np.asarray(first.task.start), np.asarray(first.task.goal)
    assert 1.8 - 1e-3 <= np.linalg.norm(x_s) <= 2.6 + 1e-3
    assert 0.9 - 1e-3 <= np.linalg.norm(x_g) <= 1.5 + 1e-3
    assert 1 <= len(first.obstacles) <= CROWDED['disks']
    for ob in first.obstacles:
        centre = np.asarray(ob.center[:2])
        assert RADII[0] - 1e-3 <= ob.radius <= RADII[1] + 1e-3
        for point in (np.zeros(2), x_s, x_g):
            assert np.linalg.norm(centre - point) > ob.radius + 0.05 - 2e-3


@pytest.mark.parametrize('seed', [12, 20, 4])
def test_every_crowded_scene_is_proved_to_have_a_plan(seed):
    """The module's promise: a crowded scene has a plan (its reference says YES).

    Seed 4 once broke it: its first random task (start [2.548, 0.182], goal [-1.298,
    -0.723]) has no proved plan even without obstacles, and came back unchecked; such a
    task is now drawn again.
    """
    scene = make_crowded(seed)
    assert decide_existence(scene, CROWDED['cells']).existence is Existence.YES, \
        f'{len(scene.obstacles)} disks'

