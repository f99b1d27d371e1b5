"""A locked-joint event from /ftplan/locked_joint, as the executor and the sim read it.

What they do with it is their logic's (execution/locks.py remembers the locks, and
`lock_angle_problem` there bounds an event's angle for both).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from sensor_msgs.msg import JointState

from ftplan_msgs_py import LockedJoint, read_locked_joint, time_to_nanoseconds


def read_lock_event(msg: JointState, names: Sequence[str] | None, waiting: str,
                    reject: Callable[[str, str | None], None],
                    ) -> tuple[LockedJoint, int, int] | None:
    """Read a locked-joint event, its joint's index among `names` and its stamp [ns], or refuse it.

    The stamp is when the joint locks: 0 (unstamped) or one already past means at once;
    one ahead schedules the failure (a drill), to take effect when the arm's command
    reaches that moment. `names` is None while the node has no scene (`waiting` says what
    it waits for). A refusal calls `reject(why, the joint's name or None)` and returns None.
    """
    try:
        event = read_locked_joint(msg)
        stamp_ns = time_to_nanoseconds(msg.header.stamp)
    except ValueError as error:
        reject(f'ignored locked-joint event: {error}', None)
        return None
    if names is None:
        reject(f'ignored lock of {event.name}: {waiting}', event.name)
        return None
    if event.name not in names:
        reject(f'ignored lock of unknown joint {event.name!r}; the arm has {list(names)}',
               event.name)
        return None
    return event, list(names).index(event.name), stamp_ns
