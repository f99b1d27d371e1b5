"""What blocks a manifold with no free point (core/collision/blocking.py), and the plan's words.

The paper's arm with a disk over its start or goal point, two disks sharing the blame, the
CAD arm (ftplan_testing.CAD_ARM) with only its adjacent links exempt, and the same arm with
the end of `upper` as a link of its own (a cap fixed to it): the pair is then named by the
URDF links that overlap, not by the chain links that carry them.
"""

import numpy as np
import yaml
from ftplan_testing import CAD_ARM, CAD_ARM_TASK, paper_scene

from ftplan_ros.core.collision.blocking import SAMPLED, find_blocking
from ftplan_ros.core.collision.checker import CollisionChecker
from ftplan_ros.core.io.scene_file import load_scene
from ftplan_ros.core.planning.planner import plan

ADJACENT = [['base', 'upper'], ['upper', 'knuckle'], ['knuckle', 'fore'], ['fore', 'hand']]
# `upper` ends 5 cm short of the joint, and a cap fixed to it fills those 5 cm.
CAPPED = CAD_ARM.replace(
    '<collision><origin xyz="0.1 0 0.15"/>\n      <geometry><cylinder radius="0.05" '
    'length="0.3"/>',
    '<collision><origin xyz="0.1 0 0.125"/>\n      <geometry><cylinder radius="0.05" '
    'length="0.25"/>').replace(
    '<link name="knuckle">',
    '<joint name="cap_joint" type="fixed"><parent link="upper"/><child link="cap"/>'
    '<origin xyz="0.1 0 0.275"/></joint>\n  <link name="cap"><collision><geometry>'
    '<cylinder radius="0.05" length="0.05"/></geometry></collision></link>\n'
    '  <link name="knuckle">')


def cad_scene(tmp_path, urdf=CAD_ARM):
    """The CAD arm with its adjacent links exempt, nothing else."""
    (tmp_path / 'arm.urdf').write_text(urdf)
    robot = {'type': 'urdf', 'file': 'arm.urdf', 'base_link': 'base', 'tip_link': 'tip',
             'disabled_collisions': ADJACENT}
    (tmp_path / 'scene.yaml').write_text(yaml.safe_dump({'robot': robot, 'task': CAD_ARM_TASK}))
    return load_scene(tmp_path / 'scene.yaml')


def test_a_disk_over_the_start_blocks_every_start_and_the_plan_says_so():
    result = plan(paper_scene(obstacles=[((2.0, 0.0), 0.2)]))
    assert not result.feasible
    assert result.reason.endswith(  # after the joint grid's proof that no plan exists
        'the paper\'s surface: every start configuration collides (M_s^F is empty): '
        f'obstacle 0 (sphere at [2.00, 0.00, 0.00]) blocks every one of the {SAMPLED} sampled '
        'start configurations: move it, or the task point')
    assert result.stats['nothing_free'] == {
        'manifold': 'start', 'sampled': SAMPLED, 'clear': 0,
        'blockers': [{'kind': 'obstacle', 'name': 'obstacle 0 (sphere at [2.00, 0.00, 0.00])',
                      'share': 1.0, 'advice': 'move it, or the task point'}]}


def test_a_disk_over_the_goal_blocks_every_goal_configuration():
    result = plan(paper_scene(obstacles=[((0.0, 2.5), 0.2), ((1.0, 0.0), 0.2)]))
    assert ('every goal configuration collides (M_g^F is empty): obstacle 1 (sphere at [1.00, '
            '0.00, 0.00]) blocks every one of' in result.reason)
    assert result.stats['nothing_free']['manifold'] == 'goal'


def test_blockers_come_most_first_with_their_shares():
    """Two disks on the circle the elbow of M_s sweeps, and one far away: together they
    block every start, each its own share; the far one blocks none."""
    scene = paper_scene(obstacles=[((-3.0, -3.0), 0.2), ((1.0, 0.0), 0.5), ((0.0, 1.0), 0.5)])
    checker = CollisionChecker(scene.robot, scene.obstacles)
    angles = np.linspace(-np.pi, np.pi, 400, endpoint=False)
    # Elbow at angle a on the unit circle; links 2 and 3 folded back toward the base.
    points = np.stack([angles, np.full_like(angles, np.pi), np.zeros_like(angles)], axis=1)
    blocking = find_blocking(checker, points, 0.0)
    names = [b.name for b in blocking.blockers]
    assert names == ['obstacle 1 (sphere at [1.00, 0.00, 0.00])',
                     'obstacle 2 (sphere at [0.00, 1.00, 0.00])'] or names == names[::-1]
    shares = [b.share for b in blocking.blockers]
    assert shares == sorted(shares, reverse=True) and 0.0 < min(shares) <= max(shares) < 1.0
    assert blocking.sampled == SAMPLED and 0 < blocking.clear < SAMPLED
    text = blocking.describe('start')
    assert f'{names[0]} blocks {100 * shares[0]:.0f} % of the {SAMPLED} sampled start' in text
    assert f'; also {names[1]} ({100 * shares[1]:.0f} %)' in text


def test_a_pair_of_links_that_overlaps_everywhere_is_named_with_what_to_do(tmp_path):
    result = plan(cad_scene(tmp_path))
    assert result.reason == (
        'every start configuration collides (M_s^F is empty): upper / fore overlap in every one '
        f'of the {SAMPLED} sampled start configurations: if they may touch, exempt them: add '
        '[upper, fore] to robot.disabled_collisions or give the robot\'s SRDF (robot.srdf, '
        '/robot_description_semantic)')


def test_a_pair_is_named_by_the_urdf_links_that_overlap(tmp_path):
    scene = cad_scene(tmp_path, CAPPED)
    assert 'cap' not in scene.robot.link_names  # folded into `upper`
    result = plan(scene)
    assert result.stats['nothing_free']['blockers'][0]['name'] == 'cap / fore'
    assert 'add [upper, fore] to robot.disabled_collisions' in result.reason


def test_points_clear_by_exact_distances_are_counted_as_clear():
    """Step 2's screen may call them colliding; the report then blames the screen."""
    scene = paper_scene(obstacles=[((-3.0, -3.0), 0.2)])
    checker = CollisionChecker(scene.robot, scene.obstacles)
    blocking = find_blocking(checker, np.zeros((7, 3)), 0.0)
    assert (blocking.sampled, blocking.clear, blocking.blockers) == (7, 7, ())
    assert blocking.describe('goal') == (
        'exact distances find 7 of 7 sampled goal configurations clear: Step 2\'s cheap lower '
        'bounds are too loose for this robot\'s geometry (meshes, thin links), not the scene '
        'too full')
