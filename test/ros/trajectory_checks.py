"""Every JointTrajectory the nodes publish, recorded by a probe and replayed against the limits.

`listen_to_trajectories` makes a probe (ros_support.Probe: a real rclpy node) keep every
message of the executor's /ftplan/joint_command; `replay_commands` sorts them by kind
(the approach ends at θ_s, the nominal command lies on the planned nominal path, a
recovery is any other motion, a stop has no points) and replays each with the shared
checker (test/trajectory_replay.py). `replay_plans` replays the planner's latched
nominal trajectories and approaches (/ftplan/plan/trajectory, /ftplan/plan/approach):
the planned paths' vertices, timed within the robot's limits and `max_joint_speed`.
"""

from collections import Counter

import numpy as np
from trajectory_msgs.msg import JointTrajectory
from trajectory_replay import ON_PATH, trajectory_violations

from ftplan_msgs_py import read_joint_trajectory
from ftplan_ros.core.model.angles import configuration_difference
from ftplan_ros.core.model.motion_limits import MotionLimits
from ftplan_ros.execution.motion import progress_along
from ftplan_ros.execution.options import ExecutorOptions
from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.topics import APPROACH, JOINT_COMMAND, TRAJECTORY

KINDS = ('approach', 'nominal', 'recovery', 'stop')


def listen_to_trajectories(probe) -> None:
    """Make `probe` keep every command of the executor (none dropped: depth 10000) and
    every latched nominal trajectory and approach of the planner."""
    probe.listen(JointTrajectory, JOINT_COMMAND, 10000)
    for topic in (TRAJECTORY, APPROACH):
        probe.listen(JointTrajectory, topic, LATCHED_QOS)


def nominal_paths(probe, names, since: int = 0) -> list[np.ndarray]:
    """Return the nominal paths (k, n) of the plans `probe` received, from the `since`-th."""
    return [read_joint_trajectory(msg, names).positions
            for msg in probe.received(TRAJECTORY)[since:]]


def commands(probe) -> list[JointTrajectory]:
    """Return the commands `probe` has received so far."""
    return probe.received(JOINT_COMMAND)


def command_kind(msg, nominal: np.ndarray, periodic: np.ndarray) -> str:
    """Which command `msg` is (KINDS) of a run of the plan whose nominal path is `nominal`."""
    if not msg.points:
        return 'stop'
    positions = np.array([point.positions for point in msg.points])
    if max(progress_along(nominal, q, periodic)[1] for q in positions) <= ON_PATH:
        return 'nominal'
    if np.max(np.abs(configuration_difference(positions[-1], nominal[0], periodic))) <= ON_PATH:
        return 'approach'
    return 'recovery'


def replay_commands(messages, robot, nominal: np.ndarray, limits: MotionLimits) -> Counter:
    """Replay the executor's commands `messages` to `robot` within `limits`; count each kind.

    Each must pass trajectory_violations: joint names, finite rates of every point, the
    limits, steps of at most the executor's max_step, rest at the end; the nominal
    command stays on `nominal` (k, n) and sends each of its vertices. Raises
    AssertionError naming every command that fails.
    """
    counts, failures = Counter(), []
    step = ExecutorOptions().max_step
    for i, msg in enumerate(messages):
        kind = command_kind(msg, nominal, robot.periodic)
        counts[kind] += 1
        if kind == 'stop':
            continue
        problems = trajectory_violations(
            msg, robot.joint_names, limits, position_limits=robot.limits, max_step=step,
            from_rest=False, periodic=robot.periodic,
            certified=nominal if kind == 'nominal' else None)
        if problems:
            failures.append(f'command {i} ({kind}): {problems}')
    assert not failures, failures
    return counts


def replay_plans(probe, robot, limits: MotionLimits, since: int = 0) -> Counter:
    """Replay the planner's latched trajectories and approaches `probe` received (from the
    `since`-th of each) to `robot` within `limits`; count each kind ('planned trajectory',
    'planned approach').

    Each must pass trajectory_violations from rest to rest, its steps unbounded (they
    are the planned vertices); an approach without points (none) is not counted.
    Raises AssertionError naming every message that fails.
    """
    counts, failures = Counter(), []
    for kind, topic in (('planned trajectory', TRAJECTORY), ('planned approach', APPROACH)):
        for i, msg in enumerate(probe.received(topic)[since:]):
            if not msg.points:
                continue
            counts[kind] += 1
            problems = trajectory_violations(msg, robot.joint_names, limits,
                                             position_limits=robot.limits, max_step=None)
            if problems:
                failures.append(f'{kind} {since + i}: {problems}')
    assert not failures, failures
    return counts
