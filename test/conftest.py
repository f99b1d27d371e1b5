"""Shared fixtures of the unit tests."""

import numpy as np
import pytest


@pytest.fixture(scope='session', autouse=True)
def cache_home(tmp_path_factory):
    """Keep a test run's cache entries (mesh covers, sampled self-collision exceptions) out
    of the user's cache: ftplan's cache folder is then XDG_CACHE_HOME/ftplan in a tmp folder."""
    with pytest.MonkeyPatch.context() as patch:
        home = tmp_path_factory.mktemp('cache')
        patch.setenv('XDG_CACHE_HOME', str(home))
        patch.delenv('FTPLAN_CACHE_DIR', raising=False)
        yield home


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture(scope='session')
def bot_urdf_file(tmp_path_factory):
    """The test robot's URDF file, with its STL mesh beside it (ftplan_testing.bot)."""
    from ftplan_testing import write_bot  # not at import: test/ros shares this file
    return write_bot(tmp_path_factory.mktemp('testbot'))


@pytest.fixture
def urdf_file(tmp_path):
    """Return write(xml) -> path: a URDF in tmp_path beside the test mesh, a garbage mesh
    and an empty one."""
    from ftplan_testing import TETRAHEDRON, write_binary_stl  # as above
    write_binary_stl(tmp_path / 'tet.stl', *TETRAHEDRON)
    (tmp_path / 'garbage.stl').write_bytes(b'solid \x00\xff not a mesh\n' * 7)
    (tmp_path / 'empty.stl').touch()

    def write(xml):
        path = tmp_path / 'variant.urdf'
        path.write_text(xml)
        return path
    return write
