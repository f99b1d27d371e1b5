"""Convex primitives and meshes: sizes, signed distances, support functions, fcl objects.

The shapes of the arm's links and of the obstacles, each in its own frame: a sphere
about the origin, a box centred on it (full edge lengths `size`), a cylinder and a
capsule along the local z axis (`length` is the cylinder's height, the capsule's core
segment), and a triangle mesh (`vertices` (V, 3), `faces` (F, 3)). Lengths are metres.

`signed_distance` is exact for the convex primitives; `support` bounds every shape,
meshes included, so `separation` is a lower bound on the distance between any two
shapes whatever direction it is given (the collision checker's certified distances).
A mesh is measured through its `cover`: convex pieces that hold it (cover.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import fcl
import numpy as np

from .cover import Cover
from .cover_cache import mesh_cover

KINDS = ('sphere', 'box', 'cylinder', 'capsule', 'mesh')


@dataclass(frozen=True, eq=False)
class Shape:
    """A collision shape in its own frame (metres); which fields count depends on `kind`."""

    kind: str
    radius: float = 0.0
    size: tuple[float, float, float] = (0.0, 0.0, 0.0)
    length: float = 0.0
    vertices: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    faces: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=int))

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f'unknown shape kind {self.kind!r}')

    def bounding_sphere(self) -> tuple[np.ndarray, float]:
        """Centre (3,) and radius [m] of a sphere holding the shape, in its frame."""
        if self.kind == 'sphere':
            return np.zeros(3), self.radius
        if self.kind == 'box':
            return np.zeros(3), 0.5 * float(np.linalg.norm(self.size))
        if self.kind == 'cylinder':
            return np.zeros(3), float(np.hypot(self.radius, 0.5 * self.length))
        if self.kind == 'capsule':
            return np.zeros(3), self.radius + 0.5 * self.length
        low, high = self.vertices.min(axis=0), self.vertices.max(axis=0)
        centre = 0.5 * (low + high)
        return centre, float(np.linalg.norm(self.vertices - centre, axis=1).max())

    @cached_property
    def cover(self) -> Cover:
        """A mesh's convex pieces (cover.py), read from the cache or built on first use.

        Raises ValueError for the other kinds, which are convex themselves.
        """
        if self.kind != 'mesh':
            raise ValueError(f'a {self.kind} is convex: only meshes have covers')
        return mesh_cover(self.vertices, self.faces)


def signed_distance(shape: Shape, points: np.ndarray) -> np.ndarray:
    """Signed distance (...,) [m] from points (..., 3) in the shape's frame; < 0 inside.

    Exact for sphere, box, cylinder and capsule; meshes have none (they are never
    obstacles, and a mesh link is bounded by its bounding sphere instead).
    """
    p = np.asarray(points, dtype=float)
    if shape.kind == 'sphere':
        return np.linalg.norm(p, axis=-1) - shape.radius
    if shape.kind == 'box':
        return box_signed_distance(p, 0.5 * np.asarray(shape.size))
    if shape.kind == 'cylinder':
        return cylinder_signed_distance(p, shape.radius, shape.length)
    if shape.kind == 'capsule':
        along = np.clip(p[..., 2], -0.5 * shape.length, 0.5 * shape.length)
        offset = p.copy()
        offset[..., 2] -= along
        return np.linalg.norm(offset, axis=-1) - shape.radius
    raise ValueError('signed distances to meshes are not supported')


def box_signed_distance(points: np.ndarray, half_sizes: np.ndarray) -> np.ndarray:
    """Signed distance (...,) [m] from points (..., 3) to boxes of half sizes (..., 3)."""
    return _box_distance(np.abs(points) - half_sizes)


def cylinder_signed_distance(points: np.ndarray, radius, length) -> np.ndarray:
    """Signed distance (...,) [m] from points (..., 3) to z-axis cylinders (radius, length)."""
    q = np.stack([np.hypot(points[..., 0], points[..., 1]) - radius,
                  np.abs(points[..., 2]) - 0.5 * np.asarray(length)], axis=-1)
    return _box_distance(q)


def _box_distance(q: np.ndarray) -> np.ndarray:
    """Signed distance from per-axis excesses q (..., k) over a box's half sizes."""
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
    inside = np.minimum(q.max(axis=-1), 0.0)
    return outside + inside


def support(shape: Shape, rotation: np.ndarray, translation: np.ndarray,
            direction: np.ndarray) -> float:
    """Return max over the shape's points x of direction · x [m], the shape posed in the world.

    `rotation` (3, 3) and `translation` (3,) place the shape; `direction` (3,) is a unit
    vector in the world frame.
    """
    centre = float(translation @ direction)
    local = rotation.T @ direction
    if shape.kind == 'sphere':
        return centre + shape.radius
    if shape.kind == 'box':
        return centre + float(0.5 * np.asarray(shape.size) @ np.abs(local))
    if shape.kind == 'cylinder':
        along = float(local[2])
        return (centre + 0.5 * shape.length * abs(along)
                + shape.radius * float(np.sqrt(max(0.0, 1.0 - along * along))))
    if shape.kind == 'capsule':
        return centre + 0.5 * shape.length * abs(float(local[2])) + shape.radius
    return centre + float(np.max(shape.vertices @ local))


def separation(a: Shape, a_pose: tuple[np.ndarray, np.ndarray], b: Shape,
               b_pose: tuple[np.ndarray, np.ndarray], direction: np.ndarray) -> float:
    """Lower bound [m] on the distance between two posed shapes, along a unit direction a→b.

    min over b of d·y minus max over a of d·x: any two points are at least this far
    apart, whatever the direction (a poor one only loosens the bound; shapes that
    overlap get a bound <= 0).
    """
    return -support(b, *b_pose, -direction) - support(a, *a_pose, direction)


def fcl_geometry(shape: Shape, padding: float = 0.0) -> fcl.CollisionGeometry:
    """Return the python-fcl geometry of a shape; `padding` [m] thickens spheres and capsules.

    fcl needs a positive radius: a capsule of radius 0 (a bare segment) is handed over
    padded, and callers bound distances with the true shape (`separation`). A mesh is
    its triangles (the collision checker measures meshes through their covers instead).
    """
    if shape.kind == 'sphere':
        return fcl.Sphere(max(shape.radius, padding))
    if shape.kind == 'box':
        return fcl.Box(*shape.size)
    if shape.kind == 'cylinder':
        return fcl.Cylinder(shape.radius, shape.length)
    if shape.kind == 'capsule':
        return fcl.Capsule(max(shape.radius, padding), shape.length)
    model = fcl.BVHModel()
    model.beginModel(len(shape.vertices), len(shape.faces))
    model.addSubModel(np.asarray(shape.vertices, dtype=float),
                      np.asarray(shape.faces, dtype=np.int32))
    model.endModel()
    return model


def rotation_from_rpy(rpy) -> np.ndarray:
    """Rotation matrix (3, 3) of fixed-axis roll, pitch, yaw [rad] (R = Rz Ry Rx, as in URDF)."""
    roll, pitch, yaw = rpy
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def transform(rotation: np.ndarray, translation) -> np.ndarray:
    """Return the homogeneous transform (4, 4) of a rotation (3, 3) and translation (3,) [m]."""
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = translation
    return out
