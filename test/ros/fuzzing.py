"""Malformed messages and requests at running nodes, and what must survive them (issue 10).

The planner, executor, sim and injector run as the installed executables, each in its
own process, on fig3a; a second planner, in a ROS domain of its own, waits for its robot
on /robot_description. After a good plan and execution, every input of theirs gets
malformed messages drawn from a seeded generator (each one malformed: a marker array
holds at least one bad marker, so none is ever applied, and the nodes then hold a set
that is not the one published until a full set arrives), then the plan service gets
malformed requests, then the Trigger services get calls in a random order. Afterwards,
with a full set of obstacles (DELETEALL) published:

- no process died (`deaths`);
- each process's resident memory (VmRSS) grew by at most 10 % (`rss_before`: after a
  warm-up round of every generator; `rss_after`);
- the last good plan is kept: the planner's latched results and the executor's held plan
  still carry its stamp;
- a valid request is answered correctly: the same plan again, executed to the goal
  without collision.

Used by test_ros_fuzz.py (a few hundred messages) and benchmarks/fuzz_nodes.py (>= 10,000
per input). Nothing here needs pytest.
"""

from __future__ import annotations

import math
import os
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import rclpy
from builtin_interfaces.msg import Duration, Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, Vector3
from nav_msgs.srv import GetPlan
from rclpy.context import Context
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import (
    Float64MultiArray,
    Header,
    MultiArrayDimension,
    MultiArrayLayout,
    String,
)
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.reporting import stamp_key
from ftplan_ros.plan_client import Outcome, PlanClient

REPO = Path(__file__).resolve().parents[2]
LIB = REPO / 'install' / 'ftplan_ros' / 'lib' / 'ftplan_ros'
FIG3A = REPO / 'config' / 'scenes' / 'fig3a.yaml'
PANDA_URDF = REPO / 'config' / 'robots' / 'panda.urdf'
NAMES = ['joint1', 'joint2', 'joint3']
NODES = ('planner', 'executor', 'sim', 'injector')
BAD = [math.nan, math.inf, -math.inf, 1e308, -1e308, 1e200, 1e155, 1e7]
RSS_GROWTH = 0.10  # at most 10 % more resident memory after the fuzz


@dataclass
class FuzzReport:
    """What a fuzz run sent, and what survived it."""

    sent: dict[str, int] = field(default_factory=dict)       # per input
    deaths: list[str] = field(default_factory=list)
    rss_before: dict[str, int] = field(default_factory=dict)  # [kB] per process
    rss_after: dict[str, int] = field(default_factory=dict)
    good_plan: str = ''
    plan_kept: bool = False
    held_plan: str = ''
    answered_after: bool = False
    answer: str = ''
    seconds: float = 0.0

    @property
    def messages(self) -> int:
        """Messages and requests sent in all."""
        return sum(self.sent.values())

    def rss_growth(self) -> dict[str, float]:
        """Growth of each process's resident memory as a fraction of its size before."""
        return {name: self.rss_after.get(name, 0) / before - 1.0
                for name, before in self.rss_before.items() if before}

    def problems(self) -> list[str]:
        """Say what went wrong; empty when the run passed."""
        problems = [f'{name} died' for name in self.deaths]
        problems += [f'{name} grew {growth:.1%} (RSS {self.rss_before[name]} -> '
                     f'{self.rss_after[name]} kB)' for name, growth in self.rss_growth().items()
                     if growth > RSS_GROWTH]
        if not self.plan_kept:
            problems.append(f'the last good plan {self.good_plan} was not kept (the executor '
                            f'holds {self.held_plan!r})')
        if not self.answered_after:
            problems.append(f'the valid request afterwards failed: {self.answer}')
        return problems

    def summary(self) -> str:
        """Tabulate the run."""
        lines = [f'{self.messages} malformed messages and requests in {self.seconds:.0f} s; '
                 f'deaths: {len(self.deaths)}']
        lines += [f'  {name:<22}{count:>8}' for name, count in self.sent.items()]
        lines.append('  resident memory [kB]: ' + ', '.join(
            f'{name} {self.rss_before[name]} -> {self.rss_after.get(name, 0)} '
            f'({growth:+.1%})' for name, growth in self.rss_growth().items()))
        lines.append(f'  last good plan {self.good_plan} kept: {self.plan_kept}; valid request '
                     f'afterwards: {self.answer}')
        return '\n'.join(lines)


def rss_kb(pid: int) -> int:
    """Return a process's resident memory [kB] (0 once it is gone)."""
    try:
        for line in Path(f'/proc/{pid}/status').read_text().splitlines():
            if line.startswith('VmRSS:'):
                return int(line.split()[1])
    except OSError:
        pass
    return 0


# Malformed messages: each generator draws one from the generator `g` --------------------

def _bad(g: np.random.Generator) -> float:
    return BAD[int(g.integers(len(BAD)))]


def _stamp(g: np.random.Generator) -> Time:
    return Time(sec=int(g.integers(0, 2**31 - 1)), nanosec=int(g.integers(0, 10**9)))


def _text(g: np.random.Generator, size: int = 8) -> str:
    return ''.join(chr(int(c)) for c in g.integers(33, 127, int(g.integers(0, size))))


def joint_state(g: np.random.Generator) -> JointState:
    """A joint state that names the arm's joints but is broken somehow."""
    q = g.uniform(-3.0, 3.0, 3)
    msg = JointState(header=Header(stamp=_stamp(g)), name=list(NAMES), position=q.tolist())
    defect = int(g.integers(6))
    if defect == 0:
        msg.position[int(g.integers(3))] = _bad(g)
    elif defect == 1:
        msg.position = q[:int(g.integers(0, 3))].tolist()
    elif defect == 2:
        msg.name = [NAMES[0], NAMES[0], NAMES[2]]
    elif defect == 3:
        msg.name = [NAMES[0], _text(g) + '?', NAMES[2]]
    elif defect == 4:
        msg.header.stamp = Time(sec=int(g.integers(-2**31, 0)), nanosec=0)
    else:
        msg.header.stamp = Time(sec=1, nanosec=int(g.integers(10**9, 2**32)))
    return msg


def _marker(g: np.random.Generator, good: bool) -> Marker:
    marker = Marker(header=Header(frame_id='base_link'), ns=_text(g), id=int(g.integers(100)),
                    type=int(g.choice([Marker.SPHERE, Marker.CUBE, Marker.CYLINDER])),
                    action=Marker.ADD, pose=Pose(position=Point(
                        x=float(g.uniform(5, 9)), y=float(g.uniform(5, 9))),
                        orientation=Quaternion(w=1.0)),
                    scale=Vector3(x=0.2, y=0.2, z=0.2))
    if good:
        return marker
    defect = int(g.integers(7))
    if defect == 0:
        marker.header.frame_id = g.choice(['map', '', 'world', _text(g)])
    elif defect == 1:
        marker.type = int(g.choice([Marker.ARROW, Marker.LINE_STRIP, Marker.TEXT_VIEW_FACING,
                                    Marker.MESH_RESOURCE, int(g.integers(-2**31, 2**31))]))
    elif defect == 2:
        marker.action = int(g.choice([Marker.MODIFY + 7, -1, int(g.integers(4, 2**31))]))
    elif defect == 3:
        setattr(marker.pose.position, 'xyz'[int(g.integers(3))], _bad(g))
    elif defect == 4:
        setattr(marker.scale, 'xyz'[int(g.integers(3))],
                float(g.choice([0.0, -1.0, math.nan, math.inf, 1e200])))
    elif defect == 5:
        marker.pose.orientation = Quaternion(x=0.0, y=0.0, z=0.0, w=0.0)
    else:
        marker.pose.orientation = Quaternion(x=float(g.choice([math.nan, math.inf])), y=0.0,
                                             z=0.0, w=1.0)
    return marker


def marker_array(g: np.random.Generator) -> MarkerArray:
    """Up to 20 markers, good ones around a bad one: the array is refused whole."""
    count = int(g.integers(1, 21))
    bad = int(g.integers(count))
    return MarkerArray(markers=[_marker(g, k != bad) for k in range(count)])


def locked_joint(g: np.random.Generator) -> JointState:
    """A lock event that must be refused: it would otherwise lock a joint of the arm."""
    defect = int(g.integers(6))
    if defect == 0:
        return JointState(name=[_text(g) + '?'])
    if defect == 5:  # its moment before the epoch: refused, not taken as at once
        return JointState(header=Header(stamp=Time(sec=int(g.integers(-2**31, 0)))),
                          name=[str(g.choice(NAMES))])
    if defect == 1:
        return JointState(name=[])
    if defect == 2:
        return JointState(name=list(g.choice(NAMES, size=2, replace=False)))
    if defect == 3:
        return JointState(name=[str(g.choice(NAMES))], position=[0.1, 0.2])
    return JointState(name=[str(g.choice(NAMES))], position=[_bad(g)])


def joint_trajectory(g: np.random.Generator) -> JointTrajectory:
    """A command or nominal trajectory of the arm, broken somehow."""
    k = int(g.integers(1, 6))
    points = [JointTrajectoryPoint(positions=g.uniform(-1, 1, 3).tolist(),
                                   time_from_start=Duration(sec=i + 1)) for i in range(k)]
    msg = JointTrajectory(header=Header(stamp=_stamp(g)), joint_names=list(NAMES),
                          points=points)
    defect = int(g.integers(7))
    point = points[int(g.integers(k))]
    if defect == 0:
        msg.joint_names = [NAMES[0], NAMES[1], _text(g) + '?']
    elif defect == 1:
        msg.joint_names = [NAMES[0], NAMES[0], NAMES[2]]
    elif defect == 2:
        point.positions = list(point.positions)[:int(g.integers(0, 3))]
    elif defect == 3:
        positions = list(point.positions)
        positions[int(g.integers(3))] = _bad(g)
        point.positions = positions
    elif defect == 4:
        point.time_from_start = Duration(sec=int(g.integers(-2**31, 0)))
    elif defect == 5:
        point.time_from_start = Duration(sec=0, nanosec=int(g.integers(10**9, 2**32)))
    else:
        points[0].time_from_start = Duration(sec=k + 5)
        msg.points = points if k > 1 else points + [JointTrajectoryPoint(
            positions=[0.0, 0.0, 0.0], time_from_start=Duration(sec=1))]
    return msg


def start_configuration(g: np.random.Generator) -> JointState:
    """θ_s of a plan, broken (missing or non-finite joints)."""
    msg = joint_state(g)
    if int(g.integers(2)):
        msg.position = msg.position[:2]
    return msg


def failure_surface(g: np.random.Generator) -> Float64MultiArray:
    """S_F with a broken layout or values."""
    K, W, n = (int(v) for v in g.integers(1, 5, 3))
    labels = ['path', 'waypoint', 'joint']
    sizes, strides = [K, W, n], [K * W * n, W * n, n]
    data = g.uniform(-3, 3, K * W * n).tolist()
    defect = int(g.integers(6))
    if defect == 0:
        labels[int(g.integers(3))] = _text(g)
    elif defect == 1:
        sizes[int(g.integers(3))] = int(g.choice([0, 2**32 - 1, int(g.integers(5, 1000))]))
    elif defect == 2:
        strides[int(g.integers(3))] += int(g.integers(1, 100))
    elif defect == 3:
        data = data[:int(g.integers(0, len(data)))]
    elif defect == 4:
        data[int(g.integers(len(data)))] = _bad(g)
    else:
        labels, sizes, strides = labels[:2], sizes[:2], strides[:2]
    return Float64MultiArray(layout=MultiArrayLayout(dim=[
        MultiArrayDimension(label=label, size=size, stride=stride)
        for label, size, stride in zip(labels, sizes, strides, strict=True)],
        data_offset=int(g.choice([0, 0, 0, int(g.integers(1, 2**32))]))), data=data)


def diagnostics(g: np.random.Generator) -> DiagnosticArray:
    """Statuses as the executor and injector read them (plan infos, executions), broken."""
    name = str(g.choice(['ftplan_planner: plan', 'ftplan_executor: execution']))
    values = {'stamp': f'{int(g.integers(1, 9))}.000000001', 'task_kind': 'planar',
              'start': '[2.0, 0.0]', 'goal': '[1.0, 0.0]', 'tolerance': '0.01',
              'orientation_tolerance': '0.01', 'tolerated_joints': 'joint1',
              'state': 'approaching', 'execution': str(int(g.integers(1, 99))), 'plan': '1.0'}
    defect = int(g.integers(5))
    level = 0
    if defect == 0:
        values['goal'] = str(g.choice(['[nan, 0.0]', '[inf, 1.0]', '[', '[1e400, 0]']))
    elif defect == 1:
        values['tolerance'] = str(g.choice(['nan', '-1', 'inf', '0', 'x']))
    elif defect == 2:
        values['execution'] = str(g.choice(['nan', '', '-', _text(g)]))
        values.pop('stamp')
    elif defect == 3:
        level = int(g.integers(4, 256))
    pairs = [KeyValue(key=k, value=v) for k, v in values.items()]
    if defect == 4:
        pairs.append(KeyValue(key='goal', value='[1.0, 0.0]'))  # a key twice
        values['goal'] = 'garbage'
        pairs[3].value = values['goal']
    return DiagnosticArray(status=[DiagnosticStatus(name=name, level=bytes([level]),
                                                    message=_text(g), values=pairs)])


def robot_description(g: np.random.Generator, urdf: str) -> String:
    """A URDF that cannot be used: garbage, cut short, non-finite, other links, huge."""
    defect = int(g.integers(6))
    if defect == 0:
        text = _text(g, 200)
    elif defect == 1:
        text = urdf[:int(g.integers(len(urdf)))]
    elif defect == 2:
        text = urdf.replace('xyz="0 0 0.333"', f'xyz="0 0 {g.choice(["nan", "inf", "1e400"])}"')
    elif defect == 3:
        text = urdf.replace('panda_hand_tcp', _text(g) + 'x')
    elif defect == 4:
        text = ('<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
                '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
                '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;">]><robot name="&c;"/>')
    else:
        text = '<robot name="x">' + '<link name="l"/>' * int(g.integers(1, 20000)) + '</robot>'
    return String(data=text)


def plan_request(g: np.random.Generator) -> GetPlan.Request:
    """A plan request that must be refused before any planning."""
    def pose(x, y, frame='base_link', z=0.0, q=(0.0, 0.0, 0.0, 1.0)):
        return PoseStamped(header=Header(frame_id=frame), pose=Pose(
            position=Point(x=x, y=y, z=z), orientation=Quaternion(x=q[0], y=q[1], z=q[2],
                                                                  w=q[3])))
    start, goal, tolerance = pose(2.0, 0.0), pose(1.0, 0.0), 0.0
    defect = int(g.integers(6))
    if defect == 0:
        goal.header.frame_id = str(g.choice(['map', 'world', _text(g) + '?']))
    elif defect == 1:
        start.pose.position.x = _bad(g)
    elif defect == 2:
        goal = pose(1.0, 0.0, z=float(g.choice([0.5, -1.0, math.nan])))
    elif defect == 3:
        tolerance = float(g.choice([-1.0, math.nan, math.inf, 1e-40]))
    elif defect == 4:
        goal = pose(float(g.uniform(3.5, 100.0)), 0.0)          # out of reach
    else:
        goal = pose(2.0, 0.0)                                    # the start itself
    return GetPlan.Request(start=start, goal=goal, tolerance=tolerance)


# The run --------------------------------------------------------------------------------

TOPICS: dict[str, tuple[type, str, object]] = {
    'joint_states': (JointState, '/joint_states', 10),
    'obstacles': (MarkerArray, '/ftplan/obstacles', LATCHED_QOS),
    'locked_joint': (JointState, '/ftplan/locked_joint', 10),
    'joint_command': (JointTrajectory, '/ftplan/joint_command', 10),
    'start_configuration': (JointState, '/ftplan/plan/start_configuration', LATCHED_QOS),
    'trajectory': (JointTrajectory, '/ftplan/plan/trajectory', LATCHED_QOS),
    'failure_surface': (Float64MultiArray, '/ftplan/plan/failure_surface', LATCHED_QOS),
    'diagnostics': (DiagnosticArray, '/diagnostics', 10),
}
GENERATORS: dict[str, Callable[[np.random.Generator], object]] = {
    'joint_states': joint_state, 'obstacles': marker_array, 'locked_joint': locked_joint,
    'joint_command': joint_trajectory, 'start_configuration': start_configuration,
    'trajectory': joint_trajectory, 'failure_surface': failure_surface,
    'diagnostics': diagnostics,
}
TRIGGERS = ('/ftplan/execute', '/ftplan_executor/reset', '/ftplan_sim/reset')


class FuzzRun:
    """Start the nodes, fuzz them, check them; see the module docstring.

    `second_domain` is a free ROS domain for the planner that waits for its robot on
    /robot_description (the caller claims it: ros_domain.py).
    """

    def __init__(self, logs: Path, second_domain: int, seed: int = 0, rate: float = 2000.0,
                 progress: Callable[[str], None] | None = None):
        self.logs = logs
        self.second_domain = second_domain
        self.g = np.random.default_rng(seed)
        self.period = 1.0 / rate
        self.progress = progress or (lambda line: None)
        self.report = FuzzReport()
        self.processes: dict[str, subprocess.Popen] = {}
        self.context = Context()
        self.urdf_context = Context()
        self.node: Node | None = None
        self.urdf_node: Node | None = None
        self.client: PlanClient | None = None
        self.urdf = PANDA_URDF.read_text()

    # Processes ------------------------------------------------------------------------

    def start(self) -> None:
        """Start the five node processes and this process's fuzzing nodes."""
        for name in NODES:
            self._spawn(name, [str(LIB / name), '--ros-args', '-p', f'scene_file:={FIG3A}',
                               '--log-level', 'warn'], os.environ.get('ROS_DOMAIN_ID', ''))
        robotless = self.logs / 'no_robot.yaml'
        robotless.write_text('obstacles:\n  - {type: sphere, center: [0.5, 0.5, 0.5], '
                             'radius: 0.1}\n')
        self._spawn('planner_urdf', [str(LIB / 'planner'), '--ros-args', '-p',
                                     f'scene_file:={robotless}', '-p', 'tip_link:=panda_hand_tcp',
                                     '--log-level', 'warn'], str(self.second_domain))
        rclpy.init(context=self.context)
        rclpy.init(context=self.urdf_context, domain_id=self.second_domain)
        self.node = Node('ftplan_fuzzer', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.urdf_node = Node('ftplan_fuzzer', context=self.urdf_context)
        self.client = PlanClient('ftplan_fuzz_client', context=self.context)

    def _spawn(self, name: str, args: list[str], domain: str) -> None:
        env = dict(os.environ, ROS_DOMAIN_ID=domain)
        with open(self.logs / f'{name}.out', 'w') as out, \
                open(self.logs / f'{name}.err', 'w') as err:
            self.processes[name] = subprocess.Popen(args, stdin=subprocess.DEVNULL, stdout=out,
                                                    stderr=err, env=env)

    def stop(self) -> None:
        """Stop every process and node this run started."""
        for process in self.processes.values():
            if process.poll() is None:
                process.send_signal(2)
        for process in self.processes.values():
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        if self.node is not None:
            self.executor.remove_node(self.node)
            self.executor.shutdown()
        for node in (self.client, self.node, self.urdf_node):
            if node is not None:
                node.destroy_node()
        for context in (self.context, self.urdf_context):
            rclpy.try_shutdown(context=context)

    def _dead(self) -> list[str]:
        return [name for name, process in self.processes.items() if process.poll() is not None]

    def _rss(self) -> dict[str, int]:
        return {name: rss_kb(process.pid) for name, process in self.processes.items()}

    # Phases -------------------------------------------------------------------------

    def run(self, per_input: int, warm_up: int = 20) -> FuzzReport:
        """Run every phase with `per_input` messages per input; return the report."""
        started = time.monotonic()
        self.start()
        try:
            self._good_plan()
            self._fuzz(warm_up, count=False)
            self.report.rss_before = self._rss()
            self._fuzz(per_input)
            self._check_plan_kept()
            self._fuzz_triggers(per_input)
            self.report.rss_after = self._rss()
            self._valid_request_afterwards()
        finally:
            self.report.deaths = self._dead()
            self.report.seconds = time.monotonic() - started
            self.stop()
        return self.report

    def _good_plan(self) -> None:
        client = self.client
        if not client.wait_until_ready(timeout=120.0):
            raise RuntimeError(f'the nodes did not start; see {self.logs}')
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=120.0)
        if not motion.succeeded:
            raise RuntimeError(f'no good plan to start from: {motion.message}')
        self.report.good_plan = motion.stamp
        self._theta_s = motion.theta_s
        execution = client.execute(motion, timeout=120.0)
        if execution.result is not Outcome.SUCCEEDED:
            raise RuntimeError(f'the good execution failed: {execution.message}')
        self.progress(f'good plan {motion.stamp} executed')

    def _fuzz(self, per_input: int, count: bool = True) -> None:
        publishers = {name: self.node.create_publisher(msg_type, topic, qos)
                      for name, (msg_type, topic, qos) in TOPICS.items()}
        description = self.urdf_node.create_publisher(String, '/robot_description',
                                                      LATCHED_QOS)
        time.sleep(1.0)  # discovery
        for name, publisher in publishers.items():
            self._publish(name, publisher, GENERATORS[name], per_input, count)
        self._publish('robot_description', description,
                      lambda g: robot_description(g, self.urdf), per_input, count)
        for publisher in publishers.values():
            self.node.destroy_publisher(publisher)
        self.urdf_node.destroy_publisher(description)
        self._requests(per_input, count)

    def _publish(self, name: str, publisher, generate, per_input: int, count: bool) -> None:
        for k in range(per_input):
            publisher.publish(generate(self.g))
            time.sleep(self.period)
            if k % 1000 == 999:
                self.progress(f'{name}: {k + 1}')
        if count:
            self.report.sent[name] = self.report.sent.get(name, 0) + per_input
            self.progress(f'{name}: {per_input} sent; dead: {self._dead() or "none"}')

    def _requests(self, per_input: int, count: bool) -> None:
        client = self.node.create_client(GetPlan, '/ftplan/plan')
        client.wait_for_service(timeout_sec=30.0)
        pending = []
        for _ in range(per_input):
            pending.append(client.call_async(plan_request(self.g)))
            if len(pending) >= 20:
                self._answered(pending[:10])
                del pending[:10]
        self._answered(pending)
        self.node.destroy_client(client)
        if count:
            self.report.sent['plan_requests'] = per_input
            self.progress(f'plan_requests: {per_input} sent; dead: {self._dead() or "none"}')

    def _answered(self, futures, timeout: float = 60.0) -> None:
        deadline = time.monotonic() + timeout
        while not all(f.done() for f in futures) and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)
        for future in futures:
            if future.done() and future.result().plan.poses:
                raise RuntimeError('a malformed plan request was planned')

    def _fuzz_triggers(self, per_input: int) -> None:
        clients = [self.node.create_client(Trigger, name) for name in TRIGGERS]
        for client in clients:
            client.wait_for_service(timeout_sec=30.0)
        futures = []
        for _ in range(per_input):
            request = Trigger.Request(structure_needs_at_least_one_member=int(
                self.g.integers(256)))
            futures.append(clients[int(self.g.integers(len(clients)))].call_async(request))
            if len(futures) >= 20:
                self._spin_until_done(futures[:10])
                del futures[:10]
        self._spin_until_done(futures)
        for client in clients:
            self.node.destroy_client(client)
        self.report.sent['trigger_requests'] = per_input
        self.progress(f'trigger_requests: {per_input} sent; dead: {self._dead() or "none"}')

    def _spin_until_done(self, futures, timeout: float = 60.0) -> None:
        deadline = time.monotonic() + timeout
        while not all(f.done() for f in futures) and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.01)

    def _check_plan_kept(self) -> None:
        """The planner's latched θ_s and the executor's held plan still carry the good stamp."""
        client = self.client
        latched: list[JointState] = []
        subscription = self.node.create_subscription(
            JointState, '/ftplan/plan/start_configuration', latched.append, LATCHED_QOS)
        deadline = time.monotonic() + 10.0
        while not latched and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.05)
        self.node.destroy_subscription(subscription)
        client.spin_until(lambda: False, 1.0)  # the fuzz's own statuses still on their way
        held = client.wait_for_status('ftplan_executor: execution', lambda v: True, 5.0,
                                      client.status_mark)
        self.report.held_plan = held.values.get('plan', '') if held else ''
        self.report.plan_kept = bool(latched) and all(
            stamp_key(msg.header.stamp) == self.report.good_plan for msg in latched) and \
            self.report.held_plan == self.report.good_plan

    def _publish_full_obstacle_set(self) -> None:
        """Publish DELETEALL (the static obstacles only); wait until the nodes applied it."""
        mark = self.client.status_mark
        publisher = self.node.create_publisher(MarkerArray, '/ftplan/obstacles', LATCHED_QOS)
        publisher.publish(MarkerArray(markers=[Marker(action=Marker.DELETEALL)]))
        for node in ('ftplan_planner', 'ftplan_executor'):
            self.client.wait_for_status(f'{node}: obstacles',
                                        lambda v: v.get('complete') == 'True', 30.0, mark)
        self.node.destroy_publisher(publisher)

    def _valid_request_afterwards(self) -> None:
        client = self.client
        deadline = time.monotonic() + 60.0
        while time.monotonic() < deadline:   # an execution the triggers started must end
            ok, _ = client.trigger('/ftplan_executor/reset')
            if ok:
                break
            client.spin_until(lambda: False, 0.5)
        client.trigger('/ftplan_sim/reset')
        self._publish_full_obstacle_set()
        motion = client.plan(goal=(1.0, 0.0), start=(2.0, 0.0), timeout=120.0)
        if not motion.succeeded or not np.allclose(motion.theta_s, self._theta_s):
            self.report.answer = f'plan: {motion.message}'
            return
        execution = client.execute(motion, timeout=120.0)
        self.report.answer = f'plan {motion.stamp} (same theta_s), execution: ' \
            f'{execution.result.value} ({execution.message})'
        self.report.answered_after = execution.result is Outcome.SUCCEEDED
