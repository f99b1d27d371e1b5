"""The MuJoCo model of an arm among static obstacles: our robot and scene as MJCF.

Every robot goes through the `Robot` interface, so the planar chains, DH arms and URDF
arms all translate the same way, with the collision primitives our checker uses: a body
per link, posed at the zero configuration; a hinge per joint, its axis found from the
links' frames (the screw of each joint); a geom per collision shape. MuJoCo's own URDF
compiler is not used: our URDF files carry no inertia (it would need them), and a
scene holds the robot, not its URDF text. Masses come from the geoms at `density`
(radius-0 links, drawn as lines, get a geom of LINE_RADIUS). Joints are driven by
position actuators (stiffness `kp`) and velocity actuators (damping `kv` towards the
commanded velocity: the servo does not lag behind a moving command), their sum within
the torque limit, from a physics file (`PhysicsOptions`, config/robots/*_mujoco.yaml);
gravity is on, and its compensation (when asked) goes through the actuators and their
limits, as the Panda's and iiwa's controllers do. A brake per joint (a joint equality,
off until the joint locks) holds a locked joint. Obstacles are static geoms of the world
body.

MuJoCo's collision detection is its own: the links collide with the obstacles and, for
the link pairs our model checks (`self_collision_pairs`), with each other.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ElementTree
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ftplan_ros.core import InputError, Robot
from ftplan_ros.core.io.files import load_yaml, read_text
from ftplan_ros.core.model.geometry import Shape, rotation_from_rpy
from ftplan_ros.core.model.scene import Obstacle
from ftplan_ros.core.validation import check_keys, mapping, number

LINE_RADIUS = 0.001   # [m] of the geom of a link drawn as a line (radius 0)
_SCREW_ANGLE = 0.5    # [rad] a joint is turned by to find its axis from the link frames
_BRAKE_SOLREF = '0.005 1'  # a stiff brake: 5 ms time constant, critically damped


@dataclass(frozen=True)
class JointDrive:
    """A joint's position actuator: stiffness `kp` [Nm/rad], damping `kv` [Nm s/rad], `torque` [Nm].

    The torque is kp (q_commanded - q) + kv (dq_commanded - dq), clamped to ±torque.
    """

    kp: float = 300.0
    kv: float = 30.0
    torque: float = 100.0


@dataclass(frozen=True)
class PhysicsOptions:
    """How the MuJoCo arm is built; each field is a key of the physics file's `mujoco:`."""

    timestep: float = 0.002              # [s] of a MuJoCo step
    density: float = 1000.0              # [kg/m^3] of the links' geoms
    armature: float = 0.05               # [kg m^2] rotor inertia added to each joint
    gravity_compensation: bool = True    # the actuators hold the links' weight
    joints: Mapping[str, JointDrive] = field(default_factory=dict)  # by name; others: default
    default: JointDrive = JointDrive()

    def drive(self, joint: str) -> JointDrive:
        """Return the actuator of `joint` (the default one where none is given)."""
        return self.joints.get(joint, self.default)


def read_physics_options(text: str, where: str) -> PhysicsOptions:
    """Read a physics file (YAML with a `mujoco:` mapping, see config/robots/*_mujoco.yaml)."""
    data = mapping(mapping(load_yaml(text, where), where).get('mujoco'), f'{where}: mujoco')
    where = f'{where}: mujoco'
    check_keys(data, where, (), ('timestep', 'density', 'armature', 'gravity_compensation',
                                 'joints', 'default'))
    scalars = {}
    for key in ('timestep', 'density', 'armature'):
        if key in data:
            scalars[key] = _positive(data[key], f'{where}.{key}', key == 'armature')
    compensation = data.get('gravity_compensation', True)
    if not isinstance(compensation, bool):
        raise InputError(f'{where}.gravity_compensation', f'must be true or false, got '
                         f'{compensation!r}')
    joints = {str(name): _drive(value, f'{where}.joints.{name}')
              for name, value in mapping(data.get('joints', {}), f'{where}.joints').items()}
    default = _drive(data['default'], f'{where}.default') if 'default' in data else JointDrive()
    return PhysicsOptions(**scalars, gravity_compensation=compensation, joints=joints,
                          default=default)


def find_physics_file(directory: Path, joint_names: Sequence[str]) -> Path | None:
    """Return the `*_mujoco.yaml` in `directory` that names all of these joints, if any."""
    for path in sorted(directory.glob('*_mujoco.yaml')):
        options = read_physics_options(read_text(path, path.name), path.name)
        if set(joint_names) <= set(options.joints):
            return path
    return None


def _positive(value, where: str, zero_allowed: bool = False) -> float:
    value = number(value, where)
    if value < 0.0 or (value == 0.0 and not zero_allowed):
        raise InputError(where, f'must be {">= 0" if zero_allowed else "> 0"}, got {value}')
    return value


def _drive(data, where: str) -> JointDrive:
    data = mapping(data, where)
    check_keys(data, where, ('kp', 'kv', 'torque'), ())
    return JointDrive(_positive(data['kp'], f'{where}.kp'),
                      _positive(data['kv'], f'{where}.kv', zero_allowed=True),
                      _positive(data['torque'], f'{where}.torque'))


def model_xml(robot: Robot, obstacles: Sequence[Obstacle], options: PhysicsOptions) -> str:
    """Return the MJCF text of `robot` among `obstacles` (base frame) [m, rad, kg, s]."""
    root = ElementTree.Element('mujoco', model='ftplan')
    ElementTree.SubElement(root, 'compiler', angle='radian', autolimits='true')
    # implicitfast: the servos' damping is integrated implicitly, so stiff gains stay stable
    ElementTree.SubElement(root, 'option', timestep=_text(options.timestep),
                           gravity='0 0 -9.81', integrator='implicitfast')
    assets = ElementTree.SubElement(root, 'asset')
    world = ElementTree.SubElement(root, 'worldbody')
    for index, obstacle in enumerate(obstacles):
        world.append(_obstacle_geom(obstacle, f'obstacle{index}'))
    geoms = _add_links(robot, world, assets, options)
    _add_self_collision_pairs(robot, geoms, root)
    actuators = ElementTree.SubElement(root, 'actuator')
    equalities = ElementTree.SubElement(root, 'equality')
    for name in robot.joint_names:
        ElementTree.SubElement(actuators, 'position', name=name, joint=name,
                               kp=_text(options.drive(name).kp))
        ElementTree.SubElement(equalities, 'joint', name=f'brake_{name}', joint1=name,
                               active='false', solref=_BRAKE_SOLREF)
    for name in robot.joint_names:
        ElementTree.SubElement(actuators, 'velocity', name=f'{name}_velocity', joint=name,
                               kv=_text(options.drive(name).kv))
    return ElementTree.tostring(root, encoding='unicode')


def _add_links(robot: Robot, world: ElementTree.Element, assets: ElementTree.Element,
               options: PhysicsOptions) -> list[list[str]]:
    """Add the links as a chain of bodies under `world`; return each link's geom names."""
    zero = np.zeros(robot.n_joints)
    frames = robot.link_frames(zero)
    joints_of = {int(c) + 1: [] for c in robot.joint_chain_index}
    for joint, chain_index in enumerate(robot.joint_chain_index):
        joints_of[int(chain_index) + 1].append(joint)
    parent, parent_frame, bodies = world, np.eye(4), []
    for link, name in enumerate(robot.link_names):
        relative = np.linalg.inv(parent_frame) @ frames[link]
        body = ElementTree.SubElement(parent, 'body', name=name, **_pose(relative),
                                      gravcomp='1' if options.gravity_compensation else '0')
        for joint in joints_of.get(link, []):
            axis, point = _joint_screw(robot, zero, joint, link, frames[link])
            name = robot.joint_names[joint]
            torque = options.drive(name).torque
            attributes = {} if robot.periodic[joint] else \
                {'range': f'{robot.limits[joint, 0]:.9g} {robot.limits[joint, 1]:.9g}'}
            ElementTree.SubElement(body, 'joint', name=name, type='hinge',
                                   axis=' '.join(_text(v) for v in axis),
                                   pos=' '.join(_text(v) for v in point),
                                   armature=_text(options.armature),
                                   actuatorgravcomp='true',
                                   actuatorfrcrange=f'{-torque:.9g} {torque:.9g}', **attributes)
        bodies.append(body)
        parent, parent_frame = body, frames[link]
    geoms: list[list[str]] = [[] for _ in robot.link_names]
    for index, link_shape in enumerate(robot.collision_shapes):
        name = f'{robot.link_names[link_shape.link]}_{index}'
        geom = _geom(link_shape.shape, link_shape.placement, name, assets)
        geom.set('density', _text(options.density))
        geom.set('contype', '1')
        geom.set('conaffinity', '0')
        bodies[link_shape.link].append(geom)
        geoms[link_shape.link].append(name)
    return geoms


def _add_self_collision_pairs(robot: Robot, geoms: list[list[str]],
                              root: ElementTree.Element) -> None:
    pairs = [(a, b) for a, b in robot.self_collision_pairs]
    if not pairs:
        return
    contact = ElementTree.SubElement(root, 'contact')
    for a, b in pairs:
        for first in geoms[a]:
            for second in geoms[b]:
                ElementTree.SubElement(contact, 'pair', geom1=first, geom2=second)


def _joint_screw(robot: Robot, zero: np.ndarray, joint: int, link: int, frame: np.ndarray,
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Return the axis (3,) and a point (3,) [m] of `joint`, in the frame of `link`.

    Turning the joint by _SCREW_ANGLE moves the link by a rotation about that axis.
    """
    turned = zero.copy()
    turned[joint] = _SCREW_ANGLE
    motion = robot.link_frames(turned)[link] @ np.linalg.inv(frame)
    rotation, translation = motion[:3, :3], motion[:3, 3]
    skew = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0],
                     rotation[1, 0] - rotation[0, 1]])
    axis = skew / (2.0 * math.sin(_SCREW_ANGLE))
    point = np.linalg.lstsq(np.eye(3) - rotation, translation, rcond=None)[0]
    inverse = np.linalg.inv(frame)
    return inverse[:3, :3] @ axis, inverse[:3, :3] @ point + inverse[:3, 3]


def _geom(shape: Shape, placement: np.ndarray, name: str,
          assets: ElementTree.Element) -> ElementTree.Element:
    """Return the geom of one of our shapes, posed by `placement` (4, 4) in its body."""
    attributes = {'name': name, **_pose(placement)}
    if shape.kind == 'sphere':
        attributes.update(type='sphere', size=_text(max(shape.radius, LINE_RADIUS)))
    elif shape.kind == 'box':
        attributes.update(type='box', size=' '.join(_text(0.5 * s) for s in shape.size))
    elif shape.kind in ('capsule', 'cylinder'):
        attributes.update(type=shape.kind, size=f'{_text(max(shape.radius, LINE_RADIUS))} '
                                                f'{_text(0.5 * shape.length)}')
    else:  # a convex mesh: MuJoCo collides with its convex hull, as our checker does
        mesh = ElementTree.SubElement(assets, 'mesh', name=f'{name}_mesh')
        mesh.set('vertex', ' '.join(_text(v) for v in np.asarray(shape.vertices).ravel()))
        attributes.update(type='mesh', mesh=f'{name}_mesh')
    return ElementTree.Element('geom', attributes)


def _obstacle_geom(obstacle: Obstacle, name: str) -> ElementTree.Element:
    """Return a static geom of the world body for `obstacle`; it collides with the links."""
    rotation = rotation_from_rpy(obstacle.rpy)
    shape = Shape(obstacle.shape, radius=obstacle.radius, size=obstacle.size,
                  length=obstacle.length)
    placement = np.eye(4)
    placement[:3, :3], placement[:3, 3] = rotation, obstacle.center
    geom = _geom(shape, placement, name, ElementTree.Element('asset'))
    geom.set('contype', '0')
    geom.set('conaffinity', '1')
    return geom


def _pose(frame: np.ndarray) -> dict[str, str]:
    """Return MJCF `pos` and `quat` (w, x, y, z) attributes of a frame (4, 4)."""
    return {'pos': ' '.join(_text(v) for v in frame[:3, 3]),
            'quat': ' '.join(_text(v) for v in _quaternion(frame[:3, :3]))}


def _quaternion(rotation: np.ndarray) -> np.ndarray:
    """Return the unit quaternion (w, x, y, z) of a rotation matrix (3, 3)."""
    x, y, z, w = Rotation.from_matrix(rotation).as_quat()
    return np.array([w, x, y, z])


def _text(value: float) -> str:
    return f'{float(value):.9g}'
