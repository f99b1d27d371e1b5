"""Convert between end-effector position paths and nav_msgs/Path."""

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, PoseStamped
from nav_msgs.msg import Path
from numpy.typing import ArrayLike, NDArray
from std_msgs.msg import Header

from ftplan_msgs_py._validation import finite_array, frame, stamp_or_zero


def create_path(positions: ArrayLike, frame_id: str, stamp: Time | None = None) -> Path:
    """Create a Path through `positions` with identity orientations.

    An empty Path (k = 0) is how the planner says it found no failure-tolerant plan.

    :param positions: (k, 2) or (k, 3) positions [m]; 2-D positions get z = 0.
    :param frame_id: the frame of the positions, set on the path and on every pose.
    :param stamp: stamp of the path and of every pose; None leaves it zero.
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
    path_stamp = stamp_or_zero(stamp)
    poses = [
        PoseStamped(
            header=Header(stamp=stamp_or_zero(path_stamp), frame_id=base),
            pose=Pose(position=Point(x=x, y=y, z=z)),
        )
        for x, y, z in points.tolist()
    ]
    return Path(header=Header(stamp=path_stamp, frame_id=base), poses=poses)


def read_path(msg: Path) -> NDArray[np.float64]:
    """Read the positions of a Path; orientations are ignored.

    :param msg: the Path; each pose must be in the path's frame or have an empty frame.
    :return: (k, 3) positions [m] in the path's frame.
    :raises ValueError: on a pose in another frame or a non-finite position.
    """
    positions = np.zeros((len(msg.poses), 3))
    for i, pose in enumerate(msg.poses):
        if pose.header.frame_id not in ('', msg.header.frame_id):
            raise ValueError(
                f'Path pose {i} is in frame {pose.header.frame_id!r} but the path is in '
                f'{msg.header.frame_id!r}; express every pose in the path frame'
            )
        p = pose.pose.position
        positions[i] = finite_array((p.x, p.y, p.z), f'Path pose {i} position')
    return positions
