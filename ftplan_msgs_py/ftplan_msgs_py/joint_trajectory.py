"""Convert between joint paths with timing and trajectory_msgs/JointTrajectory."""

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from builtin_interfaces.msg import Time
from numpy.typing import ArrayLike, NDArray
from std_msgs.msg import Header
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ftplan_msgs_py._validation import (
    check_finite_joints,
    finite_array,
    index_by_name,
    joint_names,
    optional_frame,
    select_joints,
    stamp_or_zero,
)
from ftplan_msgs_py.stamps import duration_to_seconds, seconds_to_duration


class JointTrajectoryArrays(NamedTuple):
    """A joint trajectory as arrays: (k, n) positions [rad] and (k,) times from start [s]."""

    positions: NDArray[np.float64]
    times: NDArray[np.float64]


def _check_times(times: NDArray[np.float64], field: str) -> None:
    if np.any(times < 0.0):
        i = int(np.argmax(times < 0.0))
        raise ValueError(f'{field} of point {i} is {times[i]} s; times must be >= 0')
    steps = np.diff(times)
    if np.any(steps < 0.0):
        i = int(np.argmax(steps < 0.0))
        raise ValueError(
            f'{field} decreases from {times[i]} s (point {i}) to {times[i + 1]} s '
            f'(point {i + 1}); times must be non-decreasing'
        )


def create_joint_trajectory(
    names: Sequence[str],
    positions: ArrayLike,
    times_from_start: ArrayLike,
    stamp: Time | None = None,
    frame_id: str = '',
    velocities: ArrayLike | None = None,
    accelerations: ArrayLike | None = None,
) -> JointTrajectory:
    """Create a JointTrajectory with positions (and velocities, accelerations if given).

    :param names: unique joint names, one per column of `positions`.
    :param positions: (k, n) joint positions [rad], one row per point.
    :param times_from_start: (k,) time of each point after `stamp` [s], finite, >= 0 and
        non-decreasing. (A ros2_control joint_trajectory_controller wants them strictly
        increasing.)
    :param stamp: header stamp (start time); None, i.e. zero, means "start now".
    :param frame_id: header frame, usually empty.
    :param velocities: (k, n) [rad/s] of each point, or None (left empty).
    :param accelerations: (k, n) [rad/s²] of each point, or None (left empty).
    :return: the JointTrajectory.
    """
    joints = joint_names(names, 'names')
    q = finite_array(positions, 'positions')
    if q.shape == (0,):
        q = np.zeros((0, len(joints)))
    if q.ndim != 2 or q.shape[1] != len(joints):
        raise ValueError(
            f'positions has shape {q.shape}; pass (k, {len(joints)}), one column per joint '
            f'{joints}'
        )
    t = finite_array(times_from_start, 'times_from_start')
    if t.shape != (len(q),):
        raise ValueError(
            f'times_from_start has shape {t.shape}; pass ({len(q)},), one time per point'
        )
    _check_times(t, 'times_from_start')
    header = Header(stamp=stamp_or_zero(stamp), frame_id=optional_frame(frame_id, 'frame_id'))
    rates = {}
    for name, values in (('velocities', velocities), ('accelerations', accelerations)):
        if values is not None:
            rates[name] = finite_array(values, name)
            if rates[name].shape != q.shape:
                raise ValueError(f'{name} has shape {rates[name].shape}; pass {q.shape}, like '
                                 'positions')
    points = [
        JointTrajectoryPoint(positions=row, time_from_start=seconds_to_duration(time),
                             **{name: values[i].tolist() for name, values in rates.items()})
        for i, (row, time) in enumerate(zip(q.tolist(), t.tolist(), strict=True))
    ]
    return JointTrajectory(
        header=header,
        joint_names=joints,
        points=points,
    )


def read_joint_trajectory(msg: JointTrajectory, names: Sequence[str]) -> JointTrajectoryArrays:
    """Read the positions and times of a JointTrajectory, matched by joint name.

    The message may list its joints in any order and may hold extra joints, which are
    ignored. Velocities, accelerations and efforts are ignored.

    :param msg: the JointTrajectory; every point needs one position per joint name.
    :param names: the joints wanted, in the order of the returned columns.
    :return: (k, n) positions [rad] ordered as `names` and (k,) times from start [s].
    :raises ValueError: on a missing or duplicate joint, a point with the wrong number of
        positions, a non-finite position, or negative or decreasing times.
    """
    wanted = joint_names(names, 'names')
    available = index_by_name(msg.joint_names, 'JointTrajectory.joint_names')
    columns = select_joints(available, wanted, 'JointTrajectory')
    positions = np.zeros((len(msg.points), len(wanted)))
    times = np.zeros(len(msg.points))
    for i, point in enumerate(msg.points):
        if len(point.positions) != len(msg.joint_names):
            raise ValueError(
                f'JointTrajectory point {i} has {len(point.positions)} positions for '
                f'{len(msg.joint_names)} joint names; send one position per joint'
            )
        positions[i] = np.asarray(point.positions, dtype=np.float64)[columns]
        check_finite_joints(positions[i], f'JointTrajectory point {i} position', wanted)
        times[i] = duration_to_seconds(point.time_from_start)
    _check_times(times, 'JointTrajectory time_from_start')
    return JointTrajectoryArrays(positions, times)
