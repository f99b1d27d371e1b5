"""The ROS layout `make install` builds, and the installed nodes across processes."""

import os
import time

import numpy as np
import pytest
from ament_index_python.packages import (
    get_package_prefix,
    get_package_share_directory,
    get_packages_with_prefixes,
)
from geometry_msgs.msg import Point, Pose, PoseStamped
from nav_msgs.srv import GetPlan
from ros_support import FIG3A, INSTALL, PARAMS, installed, require_install, wait_for
from spatial_scenes import PANDA_URDF, X_G, X_S, panda_scene
from std_msgs.msg import Header, String

from ftplan_msgs_py import create_pose
from ftplan_ros.nodes.injector import DRILL_TOLERANCE
from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.topics import (
    DIAGNOSTICS,
    EXECUTOR_NODE,
    INJECTOR_NODE,
    JOINT_COMMAND,
    LOCKED_JOINT,
    TRAJECTORY,
)
from ftplan_ros.plan_client import Outcome, PlanClient

EXECUTABLES = ('planner', 'injector', 'executor', 'sim', 'bringup')


def test_ament_index_finds_both_packages_and_the_executables():
    require_install()
    packages = get_packages_with_prefixes()
    assert packages['ftplan_ros'] == str(INSTALL / 'ftplan_ros')
    assert packages['ftplan_msgs_py'] == str(INSTALL / 'ftplan_msgs_py')
    lib = os.path.join(get_package_prefix('ftplan_ros'), 'lib', 'ftplan_ros')
    for executable in EXECUTABLES:                    # what `ros2 run ftplan_ros X` runs
        path = os.path.join(lib, executable)
        assert os.path.isfile(path) and os.access(path, os.X_OK), path
    share = get_package_share_directory('ftplan_ros')
    for kind, name in [('scenes', 'fig3a.yaml'), ('robots', 'planar3r.yaml')] + [
            ('params', f'{node}.yaml') for node in ('planner', 'executor', 'sim', 'injector')]:
        assert os.path.isfile(os.path.join(share, 'config', kind, name)), (kind, name)
    assert os.path.isfile(os.path.join(share, 'package.xml'))


def _pose(x, y, frame='base_link'):
    return PoseStamped(header=Header(frame_id=frame),
                       pose=Pose(position=Point(x=float(x), y=float(y))))


def _subscribes(observer, node_name: str, topic: str) -> bool:
    """Whether `observer` sees a subscription of `node_name` to `topic` in the graph."""
    return any(info.node_name == node_name
               for info in observer.get_subscriptions_info_by_topic(topic))


def test_the_installed_planner_serves_another_process(ros, processes):
    planner = processes([installed('planner'), '--ros-args', '--params-file',
                         PARAMS / 'planner.yaml', '-p', f'scene_file:={FIG3A}'])
    good = GetPlan.Request(start=_pose(2.0, 0.0), goal=_pose(1.0, 0.0))
    response = ros.probe.call(GetPlan, '/ftplan/plan', good, timeout=60.0)
    assert len(response.plan.poses) > 2
    bad = GetPlan.Request(start=_pose(2.0, 0.0, frame='map'), goal=_pose(1.0, 0.0))
    assert ros.probe.call(GetPlan, '/ftplan/plan', bad).plan.poses == []
    wait_for(lambda: ros.probe.logged('ftplan_planner', "unknown frame 'map'"))
    assert planner.alive()
    assert len(ros.probe.call(GetPlan, '/ftplan/plan', good).plan.poses) > 2
    code, _, err = planner.interrupt()
    assert code == 0, err
    assert 'Traceback' not in err


def test_four_installed_nodes_drill_across_processes(ros_context, processes):
    """Planner, executor, sim and injector as four processes; the test plans and executes."""
    scene = ['-p', f'scene_file:={FIG3A}']
    # At 0.5 rad/s the nominal path takes about 3 s: the injector has 1.5 s from half way
    # to hear the arm there, where 2 rad/s left it 0.35 s, missed twice in 80 loaded runs.
    nodes = {name: processes([installed(name), '--ros-args', '--params-file',
                              PARAMS / f'{name}.yaml', *scene, *extra])
             for name, extra in [('planner', []), ('executor', ['-p', 'max_joint_speed:=0.5']),
                                 ('sim', ['-p', 'max_joint_speed:=4.0']),
                                 ('injector', ['-p', "drills:=['joint2@0.5']"])]}
    client = PlanClient(context=ros_context)
    try:
        assert client.wait_until_ready(timeout=60.0)
        # A loaded machine may still be starting the injector when the plan is done: the
        # drill needs its subscriptions, and the executor's to its locks, in the graph.
        for node, topic in [(INJECTOR_NODE, DIAGNOSTICS), (INJECTOR_NODE, TRAJECTORY),
                            (INJECTOR_NODE, JOINT_COMMAND), (EXECUTOR_NODE, LOCKED_JOINT)]:
            wait_for(lambda node=node, topic=topic: _subscribes(client, node, topic), timeout=60.0,
                     what=f'{node} to subscribe to {topic}')
        # From the sim's joint state, once it has reached the planner process.
        motion = client.plan(goal=(1.0, 0.0), timeout=60.0)
        deadline = time.monotonic() + 30.0
        while 'no joint state received yet' in motion.message and time.monotonic() < deadline:
            time.sleep(0.2)
            motion = client.plan(goal=(1.0, 0.0), timeout=60.0)
        assert motion.result is Outcome.SUCCEEDED, motion.message
        assert np.allclose(motion.path[0, :2], [2.0, 0.0], atol=1e-6)
        report = client.execute(motion, timeout=120.0)
        assert report.result is Outcome.SUCCEEDED, report.message
        assert report.values['locked_joint'] == 'joint2'
        assert abs(report.number('lock_progress') - 0.5) <= DRILL_TOLERANCE
        arm = client.wait_for_status('ftplan_sim: arm',
                                     lambda v: v.get('goal_reached') == 'True', 10.0)
        assert arm is not None and arm.values['collisions'] == '0'
    finally:
        client.destroy_node()
    for name, process in nodes.items():
        code, _, err = process.interrupt()
        assert code == 0, (name, err)


@pytest.mark.parametrize('ros_args, named', [
    (['-p', 'scene_file:=/nonexistent/scene.yaml'], '/nonexistent/scene.yaml'),
    (['-r', '__node:=bad-name'], '__node:=bad-name'),  # rcl cannot parse it: rclpy.init fails
    (['-p', 'scene_file:='], 'scene_file:='),
], ids=['missing scene file', 'invalid node name', 'empty parameter value'])
def test_a_bad_start_stops_the_node_with_one_line_and_exit_code_2(processes, ros_args, named):
    planner = processes([installed('planner'), '--ros-args', *ros_args])
    code, _, err = planner.wait(timeout=60.0)
    assert code == 2
    assert 'cannot start' in err and named in err
    assert 'Traceback' not in err


def test_the_installed_planner_takes_a_panda_from_robot_description(ros, processes, tmp_path):
    """A scene without a robot, the Panda's description parameters from their params file."""
    scene_file = panda_scene(tmp_path, robot=False)
    planner = processes([installed('planner'), '--ros-args',
                         '--params-file', PARAMS / 'planner.yaml',
                         '--params-file', PARAMS / 'robot_description.yaml',
                         '-p', f'scene_file:={scene_file}'])
    ros.probe.hear_from('/diagnostics', timeout=60.0)  # the planner reports the robot once
    ros.probe.advertise(String, '/robot_description', LATCHED_QOS)
    ros.probe.publish(String, '/robot_description', String(data=PANDA_URDF.read_text()),
                      LATCHED_QOS)
    wait_for(lambda: [s for s in ros.probe.statuses('ftplan_planner: robot_description')
                      if s.level == 'OK'], timeout=60.0, what='the planner to build the Panda')
    request = GetPlan.Request(
        start=PoseStamped(header=Header(frame_id='base_link'),
                          pose=create_pose(X_S['position'], X_S['orientation'])),
        goal=PoseStamped(header=Header(frame_id='base_link'),
                         pose=create_pose(X_G['position'], X_G['orientation'])))
    response = ros.probe.call(GetPlan, '/ftplan/plan', request, timeout=60.0)
    assert response.plan.poses
    code, _, err = planner.interrupt()
    assert code == 0 and 'Traceback' not in err, err
