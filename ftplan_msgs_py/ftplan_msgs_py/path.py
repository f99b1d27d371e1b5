"""Convert between end-effector paths (positions, optionally orientations) and nav_msgs/Path."""

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion
from nav_msgs.msg import Path
from numpy.typing import ArrayLike, NDArray
from std_msgs.msg import Header

from ftplan_msgs_py._validation import finite_array, frame, stamp_or_zero
from ftplan_msgs_py.pose import IDENTITY_QUATERNION, PoseArrays, unit_quaternions


def create_path(positions: ArrayLike, frame_id: str, stamp: Time | None = None,
                orientations: ArrayLike | None = None) -> Path:
    """Create a Path through `positions`, with `orientations` or identity ones.

    An empty Path (k = 0) is how the planner says it found no failure-tolerant plan.

    :param positions: (k, 2) or (k, 3) positions [m]; 2-D positions get z = 0.
    :param frame_id: the frame of the poses, set on the path and on every pose.
    :param stamp: stamp of the path and of every pose; None leaves it zero.
    :param orientations: (k, 4) unit quaternions (x, y, z, w), normalised here (each
        norm must be 1 within 1e-3); None gives identity orientations.
    :return: the Path.
    """
    base = frame(frame_id, 'frame_id')
    points = finite_array(positions, 'positions')
    if points.shape == (0,):
        points = np.zeros((0, 3))
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise ValueError(f'positions has shape {points.shape}; pass (k, 2) or (k, 3) [m]')
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    if orientations is None:
        quaternions = np.tile(IDENTITY_QUATERNION, (len(points), 1))
    else:
        quaternions = finite_array(orientations, 'orientations')
        quaternions = quaternions.reshape(0, 4) if quaternions.size == 0 else \
            unit_quaternions(quaternions, 'orientations')
        if quaternions.shape != (len(points), 4):
            raise ValueError(f'orientations has shape {quaternions.shape}; pass ({len(points)}, '
                             '4): one quaternion (x, y, z, w) per position')
    path_stamp = stamp_or_zero(stamp)
    poses = [
        PoseStamped(
            header=Header(stamp=stamp_or_zero(path_stamp), frame_id=base),
            pose=Pose(position=Point(x=x, y=y, z=z),
                      orientation=Quaternion(x=qx, y=qy, z=qz, w=qw)),
        )
        for (x, y, z), (qx, qy, qz, qw) in zip(points.tolist(), quaternions.tolist(),
                                               strict=True)
    ]
    return Path(header=Header(stamp=path_stamp, frame_id=base), poses=poses)


def _check_pose_frame(msg: Path, i: int, pose: PoseStamped) -> None:
    if pose.header.frame_id not in ('', msg.header.frame_id):
        raise ValueError(
            f'Path pose {i} is in frame {pose.header.frame_id!r} but the path is in '
            f'{msg.header.frame_id!r}; express every pose in the path frame'
        )


def read_path(msg: Path) -> NDArray[np.float64]:
    """Read the positions of a Path; orientations are ignored (see `read_path_poses`).

    :param msg: the Path; each pose must be in the path's frame or have an empty frame.
    :return: (k, 3) positions [m] in the path's frame.
    :raises ValueError: on a pose in another frame or a non-finite position.
    """
    positions = np.zeros((len(msg.poses), 3))
    for i, pose in enumerate(msg.poses):
        _check_pose_frame(msg, i, pose)
        p = pose.pose.position
        positions[i] = finite_array((p.x, p.y, p.z), f'Path pose {i} position')
    return positions


def read_path_poses(msg: Path) -> PoseArrays:
    """Read the positions and orientations of a Path.

    :param msg: the Path; each pose must be in the path's frame or have an empty frame.
    :return: positions (k, 3) [m] and unit quaternions (k, 4) (x, y, z, w), normalised.
    :raises ValueError: on a pose in another frame, a non-finite value or a quaternion
        whose norm is not 1 within 1e-3 (naming the pose).
    """
    positions = read_path(msg)
    orientations = np.zeros((len(msg.poses), 4))
    for i, pose in enumerate(msg.poses):
        o = pose.pose.orientation
        orientations[i] = unit_quaternions((o.x, o.y, o.z, o.w), f'Path pose {i} orientation')
    return PoseArrays(positions, orientations)
