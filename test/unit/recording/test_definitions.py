"""recording/definitions.py: the ros2msg schema of a type, as rosbag2's MCAP storage writes it."""

import sys
from pathlib import Path

import pytest
from mcap_ros2._dynamic import generate_dynamic

from ftplan_ros.recording.definitions import SEPARATOR, DefinitionError, message_definition

# The types of every topic the bringup publishes.
BRINGUP_TYPES = ['sensor_msgs/msg/JointState', 'trajectory_msgs/msg/JointTrajectory',
                 'std_msgs/msg/Float64MultiArray', 'visualization_msgs/msg/MarkerArray',
                 'diagnostic_msgs/msg/DiagnosticArray', 'rcl_interfaces/msg/Log',
                 'rcl_interfaces/msg/ParameterEvent']


def nested(text):
    return [line[len('MSG: '):] for line in text.splitlines() if line.startswith('MSG: ')]


def test_a_definition_is_its_msg_then_each_nested_type_depth_first():
    text = message_definition('sensor_msgs/msg/JointState')
    own = (Path(sys.prefix) / 'share' / 'sensor_msgs' / 'msg' / 'JointState.msg').read_text()
    assert text.startswith(own)
    assert nested(text) == ['std_msgs/Header', 'builtin_interfaces/Time']
    header = (Path(sys.prefix) / 'share' / 'std_msgs' / 'msg' / 'Header.msg').read_text()
    assert f'\n{SEPARATOR}\nMSG: std_msgs/Header\n{header}\n{SEPARATOR}\n' in text


def test_a_type_nested_twice_is_written_once_in_sorted_depth_first_order():
    text = message_definition('visualization_msgs/msg/MarkerArray')
    assert nested(text) == [
        'visualization_msgs/Marker', 'builtin_interfaces/Duration', 'geometry_msgs/Point',
        'geometry_msgs/Pose', 'geometry_msgs/Quaternion', 'geometry_msgs/Vector3',
        'sensor_msgs/CompressedImage', 'std_msgs/Header', 'builtin_interfaces/Time',
        'std_msgs/ColorRGBA', 'visualization_msgs/MeshFile', 'visualization_msgs/UVCoordinate']


@pytest.mark.parametrize('type_name', BRINGUP_TYPES)
def test_mcap_ros2_builds_a_decoder_from_each_schema_of_the_bringup(type_name):
    """mcap_ros2 parses schemas as Foxglove does: every nested type must be there."""
    assert type_name in generate_dynamic(type_name, message_definition(type_name))


def write_msg(prefix, package, name, text):
    path = prefix / 'share' / package / 'msg' / f'{name}.msg'
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def test_fields_of_the_same_package_are_resolved_and_primitives_comments_constants_are_not(
        tmp_path):
    write_msg(tmp_path, 'pkg', 'Outer', '# Inner in a comment\n  Inner[3] inners\n'
              'string<=8 label\nuint8 MODE=1\nfloat64[] values\nbool flag true\n'
              'other/Thing thing\n')
    write_msg(tmp_path, 'pkg', 'Inner', 'int32 x\n')
    write_msg(tmp_path, 'other', 'Thing', 'pkg/Inner inner\n')
    text = message_definition('pkg/msg/Outer', [tmp_path])
    assert nested(text) == ['other/Thing', 'pkg/Inner']
    assert text.count('int32 x') == 1


def test_a_missing_definition_or_a_bad_name_is_named(tmp_path):
    write_msg(tmp_path, 'pkg', 'Outer', 'Missing m\n')
    with pytest.raises(DefinitionError, match=r'no definition of pkg/Missing: '
                       r'share/pkg/msg/Missing.msg is in none of the prefixes'):
        message_definition('pkg/msg/Outer', [tmp_path])
    with pytest.raises(DefinitionError, match='is not a message type name'):
        message_definition('JointState', [tmp_path])


def test_types_that_nest_each_other_are_written_once_each_and_a_deep_chain_is_refused(
        tmp_path):
    write_msg(tmp_path, 'pkg', 'A', 'B b\n')
    write_msg(tmp_path, 'pkg', 'B', 'A a\n')
    assert nested(message_definition('pkg/msg/A', [tmp_path])) == ['pkg/B', 'pkg/A']
    for level in range(60):
        write_msg(tmp_path, 'deep', f'T{level}', f'T{level + 1} next\n')
    write_msg(tmp_path, 'deep', 'T60', 'int8 end\n')
    assert len(nested(message_definition('deep/msg/T20', [tmp_path]))) == 40
    with pytest.raises(DefinitionError, match='deep/msg/T0 nests types more than 50 deep'):
        message_definition('deep/msg/T0', [tmp_path])
