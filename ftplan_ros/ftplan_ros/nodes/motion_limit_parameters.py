"""The motion-limit parameters of the planner and the executor: a joint_limits file, scaling.

Both nodes time trajectories within the robot's motion limits (core/model/motion_limits.py):
its own (URDF velocities, the robot file's joint_limits, else the defaults) or those of
`joint_limits_file`, times `max_velocity_scaling_factor` and
`max_acceleration_scaling_factor` (MoveIt's). A plan's status names the limits it was
timed within by their digest (`motion_limits`); the executor refuses a plan timed within
other limits than its own (README: what a plan is for).
"""

from __future__ import annotations

from typing import Any

from rclpy.node import Node

from ftplan_ros.core import Robot
from ftplan_ros.core.io.limits_file import load_joint_limits
from ftplan_ros.core.model.motion_limits import MotionLimits, robot_motion_limits

from .params import Validator, declare, positive

SCALING_FACTORS = ('max_velocity_scaling_factor', 'max_acceleration_scaling_factor')


def declare_motion_limit_parameters(node: Node, velocity_scaling: float = 1.0,
                                    acceleration_scaling: float = 1.0,
                                    ) -> dict[str, Validator]:
    """Declare joint_limits_file and the scaling factors on `node`; return their validators."""
    declare(node, 'max_velocity_scaling_factor', velocity_scaling,
            'Fraction (0, 1] of the robot\'s velocity limits the trajectories use (MoveIt\'s).')
    declare(node, 'max_acceleration_scaling_factor', acceleration_scaling,
            'Fraction (0, 1] of the robot\'s acceleration (and jerk) limits the trajectories '
            'use (MoveIt\'s).')
    declare(node, 'joint_limits_file', '',
            'MoveIt joint_limits.yaml whose velocity, acceleration and jerk limits replace '
            'the robot\'s (empty: the robot\'s own: URDF velocity, the robot file\'s '
            'joint_limits, else the defaults).', read_only=True)
    return {name: scaling_factor for name in SCALING_FACTORS}


def file_motion_limits(node: Node, robot: Robot) -> MotionLimits | None:
    """Return the limits of `node`'s joint_limits_file for `robot` (None: none given).

    Raises InputError naming joint_limits_file when the file does not fit the robot.
    """
    path = node.get_parameter('joint_limits_file').value
    if not path:
        return None
    return load_joint_limits(path, robot.joint_names, robot_motion_limits(robot),
                             'joint_limits_file')


def scaling_factor(value: Any) -> str | None:
    """Validate a scaling factor: in (0, 1]."""
    return positive(value) or (None if value <= 1.0 else f'must be at most 1, got {value!r}')
