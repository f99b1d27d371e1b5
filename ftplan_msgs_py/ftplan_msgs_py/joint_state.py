"""Convert between joint configurations and sensor_msgs/JointState, matched by joint name."""

from collections.abc import Sequence

import numpy as np
from builtin_interfaces.msg import Time
from numpy.typing import ArrayLike, NDArray
from sensor_msgs.msg import JointState
from std_msgs.msg import Header

from ftplan_msgs_py._validation import (
    check_finite_joints,
    index_by_name,
    joint_names,
    joint_vector,
    optional_frame,
    select_joints,
    stamp_or_zero,
)


def create_joint_state(
    names: Sequence[str],
    positions: ArrayLike,
    velocities: ArrayLike | None = None,
    stamp: Time | None = None,
    frame_id: str = '',
) -> JointState:
    """Create a JointState of the configuration `positions`.

    :param names: unique joint names, one per entry of `positions`.
    :param positions: (n,) joint positions [rad, or m for prismatic joints].
    :param velocities: optional (n,) joint velocities [rad/s]; left empty when None.
    :param stamp: header stamp; None leaves it zero (nodes pass their clock's now()).
    :param frame_id: header frame, usually empty for joint states.
    :return: the JointState, with an empty effort field.
    """
    joints = joint_names(names, 'names')
    q = joint_vector(positions, 'positions', joints)
    header = Header(stamp=stamp_or_zero(stamp), frame_id=optional_frame(frame_id, 'frame_id'))
    msg = JointState(header=header)
    msg.name = joints
    msg.position = q.tolist()
    if velocities is not None:
        msg.velocity = joint_vector(velocities, 'velocities', joints).tolist()
    return msg


def read_joint_state(msg: JointState, names: Sequence[str]) -> NDArray[np.float64]:
    """Read the positions of the joints `names` from a JointState, matched by name.

    The message may list its joints in any order and may hold extra joints, which are
    ignored (their values are not checked).

    :param msg: the JointState; `position` must have one entry per `name`.
    :param names: the joints wanted, in the order of the returned array.
    :return: (n,) positions [rad] ordered as `names`.
    :raises ValueError: on a missing or duplicate joint, mismatched lengths, or a
        non-finite position of a wanted joint.
    """
    wanted = joint_names(names, 'names')
    if len(msg.position) != len(msg.name):
        raise ValueError(
            f'JointState has {len(msg.name)} names but {len(msg.position)} positions; '
            'publish one position per joint name'
        )
    available = index_by_name(msg.name, 'JointState.name')
    rows = select_joints(available, wanted, 'JointState')
    q = np.asarray(msg.position, dtype=np.float64)[rows]
    check_finite_joints(q, 'JointState position', wanted)
    return q
