"""An executor holding a plan, without ROS: the tests play the arm and the clock."""

from dataclasses import dataclass

import numpy as np

from ftplan_ros.core import CollisionChecker, Obstacle
from ftplan_ros.core.model.motion_limits import motion_limits_digest, robot_motion_limits
from ftplan_ros.core.model.paths import point_at_fraction
from ftplan_ros.core.model.robot import robot_digest
from ftplan_ros.execution.actions import Moment, Status, Stop
from ftplan_ros.execution.command import Command
from ftplan_ros.execution.executor import Executor
from ftplan_ros.execution.options import ExecutorOptions, Interfaces
from ftplan_ros.execution.state import HeldPlan, State

INTERFACES = Interfaces('ftplan_executor/reset', '/robot_description',
                        'publish a full set (a MarkerArray whose first marker is DELETEALL)')
PLAN_KEY = '1.000000000'
TICK = 0.01  # [s] between two joint states of the played arm


@dataclass
class Obstacles:
    """The obstacles as the executor sees them: a checker over all, and lost updates."""

    checker: CollisionChecker
    lost: str = ''


class Rig:
    """An executor holding a plan; the test plays the arm and moves the clock on.

    The clock starts at monotonic 100 s, ROS time 1000 s; each joint state moves it on by
    TICK and is stamped with it.
    """

    def __init__(self, scene, result, surface=None, tolerated=None, digest=None, goal=None,
                 limits_digest=None, **options):
        self.scene, self.result = scene, result
        self.monotonic, self.ros_ns = 100.0, 1_000_000_000_000
        self.obstacles = Obstacles(CollisionChecker(scene.robot, scene.obstacles))
        self.executor = Executor(self.obstacles, ExecutorOptions(**options), INTERFACES)
        self.executor.use_robot(scene.robot, self.now())
        self.plan = HeldPlan(PLAN_KEY, result.theta_s, surface or result.surface, scene.robot,
                             np.array(goal or scene.task.goal),
                             tolerated or scene.robot.joint_names,
                             digest or robot_digest(scene.robot),
                             limits_digest or motion_limits_digest(ExecutorOptions(
                                 **options).scaled(robot_motion_limits(scene.robot))))
        self.executor.hold(self.plan, self.now())
        self.q = None

    def now(self) -> Moment:
        return Moment(self.monotonic, self.ros_ns)

    def wait(self, seconds: float) -> None:
        self.monotonic += seconds
        self.ros_ns += round(seconds * 1e9)

    def start(self):
        return self.executor.start(self.now())

    def at(self, q, stamp_ns=None) -> list:
        """The arm reports q (n,), a tick later (stamped then, unless `stamp_ns`)."""
        self.q = np.asarray(q, dtype=float)
        self.wait(TICK)
        return self.executor.on_joint_state(self.q.copy(), self.ros_ns if stamp_ns is None
                                            else stamp_ns, self.now())

    def follow(self, command: Command, until: float = 1.0, steps: int = 20) -> list:
        """The arm moves along the command to the fraction `until` of its length."""
        actions = []
        for fraction in np.linspace(0.0, until, steps + 1)[1:]:
            actions += self.at(point_at_fraction(command.path, fraction))
        return actions

    def stand(self, seconds: float = 0.3) -> list:
        """The arm stays where it is for `seconds`, then reports it twice."""
        self.wait(seconds)
        return self.at(self.q) + self.at(self.q)

    def lock(self, joint: int, angle=None, stamp_ns: int = 0) -> list:
        return self.executor.on_lock(joint, angle, stamp_ns, self.now())

    def tick(self, seconds: float = 0.0) -> list:
        self.wait(seconds)
        return self.executor.tick(self.now())

    def approach(self, offset) -> Command:
        """Start a run with the arm at θ_s + offset (n,): return the approach command."""
        assert self.start().success
        [command] = commands(self.at(self.result.theta_s + offset))
        return command

    def nominal(self) -> Command:
        """Start a run with the arm at θ_s: return the command of the nominal path."""
        assert self.start().success
        [command] = commands(self.at(self.result.theta_s))
        return command

    def add_obstacle(self, center, radius: float) -> Obstacle:
        """Add a sphere [m] to the obstacles the executor sees (z = 0 unless given)."""
        center = tuple(float(c) for c in center)
        obstacle = Obstacle('sphere', center + (0.0,) * (3 - len(center)), radius=radius)
        self.obstacles.checker = CollisionChecker(
            self.scene.robot, self.scene.obstacles + (obstacle,))
        return obstacle


def commands(actions) -> list[Command]:
    return [action for action in actions if isinstance(action, Command)]


def statuses(actions) -> list[Status]:
    return [action for action in actions if isinstance(action, Status)]


def stops(actions) -> int:
    return sum(isinstance(action, Stop) for action in actions)


def final(actions) -> Status:
    """The last status report of the actions."""
    return statuses(actions)[-1]


def failure(actions) -> str:
    """The failure the actions end with, the arm stopped and nothing commanded: its reason."""
    assert commands(actions) == [] and stops(actions) == 1
    status = final(actions)
    assert status.state == State.FAILED and status.level == 'ERROR'
    assert status.execution.reason == status.message
    return status.message
