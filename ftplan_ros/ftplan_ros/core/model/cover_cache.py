"""Mesh covers kept on disk by the mesh's content, so that each mesh is covered once.

A cover (cover.py) takes about a second to build for each of the Panda's meshes and up
to 20 s for a visual mesh of 8,000 triangles; every robot build, plan worker and node
would pay it again. Files live in `covers/` of ftplan's cache folder (`$FTPLAN_CACHE_DIR`
when set, else `$XDG_CACHE_HOME/ftplan`, else `~/.cache/ftplan`), named by a SHA-256 of
the mesh's vertices and faces and the builder's settings. A file read back is trusted
for its pieces only: `assign_triangles` proves again that they hold the mesh, and a file
that is damaged, stale or does not prove it is built again. A cache that cannot be
written costs only the time: the cover is used all the same, with a warning.
"""

from __future__ import annotations

import hashlib
import logging
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from .cover import MAX_PIECES, TIGHT_PADDING, Cover, assign_triangles, build_cover

logger = logging.getLogger(__name__)

# Bumped whenever build_cover makes different pieces from the same mesh.
VERSION = 1


def cache_directory() -> Path:
    """Return ftplan's cache folder (module docstring); a relative XDG_CACHE_HOME is ignored."""
    if os.environ.get('FTPLAN_CACHE_DIR'):
        return Path(os.environ['FTPLAN_CACHE_DIR'])
    base = os.environ.get('XDG_CACHE_HOME', '')
    root = Path(base) if os.path.isabs(base) else Path.home() / '.cache'
    return root / 'ftplan'


def mesh_cover(vertices: np.ndarray, faces: np.ndarray) -> Cover:
    """Return the cover of a mesh, vertices (V, 3) [m] and faces (F, 3), kept or built."""
    vertices = np.ascontiguousarray(vertices, dtype=float)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    path = cache_directory() / 'covers' / f'{_digest(vertices, faces)}.npz'
    cover = _read(path, vertices[faces])
    if cover is None:
        cover = build_cover(vertices, faces)
        _write(path, cover)
    return cover


def _digest(vertices: np.ndarray, faces: np.ndarray) -> str:
    digest = hashlib.sha256(repr((VERSION, TIGHT_PADDING, MAX_PIECES, vertices.shape,
                                  faces.shape)).encode())
    digest.update(vertices.tobytes())
    digest.update(faces.tobytes())
    return digest.hexdigest()


def _read(path: Path, mesh: np.ndarray) -> Cover | None:
    """Return the cover kept at `path` if it holds the mesh (T, 3, 3), else None."""
    try:
        with np.load(path, allow_pickle=False) as saved:
            padding = np.asarray(saved['padding'], dtype=float)
            pieces = [np.asarray(saved[f'piece_{k}'], dtype=float) for k in range(len(padding))]
    except FileNotFoundError:
        return None
    except (OSError, KeyError, ValueError, zipfile.BadZipFile) as error:
        logger.warning('mesh cover %s is unreadable (%s): building it again', path, error)
        return None
    if (padding.ndim != 1 or not len(padding) or np.isnan(padding).any()
            or any(piece.ndim != 2 or piece.shape[1:] != (3,) or not len(piece)
                   or not np.isfinite(piece).all() for piece in pieces)):
        logger.warning('mesh cover %s is malformed: building it again', path)
        return None
    triangles = assign_triangles(mesh, pieces)
    if triangles is None:
        logger.warning('mesh cover %s does not hold its mesh: building it again', path)
        return None
    return Cover(tuple(pieces), tuple(triangles), padding)


def _write(path: Path, cover: Cover) -> None:
    """Keep the cover's pieces and padding at `path`, atomically; warn if it cannot."""
    arrays = {f'piece_{k}': piece for k, piece in enumerate(cover.pieces)}
    temporary = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, suffix='.npz', delete=False) as file:
            temporary = Path(file.name)
            np.savez(file, padding=cover.padding, **arrays)
        os.replace(temporary, path)
    except OSError as error:
        if temporary is not None:
            temporary.unlink(missing_ok=True)
        logger.warning('cannot keep the mesh cover in %s (%s): it will be built again next '
                       'time', path.parent, error)
