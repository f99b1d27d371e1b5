"""The planner node in-process for a 7-joint arm: pose, axis and position tasks,
/robot_description, joint states with fingers and other arms, 3-D markers."""

import numpy as np
import pytest
from geometry_msgs.msg import PoseStamped, Quaternion
from nav_msgs.srv import GetPlan
from rclpy.parameter import Parameter
from ros_support import wait_for
from scipy.spatial.transform import Rotation
from sensor_msgs.msg import JointState
from spatial_scenes import (
    FINGERS,
    JOINTS,
    ORIENTATION_TOLERANCE,
    PANDA_URDF,
    Q_S,
    TOLERATED,
    X_G,
    X_S,
    description_parameters,
    panda_scene,
)
from std_msgs.msg import Header, String
from visualization_msgs.msg import MarkerArray

from ftplan_msgs_py import (
    create_joint_state,
    create_pose,
    read_joint_state,
    read_path_poses,
    read_plan_markers,
)
from ftplan_ros.core import load_scene, task_errors
from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.reporting import parse_vector, stamp_key

STATUS = 'ftplan_planner: plan'
FRAME = 'base_link'


def pose(point, frame=FRAME, orientation=None):
    """A PoseStamped at `point`; `orientation` (x, y, z, w) is sent as given, unit or not."""
    msg = PoseStamped(header=Header(frame_id=frame),
                      pose=create_pose(point['position'], point['orientation']))
    if orientation is not None:
        x, y, z, w = orientation
        msg.pose.orientation = Quaternion(x=x, y=y, z=z, w=w)
    return msg


def status_of(ros, response):
    stamp = stamp_key(response.plan.header.stamp)
    return wait_for(lambda: [s for s in ros.probe.statuses(STATUS)
                             if s.values.get('stamp') == stamp], what='the plan status')[-1]


def ask(ros, start, goal=None, tolerance=0.0):
    request = GetPlan.Request(start=start, goal=pose(X_G) if goal is None else goal,
                              tolerance=tolerance)
    response = ros.probe.call(GetPlan, '/ftplan/plan', request, timeout=60.0)
    return response, status_of(ros, response)


def angle_between(q1, q2):
    return (Rotation.from_quat(q1).inv() * Rotation.from_quat(q2)).magnitude()


@pytest.fixture
def panda(ros, tmp_path):
    scene_file = panda_scene(tmp_path)
    ros.make(PlannerNode, scene_file)
    ros.probe.listen(MarkerArray, '/ftplan/plan/markers', LATCHED_QOS)
    ros.probe.listen(JointState, '/ftplan/plan/start_configuration', LATCHED_QOS)
    return ros, load_scene(scene_file)


def test_a_pose_request_is_planned_with_its_orientation_and_drawn_in_3d(panda):
    ros, scene = panda
    response, status = ask(ros, pose(X_S))
    assert response.plan.poses, status.message
    assert status.values['task_kind'] == 'pose'
    assert status.values['tolerated_joints'].split(',') == TOLERATED
    positions, orientations = read_path_poses(response.plan)
    robot = scene.robot
    # The Path is the tool's poses along the nominal path: it starts at FK(θ_s) = x_s...
    stamp = status.values['stamp']
    theta_s = read_joint_state(wait_for(lambda: [
        m for m in ros.probe.received('/ftplan/plan/start_configuration')
        if stamp_key(m.header.stamp) == stamp])[-1], JOINTS)
    tool = robot.tool_frames(theta_s)
    assert np.allclose(positions[0], tool[:3, 3], atol=1e-12)
    assert angle_between(orientations[0], Rotation.from_matrix(tool[:3, :3]).as_quat()) < 1e-9
    x_s = np.concatenate([X_S['position'], X_S['orientation']])
    assert np.allclose(positions[0], X_S['position'], atol=1e-9)
    assert angle_between(orientations[0], X_S['orientation']) < 1e-6
    # The arm at θ_s is drawn in 3-D: a line through its skeleton, spheres at its joints.
    markers = read_plan_markers(wait_for(lambda: [
        m for m in ros.probe.received('/ftplan/plan/markers')
        if stamp_key(m.markers[0].header.stamp) == stamp])[-1])
    line, joints = markers['arm_theta_s']
    assert line.shape == (9, 3) and np.array_equal(line, joints)   # base, 7 joints, tool
    assert np.allclose(line, robot.skeleton(theta_s))
    # ...and ends within the tolerances of the goal, position and orientation.
    x_g = np.concatenate([X_G['position'], X_G['orientation']])
    end = np.concatenate([positions[-1], orientations[-1]])
    assert np.linalg.norm(end[:3] - x_g[:3]) <= float(status.values['tolerance'])
    assert angle_between(end[3:], x_g[3:]) <= ORIENTATION_TOLERANCE
    # The 3-D end-effector path marker is the Path's positions.
    assert np.allclose(markers['end_effector_path'][0], positions)
    assert len(markers['start_manifold'][0][0]) == 3       # joint space: joints 1-3
    assert 'obstacles' in markers
    assert np.allclose(parse_vector(status.values['start']), x_s, atol=1e-12)


@pytest.mark.parametrize('field, orientation, problem', [
    ('goal', [0.0, 0.0, 0.0, 2.0], 'goal.pose.orientation must be a unit quaternion'),
    ('start', [0.0, 0.0, 0.0, 0.0], 'start.pose.orientation must be a unit quaternion'),
    ('start', [0.5, 0.5, 0.5, 0.504], 'got norm 1.002'),
])
def test_a_quaternion_that_is_not_unit_is_refused_naming_the_field(panda, field, orientation,
                                                                   problem):
    ros, _ = panda
    bad = pose(X_S if field == 'start' else X_G, orientation=orientation)
    response, status = ask(ros, bad if field == 'start' else pose(X_S),
                           bad if field == 'goal' else None)
    assert response.plan.poses == []
    assert status.level == 'WARN' and problem in status.message, status.message
    wait_for(lambda: ros.probe.logged('ftplan_planner', problem), what='the reason in the log')


def test_a_zero_quaternion_is_refused_clearly(panda):
    ros, _ = panda
    zero = pose(X_G, orientation=[0.0, 0.0, 0.0, 0.0])
    response, status = ask(ros, pose(X_S), zero)
    assert response.plan.poses == []
    assert 'zero quaternion' in status.message and 'goal.pose.orientation' in status.message


def test_task_kind_position_and_axis_take_their_part_of_the_poses(ros, tmp_path):
    scene_file = panda_scene(tmp_path, tolerate=False, obstacles=False)
    planner = ros.make(PlannerNode, scene_file, task_kind='position')
    # Position: the orientations do not matter, not even a zero quaternion.
    response, status = ask(ros, pose(X_S, orientation=[0.0, 0.0, 0.0, 0.0]),
                           pose(X_G, orientation=[0.0, 0.0, 0.0, 0.0]))
    assert response.plan.poses, status.message
    assert status.values['task_kind'] == 'position'
    assert status.values['tolerated_joints'].split(',') == JOINTS   # the scene's: all
    positions, _ = read_path_poses(response.plan)
    assert np.allclose(positions[0], X_S['position'], atol=1e-9)
    assert np.linalg.norm(positions[-1] - X_G['position']) <= float(status.values['tolerance'])
    # Axis: the z axis of the poses, the rotation about it free; six joints tolerated.
    assert planner.set_parameters([Parameter('task_kind', value='axis'),
                                   Parameter('tolerate', value=TOLERATED)])[0].successful
    response, status = ask(ros, pose(X_S))
    assert response.plan.poses, status.message
    assert status.values['task_kind'] == 'axis'
    assert status.values['tolerated_joints'].split(',') == TOLERATED
    positions, orientations = read_path_poses(response.plan)
    axis = Rotation.from_quat(X_G['orientation']).as_matrix()[:, 2]
    tool_axis = Rotation.from_quat(orientations[-1]).as_matrix()[:, 2]
    assert np.arccos(np.clip(axis @ tool_axis, -1, 1)) <= ORIENTATION_TOLERANCE
    assert len(parse_vector(status.values['goal'])) == 6
    # Parameters the arm cannot take are refused; the node keeps its own.
    for name, value, problem in (('task_kind', 'planar', 'spatial arm'),
                                 ('tolerate', ['panda_joint9'], "unknown joint 'panda_joint9'"),
                                 ('orientation_tolerance', -0.1, '>= 0')):
        result = planner.set_parameters([Parameter(name, value=value)])[0]
        assert not result.successful and problem in result.reason, result.reason
    assert planner.get_parameter('task_kind').value == 'axis'


def test_joint_states_with_fingers_and_of_another_arm_are_read_by_name(ros, tmp_path):
    scene_file = panda_scene(tmp_path)
    ros.make(PlannerNode, scene_file)
    names = list(reversed(JOINTS)) + FINGERS
    q = list(reversed(Q_S)) + [0.04, 0.04]
    ros.probe.publish(JointState, '/joint_states', create_joint_state(names, q))
    other = [name.replace('panda', 'right') for name in JOINTS]
    ros.probe.publish(JointState, '/joint_states', create_joint_state(other, np.zeros(7)))
    wait_for(lambda: ros.probe.statuses('ftplan_planner: joint_states'),
             what='the planner to take the joint state')
    response, status = ask(ros, PoseStamped())      # empty frame: from where the arm is
    assert response.plan.poses, status.message
    robot = load_scene(scene_file).robot
    start = np.array(parse_vector(status.values['start']))
    assert np.all(task_errors(robot, start, np.array(Q_S)) < 1e-9)
    assert not ros.probe.logged('ftplan_planner', 'rejected joint state')


BAD_URDF = '<robot name="broken"><link name="a"/><joint name="j" type="revolute">'


def test_a_scene_without_robot_waits_for_robot_description_and_keeps_a_good_one(ros, tmp_path):
    scene_file = panda_scene(tmp_path, robot=False)
    planner = ros.make(PlannerNode, scene_file, **description_parameters())
    assert planner.scene is None
    response, status = ask(ros, pose(X_S))
    assert response.plan.poses == [] and 'waiting for /robot_description' in status.message
    problems = 'ftplan_planner: robot_description'
    ros.probe.publish(String, '/robot_description', String(data=BAD_URDF), LATCHED_QOS)
    error = wait_for(lambda: [s for s in ros.probe.statuses(problems) if s.level == 'ERROR'])
    assert 'is not valid XML' in error[0].message and 'waiting' in error[0].message
    ros.probe.publish(String, '/robot_description', String(data=PANDA_URDF.read_text()),
                      LATCHED_QOS)
    wait_for(lambda: [s for s in ros.probe.statuses(problems) if s.level == 'OK'])
    assert planner.scene.robot.joint_names == tuple(JOINTS)
    response, status = ask(ros, pose(X_S))
    assert response.plan.poses, status.message
    assert status.values['tolerated_joints'].split(',') == TOLERATED
    # A bad URDF now: reported, and the Panda stays.
    before = len(ros.probe.statuses(problems))
    wrong_tip = PANDA_URDF.read_text().replace('panda_hand_tcp', 'panda_hand_tip')
    ros.probe.publish(String, '/robot_description', String(data=wrong_tip), LATCHED_QOS)
    error = wait_for(lambda: ros.probe.statuses(problems)[before:])[0]
    assert error.level == 'ERROR' and "no link 'panda_hand_tcp'" in error.message
    assert 'keeping the last good robot' in error.message
    response, status = ask(ros, pose(X_S))
    assert response.plan.poses, status.message


def test_a_scene_with_a_robot_ignores_robot_description(ros, tmp_path):
    planner = ros.make(PlannerNode, panda_scene(tmp_path))
    wait_for(lambda: ros.probe.logged('ftplan_planner', 'the scene file has a robot: '
                                      '/robot_description is not used'))
    assert planner.source.subscription is None
