"""Task points in the nodes: from request poses, between task kinds, and back to poses.

Task points are the core's flat tuples (core/task_space.py): planar (x, y), position
(x, y, z), axis (x, y, z, ax, ay, az: the tool's z axis), pose (x, y, z, qx, qy, qz, qw).
A spatial arm plans the kind of task it is bound to (`bind_task_kind`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ftplan_ros.core import InputError, PlanarChain, Robot, SpatialArm
from ftplan_ros.core.model.task_space import KINDS, kind_of_point

SPATIAL_KINDS = ('position', 'axis', 'pose')
_Z = np.array([0.0, 0.0, 1.0])


def check_task_kind(value: str) -> str | None:
    """Validate a `task_kind` parameter: '' (the scene's) or a kind of task_space.py."""
    if value not in ('', *KINDS):
        return f'must be empty (the scene\'s) or one of {", ".join(KINDS)}, got {value!r}'
    return None


def bind_task_kind(robot: Robot, kind: str, field: str = 'task_kind') -> Robot:
    """Return the robot bound to tasks of `kind` ('' keeps its own); InputError if it cannot.

    A planar arm does planar tasks only, a spatial arm position, axis or pose tasks.
    """
    if not kind or kind == robot.task_kind:
        return robot
    if isinstance(robot, SpatialArm) and kind in SPATIAL_KINDS:
        return robot.with_task_kind(kind)
    what = 'a planar arm does planar tasks only' if isinstance(robot, PlanarChain) else \
        'a spatial arm does position, axis or pose tasks'
    raise InputError(field, f'{kind!r}: {what}')


def task_point(kind: str, position: np.ndarray, quaternion: np.ndarray | None) -> np.ndarray:
    """Return the task point of `kind` of a pose: position (3,) [m], unit quaternion (4,).

    The quaternion (x, y, z, w) is needed for axis and pose tasks only.
    """
    position = np.asarray(position, dtype=float)
    if kind == 'planar':
        return position[:2].copy()
    if kind == 'position':
        return position.copy()
    if quaternion is None:
        raise ValueError(f'a {kind} task point needs an orientation')
    if kind == 'axis':
        return np.concatenate([position, Rotation.from_quat(quaternion).as_matrix()[:, 2]])
    return np.concatenate([position, quaternion])


def convert_task_point(x, kind: str) -> np.ndarray | None:
    """Return task point x as a point of `kind`; None when x lacks what `kind` needs.

    A pose gives every spatial kind, an axis gives an axis or a position, a position only
    a position; a planar point stays planar.
    """
    x = np.asarray(x, dtype=float)
    own = kind_of_point(x)
    if own == kind:
        return x.copy()
    if own == 'planar' or kind == 'planar':
        return None
    if kind == 'position':
        return x[:3].copy()
    if own == 'pose' and kind == 'axis':
        return task_point('axis', x[:3], x[3:])
    return None


def pose_of_task_point(x) -> tuple[np.ndarray, np.ndarray | None]:
    """Return a position (3,) [m] and quaternion (4,) (None: any) that give task point x.

    An axis becomes the shortest rotation taking z onto it.
    """
    x = np.asarray(x, dtype=float)
    kind = kind_of_point(x)
    position = np.append(x[:2], 0.0) if kind == 'planar' else x[:3].copy()
    if kind in ('planar', 'position'):
        return position, None
    if kind == 'pose':
        return position, x[3:] / np.linalg.norm(x[3:])
    axis = x[3:] / np.linalg.norm(x[3:])
    rotation, _ = Rotation.align_vectors(axis[None, :], _Z[None, :])
    return position, rotation.as_quat()


def end_effector_poses(robot: Robot, thetas: np.ndarray,
                       ) -> tuple[np.ndarray, np.ndarray | None]:
    """Tool positions (k, 3) [m] and, for spatial arms, quaternions (k, 4) along (k, n) [rad].

    Planar arms give z = 0 and no orientations.
    """
    thetas = np.atleast_2d(np.asarray(thetas, dtype=float))
    if isinstance(robot, SpatialArm):
        frames = robot.tool_frames(thetas)
        return frames[:, :3, 3].copy(), Rotation.from_matrix(frames[:, :3, :3]).as_quat()
    return robot.skeleton(thetas)[:, -1, :].copy(), None
