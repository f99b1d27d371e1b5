"""Scenes as data: obstacles, tasks and the scene that holds them with the robot.

The types every layer above the model shares; reading them from YAML lives in
`core/io/scene_file.py`. Units are metres and radians; the task's form says its kind
(`task_space.py`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import InputError
from ..validation import LARGEST_NUMBER
from .robot import Robot
from .spatial import SpatialArm
from .task_space import kind_of_point

OBSTACLE_TYPES = ('sphere', 'box', 'cylinder')




@dataclass(frozen=True)
class Obstacle:
    """A static obstacle in the base frame.

    `center` [m] is 3-D (planar scenes give x, y and get z = 0); `rpy` [rad] orients boxes
    and cylinders (a cylinder's axis is its local z). Spheres use `radius`; boxes use `size`
    (full edge lengths); cylinders use `radius` and `length`.
    """

    shape: str
    center: tuple[float, float, float]
    radius: float = 0.0
    size: tuple[float, float, float] = (0.0, 0.0, 0.0)
    length: float = 0.0
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self):
        """Refuse what no clearance bound can hold: whatever the source (a file, a marker).

        Every number must be finite and within ±LARGEST_NUMBER, and the dimensions the
        shape uses positive: a sphere of radius 1e200 would overflow the distances to +inf
        and read as far away.
        """
        if self.shape not in OBSTACLE_TYPES:
            raise InputError('obstacle.type', f'must be one of {", ".join(OBSTACLE_TYPES)}, '
                             f'got {self.shape!r}')
        for name in ('center', 'radius', 'size', 'length', 'rpy'):
            values = np.atleast_1d(np.asarray(getattr(self, name), dtype=float))
            if not (np.all(np.isfinite(values)) and np.all(np.abs(values) <= LARGEST_NUMBER)):
                raise InputError(f'obstacle.{name}', f'must be finite and within '
                                 f'±{LARGEST_NUMBER:g}, got {getattr(self, name)}')
        used = {'sphere': ('radius',), 'box': ('size',), 'cylinder': ('radius', 'length')}
        for name in used[self.shape]:
            if not np.all(np.asarray(getattr(self, name), dtype=float) > 0.0):
                raise InputError(f'obstacle.{name}', f'must be > 0, got {getattr(self, name)}')


DEFAULT_GOAL_TOLERANCE = 0.01  # [m]
DEFAULT_ORIENTATION_TOLERANCE = 0.01  # [rad]


@dataclass(frozen=True)
class Task:
    """Move the tool from task point `start` to `goal` (task_space.py).

    It must arrive within `goal_tolerance` [m] of the goal's position and
    `orientation_tolerance` [rad] of its orientation or axis (pose and axis tasks).
    """

    start: tuple[float, ...]
    goal: tuple[float, ...]
    goal_tolerance: float = DEFAULT_GOAL_TOLERANCE
    orientation_tolerance: float = DEFAULT_ORIENTATION_TOLERANCE

    @property
    def kind(self) -> str:
        """'planar', 'position', 'axis' or 'pose', from the size of the task points."""
        return kind_of_point(self.goal)

    def reached(self, errors: np.ndarray) -> np.ndarray:
        """Whether task errors (..., 2) [m, rad] (`robot.task_errors`) are within tolerance."""
        errors = np.asarray(errors, dtype=float)
        return ((errors[..., 0] <= self.goal_tolerance)
                & (errors[..., 1] <= self.orientation_tolerance))


@dataclass(frozen=True)
class Scene:
    """A robot among obstacles, with an optional task.

    `tolerate` names the joints whose lock a plan must survive (None: all of them).
    """

    robot: Robot
    obstacles: tuple[Obstacle, ...] = ()
    task: Task | None = None
    frame_id: str = 'base_link'
    name: str = field(default='scene', compare=False)
    tolerate: tuple[str, ...] | None = None

    def with_obstacles(self, obstacles: Sequence[Obstacle]) -> Scene:
        """Return this scene with `obstacles` added to its static ones."""
        return replace(self, obstacles=self.obstacles + tuple(obstacles))

    def with_task(self, task: Task | None) -> Scene:
        """Return this scene with its task replaced (a spatial arm takes up its kind)."""
        robot = self.robot
        if task is not None and isinstance(robot, SpatialArm):
            robot = robot.with_task_kind(task.kind)
        return replace(self, robot=robot, task=task)

    def with_tolerated(self, joints: Sequence[str] | None) -> Scene:
        """Return this scene tolerating the locks of `joints` (None: all)."""
        return replace(self, tolerate=None if joints is None else tuple(joints))

    @property
    def tolerated_joints(self) -> tuple[int, ...]:
        """Indices of the joints whose lock the plan must survive."""
        names = self.robot.joint_names
        if self.tolerate is None:
            return tuple(range(len(names)))
        return tuple(names.index(name) for name in self.tolerate)
