"""Scenes as plain data (core/io/fingerprint.py): written back to YAML, fingerprinted."""

import json
from dataclasses import replace

import pytest
import yaml
from ftplan_testing import SCENES, WAM4

from ftplan_ros.core.io.fingerprint import scene_fingerprint, scene_to_dict
from ftplan_ros.core.io.scene_file import load_scene, parse_scene
from ftplan_ros.core.model.scene import Obstacle


def test_spatial_scenes_are_not_written_back():
    with pytest.raises(ValueError, match='only planar scenes'):
        scene_to_dict(load_scene(SCENES / 'panda_shelf.yaml'))


def test_a_planar_scene_comes_back_from_its_yaml_with_every_field():
    scene = parse_scene({
        'robot': {'type': 'planar', 'link_lengths': [1.0, 0.8, 0.5], 'link_radius': 0.02,
                  'joint_names': ['s', 'e', 'w'], 'joint_limits': [None, [-2.0, 2.5], None]},
        'obstacles': [{'type': 'sphere', 'center': [1.2, 0.6], 'radius': 0.2},
                      {'type': 'box', 'center': [0.0, 1.5, 0.1], 'size': [0.2, 0.4, 1.0],
                       'rpy': [0.0, 0.0, 0.5]},
                      {'type': 'cylinder', 'center': [-1.0, -1.0], 'radius': 0.1,
                       'length': 2.0}],
        'task': {'start': [2.0, 0.0], 'goal': [1.0, 0.5], 'goal_tolerance': 0.02},
        'frame_id': 'table', 'tolerate': ['e', 's']})
    written = scene_to_dict(scene)
    assert yaml.safe_load(yaml.safe_dump(written)) == written  # plain data
    assert parse_scene(written) == scene
    assert scene_fingerprint(scene) == written


def test_a_spatial_scene_is_fingerprinted_by_its_data_and_its_robots_geometry():
    shelf = load_scene(SCENES / 'panda_shelf.yaml')
    fingerprint = scene_fingerprint(shelf)
    assert scene_fingerprint(load_scene(SCENES / 'panda_shelf.yaml')) == fingerprint
    assert json.loads(json.dumps(fingerprint, allow_nan=False)) == fingerprint
    for other in (shelf.with_tolerated(['panda_joint1']),
                  shelf.with_obstacles([Obstacle('sphere', (0.3, 0.3, 0.3), radius=0.05)]),
                  shelf.with_task(replace(shelf.task, goal_tolerance=0.01))):
        changed = scene_fingerprint(other)
        assert changed != fingerprint and changed['robot'] == fingerprint['robot']
    # The same joints and limits on thicker links: only the geometry's digest tells them apart.
    thin, thick = (scene_fingerprint(parse_scene({'robot': dict(WAM4, link_radius=radius)}))
                   for radius in (0.04, 0.05))
    assert thin['robot']['geometry_sha256'] != thick['robot']['geometry_sha256']
    assert {**thin['robot'], 'geometry_sha256': ''} == {**thick['robot'], 'geometry_sha256': ''}
