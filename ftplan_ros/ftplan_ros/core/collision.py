"""Batched clearance between the arm's link capsules and the scene's obstacles.

Obstacles and links are python-fcl objects, built once and moved with `setTransform`,
which handles every shape. When every obstacle is a sphere (the paper's disks), a
vectorised segment-to-point distance gives the same numbers for thousands of
configurations in one numpy call; the tests hold the two backends to each other.
Self-collision is not checked (the paper's arm folds onto itself).
"""

from __future__ import annotations

from collections.abc import Sequence

import fcl
import numpy as np

from .robot import Robot
from .scene import Obstacle

_CHUNK = 4096  # configurations per numpy batch: bounds the (N, L, P, 3) temporaries
_FCL_PADDED_RADIUS = 1e-2  # [m] thinnest link capsule handed to fcl


class CollisionChecker:
    """Clearance [m] of each link capsule: how far it is from the nearest obstacle.

    A touching or penetrating link gets a clearance <= 0 (the numpy backend: minus the
    depth; the fcl backend: 0, also for links within 1 cm of an obstacle).
    """

    def __init__(self, robot: Robot, obstacles: Sequence[Obstacle], backend: str = 'auto'):
        """Build the obstacle objects; `backend` is 'auto', 'numpy' (spheres only) or 'fcl'."""
        self.robot = robot
        self.obstacles = tuple(obstacles)
        all_spheres = all(ob.shape == 'sphere' for ob in self.obstacles)
        if backend == 'auto':
            backend = 'numpy' if all_spheres else 'fcl'
        if backend == 'numpy' and not all_spheres:
            raise ValueError('the numpy backend handles sphere obstacles only; use "fcl"')
        if backend not in ('numpy', 'fcl'):
            raise ValueError(f'unknown collision backend {backend!r}')
        self.backend = backend
        self.checks = 0  # configurations whose clearance was computed
        self._centers = np.array([ob.center for ob in self.obstacles], dtype=float).reshape(-1, 3)
        self._radii = np.array([ob.radius for ob in self.obstacles], dtype=float)
        self._fcl_scene: _FclScene | None = None

    def clearance(self, thetas: np.ndarray) -> np.ndarray:
        """Return per-link clearance (N, L) [m] of configurations (N, n) [rad]."""
        thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
        self.checks += len(thetas)
        n_links = self.robot.link_segments(thetas[:1]).shape[-3]
        if not self.obstacles:
            return np.full((len(thetas), n_links), np.inf)
        if self.backend == 'numpy':
            return np.concatenate([self._sphere_clearance(thetas[k:k + _CHUNK])
                                   for k in range(0, len(thetas), _CHUNK)])
        if self._fcl_scene is None:
            self._fcl_scene = _FclScene(self.robot, self.obstacles)
        return self._fcl_scene.clearance(self.robot.link_segments(thetas))

    def min_clearance(self, thetas: np.ndarray) -> np.ndarray:
        """Smallest clearance (N,) [m] over all links of configurations (N, n) [rad]."""
        return self.clearance(thetas).min(axis=1)

    def _sphere_clearance(self, thetas: np.ndarray) -> np.ndarray:
        # Distance from centre c to segment a + t d, t in [0, 1], expanded into dot
        # products so no (N, L, P, 3) temporaries are built: |c - a - t d|^2 =
        # |c - a|^2 - 2 t (c - a)·d + t^2 |d|^2. Rounding is far below _ROUNDING in
        # verification.py.
        segments = self.robot.link_segments(thetas)  # (N, L, 2, 3)
        start = segments[:, :, 0, :]
        direction = segments[:, :, 1, :] - start
        length2 = np.maximum(np.einsum('nlk,nlk->nl', direction, direction), 1e-300)
        along = (np.einsum('nlk,pk->nlp', direction, self._centers)
                 - np.einsum('nlk,nlk->nl', start, direction)[..., None])
        offset2 = (np.einsum('pk,pk->p', self._centers, self._centers)
                   - 2.0 * np.einsum('nlk,pk->nlp', start, self._centers)
                   + np.einsum('nlk,nlk->nl', start, start)[..., None])
        t = np.clip(along / length2[..., None], 0.0, 1.0)
        gap2 = np.maximum(offset2 - 2.0 * t * along + t * t * length2[..., None], 0.0)
        distance = np.sqrt(gap2) - self._radii - self.robot.link_radius
        return distance.min(axis=-1)


class _FclScene:
    """fcl objects for the obstacles and one capsule per link, moved for every query.

    python-fcl's distances between thin capsules and boxes can be centimetres too long
    (GJK stops early), so fcl is only trusted for the direction: the clearance returned
    is the separation of the link and the obstacle along the line joining fcl's nearest
    points, from their support functions. That is a lower bound on the true distance
    for any direction, and a tight one when fcl is right (links get a 1 cm padded capsule
    and the INDEP solver, with which it is, to 0.2 mm in the tests).
    """

    def __init__(self, robot: Robot, obstacles: Sequence[Obstacle]):
        self.obstacles = list(obstacles)
        self.fcl_obstacles = [_fcl_obstacle(ob) for ob in obstacles]
        segments = robot.link_segments(np.zeros(robot.n_joints))
        lengths = np.linalg.norm(segments[:, 1] - segments[:, 0], axis=-1)
        self.radius = robot.link_radius
        self.padded = max(robot.link_radius, _FCL_PADDED_RADIUS)
        self.links = [fcl.CollisionObject(fcl.Capsule(self.padded, float(length)))
                      for length in lengths]

    def clearance(self, segments: np.ndarray) -> np.ndarray:
        out = np.empty(segments.shape[:2])
        for k, config in enumerate(segments):
            for j, (start, end) in enumerate(config):
                axis = end - start
                self.links[j].setTransform(fcl.Transform(
                    _rotation_from_z(axis / max(float(np.linalg.norm(axis)), 1e-300)),
                    0.5 * (start + end)))
                out[k, j] = min(
                    certified_distance(self.links[j], start, end, self.radius, ob, fcl_ob,
                                       self.padded - self.radius)
                    for ob, fcl_ob in zip(self.obstacles, self.fcl_obstacles, strict=True))
        return out


def certified_distance(link: fcl.CollisionObject, start: np.ndarray, end: np.ndarray,
                       radius: float, obstacle: Obstacle, fcl_obstacle: fcl.CollisionObject,
                       padding: float) -> float:
    """Bound [m] from below the distance between a capsule and an obstacle; 0 on contact.

    `link` is the fcl capsule around the segment start-end (3,) [m], `padding` [m] thicker
    than the true `radius`. When the padded capsule touches the obstacle the answer is 0:
    the true clearance is then at most `padding`, and any penetration depth is unknown
    (fcl's signed-distance query never returns for concentric shapes and takes 0.2 s for a
    cylinder, and no caller needs the depth: clearance <= 0 means not free).
    """
    request = fcl.DistanceRequest(enable_nearest_points=True,
                                  gjk_solver_type=fcl.GJKSolverType.GST_INDEP)
    result = fcl.DistanceResult()
    if fcl.distance(link, fcl_obstacle, request, result) <= 0.0:
        return 0.0
    near_link, near_obstacle = (np.asarray(p, dtype=float) for p in result.nearest_points)
    direction = near_obstacle - near_link
    norm = float(np.linalg.norm(direction))
    if norm == 0.0:
        return 0.0
    direction /= norm
    farthest_link = max(float(start @ direction), float(end @ direction)) + radius
    return _nearest_support(obstacle, direction) - farthest_link


def _nearest_support(obstacle: Obstacle, direction: np.ndarray) -> float:
    """Return the minimum over the obstacle's points x of direction · x [m] (unit direction)."""
    center = float(np.asarray(obstacle.center) @ direction)
    if obstacle.shape == 'sphere':
        return center - obstacle.radius
    axes = rotation_from_rpy(obstacle.rpy).T @ direction  # direction in the obstacle's frame
    if obstacle.shape == 'box':
        return center - float(np.sum(0.5 * np.asarray(obstacle.size) * np.abs(axes)))
    along = float(axes[2])  # cylinder: axis is local z
    return (center - 0.5 * obstacle.length * abs(along)
            - obstacle.radius * float(np.sqrt(max(0.0, 1.0 - along * along))))


def point_clearance(obstacles: Sequence[Obstacle], point: np.ndarray) -> np.ndarray:
    """Distance (P,) [m] from a point (3,) to each obstacle, 0 inside.

    Exact for spheres; for other shapes a lower bound from fcl, 0 within about 1 cm.
    """
    point = np.asarray(point, dtype=float)
    probe = fcl.CollisionObject(fcl.Capsule(_FCL_PADDED_RADIUS, 1e-6), fcl.Transform(point))
    return np.array([
        max(0.0, float(np.linalg.norm(point - np.asarray(ob.center))) - ob.radius)
        if ob.shape == 'sphere' else
        certified_distance(probe, point, point, 0.0, ob, _fcl_obstacle(ob), _FCL_PADDED_RADIUS)
        for ob in obstacles])


def _fcl_obstacle(obstacle: Obstacle) -> fcl.CollisionObject:
    if obstacle.shape == 'sphere':
        geometry = fcl.Sphere(obstacle.radius)
    elif obstacle.shape == 'box':
        geometry = fcl.Box(*obstacle.size)
    else:
        geometry = fcl.Cylinder(obstacle.radius, obstacle.length)
    return fcl.CollisionObject(geometry, fcl.Transform(rotation_from_rpy(obstacle.rpy),
                                                       np.asarray(obstacle.center, dtype=float)))


def rotation_from_rpy(rpy: Sequence[float]) -> np.ndarray:
    """Rotation matrix (3, 3) of fixed-axis roll, pitch, yaw [rad] (R = Rz Ry Rx, as in URDF)."""
    roll, pitch, yaw = rpy
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _rotation_from_z(axis: np.ndarray) -> np.ndarray:
    """Return a rotation (3, 3) that takes the z axis onto the unit vector `axis`."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, axis)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])
