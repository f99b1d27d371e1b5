"""Self-collision exceptions from an SRDF (MoveIt's semantic robot description).

An SRDF names links of its URDF. Its `<disable_collisions link1= link2= reason=/>`
exempt a pair of links, `<disable_default_collisions link=/>` exempts a link from every
pair and `<enable_collisions link1= link2=/>` checks a pair after all; as in MoveIt, a
pair that is both disabled and enabled is exempt. Every other element (groups, states,
end effectors, virtual joints) is left alone. A link that is not in the URDF is an
error, and so is a document over MAX_SRDF_BYTES or with more than MAX_SRDF_ENTRIES
collision entries. An SRDF whose <robot name> is not the URDF's is refused unless it names
links and every link and joint it names is the URDF's: then it is taken with a warning,
as MoveIt takes it.

The planner checks chain links, each carrying the geometry of the URDF links folded
into it (fixed joints, locked fingers: urdf.py). A pair of chain links is exempt whole
when the SRDF exempts every pair of URDF links with geometry across the two; otherwise
the pair is checked shape by shape, leaving out the shapes of the URDF links the SRDF
exempts (a UR arm's SRDF exempts wrist_2_link / wrist_3_link, but not wrist_2_link /
ee_link, folded into wrist_3_link): what the SRDF does not exempt stays checked.
"""

from __future__ import annotations

import logging
from collections.abc import Collection
from dataclasses import dataclass, replace
from itertools import combinations

from ..errors import InputError
from .chain import ChainModel
from .description_xml import parse_description

MAX_SRDF_BYTES = 4 * 1024 * 1024  # MoveIt's setup assistant writes about 100 bytes a pair
MAX_SRDF_ENTRIES = 50_000  # collision entries: a robot of a few hundred links lists thousands
# (element path, attribute) of the links and the joints an SRDF names (srdfdom's model).
_NAMED_LINKS = (('group/link', 'name'), ('group/chain', 'base_link'), ('group/chain', 'tip_link'),
                ('end_effector', 'parent_link'), ('virtual_joint', 'child_link'),
                ('disable_collisions', 'link1'), ('disable_collisions', 'link2'),
                ('enable_collisions', 'link1'), ('enable_collisions', 'link2'),
                ('disable_default_collisions', 'link'), ('link_sphere_approximation', 'link'))
_NAMED_JOINTS = (('group/joint', 'name'), ('group_state/joint', 'name'), ('passive_joint', 'name'))

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class CollisionExceptions:
    """The links an SRDF exempts from self-collision checks (URDF link names)."""

    disabled: frozenset[frozenset[str]] = frozenset()
    enabled: frozenset[frozenset[str]] = frozenset()
    no_default: frozenset[str] = frozenset()

    def exempts(self, link1: str, link2: str) -> bool:
        """Whether the pair is never checked, as MoveIt's allowed collision matrix says."""
        pair = frozenset((link1, link2))
        if pair in self.disabled:
            return True
        if pair in self.enabled:
            return False
        return link1 in self.no_default or link2 in self.no_default


def read_srdf(text: str, links: Collection[str], where: str = 'robot.srdf',
              robot_name: str | None = None, joints: Collection[str] = (),
              ) -> CollisionExceptions:
    """Read an SRDF's collision entries, checked against the URDF's `links` and name.

    InputError `where` names the entry and the link that is wrong, or the robot: an SRDF
    whose <robot name> is not the URDF's `robot_name` is taken with a warning only when
    it names links, and every link and joint it names is the URDF's (`links`, `joints`).
    """
    root = parse_description(text, where, MAX_SRDF_BYTES)
    if root.tag != 'robot':
        raise InputError(where, f'is not an SRDF: it is a <{root.tag}> element, an SRDF one '
                         '<robot>')
    if robot_name is not None and root.get('name') != robot_name:
        _check_written_for_the_urdf(root, robot_name, set(links), set(joints), where)
    tags = ('disable_collisions', 'enable_collisions', 'disable_default_collisions')
    entries = [element for element in root if element.tag in tags]
    if len(entries) > MAX_SRDF_ENTRIES:
        raise InputError(where, f'has {len(entries)} collision entries, more than the '
                         f'{MAX_SRDF_ENTRIES} an SRDF may have')
    known = set(links)
    pairs: dict[str, set[frozenset[str]]] = {'disable_collisions': set(),
                                             'enable_collisions': set()}
    no_default = set()
    for k, element in enumerate(entries):
        what = f'<{element.tag}> number {k + 1}'
        attributes = ('link',) if element.tag == 'disable_default_collisions' else (
            'link1', 'link2')
        names = [_link(element, attribute, known, where, what) for attribute in attributes]
        if element.tag == 'disable_default_collisions':
            no_default.add(names[0])
        else:
            pairs[element.tag].add(frozenset(names))
    return CollisionExceptions(frozenset(pairs['disable_collisions']),
                               frozenset(pairs['enable_collisions']), frozenset(no_default))


def _check_written_for_the_urdf(root, robot_name: str, links: set[str], joints: set[str],
                                where: str) -> None:
    """Warn of an SRDF named for another robot whose names all are the URDF's; else refuse.

    MoveIt (srdfdom) only warns on the name: example-robot-data's z1 SRDF says 'z1' for
    the URDF 'z1_description'. An SRDF that names no link shows nothing of its robot.
    """
    virtual = {element.get('name') for element in root.findall('virtual_joint')}
    named = [('link', element.get(attribute)) for path, attribute in _NAMED_LINKS
             for element in root.findall(path) if element.get(attribute)]
    named += [('joint', element.get(attribute)) for path, attribute in _NAMED_JOINTS
              for element in root.findall(path)
              if element.get(attribute) and element.get(attribute) not in virtual]
    missing = [f'{kind} {name!r}' for kind, name in named
               if name not in (links if kind == 'link' else joints)]
    written_for = f'is written for robot {root.get("name")!r}, the URDF describes {robot_name!r}'
    if missing:
        raise InputError(where, f'{written_for}, and it names {missing[0]}, which the URDF '
                         'does not have: give the SRDF of this robot')
    if not any(kind == 'link' for kind, _ in named):
        raise InputError(where, f'{written_for}, and it names none of its links: give the '
                         'SRDF of this robot')
    logger.warning('%s %s; every link and joint it names is the URDF\'s: it is taken, as '
                   'MoveIt takes it', where, written_for)


def _link(element, attribute: str, known: set[str], where: str, what: str) -> str:
    name = element.get(attribute)
    if not name:
        raise InputError(where, f'{what} has no {attribute}=: name a link of the URDF')
    if name not in known:
        raise InputError(where, f'{what} names link {name!r}, which the URDF does not have: '
                         'the SRDF must be written for this URDF')
    return name


def with_exceptions(model: ChainModel, exceptions: CollisionExceptions) -> ChainModel:
    """Return the model with the SRDF's exceptions: chain pairs exempt whole, URDF pairs."""
    links = sorted({item.urdf_link for item in model.shapes})
    exempt = frozenset(frozenset((x, y)) for x, y in combinations(links, 2)
                       if exceptions.exempts(x, y))
    return replace(model, disabled_pairs=chain_exceptions(model, exceptions),
                   exempt_urdf_pairs=exempt)


def chain_exceptions(model: ChainModel, exceptions: CollisionExceptions,
                     ) -> frozenset[tuple[int, int]]:
    """Return the chain's link pairs (a, b), a < b, that the SRDF exempts whole.

    A chain link's geometry comes from the URDF links named in its shapes' `urdf_link`;
    a pair is exempt when every pair of those across the two links is.
    """
    sources: dict[int, set[str]] = {}
    for item in model.shapes:
        sources.setdefault(item.link, set()).add(item.urdf_link)
    return frozenset(
        (a, b) for a, b in combinations(sorted(sources), 2)
        if all(exceptions.exempts(x, y) for x in sources[a] for y in sources[b]))
