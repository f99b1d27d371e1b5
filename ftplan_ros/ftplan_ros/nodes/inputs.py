"""The bounds on the joint angles that enter the nodes from messages.

ftplan_msgs_py refuses what no message may hold (NaN, a missing joint, a stamp before the
epoch); these bounds refuse what no arm can be at or be sent to: an angle beyond
`LARGEST_ANGLE` (a lifted periodic joint turns a few times, not a thousand), or, for a
joint with limits, beyond them by more than `LIMIT_SLACK`. A joint state or a command
that breaks one is refused whole, with a ValueError naming the joint.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from sensor_msgs.msg import JointState

from ftplan_msgs_py import read_joint_state, time_to_nanoseconds
from ftplan_ros.core import Robot

LARGEST_ANGLE = 1.0e4   # [rad] no joint is ever this far round
LIMIT_SLACK = 1.0e-3    # [rad] how far past its limits a joint state or command may be


def angle_problem(robot: Robot, positions: np.ndarray) -> str:
    """Say which joint of positions (..., n) [rad] is out of bounds ('' if none)."""
    positions = np.asarray(positions, dtype=float).reshape(-1, robot.n_joints)
    limits = robot.limits
    outside = (np.abs(positions) > LARGEST_ANGLE) | (
        ~robot.periodic & ((positions < limits[:, 0] - LIMIT_SLACK) |
                           (positions > limits[:, 1] + LIMIT_SLACK)))
    if not outside.any():
        return ''
    row, joint = (int(i) for i in np.argwhere(outside)[0])
    low, high = (-LARGEST_ANGLE, LARGEST_ANGLE) if robot.periodic[joint] else limits[joint]
    return (f'joint {robot.joint_names[joint]} at {positions[row, joint]:.6g} rad is outside '
            f'[{low:g}, {high:g}] rad')


def read_arm_state(msg: JointState, robot: Robot,
                   names: Sequence[str] | None = None) -> tuple[np.ndarray, int]:
    """Read the arm's configuration (n,) [rad] and its stamp [ns] from a joint state.

    :raises ValueError: as `read_joint_state` does, for a stamp before the epoch, and for
        an angle out of bounds (see the module docstring).
    """
    q = read_joint_state(msg, list(names or robot.joint_names))
    stamp = time_to_nanoseconds(msg.header.stamp)
    problem = angle_problem(robot, q)
    if problem:
        raise ValueError(f'JointState: {problem}')
    return q, stamp
