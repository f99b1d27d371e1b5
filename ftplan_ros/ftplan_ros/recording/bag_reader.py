"""Reading a recording back: checked, summarised as `ros2 bag info` does, and decoded.

`open_bag(path)` reads an MCAP file's header and summary and refuses, with an InputError
naming the file, what is not a complete recording in the `ros2` profile: another kind of
file, a file cut off (no summary at its end: the recorder did not close it), another
profile. `Bag.info()` is the text `ros2 bag info` prints for it (rosbag2 of Jazzy: files,
size, storage id, ROS distro, duration, start and end in local time, messages, and per
topic its type, count and serialization format). `Bag.messages()` decodes the messages
from their ros2msg schemas and CDR bytes, as Foxglove does, with mcap_ros2: the decoded
messages are plain objects with the fields of the ROS messages, so ftplan_msgs_py's
readers take them.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
import zstandard
from mcap.exceptions import McapError
from mcap.reader import McapReader, make_reader
from mcap.well_known import Profile
from mcap_ros2.decoder import DecoderFactory

from ..core import InputError
from .bag_writer import ROSBAG2_METADATA

# What a damaged file can raise besides McapError: struct and zstd errors in a chunk cut
# short, a schema mcap_ros2 cannot parse, CDR bytes that do not fit their schema.
_DAMAGED = (McapError, struct.error, zstandard.ZstdError, ValueError, EOFError, IndexError,
            KeyError, TypeError)


@dataclass(frozen=True)
class TopicInfo:
    """A topic of a recording: its type, message count and serialization format."""

    name: str
    type_name: str
    count: int
    serialization_format: str


@dataclass(frozen=True)
class RecordedMessage:
    """A decoded message with its times [ns since the epoch]."""

    topic: str
    type_name: str
    log_time: int
    publish_time: int
    message: Any


class Bag:
    """An open recording (use as a context manager, or call `close`)."""

    def __init__(self, path: Path, stream, reader: McapReader):
        self.path = path
        self._stream = stream
        self._reader = reader
        summary = reader.get_summary()
        self._summary = summary
        stats = summary.statistics
        self.message_count = stats.message_count if stats else 0
        self.start = stats.message_start_time if stats else 0   # [ns since the epoch]
        self.end = stats.message_end_time if stats else 0
        counts = stats.channel_message_counts if stats else {}
        self.topics = [TopicInfo(channel.topic, summary.schemas[channel.schema_id].name
                                 if channel.schema_id in summary.schemas else '',
                                 counts.get(channel_id, 0), channel.message_encoding)
                       for channel_id, channel in sorted(summary.channels.items())]
        self.metadata = {record.name: dict(record.metadata) for record in self._metadata()}

    def _metadata(self):
        try:
            return list(self._reader.iter_metadata())
        except _DAMAGED as error:
            raise _damaged(self.path, error) from None

    def __enter__(self) -> Bag:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        """Close the file."""
        self._stream.close()

    @property
    def ros_distro(self) -> str:
        """The ROS distribution rosbag2's metadata names ('unknown' without one)."""
        text = self.metadata.get(ROSBAG2_METADATA, {}).get('serialized_metadata', '')
        try:
            distro = (yaml.safe_load(text) or {}).get('ros_distro')
        except (yaml.YAMLError, AttributeError):
            distro = None
        return distro or 'unknown'

    def topic(self, name: str) -> TopicInfo | None:
        """Return the topic `name` of the recording, if it has one."""
        return next((topic for topic in self.topics if topic.name == name), None)

    def messages(self, topics: Iterable[str] | None = None,
                 log_time_order: bool = False) -> Iterator[RecordedMessage]:
        """Yield the decoded messages (of `topics` only, if given), in file order or by log time.

        Raises InputError naming the file when a message cannot be read or decoded.
        """
        try:
            for schema, channel, message, decoded in self._reader.iter_decoded_messages(
                    topics=None if topics is None else list(topics),
                    log_time_order=log_time_order):
                yield RecordedMessage(channel.topic, schema.name if schema else '',
                                      message.log_time, message.publish_time, decoded)
        except _DAMAGED as error:
            raise _damaged(self.path, error) from None

    def info(self) -> str:
        """Return the summary in the layout of `ros2 bag info` (rosbag2 of Jazzy)."""
        pad = ' ' * 19
        topics = [f'Topic: {t.name} | Type: {t.type_name} | Count: {t.count} | '
                  f'Serialization Format: {t.serialization_format}' for t in self.topics]
        lines = ['', f'Files:             {self.path.name}',
                 f'Bag size:          {_file_size(self.path.stat().st_size)}',
                 'Storage id:        mcap', f'ROS Distro:        {self.ros_distro}',
                 f'Duration:          {_seconds(self.end - self.start)}s',
                 f'Start:             {_moment(self.start)}',
                 f'End:               {_moment(self.end)}',
                 f'Messages:          {self.message_count}',
                 'Topic information: ' + f'\n{pad}'.join(topics),
                 'Service:           0', 'Service information: ']
        return '\n'.join(lines)


def open_bag(path: str | Path) -> Bag:
    """Open a recording and read its summary; InputError naming the file if it is not one."""
    path = Path(path)
    try:
        stream = path.open('rb')
    except OSError as error:
        raise InputError(str(path), f'cannot read it ({error.strerror})') from None
    try:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        header = reader.get_header()
        if header.profile != Profile.ROS2:
            raise InputError(str(path), f'is an MCAP file of profile {header.profile!r}, '
                             'not a ROS 2 recording (profile \'ros2\')')
        if reader.get_summary() is None:
            raise InputError(str(path), 'has no summary at its end: the recording was cut '
                             'off before it was closed')
        return Bag(path, stream, reader)
    except InputError:
        stream.close()
        raise
    except _DAMAGED as error:
        stream.close()
        raise _damaged(path, error) from None


def _damaged(path: Path, error: Exception) -> InputError:
    if isinstance(error, McapError) and 'magic' in str(error):
        return InputError(str(path), 'is not an MCAP file (it does not start and end with '
                          'MCAP\'s magic bytes)')
    return InputError(str(path), f'is not a complete MCAP recording: it is cut off or '
                      f'damaged ({type(error).__name__}{": " + str(error) if str(error) else ""})')


def _file_size(size: int) -> str:
    """Return a size as rosbag2 prints it: B, then KiB, MiB... with one decimal."""
    value, unit = float(size), 0
    units = ('B', 'KiB', 'MiB', 'GiB', 'TiB')
    while value >= 1024 and unit < len(units) - 1:
        value, unit = value / 1024, unit + 1
    return f'{value:.0f} B' if unit == 0 else f'{value:.1f} {units[unit]}'


def _seconds(nanoseconds: int) -> str:
    """Return 'S.NNNNNNNNN' (seconds with nine digits), as rosbag2 prints durations."""
    return f'{nanoseconds // 1_000_000_000}.{nanoseconds % 1_000_000_000:09d}'


def _moment(nanoseconds: int) -> str:
    """Return a moment as rosbag2 prints one: 'Oct  5 2026 14:03:07.123456789 (1791...)'."""
    local = time.localtime(nanoseconds // 1_000_000_000)
    return (f'{time.strftime("%b", local)} {local.tm_mday:2d} {local.tm_year} '
            f'{time.strftime("%H:%M:%S", local)}.{nanoseconds % 1_000_000_000:09d} '
            f'({_seconds(nanoseconds)})')
