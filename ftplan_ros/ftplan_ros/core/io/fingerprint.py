"""Scenes as plain data: written back to YAML, and fingerprinted for caches and studies.

Equal data, equal plans: a planar scene is its YAML (`scene_to_dict`); a spatial robot,
which comes from a file, is named by a digest of its model (`scene_fingerprint`).
"""

from __future__ import annotations

import math
from typing import Any

from ..model.robot import PlanarChain, geometry_sha256
from ..model.scene import Obstacle, Scene


def scene_to_dict(scene: Scene) -> dict:
    """Return a planar scene as plain data in the YAML format `parse_scene` reads.

    Spatial robots come from files: give their scene files instead (ValueError).
    """
    robot = scene.robot
    if not isinstance(robot, PlanarChain):
        raise ValueError('only planar scenes are written back to YAML')
    out: dict[str, Any] = {
        'robot': {'type': 'planar', 'link_lengths': list(robot.link_lengths),
                  'link_radius': robot.link_radius, 'joint_names': list(robot.joint_names),
                  'joint_limits': None if robot.joint_limits is None
                  else [None if lim is None else list(lim) for lim in robot.joint_limits]},
        'obstacles': [_obstacle_to_dict(ob) for ob in scene.obstacles],
    }
    if scene.frame_id != 'base_link':
        out['frame_id'] = scene.frame_id
    if scene.tolerate is not None:
        out['tolerate'] = list(scene.tolerate)
    if scene.task is not None:
        out['task'] = {'start': list(scene.task.start), 'goal': list(scene.task.goal),
                       'goal_tolerance': scene.task.goal_tolerance}
    return out


def scene_fingerprint(scene: Scene) -> dict:
    """Return plain data that identifies the scene: equal data, equal plans.

    A planar scene is `scene_to_dict`; a spatial robot, which comes from a file, is its
    task kind, joint names, limits [rad] and a SHA-256 of its kinematic parameters,
    collision shapes and self-collision pairs, beside the obstacles and task as data.
    """
    if isinstance(scene.robot, PlanarChain):
        return scene_to_dict(scene)
    robot = scene.robot
    limits = [[float(v) if math.isfinite(v) else None for v in row] for row in robot.limits]
    out: dict[str, Any] = {
        'robot': {'task_kind': robot.task_kind, 'joint_names': list(robot.joint_names),
                  'limits': limits, 'geometry_sha256': geometry_sha256(robot)},
        'obstacles': [_obstacle_to_dict(ob) for ob in scene.obstacles],
        'frame_id': scene.frame_id,
        'tolerate': None if scene.tolerate is None else list(scene.tolerate)}
    if scene.task is not None:
        out['task'] = {'start': list(scene.task.start), 'goal': list(scene.task.goal),
                       'goal_tolerance': scene.task.goal_tolerance,
                       'orientation_tolerance': scene.task.orientation_tolerance}
    return out


def _obstacle_to_dict(obstacle: Obstacle) -> dict:
    out: dict[str, Any] = {'type': obstacle.shape, 'center': list(obstacle.center)}
    if obstacle.shape in ('sphere', 'cylinder'):
        out['radius'] = obstacle.radius
    if obstacle.shape == 'cylinder':
        out['length'] = obstacle.length
    if obstacle.shape == 'box':
        out['size'] = list(obstacle.size)
    if obstacle.shape != 'sphere' and any(obstacle.rpy):
        out['rpy'] = list(obstacle.rpy)
    return out
