"""The planner node in-process: plans, latched results, bad requests, obstacle topic."""

import numpy as np
import pytest
from geometry_msgs.msg import Point, Pose, PoseStamped, Vector3
from nav_msgs.srv import GetPlan
from rclpy.parameter import Parameter
from ros_support import FIG3A, SCENES, wait_for
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, Header
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py import (
    ObstacleShape,
    create_joint_state,
    create_obstacle_markers,
    read_failure_surface,
    read_joint_state,
    read_joint_trajectory,
    read_path,
    read_plan_markers,
)
from ftplan_ros.core import InputError, load_scene
from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.reporting import stamp_key

NAMES = ['joint1', 'joint2', 'joint3']
AT_START = [-np.pi / 3, 2 * np.pi / 3, -np.pi / 3]   # puts the end effector at x_s = (2, 0)
STATUS = 'ftplan_planner: plan'


def pose(x, y, z=0.0, frame='base_link'):
    return PoseStamped(header=Header(frame_id=frame),
                       pose=Pose(position=Point(x=float(x), y=float(y), z=float(z))))


def request(start=(2.0, 0.0), goal=(1.0, 0.0), tolerance=0.0):
    return GetPlan.Request(start=start if isinstance(start, PoseStamped) else pose(*start),
                           goal=goal if isinstance(goal, PoseStamped) else pose(*goal),
                           tolerance=tolerance)


@pytest.fixture
def planner(ros):
    ros.make(PlannerNode)
    for msg_type, topic in ((JointState, '/ftplan/plan/start_configuration'),
                            (JointTrajectory, '/ftplan/plan/trajectory'),
                            (Float64MultiArray, '/ftplan/plan/failure_surface'),
                            (MarkerArray, '/ftplan/plan/markers')):
        ros.probe.listen(msg_type, topic, LATCHED_QOS)
    return ros


def plan_ok(ros, req=None):
    response = ros.probe.call(GetPlan, '/ftplan/plan', req or request())
    assert response.plan.poses, ros.probe.statuses(STATUS)[-1].message
    return response


def latest(ros, topic, stamp):
    """The message on `topic` stamped `stamp` (waiting for it)."""
    def find():
        for msg in reversed(ros.probe.received(topic)):
            if stamp_key(msg.header.stamp) == stamp:
                return msg
        return None
    return wait_for(find, what=f'{topic} stamped {stamp}')


def test_a_plan_is_answered_and_published_latched_and_consistent(planner):
    ros = planner
    response = plan_ok(ros)
    stamp = stamp_key(response.plan.header.stamp)
    assert response.plan.header.frame_id == 'base_link'
    path = read_path(response.plan)
    assert np.allclose(path[0, :2], [2.0, 0.0]) and np.allclose(path[-1, :2], [1.0, 0.0],
                                                                  atol=0.01)
    start = read_joint_state(latest(ros, '/ftplan/plan/start_configuration', stamp), NAMES)
    positions, times = read_joint_trajectory(latest(ros, '/ftplan/plan/trajectory', stamp), NAMES)
    assert np.array_equal(positions[0], start)
    assert np.all(np.diff(times) > 0.0)
    scene = load_scene(FIG3A)
    assert np.allclose(scene.robot.forward_kinematics(positions), path[:, :2])
    surface = wait_for(lambda: ros.probe.received('/ftplan/plan/failure_surface'))[-1]
    web = read_failure_surface(surface)
    assert any(np.array_equal(p, positions) for p in web)     # the nominal path is on S_F
    markers = read_plan_markers(wait_for(lambda: ros.probe.received('/ftplan/plan/markers'))[-1])
    for ns in ('failure_surface', 'end_effector_path', 'start_manifold', 'goal_manifold',
               'theta_s', 'failure_plane_hits', 'obstacles'):
        assert ns in markers, ns
    status = ros.probe.statuses(STATUS)[-1]
    assert status.level == 'OK' and status.values['stamp'] == stamp


def test_an_empty_start_frame_plans_from_the_latest_joint_state(ros):
    """The scene's task starts at x_s = (2.5, 0); the joint state puts the hand at (2, 0)."""
    scene_file = SCENES / 'paper_c_free.yaml'
    ros.make(PlannerNode, scene_file)
    scene = load_scene(scene_file)
    hand = scene.robot.forward_kinematics(np.array(AT_START))
    assert np.linalg.norm(hand - scene.task.start) > 0.4
    ros.probe.publish(JointState, '/joint_states', create_joint_state(NAMES, AT_START))
    wait_for(lambda: [s for s in ros.probe.statuses('ftplan_planner: joint_states')],
             what='the planner to take the joint state')
    path = read_path(plan_ok(ros, request(start=PoseStamped())).plan)
    assert np.allclose(path[0, :2], hand, atol=1e-9)
    assert np.allclose(path[-1, :2], [1.0, 0.0], atol=0.01)


def _nan_joint_state(ros):
    msg = JointState(name=NAMES, position=[0.1, float('nan'), 0.3])
    ros.probe.publish(JointState, '/joint_states', msg)
    wait_for(lambda: ros.probe.logged('ftplan_planner', 'rejected joint state'))
    return request(start=PoseStamped())


BAD_REQUESTS = {
    'before any joint state': (lambda ros: request(start=PoseStamped()),
                               'no joint state received yet'),
    'unknown start frame': (lambda ros: request(start=pose(2.0, 0.0, frame='map')),
                            "unknown frame 'map'"),
    'unknown goal frame': (lambda ros: request(goal=pose(1.0, 0.0, frame='odom')),
                           "unknown frame 'odom'"),
    'NaN goal position': (lambda ros: request(goal=(float('nan'), 0.0)),
                          'goal.pose.position has a non-finite value'),
    'NaN joint state': (_nan_joint_state, 'the latest joint state was rejected'),
    'unreachable goal': (lambda ros: request(goal=(5.0, 0.0)), "out of the arm's reach"),
    'goal off the plane': (lambda ros: request(goal=(1.0, 0.0, 0.5)), 'z = 0'),
    'negative tolerance': (lambda ros: request(tolerance=-0.1), 'tolerance'),
}


@pytest.mark.parametrize('case', sorted(BAD_REQUESTS))
def test_a_bad_request_fails_with_a_logged_reason_and_keeps_the_last_good_plan(planner, case):
    ros = planner
    good = stamp_key(plan_ok(ros).plan.header.stamp)
    latest(ros, '/ftplan/plan/start_configuration', good)
    make, reason = BAD_REQUESTS[case]
    response = ros.probe.call(GetPlan, '/ftplan/plan', make(ros))
    assert response.plan.poses == []
    assert response.plan.header.frame_id == 'base_link'
    bad = stamp_key(response.plan.header.stamp)
    status = wait_for(lambda: [s for s in ros.probe.statuses(STATUS)
                               if s.values['stamp'] == bad])[-1]
    assert status.level == 'WARN' and reason in status.message
    wait_for(lambda: ros.probe.logged('ftplan_planner', reason), what='the reason in the log')
    # The latched topics still hold the good plan, for a subscriber that joins now...
    late = ros.add(type(ros.probe)(ros.context, 'ftplan_test_late_probe'))
    late.listen(JointState, '/ftplan/plan/start_configuration', LATCHED_QOS)
    late.listen(JointTrajectory, '/ftplan/plan/trajectory', LATCHED_QOS)
    msgs = wait_for(lambda: late.received('/ftplan/plan/start_configuration'))
    assert [stamp_key(m.header.stamp) for m in msgs] == [good]
    trajectories = wait_for(lambda: late.received('/ftplan/plan/trajectory'))
    assert [stamp_key(m.header.stamp) for m in trajectories] == [good]
    # ...and the node still plans.
    assert plan_ok(ros).plan.poses


def _markers(*shapes, clear=False):
    return create_obstacle_markers(shapes, 'base_link', clear_first=clear)


def test_obstacles_add_to_the_scene_and_malformed_markers_keep_the_previous_ones(planner):
    ros = planner
    # Off-centre on purpose: the core's point_clearance hangs in fcl for a point at a
    # sphere's exact centre (reported to the core's owner).
    over_base = ObstacleShape(('test', 1), 'sphere', np.array([0.05, 0.02, 0.0]),
                              np.full(3, 0.4), np.array([0.0, 0.0, 0.0, 1.0]))
    ros.probe.publish(MarkerArray, '/ftplan/obstacles', _markers(over_base), LATCHED_QOS)
    wait_for(lambda: ros.probe.logged('ftplan_planner', '1 obstacles from /ftplan/obstacles'))
    response = ros.probe.call(GetPlan, '/ftplan/plan', request())
    assert response.plan.poses == []
    wait_for(lambda: 'covers the robot base' in ros.probe.statuses(STATUS)[-1].message)

    malformed = {
        'wrong frame': Marker(header=Header(frame_id='map'), ns='test', id=2,
                              type=Marker.SPHERE, action=Marker.ADD,
                              scale=Vector3(x=0.2, y=0.2, z=0.2)),
        'NaN pose': Marker(header=Header(frame_id='base_link'), ns='test', id=3,
                           type=Marker.SPHERE, action=Marker.ADD,
                           pose=Pose(position=Point(x=float('nan'))),
                           scale=Vector3(x=0.2, y=0.2, z=0.2)),
        'line strip': Marker(header=Header(frame_id='base_link'), ns='test', id=4,
                             type=Marker.LINE_STRIP, action=Marker.ADD),
    }
    for marker in malformed.values():
        before = len(ros.probe.logged('ftplan_planner', 'holding the 1 previous'))
        ros.probe.publish(MarkerArray, '/ftplan/obstacles', MarkerArray(markers=[marker]),
                          LATCHED_QOS)
        wait_for(lambda b=before: len(ros.probe.logged('ftplan_planner',
                                                       'holding the 1 previous')) > b)
    response = ros.probe.call(GetPlan, '/ftplan/plan', request())
    assert response.plan.poses == []       # refused: the set is not the one published
    wait_for(lambda: 'an obstacle update was refused' in ros.probe.statuses(STATUS)[-1].message)

    ros.probe.publish(MarkerArray, '/ftplan/obstacles', MarkerArray(
        markers=[Marker(action=Marker.DELETEALL)]), LATCHED_QOS)
    wait_for(lambda: ros.probe.logged('ftplan_planner', '0 obstacles from /ftplan/obstacles'))
    assert plan_ok(ros).plan.poses


def test_a_planar_arm_refuses_a_spatial_task_kind(ros):
    overrides = [Parameter('scene_file', value=str(FIG3A)), Parameter('task_kind', value='pose')]
    with pytest.raises(InputError, match="task_kind: 'pose': a planar arm does planar tasks"):
        PlannerNode(context=ros.context, parameter_overrides=overrides)
    planner = ros.make(PlannerNode)
    result = planner.set_parameters([Parameter('task_kind', value='axis')])[0]
    assert not result.successful and 'a planar arm does planar tasks only' in result.reason
    assert planner.set_parameters([Parameter('task_kind', value='planar')])[0].successful
    assert plan_ok(ros).plan.poses[0].pose.orientation.w == 1.0   # planar: no orientation
