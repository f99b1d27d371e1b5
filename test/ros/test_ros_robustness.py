"""Bad inputs that used to stop a node or corrupt its output, in one process with real DDS."""

import time

import numpy as np
from rclpy.node import Node
from rclpy.parameter import Parameter
from ros_support import FIG3A, SCENES, wait_for
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, MultiArrayLayout, String
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py import (
    ObstacleShape,
    create_joint_state,
    create_joint_trajectory,
    create_obstacle_markers,
    read_locked_joint,
)
from ftplan_ros.core import load_scene, plan
from ftplan_ros.nodes.executor import ExecutorNode
from ftplan_ros.nodes.injector import InjectorNode
from ftplan_ros.nodes.plan_markers import plan_markers
from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.reporting import parse_vector
from ftplan_ros.nodes.sim import SimNode
from ftplan_ros.nodes.topics import FAILURE_SURFACE, START_CONFIGURATION, TRAJECTORY
from ftplan_ros.plan_client import Outcome, PlanClient

NAMES = ['joint1', 'joint2', 'joint3']


def test_an_empty_failure_surface_is_rejected_and_the_executor_stays_up(ros):
    ros.make(ExecutorNode)
    stamp = ros.probe.get_clock().now().to_msg()
    nominal = np.array([[0.1, 0.2, 0.3], [0.2, 0.3, 0.4]])
    empty = Float64MultiArray(layout=MultiArrayLayout(dim=[
        MultiArrayDimension(label='path', size=1, stride=0),
        MultiArrayDimension(label='waypoint', size=0, stride=0),
        MultiArrayDimension(label='joint', size=3, stride=3)]))
    ros.probe.publish(Float64MultiArray, FAILURE_SURFACE, empty, LATCHED_QOS)
    ros.probe.publish(JointState, START_CONFIGURATION,
                      create_joint_state(NAMES, nominal[0], stamp=stamp), LATCHED_QOS)
    ros.probe.publish(JointTrajectory, TRAJECTORY,
                      create_joint_trajectory(NAMES, nominal, [0.0, 1.0], stamp), LATCHED_QOS)
    wait_for(lambda: [s for s in ros.probe.statuses('ftplan_executor: plan')
                      if 'each must be >= 1' in s.message], what='the rejection')
    response = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    assert not response.success and 'no plan yet' in response.message


def test_bad_seeds_are_refused_and_the_nodes_stay_up(ros):
    injector = ros.make(InjectorNode)
    planner = ros.make(PlannerNode)
    for node in (injector, planner):
        result = node.set_parameters([Parameter('seed', value=-1)])[0]
        assert not result.successful and '>= 0' in result.reason
        assert node.get_parameter('seed').value == 0
    assert not planner.set_parameters([Parameter('joint_space_frame', value='')])[0].successful
    assert injector.set_parameters([Parameter('seed', value=7)])[0].successful
    assert injector.get_parameter('seed').value == 7


def test_the_nominal_lead_is_bounded(ros):
    """The executor's pause before the nominal path (time for a drill's scheduled lock):
    negative, endless or longer than a second is refused, naming the bound."""
    executor = ros.make(ExecutorNode)
    for value, problem in [(-0.1, '>= 0'), (float('inf'), '>= 0'), (1.5, 'at most 1.0 s')]:
        result = executor.set_parameters([Parameter('nominal_lead', value=value)])[0]
        assert not result.successful and problem in result.reason, (value, result.reason)
    assert executor.get_parameter('nominal_lead').value == 0.05
    assert executor.set_parameters([Parameter('nominal_lead', value=0.0)])[0].successful


def test_lock_now_set_twice_at_once_locks_twice_and_then_stays_quiet(ros):
    injector = ros.make(InjectorNode)
    ros.probe.listen(JointState, '/ftplan/locked_joint')
    wait_for(lambda: injector.lock_publisher.get_subscription_count() > 0)
    sets = []
    injector.add_post_set_parameters_callback(lambda parameters: sets.extend(
        p.value for p in parameters if p.name == 'lock_now'))
    assert injector.set_parameters([Parameter('lock_now', value='joint1')])[0].successful
    assert injector.set_parameters([Parameter('lock_now', value='joint2')])[0].successful
    wait_for(lambda: len(ros.probe.received('/ftplan/locked_joint')) == 2, what='two locks')
    wait_for(lambda: injector.get_parameter('lock_now').value == '', what='lock_now cleared')
    events = [read_locked_joint(m).name for m in ros.probe.received('/ftplan/locked_joint')]
    assert events == ['joint1', 'joint2']
    time.sleep(0.5)  # a leaked clearing timer would set lock_now again and again meanwhile
    assert sets[:1] == ['joint1'] and 'joint2' in sets and sets[-1] == ''
    assert len(sets) <= 4  # each request, then one or two clears
    assert len(ros.probe.received('/ftplan/locked_joint')) == 2


def test_plan_markers_clear_rviz_once_before_the_plan_and_its_obstacles():
    scene = load_scene(FIG3A)
    result = plan(scene)
    assert result.feasible
    markers = plan_markers(scene, result, None, 'ftplan_joint_space').markers
    clears = [k for k, m in enumerate(markers) if m.action == Marker.DELETEALL]
    assert clears == [0]
    assert sum(m.ns == 'obstacles' for m in markers) == len(scene.obstacles)


def test_a_joint_state_of_other_joints_does_not_make_the_start_unknown(ros, ros_context):
    ros.make(PlannerNode, scene_file=SCENES / 'paper_c_free.yaml')
    q = np.array([0.3, -0.6, 0.4])
    ros.probe.publish(JointState, '/joint_states', create_joint_state(NAMES, q))
    gripper = create_joint_state(['finger_left', 'finger_right'], np.array([0.01, 0.01]))
    ros.probe.publish(JointState, '/joint_states', gripper)
    time.sleep(0.2)  # let the gripper's message reach the planner
    client = PlanClient(context=ros_context)
    try:
        motion = client.plan(goal=(1.0, 0.0), timeout=60.0)
    finally:
        client.destroy_node()
    assert motion.result in (Outcome.SUCCEEDED, Outcome.FAILED), motion.message
    assert 'joint state' not in motion.message, motion.message
    x_q = load_scene(SCENES / 'paper_c_free.yaml').robot.forward_kinematics(q)
    reported = wait_for(lambda: [s for s in ros.probe.statuses('ftplan_planner: plan')
                                 if s.values.get('stamp') == motion.stamp])[0]
    # Planned from where the joint state puts the end effector:
    assert np.allclose(parse_vector(reported.values['start']), x_q, atol=1e-6)


def test_a_callback_that_raises_is_logged_and_spinning_goes_on(ros):
    received = []

    class Fragile(Node):
        def __init__(self):
            super().__init__('ftplan_test_fragile', context=ros.context)
            self.create_subscription(String, '/ftplan_test/fragile', self.callback, 10)

        def callback(self, msg):
            received.append(msg.data)
            if msg.data == 'bad':
                raise RuntimeError('a bad message')

    ros.add(Fragile())
    for text in ('bad', 'good'):
        ros.probe.publish(String, '/ftplan_test/fragile', String(data=text))
    wait_for(lambda: received == ['bad', 'good'], what='both messages')
    assert ros.spin.thread.is_alive()


def test_a_plan_whose_surface_meets_a_new_obstacle_is_not_executed(ros, ros_context):
    ros.make(PlannerNode)
    executor = ros.make(ExecutorNode)
    ros.make(SimNode)
    client = PlanClient(context=ros_context)
    try:
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=60.0)
    finally:
        client.destroy_node()
    assert motion.succeeded, motion.message
    wait_for(lambda: executor.plan is not None and executor.plan.key == motion.stamp)
    # A small disk on the arm's elbow halfway along the nominal path.
    middle = motion.trajectory[len(motion.trajectory) // 2]
    elbow = load_scene(FIG3A).robot.joint_positions(middle)[2]
    disk = ObstacleShape(('dropped', 0), 'sphere', np.array([elbow[0], elbow[1], 0.0]),
                         np.full(3, 0.1), np.array([0.0, 0.0, 0.0, 1.0]))
    ros.probe.publish(MarkerArray, '/ftplan/obstacles',
                      create_obstacle_markers([disk], 'base_link'), LATCHED_QOS)
    wait_for(lambda: len(executor._obstacles) == 1, what='the executor to read the obstacle')
    refused = ros.probe.call(Trigger, '/ftplan/execute', Trigger.Request())
    assert not refused.success
    assert f'the obstacles changed since plan {motion.stamp}' in refused.message
