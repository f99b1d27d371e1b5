"""Fixtures of the ROS tests; the machinery is in ros_support.py (imported first: it sets
ROS_DOMAIN_ID for this run and worker before rclpy starts)."""

import pytest
import rclpy
from rclpy.context import Context
from ros_support import Process, RosHarness


@pytest.fixture
def ros():
    """A RosHarness (nodes spinning in a daemon thread, a probe), torn down after the test."""
    harness = RosHarness()
    try:
        yield harness
    finally:
        harness.close()


@pytest.fixture
def ros_context():
    """A bare initialised Context, for code that spins itself (e.g. a PlanClient)."""
    context = Context()
    rclpy.init(context=context)
    yield context
    rclpy.try_shutdown(context=context)


@pytest.fixture
def processes():
    """Start child processes with processes(args); all are stopped in teardown."""
    started: list[Process] = []

    def start(args) -> Process:
        process = Process([str(a) for a in args])
        started.append(process)
        return process

    yield start
    for process in started:
        process.kill()
