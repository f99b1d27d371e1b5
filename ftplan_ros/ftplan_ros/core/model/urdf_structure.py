"""A URDF's structure, checked before any C++ parser sees it.

Pinocchio (through urdfdom) trusts the tree it is given: a cycle of links made it
recurse until it crashed (SIGSEGV), and what urdfdom refuses comes back as "does not
contain a valid URDF model" without saying why. `read_urdf` checks, in this order, and
says which link or joint is wrong and what to change:

- the text, as description_xml.py reads it (at most MAX_URDF_BYTES);
- at most MAX_LINKS links, MAX_JOINTS joints and MAX_GEOMETRIES <collision> and as
  many <visual> elements (Pinocchio's geometry build grows faster than linearly with
  them: about a second for a thousand);
- names: every link and joint has one, unique among its kind;
- joints: a known type, one parent and one child, both links that exist, limits on
  revolute and prismatic joints (effort and velocity, as urdfdom wants), mimic joints
  naming another joint that is not itself a mimic;
- the tree: each link the child of at most one joint, exactly one root link (the child
  of none), no cycle;
- every number Pinocchio reads (origins, axes, limits, dynamics, inertials, geometry
  sizes, mesh scales): decimal, finite, within ±LARGEST_NUMBER, sizes >= 0, mesh scales
  nonzero (a negative one mirrors the mesh, which its cover holds as any other).

Units are those of the URDF: metres, radians, kilograms.
"""

from __future__ import annotations

import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass

from ..errors import InputError
from .description_xml import parse_description, read_numbers, serialize

MAX_URDF_BYTES = 4 * 1024 * 1024  # a real arm's URDF has tens of kB, a humanoid's hundreds
MAX_LINKS = 1000  # a dual-arm robot with two hands has a few hundred
MAX_JOINTS = 1000
MAX_GEOMETRIES = 1000  # <collision> elements, and as many <visual> ones

JOINT_TYPES = ('revolute', 'continuous', 'prismatic', 'fixed', 'floating', 'planar')
_LIMITED = ('revolute', 'prismatic')
_SHAPE_SIZES = {'box': (('size', 3),), 'cylinder': (('radius', 1), ('length', 1)),
                'sphere': (('radius', 1),), 'capsule': (('radius', 1), ('length', 1))}
# Numbers of a joint's elements that Pinocchio or urdfdom reads: (element, attribute, count).
_JOINT_NUMBERS = (('origin', 'xyz', 3), ('origin', 'rpy', 3), ('axis', 'xyz', 3),
                  ('limit', 'lower', 1), ('limit', 'upper', 1), ('limit', 'effort', 1),
                  ('limit', 'velocity', 1), ('dynamics', 'damping', 1),
                  ('dynamics', 'friction', 1), ('mimic', 'multiplier', 1),
                  ('mimic', 'offset', 1), ('safety_controller', 'soft_lower_limit', 1),
                  ('safety_controller', 'soft_upper_limit', 1),
                  ('safety_controller', 'k_position', 1), ('safety_controller', 'k_velocity', 1),
                  ('calibration', 'rising', 1), ('calibration', 'falling', 1))
# Pinocchio reads these as bounds about 0 (|v| <= max): a negative one is refused.
_NOT_NEGATIVE = ('effort', 'velocity', 'friction')
_INERTIA = ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')


@dataclass(frozen=True)
class UrdfDescription:
    """A URDF that passed `read_urdf`: its robot's name, root link, links and text.

    `xml` is the document as it was checked (comments left out), for Pinocchio.
    `mimics` pairs each joint that mimics another with the joint it follows; `joints`
    are the joints' names.
    """

    name: str
    root: str
    links: tuple[str, ...]
    xml: str
    mimics: tuple[tuple[str, str], ...] = ()
    joints: tuple[str, ...] = ()


@dataclass(frozen=True)
class _Joint:
    name: str
    parent: str
    child: str


def read_urdf(text: str, where: str = 'robot') -> UrdfDescription:
    """Check a URDF (see the module docstring); InputError `<where>.file` names the problem."""
    field = f'{where}.file'
    root = parse_description(text, field, MAX_URDF_BYTES)
    name = root.get('name')
    if root.tag != 'robot' or not name:
        raise InputError(field, f'is not a URDF: it is a <{root.tag}> element'
                         f'{" with a name" if name else " without a name"}, a URDF one '
                         '<robot name="...">')
    _check_counts(root, field)
    links = _unique_names(root.findall('link'), 'link', field)
    if not links:
        raise InputError(field, 'has no <link>: a URDF has at least one')
    joint_names = _unique_names(root.findall('joint'), 'joint', field)
    joints = [_joint(element, set(links), field) for element in root.findall('joint')]
    mimics = _mimics(root.findall('joint'), field)
    base = _root_link(links, joints, field)
    for element in root.findall('link'):
        _check_link_numbers(element, field)
    for material in root.iter('material'):
        for color in material.findall('color'):
            read_numbers(color, 'rgba', 4, field, f'material {material.get("name")!r} <color>')
    return UrdfDescription(name, base, tuple(links), serialize(root), mimics,
                           tuple(joint_names))


def _check_counts(root: ElementTree.Element, field: str) -> None:
    for tag, most in (('link', MAX_LINKS), ('joint', MAX_JOINTS)):
        count = len(root.findall(tag))
        if count > most:
            raise InputError(field, f'has {count} {tag}s, more than the {most} a robot '
                             'description may have')
    for tag in ('collision', 'visual'):
        count = len(root.findall(f'link/{tag}'))
        if count > MAX_GEOMETRIES:
            raise InputError(field, f'has {count} <{tag}> elements, more than the '
                             f'{MAX_GEOMETRIES} a robot description may have')


def _unique_names(elements: list[ElementTree.Element], kind: str, field: str) -> list[str]:
    names: list[str] = []
    seen: set[str] = set()
    for k, element in enumerate(elements):
        name = element.get('name')
        if not name:
            raise InputError(field, f'{kind} number {k + 1} has no name: give it name="..."')
        if name in seen:
            raise InputError(field, f'{kind} {name!r} is defined twice: {kind} names must be '
                             'unique')
        seen.add(name)
        names.append(name)
    return names


def _joint(element: ElementTree.Element, links: set[str], field: str) -> _Joint:
    """Check one joint's name, type, parent, child and numbers."""
    name = element.get('name') or '(no name)'
    kind = element.get('type')
    if kind not in JOINT_TYPES:
        raise InputError(field, f'joint {name!r} has type {kind!r}: use one of '
                         f'{", ".join(JOINT_TYPES)}')
    ends = {}
    for end in ('parent', 'child'):
        found = element.findall(end)
        if len(found) != 1 or not found[0].get('link'):
            raise InputError(field, f'joint {name!r} needs one <{end} link="..."/>, has '
                             f'{len(found)}{"" if len(found) != 1 else " without link="}')
        ends[end] = found[0].get('link')
        if ends[end] not in links:
            raise InputError(field, f'joint {name!r} names {end} link {ends[end]!r}, which is '
                             f'not defined: add <link name="{ends[end]}"/> or fix the name')
    if kind in _LIMITED:
        limit = element.find('limit')
        if limit is None or limit.get('effort') is None or limit.get('velocity') is None:
            raise InputError(field, f'joint {name!r} is {kind} but has no <limit> with effort '
                             'and velocity: give <limit lower= upper= effort= velocity=/>')
    for tag, attribute, count in _JOINT_NUMBERS:
        for child in element.findall(tag):
            if attribute in child.attrib:
                values = read_numbers(child, attribute, count, field, f'joint {name!r} <{tag}>')
                if attribute in _NOT_NEGATIVE and values[0] < 0.0:
                    raise InputError(field, f'joint {name!r} <{tag}> {attribute}="'
                                     f'{child.get(attribute)}" must be >= 0')
    return _Joint(name, ends['parent'], ends['child'])


def _mimics(elements: list[ElementTree.Element], field: str) -> tuple[tuple[str, str], ...]:
    """Return (follower, leader) per mimic joint, after checking that each leader leads."""
    mimics = {element.get('name'): element.find('mimic') for element in elements}
    pairs = []
    for name, mimic in mimics.items():
        if mimic is None:
            continue
        leader = mimic.get('joint')
        if leader not in mimics or leader == name:
            raise InputError(field, f'joint {name!r} mimics {leader!r}, which is not another '
                             'joint of the URDF: name the joint it follows')
        if mimics[leader] is not None:
            raise InputError(field, f'joint {name!r} mimics {leader!r}, which mimics a joint '
                             'itself: name the joint that leads')
        pairs.append((name, leader))
    return tuple(pairs)


def _root_link(links: list[str], joints: list[_Joint], field: str) -> str:
    """Return the one root link after checking that the joints make a tree of the links."""
    parent_joint: dict[str, _Joint] = {}
    for joint in joints:
        if joint.parent == joint.child:
            raise InputError(field, f'joint {joint.name!r} has link {joint.child!r} as both its '
                             'parent and its child: a joint joins two links')
        if joint.child in parent_joint:
            raise InputError(field, f'link {joint.child} has two parents (joints '
                             f'{parent_joint[joint.child].name!r} and {joint.name!r}): a URDF '
                             'is a tree, each link the child of one joint; remove one of them')
        parent_joint[joint.child] = joint
    roots = [link for link in links if link not in parent_joint]
    if len(roots) > 1:
        named = [repr(link) for link in roots[:5]]
        listed = (', '.join(named[:-1]) + f' and {named[-1]}' if len(roots) <= 5
                  else ', '.join(named) + f' and {len(roots) - 5} more')
        raise InputError(field, f'has {len(roots)} root links, {listed} (no joint has them as '
                         'its child): a URDF has one root; join the others to the tree with '
                         'joints, or remove them')
    below = {root: [] for root in links}
    for joint in joints:
        below[joint.parent].append(joint.child)
    reached = set(roots)
    stack = list(roots)
    while stack:
        for child in below[stack.pop()]:
            reached.add(child)
            stack.append(child)
    if len(reached) < len(links):
        start = next(link for link in links if link not in reached)
        raise InputError(field, _cycle(start, parent_joint))
    return roots[0]


def _cycle(start: str, parent_joint: dict[str, _Joint]) -> str:
    """Describe the cycle above `start`: a link no root reaches, so each link above has a parent."""
    path = [start]
    while parent_joint[path[-1]].parent not in path:
        path.append(parent_joint[path[-1]].parent)
    loop = path[path.index(parent_joint[path[-1]].parent):][::-1]  # parent before child
    joints = ', '.join(repr(parent_joint[link].name) for link in loop[1:] + loop[:1])
    return (f'links {" -> ".join(loop + [loop[0]])} form a cycle (joints {joints}): a URDF is '
            'a tree; remove one of those joints')


def _check_link_numbers(link: ElementTree.Element, field: str) -> None:
    """Check the numbers of a link's inertial, visual and collision elements."""
    name = link.get('name')
    for inertial in link.findall('inertial'):
        _check_origin(inertial, field, f'link {name!r} <inertial>')
        for mass in inertial.findall('mass'):
            read_numbers(mass, 'value', 1, field, f'link {name!r} <mass>')
        for inertia in inertial.findall('inertia'):
            for attribute in _INERTIA:
                read_numbers(inertia, attribute, 1, field, f'link {name!r} <inertia>')
    for tag in ('visual', 'collision'):
        for k, element in enumerate(link.findall(tag)):
            what = f'link {name!r} <{tag}> number {k + 1}'
            _check_origin(element, field, what)
            _check_geometry(element, field, what)


def _check_origin(element: ElementTree.Element, field: str, what: str) -> None:
    for origin in element.findall('origin'):
        for attribute in ('xyz', 'rpy'):
            read_numbers(origin, attribute, 3, field, f'{what} <origin>', default='0 0 0')


def _check_geometry(element: ElementTree.Element, field: str, what: str) -> None:
    """One <geometry> with one known shape, its sizes numbers >= 0."""
    geometries = element.findall('geometry')
    shapes = [] if len(geometries) != 1 else list(geometries[0])
    if len(shapes) != 1 or shapes[0].tag not in (*_SHAPE_SIZES, 'mesh'):
        raise InputError(field, f'{what} needs one <geometry> holding one box, cylinder, '
                         'sphere, capsule or mesh')
    shape = shapes[0]
    if shape.tag == 'mesh':
        if not shape.get('filename'):
            raise InputError(field, f'{what} has a <mesh> without filename=')
        scale = read_numbers(shape, 'scale', 3, field, f'{what} <mesh>', default='1 1 1')
        if 0.0 in scale:
            raise InputError(field, f'{what} <mesh> scale="{shape.get("scale")}" has a zero '
                             'value, which flattens the mesh: give each axis its factor '
                             '(1 keeps the size; a negative one mirrors)')
        return
    for attribute, count in _SHAPE_SIZES[shape.tag]:
        values = read_numbers(shape, attribute, count, field, f'{what} <{shape.tag}>')
        if min(values) < 0.0:
            raise InputError(field, f'{what} <{shape.tag}> {attribute}= has a negative value: '
                             'sizes are >= 0 [m]')
