"""Scenes: the robot, its static obstacles and the task, loaded from YAML and validated.

The format is the one in CONTRACT.md (`robot`, `obstacles`, `task`, `tolerate`); every
value is checked and a bad one raises `InputError` naming its field, e.g.
`obstacles[2].radius`. Robots are planar chains (`type: planar`), URDF files (`type:
urdf`, parsed by Pinocchio) or DH tables (`type: dh`); a task's form says its kind:
`[x, y]` planar, `[x, y, z]` a 3-D position, `{position, orientation}` a 6-D pose,
`{position, axis}` a tool axis. Units are metres and radians.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..errors import InputError
from ..model.chain import ChainModel
from ..model.dh import DHRow, chain_from_dh
from ..model.robot import PlanarChain, Robot
from ..model.scene import (
    DEFAULT_GOAL_TOLERANCE,
    DEFAULT_ORIENTATION_TOLERANCE,
    OBSTACLE_TYPES,
    Obstacle,
    Scene,
    Task,
)
from ..model.spatial import SpatialArm
from ..model.srdf import read_srdf, with_exceptions
from ..model.task_space import unit_vector
from ..model.urdf import chain_from_urdf
from ..model.urdf_structure import read_urdf
from ..validation import check_keys, mapping, nonnegative, number, sequence, vector
from .files import load_yaml, read_text
from .limits_file import load_joint_limits
from .mesh_files import with_mesh_files
from .sampled_exceptions import parse_sampling, sampled_exceptions

# [rad] Widest joint limit: a joint that turns further has no limit (it wraps).
LARGEST_JOINT_ANGLE = 2.0 * math.pi


class MissingRobotError(InputError):
    """A scene without a robot was loaded without one to put in it."""








def load_scene(path: str | Path, robot: Robot | None = None) -> Scene:
    """Read and validate a scene YAML file (`robot`: the robot when the file has none)."""
    path = Path(path)
    data = load_yaml(read_text(path, str(path)), str(path))
    return parse_scene(data, name=path.stem, directory=path.parent, robot=robot)


def parse_scene(data: Any, name: str = 'scene', directory: Path | None = None,
                robot: Robot | None = None) -> Scene:
    """Validate a scene given as plain data (what `yaml.safe_load` returns).

    `robot` is a mapping, or the path of a robot YAML file (holding one `robot` mapping)
    relative to `directory`, the scene file's folder; a URDF's `file` is relative to the
    file that names it. A scene without one takes the `robot` argument (the nodes build
    it from /robot_description).
    """
    data = mapping(data, 'scene')
    check_keys(data, 'scene', required=(),
                optional=('robot', 'obstacles', 'task', 'frame_id', 'tolerate'))
    directory = Path(directory or '.')
    if 'robot' in data:
        robot_data = data['robot']
        if isinstance(robot_data, str):
            robot_data, directory = _robot_file(directory / robot_data)
        robot = parse_robot(robot_data, directory)
    elif robot is None:
        raise MissingRobotError('robot', 'is missing: give the robot in the scene (the nodes can '
                           'take it from /robot_description instead)')
    frame_id = data.get('frame_id', 'base_link')
    if not isinstance(frame_id, str) or not frame_id:
        raise InputError('frame_id', 'must be a non-empty string')
    planar = isinstance(robot, PlanarChain)
    obstacles = tuple(
        parse_obstacle(item, f'obstacles[{k}]', planar)
        for k, item in enumerate(sequence(data.get('obstacles') or [], 'obstacles')))
    scene = Scene(robot, obstacles, None, frame_id, name,
                  parse_tolerated(data.get('tolerate'), robot.joint_names))
    return scene if data.get('task') is None else scene.with_task(parse_task(data['task'], robot))


def parse_tolerated(data: Any, joint_names: Sequence[str], where: str = 'tolerate',
                    ) -> tuple[str, ...] | None:
    """Validate a list of joint names whose locks a plan must survive (None: all joints)."""
    if data is None:
        return None
    names = sequence(data, where)
    if not names:
        raise InputError(where, 'names no joint: leave it out to tolerate every joint')
    for k, joint in enumerate(names):
        if joint not in joint_names:
            raise InputError(f'{where}[{k}]', f'unknown joint {joint!r} (joints: '
                             f'{", ".join(joint_names)})')
    if len(set(names)) != len(names):
        raise InputError(where, 'names a joint twice')
    return tuple(sorted(names, key=list(joint_names).index))


def _robot_file(path: Path) -> tuple[Any, Path]:
    data = load_yaml(read_text(path, 'robot'), f'robot file {path.name}')
    data = mapping(data, f'robot file {path.name}')
    check_keys(data, f'robot file {path.name}', required=('robot',), optional=())
    return data['robot'], path.parent


def parse_robot(data: Any, directory: Path | None = None) -> Robot:
    """Validate the `robot` section: `type` planar, urdf or dh; files relative to `directory`.

    A spatial robot comes bound to pose tasks; `Scene.with_task` rebinds it to the task's
    kind.
    """
    data = mapping(data, 'robot')
    kind = data.get('type')
    if kind == 'planar':
        return _planar_robot(data)
    if kind == 'urdf':
        return SpatialArm(_urdf_chain(data, Path(directory or '.')))
    if kind == 'dh':
        return SpatialArm(_dh_chain(data))
    raise InputError('robot.type', f'must be "planar", "urdf" or "dh", got {kind!r}')


def _planar_robot(data: Mapping) -> PlanarChain:
    check_keys(data, 'robot', required=('type', 'link_lengths'),
                optional=('link_radius', 'joint_names', 'joint_limits'))
    lengths = vector(data['link_lengths'], 'robot.link_lengths')
    if not lengths:
        raise InputError('robot.link_lengths', 'needs at least one link')
    for k, value in enumerate(lengths):
        if value <= 0.0:
            raise InputError(f'robot.link_lengths[{k}]', f'must be > 0, got {value}')
    radius = _link_radius(data)
    n = len(lengths)
    names = _joint_names(data.get('joint_names'), n)
    limits = data.get('joint_limits')
    if limits is not None:
        limits = sequence(limits, 'robot.joint_limits')
        if len(limits) != n:
            raise InputError('robot.joint_limits', f'has {len(limits)} entries for {n} joints')
        limits = tuple(_joint_limit(item, f'robot.joint_limits[{k}]')
                       for k, item in enumerate(limits))
    return PlanarChain(tuple(lengths), tuple(names), radius, limits)


def _urdf_chain(data: Mapping, directory: Path) -> ChainModel:
    check_keys(data, 'robot', required=('type', 'file', 'tip_link'),
                optional=('base_link', 'tip_offset', 'disabled_collisions', 'srdf', 'mesh_dirs',
                          'self_collision_sampling', 'joint_limits'))
    texts = {}
    for key, kind in (('file', 'URDF'), ('srdf', 'SRDF')):
        if key in data:
            if not isinstance(data[key], str) or not data[key]:
                raise InputError(f'robot.{key}', f'must be the path of an {kind} file')
            texts[key] = read_text(directory / data[key], f'robot.{key}')
    mesh_dirs = []
    for k, folder in enumerate(sequence(data.get('mesh_dirs', []), 'robot.mesh_dirs')):
        if not isinstance(folder, str) or not folder:
            raise InputError(f'robot.mesh_dirs[{k}]', 'must be the path of a folder')
        mesh_dirs.append(directory / folder)
    model = robot_from_urdf(texts['file'], data['tip_link'], data.get('base_link'),
                            data.get('tip_offset', [0.0, 0.0, 0.0]),
                            data.get('disabled_collisions'), mesh_dirs=mesh_dirs,
                            srdf=texts.get('srdf'), directory=(directory / data['file']).parent,
                            self_collision_sampling=data.get('self_collision_sampling')).model
    if 'joint_limits' not in data:
        return model
    if not isinstance(data['joint_limits'], str) or not data['joint_limits']:
        raise InputError('robot.joint_limits', 'must be the path of a joint_limits.yaml file '
                         '(MoveIt\'s format)')
    return replace(model, motion_limits=load_joint_limits(
        directory / data['joint_limits'], model.joint_names, model.motion_limits,
        'robot.joint_limits'))


def _dh_chain(data: Mapping) -> ChainModel:
    check_keys(data, 'robot', required=('type', 'rows'),
                optional=('link_radius', 'joint_names', 'tip_offset', 'disabled_collisions',
                          'self_collision_sampling'))
    rows = []
    for k, row in enumerate(sequence(data['rows'], 'robot.rows')):
        where = f'robot.rows[{k}]'
        row = mapping(row, where)
        check_keys(row, where, required=('a', 'alpha', 'd'), optional=('offset', 'limits'))
        values = {key: number(row.get(key, 0.0), f'{where}.{key}')
                  for key in ('a', 'alpha', 'd', 'offset')}
        rows.append(DHRow(**values, limits=_joint_limit(row.get('limits'), f'{where}.limits')))
    if not rows:
        raise InputError('robot.rows', 'needs at least one joint')
    offset = vector(data.get('tip_offset', [0.0, 0.0, 0.0]), 'robot.tip_offset', length=3)
    model = chain_from_dh(rows, _joint_names(data.get('joint_names'), len(rows)),
                          _link_radius(data), offset)
    return with_disabled_collisions(model, data.get('disabled_collisions'),
                                    data.get('self_collision_sampling'))


def robot_from_urdf(xml: str, tip_link: str, base_link: str | None = None,
                    tip_offset: Sequence[float] = (0.0, 0.0, 0.0),
                    disabled_collisions: Any = None, mesh_dirs: Sequence[str | Path] = (),
                    task_kind: str = 'pose', srdf: str | None = None,
                    directory: Path | None = None,
                    self_collision_sampling: Any = None) -> SpatialArm:
    """Build the arm of a URDF given as text (e.g. /robot_description) for a kind of task.

    The arguments are those of a scene's `robot: {type: urdf, ...}` (InputError names
    them the same way); `srdf` is the text of an SRDF (e.g. /robot_description_semantic)
    whose exceptions replace the default ones (srdf.py). The exceptions come from one
    place: an SRDF beside a `disabled_collisions` list is refused, and either beside
    `self_collision_sampling` (how the exceptions of a robot without them are sampled:
    io/sampled_exceptions.py). Meshes are found as
    io/mesh_files.py says, from `directory` (the URDF file's folder; None for a URDF that
    is no file) and `mesh_dirs`.
    """
    for key, value in (('tip_link', tip_link), ('base_link', base_link)):
        if value is not None and (not isinstance(value, str) or not value):
            raise InputError(f'robot.{key}', 'must be a link name')
    if srdf is not None and disabled_collisions is not None:
        raise InputError('robot.srdf', 'and robot.disabled_collisions both give the '
                         'self-collision exceptions: keep one of them')
    if srdf is not None and self_collision_sampling is not None:
        raise InputError('robot.self_collision_sampling', 'samples the exceptions of a robot '
                         'without them, and robot.srdf gives them: keep one of them')
    offset = vector(list(tip_offset), 'robot.tip_offset', length=3)
    urdf = read_urdf(xml)
    exceptions = None if srdf is None else read_srdf(srdf, urdf.links, robot_name=urdf.name,
                                                         joints=urdf.joints)
    urdf = with_mesh_files(urdf, directory, [Path(d) for d in mesh_dirs])
    model = chain_from_urdf(urdf, tip_link, base_link, offset)
    if not any(item.link >= 1 for item in model.shapes):
        raise InputError('robot.file', f'no link that the joints {model.link_names[0]!r} -> '
                         f'{tip_link!r} move has <collision> geometry: ftplan checks the '
                         'links\' collision shapes against obstacles and each other; give '
                         'them <collision> elements')
    if exceptions is not None:
        return SpatialArm(with_exceptions(model, exceptions), task_kind)
    return SpatialArm(with_disabled_collisions(model, disabled_collisions,
                                               self_collision_sampling), task_kind)


def with_disabled_collisions(model: ChainModel, data: Any, sampling: Any = None) -> ChainModel:
    """Return the model with its self-collision exceptions: `data` lists link-name pairs.

    Without a list, MoveIt's sampled exceptions: adjacent links, links touching in >= 95 %
    of random configurations and links touching in none (io/sampled_exceptions.py), sampled
    as `sampling` (a robot's `self_collision_sampling`) says; a list beside it is refused.
    """
    if data is None:
        return replace(model, disabled_pairs=sampled_exceptions(model, parse_sampling(sampling)))
    if sampling is not None:
        raise InputError('robot.self_collision_sampling', 'samples the exceptions of a robot '
                         'without them, and robot.disabled_collisions gives them: keep one of '
                         'them')
    pairs = set()
    for k, pair in enumerate(sequence(data, 'robot.disabled_collisions')):
        names = sequence(pair, f'robot.disabled_collisions[{k}]')
        if len(names) != 2:
            raise InputError(f'robot.disabled_collisions[{k}]', 'must be two link names')
        indices = []
        for name in names:
            if name not in model.link_names:
                raise InputError(f'robot.disabled_collisions[{k}]', f'unknown link {name!r} '
                                 f'(links of the chain: {", ".join(model.link_names)})')
            indices.append(model.link_names.index(name))
        pairs.add(tuple(sorted(indices)))
    return replace(model, disabled_pairs=frozenset(pairs))


def _link_radius(data: Mapping) -> float:
    return nonnegative(data.get('link_radius', 0.0), 'robot.link_radius')


def _joint_names(names: Any, n: int) -> list[str]:
    names = [f'joint{k + 1}' for k in range(n)] if names is None else names
    names = sequence(names, 'robot.joint_names')
    if len(names) != n:
        raise InputError('robot.joint_names', f'has {len(names)} names for {n} joints')
    for k, joint in enumerate(names):
        if not isinstance(joint, str) or not joint:
            raise InputError(f'robot.joint_names[{k}]', 'must be a non-empty string')
    if len(set(names)) != n:
        raise InputError('robot.joint_names', 'names must be unique')
    return names


def parse_obstacle(data: Any, where: str, planar: bool = True) -> Obstacle:
    """Validate one obstacle mapping; `where` names it in errors (e.g. `obstacles[0]`).

    Beside a planar robot a `center` or box `size` may leave out z; beside a spatial one
    it needs all three values.
    """
    data = mapping(data, where)
    shape = data.get('type')
    if shape not in OBSTACLE_TYPES:
        raise InputError(f'{where}.type', f'must be one of {", ".join(OBSTACLE_TYPES)}, '
                         f'got {shape!r}')
    per_shape = {'sphere': ('radius',), 'box': ('size', 'rpy'),
                 'cylinder': ('radius', 'length', 'rpy')}
    required = {'sphere': ('radius',), 'box': ('size',), 'cylinder': ('radius',)}[shape]
    check_keys(data, where, required=('type', 'center') + required,
                optional=tuple(k for k in per_shape[shape] if k not in required))
    center = _point3(data['center'], f'{where}.center', planar)
    rpy = tuple(vector(data.get('rpy', [0.0, 0.0, 0.0]), f'{where}.rpy', length=3))
    if shape == 'box':
        size = vector(data['size'], f'{where}.size')
        _check_dimensions(size, f'{where}.size', planar)
        size = size + [1.0] * (3 - len(size))  # planar boxes get a unit height
        for k, value in enumerate(size):
            if value <= 0.0:
                raise InputError(f'{where}.size[{k}]', f'must be > 0, got {value}')
        return Obstacle('box', center, size=tuple(size), rpy=rpy)
    radius = number(data['radius'], f'{where}.radius')
    if radius <= 0.0:
        raise InputError(f'{where}.radius', f'must be > 0, got {radius}')
    if shape == 'sphere':
        return Obstacle('sphere', center, radius=radius)
    length = number(data.get('length', 1.0), f'{where}.length')
    if length <= 0.0:
        raise InputError(f'{where}.length', f'must be > 0, got {length}')
    return Obstacle('cylinder', center, radius=radius, length=length, rpy=rpy)


def parse_task(data: Any, robot: Robot) -> Task:
    """Validate the `task` section; its form sets the kind (see the module docstring)."""
    data = mapping(data, 'task')
    check_keys(data, 'task', required=('start', 'goal'),
                optional=('goal_tolerance', 'orientation_tolerance'))
    start = parse_task_point(data['start'], 'task.start', robot)
    goal = parse_task_point(data['goal'], 'task.goal', robot)
    if len(start) != len(goal):
        raise InputError('task.goal', 'must have the same form as task.start')
    tolerance = number(data.get('goal_tolerance', DEFAULT_GOAL_TOLERANCE),
                        'task.goal_tolerance')
    if tolerance <= 0.0:
        raise InputError('task.goal_tolerance', f'must be > 0, got {tolerance}')
    angle = number(data.get('orientation_tolerance', DEFAULT_ORIENTATION_TOLERANCE),
                    'task.orientation_tolerance')
    if angle <= 0.0:
        raise InputError('task.orientation_tolerance', f'must be > 0, got {angle}')
    return Task(start, goal, tolerance, angle)


def parse_task_point(data: Any, where: str, robot: Robot) -> tuple[float, ...]:
    """Validate a task point for the robot: [x, y] (planar), [x, y, z], or a mapping.

    A mapping holds `position` [x, y, z] and `orientation` [qx, qy, qz, qw] (a unit
    quaternion) or `axis` (a unit vector).
    """
    planar = isinstance(robot, PlanarChain)
    if not isinstance(data, Mapping):
        point = vector(data, where, length=2 if planar else 3)
        return tuple(point)
    if planar:
        raise InputError(where, 'a planar arm takes [x, y]')
    check_keys(data, where, required=('position',), optional=('orientation', 'axis'))
    position = vector(data['position'], f'{where}.position', length=3)
    if ('orientation' in data) == ('axis' in data):
        raise InputError(where, 'needs exactly one of orientation (a pose) or axis (a tool '
                         'axis); give [x, y, z] for a position')
    key = 'orientation' if 'orientation' in data else 'axis'
    values = vector(data[key], f'{where}.{key}', length=4 if key == 'orientation' else 3)
    try:
        unit = unit_vector(values, 'a quaternion' if key == 'orientation' else 'an axis')
    except ValueError as error:
        raise InputError(f'{where}.{key}', str(error)) from None
    return tuple(position) + tuple(float(v) for v in unit)








def _joint_limit(data: Any, where: str) -> tuple[float, float] | None:
    if data is None:
        return None
    low, high = vector(data, where, length=2)
    if not low < high:
        raise InputError(where, f'lower limit {low} must be below upper limit {high}')
    if max(abs(low), abs(high)) > LARGEST_JOINT_ANGLE:
        raise InputError(where, f'limits must be within ±2π [rad], got [{low}, {high}]: leave '
                         'them out (null) for a joint that turns without limit')
    return (low, high)


def _check_dimensions(values: list[float], where: str, planar: bool) -> None:
    """Refuse a point or size that is not x, y, z (or x, y beside a planar robot)."""
    if len(values) == 3 or (planar and len(values) == 2):
        return
    raise InputError(where, f'needs 2 or 3 values, got {len(values)}' if planar else
                     f'needs 3 values (x, y, z) beside a spatial robot, got {len(values)}')


def _point3(data: Any, where: str, planar: bool = True) -> tuple[float, float, float]:
    values = vector(data, where)
    _check_dimensions(values, where, planar)
    return tuple(values + [0.0] * (3 - len(values)))
