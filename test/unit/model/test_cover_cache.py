"""Mesh covers kept on disk (core/model/cover_cache.py): written once, proved when read."""

import logging

import numpy as np
import pytest
from ftplan_testing import CUBE, capsule_hull

from ftplan_ros.core.model import cover_cache
from ftplan_ros.core.model.cover_cache import cache_directory, mesh_cover


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path))
    return tmp_path / 'ftplan' / 'covers'


def refuse_to_build(*_):
    raise AssertionError('built again')


def test_a_cover_is_kept_under_xdg_cache_home_and_read_back(cache, monkeypatch):
    vertices, faces = capsule_hull()
    built = mesh_cover(vertices, faces)
    files = list(cache.glob('*.npz'))
    assert len(files) == 1
    monkeypatch.setattr(cover_cache, 'build_cover', refuse_to_build)
    read = mesh_cover(vertices, faces)
    assert len(read.pieces) == len(built.pieces)
    assert all(np.array_equal(a, b) for a, b in zip(read.pieces, built.pieces, strict=True))
    assert np.array_equal(read.padding, built.padding)
    assert sum(map(len, read.triangles)) == len(faces)
    moved = vertices + [0.001, 0.0, 0.0]  # another mesh: another file
    with pytest.raises(AssertionError, match='built again'):
        mesh_cover(moved, faces)


@pytest.mark.parametrize('damage', ['garbage', 'shrunk', 'no padding', 'nan'])
def test_a_damaged_or_wrong_file_is_built_again(damage, cache, caplog):
    vertices, faces = CUBE
    mesh_cover(vertices, faces)
    path, = cache.glob('*.npz')
    if damage == 'garbage':
        path.write_bytes(b'not a zip file')
    elif damage == 'shrunk':  # pieces that miss the mesh's corners: never trusted
        np.savez(path, padding=np.zeros(1), piece_0=0.9 * vertices)
    elif damage == 'no padding':
        np.savez(path, piece_0=vertices)
    else:
        np.savez(path, padding=np.zeros(1), piece_0=np.full((8, 3), np.nan))
    with caplog.at_level(logging.WARNING, logger=cover_cache.__name__):
        cover = mesh_cover(vertices, faces)
    assert 'building it again' in caplog.text
    assert np.allclose(np.sort(cover.pieces[0], axis=0), np.sort(vertices, axis=0))
    assert mesh_cover(vertices, faces).pieces[0].shape == (8, 3)  # and kept again


def test_a_cache_that_cannot_be_written_only_warns(tmp_path, monkeypatch, caplog):
    blocked = tmp_path / 'file'
    blocked.write_text('a file where the cache folder would be')
    monkeypatch.setenv('XDG_CACHE_HOME', str(blocked))
    vertices, faces = CUBE
    with caplog.at_level(logging.WARNING, logger=cover_cache.__name__):
        cover = mesh_cover(vertices, faces)
    assert len(cover.pieces) == 1
    assert 'cannot keep the mesh cover' in caplog.text


def test_the_cache_folder_is_ftplan_cache_dir_else_xdg_else_home(monkeypatch, tmp_path):
    monkeypatch.setenv('HOME', str(tmp_path))
    monkeypatch.setenv('XDG_CACHE_HOME', 'relative/cache')  # ignored, as XDG says
    assert cache_directory() == tmp_path / '.cache' / 'ftplan'
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path / 'xdg'))
    assert cache_directory() == tmp_path / 'xdg' / 'ftplan'
    monkeypatch.setenv('FTPLAN_CACHE_DIR', str(tmp_path / 'mine'))
    assert cache_directory() == tmp_path / 'mine'
