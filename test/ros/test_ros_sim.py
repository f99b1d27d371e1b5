"""The sim node in-process: following commands, velocity limits, locks, collisions, reset."""

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from rclpy.duration import Duration
from ros_support import FIG3A, SCENES, wait_for
from sensor_msgs.msg import JointState
from std_msgs.msg import Header
from std_srvs.srv import Trigger
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

from ftplan_msgs_py import create_joint_trajectory, create_locked_joint, read_joint_state
from ftplan_ros.core import CollisionChecker, InputError, load_scene
from ftplan_ros.nodes.sim import SimNode

NAMES = ['joint1', 'joint2', 'joint3']
STATUS = 'ftplan_sim: arm'
SPEED = 2.0  # [rad/s] the sim's velocity limit in these tests


@pytest.fixture
def sim(ros):
    ros.make(SimNode, SCENES / 'paper_a_free.yaml', max_joint_speed=SPEED,
             initial_configuration=[0.0, 0.0, 0.0])
    ros.probe.listen(JointState, '/joint_states', 1000)
    wait_for(lambda: ros.probe.received('/joint_states'))
    return ros


def states(ros):
    return [(msg, read_joint_state(msg, NAMES)) for msg in ros.probe.received('/joint_states')]


def command(ros, positions, times):
    ros.probe.publish(JointTrajectory, '/ftplan/joint_command',
                      create_joint_trajectory(NAMES, positions, times))


def last(ros):
    """The latest joint configuration (reading only the newest message: polls stay cheap)."""
    msgs = ros.probe.received('/joint_states')
    return read_joint_state(msgs[-1], NAMES) if msgs else None


def at(ros, q, atol=1e-12):
    def check():
        now = last(ros)
        return now is not None and np.allclose(now, q, atol=atol, rtol=0)
    return check


def test_the_sim_follows_a_command_and_slows_down_a_too_fast_one(sim):
    ros = sim
    target = [1.5, -1.0, 0.5]
    command(ros, [[0.5, -0.2, 0.1], target], [0.1, 0.2])   # asks for 8 rad/s
    wait_for(at(ros, target), what='the arm at the target')
    velocities = np.array([msg.velocity for msg, _ in states(ros)])
    assert np.abs(velocities).max() <= SPEED * (1 + 1e-6)
    assert np.abs(velocities).max() > 0.5 * SPEED
    positions = np.array([q for _, q in states(ros)])
    steps = np.abs(np.diff(positions, axis=0)).max(axis=1)
    assert steps.max() <= SPEED / 100.0 * (1 + 1e-6)        # one tick at 100 Hz
    wait_for(lambda: any(s.values['state'] == 'stopped' for s in ros.probe.statuses(STATUS)))


def test_a_locked_joint_brakes_the_arm_and_stays_locked(sim):
    ros = sim
    command(ros, [[3.0, 3.0, 3.0]], [1.5])
    wait_for(lambda: last(ros)[0] > 0.5, what='the arm moving')
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint2'))
    status = wait_for(lambda: [s for s in ros.probe.statuses(STATUS)
                               if s.values['locked'] == 'joint2'])[0]
    assert status.level == 'WARN' and 'joint2 locked' in status.message
    # Braked within the acceleration limits (issue 36): joints 1 and 3 go on past joint 2's
    # angle by at most v²/2a (<= 2²/(2·2) rad), then two joint states in a row are equal.
    def braked():
        recent = [read_joint_state(m, NAMES) for m in ros.probe.received('/joint_states')[-2:]]
        return len(recent) == 2 and np.array_equal(*recent)
    wait_for(braked, what='the arm to stop')
    stopped = last(ros)
    assert stopped[0] < 3.0 and stopped[0] == pytest.approx(stopped[2])
    assert stopped[1] < stopped[0] <= stopped[1] + 1.0 + 1e-9
    # A new command moves the free joints only; the locked one is held (and reported).
    command(ros, [[0.0, 0.0, 0.0]], [2.0])
    wait_for(lambda: abs(last(ros)[0]) < 1e-12, what='joint1 back at 0')
    assert last(ros)[1] == stopped[1]
    wait_for(lambda: ros.probe.logged('ftplan_sim', 'moves locked joint joint2'))


def test_a_lock_stamped_ahead_locks_where_the_command_puts_the_arm_at_that_moment(sim):
    """Issue 33: a drill's lock event, stamped with its moment on the command's timeline,
    locks the joint exactly there, between two ticks too, however early it arrives (the
    sim locked where the arm stood when the event came: here before the motion began)."""
    ros = sim
    start = ros.probe.get_clock().now() + Duration(seconds=0.3)
    ros.probe.publish(JointTrajectory, '/ftplan/joint_command', create_joint_trajectory(
        NAMES, [[1.0, 0.0, 0.0], [1.0, 1.0, 0.5]], [0.5, 1.0], start.to_msg()))
    moment = start + Duration(seconds=0.6537)                # 0.1537 s into the second step
    ros.probe.publish(JointState, '/ftplan/locked_joint',
                      create_locked_joint('joint2', stamp=moment.to_msg()))
    wait_for(lambda: [s for s in ros.probe.statuses(STATUS) if s.values['locked'] == 'joint2'],
             what='joint2 locked')
    def braked():
        recent = [read_joint_state(m, NAMES) for m in ros.probe.received('/joint_states')[-2:]]
        return len(recent) == 2 and np.array_equal(*recent)
    wait_for(braked, what='the arm to stop')
    # Locked at [1.0, 0.3074, 0.1537]; joint 3 then brakes from 1 rad/s at 2 rad/s²: 0.25 on.
    assert np.allclose(last(ros), [1.0, 0.3074, 0.1537 + 0.25], atol=1e-9, rtol=0)


def test_reset_unlocks_and_returns_to_the_initial_configuration(sim):
    ros = sim
    command(ros, [[1.0, 1.0, 1.0]], [1.0])
    wait_for(at(ros, [1.0, 1.0, 1.0]))
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint1'))
    wait_for(lambda: [s for s in ros.probe.statuses(STATUS) if s.values['locked'] == 'joint1'])
    response = ros.probe.call(Trigger, '/ftplan_sim/reset', Trigger.Request())
    assert response.success
    wait_for(at(ros, [0.0, 0.0, 0.0]))
    status = wait_for(lambda: [s for s in ros.probe.statuses(STATUS)
                               if s.values['resets'] == '1'])[-1]
    assert status.values['locked'] == '' and status.values['collisions'] == '0'
    command(ros, [[0.5, 0.5, 0.5]], [1.0])                 # joint1 moves again
    wait_for(at(ros, [0.5, 0.5, 0.5]))


def test_malformed_commands_and_events_are_logged_and_ignored(sim):
    ros = sim
    bad = JointTrajectory(joint_names=['joint1', 'elbow'], points=[
        JointTrajectoryPoint(positions=[1.0, 1.0])])
    ros.probe.publish(JointTrajectory, '/ftplan/joint_command', bad)
    wait_for(lambda: ros.probe.logged('ftplan_sim', 'ignored joint command'))
    nan = JointTrajectory(joint_names=NAMES, points=[
        JointTrajectoryPoint(positions=[1.0, float('nan'), 0.0])])
    ros.probe.publish(JointTrajectory, '/ftplan/joint_command', nan)
    wait_for(lambda: len(ros.probe.logged('ftplan_sim', 'ignored joint command')) >= 2)
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('elbow'))
    wait_for(lambda: ros.probe.logged('ftplan_sim', "unknown joint 'elbow'"))
    ros.probe.publish(JointState, '/ftplan/locked_joint', JointState(name=['a', 'b']))
    wait_for(lambda: ros.probe.logged('ftplan_sim', 'ignored locked-joint event'))
    # Its stamp is when the joint locks: one before the epoch is refused, not taken as now.
    ros.probe.publish(JointState, '/ftplan/locked_joint', JointState(
        header=Header(stamp=Time(sec=-5)), name=['joint2']))
    wait_for(lambda: ros.probe.logged('ftplan_sim', 'Time.sec = -5 is before the epoch'))
    assert np.array_equal(last(ros), [0.0, 0.0, 0.0])
    assert all(s.values['locked'] == '' for s in ros.probe.statuses(STATUS))
    command(ros, [[0.2, 0.2, 0.2]], [0.5])                 # still works
    wait_for(at(ros, [0.2, 0.2, 0.2]))


def test_collisions_are_reported_and_the_goal_is_recognised(ros):
    scene = load_scene(FIG3A)
    ros.make(SimNode, FIG3A, initial_configuration=[0.0, 0.0, 0.0])
    ros.probe.listen(JointState, '/joint_states', 1000)
    checker = CollisionChecker(scene.robot, scene.obstacles)
    # Sweep joint1 a full turn: the stretched arm hits the disks on the way.
    sweep = np.column_stack([np.linspace(0.0, 2 * np.pi, 64), np.zeros(64), np.zeros(64)])
    assert checker.min_clearance(sweep).min() < 0.0
    command(ros, sweep[1:], np.linspace(0.1, 3.0, 63))
    status = wait_for(lambda: [s for s in ros.probe.statuses(STATUS) if s.level == 'ERROR'])[0]
    assert 'collision' in status.message and int(status.values['collisions']) >= 1
    assert float(status.values['min_clearance_m']) < 0.0
    wait_for(lambda: ros.probe.logged('ftplan_sim', 'collision at'))
    # A configuration at the task goal (1, 0): 'goal reached'.
    theta = _configuration_at(scene, np.array(scene.task.goal))
    command(ros, [theta], [2.0])
    status = wait_for(lambda: [s for s in ros.probe.statuses(STATUS)
                               if s.values['goal_reached'] == 'True'])[-1]
    assert float(status.values['goal_error_m']) <= scene.task.goal_tolerance


@pytest.mark.parametrize('room', [None, 0.01], ids=['swing', 'within-a-tick'])
def test_a_collision_at_the_turn_of_a_command_is_reported_between_ticks(ros, room):
    """Issue 10's soak: the sim checked the chord between two ticks, which cuts the
    corners of a command. A joint1 swing that turns back 1e-5 rad inside a disk, at
    0.05 rad per tick, passed unseen unless a tick landed on the turn; so did a short
    swing out and back that a single tick holds whole."""
    scene = load_scene(FIG3A)
    checker = CollisionChecker(scene.robot, scene.obstacles)
    swing = np.linspace(0.0, 2 * np.pi, 2000)  # joint1 of the stretched arm
    first = int(np.argmax(checker.min_clearance(np.column_stack(
        [swing, np.zeros_like(swing), np.zeros_like(swing)])) <= 0.0))
    assert first > 0
    clear, hit = swing[first - 1], swing[first]  # the first contact lies in between
    while hit - clear > 1e-9:
        middle = 0.5 * (clear + hit)
        inside = checker.min_clearance(np.array([[middle, 0.0, 0.0]]))[0] <= 0.0
        clear, hit = (clear, middle) if inside else (middle, hit)
    turn = hit + 1e-5
    assert checker.min_clearance(np.array([[turn, 0.0, 0.0]]))[0] < 0.0
    # The swing starts from the stretched arm; the other starts `room` [rad] short of the
    # disk, and its way out and back takes 4 ms of one 10 ms tick, ending where it began.
    start = 0.0 if room is None else hit - room
    ros.make(SimNode, FIG3A, initial_configuration=[start, 0.0, 0.0], max_joint_speed=5.0,
             rate=100.0)
    ros.probe.listen(JointState, '/joint_states', 1000)
    wait_for(lambda: ros.probe.received('/joint_states'))
    duration = (turn - start) / 5.0
    command(ros, [[turn, 0.0, 0.0], [start, 0.0, 0.0]], [duration, 2.0 * duration])
    status = wait_for(lambda: [s for s in ros.probe.statuses(STATUS) if s.level == 'ERROR'])[0]
    assert 'collision' in status.message and int(status.values['collisions']) == 1


def _configuration_at(scene, x):
    """A configuration (n,) with the end effector at x, by the core's Newton projection."""
    from ftplan_ros.core.paper.manifolds import project_to_preimage
    theta = project_to_preimage(scene.robot, x, np.array([0.3, 1.0, 1.0]))
    assert theta is not None
    return theta


def test_a_lock_at_an_angle_sweeps_the_arm_there_and_checks_the_sweep(ros):
    scene = load_scene(FIG3A)
    ros.make(SimNode, FIG3A, initial_configuration=[0.0, 0.0, 0.0], lock_angle_tolerance=1.5)
    ros.probe.listen(JointState, '/joint_states', 1000)
    wait_for(lambda: ros.probe.received('/joint_states'))
    # Locking joint1 a radian away swings the stretched arm through a disk, although it
    # starts and ends clear of them (a tolerance this wide is for this test only).
    target = 1.0
    checker = CollisionChecker(scene.robot, scene.obstacles)
    assert checker.min_clearance(np.array([[0.0, 0.0, 0.0], [target, 0.0, 0.0]])).min() > 0.0
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint1', target))
    status = wait_for(lambda: [s for s in ros.probe.statuses(STATUS) if s.level == 'ERROR'])[0]
    assert 'collision' in status.message and int(status.values['collisions']) == 1
    wait_for(lambda: abs(last(ros)[0] - target) < 1e-12, what='joint1 at the lock angle')


@pytest.mark.parametrize('angle', [1.0, 1e5, 1e308, -2 * np.pi + 1.0])
def test_a_lock_angle_away_from_the_joint_is_refused_and_the_arm_stays(ros, angle):
    """Issue 10, row 9: such locks jumped the joint through a disk, stalled /joint_states
    for seconds (1e5) or were dropped without a word (1e308)."""
    ros.make(SimNode, FIG3A, initial_configuration=[0.0, 0.0, 0.0])
    ros.probe.listen(JointState, '/joint_states', 1000)
    wait_for(lambda: ros.probe.received('/joint_states'))
    ros.probe.publish(JointState, '/ftplan/locked_joint', create_locked_joint('joint1', angle))
    refused = wait_for(lambda: [s for s in ros.probe.statuses('ftplan_sim: input')
                                if 'ignored locked-joint event' in s.message])[0]
    assert 'a joint locks where it stands' in refused.message
    count = len(ros.probe.received('/joint_states'))
    wait_for(lambda: len(ros.probe.received('/joint_states')) > count + 20, timeout=5.0,
             what='joint states flowing on')
    assert np.array_equal(last(ros), [0.0, 0.0, 0.0])
    assert all(s.values['collisions'] == '0' and s.values['locked'] == ''
               for s in ros.probe.statuses(STATUS))
    # Within the tolerance (here a whole turn plus a hair away) it locks, a hair off.
    ros.probe.publish(JointState, '/ftplan/locked_joint',
                      create_locked_joint('joint1', 2 * np.pi + 0.01))
    wait_for(lambda: [s for s in ros.probe.statuses(STATUS) if s.values['locked'] == 'joint1'])
    wait_for(lambda: abs(last(ros)[0] - 0.01) < 1e-12, what='joint1 locked 0.01 rad on')


def test_the_mujoco_backend_reports_efforts_and_its_own_contacts(ros):
    """sim_backend mujoco: /joint_states carries torques; MuJoCo's contact names the bodies."""
    ros.make(SimNode, FIG3A, initial_configuration=[0.0, 0.0, 0.0], sim_backend='mujoco')
    ros.probe.listen(JointState, '/joint_states', 1000)
    wait_for(lambda: ros.probe.received('/joint_states'))
    command(ros, [[0.6, 0.0, 0.0]], [1.0])  # link1 turns into fig3a's first disk
    status = wait_for(lambda: [s for s in ros.probe.statuses(STATUS)
                               if 'MuJoCo' in s.message])[0]
    assert status.level == 'ERROR' and int(status.values['contacts']) == 1
    assert 'contact between link1 and obstacle0' in status.message
    assert float(status.message.split(', ')[1].split()[0]) > 0.0  # its depth [m]
    efforts = [msg.effort for msg in ros.probe.received('/joint_states')]
    assert all(len(effort) == 3 for effort in efforts)
    assert max(abs(value) for effort in efforts for value in effort) > 1.0  # pushing [Nm]


def test_an_unknown_sim_backend_is_refused_naming_the_choices(ros):
    with pytest.raises(InputError, match=r'sim_backend.*kinematic, mujoco'):
        ros.make(SimNode, FIG3A, sim_backend='bullet')
