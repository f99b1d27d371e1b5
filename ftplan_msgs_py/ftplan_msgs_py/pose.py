"""Convert between end-effector poses and geometry_msgs/Pose (position and unit quaternion).

Quaternions are (x, y, z, w), the order of geometry_msgs/Quaternion. A quaternion read
from a message must have norm 1 within `QUATERNION_TOLERANCE`; it is returned normalised.
A zero quaternion (what some client libraries send for an unset orientation; ROS 2's
default-constructed Quaternion is (0, 0, 0, 1)) is refused with a message that says so.
"""

from typing import NamedTuple

import numpy as np
from geometry_msgs.msg import Point, Pose, Quaternion
from numpy.typing import ArrayLike, NDArray

from ftplan_msgs_py._validation import finite_array

QUATERNION_TOLERANCE = 1e-3  # how far from 1 the norm of a quaternion may be
IDENTITY_QUATERNION = (0.0, 0.0, 0.0, 1.0)


class PoseArrays(NamedTuple):
    """Positions (..., 3) [m] and unit quaternions (..., 4) (x, y, z, w)."""

    position: NDArray[np.float64]
    orientation: NDArray[np.float64]


def unit_quaternions(value: ArrayLike, field: str) -> NDArray[np.float64]:
    """Return quaternions (..., 4) normalised, after checking each has norm 1 within 1e-3.

    :raises ValueError: naming `field` (and the row, for several) on a wrong shape, a
        non-finite value or a norm off by more than `QUATERNION_TOLERANCE`.
    """
    array = finite_array(value, field)
    if array.ndim == 0 or array.shape[-1] != 4:
        raise ValueError(f'{field} has shape {array.shape}; pass (4,) or (k, 4) quaternions '
                         '(x, y, z, w)')
    norms = np.linalg.norm(array, axis=-1)
    bad = np.abs(norms - 1.0) > QUATERNION_TOLERANCE
    if np.any(bad):
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        where = f'{field}[{index[0]}]' if index else field
        norm = float(norms[index])
        hint = ' (a zero quaternion: unset? no rotation is (0, 0, 0, 1))' if norm == 0.0 else ''
        raise ValueError(f'{where} must be a unit quaternion (x, y, z, w) with norm 1 within '
                         f'{QUATERNION_TOLERANCE:g}, got norm {norm:.6g}{hint}')
    return array / norms[..., None]


def create_pose(position: ArrayLike, orientation: ArrayLike | None = None) -> Pose:
    """Create a Pose at `position` with `orientation`.

    :param position: (2,) or (3,) [m]; a 2-D position gets z = 0.
    :param orientation: unit quaternion (4,) (x, y, z, w), normalised here; None is the
        identity.
    :return: the Pose.
    :raises ValueError: naming `position` or `orientation` on bad input.
    """
    point = finite_array(position, 'position')
    if point.shape not in ((2,), (3,)):
        raise ValueError(f'position has shape {point.shape}; pass (2,) or (3,) [m]')
    x, y, z = (point.tolist() + [0.0])[:3]
    q = unit_quaternions(IDENTITY_QUATERNION if orientation is None else orientation,
                         'orientation')
    if q.shape != (4,):
        raise ValueError(f'orientation has shape {q.shape}; pass one quaternion (4,)')
    qx, qy, qz, qw = q.tolist()
    return Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw))


def read_point(msg: Point, field: str = 'position') -> NDArray[np.float64]:
    """Read a Point as (3,) [m]; ValueError naming `field` when a coordinate is not finite."""
    return finite_array((msg.x, msg.y, msg.z), field)


def read_quaternion(msg: Quaternion, field: str = 'orientation') -> NDArray[np.float64]:
    """Read a Quaternion as a normalised (4,) (x, y, z, w); see `unit_quaternions`."""
    return unit_quaternions((msg.x, msg.y, msg.z, msg.w), field)


def read_pose(msg: Pose, field: str = 'pose') -> PoseArrays:
    """Read a Pose: position (3,) [m] and unit quaternion (4,).

    :raises ValueError: naming `<field>.position` or `<field>.orientation`.
    """
    return PoseArrays(read_point(msg.position, f'{field}.position'),
                      read_quaternion(msg.orientation, f'{field}.orientation'))
