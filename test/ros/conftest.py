"""Fixtures of the ROS tests; the machinery is in ros_support.py (imported first: it claims
a ROS_DOMAIN_ID for this test process before rclpy starts)."""

from pathlib import Path

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
def processes(tmp_path):
    """Start child processes with processes(args); all are stopped in teardown.

    Each one writes its stdout and stderr to files in the test's tmp_path (kept by pytest
    for the last runs), named after the executable.
    """
    started: list[Process] = []

    def start(args) -> Process:
        args = [str(a) for a in args]
        process = Process(args, tmp_path / f'{len(started) + 1}-{Path(args[0]).name}')
        started.append(process)
        return process

    yield start
    for process in started:
        process.kill()
