"""Random scenes of the paper's arm (bench/scenes.py): the promised task and disks, repeatable."""

import numpy as np

from ftplan_ros.bench.scenes import random_scene


def test_random_scenes_repeat_and_keep_their_disks_clear_of_base_start_and_goal():
    for seed in range(20):
        disks = seed % 7
        scene = random_scene(np.random.default_rng(seed), disks)
        assert scene == random_scene(np.random.default_rng(seed), disks)
        start, goal = np.asarray(scene.task.start), np.asarray(scene.task.goal)
        assert 1.8 - 1e-3 <= np.linalg.norm(start) <= 2.6 + 1e-3  # written to 1 mm
        assert 0.9 - 1e-3 <= np.linalg.norm(goal) <= 1.5 + 1e-3
        assert scene.robot.link_lengths == (1.0, 1.0, 1.0) and len(scene.obstacles) == disks
        for disk in scene.obstacles:
            centre = np.asarray(disk.center[:2])
            assert disk.shape == 'sphere' and 0.1 - 1e-3 <= disk.radius <= 0.3 + 1e-3
            for point in (np.zeros(2), start, goal):
                assert np.linalg.norm(centre - point) > disk.radius + 0.05 - 2e-3
