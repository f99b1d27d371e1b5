"""What the executor is set up with: its options, the obstacles it watches, its wording.

The node fills `ExecutorOptions` from its parameters (the same names; README, executor
parameters) and gives the names of the ROS interfaces its messages mention
(`Interfaces`), so that the executor itself knows no topic.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from ftplan_ros.core import CollisionChecker
from ftplan_ros.core.model.motion_limits import MotionLimits
from ftplan_ros.core.planning.timing import DEFAULT_MAX_STEP

from .locks import DEFAULT_LOCK_ANGLE_TOLERANCE

LONGEST_LEAD = 1.0  # [s] of the nominal path's command: a longer pause would only stall


@dataclass(frozen=True)
class ExecutorOptions:
    """Speeds [rad/s], tolerances [rad] and times [s] of the executor (the node's parameters)."""

    max_joint_speed: float = 1.0      # cap on every joint's speed, below the robot's limits
    max_velocity_scaling_factor: float = 1.0      # (0, 1] of the robot's velocity limits
    max_acceleration_scaling_factor: float = 1.0  # (0, 1] of its acceleration (and jerk) limits
    max_step: float = DEFAULT_MAX_STEP  # farthest a joint moves between two commanded points
    arrival_tolerance: float = 1e-6   # joint error at which a command counts as completed
    max_path_offset: float = 1e-6     # farthest the stopped arm may be from the nominal path
    path_tolerance: float = 0.1       # farthest the arm may be from its command: tracking error
    stopped_tolerance: float = 1e-9   # two joint states this close: the arm stands still
    stop_timeout: float = 5.0         # wait for the arm to stop after a lock
    stop_settle_time: float = 0.2     # after a lock, before standing still counts as stopped
    start_timeout: float = 5.0        # wait for a joint state stamped after the request
    joint_state_timeout: float = 2.0  # silence of /joint_states that trips the watchdog
    stall_timeout: float = 5.0        # standing still short of the end of a command
    lock_angle_tolerance: float = DEFAULT_LOCK_ANGLE_TOLERANCE  # a lock's angle from the joint's
    approach_time: float = 1.0        # budget of each RRT-Connect attempt of an approach
    margin: float = 0.0               # [m] clearance the executor's own certifications keep
    nominal_lead: float = 0.05        # from sending the nominal path's command to its stamp

    def scaled(self, limits: MotionLimits) -> MotionLimits:
        """Return the robot's `limits` times the scaling factors (what a plan is timed for)."""
        return limits.scaled(self.max_velocity_scaling_factor,
                             self.max_acceleration_scaling_factor)

    def commanded(self, limits: MotionLimits) -> MotionLimits:
        """Return the robot's `limits` as commands use them: scaled, speed capped."""
        return self.scaled(limits).capped(self.max_joint_speed)


@dataclass(frozen=True)
class Interfaces:
    """How the executor's messages name the interfaces around it."""

    reset_service: str   # declares locked joints repaired, e.g. 'ftplan_executor/reset'
    robot_source: str    # where a new robot comes from, e.g. '/robot_description'
    obstacles_fix: str   # what makes lost obstacle updates good again


class Obstacles(Protocol):
    """The obstacles of the moment (the scene's and the topic's): nodes/obstacles.py ObstacleSet."""

    checker: CollisionChecker  # the arm against all of them
    lost: str                  # why updates are missing ('' when none are)
