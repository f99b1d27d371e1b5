"""Plan workers without ROS: a job plans in a worker as it plans here, errors come back, close."""

import threading

import numpy as np
import pytest
from ftplan_testing import SCENES

from ftplan_ros.core import InputError, ManifoldCache, Task, load_scene
from ftplan_ros.nodes.plan_jobs import PlanJob, PlanSettings, run_job
from ftplan_ros.nodes.plan_pool import PlanPool


@pytest.fixture
def pool():
    pool = PlanPool(1)
    yield pool
    pool.close()


def _job(name: str) -> PlanJob:
    return PlanJob(load_scene(SCENES / f'{name}.yaml'), None, PlanSettings(), 60.0)


def test_jobs_plan_in_a_worker_as_here_robot_after_robot(pool):
    jobs = [_job('fig3a'), _job('panda_free_pose'), _job('fig3a'), _job('panda_free_pose')]
    here = ManifoldCache()   # one cache over the jobs, as the worker keeps one
    for job in jobs:
        there, _ = pool.run(job)
        expected, _ = run_job(job, here)
        assert there.feasible and expected.feasible
        assert there.joint_names == expected.joint_names
        assert np.array_equal(there.nominal_path, expected.nominal_path)
        assert np.array_equal(there.surface.paths, expected.surface.paths)


def test_a_job_the_core_refuses_raises_its_input_error_and_the_worker_stays(pool):
    job = _job('fig3a')
    far = PlanJob(job.scene.with_task(Task((2.0, 0.0), (4.0, 0.0))), None, PlanSettings(), 60.0)
    with pytest.raises(InputError, match="task.goal: .*out of the arm's reach") as refused:
        pool.run(far)
    assert refused.value.field == 'task.goal'
    [pid] = pool.pids
    assert pool.run(job)[0].feasible and pool.pids == (pid,)


def test_a_job_that_does_not_pickle_is_refused_and_the_pool_keeps_its_worker(pool):
    job = _job('fig3a')
    unsendable = PlanJob(job.scene, threading.Lock(), PlanSettings(), 60.0)   # a lock for q
    with pytest.raises(TypeError, match='cannot pickle'):
        pool.run(unsendable)
    assert pool.run(job)[0].feasible


def test_close_ends_every_worker():
    pool = PlanPool(2)
    processes = list(pool._workers)
    assert all(worker.process.is_alive() for worker in processes)
    pool.close()
    assert not any(worker.process.is_alive() for worker in processes)
    assert [worker.process.exitcode for worker in processes] == [0, 0]   # idle: they left
    assert pool.pids == ()
