"""`ftplan-bringup` as a user runs it: a drill, bad input, Ctrl-C."""

import sys
from pathlib import Path

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from ros_support import FIG3A, wait_for
from spatial_scenes import panda_scene
from trajectory_checks import (
    KINDS,
    commands,
    listen_to_trajectories,
    nominal_paths,
    replay_commands,
    replay_plans,
)

from ftplan_msgs_py import create_diagnostic_array, create_diagnostic_status
from ftplan_ros.bringup import INJECTOR_STATUS, Director, RunReport, summarize
from ftplan_ros.core import load_scene
from ftplan_ros.core.model.motion_limits import robot_motion_limits
from ftplan_ros.execution.options import ExecutorOptions
from ftplan_ros.nodes.topics import DIAGNOSTICS, TRAJECTORY
from ftplan_ros.plan_client import Outcome, PlanClient, PlannedMotion
from ftplan_ros.recording.bag_reader import open_bag

# The console script users run (pip -e puts it beside the interpreter).
BRINGUP = [str(Path(sys.executable).parent / 'ftplan-bringup')]
DETOUR = Path(__file__).parent / 'scenes' / 'detour.yaml'
SPEED = 2.0  # [rad/s] the bringup's --speed: the executor's max_joint_speed


def test_a_drill_through_the_bringup_reaches_the_goal_and_draws_it(processes, tmp_path):
    png = tmp_path / 'motion.png'
    bringup = processes(BRINGUP + ['--scene', FIG3A, '--drill', 'joint2@0.4', '--png', png])
    code, out, err = bringup.wait(timeout=300)
    assert code == 0, out + err
    assert '1/1 runs reached the goal without collision' in out
    assert 'joint2@0.4' in out and 'recovery time p50' in out
    assert 'plan ' in out.splitlines()[0] and 'theta_s' in out.splitlines()[0]
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b'\x89PNG'
    assert 'run 1/1: joint2@0.4 -> reached' in err
    assert 'approach: ' in err  # how the arm gets to θ_s, from the planner's status
    clearance, deviation = braking_figures(out, locks=1)
    assert 0.0 < clearance < 1.0 and 0.0 <= deviation < 0.1


def braking_figures(out: str, locks: int) -> tuple[float, float]:
    """The bringup's braking line: (smallest clearance [m], largest deviation [rad])."""
    line = next(line for line in out.splitlines() if line.startswith('braking after '))
    head, tail = line.split(': smallest clearance ')
    assert head == f'braking after {locks} lock(s)'
    clearance, rest = tail.split(' m, largest deviation from the lock point ')
    deviation, measured = rest.split(' rad (∞-norm, ')
    assert measured == f'{locks} measured)'
    return float(clearance), float(deviation)


def test_a_drill_that_cannot_land_during_the_motion_is_not_drilled_and_exits_1(processes):
    """Issue 33: a lock after the motion is no drilled run. Locked 60 s after the start,
    long after the goal, joint2 is dropped by the injector; the summary said '1/1 runs
    reached the goal' and the bringup exited 0, as if the recovery had been drilled."""
    code, out, err = processes(BRINGUP + ['--scene', FIG3A, '--drill', 'joint2@60s']).wait(
        timeout=300)
    assert code == 1, out + err
    assert out.splitlines()[-1] == (
        '1/1 runs reached the goal without collision; 0/1 drilled as asked, 1 not drilled '
        '(run 1 joint2@60s: no lock during the execution)')
    assert 'reached; NOT DRILLED: no lock during the execution' in out
    assert 'run 1/1: joint2@60s -> reached; NOT DRILLED' in err


def test_the_summary_counts_drilled_runs_apart_from_runs_that_reached_the_goal():
    """Issue 33: a lock after the motion read as a drilled run ('10/10 reached')."""
    scene = load_scene(FIG3A)
    motion = PlannedMotion(Outcome.SUCCEEDED, 'plan found', '1.0', ('joint1', 'joint2', 'joint3'),
                           theta_s=np.zeros(3), trajectory=np.zeros((5, 3)),
                           surface=np.zeros((4, 5, 3)), plan_time_s=0.1, round_trip_s=0.2)
    late = 'lock landed at 100.0%: after the motion, asked 90.0%'
    runs = [RunReport(1, 'joint2@0.5', True, 'reached', 'joint2', 0.5, 0.4, 1e-6,
                      min_clearance=0.05),
            RunReport(2, 'joint3@0.9', True, 'reached', 'joint3', 1.0, 0.1, 1e-6,
                      min_clearance=0.05, missed=late),
            RunReport(3, 'joint1@60s', True, 'reached', goal_error=1e-6, min_clearance=0.05,
                      missed='no lock during the execution'),
            RunReport(4, '', False, 'the sim did not report the goal reached')]
    summary = summarize(scene, motion, runs).splitlines()
    assert summary[-1] == (
        '3/4 runs reached the goal without collision; 1/3 drilled as asked, 2 not drilled '
        f'(run 2 joint3@0.9: {late}; run 3 joint1@60s: no lock during the execution)')
    row = next(line for line in summary if line.lstrip().startswith('2 '))
    assert row.endswith(f'reached; NOT DRILLED: {late}') and ' 100.0 ' in row
    assert summarize(scene, motion, runs[:1]).splitlines()[-1] == \
        '1/1 runs reached the goal without collision; 1/1 drilled as asked'
    assert summarize(scene, motion, runs[3:]).splitlines()[-1] == \
        '0/1 runs reached the goal without collision'


def test_bad_input_exits_2_with_one_line(processes):
    for args, problem in [(['--drill', 'joint7@0.4'], "unknown joint 'joint7'"),
                          (['--drill', 'joint1@4'], 'must be in [0, 1]'),
                          (['--trials', '-3'], '--trials'),
                          (['--ros-args', '-r', '__node:=bad-name'],
                           "cannot start ROS: failed to initialize rcl: Couldn't parse remap")]:
        code, out, err = processes(BRINGUP + ['--scene', FIG3A, *args]).wait(timeout=120)
        assert code == 2, (args, out, err)
        assert problem in err and 'Traceback' not in err
    code, _, err = processes(BRINGUP + ['--scene', '/nonexistent.yaml']).wait(timeout=120)
    assert code == 2 and 'cannot read nonexistent.yaml (no such file)' in err


def test_ctrl_c_shuts_every_node_down_cleanly_and_closes_the_recording(processes, tmp_path):
    recording = tmp_path / 'run.mcap'
    bringup = processes(BRINGUP + ['--scene', FIG3A, '--trials', '200', '--seed', '3',
                                   '--record', recording])
    wait_for(lambda: 'run 1/200' in bringup.output()[1] or not bringup.alive(), timeout=300,
             what='the first run')
    code, out, err = bringup.interrupt()
    assert code == 130, out + err
    assert 'interrupted; shutting the nodes down' in err
    assert 'Traceback' not in err and 'exception' not in err.lower()
    with open_bag(recording) as bag:  # complete, with its summary
        assert bag.topic('/joint_states').count > 0
        assert f'Messages:          {bag.message_count}' in bag.info()


def test_a_drill_of_a_7_joint_arm_through_the_bringup(processes, tmp_path):
    png = tmp_path / 'panda.png'
    bringup = processes(BRINGUP + ['--scene', panda_scene(tmp_path), '--drill',
                                   'panda_joint2@0.4', '--png', png])
    code, out, err = bringup.wait(timeout=300)
    assert code == 0, out + err
    assert '1/1 runs reached the goal without collision' in out
    assert 'tolerates panda_joint1, panda_joint2, panda_joint3, panda_joint5' in out
    row = next(line for line in out.splitlines() if 'panda_joint2@0.4' in line)
    assert row.split()[2] == 'panda_joint2' and row.endswith('reached')
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b'\x89PNG'


def test_a_bad_png_or_record_or_an_unplannable_scene_exit_2_before_any_run(processes, tmp_path):
    """Issue 10, row 11: both ran the whole suite first, then a traceback and exit 1.
    Issue 37: a --record path is checked as --png is, and no file is left behind."""
    two = tmp_path / 'two_links.yaml'
    two.write_text('robot: {type: planar, link_lengths: [1.0, 1.0]}\n'
                   'task: {start: [1.5, 0.0], goal: [1.0, 0.5]}\n')
    for args, problem in [(['--scene', FIG3A, '--png', tmp_path / 'x.jpg'],
                           '--png: writes PNG files: give a path ending in .png'),
                          (['--scene', FIG3A, '--png', tmp_path / 'none' / 'x.png'],
                           'does not exist'),
                          (['--scene', FIG3A, '--record', tmp_path / 'run.bag'],
                           '--record: writes MCAP files: give a path ending in .mcap'),
                          (['--scene', FIG3A, '--record', tmp_path / 'none' / 'run.mcap'],
                           '--record: the folder of'),
                          (['--scene', two], '2 joints give no redundancy')]:
        code, out, err = processes(BRINGUP + args).wait(timeout=120)
        assert code == 2, (args, out, err)
        assert problem in err and 'Traceback' not in err
        assert 'starting the planner' not in err                 # refused before any node
    assert not (tmp_path / 'run.bag').exists()


def test_where_no_plan_starts_within_the_arms_reach_the_bringup_says_so(processes):
    """out_of_reach (issue 36): the sim's default start lies in another free component than
    every start that may be failure-tolerant. The planner found a plan there and served it,
    its approach proved impossible; now it answers that none is reachable, proved, and the
    bringup exits 1 before any run."""
    scene = Path(__file__).parent / 'scenes' / 'out_of_reach.yaml'
    code, out, err = processes(BRINGUP + ['--scene', scene]).wait(timeout=300)
    assert code == 1, out + err
    assert 'scene out_of_reach: none reachable (proved): no failure-tolerant plan starts where ' \
        'the arm can get to from here (proved on a 64^3 joint grid' in out
    assert 'runs reached' not in out


def test_drills_from_the_sims_default_start_work_when_theta_s_is_on_another_arc(processes):
    """Issue 10: the sim starts on another arc of M_s than θ_s and a straight joint move
    collides; runs failed before any drill with "no collision-free approach to theta_s"."""
    bringup = processes(BRINGUP + ['--scene', DETOUR, '--drill', 'joint2@0.5',
                                   '--drill', 'joint1@0.0s'])
    code, out, err = bringup.wait(timeout=300)
    assert code == 0, out + err
    assert '2/2 runs reached the goal without collision' in out


def test_physics_drills_through_the_bringup_reach_the_goal_without_contact(processes, ros):
    """--sim mujoco: 2 drills on fig3a and 1 on the Panda shelf, through the real nodes.

    Issue 36: every command the executor published, as a subscriber on the bringup's ROS
    domain received it, replays within the limits the executor times them by."""
    shelf = FIG3A.parent / 'panda_shelf.yaml'
    listen_to_trajectories(ros.probe)
    counts = {}
    for scene, drills in ((FIG3A, ['joint2@0.4', 'joint1@0.6']), (shelf, ['panda_joint2@0.5'])):
        robot = load_scene(scene).robot
        sent, planned = len(commands(ros.probe)), len(ros.probe.received(TRAJECTORY))
        arguments = [part for drill in drills for part in ('--drill', drill)]
        code, out, err = processes(BRINGUP + ['--scene', scene, '--sim', 'mujoco', '--speed',
                                              str(SPEED), *arguments]).wait(timeout=300)
        assert code == 0, out + err
        assert f'{len(drills)}/{len(drills)} runs reached the goal without collision' in out
        physics = next(line for line in out.splitlines() if line.startswith('physics: '))
        assert physics.startswith('physics: 0 MuJoCo contacts, largest tracking error ')
        assert 'standstill after a lock at most -' not in physics  # each lock was timed
        clearance, deviation = braking_figures(out, locks=len(drills))
        assert 0.0 < clearance < 1.0 and 0.0 <= deviation < 0.1
        [nominal] = nominal_paths(ros.probe, robot.joint_names, since=planned)
        limits = ExecutorOptions(max_joint_speed=SPEED).commanded(robot_motion_limits(robot))
        counts[scene.stem] = replay_commands(commands(ros.probe)[sent:], robot, nominal, limits)
        counts[scene.stem] += replay_plans(ros.probe, robot, robot_motion_limits(robot).capped(
            SPEED), since=planned)
    # Each bringup is a new process: its first approach may go out before this process has
    # discovered its executor (the topic is volatile), as on a loaded machine it did.
    for scene, runs in (('fig3a', 2), ('panda_shelf', 1)):
        approaches = counts[scene].pop('approach', 0)
        assert runs - 1 <= approaches <= runs, counts
        assert counts[scene] == {kind: runs for kind in KINDS if kind != 'approach'} | {
            'planned trajectory': 1, 'planned approach': 1}, counts


def test_the_drill_of_a_long_run_is_kept_when_its_statuses_overflow_the_clients_log(
        ros_context):
    """A 50 s run on crowded_sheets_100 (an executor status at 10 Hz) pushed the injector's
    'armed' status out of the client's 500 kept statuses: the run read 'NOT DRILLED: the
    injector armed no drill' although its joint locked as drilled."""
    client = PlanClient(context=ros_context)
    director = Director(client, load_scene(FIG3A))
    talker = Node('ftplan_test_statuses', context=ros_context)
    try:
        publisher = talker.create_publisher(DiagnosticArray, DIAGNOSTICS, 50)
        wait_for(lambda: publisher.get_subscription_count() >= 1)  # the client's

        def send(name, values, count=1):
            for _ in range(count):
                publisher.publish(create_diagnostic_array(
                    [create_diagnostic_status(name, 'OK', 'status', values)]))

        send(INJECTOR_STATUS, {'execution': 7, 'drill': 'joint2@0.5'})
        for _ in range(30):                        # 600 executor statuses, 20 at a time
            send('ftplan_executor: execution', {'execution': 7, 'state': 'nominal'}, 20)
            client.spin_until(lambda: False, 0.05)
        assert client.spin_until(lambda: director.drills == {'7': 'joint2@0.5'}, 2.0)
        assert client.statuses(INJECTOR_STATUS) == []   # gone from the client's log
    finally:
        talker.destroy_node()
        client.destroy_node()
