"""Mesh covers (core/model/cover.py) against independent references.

Containment is checked by scipy's Delaunay point location on densely sampled points of
every triangle, and by distances from those points to the pieces computed from their
convex hulls; the padding against dense samples of the pieces' surfaces measured by a
k-d tree over dense samples of the mesh.
"""

import tracemalloc

import numpy as np
import pytest
from ftplan_testing import CUBE, capsule_hull, torus
from scipy.spatial import ConvexHull, Delaunay, cKDTree
from shape_references import surface_points

from ftplan_ros.core.model.cover import (
    MAX_CUT_TRIANGLES,
    MAX_MESH_TRIANGLES,
    MAX_PIECES,
    TIGHT_PADDING,
    assign_triangles,
    build_cover,
)
from ftplan_ros.core.model.geometry import Shape

SPACING = 0.001  # [m] between the samples of a triangle


def sampled_mesh(vertices, faces, spacing=SPACING):
    """Points (P, 3) on every triangle, at most about `spacing` apart (shape_references)."""
    return surface_points(Shape('mesh', vertices=vertices, faces=faces), spacing)


def held(cover, points):
    """(P,) bool: whether each point lies in some piece (Delaunay point location)."""
    inside = np.zeros(len(points), dtype=bool)
    for piece in cover.pieces:
        inside |= Delaunay(piece).find_simplex(points, tol=1e-9) >= 0
    return inside


def outside_distance(cover, points):
    """(P,) [m]: how far each point lies outside the nearest piece (0 inside), by facets."""
    outside = np.full(len(points), np.inf)
    for piece in cover.pieces:
        planes = ConvexHull(piece).equations
        for start in range(0, len(points), 50_000):  # (50,000, F) at a time: tens of MB
            chunk = slice(start, start + 50_000)
            outside[chunk] = np.minimum(outside[chunk], np.maximum(
                (points[chunk] @ planes[:, :3].T + planes[:, 3]).max(axis=1), 0.0))
    return outside


@pytest.fixture(scope='module')
def hull_300():
    vertices, faces = capsule_hull()
    return vertices, faces, build_cover(vertices, faces)


@pytest.fixture(scope='module')
def ring():
    vertices, faces = torus()
    return vertices, faces, build_cover(vertices, faces)


def test_a_convex_hull_of_300_triangles_is_one_tight_piece_that_holds_it(hull_300):
    vertices, faces, cover = hull_300
    assert len(faces) == 300
    assert len(cover.pieces) == 1 and cover.tight.all()
    assert cover.largest_padding < 1e-9  # its own hull: nothing to bulge over
    points = sampled_mesh(vertices, faces)
    assert held(cover, points).all()
    assert outside_distance(cover, points).max() < 1e-12
    assert sum(len(t) for t in cover.triangles) == 300  # each held whole


def test_a_non_convex_mesh_is_split_and_every_point_of_every_triangle_is_held(ring):
    vertices, faces, cover = ring
    assert 1 < len(cover.pieces) <= MAX_PIECES
    points = sampled_mesh(vertices, faces)
    assert held(cover, points).all()
    assert outside_distance(cover, points).max() < 1e-12
    # The pieces' triangles are the mesh, some cut where no one piece holds them.
    area = sum(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]),
                                    axis=1).sum() for t in cover.triangles)
    mesh = vertices[faces]
    expected = 0.5 * np.linalg.norm(np.cross(mesh[:, 1] - mesh[:, 0], mesh[:, 2] - mesh[:, 0]),
                                    axis=1).sum()
    assert area == pytest.approx(expected, rel=1e-9)


def test_the_padding_is_how_far_each_piece_reaches_beyond_the_mesh(ring, hull_300):
    """Against dense samples of each piece's surface, measured to dense samples of the mesh."""
    for vertices, faces, cover in (ring, hull_300):
        tree = cKDTree(sampled_mesh(vertices, faces, 0.0005))
        for piece, padding in zip(cover.pieces, cover.padding, strict=True):
            hull = ConvexHull(piece)
            surface = sampled_mesh(piece, hull.simplices, 0.001)
            reference = tree.query(surface)[0].max()
            # Both sample: the cover's every 2 mm, the reference's mesh every 0.5 mm.
            assert reference - 0.002 <= padding <= reference + 0.0005
    assert ring[2].largest_padding > TIGHT_PADDING  # the hole's rim bulges: not tight
    assert not ring[2].tight.all()


def test_assign_triangles_refuses_pieces_that_miss_part_of_the_mesh():
    vertices, faces = CUBE
    mesh = vertices[faces]
    assert assign_triangles(mesh, [vertices]) is not None
    assert assign_triangles(mesh, [0.999 * vertices]) is None


def test_a_triangle_no_one_piece_holds_is_cut_and_held_by_two():
    """A long triangle across two boxes' point sets, which together hold it."""
    triangle = np.array([[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0], [0.0, 0.02, 0.0]]])
    low = np.array([[x, y, z] for x in (-0.01, 0.11) for y in (-0.01, 0.03)
                    for z in (-0.01, 0.01)])
    high = low + [0.1, 0.0, 0.0]
    parts = assign_triangles(triangle, [low, high])
    assert parts is not None and all(len(part) for part in parts)
    assert sum(len(part) for part in parts) > 1
    assert assign_triangles(triangle, [low]) is None


@pytest.mark.parametrize('corner', [(100.0, 0.0, 0.0), (np.nan, 0.0, 0.0), (1e30, 0.0, 0.0)],
                         ids=['100-m', 'nan', '1e30'])
def test_a_mesh_that_would_be_cut_into_too_many_triangles_is_refused(corner):
    """Its triangles were quartered to 2 cm edges without a cap: a 100 m triangle (a mesh
    in millimetres read as metres) asked for 67 million, a NaN corner for ever more."""
    vertices = np.array([corner, (0.0, 0.1, 0.0), (0.0, 0.0, 0.1)])
    with pytest.raises(ValueError, match=f'would be cut into more than {MAX_CUT_TRIANGLES}'):
        build_cover(vertices, np.array([[0, 1, 2]]))


def test_proving_a_cover_holds_a_mesh_takes_no_corners_by_facets_array():
    """assign_triangles measured every corner against every facet of a piece at once: a
    smooth collision mesh of 40,000 triangles asked for 35 GiB."""
    rng = np.random.default_rng(3)
    points = rng.normal(size=(1000, 3))
    points /= np.linalg.norm(points, axis=1, keepdims=True)
    hull = ConvexHull(points)
    mesh = points[hull.simplices]  # about 2000 triangles, each a facet of the one piece
    assign_triangles(mesh, [points])  # the compiled kernels, once
    tracemalloc.start()
    try:
        triangles = assign_triangles(mesh, [points])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert triangles is not None and len(triangles[0]) == len(mesh)
    corners_by_facets = 3 * len(mesh) * len(hull.equations) * 8  # [bytes] 96 MB
    assert peak < corners_by_facets / 20, peak


def test_a_mesh_of_too_many_triangles_is_refused_before_any_work():
    vertices = np.random.default_rng(4).uniform(-0.1, 0.1, size=(1000, 3))
    faces = np.arange(3 * (MAX_MESH_TRIANGLES + 1)).reshape(-1, 3) % len(vertices)
    with pytest.raises(ValueError, match=f'has {MAX_MESH_TRIANGLES + 1} triangles, more than '
                       f'the {MAX_MESH_TRIANGLES}.*: simplify it'):
        build_cover(vertices, faces)


def test_an_empty_mesh_has_no_cover():
    with pytest.raises(ValueError, match='at least one triangle'):
        build_cover(np.zeros((0, 3)), np.zeros((0, 3), dtype=int))
