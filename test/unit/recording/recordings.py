"""Small recordings for the tests of recording/: std_msgs/String messages, a clock in hand."""

import struct

from ftplan_ros.recording.bag_writer import BagWriter

STRING = 'std_msgs/msg/String'
LATCHED = {'history': 'keep_last', 'depth': 1, 'reliability': 'reliable',
           'durability': 'transient_local', 'deadline': {'sec': 0, 'nsec': 0},
           'lifespan': {'sec': 0, 'nsec': 0}, 'liveliness': 'automatic',
           'liveliness_lease_duration': {'sec': 0, 'nsec': 0},
           'avoid_ros_namespace_conventions': False}
EPOCH = 1_700_000_000_000_000_000  # [ns] the tests' clock starts here


def cdr_string(text: str) -> bytes:
    """Return a std_msgs/String as CDR bytes (little endian), as rclpy serialises it."""
    data = text.encode() + b'\0'
    return b'\x00\x01\x00\x00' + struct.pack('<I', len(data)) + data


class Clock:
    """A clock [ns] the test sets: `clock.now = ...`."""

    def __init__(self, now: int = EPOCH):
        self.now = now

    def __call__(self) -> int:
        return self.now


def write_recording(path, messages, clock=None, metadata=None) -> BagWriter:
    """Write (topic, text, log time [ns]) String messages to `path`; return the closed writer."""
    clock = clock or Clock()
    writer = BagWriter(path, metadata, clock=clock)
    for topic, text, log_time in messages:
        writer.add_topic(topic, STRING, [LATCHED], 'RIHS01_00')
        clock.now = log_time
        writer.write(topic, cdr_string(text), log_time - 5)
    writer.close()
    return writer
