"""The robot from /robot_description and /robot_description_semantic (nodes/scene_source.py).

A description that must be refused leaves the node up with its last good robot and an
ERROR on /diagnostics naming the problem; a big one is built while the node goes on
serving; the SRDF gives the self-collision exceptions.
"""

import math
import time

import pytest
from descriptions import CYCLE_JOINT, PANDA_SRDF, PANDA_URDF, heavy_panda, panda_with
from ftplan_testing import CAD_ARM_SHORT_UPPER, CAD_ARM_SRDF, CAD_ARM_TASK
from geometry_msgs.msg import PoseStamped
from nav_msgs.srv import GetPlan
from ros_support import PARAMS, installed, wait_for
from sensor_msgs.msg import JointState
from spatial_scenes import BASE_LINK, JOINTS, Q_S, TIP_LINK, X_G, X_S, panda_scene
from std_msgs.msg import Header, String

from ftplan_msgs_py import create_joint_state, create_pose
from ftplan_ros.core.model.urdf_structure import MAX_URDF_BYTES
from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.topics import ROBOT_DESCRIPTION, ROBOT_DESCRIPTION_SEMANTIC

STATUS = 'ftplan_planner: robot_description'
PLAN_STATUS = 'ftplan_planner: plan'
SEMANTIC_STATUS = 'ftplan_planner: robot_description_semantic'
JOINT_STATUS = 'ftplan_planner: joint_states'


def plan_request() -> GetPlan.Request:
    def pose(point):
        return PoseStamped(header=Header(frame_id='base_link'),
                           pose=create_pose(point['position'], point['orientation']))
    return GetPlan.Request(start=pose(X_S), goal=pose(X_G))


def publish(ros, topic: str, text: str) -> None:
    ros.probe.publish(String, topic, String(data=text), LATCHED_QOS)


def statuses(ros, name: str, level: str | None = None, after: int = 0) -> list:
    return [s for s in ros.probe.statuses(name)[after:] if level is None or s.level == level]


def test_the_installed_planner_outlives_a_urdf_whose_links_form_a_cycle(ros, processes,
                                                                        tmp_path):
    """Pinocchio crashed on it (SIGSEGV): the planner died and its last good plan with it."""
    planner = processes([installed('planner'), '--ros-args',
                         '--params-file', PARAMS / 'planner.yaml',
                         '--params-file', PARAMS / 'robot_description.yaml',
                         '-p', f'scene_file:={panda_scene(tmp_path, robot=False)}'])
    ros.probe.hear_from('/diagnostics', timeout=60.0)
    publish(ros, ROBOT_DESCRIPTION, PANDA_URDF.read_text())
    wait_for(lambda: statuses(ros, STATUS, 'OK'), 60.0, 'the planner to build the Panda')
    assert ros.probe.call(GetPlan, '/ftplan/plan', plan_request(), timeout=60.0).plan.poses
    publish(ros, ROBOT_DESCRIPTION, panda_with(CYCLE_JOINT))
    error = wait_for(lambda: statuses(ros, STATUS, 'ERROR'), 60.0, 'the ERROR')[0]
    assert ("ignored /robot_description: robot.file: link panda_link2 has two parents "
            "(joints 'panda_joint2' and 'cyc')") in error.message
    assert 'keeping the last good robot' in error.message
    assert planner.alive()
    assert ros.probe.call(GetPlan, '/ftplan/plan', plan_request(), timeout=60.0).plan.poses
    code, _, err = planner.interrupt()
    assert code == 0 and 'Traceback' not in err, err


@pytest.fixture
def planner(ros, tmp_path):
    """A planner whose Panda comes from /robot_description (no disabled_collisions)."""
    node = ros.make(PlannerNode, panda_scene(tmp_path, robot=False), base_link=BASE_LINK,
                    tip_link=TIP_LINK)
    publish(ros, ROBOT_DESCRIPTION, PANDA_URDF.read_text())
    wait_for(lambda: statuses(ros, STATUS, 'OK'), 60.0, 'the Panda')
    return node


@pytest.mark.parametrize('text, words', [
    pytest.param(panda_with('<link name="pedestal"/>'), "has 2 root links, 'panda_link0' and "
                 "'pedestal' (no joint has them as its child)", id='two-roots'),
    pytest.param(heavy_panda(21_000), f'more than the {MAX_URDF_BYTES} a robot description '
                 'may have', id='21000-links'),
    pytest.param(heavy_panda(1_000), 'has 1013 links, more than the 1000', id='1013-links'),
])
def test_a_urdf_beyond_what_a_robot_is_keeps_the_last_good_robot(ros, planner, text, words):
    robot = planner.scene.robot
    publish(ros, ROBOT_DESCRIPTION, text)
    error = wait_for(lambda: statuses(ros, STATUS, 'ERROR'), 60.0, 'the ERROR')[0]
    assert words in error.message and 'keeping the last good robot' in error.message
    assert planner.scene.robot is robot


def test_the_planner_serves_joint_states_while_a_big_urdf_is_built(ros, planner):
    """A 1.1 MB Panda with 960 more links takes seconds to build and warm up: joint states
    (alternately good and bad, each answered on /diagnostics) are read meanwhile, most of
    them before the robot is there. Built in the subscription's callback, none was (they
    waited in the node's queue); with the kernels warmed in the node's callback, about
    one in ten."""
    ros.probe.advertise(JointState, '/joint_states')
    good = create_joint_state(JOINTS, Q_S)
    bad = JointState(name=JOINTS, position=[math.nan] * len(JOINTS))
    start = len(ros.probe.received('/diagnostics'))
    publish(ros, ROBOT_DESCRIPTION, heavy_panda(960, gazebo_tags=6000))
    sent = 0
    while not statuses(ros, STATUS, 'OK', after=1):
        ros.probe.publishers_['/joint_states'].publish(bad if sent % 2 else good)
        sent += 1
        time.sleep(0.02)
        if sent > 20_000:
            pytest.fail('the big URDF was not built')
    answered = 0
    for array in ros.probe.received('/diagnostics')[start:]:
        names = [status.name for status in array.status]
        if STATUS in names:
            break
        answered += names.count(JOINT_STATUS)
    assert 2 * answered >= sent, f'{answered} of {sent} joint states answered before the robot'
    assert len(planner.scene.robot.collision_shapes) > 900  # the big one


def test_a_description_that_arrives_during_a_build_supersedes_it(ros, planner):
    """The newest description wins: the build under way is dropped, the newest is built.

    The two arrive as from the subscription, one right after the other (over DDS the
    first could be dropped from the depth-1 queue before it is taken).
    """
    before = len(statuses(ros, STATUS))
    spare = ('<link name="spare"/><joint name="s" type="fixed"><parent link="panda_link0"/>'
             '<child link="spare"/></joint>')
    planner.source.robot_description_callback(String(data=heavy_panda(100)))  # 1 s or so
    planner.source.robot_description_callback(String(data=panda_with(spare)))
    wait_for(lambda: statuses(ros, STATUS, after=before), 60.0, 'a robot')
    assert [s.level for s in statuses(ros, STATUS, after=before)] == ['OK']
    assert len(planner.scene.robot.collision_shapes) == 37  # the Panda's, not the bigger one's


def test_the_srdf_gives_the_exceptions_and_a_bad_one_keeps_the_last_good_robot(ros, planner):
    assert 'sampled as MoveIt' in statuses(ros, STATUS, 'OK')[-1].message
    before = len(statuses(ros, STATUS))
    publish(ros, ROBOT_DESCRIPTION_SEMANTIC, PANDA_SRDF.read_text())
    ok = wait_for(lambda: statuses(ros, STATUS, 'OK', after=before), 60.0, 'the new robot')[0]
    assert 'self-collision exceptions from /robot_description_semantic' in ok.message
    pairs = planner.scene.robot.model.disabled_pairs
    assert len(pairs) == 17
    assert ros.probe.call(GetPlan, '/ftplan/plan', plan_request(), timeout=60.0).plan.poses
    wrong = PANDA_SRDF.read_text().replace('link2="panda_link6"', 'link2="panda_wrist"', 1)
    publish(ros, ROBOT_DESCRIPTION_SEMANTIC, wrong)
    error = wait_for(lambda: statuses(ros, SEMANTIC_STATUS, 'ERROR'), 60.0, 'the ERROR')[0]
    assert ("ignored /robot_description_semantic: robot.srdf: <disable_collisions> number 14 "
            "names link 'panda_wrist', which the URDF does not have") in error.message
    assert 'keeping the last good robot' in error.message
    assert planner.scene.robot.model.disabled_pairs is pairs


def test_the_srdf_on_the_topic_exempts_the_pair_that_blocked_every_start(ros, tmp_path):
    """The CAD arm whose `upper` and `fore` touch in 91 % of random configurations: MoveIt's
    sampling keeps that pair checked, and the planner answers that it blocks every start
    and that the SRDF would exempt it; with the SRDF on /robot_description_semantic the
    same request is planned."""
    scene_file = tmp_path / 'no_robot.yaml'
    scene_file.write_text('obstacles: []\n')
    ros.make(PlannerNode, scene_file, base_link='base', tip_link='tip', task_kind='position')
    publish(ros, ROBOT_DESCRIPTION, CAD_ARM_SHORT_UPPER)
    ok = wait_for(lambda: statuses(ros, STATUS, 'OK'), 60.0, 'the arm')[0]
    assert 'sampled as MoveIt' in ok.message

    def position(point):
        return PoseStamped(header=Header(frame_id='base_link'),
                           pose=create_pose(point, [0.0, 0.0, 0.0, 1.0]))
    request = GetPlan.Request(start=position(CAD_ARM_TASK['start']),
                              goal=position(CAD_ARM_TASK['goal']))
    assert not ros.probe.call(GetPlan, '/ftplan/plan', request, timeout=60.0).plan.poses
    refused = wait_for(lambda: statuses(ros, PLAN_STATUS, 'WARN'), 60.0, 'the reason')[0]
    assert ('upper / fore overlap in every one of the 100 sampled start configurations: if '
            'they may touch, exempt them: add [upper, fore] to robot.disabled_collisions or '
            "give the robot's SRDF (robot.srdf, /robot_description_semantic)") in refused.message
    publish(ros, ROBOT_DESCRIPTION_SEMANTIC, CAD_ARM_SRDF)
    wait_for(lambda: statuses(ros, STATUS, 'OK', after=1), 60.0, 'the arm with its SRDF')
    assert ros.probe.call(GetPlan, '/ftplan/plan', request, timeout=60.0).plan.poses


def test_a_disabled_collisions_parameter_leaves_the_srdf_topic_unused(ros, tmp_path):
    planner = ros.make(PlannerNode, panda_scene(tmp_path, robot=False), base_link=BASE_LINK,
                       tip_link=TIP_LINK, disabled_collisions=['panda_link0', 'panda_link1'])
    wait_for(lambda: ros.probe.logged('ftplan_planner', 'disabled_collisions is set: '
                                      '/robot_description_semantic is not used'))
    assert planner.source.semantic_subscription is None
    publish(ros, ROBOT_DESCRIPTION, PANDA_URDF.read_text())
    ok = wait_for(lambda: statuses(ros, STATUS, 'OK'), 60.0, 'the Panda')[0]
    assert 'from the disabled_collisions parameter' in ok.message
    assert planner.scene.robot.model.disabled_pairs == {(0, 1)}
