"""Robot descriptions for the tests and benchmarks: the Panda's URDF altered, big URDFs,
and hypothesis strategies that draw URDFs and SRDFs, mostly broken.

The strategies draw link and joint names from a few letters, so that names repeat and
joints join links into trees, forests and cycles; numbers are decimal or not, finite or
not, small or huge; elements are missing, repeated, unknown or nested deep; a few
documents are hostile XML (entity expansion, truncation). Two thirds of the documents
carry no fault, so that Pinocchio gets to build robots.
"""

from __future__ import annotations

import random
from pathlib import Path

from hypothesis import strategies as st

REPO = Path(__file__).resolve().parents[1]
PANDA_URDF = REPO / 'config' / 'robots' / 'panda.urdf'
PANDA_SRDF = REPO / 'config' / 'robots' / 'panda.srdf'
# The cycle: panda_link2 becomes the child of panda_link7 too.
CYCLE_JOINT = ('<joint name="cyc" type="fixed"><parent link="panda_link7"/>'
               '<child link="panda_link2"/></joint>')


def panda_with(elements: str) -> str:
    """The Panda's URDF with `elements` (XML text) added at the end of <robot>."""
    return PANDA_URDF.read_text().replace('</robot>', f'{elements}\n</robot>')


def heavy_panda(extra_links: int, gazebo_tags: int = 0) -> str:
    """The Panda with `extra_links` more links, each on a revolute joint, and Gazebo tags.

    The extra links hang in rows of ten off panda_link0, 2 m away (so they never touch
    the arm), each with an inertial, a visual and a collision box; the arm's chain stays
    the same (its joints are those of the Panda, the others are locked). With 960 links
    and 6000 tags the text is about 1.1 MB and takes about as long to build as the
    largest URDF the bounds allow.
    """
    box = '<geometry><box size="0.01 0.01 0.01"/></geometry>'
    parts = []
    for k in range(extra_links):
        parent = 'panda_link0' if k % 10 == 0 else f'extra{k - 1}'
        parts.append(
            f'<link name="extra{k}"><inertial><origin xyz="0 0 0" rpy="0 0 0"/>'
            '<mass value="0.1"/><inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" '
            f'izz="0.001"/></inertial><visual><origin xyz="0 0 0.01"/>{box}</visual>'
            f'<collision><origin xyz="0 0 0.01"/>{box}</collision></link>\n'
            f'<joint name="extra_joint{k}" type="revolute"><parent link="{parent}"/>'
            f'<child link="extra{k}"/><origin xyz="2 0 0"/><axis xyz="0 0 1"/>'
            '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>\n')
    for k in range(gazebo_tags):
        parts.append(f'<gazebo reference="extra{k % max(extra_links, 1)}"><mu1>0.2</mu1>'
                     '<mu2>0.2</mu2><selfCollide>false</selfCollide></gazebo>\n')
    return panda_with(''.join(parts))


# Random documents ---------------------------------------------------------------------
# Drawn from a random.Random: hypothesis draws its seed (`urdf_documents`), a benchmark
# can seed it by case number; a hypothesis draw per number was a hundred times slower.

NAMES = ('a', 'b', 'c', 'd', 'e', 'f')
BAD_NUMBERS = ('nan', 'inf', '-inf', 'NaN', '1e400', '-1e309', '1e7', '2e6', '1_0', '0x10', '',
               'abc', '1,5', '+-1', '1e', '.', '\u0661', '1e-400', '-0', '9' * 40)
# The ways a URDF is broken; a document has none (a third of them), one or two.
URDF_FAULTS = ('names', 'cycle', 'second-root', 'missing-link', 'numbers', 'vector-sizes',
               'joint-types', 'limits', 'mimic', 'geometry', 'odd-elements', 'robot-tag', 'xml')
SRDF_FAULTS = ('links', 'attributes', 'tags', 'odd-elements', 'robot-tag', 'xml')
MESHES = ('tet.stl', 'tet.stl', 'missing.stl', 'garbage.stl')  # next to the test's URDF
HOSTILE_XML = ('<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY a "aaaaaaaaaa">'
               '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
               '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;">]>'
               '<robot name="&c;"><link name="a"/></robot>')


def _attributes(values: dict) -> str:
    return ''.join(f' {key}="{value}"' for key, value in values.items() if value is not None)


class _Parts:
    """Draws the parts of one document from `rng`, broken where its faults say."""

    def __init__(self, rng: random.Random, faults: tuple[str, ...]):
        self.rng = rng
        self.faults = rng.choice([(), (), (), (), rng.sample(faults, 1), rng.sample(faults, 2)])

    def sometimes(self, fault: str, one_in: int = 3) -> bool:
        """Whether to break this part: only under `fault`, one time in `one_in`."""
        return fault in self.faults and self.rng.randrange(one_in) == 0

    def number(self, sign: str = '') -> str:
        """A decimal number; of `sign` '+' or '-' (a size, a bound) unless it is broken."""
        rng = self.rng
        if self.sometimes('numbers'):
            return rng.choice(BAD_NUMBERS)
        if sign:
            return f'{sign}{rng.uniform(0.01, 0.5):.3g}'
        return rng.choice([str(rng.randint(-3, 3)), f'{rng.uniform(-2.0, 2.0):.4g}',
                           f'{rng.uniform(-1.0, 1.0) * 10.0 ** rng.randint(-300, 0):.4g}'])

    def vector(self, size: int, sign: str = '') -> str:
        count = size + (self.rng.choice([-1, 1]) if self.sometimes('vector-sizes') else 0)
        return ' '.join(self.number(sign) for _ in range(count))

    def origin(self) -> str:
        if self.rng.random() < 0.5:
            return ''
        return f'<origin{_attributes({"xyz": self.vector(3), "rpy": self.vector(3)})}/>'

    def geometry(self) -> str:
        kinds = ['box', 'cylinder', 'sphere', 'capsule', 'mesh']
        if self.sometimes('geometry', 2):
            kinds = ['cone', 'none', 'two', 'mesh-without-file']
        kind = self.rng.choice(kinds)
        if kind == 'box':
            shape = f'<box size="{self.vector(3, "+")}"/>'
        elif kind in ('cylinder', 'capsule'):
            shape = f'<{kind} radius="{self.number("+")}" length="{self.number("+")}"/>'
        elif kind == 'sphere':
            shape = f'<sphere radius="{self.number("+")}"/>'
        elif kind == 'mesh':
            shape = f'<mesh filename="{self.rng.choice(MESHES)}" scale="{self.vector(3, "+")}"/>'
        else:
            shape = {'cone': '<cone radius="1"/>', 'none': '', 'mesh-without-file': '<mesh/>',
                     'two': '<sphere radius="0.1"/><box size="0.1 0.1 0.1"/>'}[kind]
        return f'<geometry>{shape}</geometry>'

    def link(self, name: str | None) -> str:
        body = []
        if self.rng.random() < 0.5:
            inertia = _attributes({key: self.number('+' if key[1] == key[2] else '')
                                   for key in ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')})
            body.append(f'<inertial>{self.origin()}<mass value="{self.number("+")}"/>'
                        f'<inertia{inertia}/></inertial>')
        for _ in range(self.rng.randint(0, 3)):
            tag = self.rng.choice(['collision', 'visual'])
            body.append(f'<{tag}>{self.origin()}{self.geometry()}</{tag}>')
        return f'<link{_attributes({"name": name})}>{"".join(body)}</link>'

    def joint(self, name: str, parent: str | None, child: str | None,
              joint_names: list[str]) -> str:
        rng = self.rng
        kind = rng.choice(['ball', '', 'REVOLUTE'] if self.sometimes('joint-types', 4) else
                          ['revolute'] * 4 + ['continuous', 'prismatic', 'fixed', 'floating',
                                              'planar'])
        body = [self.origin()]
        for end, link in (('parent', parent), ('child', child)):
            if link is not None:
                body.append(f'<{end} link="{link}"/>')
        body.append(f'<axis xyz="{self.vector(3)}"/>')
        limits = {'lower': self.number('-'), 'upper': self.number('+'),
                  'effort': self.number('+'), 'velocity': self.number('+')}
        if self.sometimes('limits', 2):
            limits[rng.choice(sorted(limits))] = None
        if not self.sometimes('limits', 2):
            body.append(f'<limit{_attributes(limits)}/>')
        if self.sometimes('mimic', 2):
            body.append(f'<mimic joint="{rng.choice(joint_names + ["nope"])}" '
                        f'multiplier="{self.number()}"/>')
        if rng.random() < 0.2:
            body.append(f'<dynamics damping="{self.number("+")}" '
                        f'friction="{self.number("+")}"/>')
        return f'<joint{_attributes({"name": name, "type": kind})}>{"".join(body)}</joint>'

    def odd_elements(self) -> str:
        """Tags URDF parsers do not know, nested up to 40 deep, with text."""
        rng = self.rng
        depth = rng.choice([1, 2, 5, 31, 40])
        tag = rng.choice(['gazebo', 'transmission', 'foo', 'ros2_control'])
        text = rng.choice(['', 'text', '&amp;', '<![CDATA[<a>]]>'])
        return f'<{tag}>' * depth + text + f'</{tag}>' * depth

    def document(self, elements: list[str], robots: list[str]) -> str:
        """<robot> around the elements in a random order, or (under 'xml') worse."""
        self.rng.shuffle(elements)
        robot = self.rng.choice(robots) if self.sometimes('robot-tag', 1) else '<robot name="x">'
        text = robot + ''.join(elements) + f'</{robot[1:].split()[0].rstrip(">")}>'
        if not self.sometimes('xml', 1):
            return text
        return self.rng.choice([text[:len(text) // 2], HOSTILE_XML, text.replace('>', '', 1),
                                text + '<x/>'])


def random_urdf(rng: random.Random) -> str:
    """A URDF text: a random tree of one to six links, broken in none, one or two ways.

    Meshes are named by file name only (MESHES): put them beside it (`mesh_dirs`).
    """
    parts = _Parts(rng, URDF_FAULTS)
    names = rng.sample(NAMES, rng.randint(1, 6))
    link_names: list[str | None] = list(names)
    if parts.sometimes('names', 1):  # a link named twice, or not at all
        link_names.append(rng.choice([*NAMES, None]))
    pairs = [(rng.choice(names[:k]), names[k]) for k in range(1, len(names))]
    if parts.sometimes('cycle', 1):  # a second parent, or a cycle
        pairs.append((rng.choice(NAMES), rng.choice(NAMES)))
    if pairs and parts.sometimes('second-root', 1):
        pairs.pop(rng.randrange(len(pairs)))
    joint_names = [f'j{k}' for k in range(len(pairs))]
    if len(joint_names) > 1 and parts.sometimes('names', 2):
        joint_names[-1] = joint_names[0]
    elements = [parts.link(name) for name in link_names]
    for name, (parent, child) in zip(joint_names, pairs, strict=True):
        ends = [parent, child]
        if parts.sometimes('missing-link', 2):
            ends[rng.randrange(2)] = rng.choice([None, 'nowhere'])
        elements.append(parts.joint(name, *ends, joint_names))
    if parts.sometimes('odd-elements', 1):
        elements.append(parts.odd_elements())
    return parts.document(elements, ['<robot>', '<robt name="x">', '<robot name="">'])


def random_srdf(rng: random.Random, link_names: list[str]) -> str:
    """An SRDF text for a URDF of `link_names`: collision entries, broken or not."""
    parts = _Parts(rng, SRDF_FAULTS)
    known = list(link_names) or ['nowhere']
    entries = []
    for _ in range(rng.randint(0, 6)):
        tag = rng.choice(['disable_collisions'] * 4 + ['enable_collisions',
                                                       'disable_default_collisions'])
        if parts.sometimes('tags'):
            tag = rng.choice(['group', 'foo', 'disable_collision'])
        names = {'link1': rng.choice(known), 'link2': rng.choice(known)}
        if parts.sometimes('links'):
            names[rng.choice(['link1', 'link2'])] = 'nowhere'
        if parts.sometimes('attributes'):
            names[rng.choice(['link1', 'link2'])] = rng.choice([None, ''])
        if tag == 'disable_default_collisions':
            names = {'link': names['link1']}
        reason = rng.choice(['Adjacent', 'Never', 'Default', None])
        entries.append(f'<{tag}{_attributes({**names, "reason": reason})}/>')
    if parts.sometimes('odd-elements', 1):
        entries.append(parts.odd_elements())
    return parts.document(entries, ['<robot>', '<srdf>'])


SEEDS = st.integers(0, 2**64 - 1)


def urdf_documents() -> st.SearchStrategy[str]:
    """Hypothesis: `random_urdf` texts (a failing example prints the text)."""
    return SEEDS.map(lambda seed: random_urdf(random.Random(seed)))


def srdf_documents(link_names: list[str]) -> st.SearchStrategy[str]:
    """Hypothesis: `random_srdf` texts for a URDF of `link_names`."""
    return SEEDS.map(lambda seed: random_srdf(random.Random(seed), link_names))
