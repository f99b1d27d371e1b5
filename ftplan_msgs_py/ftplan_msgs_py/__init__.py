"""Pure-Python conversions between numpy arrays and the standard ROS 2 messages of ftplan.

Like sensor_msgs_py: free functions in create_* / read_* pairs, no node and no rclpy.
Units are SI (metres, radians, seconds); readers return arrays and NamedTuples.
"""

from ftplan_msgs_py.diagnostics import (
    DIAGNOSTIC_LEVELS,
    DiagnosticReading,
    create_diagnostic_array,
    create_diagnostic_status,
    read_diagnostic_status,
)
from ftplan_msgs_py.failure_surface import (
    FAILURE_SURFACE_LABELS,
    create_failure_surface,
    read_failure_surface,
)
from ftplan_msgs_py.joint_state import create_joint_state, read_joint_state
from ftplan_msgs_py.joint_trajectory import (
    JointTrajectoryArrays,
    create_joint_trajectory,
    read_joint_trajectory,
)
from ftplan_msgs_py.locked_joint import LockedJoint, create_locked_joint, read_locked_joint
from ftplan_msgs_py.obstacles import (
    DEFAULT_OBSTACLE_COLOR,
    ObstacleKey,
    ObstacleShape,
    create_obstacle_markers,
    read_obstacle_markers,
)
from ftplan_msgs_py.path import create_path, read_path, read_path_poses
from ftplan_msgs_py.plan_markers import (
    DEFAULT_JOINT_SPACE_FRAME,
    END_EFFECTOR_NS,
    FAILURE_SURFACE_NS,
    create_plan_markers,
    read_plan_markers,
)
from ftplan_msgs_py.pose import (
    QUATERNION_TOLERANCE,
    PoseArrays,
    create_pose,
    read_point,
    read_pose,
    read_quaternion,
    unit_quaternions,
)
from ftplan_msgs_py.stamps import (
    duration_to_seconds,
    seconds_to_duration,
    seconds_to_time,
    time_to_nanoseconds,
    time_to_seconds,
)

__all__ = [
    'DEFAULT_JOINT_SPACE_FRAME',
    'DEFAULT_OBSTACLE_COLOR',
    'DIAGNOSTIC_LEVELS',
    'END_EFFECTOR_NS',
    'FAILURE_SURFACE_LABELS',
    'FAILURE_SURFACE_NS',
    'DiagnosticReading',
    'JointTrajectoryArrays',
    'LockedJoint',
    'PoseArrays',
    'QUATERNION_TOLERANCE',
    'ObstacleKey',
    'ObstacleShape',
    'create_diagnostic_array',
    'create_diagnostic_status',
    'create_failure_surface',
    'create_joint_state',
    'create_joint_trajectory',
    'create_locked_joint',
    'create_obstacle_markers',
    'create_path',
    'create_plan_markers',
    'create_pose',
    'duration_to_seconds',
    'read_diagnostic_status',
    'read_failure_surface',
    'read_joint_state',
    'read_joint_trajectory',
    'read_locked_joint',
    'read_obstacle_markers',
    'read_path',
    'read_path_poses',
    'read_plan_markers',
    'read_point',
    'read_pose',
    'read_quaternion',
    'seconds_to_duration',
    'seconds_to_time',
    'time_to_nanoseconds',
    'time_to_seconds',
    'unit_quaternions',
]
