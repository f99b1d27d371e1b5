"""After a lock, once the arm stands still: the way on to the goal, or why there is none.

A lock on the nominal path is recovered within S_F: the core's `recover` gives the path
in S_F ∩ H_i from where the arm stopped to M_g^F (paper, Step 7). A lock on the approach
to θ_s, before the failure-tolerant part began, gets a path to the goal planned with the
joints left (`path_to_goal`), when there is one: not failure-tolerant. Angles [rad].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ftplan_ros.core import InputError, recover
from ftplan_ros.core.model.paths import path_length
from ftplan_ros.core.paper.manifolds import project_to_preimage
from ftplan_ros.core.planning.approach import ApproachPlanner

from .state import Execution


@dataclass(frozen=True, eq=False)
class WayOn:
    """How a run goes on from where the arm stopped locked: a path to command, or none.

    `message` is the status once the path is commanded (at `level`), or why there is none.
    """

    path: np.ndarray | None   # (k, n) from where the arm stands to the goal
    length: float             # [rad] of the path (NaN without one)
    message: str
    level: str = 'OK'


def within_surface(ex: Execution, q: np.ndarray, start: np.ndarray, name: str,
                   max_offset: float, planner: ApproachPlanner, max_step_to_goal: float,
                   ) -> WayOn:
    """Recover in the run's S_F from q (n,), where its locked joint `name` stopped.

    `start` (n,) is where on the nominal path the arm braked from (certified: in a
    braking box, or by the executor), or q: the path goes straight back there, then on
    in S_F. `max_offset` [rad] is how far `start` may lie from the nominal path; the step
    from there onto it is certified by `planner` now. A brake that slipped past the
    path's range of the joint gets S_F's path moved by the slip, which ends off the goal:
    it goes on to a goal configuration with the joint where it is, at most
    `max_step_to_goal` [rad] away, and `planner` certifies the whole moved path now. What
    is not certified keeps the arm where it stopped.
    """
    progress, tolerated = ex.lock_progress, ex.plan.tolerated
    try:
        rescue, problem = recover(ex.surface, start, ex.locked_joint, max_offset), ''
    except InputError as error:
        rescue, problem = None, str(error)
    if rescue is None:
        return WayOn(None, float('nan'), no_recovery(name, progress, tolerated, problem))
    note = '' if name in tolerated else \
        ' (not tolerated by this plan, but S_F holds a recovery path)'
    path, length = rescue.path, rescue.length
    if rescue.slip != 0.0:
        path = _on_to_the_goal(ex, path, rescue.joint, max_step_to_goal)
        if path is None or not planner.certify(path):
            return WayOn(None, float('nan'), f'{name} locked {abs(rescue.slip):.4f} rad past '
                         f'the nominal path\'s range of it, at {progress:.1%} of the path, and '
                         'S_F\'s recovery path moved there is not certified clear; the arm is '
                         'stopped there')
        length = path_length(path)
    elif np.any(path[0] != path[1]) and not planner.certify(path[:2]):
        return WayOn(None, float('nan'), f'{name} locked at {progress:.1%} of the nominal path '
                     f'{float(np.max(np.abs(path[1] - path[0]))):.4f} rad off it, and the move '
                     'onto it is not certified clear; the arm is stopped there')
    if np.any(start != q):
        path = np.vstack([q[None, :], path])
        length += float(np.linalg.norm(start - q))
    return WayOn(path, length, f'{name} locked at {progress:.1%} of the nominal '
                 f'path{note}: following the recovery path ({len(path)} points, '
                 f'{length:.3f} rad)')


def _on_to_the_goal(ex: Execution, path: np.ndarray, joint: int, max_step: float,
                    ) -> np.ndarray | None:
    """Return `path` (k, n) [rad] and then its end moved onto the goal, `joint` held.

    None when Newton's method finds no goal configuration within `max_step` [rad] of the
    end (it may converge on a far branch of the goal's preimage).
    """
    end = project_to_preimage(ex.plan.robot, ex.plan.goal, path[-1], fixed_joint=joint)
    if end is None or np.max(np.abs(end - path[-1])) > max_step:
        return None
    return np.vstack([path, end[None, :]])


def with_joints_left(planner: ApproachPlanner, ex: Execution, q: np.ndarray, name: str,
                     ) -> WayOn:
    """Plan a path from q (n,) to the run's goal with its locked joint `name` held."""
    found = planner.path_to_goal(q, ex.plan.goal, ex.locked_joint)
    if not found.ok:
        return WayOn(None, float('nan'), f'{name} locked while approaching theta_s (not '
                     f'failure-tolerant) and {found.reason}; the arm is stopped where it is')
    return WayOn(found.path, found.length, f'{name} locked while approaching theta_s: '
                 f'following a path to the goal with the joints left, {found.describe()} '
                 '(not failure-tolerant)', 'WARN')


def no_recovery(name: str, progress: float, tolerated: tuple[str, ...], problem: str) -> str:
    """Say why there is no recovery path for joint `name` locked at `progress` (0..1) of the path.

    `tolerated` are the joints the plan tolerates; `problem` is the core's objection ('' if none).
    """
    where = f'{progress:.1%} of the nominal path'
    if name not in tolerated:
        return (f'joint {name} is not tolerated by this plan (it tolerates '
                f'{", ".join(tolerated)}): S_F holds no recovery path from where it '
                f'locked, at {where}; the arm is stopped there')
    if problem:
        return f'cannot recover from {name} locked at {where}: {problem}; the arm is stopped there'
    return (f'S_F holds no recovery path for {name} locked at {where}: the plan\'s guarantee '
            'is broken, please report')


def lock_message(name: str, approaching: bool, progress: float) -> str:
    """Say what the executor does about joint `name` locking (at `progress` of the path): stop."""
    if approaching:
        return (f'{name} locked while approaching theta_s, before the failure-tolerant '
                'nominal path began: stopping, then planning a path to the goal with the '
                'joints left (not failure-tolerant)')
    return f'{name} locked at about {progress:.1%} of the nominal path: stopping'
