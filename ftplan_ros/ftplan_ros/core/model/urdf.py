"""Spatial chains from URDF, parsed by Pinocchio.

The URDF is checked first (urdf_structure.py): Pinocchio reads only a tree it can
build, and reads it as it was checked. The chain runs from `base_link` (fixed to the
URDF's root) to `tip_link`: its joints must be revolute or continuous. Joints off that
path (fingers, a second arm) are locked at zero with Pinocchio's `buildReducedModel`,
which folds their links' geometry into the chain, and fixed joints are folded in the
same way. Joint velocity limits are the URDF's (`<limit velocity>`; 0 or none: the
default of motion_limits.py). Collision geometry is the links' `<collision>` elements:
boxes, cylinders, spheres, capsules and meshes (STL, OBJ, COLLADA: loaded by Pinocchio,
through coal and assimp, from the paths the URDF gives; core/io/mesh_files.py makes them
absolute). Each mesh is covered by convex pieces as it is loaded (cover.py; read from
the cache after the first time), and its cover is logged with the padding it adds. A mesh
with a vertex that is not finite, or wider than MAX_LINK_SIZE, is refused first.
"""

from __future__ import annotations

import logging
import re
import xml.etree.ElementTree as ElementTree
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from ..errors import InputError
from .chain import ChainModel
from .geometry import Shape
from .motion_limits import default_motion_limits
from .robot import LinkShape
from .urdf_structure import UrdfDescription, read_urdf

logger = logging.getLogger(__name__)

_REVOLUTE = ('JointModelRX', 'JointModelRY', 'JointModelRZ', 'JointModelRevoluteUnaligned')
_CONTINUOUS = ('JointModelRUBX', 'JointModelRUBY', 'JointModelRUBZ',
               'JointModelRevoluteUnboundedUnaligned')
# [rad] Limits written as ±2π rounded up (6.28318530718 in UR's URDFs, 6.2832) are ±2π:
# the range narrows by this much at most, which keeps every plan within the true limits.
TURN_ROUNDING = 1e-4
_PRISMATIC = ('JointModelPX', 'JointModelPY', 'JointModelPZ', 'JointModelPrismaticUnaligned')
# [m] The widest a link's collision mesh may be, along any axis: arm links are at most a
# few metres; a mesh in millimetres read as metres is a thousand times its size.
MAX_LINK_SIZE = 10.0
# coal's message for a mesh file it found but could not read: the path, then the reason.
_UNREADABLE_MESH = re.compile(r'Could not load resource ([^\n]+)\n(.*?)(?:Hint:|$)', re.DOTALL)
# Joints of a chain: redundant arms have 7 or 8; the cost of building a chain (its
# self-collision pairs) grows with the square of its links.
MAX_CHAIN_JOINTS = 32


def chain_from_urdf(urdf: str | UrdfDescription, tip_link: str, base_link: str | None = None,
                    tip_offset: Sequence[float] = (0.0, 0.0, 0.0),
                    where: str = 'robot') -> ChainModel:
    """Build the chain base_link → tip_link of a URDF; tool at `tip_offset` [m].

    `urdf` is the URDF's text, or what `read_urdf` made of it; its mesh filenames are
    read as paths (relative ones from the working directory). `tip_offset` is in the tip
    link's frame. Bad input raises InputError naming `<where>.file`, `<where>.base_link`
    or `<where>.tip_link`.
    """
    if not isinstance(urdf, UrdfDescription):
        urdf = read_urdf(urdf, where)
    xml = urdf.xml
    try:
        model = pin.buildModelFromXML(xml)
    except (ValueError, RuntimeError) as error:
        raise InputError(f'{where}.file', f'is not a URDF Pinocchio can read: '
                         f'{_one_line(error)}') from None
    base_link = base_link or urdf.root
    base = _body_frame(model, base_link, f'{where}.base_link')
    tip = _body_frame(model, tip_link, f'{where}.tip_link')
    if model.frames[base].parentJoint != 0:
        raise InputError(f'{where}.base_link', f'{base_link!r} moves with joint '
                         f'{model.names[model.frames[base].parentJoint]!r}: the base must be '
                         'fixed to the URDF\'s root link')
    path = _joint_path(model, model.frames[tip].parentJoint)
    if not path:
        raise InputError(f'{where}.tip_link', f'no joint moves {tip_link!r} relative to '
                         f'{base_link!r}')
    _check_chain_joints(model, path, urdf.mimics, base_link, tip_link, where)
    try:
        geometry = pin.buildGeomFromUrdfString(model, xml, pin.GeometryType.COLLISION)
    except (ValueError, RuntimeError) as error:
        raise _geometry_error(error, xml, where) from None
    model, geometry = _hold_joints_off_the_chain(model, geometry, path, where)
    chain = _chain(model, geometry, base_link, tip_link, np.asarray(tip_offset, dtype=float),
                   where)
    return chain


def _check_chain_joints(model: pin.Model, path: list[int], mimics: Sequence[tuple[str, str]],
                        base_link: str, tip_link: str, where: str) -> None:
    """Raise InputError unless the chain is short, revolute or continuous, and uncoupled."""
    if len(path) > MAX_CHAIN_JOINTS:
        raise InputError(f'{where}.tip_link', f'{len(path)} joints move {tip_link!r} relative '
                         f'to {base_link!r}: ftplan plans for chains of at most '
                         f'{MAX_CHAIN_JOINTS}; choose a tip_link (or base_link) nearer')
    for joint in path:
        kind = model.joints[joint].shortname()
        if kind not in _REVOLUTE + _CONTINUOUS:
            what = 'prismatic' if kind in _PRISMATIC else 'floating or multi-axis'
            raise InputError(f'{where}.file', f'joint {model.names[joint]!r} between '
                             f'{base_link!r} and {tip_link!r} is {what} ({kind}): only '
                             'revolute and continuous joints are supported')
    _refuse_coupled_joints(mimics, {model.names[j] for j in path}, base_link, tip_link, where)


def _hold_joints_off_the_chain(model: pin.Model, geometry: pin.GeometryModel, path: list[int],
                               where: str) -> tuple[pin.Model, pin.GeometryModel]:
    """Lock the joints off the chain at zero (Pinocchio's buildReducedModel)."""
    locked = [j for j in range(1, model.njoints) if j not in path]
    if not locked:
        return model, geometry
    try:
        return pin.buildReducedModel(model, geometry, locked, pin.neutral(model))
    except (ValueError, RuntimeError) as error:
        bodies = {frame.name for frame in model.frames if frame.type == pin.FrameType.BODY}
        clash = sorted(bodies & set(model.names[1:]))
        hint = f'; link {clash[0]!r} has the name of a joint: rename one' if clash else ''
        raise InputError(f'{where}.file', f'cannot hold the joints off the chain still: '
                         f'{_one_line(error)}{hint}') from None


def _refuse_coupled_joints(mimics: Sequence[tuple[str, str]], chain: set[str], base_link: str,
                           tip_link: str, where: str) -> None:
    """Raise InputError if a mimic joint follows a chain joint or is one itself.

    The chain's joints move independently in every step of the method, and the links
    off the chain are held still: a coupling to a chain joint would move geometry that
    the guarantee does not see.
    """
    for follower, leader in mimics:
        if follower in chain or leader in chain:
            raise InputError(f'{where}.file', f'joint {follower!r} mimics {leader!r}, and '
                             f'{follower if follower in chain else leader!r} moves the chain '
                             f'{base_link!r} -> {tip_link!r}: coupled joints are not '
                             'supported there; remove the <mimic> or choose another tip_link')


def _chain(model: pin.Model, geometry: pin.GeometryModel, base_link: str, tip_link: str,
           tip_offset: np.ndarray, where: str) -> ChainModel:
    """Read the reduced model (joints 1..n are the chain) into a ChainModel."""
    n = model.njoints - 1
    base_frame = model.frames[model.getFrameId(base_link)].placement.homogeneous
    to_base = np.linalg.inv(base_frame)
    placements = np.array([model.jointPlacements[j].homogeneous for j in range(1, n + 1)])
    placements[0] = to_base @ placements[0]
    tip = model.frames[model.getFrameId(tip_link)]
    tool = tip.placement.homogeneous.copy()
    tool[:3, 3] += tool[:3, :3] @ tip_offset
    limits = []
    for j in range(1, n + 1):
        if model.joints[j].shortname() in _CONTINUOUS:
            limits.append(None)
        else:
            k = model.joints[j].idx_q
            low, high = float(model.lowerPositionLimit[k]), float(model.upperPositionLimit[k])
            widest = 2.0 * np.pi + TURN_ROUNDING
            if not (-widest <= low < high <= widest):
                raise InputError(f'{where}.file', f'joint {model.names[j]!r} has limits '
                                 f'[{low}, {high}]: a revolute joint\'s must be an interval '
                                 'within ±2π [rad] (make it continuous to turn without limit)')
            limits.append((max(low, -2.0 * np.pi), min(high, 2.0 * np.pi)))
    shapes = []
    for item in geometry.geometryObjects:
        placement = item.placement.homogeneous
        if item.parentJoint == 0:
            placement = to_base @ placement
        link = model.frames[item.parentFrame].name
        shapes.append(LinkShape(int(item.parentJoint), _shape(item, link, where), placement,
                                link))
    link_names = [base_link] + [_child_link(model, j) for j in range(1, n + 1)]
    velocities = [float(model.velocityLimit[model.joints[j].idx_v]) for j in range(1, n + 1)]
    return ChainModel(model.name, tuple(model.names[1:n + 1]), tuple(link_names), placements,
                      _joint_axes(model, where), tool, tuple(limits), tuple(shapes),
                      tool_frame=tip_link, motion_limits=default_motion_limits(n, velocities))


def _joint_axes(model: pin.Model, where: str) -> np.ndarray:
    """Return unit axes (n, 3) of the joints in their own frames (motion subspaces).

    Raises InputError for a joint whose URDF axis is not a direction (e.g. xyz="0 0 0").
    """
    data = model.createData()
    pin.computeJointJacobians(model, data, pin.neutral(model))
    axes = []
    for j in range(1, model.njoints):
        # (6, nv); a model of one joint comes back as (6,).
        local = np.reshape(pin.getJointJacobian(model, data, j, pin.ReferenceFrame.LOCAL), (6, -1))
        axis = local[3:, model.joints[j].idx_v]
        if not abs(np.linalg.norm(axis) - 1.0) <= 1e-9:
            raise InputError(f'{where}.file', f'joint {model.names[j]!r} has the axis '
                             f'{axis.tolist()}: a revolute joint\'s axis must be a direction')
        axes.append(axis)
    return np.array(axes)


def _shape(item: pin.GeometryObject, link: str, where: str) -> Shape:
    geometry = item.geometry
    kind = type(geometry).__name__
    if kind == 'Box':
        return Shape('box', size=tuple(float(v) for v in 2.0 * np.asarray(geometry.halfSide)))
    if kind == 'Cylinder':
        return Shape('cylinder', radius=float(geometry.radius),
                     length=2.0 * float(geometry.halfLength))
    if kind == 'Capsule':
        return Shape('capsule', radius=float(geometry.radius),
                     length=2.0 * float(geometry.halfLength))
    if kind == 'Sphere':
        return Shape('sphere', radius=float(geometry.radius))
    if kind.startswith('BVHModel'):
        vertices = np.array(geometry.vertices(), dtype=float).reshape(-1, 3)
        faces = np.array([[geometry.tri_indices(k)[c] for c in range(3)]
                          for k in range(geometry.num_tris)], dtype=np.int64).reshape(-1, 3)
        return _mesh_shape(vertices, faces, f'mesh {item.meshPath} of link {link!r}', where)
    raise InputError(f'{where}.file', f'collision geometry {item.name!r} is a {kind}: '
                     'use box, cylinder, sphere, capsule or mesh')


def _mesh_shape(vertices: np.ndarray, faces: np.ndarray, name: str, where: str) -> Shape:
    """Return a mesh shape, vertices (V, 3) [m] and faces (F, 3), covered now (cover.py).

    Logs the cover's pieces and padding. InputError `<where>.file` naming the mesh
    (`name`) for a vertex that is not finite, a mesh wider than MAX_LINK_SIZE, or one
    that cannot be covered.
    """
    if not np.isfinite(vertices).all():
        raise InputError(f'{where}.file', f'{name} has a vertex that is not finite')
    size = float(np.ptp(vertices, axis=0).max()) if len(vertices) else 0.0
    if size > MAX_LINK_SIZE:
        raise InputError(f'{where}.file', f'{name} is {size:.4g} m across (at most '
                         f'{MAX_LINK_SIZE:g} m): is it in millimetres? give '
                         'scale="0.001 0.001 0.001"')
    shape = Shape('mesh', vertices=vertices, faces=faces)
    try:
        cover = shape.cover
    except ValueError as error:
        raise InputError(f'{where}.file', f'{name} {error}') from None
    logger.info('%s: %d triangles covered by %d convex piece(s), padding %.2f mm', name,
                len(faces), len(cover.pieces), 1e3 * cover.largest_padding)
    return shape


def _geometry_error(error: Exception, xml: str, where: str) -> InputError:
    """InputError `<where>.file` for Pinocchio's failure to load a URDF's collision geometry.

    A mesh file that coal cannot read (empty, truncated, not a mesh) is named with its
    link and coal's reason; Pinocchio's hint that the mesh directory may be wrong is left
    out, since core/io/mesh_files.py found the file.
    """
    found = _UNREADABLE_MESH.search(str(error))
    if found is None:
        return InputError(f'{where}.file', f'cannot load its collision geometry: '
                          f'{_one_line(error)}')
    path, reason = found.group(1).strip(), ' '.join(found.group(2).split())
    links = [link.get('name') for link in ElementTree.fromstring(xml).findall('link')
             if any(mesh.get('filename') == path
                    for mesh in link.findall('collision/geometry/mesh'))]
    owner = f'link {links[0]!r}' if links else 'a link'
    return InputError(f'{where}.file', f'{owner}: collision mesh {path} was found but could '
                      f'not be read ({reason[:200] or "no reason given"}): give an STL, OBJ or '
                      'COLLADA file')


def _body_frame(model: pin.Model, name: str, where: str) -> int:
    for k, frame in enumerate(model.frames):
        if frame.name == name and frame.type == pin.FrameType.BODY:
            return k
    links = ', '.join(f.name for f in model.frames if f.type == pin.FrameType.BODY)
    raise InputError(where, f'no link {name!r} in the URDF (links: {links})')


def _joint_path(model: pin.Model, joint: int) -> list[int]:
    """Joints from the root to `joint`, in order."""
    path = []
    while joint != 0:
        path.append(joint)
        joint = model.parents[joint]
    return path[::-1]


def _child_link(model: pin.Model, joint: int) -> str:
    """Return the link a joint moves directly (its first body frame)."""
    return next(f.name for f in model.frames
                if f.type == pin.FrameType.BODY and f.parentJoint == joint)


def _one_line(error: Exception, most: int = 300) -> str:
    """Pinocchio's message in one line of at most `most` characters.

    Its C++ errors span several lines (file, function, line, then the message): only the
    message and what follows it are kept.
    """
    text = str(error)
    if 'message:' in text:
        text = text.split('message:', 1)[1]
    text = ' '.join(text.split())
    return text if len(text) <= most else text[:most - 3] + '...'
