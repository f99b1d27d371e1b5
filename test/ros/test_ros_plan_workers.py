"""The planner's plan workers (`plan_workers` >= 1): plans side by side, a worker that dies
or hangs fails its own request only, and the workers end with the node."""

import os
import signal
import threading

import numpy as np
import pytest
from nav_msgs.srv import GetPlan
from rclpy.parameter import Parameter
from ros_support import FIG3A, WAIT, descendants, installed, plan_workers, running, wait_for
from test_ros_planner import plan_ok, request
from test_ros_reliability import status_of

from ftplan_ros.core import InputError
from ftplan_ros.nodes.planner import PlannerNode
from ftplan_ros.plan_client import Outcome, PlanClient

GOALS = [(1.0, 0.0), (1.2, 0.3), (0.9, -0.4), (1.4, 0.1)]


def test_four_clients_at_once_each_get_their_own_plan_from_two_workers(ros):
    ros.make(PlannerNode, plan_workers=2)
    clients = [PlanClient(f'ftplan_client_{k}', context=ros.context) for k in range(4)]
    motions = [None] * len(clients)

    def ask(k: int) -> None:
        motions[k] = clients[k].plan(goal=GOALS[k], start=(2.0, 0.0), timeout=WAIT)

    try:
        for _ in range(3):   # plans answered together publish their results back to back
            threads = [threading.Thread(target=ask, args=(k,)) for k in range(len(clients))]
            for thread in threads:
                thread.start()
            for thread in threads:
                thread.join()
            for motion, goal in zip(motions, GOALS, strict=True):
                assert motion.result is Outcome.SUCCEEDED, motion.message
                assert np.linalg.norm(motion.path[-1, :2] - goal) <= 0.01   # its own plan
                assert np.array_equal(motion.surface[motion.nominal_index], motion.trajectory)
    finally:
        for client in clients:
            client.destroy_node()


def test_a_worker_that_dies_fails_its_request_and_the_next_request_is_planned(ros):
    planner = ros.make(PlannerNode, plan_workers=1)
    plan_ok(ros)
    [pid] = planner.pool.pids
    os.kill(pid, signal.SIGSTOP)   # the request waits in the worker until it is killed
    client = ros.probe.create_client(GetPlan, '/ftplan/plan')
    future = client.call_async(request())
    wait_for(lambda: planner.pool.busy == (pid,), what='the request in the worker')
    os.kill(pid, signal.SIGKILL)
    wait_for(future.done, what='the answer')
    assert future.result().plan.poses == []
    assert status_of(ros, future.result()).message == (
        f'internal planner error: plan worker {pid} died of SIGKILL while planning; a new '
        'worker takes its place')
    wait_for(lambda: len(planner.pool.pids) == 1, what='a new worker')
    assert pid not in planner.pool.pids
    # The new worker warms up first: with numba's cache cold (a fresh clone) it compiles
    # the kernels again, about a minute on a loaded machine.
    answer = ros.probe.call(GetPlan, '/ftplan/plan', request(), timeout=300.0)
    assert answer.plan.poses, status_of(ros, answer).message


def test_a_worker_still_busy_past_plan_timeout_is_replaced(ros):
    planner = ros.make(PlannerNode, plan_workers=1, plan_timeout=1.0)
    plan_ok(ros)   # its first plan: from now on it has no warm-up allowance
    [pid] = planner.pool.pids
    os.kill(pid, signal.SIGSTOP)   # hung: it will never reach its next stage
    response = ros.probe.call(GetPlan, '/ftplan/plan', request())
    assert response.plan.poses == []
    assert 'no answer within plan_timeout = 1 s' in status_of(ros, response).message
    assert not running(pid)
    wait_for(lambda: len(planner.pool.pids) == 1, what='a new worker')
    assert pid not in planner.pool.pids
    plan_ok(ros)


@pytest.mark.parametrize('workers', [-1, (os.cpu_count() or 1) + 1])
def test_plan_workers_out_of_range_stop_the_start_naming_the_parameter(ros, workers):
    with pytest.raises(InputError, match=r'plan_workers: must be an integer from 0'):
        PlannerNode(context=ros.context, parameter_overrides=[
            Parameter('scene_file', value=str(FIG3A)), Parameter('plan_workers', value=workers)])


def test_plan_workers_cannot_change_while_the_planner_runs(ros):
    planner = ros.make(PlannerNode, plan_workers=1)
    [result] = planner.set_parameters([Parameter('plan_workers', value=0)])
    assert not result.successful and 'read-only parameter: plan_workers' in result.reason
    assert len(planner.pool.pids) == 1


def test_sigterm_ends_the_installed_planner_and_all_its_workers(ros, processes):
    planner = processes([installed('planner'), '--ros-args', '-p', f'scene_file:={FIG3A}',
                         '-p', 'plan_workers:=2'])
    response = ros.probe.call(GetPlan, '/ftplan/plan', request(), timeout=60.0)
    assert response.plan.poses
    workers = plan_workers(planner.popen.pid)
    family = descendants(planner.popen.pid)   # the workers, their fork server and so on
    assert len(workers) == 2 and set(workers) < set(family)
    planner.popen.send_signal(signal.SIGTERM)
    code, _, err = planner.wait()
    assert code == 0, err
    assert 'Traceback' not in err
    wait_for(lambda: not any(running(pid) for pid in family), what='no process left behind')
