"""Obstacles from /ftplan/obstacles as core obstacles, added to the scene's static ones.

Marker shapes map onto the core's: a SPHERE of scale (d, d, d) is a sphere of radius d/2
(an ellipsoid is bounded by the sphere of its largest diameter), a CUBE is a box of
edges `scale`, and a CYLINDER (axis along its local z) has radius max(sx, sy)/2 and
length sz. Orientations become roll, pitch, yaw [rad].
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence

import numpy as np
from scipy.spatial.transform import Rotation
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py import ObstacleKey, ObstacleShape, read_obstacle_markers
from ftplan_ros.core import CollisionChecker, Obstacle, Scene

# Fixed-axis x, y, z ('xyz' in scipy, lower case: extrinsic): R = Rz Ry Rx, as in URDF.
_RPY_AXES = 'xyz'
_MAX_WAITING = 100  # marker arrays kept until there is a robot


def rpy_from_quaternion(q: np.ndarray) -> tuple[float, float, float]:
    """Return roll, pitch, yaw [rad] (R = Rz Ry Rx) of the unit quaternion (x, y, z, w)."""
    return tuple(float(v) for v in Rotation.from_quat(q).as_euler(_RPY_AXES))


def quaternion_from_rpy(rpy) -> np.ndarray:
    """Return the unit quaternion (x, y, z, w) of roll, pitch, yaw [rad] (R = Rz Ry Rx)."""
    return Rotation.from_euler(_RPY_AXES, rpy).as_quat()


def obstacle_from_shape(shape: ObstacleShape) -> Obstacle:
    """Return the core obstacle of a marker shape (scale and centre in metres)."""
    center = tuple(float(v) for v in shape.center)
    sx, sy, sz = (float(v) for v in shape.scale)
    rpy = rpy_from_quaternion(shape.orientation)
    if shape.shape == 'sphere':
        return Obstacle('sphere', center, radius=0.5 * max(sx, sy, sz))
    if shape.shape == 'box':
        return Obstacle('box', center, size=(sx, sy, sz), rpy=rpy)
    return Obstacle('cylinder', center, radius=0.5 * max(sx, sy), length=sz, rpy=rpy)


def shape_from_obstacle(key: ObstacleKey, obstacle: Obstacle) -> ObstacleShape:
    """Return the marker shape of a core obstacle, keyed `key` (ns, id)."""
    if obstacle.shape == 'sphere':
        scale = np.full(3, 2.0 * obstacle.radius)
    elif obstacle.shape == 'box':
        scale = np.array(obstacle.size, dtype=float)
    else:
        scale = np.array([2.0 * obstacle.radius, 2.0 * obstacle.radius, obstacle.length])
    return ObstacleShape(key, obstacle.shape, np.array(obstacle.center, dtype=float), scale,
                         quaternion_from_rpy(obstacle.rpy))


def obstacle_set_key(obstacles: Sequence[Obstacle]) -> str:
    """Name a set of obstacles (in order) by a digest of every number: 12 hex digits.

    The planner's plan status carries it, so that a client can tell which obstacles a plan
    was made for (the load benchmark checks each plan against them).
    """
    text = repr([(o.shape, tuple(map(float, o.center)), float(o.radius),
                  tuple(map(float, o.size)), float(o.length), tuple(map(float, o.rpy)))
                 for o in obstacles])
    return hashlib.sha1(text.encode(), usedforsecurity=False).hexdigest()[:12]


def is_full_set(msg: MarkerArray) -> bool:
    """Whether a MarkerArray replaces the whole set: it holds a DELETEALL (normally first)."""
    return any(marker.action == Marker.DELETEALL for marker in msg.markers)


class ObstacleSet:
    """The obstacles received on /ftplan/obstacles, keyed (ns, id) as RViz keys markers.

    They add to the static obstacles of a base scene; `checker` checks against both.
    Without a base scene yet (a robot to come from /robot_description) the marker arrays
    wait, in order, and are applied when `rebase` gives one.

    Updates must all be applied, in order: `lost` says why the set is not the one
    published when some were not received or were refused ('' when it is). It is set by
    an update that comes after lost ones (`update`'s `lost`) or by one refused, and
    cleared by a full set (`is_full_set`) applied after them.
    """

    def __init__(self, base: Scene | None):
        self.base = base
        self.shapes: Mapping[ObstacleKey, ObstacleShape] = {}
        self.obstacles: tuple[Obstacle, ...] = ()
        self.lost = ''
        self._waiting: list[tuple[MarkerArray, str]] = []
        self._checker: tuple[Scene, tuple[Obstacle, ...], CollisionChecker] | None = None

    @property
    def checker(self) -> CollisionChecker | None:
        """The checker of the base scene with these obstacles (None without a base scene).

        Built when first asked for after a change, so that a burst of updates costs one
        build, not one per update; kept with the base and obstacles it was built for, so
        that a build that an update overtook is not taken for the new set.
        """
        base, obstacles = self.base, self.obstacles
        if base is None:
            return None
        built = self._checker
        if built is None or built[0] is not base or built[1] is not obstacles:
            scene = _with_obstacles(base, obstacles)
            built = self._checker = (base, obstacles,
                                     CollisionChecker(scene.robot, scene.obstacles))
        return built[2]

    def update(self, msg: MarkerArray, lost: str = '') -> None:
        """Apply a MarkerArray (ADD, DELETE, DELETEALL); all or nothing.

        :param lost: why updates before this one were lost ('' when none were).
        :raises ValueError: on a malformed marker; the set's obstacles are then left as
            they were, and `lost` says it is not the set published.
        """
        if self.base is None:
            self._wait(msg, lost)
            return
        self._apply(msg, lost)

    def _wait(self, msg: MarkerArray, lost: str) -> None:
        self._waiting.append((msg, lost))
        if len(self._waiting) > _MAX_WAITING:
            del self._waiting[0]
            first, first_lost = self._waiting[0]
            self._waiting[0] = (first, first_lost or f'obstacle updates were lost (more than '
                                f'{_MAX_WAITING} arrived before the robot: the oldest were '
                                'dropped)')

    def _apply(self, msg: MarkerArray, lost: str) -> None:
        self.lost = lost or self.lost
        try:
            shapes = read_obstacle_markers(msg, self.base.frame_id, self.shapes)
            obstacles = tuple(obstacle_from_shape(shapes[key]) for key in sorted(shapes))
        except ValueError as error:
            refused = f'an obstacle update was refused ({error})'
            self.lost = f'{self.lost}; {refused}' if self.lost else refused
            raise
        self.shapes, self.obstacles = shapes, obstacles
        if is_full_set(msg):
            self.lost = ''

    def rebase(self, base: Scene) -> list[str]:
        """Add the obstacles to a new base scene (a new robot).

        Returns the problems of the marker arrays that waited for it (left out).
        """
        self.base = base
        waiting, self._waiting = self._waiting, []
        problems = []
        for msg, lost in waiting:
            try:
                self._apply(msg, lost)
            except ValueError as error:
                problems.append(str(error))
        return problems

    @property
    def pending(self) -> int:
        """Marker arrays waiting for a base scene."""
        return len(self._waiting)

    def scene(self) -> Scene | None:
        """Return the base scene with these obstacles added to its static ones."""
        if self.base is None:
            return None
        return _with_obstacles(self.base, self.obstacles)

    def __len__(self) -> int:
        return len(self.obstacles)


def _with_obstacles(base: Scene, obstacles: tuple[Obstacle, ...]) -> Scene:
    """Return `base` with `obstacles` added to its static ones (`base` itself for none)."""
    return base.with_obstacles(obstacles) if obstacles else base
