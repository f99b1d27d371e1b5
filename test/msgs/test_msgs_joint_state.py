import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from sensor_msgs.msg import JointState

from ftplan_msgs_py.joint_state import create_joint_state, read_joint_state
from ftplan_msgs_py.locked_joint import LockedJoint, create_locked_joint, read_locked_joint

NAMES = ['joint1', 'joint2', 'joint3']


def test_create_fills_every_field():
    msg = create_joint_state(NAMES, [0.1, -0.2, 3.0], velocities=[1.0, 0.0, -1.0],
                             stamp=Time(sec=4, nanosec=5), frame_id='base_link')
    assert list(msg.name) == NAMES
    assert np.allclose(msg.position, [0.1, -0.2, 3.0])
    assert np.allclose(msg.velocity, [1.0, 0.0, -1.0])
    assert len(msg.effort) == 0
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (4, 5)
    assert msg.header.frame_id == 'base_link'


def test_create_without_velocities_or_stamp():
    msg = create_joint_state(NAMES, np.zeros(3))
    assert len(msg.velocity) == 0
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 0)


def test_round_trip():
    q = np.array([0.3, -1.2, 2.9])
    assert np.allclose(read_joint_state(create_joint_state(NAMES, q), NAMES), q)


def test_stamp_is_copied_not_shared():
    stamp = Time(sec=1)
    msg = create_joint_state(NAMES, np.zeros(3), stamp=stamp)
    stamp.sec = 99
    assert msg.header.stamp.sec == 1


def test_read_matches_joints_by_name_in_any_order():
    msg = JointState(name=['joint3', 'joint1', 'joint2'], position=[3.0, 1.0, 2.0])
    assert np.allclose(read_joint_state(msg, NAMES), [1.0, 2.0, 3.0])
    assert np.allclose(read_joint_state(msg, ['joint2', 'joint3']), [2.0, 3.0])


def test_read_ignores_extra_joints_even_non_finite_ones():
    msg = JointState(name=['gripper', 'joint1', 'joint2', 'joint3'],
                     position=[math.nan, 1.0, 2.0, 3.0])
    assert np.allclose(read_joint_state(msg, NAMES), [1.0, 2.0, 3.0])


def test_read_missing_joint_is_named():
    msg = JointState(name=['joint1', 'joint2'], position=[1.0, 2.0])
    with pytest.raises(ValueError, match=r"lacks joint\(s\) \['joint3'\]"):
        read_joint_state(msg, NAMES)


def test_read_rejects_length_mismatch():
    msg = JointState(name=NAMES, position=[1.0, 2.0])
    with pytest.raises(ValueError, match='3 names but 2 positions'):
        read_joint_state(msg, NAMES)


def test_read_rejects_duplicate_joint_in_message():
    msg = JointState(name=['joint1', 'joint2', 'joint1'], position=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="JointState.name lists joint 'joint1' twice"):
        read_joint_state(msg, ['joint1', 'joint2'])


def test_read_rejects_duplicate_wanted_joint():
    msg = JointState(name=NAMES, position=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="names lists joint 'joint2' twice"):
        read_joint_state(msg, ['joint2', 'joint2'])


@pytest.mark.parametrize('bad', [math.nan, math.inf])
def test_read_non_finite_position_names_the_joint(bad):
    msg = JointState(name=NAMES, position=[1.0, bad, 3.0])
    with pytest.raises(ValueError, match="joint 'joint2'"):
        read_joint_state(msg, NAMES)


def test_create_non_finite_position_names_the_joint():
    with pytest.raises(ValueError, match="positions of joint 'joint3'"):
        create_joint_state(NAMES, [0.0, 0.0, math.inf])
    with pytest.raises(ValueError, match="velocities of joint 'joint1'"):
        create_joint_state(NAMES, [0.0, 0.0, 0.0], velocities=[math.nan, 0.0, 0.0])


def test_create_rejects_wrong_lengths():
    with pytest.raises(ValueError, match=r'positions has shape \(2,\)'):
        create_joint_state(NAMES, [0.0, 0.0])
    with pytest.raises(ValueError, match=r'velocities has shape \(4,\)'):
        create_joint_state(NAMES, [0.0, 0.0, 0.0], velocities=np.zeros(4))


def test_create_rejects_non_numeric_positions():
    with pytest.raises(ValueError, match='positions must be a numeric array'):
        create_joint_state(NAMES, ['a', 'b', 'c'])


@pytest.mark.parametrize('names, match', [
    ('joint1', 'not the string'),
    ([], 'empty'),
    (['joint1', ''], 'non-empty strings'),
    (['joint1', 2], 'non-empty strings'),
])
def test_create_rejects_bad_names(names, match):
    with pytest.raises(ValueError, match=match):
        create_joint_state(names, np.zeros(2))


def test_create_rejects_a_stamp_that_is_not_a_time():
    with pytest.raises(ValueError, match='stamp must be a builtin_interfaces/Time'):
        create_joint_state(NAMES, np.zeros(3), stamp=1.5)


def test_locked_joint_round_trip_with_and_without_angle():
    lock_here = create_locked_joint('joint2', stamp=Time(sec=7))
    assert list(lock_here.name) == ['joint2']
    assert len(lock_here.position) == 0
    assert lock_here.header.stamp.sec == 7
    assert read_locked_joint(lock_here) == LockedJoint('joint2', None)

    lock_at = create_locked_joint('joint1', angle=0.75)
    assert list(lock_at.position) == [0.75]
    assert read_locked_joint(lock_at) == LockedJoint('joint1', 0.75)


def test_read_hand_built_locked_joint():
    event = read_locked_joint(JointState(name=['joint3'], position=[-1.0]))
    assert event.name == 'joint3'
    assert event.angle == -1.0


@pytest.mark.parametrize('name', ['', None])
def test_create_locked_joint_rejects_bad_name(name):
    with pytest.raises(ValueError, match='locked joint name'):
        create_locked_joint(name)


def test_create_locked_joint_rejects_non_finite_angle():
    with pytest.raises(ValueError, match="lock angle of joint 'joint1'"):
        create_locked_joint('joint1', angle=math.nan)


@pytest.mark.parametrize('names', [[], ['joint1', 'joint2'], ['']])
def test_read_locked_joint_needs_exactly_one_name(names):
    with pytest.raises(ValueError, match='exactly one joint'):
        read_locked_joint(JointState(name=names))


def test_read_locked_joint_rejects_several_positions():
    with pytest.raises(ValueError, match="'joint1' has 2 positions"):
        read_locked_joint(JointState(name=['joint1'], position=[0.1, 0.2]))


@pytest.mark.parametrize('bad', [math.nan, -math.inf])
def test_read_locked_joint_rejects_non_finite_angle(bad):
    with pytest.raises(ValueError, match="lock angle of joint 'joint1'"):
        read_locked_joint(JointState(name=['joint1'], position=[bad]))


def test_create_rejects_a_frame_id_that_is_not_a_string():
    with pytest.raises(ValueError, match='frame_id must be a string'):
        create_joint_state(NAMES, np.zeros(3), frame_id=None)
