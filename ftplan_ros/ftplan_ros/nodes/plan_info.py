"""What a plan is for, beyond its joint data: the planner's plan status.

The latched topics carry θ_s, the joint path and S_F. The robot and the obstacles they
were planned for, the task, its tolerances and the joints whose lock the plan tolerates
are values of the planner's status 'ftplan_planner: plan' on /diagnostics, which also
goes out latched on /ftplan/plan/info (a DiagnosticArray stamped like the plan) for
nodes that join late:

| key | value |
|---|---|
| `stamp` | the plan's stamp 'sec.nanosec' |
| `task_kind` | planar, position, axis or pose |
| `start`, `goal` | task points '[x, y, ...]' (task_space.py) |
| `tolerance`, `orientation_tolerance` | [m], [rad] |
| `tolerated_joints` | joint names, comma-separated (e.g. 'joint1,joint3') |
| `robot` | a digest of the robot's model (core robot_digest): joints, limits, geometry |
| `motion_limits` | a digest of the velocity, acceleration, jerk limits the plan is timed within |
| `obstacles`, `obstacle_set` | how many obstacles, and a digest naming them (obstacles.py) |
| `approach` | how the arm gets to θ_s from where it stood (core/planning/approach.py) |
| `reach`, `reach_search` | the answer for the arm where it stands; how far it looked |

The executor reads them from /ftplan/plan/info to tell a plan for another robot (or
timed within other motion limits: motion_limit_parameters.py), to
judge arrival and to name an untolerated lock, and repeats `tolerated_joints` in its
execution status, which the injector reads for random drills.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ftplan_ros.core import Obstacle, Robot, Task
from ftplan_ros.core.model.motion_limits import MotionLimits, motion_limits_digest
from ftplan_ros.core.model.robot import robot_digest

from .obstacles import obstacle_set_key
from .reporting import parse_vector

PLANNER_STATUS = 'ftplan_planner: plan'
INFOS_KEPT = 8  # plan statuses kept by PlanInfos: the latest plans'


def join_names(names: Sequence[str]) -> str:
    """Return joint names as one comma-separated value."""
    return ','.join(names)


def split_names(text: str) -> tuple[str, ...]:
    """Read back `join_names`."""
    return tuple(name for name in text.split(',') if name)


@dataclass(frozen=True, eq=False)
class PlanInfo:
    """What a plan is for: robot, obstacles, task, tolerances [m], [rad], tolerated joints."""

    stamp: str
    robot: str
    motion_limits: str
    obstacle_set: str
    task_kind: str
    start: np.ndarray
    goal: np.ndarray
    goal_tolerance: float
    orientation_tolerance: float
    tolerated_joints: tuple[str, ...]

    @property
    def task(self) -> Task:
        """The plan's task, as the core's Task."""
        return Task(tuple(self.start), tuple(self.goal), self.goal_tolerance,
                    self.orientation_tolerance)


def format_point(values) -> str:
    """Return a task point as '[a, b, ...]' with every digit (parse_vector reads it back)."""
    return '[' + ', '.join(repr(float(v)) for v in values) + ']'


def plan_info_values(robot: Robot, limits: MotionLimits, obstacles: Sequence[Obstacle],
                     task: Task, tolerated: Sequence[str]) -> dict[str, object]:
    """Return the status values that describe a plan (the table above, bar stamp, approach).

    `limits` are the motion limits its trajectories are timed within, scaled.
    """
    return {'robot': robot_digest(robot), 'motion_limits': motion_limits_digest(limits),
            'obstacles': len(obstacles),
            'obstacle_set': obstacle_set_key(obstacles), 'task_kind': task.kind,
            'start': format_point(task.start), 'goal': format_point(task.goal),
            'tolerance': task.goal_tolerance,
            'orientation_tolerance': task.orientation_tolerance,
            'tolerated_joints': join_names(tolerated)}


def read_plan_info(values: Mapping[str, str]) -> PlanInfo | None:
    """Read a plan status's values; None when they do not describe a plan.

    Every number must be finite, and the tolerances positive.
    """
    try:
        info = PlanInfo(values['stamp'], values['robot'], values['motion_limits'],
                        values['obstacle_set'],
                        values['task_kind'],
                        np.array(parse_vector(values['start'])),
                        np.array(parse_vector(values['goal'])), float(values['tolerance']),
                        float(values['orientation_tolerance']),
                        split_names(values['tolerated_joints']))
    except (KeyError, ValueError):
        return None
    numbers = np.concatenate([info.start, info.goal])
    if not (np.all(np.isfinite(numbers)) and info.goal_tolerance > 0.0 and
            info.orientation_tolerance > 0.0 and np.isfinite(info.goal_tolerance) and
            np.isfinite(info.orientation_tolerance)):
        return None
    return info


class PlanInfos:
    """The plan infos of the latest plans, by stamp (the oldest are dropped)."""

    def __init__(self, size: int = INFOS_KEPT):
        self.size = size
        self._infos: OrderedDict[str, PlanInfo] = OrderedDict()

    def add(self, info: PlanInfo) -> None:
        """Keep `info`; the first info of a stamp stays (the planner sends one per plan)."""
        if info.stamp in self._infos:
            return
        self._infos[info.stamp] = info
        self._infos.move_to_end(info.stamp)
        while len(self._infos) > self.size:
            self._infos.popitem(last=False)

    def get(self, stamp: str) -> PlanInfo | None:
        """Return the info of the plan stamped `stamp`, if it arrived."""
        return self._infos.get(stamp)
