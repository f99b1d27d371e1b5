"""Convert between locked-joint failure events and sensor_msgs/JointState.

By the ftplan contract a failure event on `/ftplan/locked_joint` is a JointState with
`name=[joint]` and `position=[]` (the joint locks where it is) or `position=[angle]`.
"""

from typing import NamedTuple

from builtin_interfaces.msg import Time
from sensor_msgs.msg import JointState
from std_msgs.msg import Header

from ftplan_msgs_py._validation import finite_float, stamp_or_zero


class LockedJoint(NamedTuple):
    """A locked-joint event: the joint's name and the angle [rad] it locks at, if given."""

    name: str
    angle: float | None


def create_locked_joint(
    name: str, angle: float | None = None, stamp: Time | None = None
) -> JointState:
    """Create the failure event that locks joint `name`.

    :param name: the joint that fails.
    :param angle: the angle [rad] it locks at; None means where it is when the event arrives.
    :param stamp: header stamp; None leaves it zero.
    :return: a JointState with one name and zero or one position.
    """
    if not isinstance(name, str) or not name:
        raise ValueError(f'locked joint name must be a non-empty string, got {name!r}')
    msg = JointState(header=Header(stamp=stamp_or_zero(stamp)), name=[name])
    if angle is not None:
        msg.position = [finite_float(angle, f'lock angle of joint {name!r}')]
    return msg


def read_locked_joint(msg: JointState) -> LockedJoint:
    """Read a failure event: which joint locks and, optionally, at what angle [rad].

    :raises ValueError: unless the message names exactly one joint and has no position or
        one finite position.
    """
    if len(msg.name) != 1 or not msg.name[0]:
        raise ValueError(
            f'a locked-joint event must name exactly one joint, got name={list(msg.name)}'
        )
    name = msg.name[0]
    if len(msg.position) == 0:
        return LockedJoint(name, None)
    if len(msg.position) != 1:
        raise ValueError(
            f'a locked-joint event for {name!r} has {len(msg.position)} positions; send none '
            '(lock where it is) or one angle'
        )
    return LockedJoint(name, finite_float(msg.position[0], f'lock angle of joint {name!r}'))
