"""recording/bag_writer.py: MCAP in the ros2 profile, as rosbag2's MCAP storage writes it.

Read back with the mcap package's own reader, not ours: the file must stand on its own.
"""

import pytest
import yaml
from mcap.reader import make_reader

from ftplan_ros.recording.bag_writer import BagWriter
from ftplan_ros.recording.definitions import message_definition

from .recordings import EPOCH, LATCHED, STRING, Clock, cdr_string, write_recording


def read(path):
    with open(path, 'rb') as stream:
        reader = make_reader(stream)
        return (reader.get_header(), reader.get_summary(), list(reader.iter_messages()),
                {m.name: m.metadata for m in reader.iter_metadata()})


def test_schemas_channels_and_messages_follow_the_ros2_profile(tmp_path):
    path = tmp_path / 'run.mcap'
    write_recording(path, [('/a', 'one', EPOCH + 10), ('/b', 'two', EPOCH + 20),
                           ('/a', 'three', EPOCH + 30)], metadata={'scene': 'fig3a'})
    header, summary, messages, metadata = read(path)
    assert header.profile == 'ros2'
    [schema] = summary.schemas.values()
    assert (schema.name, schema.encoding) == (STRING, 'ros2msg')
    assert schema.data.decode() == message_definition(STRING)
    channels = {c.topic: c for c in summary.channels.values()}
    assert set(channels) == {'/a', '/b'}
    for channel in channels.values():
        assert channel.message_encoding == 'cdr' and channel.schema_id == schema.id
        assert yaml.safe_load(channel.metadata['offered_qos_profiles']) == [LATCHED]
        assert channel.metadata['topic_type_hash'] == 'RIHS01_00'
    assert [(channels['/a'].id, EPOCH + 10, EPOCH + 5, 0), (channels['/b'].id, EPOCH + 20,
            EPOCH + 15, 0), (channels['/a'].id, EPOCH + 30, EPOCH + 25, 1)] == [
        (m.channel_id, m.log_time, m.publish_time, m.sequence) for _, _, m in messages]
    assert messages[2][2].data == cdr_string('three')
    assert summary.statistics.message_count == 3
    assert summary.statistics.channel_message_counts == {channels['/a'].id: 2,
                                                         channels['/b'].id: 1}
    assert metadata['ftplan'] == {'scene': 'fig3a'}


def test_the_rosbag2_metadata_record_has_every_key_ros2_bag_info_of_jazzy_reads(tmp_path):
    """rosbag2_storage (Jazzy) decodes `serialized_metadata` as metadata.yaml of version 9:
    a missing key throws, and `ros2 bag info` fails."""
    path = tmp_path / 'run.mcap'
    write_recording(path, [('/a', 'one', EPOCH + 10), ('/a', 'two', EPOCH + 1_500_000_010)])
    text = read(path)[3]['rosbag2']['serialized_metadata']
    assert '&' not in text and '*' not in text  # no YAML anchor or alias, as yaml-cpp writes
    bag = yaml.safe_load(text)
    assert bag['version'] == 9 and bag['storage_identifier'] == 'mcap'
    assert bag['duration'] == {'nanoseconds': 1_500_000_000}
    assert bag['starting_time'] == {'nanoseconds_since_epoch': EPOCH + 10}
    assert bag['message_count'] == 2
    [topic] = bag['topics_with_message_count']
    assert topic == {'topic_metadata': {'name': '/a', 'type': STRING,
                                        'serialization_format': 'cdr',
                                        'offered_qos_profiles': [LATCHED],
                                        'type_description_hash': 'RIHS01_00'},
                     'message_count': 2}
    assert bag['relative_file_paths'] == ['run.mcap']
    assert bag['files'] == [{'path': 'run.mcap', 'starting_time': bag['starting_time'],
                             'duration': bag['duration'], 'message_count': 2}]
    assert bag['compression_format'] == bag['compression_mode'] == ''
    assert bag['custom_data'] == {} and bag['ros_distro']


def test_log_times_never_go_back_in_the_file_and_an_unknown_publish_time_is_the_log_time(
        tmp_path):
    clock = Clock()
    writer = BagWriter(tmp_path / 'run.mcap', clock=clock)
    writer.add_topic('/a', STRING, [])
    written = []
    for now in (EPOCH + 50, EPOCH + 40, EPOCH + 60):  # the wall clock set back once
        clock.now = now
        written.append(writer.write('/a', cdr_string('x')))
    writer.close()
    assert written == [EPOCH + 50, EPOCH + 50, EPOCH + 60]
    messages = read(tmp_path / 'run.mcap')[2]
    assert [(m.log_time, m.publish_time) for _, _, m in messages] == [
        (t, t) for t in written]
    assert read(tmp_path / 'run.mcap')[1].channels[1].metadata['offered_qos_profiles'] == ''


def test_a_topic_added_twice_keeps_its_channel_and_a_closed_file_takes_nothing(tmp_path):
    writer = BagWriter(tmp_path / 'run.mcap', clock=Clock())
    writer.add_topic('/a', STRING, [LATCHED])
    writer.add_topic('/a', 'std_msgs/msg/Int32', [])
    writer.write('/a', cdr_string('x'))
    assert writer.has_topic('/a') and not writer.has_topic('/b')
    writer.close()
    writer.close()  # once is enough
    with pytest.raises(ValueError, match='run.mcap is closed'):
        writer.write('/a', cdr_string('y'))
    assert writer.counts() == {'/a': 1}
    assert len(read(tmp_path / 'run.mcap')[1].channels) == 1
    with pytest.raises(ValueError, match='a recording is an .mcap file, not run.bag'):
        BagWriter(tmp_path / 'run.bag')
