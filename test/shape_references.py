"""Independent references for distances, written without the core's geometry code.

Signed distances of obstacles by closest points, shapes' surfaces sampled densely, and
random link shapes and poses to measure them on (collision/ and model/geometry.py tests).
"""

import numpy as np
from ftplan_testing import CUBE, TETRAHEDRON
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from ftplan_ros.core.model.geometry import Shape, transform

SPACING = 0.002  # [m] between surface samples: sampled distances exceed the truth by less


def obstacle_frame(obstacle):
    """Rotation (3, 3) of an obstacle: fixed-axis roll, pitch, yaw (scipy's 'xyz')."""
    return Rotation.from_euler('xyz', obstacle.rpy).as_matrix()


def distance_to_obstacle(obstacle, points):
    """Signed distance (P,) [m] from world points (P, 3) to an obstacle, by closest points."""
    local = (np.asarray(points, dtype=float) - obstacle.center) @ obstacle_frame(obstacle)
    if obstacle.shape == 'sphere':
        return np.linalg.norm(local, axis=1) - obstacle.radius
    if obstacle.shape == 'box':
        half = 0.5 * np.asarray(obstacle.size)
        closest = np.clip(local, -half, half)
        outside = np.linalg.norm(local - closest, axis=1)
        depth = np.min(half - np.abs(local), axis=1)
        return np.where(depth > 0.0, -depth, outside)
    radial = np.hypot(local[:, 0], local[:, 1])
    half = 0.5 * obstacle.length
    out_r = np.maximum(radial - obstacle.radius, 0.0)
    out_z = np.maximum(np.abs(local[:, 2]) - half, 0.0)
    depth = np.minimum(obstacle.radius - radial, half - np.abs(local[:, 2]))
    return np.where(depth > 0.0, -depth, np.hypot(out_r, out_z))


def grid(low, high, spacing):
    return np.linspace(low, high, max(2, int(np.ceil((high - low) / spacing)) + 1))


def fibonacci_sphere(radius, spacing):
    count = max(8, int(np.ceil(4.0 * np.pi * radius ** 2 / spacing ** 2)))
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    angle = np.pi * (1.0 + 5 ** 0.5) * k
    r = np.sqrt(1.0 - z * z)
    return radius * np.stack([r * np.cos(angle), r * np.sin(angle), z], axis=1)


def disk(radius, z, spacing):
    rings = [np.array([[0.0, 0.0, z]])]
    for rho in grid(0.0, radius, spacing)[1:]:
        phi = np.linspace(0.0, 2 * np.pi, max(8, int(np.ceil(2 * np.pi * rho / spacing))),
                          endpoint=False)
        rings.append(np.stack([rho * np.cos(phi), rho * np.sin(phi), np.full_like(phi, z)], 1))
    return np.vstack(rings)


def surface_points(shape, spacing=SPACING):
    """Points (P, 3) on a shape's surface, in its frame, at most about `spacing` apart."""
    if shape.kind == 'sphere':
        return fibonacci_sphere(shape.radius, spacing)
    if shape.kind == 'box':
        half = 0.5 * np.asarray(shape.size)
        faces = []
        for axis in range(3):
            u, v = (a for a in range(3) if a != axis)
            uu, vv = np.meshgrid(grid(-half[u], half[u], spacing), grid(-half[v], half[v], spacing))
            for side in (-1.0, 1.0):
                face = np.zeros((uu.size, 3))
                face[:, u], face[:, v], face[:, axis] = uu.ravel(), vv.ravel(), side * half[axis]
                faces.append(face)
        return np.vstack(faces)
    if shape.kind in ('cylinder', 'capsule'):
        half = 0.5 * shape.length
        phi = np.linspace(0.0, 2 * np.pi, max(8, int(np.ceil(2 * np.pi * shape.radius / spacing))),
                          endpoint=False)
        pp, zz = np.meshgrid(phi, grid(-half, half, spacing))
        side = np.stack([shape.radius * np.cos(pp).ravel(), shape.radius * np.sin(pp).ravel(),
                         zz.ravel()], axis=1)
        if shape.kind == 'cylinder':
            return np.vstack([side, disk(shape.radius, -half, spacing),
                              disk(shape.radius, half, spacing)])
        ball = fibonacci_sphere(shape.radius, spacing)
        return np.vstack([side, ball[ball[:, 2] >= 0] + [0, 0, half],
                          ball[ball[:, 2] <= 0] - [0, 0, half]])
    pieces = []
    for face in shape.faces:
        a, b, c = shape.vertices[face]
        steps = max(1, int(np.ceil(max(np.linalg.norm(b - a), np.linalg.norm(c - a)) / spacing)))
        s, t = np.meshgrid(np.arange(steps + 1), np.arange(steps + 1))
        inside = s + t <= steps
        s, t = s[inside] / steps, t[inside] / steps
        pieces.append(a + np.outer(s, b - a) + np.outer(t, c - a))
    return np.vstack(pieces)


def posed(points, pose):
    return points @ pose[:3, :3].T + pose[:3, 3]


def closest(first, second):
    """Smallest distance [m] between two point sets (P, 3) and (Q, 3)."""
    return float(cKDTree(second).query(first)[0].min())


def random_pose(rng, spread=0.1):
    return transform(Rotation.random(random_state=rng.integers(1 << 31)).as_matrix(),
                     rng.uniform(-spread, spread, 3))


def random_link_shape(kind, rng):
    if kind == 'box':
        return Shape('box', size=tuple(rng.uniform(0.05, 0.3, 3)))
    if kind in ('cylinder', 'capsule'):
        return Shape(kind, radius=rng.uniform(0.02, 0.1), length=rng.uniform(0.05, 0.4))
    if kind == 'sphere':
        return Shape('sphere', radius=rng.uniform(0.02, 0.15))
    vertices, faces = {'cube': CUBE, 'tetrahedron': TETRAHEDRON}[kind]
    return Shape('mesh', vertices=vertices * rng.uniform(1.0, 2.0), faces=faces)
