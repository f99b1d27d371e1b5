"""The locked joints (locks.py): remembered until repaired, never commanded; the angle bound."""

import numpy as np

from ftplan_ros.execution.locks import JointLocks, lock_angle_problem

NAMES = ['joint1', 'joint2', 'joint3']


def test_a_lock_is_remembered_once_until_cleared():
    locks = JointLocks(NAMES)
    assert locks.lock(1, 0.5, None) and not locks.lock(1, 0.7, 3)
    assert locks.lock(2, None, 3)
    assert len(locks) == 2 and 1 in locks and locks.joints == [1, 2]
    assert locks.describe() == 'joint2 (while idle), joint3 (in execution 3)'
    assert locks.clear() == ['joint2', 'joint3'] and len(locks) == 0


def test_a_path_that_moves_a_locked_joint_is_named():
    locks = JointLocks(NAMES)
    locks.lock(1, 0.5, 1)
    assert locks.moved(np.array([[0.0, 0.5, 0.0], [1.0, 0.5, 2.0]])) == ''
    assert locks.moved(np.array([[0.0, 0.5, 0.0], [0.0, 0.75, 0.0]])) == 'joint2 by 0.25 rad'


def test_a_lock_at_an_unknown_angle_counts_any_change_and_settles_where_the_arm_stops():
    locks = JointLocks(NAMES)
    locks.lock(0, None, 1)
    assert locks.moved(np.array([[0.2, 0.0, 0.0], [0.2, 1.0, 0.0]])) == ''
    assert locks.moved(np.array([[0.2, 0.0, 0.0], [0.3, 0.0, 0.0]])) == 'joint1 by 0.1 rad'
    locks.settle(np.array([0.3, 0.0, 0.0]))
    assert locks.moved(np.array([[0.2, 0.0, 0.0], [0.2, 1.0, 0.0]])) == 'joint1 by 0.1 rad'


def test_a_lock_angle_must_lie_where_the_joint_is():
    assert lock_angle_problem('joint1', None, None, False, 0.05) == ''
    assert lock_angle_problem('joint1', 0.52, 0.5, False, 0.05) == ''
    assert lock_angle_problem('joint1', 0.5 + 2 * np.pi, 0.5, True, 0.05) == ''  # whole turns
    far = lock_angle_problem('joint1', 0.5 + 2 * np.pi, 0.5, False, 0.05)
    assert far.startswith('joint1 would lock at 6.78319 rad, +6.28 rad from where it is')
    assert far.endswith('(lock_angle_tolerance 0.05 rad); send no position to lock it there')
    assert 'a joint locks where it stands' in lock_angle_problem('joint1', 1e308, 0.5, True, 0.05)
    assert lock_angle_problem('joint1', 0.5, None, False, 0.05) == (
        'joint1 locks at 0.5 rad, but its current angle is not known yet')
