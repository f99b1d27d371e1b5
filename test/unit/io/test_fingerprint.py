"""Scenes as plain data (core/io/fingerprint.py): written back to YAML, fingerprinted."""

import pytest
from ftplan_testing import SCENES

from ftplan_ros.core.io.fingerprint import scene_to_dict
from ftplan_ros.core.io.scene_file import load_scene


def test_spatial_scenes_are_not_written_back():
    with pytest.raises(ValueError, match='only planar scenes'):
        scene_to_dict(load_scene(SCENES / 'panda_shelf.yaml'))
