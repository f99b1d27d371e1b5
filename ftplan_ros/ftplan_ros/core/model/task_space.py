"""Task spaces: what the tool must do, as flat task points x.

| kind | x | m |
|---|---|---|
| planar | (x, y) [m] | 2 |
| position | (x, y, z) [m] | 3 |
| axis | (x, y, z, ax, ay, az): position and the unit direction of the tool's z axis | 5 |
| pose | (x, y, z, qx, qy, qz, qw): position and orientation (ROS quaternion order) | 6 |

The degree of redundancy is r = n - m. How far a configuration is from x is measured by
`robot.task_errors` (position [m] and orientation [rad] apart, each with its tolerance).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

KINDS = ('planar', 'position', 'axis', 'pose')
TASK_DIM = {'planar': 2, 'position': 3, 'axis': 5, 'pose': 6}
POINT_SIZE = {'planar': 2, 'position': 3, 'axis': 6, 'pose': 7}
UNIT_TOLERANCE = 1e-3  # how far from 1 the norm of a given quaternion or axis may be
_KIND_OF_SIZE = {size: kind for kind, size in POINT_SIZE.items()}


def kind_of_point(x) -> str:
    """Return the kind of a task point from its size (2, 3, 6 or 7 numbers); else ValueError."""
    kind = _KIND_OF_SIZE.get(len(x))
    if kind is None:
        raise ValueError(f'a task point has 2, 3, 6 or 7 numbers, got {len(x)}')
    return kind


def points_from_frames(kind: str, frames: np.ndarray) -> np.ndarray:
    """Task points (..., k) of tool frames (..., 4, 4) for a spatial task kind."""
    position = frames[..., :3, 3]
    if kind == 'position':
        return position.copy()
    if kind == 'axis':
        return np.concatenate([position, frames[..., :3, 2]], axis=-1)
    flat = frames[..., :3, :3].reshape(-1, 3, 3)
    quaternions = Rotation.from_matrix(flat).as_quat().reshape(frames.shape[:-2] + (4,))
    return np.concatenate([position, quaternions], axis=-1)


def unit_vector(values: np.ndarray, what: str) -> np.ndarray:
    """Return `values` normalised; ValueError when their norm is not 1 within 1e-3."""
    values = np.asarray(values, dtype=float)
    norm = float(np.linalg.norm(values))
    if not abs(norm - 1.0) <= UNIT_TOLERANCE:
        raise ValueError(f'{what} must have norm 1, got {norm:.6g}')
    return values / norm


def point_position(x: np.ndarray) -> np.ndarray:
    """Return the position part (2,) or (3,) [m] of a task point."""
    x = np.asarray(x, dtype=float)
    return x[:2] if len(x) == 2 else x[:3]


def describe_point(kind: str, x) -> str:
    """Describe a task point in one short line for people (3 decimals; orientation as given)."""
    values = [float(v) for v in x]
    position = '[' + ', '.join(f'{v:.3f}' for v in values[:3 if kind != 'planar' else 2]) + ']'
    if kind == 'axis':
        return position + ' axis [' + ', '.join(f'{v:.3f}' for v in values[3:]) + ']'
    if kind == 'pose':
        return position + ' q [' + ', '.join(f'{v:.3f}' for v in values[3:]) + ']'
    return position
