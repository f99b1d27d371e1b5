"""Writing a recording: an MCAP file as rosbag2's MCAP storage (ROS 2 Jazzy) writes one.

The MCAP specification's `ros2` profile: the header's profile 'ros2'; per message type a
schema named like 'sensor_msgs/msg/JointState' in the `ros2msg` encoding (its .msg text
and those it nests: definitions.py); per topic a channel of message encoding 'cdr' whose
metadata holds `offered_qos_profiles` (the QoS of the topic's publishers, a YAML list as
rosbag2 serialises it: history, depth, reliability, durability, deadline, lifespan,
liveliness, liveliness_lease_duration, avoid_ros_namespace_conventions) and
`topic_type_hash`. Messages are the CDR bytes as they came off the wire, with a publish
time and a log time, the moment the writer took them [ns since the epoch, wall clock],
so that the file is in log time order. Closing the file
adds rosbag2's metadata record ('rosbag2', its `serialized_metadata`: the bag's
metadata.yaml of version 9, which `ros2 bag info` reads) and ftplan's own ('ftplan':
what was recorded), then the summary and indexes that readers seek by.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import yaml
from mcap.well_known import MessageEncoding, Profile, SchemaEncoding
from mcap.writer import CompressionType, Writer

from .definitions import message_definition

ROSBAG2_METADATA = 'rosbag2'           # the metadata record rosbag2 reads
FTPLAN_METADATA = 'ftplan'             # ours: the scene and command of the recorded run
METADATA_VERSION = 9                   # rosbag2's metadata version in Jazzy
# The ROS 2 wheels set no ROS_DISTRO: they are Jazzy's.
ROS_DISTRO = os.environ.get('ROS_DISTRO') or 'jazzy'


@dataclass
class _Topic:
    channel: int
    type_name: str
    offered_qos: list[dict]
    type_hash: str
    count: int = 0


class BagWriter:
    """A recording being written; `write` may be called from any thread.

    `path` must end in .mcap; it is created (or truncated) at once. `metadata` goes into
    the 'ftplan' metadata record (text keys and values). `clock` gives the log times
    [ns since the epoch].
    """

    def __init__(self, path: str | Path, metadata: Mapping[str, str] | None = None,
                 clock: Callable[[], int] = time.time_ns):
        self.path = Path(path)
        if self.path.suffix != '.mcap':
            raise ValueError(f'a recording is an .mcap file, not {self.path.name}')
        self._stream = self.path.open('wb')
        self._writer = Writer(self._stream, compression=CompressionType.ZSTD)
        self._writer.start(profile=Profile.ROS2, library='ftplan')
        self._metadata = dict(metadata or {})
        self._clock = clock
        self._schemas: dict[str, int] = {}
        self._topics: dict[str, _Topic] = {}
        self._lock = threading.Lock()
        self._first = self._last = None
        self._closed = False

    def add_topic(self, name: str, type_name: str, offered_qos: Sequence[Mapping],
                  type_hash: str = '') -> None:
        """Add a topic: `type_name` like 'sensor_msgs/msg/JointState', its publishers' QoS.

        Each QoS is a mapping with rosbag2's keys (module docstring), e.g. from
        nodes/recorder.py `offered_qos`. A topic added twice keeps its first channel.
        Raises DefinitionError when the type's .msg definition cannot be found.
        """
        with self._lock:
            if name in self._topics:
                return
            schema = self._schemas.get(type_name)
            if schema is None:
                text = message_definition(type_name)
                schema = self._writer.register_schema(type_name, SchemaEncoding.ROS2,
                                                      text.encode())
                self._schemas[type_name] = schema
            qos = [dict(profile) for profile in offered_qos]
            channel = self._writer.register_channel(
                name, MessageEncoding.CDR, schema,
                {'offered_qos_profiles': _dump(qos) if qos else '',
                 'topic_type_hash': type_hash})
            self._topics[name] = _Topic(channel, type_name, qos, type_hash)

    def has_topic(self, name: str) -> bool:
        """Whether the topic `name` was added."""
        with self._lock:
            return name in self._topics

    def write(self, topic: str, data: bytes, publish_time: int = 0) -> int:
        """Write a CDR message of an added topic, logged now; return its log time [ns].

        `publish_time` [ns since the epoch] 0 means unknown: the log time stands in, as
        the MCAP specification asks. A clock set back does not set log times back.
        """
        with self._lock:
            if self._closed:
                raise ValueError(f'{self.path.name} is closed')
            entry = self._topics[topic]
            log_time = max(self._clock(), self._last or 0)
            self._writer.add_message(entry.channel, log_time, bytes(data),
                                     int(publish_time) or log_time, entry.count)
            entry.count += 1
            self._first = log_time if self._first is None else self._first
            self._last = log_time
            return log_time

    def counts(self) -> dict[str, int]:
        """Return the messages written per topic."""
        with self._lock:
            return {name: topic.count for name, topic in self._topics.items()}

    def close(self) -> None:
        """Write the metadata records, the summary and the indexes; close the file (once)."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
            self._writer.add_metadata(ROSBAG2_METADATA,
                                      {'serialized_metadata': _dump(self._bag_metadata())})
            self._writer.add_metadata(FTPLAN_METADATA, self._metadata)
            self._writer.finish()
            self._stream.close()

    def _bag_metadata(self) -> dict:
        """Return the bag's metadata as rosbag2 serialises it (metadata.yaml, version 9)."""
        first = self._first or 0
        duration = (self._last or 0) - first
        count = sum(topic.count for topic in self._topics.values())
        return {
            'version': METADATA_VERSION, 'storage_identifier': 'mcap',
            'duration': {'nanoseconds': duration},
            'starting_time': {'nanoseconds_since_epoch': first}, 'message_count': count,
            'topics_with_message_count': [
                {'topic_metadata': {'name': name, 'type': topic.type_name,
                                    'serialization_format': MessageEncoding.CDR,
                                    'offered_qos_profiles': topic.offered_qos,
                                    'type_description_hash': topic.type_hash},
                 'message_count': topic.count} for name, topic in self._topics.items()],
            'compression_format': '', 'compression_mode': '',
            'relative_file_paths': [self.path.name],
            'files': [{'path': self.path.name, 'starting_time':
                       {'nanoseconds_since_epoch': first}, 'duration': {'nanoseconds': duration},
                       'message_count': count}],
            'custom_data': {}, 'ros_distro': ROS_DISTRO}


def _dump(data) -> str:
    """Return YAML in block style, keys in the given order (as yaml-cpp writes rosbag2's).

    A value that appears twice is written twice: the same object would become an anchor
    and an alias, which yaml-cpp reads but rosbag2 never writes.
    """
    return yaml.dump(data, Dumper=_PlainDumper, sort_keys=False, default_flow_style=False)


class _PlainDumper(yaml.SafeDumper):
    def ignore_aliases(self, data) -> bool:
        return True
