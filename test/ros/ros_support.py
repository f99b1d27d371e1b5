"""ROS test support: an isolated ROS_DOMAIN_ID, nodes spinning in a daemon thread, a probe.

Every test process (each xdist worker) claims a ROS_DOMAIN_ID that no other ftplan test
run or benchmark on this host holds (ros_domain.py; set here, before any rclpy.init, and
inherited by child processes), so concurrent runs never see each other's nodes. Each test
gets a fresh rclpy Context: its nodes spin on a MultiThreadedExecutor in a daemon thread
that the fixture shuts down in teardown.
Tests wait for things to happen with generous timeouts; none of them asserts a speed.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest
import rclpy
from rcl_interfaces.msg import Log
from rclpy.context import Context
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import QoSProfile
from ros_domain import claim_domain

from ftplan_msgs_py import DiagnosticReading, read_diagnostic_status
from ftplan_ros.nodes.spinning import BackgroundSpin

REPO = Path(__file__).resolve().parents[2]
INSTALL = REPO / 'install'
LIB = INSTALL / 'ftplan_ros' / 'lib' / 'ftplan_ros'
SCENES = REPO / 'config' / 'scenes'
PARAMS = REPO / 'config' / 'params'
FIG3A = SCENES / 'fig3a.yaml'
WAIT = 30.0  # [s] how long a test waits for something that should happen soon


def _isolate() -> None:
    """Set this process's ROS environment; rclpy reads it at init, so before any test runs."""
    claim_domain()
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
        self.subscriptions_: dict[str, object] = {}
        self.listen(Log, '/rosout', QoSProfile(depth=1000))

    def listen(self, msg_type, topic: str, qos=10) -> None:
        """Record every message on `topic` (latched topics: pass LATCHED_QOS)."""
        self.messages.setdefault(topic, [])

        def record(msg):
            with self._lock:
                self.messages[topic].append(msg)

        self.subscriptions_[topic] = self.create_subscription(msg_type, topic, record, qos)

    def hear_from(self, topic: str, writers: int = 1, timeout: float = WAIT) -> None:
        """Wait until `writers` publishers match the probe's recording of `topic`.

        Call it before a node publishes something once on a volatile topic (a status), as
        `advertise` is called before the probe publishes: a message sent before the match
        is lost, and a loaded machine can take seconds to discover a new process.
        """
        subscription = self.subscriptions_[topic]
        wait_for(lambda: subscription.get_publisher_count() >= writers, timeout,
                 f'{writers} writers of {topic}')

    def received(self, topic: str) -> list:
        """Return a copy of the messages recorded on `topic` so far."""
        with self._lock:
            return list(self.messages.get(topic, []))

    def advertise(self, msg_type, topic: str, qos=10, readers: int = 1) -> None:
        """Create the publisher of `topic` and wait until `readers` subscribers match it.

        Call it before the moment a test must publish at, so that discovery is done by then.
        """
        if topic not in self.publishers_:
            self.publishers_[topic] = self.create_publisher(msg_type, topic, qos)
        publisher = self.publishers_[topic]
        wait_for(lambda: publisher.get_subscription_count() >= readers,
                 what=f'{readers} readers of {topic}')

    def publish(self, msg_type, topic: str, msg, qos=10) -> None:
        """Publish `msg`, advertising `topic` first if this probe has not yet."""
        self.advertise(msg_type, topic, qos)
        self.publishers_[topic].publish(msg)

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
    """A child process (an installed node or the bringup) stopped with SIGINT at the end.

    Its stdout and stderr go to `<logs>.out` and `<logs>.err` (a pipe that nobody reads
    while it runs could fill up and block it); output() reads what it has written so far.
    """

    def __init__(self, args: list[str], logs: Path):
        self.args = args
        self.stdout_path = logs.parent / f'{logs.name}.out'
        self.stderr_path = logs.parent / f'{logs.name}.err'
        with open(self.stdout_path, 'w') as out, open(self.stderr_path, 'w') as err:
            self.popen = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=out,
                                          stderr=err, env=dict(os.environ), cwd=REPO)

    def alive(self) -> bool:
        """Whether the process is still running."""
        return self.popen.poll() is None

    def output(self) -> tuple[str, str]:
        """Return (stdout, stderr) as written so far."""
        return (self.stdout_path.read_text(errors='replace'),
                self.stderr_path.read_text(errors='replace'))

    def wait(self, timeout: float = WAIT) -> tuple[int, str, str]:
        """Wait for the exit; return (exit code, stdout, stderr). Fail the test on timeout."""
        try:
            self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            out, err = self.output()
            pytest.fail(f'{self.args[0]} still ran after {timeout} s; killed it.\n'
                        f'stdout:\n{out[-2000:]}\nstderr:\n{err[-2000:]}')
        return (self.popen.returncode, *self.output())

    def interrupt(self, timeout: float = WAIT) -> tuple[int, str, str]:
        """Send SIGINT; return (exit code, stdout, stderr) once it has exited (else kill it)."""
        if self.alive():
            self.popen.send_signal(signal.SIGINT)
        try:
            self.popen.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill()
        return (self.popen.returncode, *self.output())

    def kill(self) -> None:
        """Make sure the process is gone."""
        if self.alive():
            self.popen.kill()
        self.popen.wait()


def children(pid: int) -> list[int]:
    """Return the process ids whose parent is `pid` (from /proc)."""
    found = []
    for stat in Path('/proc').glob('[0-9]*/stat'):
        try:
            fields = stat.read_text().rsplit(')', 1)[1].split()
        except OSError:  # it ended meanwhile
            continue
        if int(fields[1]) == pid:
            found.append(int(stat.parent.name))
    return found


def descendants(pid: int) -> list[int]:
    """Return the process ids of the children of `pid`, their children, and so on."""
    found = children(pid)
    for child in list(found):
        found += descendants(child)
    return found


def running(pid: int) -> bool:
    """Whether process `pid` exists and has not ended (a zombie has)."""
    try:
        state = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ('Z', 'X')


def plan_workers(planner_pid: int) -> list[int]:
    """Return the plan workers of a planner process: the children of its fork server."""
    servers = [pid for pid in children(planner_pid)
               if b'forkserver' in _command_line(pid)]
    return [pid for server in servers for pid in children(server)]


def _command_line(pid: int) -> bytes:
    try:
        return Path(f'/proc/{pid}/cmdline').read_bytes()
    except OSError:
        return b''


def installed(executable: str) -> str:
    """Return the path of an installed executable in lib/ftplan_ros."""
    require_install()
    return str(LIB / executable)


PYTHON = sys.executable
