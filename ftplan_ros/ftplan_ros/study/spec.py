"""Study specs: what a study plans, read from YAML, validated, and enumerated task by task.

A spec names a base scene (robot, obstacles, task defaults; a path relative to the spec
file) and what varies (CONTRACT.md, *Studies*):

    scene: ../scenes/fig3a.yaml
    vary:                          # exactly one of start / goal / random
      start: {x: [-3.0, 3.0, 61], y: [-3.0, 3.0, 61]}     # a map: linspace per axis
      # goal: {...}                                        # the same over goal positions
      # random: {tasks: 2000, seed: 1, start: {radius: [1.8, 2.6]},
      #          goal: {x: [0.5, 1.5], y: [-1.0, 1.0]},
      #          obstacles: {count: [0, 10], radius: [0.1, 0.3], region: {radius: [0.3, 3.0]}}}
    planner: {seed: 0, margin: 0.0, methods: [paper_surface]}   # default: every method
    chunk: 200                     # tasks per Dask task

Positions have one axis per task dimension of the robot: x, y for planar arms (x, y, z
for spatial position tasks), each `[low, high, count]` (a map axis) or one number (held
fixed: a slice). Random regions are boxes (`x: [low, high]`, ...) or shells about the
base (`radius: [low, high]`: radius uniform, direction uniform). Bad values raise the
core's InputError naming the field, e.g. `vary.start.x[2]: must be an integer >= 1`.

Task k of a map is grid point k with x varying fastest. Task k of a random study draws
from its own generator, seeded with (seed, k), so every task, and so every chunk, is
the same whatever the chunk size or the worker; random obstacle counts cycle through
their range (task k gets low + k mod (high - low + 1)), so each count gets as many tasks.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..core import (
    InputError,
    Obstacle,
    PlannerOptions,
    Scene,
    Task,
    VerificationOptions,
    load_scene,
)
from ..core.io.files import load_yaml, read_text
from ..core.io.fingerprint import scene_fingerprint
from ..core.paper.options import METHODS
from ..core.validation import check_keys, integer, mapping, number

AXES = ('x', 'y', 'z')
DEFAULT_CHUNK = 200
MAX_TASKS = 10_000_000         # a typo in a grid should not fill the scheduler's memory
MAX_OBSTACLES = 1000
OBSTACLE_GAP = 0.05            # [m] random obstacles keep this clear of base, start and goal
PLACEMENT_ATTEMPTS = 1000      # draws per random obstacle before the task gives up


@dataclass(frozen=True)
class PositionGrid:
    """A map: the start or goal position over a grid; `axes` (m,) hold each axis' values [m]."""

    endpoint: str                        # 'start' or 'goal'
    axes: tuple[tuple[float, ...], ...]

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of values per axis (x first)."""
        return tuple(len(values) for values in self.axes)

    @property
    def tasks(self) -> int:
        """Grid points in the map."""
        return math.prod(self.shape)

    def position(self, index: int) -> tuple[float, ...]:
        """Grid point `index` (m,) [m], x varying fastest."""
        point = []
        for values in self.axes:
            index, k = divmod(index, len(values))
            point.append(values[k])
        return tuple(point)


@dataclass(frozen=True)
class Region:
    """Where random positions fall: a box (`bounds` per axis) or a shell (`radius`) [m]."""

    bounds: tuple[tuple[float, float], ...] = ()
    radius: tuple[float, float] | None = None

    def sample(self, rng: np.random.Generator, dim: int) -> np.ndarray:
        """Draw one position (dim,) [m]."""
        if self.radius is None:
            return np.array([rng.uniform(low, high) for low, high in self.bounds])
        direction = rng.normal(size=dim)
        direction /= max(np.linalg.norm(direction), 1e-300)
        return rng.uniform(*self.radius) * direction


@dataclass(frozen=True)
class RandomObstacles:
    """Spheres (disks in the plane) added per task: `count` and `radius` [m] ranges."""

    count: tuple[int, int]
    radius: tuple[float, float]
    region: Region


@dataclass(frozen=True)
class RandomTasks:
    """A sweep: `tasks` seeded random tasks; a region left out keeps the scene's position."""

    tasks: int
    seed: int
    start: Region | None = None
    goal: Region | None = None
    obstacles: RandomObstacles | None = None


@dataclass(frozen=True)
class PlannerSettings:
    """The planner's seed, margin [m] and methods tried, as every task of the study uses them."""

    seed: int = 0
    margin: float = 0.0
    methods: tuple[str, ...] = METHODS

    def options(self) -> PlannerOptions:
        """Return the core's options for these settings."""
        return PlannerOptions(verification=VerificationOptions(margin=self.margin),
                              methods=self.methods)


@dataclass(frozen=True)
class StudyTask:
    """One task of a study: where the end effector goes, among which obstacles."""

    index: int
    start: tuple[float, ...]
    goal: tuple[float, ...]
    added_obstacles: tuple[Obstacle, ...]
    scene: Scene                                 # the base scene with this task and obstacles


@dataclass(frozen=True)
class Study:
    """A validated spec: the base scene, what varies, planner settings, chunk size."""

    name: str
    scene: Scene
    vary: PositionGrid | RandomTasks
    planner: PlannerSettings = PlannerSettings()
    chunk: int = DEFAULT_CHUNK

    @property
    def kind(self) -> str:
        """'map' for a grid of positions, 'sweep' for random tasks."""
        return 'map' if isinstance(self.vary, PositionGrid) else 'sweep'

    @property
    def dim(self) -> int:
        """Task dimension m of the robot (2 for planar arms)."""
        return self.scene.robot.task_dim

    @property
    def tasks(self) -> int:
        """Number of tasks."""
        return self.vary.tasks

    @property
    def chunks(self) -> int:
        """Number of chunks (Dask tasks)."""
        return -(-self.tasks // self.chunk)

    def chunk_tasks(self, chunk: int) -> range:
        """Task indices of chunk `chunk`."""
        return range(chunk * self.chunk, min((chunk + 1) * self.chunk, self.tasks))

    def task(self, index: int) -> StudyTask:
        """Enumerate task `index` (deterministic: the same on every machine and run)."""
        if not 0 <= index < self.tasks:
            raise IndexError(f'task {index} is not in 0..{self.tasks - 1}')
        base = self.scene.task
        start = None if base is None else base.start
        goal = None if base is None else base.goal
        added: tuple[Obstacle, ...] = ()
        if isinstance(self.vary, PositionGrid):
            if self.vary.endpoint == 'start':
                start = self.vary.position(index)
            else:
                goal = self.vary.position(index)
        else:
            start, goal, added = _random_task(self.vary, index, start, goal, self.dim)
        task = Task(start, goal) if base is None else replace(base, start=start, goal=goal)
        scene = self.scene.with_obstacles(added).with_task(task)
        return StudyTask(index, start, goal, added, scene)

    def describe(self) -> dict:
        """Return the study as plain data: the spec with its defaults, the scene's content."""
        vary = self.vary
        if isinstance(vary, PositionGrid):
            varied = {vary.endpoint: {axis: list(values)
                                      for axis, values in zip(AXES, vary.axes, strict=False)}}
        else:
            varied = {'random': {
                'tasks': vary.tasks, 'seed': vary.seed,
                'start': _region_to_dict(vary.start), 'goal': _region_to_dict(vary.goal),
                'obstacles': None if vary.obstacles is None else {
                    'count': list(vary.obstacles.count), 'radius': list(vary.obstacles.radius),
                    'region': _region_to_dict(vary.obstacles.region)}}}
        return {'scene': scene_fingerprint(self.scene), 'vary': varied,
                'planner': {'seed': self.planner.seed, 'margin': self.planner.margin,
                            'methods': list(self.planner.methods)},
                'chunk': self.chunk}

    def digest(self) -> str:
        """Hash `describe()`: two studies with the same digest give the same rows."""
        text = json.dumps(self.describe(), sort_keys=True, allow_nan=False)
        return hashlib.sha256(text.encode()).hexdigest()


def load_study(path: str | Path) -> Study:
    """Read and validate a study spec YAML file (its scene path is relative to it)."""
    path = Path(path)
    data = load_yaml(read_text(path, str(path)), str(path))
    return parse_study(data, name=path.stem, directory=path.parent)


def parse_study(data: Any, name: str = 'study', directory: Path | None = None) -> Study:
    """Validate a spec given as plain data; `directory` is where its scene path starts."""
    data = mapping(data, 'study')
    check_keys(data, 'study', required=('scene', 'vary'), optional=('planner', 'chunk'))
    scene = _scene(data['scene'], Path(directory or '.'))
    if scene.robot.task_dim not in (2, 3):
        # Axis and pose tasks hold an orientation too: varying them is for later.
        raise InputError('scene', f'studies vary planar and 3-D position tasks; this robot\'s '
                         f'tasks have {scene.robot.task_dim} components')
    vary = mapping(data['vary'], 'vary')
    check_keys(vary, 'vary', required=(), optional=('start', 'goal', 'random'))
    if len(vary) != 1:
        raise InputError('vary', 'needs exactly one of start (a map), goal (a map) or random '
                         f'(a sweep), got {", ".join(vary) or "none"}')
    (kind, value), = vary.items()
    if kind == 'random':
        varied = _random_tasks(value, scene)
    else:
        varied = _grid(value, f'vary.{kind}', kind, scene)
    if varied.tasks > MAX_TASKS:
        raise InputError(f'vary.{kind}', f'{varied.tasks} tasks: at most {MAX_TASKS} per study')
    planner = _planner(data.get('planner') or {})
    chunk = integer(data.get('chunk', DEFAULT_CHUNK), 'chunk', least=1)
    return Study(name, scene, varied, planner, chunk)


# --- sections ------------------------------------------------------------------------------

def _scene(value: Any, directory: Path) -> Scene:
    if not isinstance(value, str) or not value:
        raise InputError('scene', 'must be the path of a scene YAML file, relative to the spec')
    try:
        return load_scene(directory / value)
    except InputError as error:
        if error.field == str(directory / value):  # the file itself: unreadable or not YAML
            raise InputError('scene', f'{value}: {error.problem}') from None
        raise InputError(f'scene {value}: {error.field}', error.problem) from None


def _grid(data: Any, where: str, endpoint: str, scene: Scene) -> PositionGrid:
    other = 'goal' if endpoint == 'start' else 'start'
    if scene.task is None:
        raise InputError(where, f'the scene has no task: a {endpoint} map takes task.{other} '
                         'and task.goal_tolerance from it')
    axes = _axes(data, where, scene.robot.task_dim)
    spans = [_axis_span(axes[a], f'{where}.{a}') for a in axes]
    tasks = math.prod(count for _, _, count in spans)
    if tasks > MAX_TASKS:
        raise InputError(where, f'{tasks} tasks: at most {MAX_TASKS} per study')
    return PositionGrid(endpoint, tuple(tuple(float(v) for v in np.linspace(*span))
                                        for span in spans))


def _axis_span(value: Any, where: str) -> tuple[float, float, int]:
    """(low, high, count) of a map axis: [low, high, count] or one number."""
    if not isinstance(value, list):
        value = number(value, where)
        return (value, value, 1)
    if len(value) != 3:
        raise InputError(where, f'needs [low, high, count] or one number, got {len(value)} values')
    low, high = (number(v, f'{where}[{k}]') for k, v in enumerate(value[:2]))
    count = integer(value[2], f'{where}[2]', least=1)
    if high < low:
        raise InputError(where, f'low {low} is above high {high}')
    if count == 1 and high != low:
        raise InputError(f'{where}[2]', 'is 1: give low == high, or one number')
    return (low, high, count)


def _random_tasks(data: Any, scene: Scene) -> RandomTasks:
    where = 'vary.random'
    data = mapping(data, where)
    check_keys(data, where, required=('tasks',), optional=('seed', 'start', 'goal', 'obstacles'))
    tasks = integer(data['tasks'], f'{where}.tasks', least=1)
    seed = integer(data.get('seed', 0), f'{where}.seed', least=0)
    dim = scene.robot.task_dim
    start, goal = (None if data.get(k) is None else _region(data[k], f'{where}.{k}', dim)
                   for k in ('start', 'goal'))
    obstacles = None if data.get('obstacles') is None else \
        _random_obstacles(data['obstacles'], f'{where}.obstacles', scene)
    if start is None and goal is None and obstacles is None:
        raise InputError(where, 'varies nothing: give start, goal or obstacles')
    if scene.task is None and (start is None or goal is None):
        raise InputError(where, 'the scene has no task: give both start and goal regions')
    return RandomTasks(tasks, seed, start, goal, obstacles)


def _random_obstacles(data: Any, where: str, scene: Scene) -> RandomObstacles:
    data = mapping(data, where)
    check_keys(data, where, required=('count', 'radius'), optional=('region',))
    count = _range(data['count'], f'{where}.count', whole=True)
    if count[0] < 0 or count[1] > MAX_OBSTACLES:
        raise InputError(f'{where}.count', f'must lie in [0, {MAX_OBSTACLES}], got {list(count)}')
    radius = _range(data['radius'], f'{where}.radius')
    if radius[0] <= 0.0:
        raise InputError(f'{where}.radius', f'must be > 0, got {radius[0]}')
    dim = scene.robot.task_dim
    if data.get('region') is None:
        reach = float(scene.robot.tip_lever_arms()[0])  # [m] farthest the tip gets from joint 1
        region = Region(radius=(0.0, reach))
    else:
        region = _region(data['region'], f'{where}.region', dim)
    return RandomObstacles(count, radius, region)


def _region(data: Any, where: str, dim: int) -> Region:
    data = mapping(data, where)
    if 'radius' in data:
        check_keys(data, where, required=('radius',), optional=())
        radius = _range(data['radius'], f'{where}.radius')
        if radius[0] < 0.0:
            raise InputError(f'{where}.radius', f'must be >= 0, got {radius[0]}')
        return Region(radius=radius)
    axes = _axes(data, where, dim, also='radius')
    return Region(bounds=tuple(_range(axes[a], f'{where}.{a}') for a in axes))


def _planner(data: Any) -> PlannerSettings:
    data = mapping(data, 'planner')
    check_keys(data, 'planner', required=(), optional=('seed', 'margin', 'methods'))
    seed = integer(data.get('seed', 0), 'planner.seed', least=0)
    margin = number(data.get('margin', 0.0), 'planner.margin')
    if margin < 0.0:
        raise InputError('planner.margin', f'must be >= 0, got {margin}')
    methods = data.get('methods', list(METHODS))
    if not isinstance(methods, list) or not methods or \
            any(m not in METHODS for m in methods) or len(set(methods)) < len(methods):
        raise InputError('planner.methods', f'must be a list of distinct methods from '
                         f'{", ".join(METHODS)}, got {methods!r}')
    if methods[0] != METHODS[0]:
        raise InputError('planner.methods', f'{METHODS[0]} comes first (the others run where '
                         f'it finds no plan), got {methods!r}')
    return PlannerSettings(seed, margin, tuple(methods))


# --- random tasks ----------------------------------------------------------------------------

def _random_task(vary: RandomTasks, index: int, start, goal, dim: int):
    """Draw task `index`: (start, goal, added obstacles), from its own generator."""
    rng = np.random.default_rng([vary.seed, index])
    if vary.start is not None:
        start = tuple(float(v) for v in vary.start.sample(rng, dim))
    if vary.goal is not None:
        goal = tuple(float(v) for v in vary.goal.sample(rng, dim))
    added: tuple[Obstacle, ...] = ()
    if vary.obstacles is not None:
        low, high = vary.obstacles.count
        count = low + index % (high - low + 1)
        added = _place_obstacles(vary.obstacles, count, (np.zeros(dim), start, goal), rng, dim)
    return start, goal, added


def _place_obstacles(spec: RandomObstacles, count: int, keep_clear, rng: np.random.Generator,
                     dim: int) -> tuple[Obstacle, ...]:
    """Spheres clear of the points `keep_clear` [m] by their radius plus OBSTACLE_GAP."""
    points = np.array([np.asarray(p, dtype=float) for p in keep_clear])
    obstacles = []
    for _ in range(count):
        for _ in range(PLACEMENT_ATTEMPTS):
            radius = float(rng.uniform(*spec.radius))
            center = spec.region.sample(rng, dim)
            if np.min(np.linalg.norm(points - center, axis=1)) > radius + OBSTACLE_GAP:
                break
        else:
            raise InputError('vary.random.obstacles.region', f'no room for an obstacle clear of '
                             f'the base, start and goal in {PLACEMENT_ATTEMPTS} draws')
        xyz = tuple(float(v) for v in center) + (0.0,) * (3 - dim)
        obstacles.append(Obstacle('sphere', xyz, radius=radius))
    return tuple(obstacles)


# --- values ----------------------------------------------------------------------------------

def _region_to_dict(region: Region | None) -> dict | None:
    if region is None:
        return None
    if region.radius is not None:
        return {'radius': list(region.radius)}
    return {axis: list(bounds) for axis, bounds in zip(AXES, region.bounds, strict=False)}


def _axes(data: Any, where: str, dim: int, also: str | None = None) -> dict:
    """Return the axes of a position (x, y for m = 2; x, y, z for m = 3), in order."""
    data = mapping(data, where)
    wanted = AXES[:dim]
    for key in data:
        if key not in wanted:
            allowed = ', '.join(wanted + ((also,) if also else ()))
            hint = f' (the robot\'s positions are {dim}-D)' if key in AXES else ''
            raise InputError(f'{where}.{key}', f'unknown key{hint} (allowed: {allowed})')
    for key in wanted:
        if key not in data:
            raise InputError(f'{where}.{key}', 'is missing')
    return {key: data[key] for key in wanted}


def _range(value: Any, where: str, whole: bool = False) -> tuple:
    """[low, high] (or one number for low == high), low <= high; `whole`: integers."""
    read = integer if whole else number
    if not isinstance(value, list):
        value = read(value, where)
        return (value, value)
    if len(value) != 2:
        raise InputError(where, f'needs [low, high] or one number, got {len(value)} values')
    low, high = (read(v, f'{where}[{k}]') for k, v in enumerate(value))
    if high < low:
        raise InputError(where, f'low {low} is above high {high}')
    return (low, high)


