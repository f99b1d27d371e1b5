"""recording/bag_reader.py: a recording checked, summarised as `ros2 bag info` does, decoded."""

import time

import pytest
from mcap.writer import Writer

from ftplan_ros.core import InputError
from ftplan_ros.recording.bag_reader import open_bag
from ftplan_ros.recording.bag_writer import ROS_DISTRO

from .recordings import EPOCH, STRING, write_recording

SECOND = 1_000_000_000


@pytest.fixture
def recording(tmp_path):
    path = tmp_path / 'run.mcap'
    write_recording(path, [('/chatter', 'one', EPOCH + 10), ('/b', 'two', EPOCH + 20),
                           ('/chatter', 'three', EPOCH + 12 * SECOND + 30)],
                    metadata={'scene_file': 'fig3a.yaml'})
    return path


def test_the_summary_is_laid_out_as_ros2_bag_info_of_jazzy_prints_it(recording):
    with open_bag(recording) as bag:
        lines = bag.info().splitlines()
    start = time.localtime(EPOCH // SECOND)
    assert lines[0] == ''
    assert lines[1:5] == ['Files:             run.mcap',
                          f'Bag size:          {recording.stat().st_size / 1024:.1f} KiB',
                          'Storage id:        mcap', f'ROS Distro:        {ROS_DISTRO}']
    assert lines[5] == 'Duration:          12.000000020s'
    assert lines[6] == (f'Start:             {time.strftime("%b", start)} {start.tm_mday:2d} '
                        f'{start.tm_year} {time.strftime("%H:%M:%S", start)}.000000010 '
                        '(1700000000.000000010)')
    assert lines[7].startswith('End:               ') and lines[7].endswith(
        '.000000030 (1700000012.000000030)')
    assert lines[8:] == [
        'Messages:          3',
        'Topic information: Topic: /chatter | Type: std_msgs/msg/String | Count: 2 | '
        'Serialization Format: cdr',
        '                   Topic: /b | Type: std_msgs/msg/String | Count: 1 | '
        'Serialization Format: cdr',
        'Service:           0', 'Service information: ']


def test_messages_are_decoded_from_their_schemas_with_their_times(recording):
    with open_bag(recording) as bag:
        assert bag.metadata['ftplan'] == {'scene_file': 'fig3a.yaml'}
        assert bag.topic('/b').count == 1 and bag.topic('/nothing') is None
        read = [(m.topic, m.type_name, m.log_time, m.publish_time, m.message.data)
                for m in bag.messages()]
        only = [m.message.data for m in bag.messages(['/chatter'], log_time_order=True)]
    assert read == [('/chatter', STRING, EPOCH + 10, EPOCH + 5, 'one'),
                    ('/b', STRING, EPOCH + 20, EPOCH + 15, 'two'),
                    ('/chatter', STRING, EPOCH + 12 * SECOND + 30, EPOCH + 12 * SECOND + 25,
                     'three')]
    assert only == ['one', 'three']


def refused(path, problem):
    with pytest.raises(InputError, match=problem) as error:
        open_bag(path)
    assert error.value.field == str(path)


def test_what_is_no_complete_recording_is_refused_naming_the_file(recording, tmp_path):
    data = recording.read_bytes()
    (tmp_path / 'text.mcap').write_text('rosbag2_bagfile_information:\n  version: 9\n')
    refused(tmp_path / 'text.mcap', 'is not an MCAP file')
    (tmp_path / 'empty.mcap').write_bytes(b'')
    refused(tmp_path / 'empty.mcap', 'is not a complete MCAP recording: it is cut off')
    for cut in (len(data) // 2, len(data) - 5, 40):
        (tmp_path / 'cut.mcap').write_bytes(data[:cut])
        refused(tmp_path / 'cut.mcap', 'is not a complete MCAP recording: it is cut off')
    refused(tmp_path / 'none.mcap', r'cannot read it \(No such file or directory\)')
    with open(tmp_path / 'ros1.mcap', 'wb') as stream:
        writer = Writer(stream)
        writer.start(profile='ros1')
        writer.finish()
    refused(tmp_path / 'ros1.mcap', "is an MCAP file of profile 'ros1', not a ROS 2 recording")
    with open(tmp_path / 'open.mcap', 'wb') as stream:  # never finished: no summary
        writer = Writer(stream, use_summary_offsets=False)
        writer.start(profile='ros2')
    refused(tmp_path / 'open.mcap', 'cut off')


def test_a_message_that_does_not_fit_its_schema_is_refused_naming_the_file(tmp_path):
    with open(tmp_path / 'bad.mcap', 'wb') as stream:
        writer = Writer(stream)
        writer.start(profile='ros2')
        schema = writer.register_schema(STRING, 'ros2msg', b'string data')
        channel = writer.register_channel('/a', 'cdr', schema, {})
        writer.add_message(channel, EPOCH, b'\x00\x01\x00\x00\xff\xff', EPOCH)
        writer.finish()
    with open_bag(tmp_path / 'bad.mcap') as bag, pytest.raises(
            InputError, match='bad.mcap: is not a complete MCAP recording: it is cut off or '
            'damaged'):
        list(bag.messages())
