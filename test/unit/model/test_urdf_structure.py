"""URDFs refused before Pinocchio sees them: one line naming the link or joint, and the bounds.

Pinocchio crashed (SIGSEGV) on a cycle of links and said "does not contain a valid URDF
model" for the rest; each case here names what is wrong instead.
"""

import re
from collections import Counter

import numpy as np
import pytest
from descriptions import CYCLE_JOINT, HOSTILE_XML, PANDA_URDF, panda_with, urdf_documents
from ftplan_testing import TETRAHEDRON, bot_urdf, write_binary_stl
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.mesh_files import with_mesh_files
from ftplan_ros.core.io.scene_file import robot_from_urdf
from ftplan_ros.core.model.description_xml import MAX_DEPTH, MAX_ELEMENTS
from ftplan_ros.core.model.urdf import chain_from_urdf
from ftplan_ros.core.model.urdf_structure import (
    MAX_GEOMETRIES,
    MAX_JOINTS,
    MAX_LINKS,
    MAX_URDF_BYTES,
    read_urdf,
)

LINKS = '<link name="a"/><link name="b"/><link name="c"/>'


def robot(body: str, name: str = 'r') -> str:
    return f'<robot name="{name}">{body}</robot>'


def joint(name: str, parent: str, child: str, kind: str = 'fixed', extra: str = '') -> str:
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/>{extra}</joint>')


LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def arm(extra: str = '', axis: str = '0 0 1', limit: str = LIMIT) -> str:
    """Links a, b, c joined by two revolute joints, with `extra` inside joint j1."""
    return robot(LINKS + joint('j1', 'a', 'b', 'revolute', f'<axis xyz="{axis}"/>{limit}{extra}')
                 + joint('j2', 'b', 'c', 'revolute', f'<axis xyz="0 1 0"/>{LIMIT}'))


def link_with(element: str) -> str:
    return robot(f'<link name="a">{element}</link>')


BAD = {
    # The tree
    'second-parent-cycle': (panda_with(CYCLE_JOINT), r"link panda_link2 has two parents "
                            r"\(joints 'panda_joint2' and 'cyc'\)"),
    'cycle': (robot('<link name="r"/>' + LINKS + joint('j0', 'r', 'a') + joint('j1', 'b', 'c')
                    + joint('j2', 'c', 'b')),
              r"links c -> b -> c form a cycle \(joints 'j2', 'j1'\)"),
    'cycle-without-root': (robot(LINKS + joint('j1', 'a', 'b') + joint('j2', 'b', 'c')
                                 + joint('j3', 'c', 'a')),
                           r"links b -> c -> a -> b form a cycle \(joints 'j2', 'j3', 'j1'\)"),
    'joint-onto-itself': (robot(LINKS + joint('j1', 'a', 'a')),
                          "joint 'j1' has link 'a' as both its parent and its child"),
    'two-roots': (robot(LINKS + joint('j1', 'a', 'b')),
                  "has 2 root links, 'a' and 'c' .no joint has them as its child"),
    'many-roots': (robot(''.join(f'<link name="l{k}"/>' for k in range(8))),
                   "has 8 root links, 'l0', 'l1', 'l2', 'l3', 'l4' and 3 more"),
    'no-link': (robot(''), 'has no <link>'),
    'missing-child': (robot(LINKS + joint('j1', 'a', 'x')),
                      "joint 'j1' names child link 'x', which is not defined"),
    'missing-parent': (robot(LINKS + joint('j1', 'x', 'a')),
                       "joint 'j1' names parent link 'x', which is not defined"),
    'no-parent': (robot(LINKS + '<joint name="j1" type="fixed"><child link="b"/></joint>'),
                  r"joint 'j1' needs one <parent link=\"...\"/>, has 0"),
    'two-children': (robot(LINKS + '<joint name="j1" type="fixed"><parent link="a"/>'
                           '<child link="b"/><child link="c"/></joint>'),
                     r"joint 'j1' needs one <child link=\"...\"/>, has 2"),
    # Names
    'duplicate-link': (robot(LINKS + '<link name="b"/>' + joint('j1', 'a', 'b')),
                       "link 'b' is defined twice"),
    'duplicate-joint': (robot(LINKS + joint('j1', 'a', 'b') + joint('j1', 'a', 'c')),
                        "joint 'j1' is defined twice"),
    'nameless-link': (robot('<link name="a"/><link/>'), 'link number 2 has no name'),
    'nameless-robot': ('<robot><link name="a"/></robot>', 'is not a URDF'),
    # Joints
    'unknown-type': (robot(LINKS + joint('j1', 'a', 'b', 'ball')),
                     "joint 'j1' has type 'ball': use one of revolute"),
    'revolute-without-limit': (arm(limit=''), "joint 'j1' is revolute but has no <limit>"),
    'limit-without-effort': (arm(limit='<limit lower="0" upper="1" velocity="1"/>'),
                             "joint 'j1' is revolute but has no <limit> with effort"),
    'negative-velocity': (arm(limit='<limit lower="0" upper="1" effort="1" velocity="-1"/>'),
                          "joint 'j1' <limit> velocity=\"-1\" must be >= 0"),
    'mimic-of-nothing': (arm('<mimic joint="nope"/>'), "joint 'j1' mimics 'nope', which is not"),
    'mimic-of-itself': (arm('<mimic joint="j1"/>'), "joint 'j1' mimics 'j1', which is not"),
    'mimic-of-a-mimic': (robot(LINKS + joint('j1', 'a', 'b', 'continuous', '<mimic joint="j2"/>')
                               + joint('j2', 'b', 'c', 'continuous', '<mimic joint="j1"/>')),
                         "joint 'j1' mimics 'j2', which mimics a joint itself"),
    # Numbers
    'nan': (arm(axis='0 nan 1'), r"joint 'j1' <axis> xyz=\"0 nan 1\": 'nan' is not a decimal"),
    'inf': (arm(limit='<limit lower="-inf" upper="1" effort="1" velocity="1"/>'),
            "'-inf' is not a decimal number"),
    'overflow': (arm('<origin xyz="1e400 0 0"/>'), r'1e400 is not within ±1e\+06'),
    'huge': (arm('<origin xyz="0 2e6 0"/>'), r'2e6 is not within ±1e\+06'),
    'digit-separator': (arm('<origin rpy="1_0 0 0"/>'), "'1_0' is not a decimal number"),
    'two-values': (arm('<origin xyz="0 1"/>'), r'xyz="0 1" needs 3 numbers, got 2'),
    'inertia-nan': (link_with('<inertial><mass value="1"/><inertia ixx="nan" ixy="0" ixz="0" '
                              'iyy="1" iyz="0" izz="1"/></inertial>'),
                    r"link 'a' <inertia> ixx=\"nan\""),
    'mass-missing': (link_with('<inertial><mass/></inertial>'),
                     "link 'a' <mass> has no value="),
    'color': (robot('<material name="m"><color rgba="1 0 0"/></material><link name="a"/>'),
              r"material 'm' <color> rgba=\"1 0 0\" needs 4 numbers"),
    # Geometry
    'negative-box': (link_with('<collision><geometry><box size="1 -1 1"/></geometry></collision>'),
                     "link 'a' <collision> number 1 <box> size= has a negative value"),
    'infinite-radius': (link_with('<visual><geometry><sphere radius="inf"/></geometry></visual>'),
                        "link 'a' <visual> number 1 <sphere> radius=\"inf\""),
    'no-geometry': (link_with('<collision><origin xyz="0 0 0"/></collision>'),
                    "link 'a' <collision> number 1 needs one <geometry>"),
    'unknown-shape': (link_with('<visual><geometry><cone radius="1"/></geometry></visual>'),
                      "link 'a' <visual> number 1 needs one <geometry> holding one box"),
    'mesh-without-file': (link_with('<collision><geometry><mesh/></geometry></collision>'),
                          'has a <mesh> without filename='),
    'mesh-scale': (link_with('<collision><geometry><mesh filename="m.stl" scale="1 1"/>'
                             '</geometry></collision>'), r'scale="1 1" needs 3 numbers'),
    'mesh-scale-zero': (link_with('<collision><geometry><mesh filename="m.stl" scale="0 0 0"/>'
                                  '</geometry></collision>'),
                        r"link 'a' <collision> number 1 <mesh> scale=\"0 0 0\" has a zero value"),
    'mesh-scale-one-zero': (link_with('<visual><geometry><mesh filename="m.stl" '
                                      'scale="1 -0.0 1"/></geometry></visual>'),
                            r"link 'a' <visual> number 1 <mesh> scale=\"1 -0.0 1\" has a zero"),
    # The text
    'not-xml': ('<robot name="r"><link name="a"></robot>', 'is not valid XML'),
    'entities': (HOSTILE_XML, 'has a DOCTYPE'),
    'deep': (robot('<link name="a"/>' + '<g>' * MAX_DEPTH + '</g>' * MAX_DEPTH),
             f'nests <g> deeper than {MAX_DEPTH} elements'),
}


@pytest.mark.parametrize('name', sorted(BAD))
def test_a_bad_urdf_is_one_line_naming_what_to_change(name):
    xml, words = BAD[name]
    with pytest.raises(InputError) as error:
        read_urdf(xml)
    message = str(error.value)
    assert error.value.field == 'robot.file'
    assert '\n' not in message
    assert re.search(words, message), message


def test_the_cycle_goes_through_robot_from_urdf_with_its_callers_name():
    with pytest.raises(InputError, match=r'^arm\.file: link panda_link2 has two parents'):
        read_urdf(panda_with(CYCLE_JOINT), where='arm')
    with pytest.raises(InputError, match='link panda_link2 has two parents'):
        robot_from_urdf(panda_with(CYCLE_JOINT), 'panda_hand_tcp', 'panda_link0')


def test_the_robots_urdfs_pass_with_their_root_and_links():
    panda = read_urdf(PANDA_URDF.read_text())
    assert (panda.name, panda.root, len(panda.links)) == ('panda', 'panda_link0', 13)
    assert 'panda_leftfinger' in panda.links
    bot = read_urdf(bot_urdf())
    assert bot.root == 'base' and bot.links[-1] == 'finger'
    assert read_urdf(bot.xml) == bot  # the text Pinocchio reads is the one checked


def many_links(count: int, collisions: int = 0, visuals: int = 0) -> str:
    shape = '<geometry><sphere radius="0.1"/></geometry>'
    geometry = (f'<collision>{shape}</collision>' * collisions
                + f'<visual>{shape}</visual>' * visuals)
    links = [f'<link name="l{k}">{geometry}</link>' for k in range(count)]
    joints = [joint(f'j{k}', 'l0', f'l{k}') for k in range(1, count)]
    return robot(''.join(links + joints))


@pytest.mark.parametrize('xml, words', [
    pytest.param(many_links(MAX_LINKS + 1), f'has {MAX_LINKS + 1} links, more than the '
                 f'{MAX_LINKS}', id='links'),
    pytest.param(robot('<link name="a"/>' + '<joint/>' * (MAX_JOINTS + 1)),
                 f'has {MAX_JOINTS + 1} joints', id='joints'),
    pytest.param(many_links(MAX_GEOMETRIES // 2 + 1, collisions=2),
                 f'has {MAX_GEOMETRIES + 2} <collision> elements', id='collisions'),
    pytest.param(many_links(MAX_GEOMETRIES // 4 + 1, visuals=4),
                 f'has {MAX_GEOMETRIES + 4} <visual> elements', id='visuals'),
    pytest.param(robot('<link name="a"/>' + '<g/>' * MAX_ELEMENTS),
                 f'more than {MAX_ELEMENTS} XML elements', id='elements'),
    pytest.param(robot('<link name="a"/>' + ' ' * MAX_URDF_BYTES),
                 f'has at least {MAX_URDF_BYTES + 40} bytes, more than the {MAX_URDF_BYTES}',
                 id='bytes'),
    pytest.param(robot('<link name="a"/>' + '\u00e9' * (MAX_URDF_BYTES // 2)),  # 2 bytes each
                 f'has {MAX_URDF_BYTES + 40} bytes', id='utf8-bytes'),
])
def test_descriptions_beyond_the_bounds_are_refused(xml, words):
    with pytest.raises(InputError, match='^robot.file: ') as error:
        read_urdf(xml)
    assert words in str(error.value)


def test_the_bounds_leave_room_for_a_robot_with_hundreds_of_links():
    description = read_urdf(many_links(MAX_LINKS, collisions=1, visuals=1))
    assert len(description.links) == MAX_LINKS


def test_entity_expansion_is_refused_at_the_doctype():
    """A billion laughs: nine levels of ten entities (gigabytes once expanded)."""
    levels = ''.join(f'<!ENTITY e{k} "{f"&e{k - 1};" * 10}">' for k in range(1, 10))
    bomb = (f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY e0 "lol">{levels}]>'
            '<robot name="&e9;"><link name="a"/></robot>')
    with pytest.raises(InputError, match='has a DOCTYPE: a robot description needs none'):
        read_urdf(bomb)
    with pytest.raises(InputError, match='has a DOCTYPE'):
        read_urdf('<!DOCTYPE robot SYSTEM "file:///etc/passwd"><robot name="r"/>')


# Fuzzing: any text is a chain or an InputError naming a field --------------------------

PROPERTY = settings(max_examples=300, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow])


@pytest.fixture(scope='module')
def meshes(tmp_path_factory):
    """A folder with the meshes the drawn URDFs name (descriptions.MESHES)."""
    folder = tmp_path_factory.mktemp('meshes')
    write_binary_stl(folder / 'tet.stl', *TETRAHEDRON)
    (folder / 'garbage.stl').write_bytes(b'solid \x00\xff not a mesh\n' * 7)
    return folder


def test_any_urdf_text_is_a_chain_or_an_input_error_naming_its_field(meshes):
    """Random trees with cycles, second parents and roots, repeated and missing names, odd
    numbers, tags and nesting, hostile XML. Pinocchio builds only what read_urdf accepts."""
    seen = Counter()

    @PROPERTY
    @given(urdf_documents(), st.data())
    def check(text, data):
        try:
            description = read_urdf(text)
        except InputError as error:
            assert error.field == 'robot.file' and '\n' not in str(error)
            seen['refused'] += 1
            return
        tip = data.draw(st.sampled_from(description.links))
        try:
            chain = chain_from_urdf(with_mesh_files(description, mesh_dirs=[meshes]), tip)
        except InputError as error:
            assert error.field in ('robot.file', 'robot.tip_link'), str(error)
            seen['no chain'] += 1
            return
        assert chain.n_joints >= 1 and chain.tool_frame == tip
        assert np.all(np.isfinite(chain.placements)) and np.all(np.isfinite(chain.axes))
        seen['chain'] += 1

    check()
    assert min(seen['refused'], seen['no chain'], seen['chain']) >= 30, seen
