"""Recordings through real nodes: the recorder node, `ftplan-bringup --record`, `ftplan replay`.

The files are read back with recording/bag_reader.py, whose decoding is mcap_ros2's (as
Foxglove's): a schema that did not describe rclpy's CDR bytes would fail there.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from builtin_interfaces.msg import Duration
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point
from matplotlib.image import imread
from mcap_ros2._dynamic import generate_dynamic
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.serialization import serialize_message
from ros_support import FIG3A, SCENES, wait_for
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, MultiArrayLayout
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py import create_joint_state
from ftplan_ros.core import InputError, load_scene
from ftplan_ros.core.model.robot import robot_digest
from ftplan_ros.nodes.qos import LATCHED_QOS
from ftplan_ros.nodes.recorder import Recording, subscription_qos
from ftplan_ros.recording.bag_reader import open_bag
from ftplan_ros.recording.bag_writer import BagWriter
from ftplan_ros.recording.definitions import message_definition
from ftplan_ros.recording.replay import recorded_runs, recorded_scene

BIN = Path(sys.executable).parent
# What a recorded bringup holds: every topic the suite publishes, with its type.
BRINGUP_TOPICS = {
    '/joint_states': 'sensor_msgs/msg/JointState',
    '/ftplan/joint_command': 'trajectory_msgs/msg/JointTrajectory',
    '/ftplan/locked_joint': 'sensor_msgs/msg/JointState',
    '/ftplan/plan/start_configuration': 'sensor_msgs/msg/JointState',
    '/ftplan/plan/trajectory': 'trajectory_msgs/msg/JointTrajectory',
    '/ftplan/plan/approach': 'trajectory_msgs/msg/JointTrajectory',
    '/ftplan/plan/failure_surface': 'std_msgs/msg/Float64MultiArray',
    '/ftplan/plan/markers': 'visualization_msgs/msg/MarkerArray',
    '/ftplan/plan/info': 'diagnostic_msgs/msg/DiagnosticArray',
    '/diagnostics': 'diagnostic_msgs/msg/DiagnosticArray',
    '/rosout': 'rcl_interfaces/msg/Log',
    '/parameter_events': 'rcl_interfaces/msg/ParameterEvent'}
PLAN_TOPICS = [topic for topic in BRINGUP_TOPICS if topic.startswith('/ftplan/plan/')]


def test_the_recorder_writes_each_message_once_latched_ones_too_with_the_offered_qos(
        ros, tmp_path):
    probe = ros.probe
    names = ['a', 'b']
    latched = probe.create_publisher(JointState, '/test/latched', LATCHED_QOS)
    latched.publish(create_joint_state(names, [1.0, 2.0]))  # before the recorder exists
    recording = Recording(BagWriter(tmp_path / 'run.mcap'), context=ros.context)
    try:
        probe.advertise(JointState, '/test/states', 10)  # the recorder subscribes to it
        for k in range(200):
            probe.publishers_['/test/states'].publish(create_joint_state(names, [k, -k]))
        wait_for(lambda: recording.writer.counts().get('/test/states') == 200,
                 what='200 joint states recorded')
        wait_for(lambda: recording.writer.counts().get('/test/latched') == 1,
                 what='the latched joint state')
    finally:
        counts = recording.stop()
    assert counts['/test/states'] == 200 and counts['/test/latched'] == 1
    with open_bag(tmp_path / 'run.mcap') as bag:
        assert bag.topic('/test/states').type_name == 'sensor_msgs/msg/JointState'
        recorded = list(bag.messages(['/test/states']))
        latched_message = list(bag.messages(['/test/latched']))
        offered = {channel.topic: yaml.safe_load(channel.metadata['offered_qos_profiles'])
                   for channel in bag._summary.channels.values()}
    assert [list(m.message.position) for m in recorded] == [[k, -k] for k in range(200)]
    assert [m.message.name for m in latched_message] == [names]
    log_times = [m.log_time for m in recorded]
    assert log_times == sorted(log_times)
    assert all(0 < m.publish_time <= m.log_time for m in recorded)
    [profile] = offered['/test/latched']
    assert (profile['durability'], profile['reliability']) == ('transient_local', 'reliable')
    assert offered['/test/states'][0]['durability'] == 'volatile'


class FullDisk(BagWriter):
    """A recording whose file system fills up after the first message."""

    def write(self, topic, data, publish_time=0):
        if self.counts().get(topic):
            raise OSError(28, 'No space left on device')
        return super().write(topic, data, publish_time)


def test_a_full_disk_stops_the_recording_with_one_error_and_counts_what_is_lost(
        ros, tmp_path):
    recording = Recording(FullDisk(tmp_path / 'run.mcap'), context=ros.context)
    try:
        ros.probe.advertise(JointState, '/test/states', 10)
        for k in range(5):
            ros.probe.publishers_['/test/states'].publish(create_joint_state(['a'], [k]))
        # 4 joint states, and what comes after (the error's own line on /rosout)
        wait_for(lambda: recording.node.lost >= 4, what='4 messages lost')
        errors = wait_for(lambda: ros.probe.logged('ftplan_recorder', 'cannot write'))
    finally:
        counts = recording.stop()
    assert counts['/test/states'] == 1 and len(errors) == 1
    assert 'No space left on device; the messages from now on are lost' in errors[0]


def test_the_recorder_asks_for_what_every_publisher_offers():
    """rosbag2's rule: reliable and transient-local only when every publisher offers it."""
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    sensor = QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT,
                        durability=DurabilityPolicy.VOLATILE)
    both = subscription_qos([latched, latched])
    assert (both.reliability, both.durability) == (ReliabilityPolicy.RELIABLE,
                                                   DurabilityPolicy.TRANSIENT_LOCAL)
    mixed = subscription_qos([latched, sensor])
    assert (mixed.reliability, mixed.durability) == (ReliabilityPolicy.BEST_EFFORT,
                                                     DurabilityPolicy.VOLATILE)
    assert both.depth == mixed.depth == 1000


@pytest.mark.parametrize('message', [
    JointTrajectory(joint_names=['a', 'b'], points=[JointTrajectoryPoint(
        positions=[0.5, -0.25], velocities=[1.0, 0.0], time_from_start=Duration(
            sec=1, nanosec=5))]),
    MarkerArray(markers=[Marker(ns='obstacles', id=3, type=Marker.SPHERE_LIST,
                                points=[Point(x=1.0, y=2.0, z=3.0)], text='x')]),
    DiagnosticArray(status=[DiagnosticStatus(level=DiagnosticStatus.WARN, name='n',
                                             values=[KeyValue(key='k', value='v')])]),
    Float64MultiArray(layout=MultiArrayLayout(dim=[MultiArrayDimension(
        label='path', size=2, stride=2)]), data=[1.5, 2.5]),
], ids=['trajectory', 'markers', 'diagnostics', 'array'])
def test_rclpy_cdr_bytes_decode_with_the_recorded_schema(message):
    type_name = f'{type(message).__module__.split(".")[0]}/msg/{type(message).__name__}'
    decoded = generate_dynamic(type_name, message_definition(type_name))[type_name](
        serialize_message(message))
    assert plain(decoded, message) == plain(message, message)


def plain(message, like):
    """Return `message`'s fields as plain values, walking those of the rclpy message `like`."""
    if hasattr(like, 'get_fields_and_field_types'):
        return {name: plain(getattr(message, name), getattr(like, name))
                for name in like.get_fields_and_field_types()}
    if isinstance(like, (list, tuple, np.ndarray)) or type(like).__name__ == 'array':
        return [plain(value, value_like) for value, value_like in zip(message, like,
                                                                         strict=True)]
    return ord(message) if isinstance(message, bytes) else message


def test_a_recorded_drill_holds_every_topic_in_time_order_and_replays_to_the_live_figure(
        processes, tmp_path):
    recording, live, replayed = tmp_path / 'run.mcap', tmp_path / 'live.png', \
        tmp_path / 'replay.png'
    code, out, err = processes([BIN / 'ftplan-bringup', '--scene', FIG3A, '--drill',
                                'joint2@0.4', '--record', recording, '--png', live]).wait(
        timeout=300)
    assert code == 0, out + err
    with open_bag(recording) as bag:
        types = {topic.name: topic.type_name for topic in bag.topics}
        counts = {topic.name: topic.count for topic in bag.topics}
        assert all(topic.serialization_format == 'cdr' for topic in bag.topics)
        messages = list(bag.messages())
        total = bag.message_count
    assert {name: types.get(name) for name in BRINGUP_TOPICS} == BRINGUP_TOPICS
    assert f'wrote {recording}: {total} messages on {len(types)} topics' in out
    assert len(messages) == total == sum(counts.values())
    assert [counts[topic] for topic in PLAN_TOPICS] == [1] * len(PLAN_TOPICS)
    assert counts['/ftplan/locked_joint'] == 1
    assert counts['/ftplan/joint_command'] >= 3     # approach, nominal, stop, recovery
    assert counts['/joint_states'] > 100            # 100 Hz for seconds
    log_times = [m.log_time for m in messages]
    assert log_times == sorted(log_times)
    stamps = [m.message.header.stamp for m in messages if m.topic == '/joint_states']
    assert all((a.sec, a.nanosec) < (b.sec, b.nanosec) for a, b in zip(stamps, stamps[1:],
                                                                      strict=False))
    [lock] = [m.message for m in messages if m.topic == '/ftplan/locked_joint']
    assert list(lock.name) == ['joint2']
    [markers] = [m.message for m in messages if m.topic == '/ftplan/plan/markers']
    assert sum(marker.ns == 'obstacles' for marker in markers.markers) == 3  # fig3a's disks

    code, out, err = processes([BIN / 'ftplan', 'replay', recording, '--png',
                                replayed]).wait(timeout=300)
    assert code == 0, out + err
    assert f'Messages:          {total}\n' in out
    assert 'run 1: joint2@0.4, joint2 locked at 40.0% of the nominal path' in out
    assert np.array_equal(imread(replayed), imread(live))  # one drawing, the same run
    code, out, err = processes([BIN / 'ftplan', 'replay', recording, '--png', replayed,
                                '--scene', SCENES / 'panda_shelf.yaml']).wait(timeout=300)
    assert code == 2 and err.strip().splitlines() == [
        f'ftplan: error: --scene: the robot of panda_shelf.yaml (digest '
        f'{robot_digest(load_scene(SCENES / "panda_shelf.yaml").robot)}) is not the recorded '
        f'one ({robot_digest(load_scene(FIG3A).robot)}): give the scene the run was recorded '
        'with']


def test_a_replay_needs_the_scene_the_recording_names_or_one_given(tmp_path):
    BagWriter(tmp_path / 'anonymous.mcap').close()
    BagWriter(tmp_path / 'moved.mcap', {'scene_file': str(tmp_path / 'gone.yaml')}).close()
    with open_bag(tmp_path / 'anonymous.mcap') as bag, pytest.raises(
            InputError, match='does not name the scene it recorded: give it with --scene'):
        recorded_scene(bag)
    with open_bag(tmp_path / 'moved.mcap') as bag:
        with pytest.raises(InputError, match=r'--scene: the recorded scene file .*gone.yaml is '
                           'not here: give the scene with --scene SCENE.yaml'):
            recorded_scene(bag)
        assert recorded_scene(bag, FIG3A).name == 'fig3a'  # no plan recorded: no digest
        assert recorded_runs(bag, ['joint1', 'joint2', 'joint3']) == []
