"""ROS test support: an isolated ROS_DOMAIN_ID, nodes spinning in a daemon thread, a probe.

Every test run and every xdist worker gets its own ROS_DOMAIN_ID (set here, before any
rclpy.init, and inherited by child processes), so concurrent runs on one host never see
each other's nodes. Each test gets a fresh rclpy Context: its nodes spin on a
MultiThreadedExecutor in a daemon thread that the fixture shuts down in teardown.
Tests wait for things to happen with generous timeouts; none of them asserts a speed.
"""

from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Callable
from pathlib import Path

import pytest
import rclpy
from rcl_interfaces.msg import Log
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile

from ftplan_msgs_py import DiagnosticReading, read_diagnostic_status
from ftplan_ros.nodes.spinning import BackgroundSpin

REPO = Path(__file__).resolve().parents[2]
INSTALL = REPO / 'install'
LIB = INSTALL / 'ftplan_ros' / 'lib' / 'ftplan_ros'
SCENES = REPO / 'config' / 'scenes'
PARAMS = REPO / 'config' / 'params'
FIG3A = SCENES / 'fig3a.yaml'
WAIT = 30.0  # [s] how long a test waits for something that should happen soon


def _domain_id() -> int:
    """A domain per test run (xdist's run id, else random) and per worker, in 1..200."""
    run = os.environ.get('PYTEST_XDIST_TESTRUNUID') or uuid.uuid4().hex
    worker = os.environ.get('PYTEST_XDIST_WORKER', 'gw0')
    index = int(worker[2:]) if worker[2:].isdigit() else 0
    slot = int(hashlib.sha256(run.encode()).hexdigest(), 16) % 50
    return 1 + (slot * 4 + index) % 200


def _isolate() -> None:
    """Set this run's ROS environment; rclpy reads it at init, so before any test runs."""
    os.environ['ROS_DOMAIN_ID'] = str(_domain_id())
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    # The installed ROS layout (`make install`), for ament_index and the default scene.
    prefix = f'{INSTALL / "ftplan_ros"}:{INSTALL / "ftplan_msgs_py"}'
    if str(INSTALL / 'ftplan_ros') not in os.environ.get('AMENT_PREFIX_PATH', ''):
        os.environ['AMENT_PREFIX_PATH'] = ':'.join(
            p for p in (prefix, os.environ.get('AMENT_PREFIX_PATH', '')) if p)


_isolate()


def wait_for(condition: Callable[[], object], timeout: float = WAIT, what: str = '') -> object:
    """Poll `condition` until it returns something truthy; fail the test after `timeout`."""
    deadline = time.monotonic() + timeout
    while True:
        value = condition()
        if value:
            return value
        if time.monotonic() > deadline:
            pytest.fail(f'timed out after {timeout} s waiting for {what or condition}')
        time.sleep(0.01)


class Probe(Node):
    """A test node: records topics, publishes, calls services (spun by the harness)."""

    def __init__(self, context: Context, name: str = 'ftplan_test_probe'):
        super().__init__(name, context=context)
        self._lock = threading.Lock()
        self.messages: dict[str, list] = {}
        self.publishers_: dict[str, object] = {}
        self.listen(Log, '/rosout', QoSProfile(depth=1000))

    def listen(self, msg_type, topic: str, qos=10) -> None:
        """Record every message on `topic` (latched topics: pass LATCHED_QOS)."""
        self.messages.setdefault(topic, [])

        def record(msg):
            with self._lock:
                self.messages[topic].append(msg)

        self.create_subscription(msg_type, topic, record, qos)

    def received(self, topic: str) -> list:
        """Return a copy of the messages recorded on `topic` so far."""
        with self._lock:
            return list(self.messages.get(topic, []))

    def publish(self, msg_type, topic: str, msg, qos=10) -> None:
        """Publish `msg`, creating the publisher (and waiting for a subscriber) first."""
        if topic not in self.publishers_:
            self.publishers_[topic] = self.create_publisher(msg_type, topic, qos)
        publisher = self.publishers_[topic]
        wait_for(lambda: publisher.get_subscription_count() > 0, what=f'a reader of {topic}')
        publisher.publish(msg)

    def call(self, srv_type, name: str, request, timeout: float = WAIT):
        """Call a service and return its response."""
        client = self.create_client(srv_type, name)
        wait_for(client.service_is_ready, timeout, f'service {name}')
        future = client.call_async(request)
        wait_for(future.done, timeout, f'the answer of {name}')
        self.destroy_client(client)
        return future.result()

    def logged(self, node_name: str, text: str) -> list[str]:
        """Return the /rosout lines of `node_name` that contain `text`."""
        return [log.msg for log in self.received('/rosout')
                if log.name == node_name and text in log.msg]

    def statuses(self, name: str) -> list[DiagnosticReading]:
        """Return the recorded /diagnostics statuses called `name`, as plain readings."""
        return [read_diagnostic_status(status) for array in self.received('/diagnostics')
                for status in array.status if status.name == name]


class RosHarness:
    """Nodes of one test on a MultiThreadedExecutor in a daemon thread, with a Probe."""

    def __init__(self):
        self.context = Context()
        rclpy.init(context=self.context)
        self.spin = BackgroundSpin(context=self.context, name='ftplan-test')
        self.probe = self.add(Probe(self.context))
        from diagnostic_msgs.msg import DiagnosticArray
        self.probe.listen(DiagnosticArray, '/diagnostics', 100)

    def add(self, node: Node) -> Node:
        """Spin `node` in the harness's executor."""
        return self.spin.add(node)

    def make(self, node_class, scene_file: Path = FIG3A, **parameters) -> Node:
        """Create a node of `node_class` with parameters and spin it."""
        overrides = [Parameter('scene_file', value=str(scene_file))]
        overrides += [Parameter(name, value=value) for name, value in parameters.items()]
        return self.add(node_class(context=self.context, parameter_overrides=overrides))

    def close(self) -> None:
        """Stop spinning, destroy every node, shut the context down."""
        self.spin.stop()
        rclpy.try_shutdown(context=self.context)


def require_install() -> None:
    """Fail with the fix when the ROS layout has not been built."""
    if not (LIB / 'planner').exists():
        pytest.fail(f'{LIB} has no executables: run `make install` first')


class Process:
    """A child process (an installed node or the bringup) stopped with SIGINT at the end."""

    def __init__(self, args: list[str]):
        self.args = args
        self.popen = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                      text=True, env=dict(os.environ), cwd=REPO)

    def alive(self) -> bool:
        """Whether the process is still running."""
        return self.popen.poll() is None

    def interrupt(self, timeout: float = WAIT) -> tuple[int, str, str]:
        """Send SIGINT; return (exit code, stdout, stderr) once it has exited."""
        import signal
        if self.alive():
            self.popen.send_signal(signal.SIGINT)
        try:
            out, err = self.popen.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.popen.kill()
            out, err = self.popen.communicate()
        return self.popen.returncode, out, err

    def kill(self) -> None:
        """Make sure the process is gone."""
        if self.alive():
            self.popen.kill()
        self.popen.communicate()


def installed(executable: str) -> str:
    """Return the path of an installed executable in lib/ftplan_ros."""
    require_install()
    return str(LIB / executable)


PYTHON = sys.executable
