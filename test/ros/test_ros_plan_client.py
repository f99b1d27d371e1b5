"""PlanClient: outcomes as an Enum with a message, no futures for the caller."""

import os
import signal
import threading

import numpy as np
from ros_support import FIG3A, installed, plan_workers, running, wait_for

from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.nodes.sim import SimNode
from ftplan_ros.plan_client import Outcome, PlanClient


def test_without_a_planner_the_client_says_unavailable(ros_context):
    client = PlanClient(context=ros_context)
    try:
        assert not client.wait_until_ready(timeout=0.5)
        motion = client.plan(goal=(1.0, 0.0), timeout=0.5)
        assert motion.result is Outcome.UNAVAILABLE and '/ftplan/plan' in motion.message
        report = client.execute(timeout=0.5)
        assert report.result is Outcome.UNAVAILABLE
        assert client.trigger('/ftplan_sim/reset', timeout=0.2)[0] is False
    finally:
        client.destroy_node()


def test_a_failed_plan_carries_the_planners_reason(ros):
    ros.make(PlannerNode)
    client = PlanClient(context=ros.context)
    try:
        motion = client.plan(goal=(4.0, 0.0), start=(2.0, 0.0))
        assert motion.result is Outcome.FAILED and not motion.succeeded
        assert "out of the arm's reach" in motion.message
        assert motion.theta_s is None and motion.stamp
    finally:
        client.destroy_node()


def test_a_plan_comes_back_as_one_result(ros):
    ros.make(PlannerNode)
    client = PlanClient(context=ros.context)
    try:
        assert client.wait_until_ready(timeout=1.0) is False   # no executor in this test
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), tolerance=0.02)
    finally:
        client.destroy_node()
    assert motion.result is Outcome.SUCCEEDED, motion.message
    assert motion.joint_names == ('joint1', 'joint2', 'joint3')
    assert np.array_equal(motion.trajectory[0], motion.theta_s)
    assert np.array_equal(motion.surface[motion.nominal_index], motion.trajectory)
    assert np.all(np.diff(motion.times) > 0)
    assert np.allclose(motion.path[0, :2], [2.0, 0.0]) and motion.round_trip_s > 0
    assert np.linalg.norm(motion.path[-1, :2] - [1.0, 0.0]) <= 0.02   # the tolerance asked
    assert motion.plan_time_s > 0
    wait_for(lambda: ros.probe.logged('ftplan_planner', 'plan found'))


def test_a_planner_killed_mid_request_fails_the_plan_saying_it_left(ros_context, processes):
    """The client watches the ROS graph: it does not wait out its timeout for a dead planner."""
    planner = processes([installed('planner'), '--ros-args', '-p', f'scene_file:={FIG3A}',
                         '-p', 'plan_workers:=1'])
    client = PlanClient(context=ros_context)
    try:
        assert client.spin_until(client.plan_client.service_is_ready, 60.0)
        [worker] = plan_workers(planner.popen.pid)
        os.kill(worker, signal.SIGSTOP)   # the request cannot be answered

        def kill_the_planner() -> None:
            planner.kill()   # SIGKILL: DDS sees the planner go when its lease (20 s) ends
            os.kill(worker, signal.SIGCONT)

        killer = threading.Timer(1.0, kill_the_planner)
        killer.start()
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=120.0)
        killer.join()
    finally:
        client.destroy_node()
    assert motion.result is Outcome.FAILED   # not TIMED_OUT: it did not wait 120 s
    assert motion.message == ('/ftplan/plan left the ROS graph before answering: the planner '
                              'is gone (stopped, or its process died)')
    wait_for(lambda: not running(worker), what='the orphaned worker to end')


def test_an_executor_stopped_mid_execution_fails_the_execution_saying_it_left(ros, processes):
    ros.make(PlannerNode)
    ros.make(SimNode, max_joint_speed=4.0)
    executor = processes([installed('executor'), '--ros-args', '-p', f'scene_file:={FIG3A}',
                          '-p', 'max_joint_speed:=0.2'])   # an execution of about 10 s

    def stop_the_executor_once_it_moves() -> None:
        wait_for(lambda: [s for s in ros.probe.statuses('ftplan_executor: execution')
                          if s.values.get('state') in ('approaching', 'nominal')],
                 timeout=120.0, what='the execution under way')
        executor.popen.send_signal(signal.SIGTERM)

    client = PlanClient(context=ros.context)
    try:
        assert client.wait_until_ready(timeout=60.0)
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=60.0)
        assert motion.result is Outcome.SUCCEEDED, motion.message
        stopper = threading.Thread(target=stop_the_executor_once_it_moves)
        stopper.start()
        report = client.execute(motion, timeout=120.0)
        stopper.join()
    finally:
        client.destroy_node()
    assert report.result is Outcome.FAILED   # not TIMED_OUT: it did not wait 120 s
    assert report.message == (f'execution {report.execution}: the executor left the ROS graph '
                              '(/ftplan/execute has no server) before it finished')
