"""Scenes: the robot, its static obstacles and the task, loaded from YAML and validated.

The format is the one in CONTRACT.md (`robot`, `obstacles`, `task`); every value is
checked and a bad one raises `InputError` naming its field, e.g. `obstacles[2].radius`.
Units are metres and radians.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from .errors import InputError
from .robot import PlanarChain

OBSTACLE_TYPES = ('sphere', 'box', 'cylinder')
# [m or rad] Largest magnitude of any number: the clearance bounds allow for float rounding
# of about 1e-6 m, which holds for coordinates up to here (and a scene is not bigger).
LARGEST_NUMBER = 1.0e6


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


@dataclass(frozen=True)
class Task:
    """Move the end effector from `start` to `goal` [m], arriving within `goal_tolerance` [m]."""

    start: tuple[float, ...]
    goal: tuple[float, ...]
    goal_tolerance: float = 0.01


@dataclass(frozen=True)
class Scene:
    """A robot among obstacles, with an optional task."""

    robot: PlanarChain
    obstacles: tuple[Obstacle, ...] = ()
    task: Task | None = None
    frame_id: str = 'base_link'
    name: str = field(default='scene', compare=False)

    def with_obstacles(self, obstacles: Sequence[Obstacle]) -> Scene:
        """Return this scene with `obstacles` added to its static ones."""
        return Scene(self.robot, self.obstacles + tuple(obstacles), self.task,
                     self.frame_id, self.name)

    def with_task(self, task: Task) -> Scene:
        """Return this scene with its task replaced."""
        return Scene(self.robot, self.obstacles, task, self.frame_id, self.name)


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene YAML file."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise InputError(str(path), f'cannot read scene file ({error.strerror})') from None
    except UnicodeDecodeError:
        raise InputError(str(path), 'is not UTF-8 text') from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, 'problem_mark', None)
        where = f' at line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        problem = getattr(error, 'problem', None) or 'malformed YAML'
        raise InputError(str(path), f'malformed YAML{where}: {problem}') from None
    return parse_scene(data, name=path.stem, directory=path.parent)


def parse_scene(data: Any, name: str = 'scene', directory: Path | None = None) -> Scene:
    """Validate a scene given as plain data (what `yaml.safe_load` returns).

    `robot` is a mapping, or the path of a robot YAML file (holding one `robot` mapping)
    relative to `directory`, the scene file's folder.
    """
    data = _mapping(data, 'scene')
    _check_keys(data, 'scene', required=('robot',), optional=('obstacles', 'task', 'frame_id'))
    robot_data = data['robot']
    if isinstance(robot_data, str):
        robot_data = _robot_file(Path(directory or '.') / robot_data)
    robot = parse_robot(robot_data)
    frame_id = data.get('frame_id', 'base_link')
    if not isinstance(frame_id, str) or not frame_id:
        raise InputError('frame_id', 'must be a non-empty string')
    obstacles = tuple(
        parse_obstacle(item, f'obstacles[{k}]')
        for k, item in enumerate(_sequence(data.get('obstacles') or [], 'obstacles')))
    task = None if data.get('task') is None else parse_task(data['task'], robot)
    return Scene(robot, obstacles, task, frame_id, name)


def _robot_file(path: Path) -> Any:
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        raise InputError('robot', f'cannot read robot file {path.name}: {error}') from None
    data = _mapping(data, f'robot file {path.name}')
    _check_keys(data, f'robot file {path.name}', required=('robot',), optional=())
    return data['robot']


def parse_robot(data: Any) -> PlanarChain:
    """Validate the `robot` section; only `type: planar` is implemented so far."""
    data = _mapping(data, 'robot')
    kind = data.get('type')
    if kind in ('dh', 'urdf'):
        raise InputError('robot.type', f'"{kind}" robots are not supported yet; use "planar"')
    if kind != 'planar':
        raise InputError('robot.type', f'must be "planar", got {kind!r}')
    _check_keys(data, 'robot', required=('type', 'link_lengths'),
                optional=('link_radius', 'joint_names', 'joint_limits'))
    lengths = _vector(data['link_lengths'], 'robot.link_lengths')
    if not lengths:
        raise InputError('robot.link_lengths', 'needs at least one link')
    for k, value in enumerate(lengths):
        if value <= 0.0:
            raise InputError(f'robot.link_lengths[{k}]', f'must be > 0, got {value}')
    radius = _number(data.get('link_radius', 0.0), 'robot.link_radius')
    if radius < 0.0:
        raise InputError('robot.link_radius', f'must be >= 0, got {radius}')
    n = len(lengths)
    names = data.get('joint_names')
    names = [f'joint{k + 1}' for k in range(n)] if names is None else names
    names = _sequence(names, 'robot.joint_names')
    if len(names) != n:
        raise InputError('robot.joint_names', f'has {len(names)} names for {n} joints')
    for k, joint in enumerate(names):
        if not isinstance(joint, str) or not joint:
            raise InputError(f'robot.joint_names[{k}]', 'must be a non-empty string')
    if len(set(names)) != n:
        raise InputError('robot.joint_names', 'names must be unique')
    limits = data.get('joint_limits')
    if limits is not None:
        limits = _sequence(limits, 'robot.joint_limits')
        if len(limits) != n:
            raise InputError('robot.joint_limits', f'has {len(limits)} entries for {n} joints')
        limits = tuple(_joint_limit(item, f'robot.joint_limits[{k}]')
                       for k, item in enumerate(limits))
    return PlanarChain(tuple(lengths), tuple(names), radius, limits)


def parse_obstacle(data: Any, where: str) -> Obstacle:
    """Validate one obstacle mapping; `where` names it in errors (e.g. `obstacles[0]`)."""
    data = _mapping(data, where)
    shape = data.get('type')
    if shape not in OBSTACLE_TYPES:
        raise InputError(f'{where}.type', f'must be one of {", ".join(OBSTACLE_TYPES)}, '
                         f'got {shape!r}')
    per_shape = {'sphere': ('radius',), 'box': ('size', 'rpy'),
                 'cylinder': ('radius', 'length', 'rpy')}
    required = {'sphere': ('radius',), 'box': ('size',), 'cylinder': ('radius',)}[shape]
    _check_keys(data, where, required=('type', 'center') + required,
                optional=tuple(k for k in per_shape[shape] if k not in required))
    center = _point3(data['center'], f'{where}.center')
    rpy = tuple(_vector(data.get('rpy', [0.0, 0.0, 0.0]), f'{where}.rpy', length=3))
    if shape == 'box':
        size = _vector(data['size'], f'{where}.size')
        if len(size) not in (2, 3):
            raise InputError(f'{where}.size', f'needs 2 or 3 values, got {len(size)}')
        size = size + [1.0] * (3 - len(size))  # planar boxes get a unit height
        for k, value in enumerate(size):
            if value <= 0.0:
                raise InputError(f'{where}.size[{k}]', f'must be > 0, got {value}')
        return Obstacle('box', center, size=tuple(size), rpy=rpy)
    radius = _number(data['radius'], f'{where}.radius')
    if radius <= 0.0:
        raise InputError(f'{where}.radius', f'must be > 0, got {radius}')
    if shape == 'sphere':
        return Obstacle('sphere', center, radius=radius)
    length = _number(data.get('length', 1.0), f'{where}.length')
    if length <= 0.0:
        raise InputError(f'{where}.length', f'must be > 0, got {length}')
    return Obstacle('cylinder', center, radius=radius, length=length, rpy=rpy)


def parse_task(data: Any, robot: PlanarChain) -> Task:
    """Validate the `task` section against the robot's workspace dimension m."""
    data = _mapping(data, 'task')
    _check_keys(data, 'task', required=('start', 'goal'), optional=('goal_tolerance',))
    start = _vector(data['start'], 'task.start', length=robot.task_dim)
    goal = _vector(data['goal'], 'task.goal', length=robot.task_dim)
    tolerance = _number(data.get('goal_tolerance', 0.01), 'task.goal_tolerance')
    if tolerance <= 0.0:
        raise InputError('task.goal_tolerance', f'must be > 0, got {tolerance}')
    return Task(tuple(start), tuple(goal), tolerance)


def scene_to_dict(scene: Scene) -> dict:
    """Return the scene as plain data in the YAML format `parse_scene` reads."""
    robot = scene.robot
    out: dict[str, Any] = {
        'robot': {'type': 'planar', 'link_lengths': list(robot.link_lengths),
                  'link_radius': robot.link_radius, 'joint_names': list(robot.joint_names),
                  'joint_limits': None if robot.joint_limits is None
                  else [None if lim is None else list(lim) for lim in robot.joint_limits]},
        'obstacles': [_obstacle_to_dict(ob) for ob in scene.obstacles],
    }
    if scene.frame_id != 'base_link':
        out['frame_id'] = scene.frame_id
    if scene.task is not None:
        out['task'] = {'start': list(scene.task.start), 'goal': list(scene.task.goal),
                       'goal_tolerance': scene.task.goal_tolerance}
    return out


def _obstacle_to_dict(obstacle: Obstacle) -> dict:
    out: dict[str, Any] = {'type': obstacle.shape, 'center': list(obstacle.center)}
    if obstacle.shape in ('sphere', 'cylinder'):
        out['radius'] = obstacle.radius
    if obstacle.shape == 'cylinder':
        out['length'] = obstacle.length
    if obstacle.shape == 'box':
        out['size'] = list(obstacle.size)
    if obstacle.shape != 'sphere' and any(obstacle.rpy):
        out['rpy'] = list(obstacle.rpy)
    return out


def _joint_limit(data: Any, where: str) -> tuple[float, float] | None:
    if data is None:
        return None
    low, high = _vector(data, where, length=2)
    if not low < high:
        raise InputError(where, f'lower limit {low} must be below upper limit {high}')
    return (low, high)


def _mapping(data: Any, where: str) -> Mapping:
    if not isinstance(data, Mapping):
        raise InputError(where, f'must be a mapping, got {type(data).__name__}')
    return data


def _sequence(data: Any, where: str) -> list:
    if isinstance(data, (str, bytes)) or not isinstance(data, Sequence):
        raise InputError(where, f'must be a list, got {type(data).__name__}')
    return list(data)


def _check_keys(data: Mapping, where: str, required: tuple, optional: tuple) -> None:
    for key in data:
        if key not in required and key not in optional:
            allowed = ', '.join(required + optional)
            raise InputError(f'{where}.{key}', f'unknown key (allowed: {allowed})')
    for key in required:
        if key not in data:
            raise InputError(f'{where}.{key}', 'is missing')


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(where, f'must be a number, got {value!r}')
    try:
        value = float(value)
    except OverflowError:
        value = math.inf
    if not math.isfinite(value):
        raise InputError(where, f'must be finite, got {value}')
    if abs(value) > LARGEST_NUMBER:
        raise InputError(where, f'must be within ±{LARGEST_NUMBER:g}, got {value:g}')
    return value


def _vector(data: Any, where: str, length: int | None = None) -> list[float]:
    items = _sequence(data, where)
    if length is not None and len(items) != length:
        raise InputError(where, f'needs {length} values, got {len(items)}')
    return [_number(item, f'{where}[{k}]') for k, item in enumerate(items)]


def _point3(data: Any, where: str) -> tuple[float, float, float]:
    values = _vector(data, where)
    if len(values) not in (2, 3):
        raise InputError(where, f'needs 2 or 3 values, got {len(values)}')
    return tuple(values + [0.0] * (3 - len(values)))
