"""A GetPlan request read into the scene to plan: its task, tolerances and tolerated joints.

The planner node (planner.py) reads each request with the settings of its parameters
(`RequestSettings`): the start and goal poses, in the scene's base frame, become task
points of the `task_kind` (an empty start frame: the forward kinematics of the latest
joint state; an empty goal frame: the scene task's goal); `tolerance` > 0 overrides the
goal tolerance [m], `orientation_tolerance` [rad] and `tolerate` come from the settings
(0 and empty: the scene's). Whatever cannot be used raises an error naming the field.
The same settings are checked against a new scene before it is used
(`check_settings`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from geometry_msgs.msg import PoseStamped
from nav_msgs.srv import GetPlan

from ftplan_msgs_py import read_point, read_quaternion
from ftplan_ros.core import InputError, Robot, Scene, Task
from ftplan_ros.core.io.scene_file import parse_tolerated
from ftplan_ros.core.model.scene import DEFAULT_GOAL_TOLERANCE, DEFAULT_ORIENTATION_TOLERANCE
from ftplan_ros.core.planning.planner import check_plannable

from .tasks import bind_task_kind, convert_task_point, task_point

_PLANAR_Z_TOLERANCE = 1e-9  # [m] a planar arm's task lies in z = 0
# [m] GetPlan.tolerance is a float32: below its smallest normal number a tolerance has
# lost its digits on the way (and one below 1.4e-45 arrives as 0, the scene's).
SMALLEST_TOLERANCE = float(np.finfo(np.float32).tiny)


class RequestError(ValueError):
    """A request field the planner cannot use; the message names it."""


class StaleInputError(Exception):
    """The obstacles or the robot are not those published (updates lost, robot replaced)."""


@dataclass(frozen=True)
class RequestSettings:
    """The planner's parameters that shape a request's task."""

    task_kind: str = ''                  # '' = the scene's
    orientation_tolerance: float = 0.0   # [rad]; 0 = the scene task's
    tolerate: tuple[str, ...] = ()       # empty = the scene's `tolerate`, else every joint

    def robot(self, scene: Scene) -> Robot:
        """Return the scene's robot bound to the requests' task kind (InputError if it cannot)."""
        return bind_task_kind(scene.robot, self.task_kind)


def check_settings(scene: Scene, settings: RequestSettings) -> None:
    """Raise InputError when the settings do not fit the scene, or nothing can plan.

    task_kind and tolerate must fit the robot; a robot without redundancy for the task
    kind, a static obstacle over the base or a scene task that cannot be planned would
    make every request fail.
    """
    robot = settings.robot(scene)
    parse_tolerated(list(settings.tolerate) or None, scene.robot.joint_names)
    if robot.n_joints - robot.task_dim < 1:
        raise InputError('robot', f'{robot.n_joints} joints give no redundancy for a '
                         f'{robot.task_dim}-D {robot.task_kind} task: every plan request '
                         'would fail')
    task = scene.task
    start = None if task is None else convert_task_point(task.start, robot.task_kind)
    goal = None if task is None else convert_task_point(task.goal, robot.task_kind)
    if start is not None and goal is not None:
        check_plannable(scene.with_task(Task(tuple(start), tuple(goal), task.goal_tolerance,
                                             task.orientation_tolerance)))


def read_request(request: GetPlan.Request, scene: Scene, settings: RequestSettings,
                 q: np.ndarray | None, no_joint_state: str) -> Scene:
    """Return the scene with the request's task and tolerated joints, or raise naming the field.

    `q` (n,) [rad] is the latest joint configuration, None when there is none (then
    `no_joint_state` says why).
    """
    robot = settings.robot(scene)
    kind = robot.task_kind
    if request.start.header.frame_id == '':
        if q is None:
            raise InputError('start', f'empty frame_id asks for the current position, but '
                             f'{no_joint_state}')
        x_s = robot.forward_kinematics(q)
    else:
        x_s = _task_point(scene, request.start, 'start', kind)
    if request.goal.header.frame_id == '':
        x_g = _scene_goal(scene, kind)
    else:
        x_g = _task_point(scene, request.goal, 'goal', kind)
    tolerance = _goal_tolerance(float(request.tolerance), scene)
    angle = settings.orientation_tolerance or (
        scene.task.orientation_tolerance if scene.task else DEFAULT_ORIENTATION_TOLERANCE)
    tolerate = list(settings.tolerate) or scene.tolerate
    tolerated = parse_tolerated(None if tolerate is None else list(tolerate), robot.joint_names)
    task = Task(tuple(x_s.tolist()), tuple(x_g.tolist()), tolerance, angle)
    return scene.with_task(task).with_tolerated(tolerated)


def _goal_tolerance(tolerance: float, scene: Scene) -> float:
    """Return the request's goal tolerance [m] (0: the scene's), or raise InputError."""
    if not np.isfinite(tolerance) or tolerance < 0.0:
        raise InputError('tolerance', f'must be >= 0 [m] (0: the scene\'s), got {tolerance}')
    if 0.0 < tolerance < SMALLEST_TOLERANCE:
        raise InputError('tolerance', f'{tolerance:g} m is below the smallest normal float32 '
                         f'({SMALLEST_TOLERANCE:g}), the type of GetPlan.tolerance: its '
                         'digits were lost on the way')
    if tolerance == 0.0:
        return scene.task.goal_tolerance if scene.task else DEFAULT_GOAL_TOLERANCE
    return tolerance


def _scene_goal(scene: Scene, kind: str) -> np.ndarray:
    """Return the scene's task goal as a task point of `kind`, or raise InputError."""
    if scene.task is None:
        raise InputError('goal.header.frame_id', f'is empty and scene {scene.name} '
                         f'has no task goal; give the goal in {scene.frame_id!r}')
    goal = convert_task_point(scene.task.goal, kind)
    if goal is None:
        raise InputError('goal.header.frame_id', f'is empty, but the {scene.task.kind} '
                         f'goal of scene {scene.name} is no {kind} goal (task_kind); give '
                         f'the goal pose in {scene.frame_id!r}')
    return goal


def _task_point(scene: Scene, pose: PoseStamped, field: str, kind: str) -> np.ndarray:
    """Return the task point of `kind` of a pose in the base frame, or raise."""
    if pose.header.frame_id != scene.frame_id:
        raise InputError(f'{field}.header.frame_id',
                         f'unknown frame {pose.header.frame_id!r}: poses must be in the '
                         f'base frame {scene.frame_id!r} (no tf lookups here)')
    try:
        position = read_point(pose.pose.position, f'{field}.pose.position')
        quaternion = read_quaternion(pose.pose.orientation, f'{field}.pose.orientation') \
            if kind in ('axis', 'pose') else None
    except ValueError as error:
        raise RequestError(f'{error} ({kind} task)') from None
    if kind == 'planar' and abs(position[2]) > _PLANAR_Z_TOLERANCE:
        raise InputError(f'{field}.pose.position.z',
                         f'is {position[2]} but the planar arm works in z = 0')
    return task_point(kind, position, quaternion)
