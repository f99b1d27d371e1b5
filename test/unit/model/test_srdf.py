"""Self-collision exceptions from an SRDF: read as MoveIt reads them, checked against the URDF,
and never exempting a chain link pair the SRDF does not exempt whole."""

import itertools
import logging

import numpy as np
import pytest
import yaml
from descriptions import HOSTILE_XML, PANDA_SRDF, PANDA_URDF, srdf_documents
from ftplan_testing import CAD_ARM, CAD_ARM_SRDF, ROBOTS, robot_config
from hypothesis import given, settings

from ftplan_ros.core import CollisionChecker
from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.scene_file import load_scene, robot_from_urdf
from ftplan_ros.core.model.srdf import (
    MAX_SRDF_BYTES,
    MAX_SRDF_ENTRIES,
    CollisionExceptions,
    chain_exceptions,
    read_srdf,
)
from ftplan_ros.core.model.urdf_structure import read_urdf

PANDA_LINKS = read_urdf(PANDA_URDF.read_text()).links
HAND = ('panda_hand', 'panda_leftfinger', 'panda_rightfinger')  # ride on panda_link7


def srdf(*entries: str) -> str:
    return f'<robot name="panda">{"".join(entries)}</robot>'


def disable(a: str, b: str, reason: str = 'Never') -> str:
    return f'<disable_collisions link1="{a}" link2="{b}" reason="{reason}"/>'


def panda_arm(*entries: str):
    return robot_from_urdf(PANDA_URDF.read_text(), 'panda_hand_tcp', 'panda_link0',
                           srdf=srdf(*entries))


def test_the_panda_srdf_gives_the_pairs_of_panda_yaml():
    listed = robot_config('panda').model.disabled_pairs
    arm = panda_arm(*[line for line in PANDA_SRDF.read_text().splitlines()
                      if '<disable_collisions' in line])
    assert arm.model.disabled_pairs == listed and len(listed) == 17


def test_a_robot_yaml_takes_srdf_relative_to_itself(tmp_path):
    robot = yaml.safe_load((ROBOTS / 'panda.yaml').read_text())['robot']
    del robot['disabled_collisions']
    robot.update(file=str(PANDA_URDF), srdf=str(PANDA_SRDF.relative_to(ROBOTS.parent)),
                 joint_limits=str(ROBOTS / robot['joint_limits']))
    (tmp_path / 'robots').mkdir()
    (tmp_path / 'robots' / 'arm.yaml').write_text(yaml.safe_dump({'robot': robot}))
    (tmp_path / 'scene.yaml').write_text('robot: robots/arm.yaml\n')
    with pytest.raises(InputError, match=r"robot.srdf: cannot read panda.srdf"):
        load_scene(tmp_path / 'scene.yaml')
    (tmp_path / 'robots' / 'arm.srdf').write_text(PANDA_SRDF.read_text())
    robot['srdf'] = 'arm.srdf'
    (tmp_path / 'robots' / 'arm.yaml').write_text(yaml.safe_dump({'robot': robot}))
    assert (load_scene(tmp_path / 'scene.yaml').robot.model.disabled_pairs
            == robot_config('panda').model.disabled_pairs)


def test_srdf_and_disabled_collisions_together_are_refused(tmp_path):
    robot = yaml.safe_load((ROBOTS / 'panda.yaml').read_text())['robot']
    robot.update(file=str(PANDA_URDF), srdf=str(PANDA_SRDF),
                 joint_limits=str(ROBOTS / robot['joint_limits']))
    (tmp_path / 'scene.yaml').write_text(yaml.safe_dump({'robot': robot}))
    with pytest.raises(InputError, match='robot.srdf: and robot.disabled_collisions both give '
                       'the self-collision exceptions: keep one of them'):
        load_scene(tmp_path / 'scene.yaml')


def test_a_chain_pair_is_exempt_only_when_every_folded_link_pair_is():
    """panda_link7 carries the hand and fingers: exempting link6-link7 alone leaves the hand
    checked against link6, so the pair of chain links stays checked."""
    assert (6, 7) not in panda_arm(disable('panda_link6', 'panda_link7')).model.disabled_pairs
    every = [disable('panda_link6', link) for link in ('panda_link7',) + HAND]
    assert (6, 7) in panda_arm(*every).model.disabled_pairs
    assert (6, 7) not in panda_arm(*every[:-1]).model.disabled_pairs
    # Links without geometry (link8, the TCP) need no entry; pairs on one chain link are moot.
    arm = panda_arm(*every, disable('panda_link8', 'panda_link6'), disable('panda_hand',
                                                                         'panda_link7'))
    assert arm.model.disabled_pairs == {(6, 7)}


# The CAD arm with a cap on the side of `fore` (folded into it), which its SRDF does not name.
CAPPED_CAD_ARM = CAD_ARM.replace('<link name="hand">', """<joint name="cap_joint" type="fixed">
    <parent link="fore"/><child link="cap"/><origin xyz="0.06 0 0.15"/>
  </joint>
  <link name="cap">
    <collision><geometry><box size="0.02 0.02 0.02"/></geometry></collision>
  </link>
  <link name="hand">""")


def test_a_pair_exempt_in_part_is_checked_shape_by_shape():
    """The SRDF exempts upper / fore, not upper / cap: the pair of chain links is checked, but
    only upper against the cap (a UR arm's SRDF and the ee_link folded into wrist_3_link).
    Before, fore's cylinder was checked against upper's too: they overlap once bent."""
    arm = robot_from_urdf(CAPPED_CAD_ARM, 'tip', 'base', srdf=CAD_ARM_SRDF)
    names = arm.model.link_names
    assert (names.index('upper'), names.index('fore')) not in arm.model.disabled_pairs
    checker = CollisionChecker(arm, [])
    assert 'upper[0] / fore[1]' in checker.channel_names  # the cap
    assert 'upper[0] / fore[0]' not in checker.channel_names
    bent = np.array([[0.0, 1.0, 0.0, 0.0]])
    assert checker.min_clearance(bent)[0] > 0.0
    assert arm.exempt_urdf_pairs >= {frozenset(('upper', 'fore'))}


def test_default_and_enabled_collisions_as_moveit_reads_them():
    exceptions = read_srdf(srdf('<disable_default_collisions link="panda_link0"/>',
                                '<enable_collisions link1="panda_link0" link2="panda_link5"/>',
                                disable('panda_link2', 'panda_link3'),
                                '<enable_collisions link1="panda_link3" link2="panda_link2"/>'),
                           PANDA_LINKS)
    assert exceptions.exempts('panda_link4', 'panda_link0')
    assert not exceptions.exempts('panda_link5', 'panda_link0')  # enabled again
    assert exceptions.exempts('panda_link2', 'panda_link3')      # disabled wins, as in MoveIt
    assert not exceptions.exempts('panda_link4', 'panda_link5')
    assert CollisionExceptions() == read_srdf('<robot name="r"><group name="arm"/></robot>',
                                              PANDA_LINKS)


@pytest.mark.parametrize('text, words', [
    pytest.param(srdf(disable('panda_link1', 'panda_wrist')),
                 "<disable_collisions> number 1 names link 'panda_wrist', which the URDF does "
                 'not have', id='unknown-link'),
    pytest.param(srdf(disable('panda_link1', 'panda_link2'),
                      '<enable_collisions link1="panda_link1"/>'),
                 '<enable_collisions> number 2 has no link2=', id='missing-link'),
    pytest.param(srdf('<disable_default_collisions link=""/>'),
                 '<disable_default_collisions> number 1 has no link=', id='empty-link'),
    pytest.param('<srdf/>', 'is not an SRDF: it is a <srdf> element', id='not-an-srdf'),
    pytest.param('<robot name="r">', 'is not valid XML', id='not-xml'),
    pytest.param(HOSTILE_XML, 'has a DOCTYPE', id='entities'),
    pytest.param(srdf(disable('panda_link1', 'panda_link2') * (MAX_SRDF_ENTRIES + 1)),
                 f'has {MAX_SRDF_ENTRIES + 1} collision entries, more than the '
                 f'{MAX_SRDF_ENTRIES}', id='entries'),
    pytest.param(srdf('<!--' + ' ' * MAX_SRDF_BYTES + '-->'), 'bytes, more than the '
                 f'{MAX_SRDF_BYTES} a robot description may have', id='bytes'),
])
def test_a_bad_srdf_is_one_line_naming_the_entry(text, words):
    with pytest.raises(InputError) as error:
        read_srdf(text, PANDA_LINKS)
    assert error.value.field == 'robot.srdf' and '\n' not in str(error.value)
    assert words in str(error.value), str(error.value)
    with pytest.raises(InputError, match='^robot.srdf: '):  # and so is the arm
        robot_from_urdf(PANDA_URDF.read_text(), 'panda_hand_tcp', srdf=text)


@settings(max_examples=150, deadline=None, derandomize=True, database=None)
@given(srdf_documents(list(PANDA_LINKS) + ['panda_link9', 'world']))
def test_any_srdf_text_is_exceptions_or_an_input_error_and_exempts_only_whole_pairs(text):
    """Random entries naming the Panda's links and others, missing attributes, odd tags."""
    try:
        exceptions = read_srdf(text, PANDA_LINKS)
    except InputError as error:
        assert error.field == 'robot.srdf' and '\n' not in str(error)
        return
    model = robot_config('panda').model
    exempt = chain_exceptions(model, exceptions)
    for a, b in itertools.combinations(sorted({item.link for item in model.shapes}), 2):
        whole = all(exceptions.exempts(s.urdf_link, t.urdf_link) for s in model.shapes
                    for t in model.shapes if (s.link, t.link) == (a, b))
        assert ((a, b) in exempt) == whole


def test_an_srdf_named_for_another_robot_naming_only_the_urdfs_links_is_taken_with_a_warning(
        caplog):
    """example-robot-data's z1 SRDF says <robot name="z1">, its URDF z1_description: it
    was refused, where MoveIt only warns."""
    srdf = ('<robot name="panda_arm"><virtual_joint name="fixed_base" type="fixed" '
            'parent_frame="world" child_link="panda_link0"/><group name="arm"><chain '
            'base_link="panda_link0" tip_link="panda_link8"/><joint name="panda_joint1"/>'
            '</group><group_state name="home" group="arm"><joint name="fixed_base" value="0"/>'
            '<joint name="panda_joint4" value="-2"/></group_state>'
            '<disable_collisions link1="panda_link0" link2="panda_link1" reason="Adjacent"/>'
            '</robot>')
    with caplog.at_level(logging.WARNING, logger='ftplan_ros.core.model.srdf'):
        arm = robot_from_urdf(PANDA_URDF.read_text(), 'panda_hand_tcp', 'panda_link0',
                              srdf=srdf)
    assert "robot.srdf is written for robot 'panda_arm', the URDF describes 'panda'" in (
        caplog.text)
    names = arm.model.link_names
    assert (names.index('panda_link0'), names.index('panda_link1')) in arm.model.disabled_pairs
    for original, wrong, named in (('panda_link8', 'panda_link9', "link 'panda_link9'"),
                                   ('panda_joint1', 'panda_joint9', "joint 'panda_joint9'")):
        with pytest.raises(InputError, match=rf"robot\.srdf: is written for robot 'panda_arm', "
                           rf"the URDF describes 'panda', and it names {named}, which the URDF "
                           'does not have'):
            robot_from_urdf(PANDA_URDF.read_text(), 'panda_hand_tcp', 'panda_link0',
                            srdf=srdf.replace(original, wrong))


def test_an_srdf_written_for_another_robot_is_refused():
    """Review of issue 34 on vendor models: cassie_v2.srdf (robot 'cassie', no entries)
    given with the Panda's URDF was taken as the Panda's, so every pair was checked and
    the planner blamed obstacles in a scene that had none."""
    with pytest.raises(InputError, match=r"robot\.srdf: is written for robot 'cassie', the "
                       r"URDF describes 'panda', and it names none of its links: give the SRDF "
                       'of this robot'):
        robot_from_urdf(PANDA_URDF.read_text(), 'panda_hand_tcp', 'panda_link0',
                        srdf='<robot name="cassie"><group name="legs"/></robot>')
