"""Shared fixtures of the unit tests."""

import numpy as np
import pytest


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(scope='session')
def bot_urdf_file(tmp_path_factory):
    """The test robot's URDF file, with its STL mesh beside it (ftplan_testing.bot)."""
    from ftplan_testing import write_bot  # not at import: test/ros shares this file
    return write_bot(tmp_path_factory.mktemp('testbot'))
