"""A plan drawn for RViz: the arm at θ_s, the tool's path, M_s, M_g, S_F (thinned), obstacles.

The planner publishes it on /ftplan/plan/markers (plan_results.py). The arm and the
tool's path are in 3-D in the base frame; the joint-space objects show joints 1-3 as x,
y, z in the `joint_space_frame`.
"""

from __future__ import annotations

import numpy as np
from visualization_msgs.msg import MarkerArray

from ftplan_msgs_py import create_obstacle_markers, create_plan_markers
from ftplan_ros.core import PlanResult, Scene

from .obstacles import shape_from_obstacle
from .tasks import end_effector_poses

MARKER_WEB_SIZE = 40  # paths and waypoints of S_F drawn at most (~6000 marker points)


def display_web(paths: np.ndarray, most: int = MARKER_WEB_SIZE) -> np.ndarray:
    """Thin the S_F web (K, W, n) to at most `most` paths of `most` waypoints for RViz.

    The first and last path and waypoint are kept; the full web is on
    /ftplan/plan/failure_surface.
    """
    rows = np.unique(np.linspace(0, paths.shape[0] - 1, min(most, paths.shape[0])).round())
    columns = np.unique(np.linspace(0, paths.shape[1] - 1, min(most, paths.shape[1])).round())
    return paths[rows.astype(int)][:, columns.astype(int)]


def plan_markers(scene: Scene, result: PlanResult, stamp, joint_space_frame: str,
                 ) -> MarkerArray:
    """Draw a plan for RViz: arm at θ_s, end-effector path, M_s, M_g, S_F (thinned), obstacles.

    The arm and the tool's path are in 3-D in the base frame; the joint-space objects
    show joints 1-3 as x, y, z.
    """
    robot = scene.robot
    markers = create_plan_markers(
        scene.frame_id, stamp,
        arm_polylines={'arm_theta_s': robot.skeleton(result.theta_s)},
        end_effector_path=end_effector_poses(robot, result.nominal_path)[0],
        joint_space_frame=joint_space_frame,
        joint_space_curves={
            'start_manifold': [b.points for b in result.start_manifolds if len(b) > 1],
            'goal_manifold': [b.points for b in result.goal_manifolds if len(b) > 1],
            'nominal_path': [result.nominal_path],
        },
        joint_space_points={'theta_s': result.theta_s[None, :],
                            'failure_plane_hits': result.failure_plane_hits},
        surface_paths=display_web(result.surface.paths))
    if scene.obstacles:
        shapes = [shape_from_obstacle(('obstacles', k), obstacle)
                  for k, obstacle in enumerate(scene.obstacles)]
        markers.markers.extend(
            create_obstacle_markers(shapes, scene.frame_id, stamp, clear_first=False).markers)
    return markers
