"""The recorder node: every topic of the ROS graph into a rosbag2-compatible MCAP file.

    ftplan-bringup --scene config/scenes/fig3a.yaml --drill joint2@0.4 --record out/run.mcap

Like `ros2 bag record --all`: it looks at the graph every `DISCOVERY_PERIOD` (and when
asked, `subscribe_to_graph`) and subscribes to each topic that has a publisher and a
message type it can import, with the QoS its publishers offer, by rosbag2's rule:
reliable when all of them are, transient-local when all of them are (so the latched plan
topics are recorded even when they were published before it joined), volatile and best
effort otherwise. It takes the messages as CDR bytes (`raw`), never deserialised, and
writes them (recording/bag_writer.py) with the moment it took them as log time and the
publisher's source timestamp as publish time, as rosbag2 does. Each channel records the
QoS profiles its publishers offered and the type's hash.

A topic of a type this Python environment cannot import, or of more than one type, is
left out with a warning, once. Writing stops at the first error of the file system (a
full disk), with an error in the log; the messages lost after it are counted.
"""

from __future__ import annotations

import importlib
import threading

from rclpy.context import Context
from rclpy.node import Node
from rclpy.qos import (
    DurabilityPolicy,
    HistoryPolicy,
    LivelinessPolicy,
    QoSProfile,
    ReliabilityPolicy,
)

from ..recording.bag_writer import BagWriter
from ..recording.definitions import DefinitionError
from .spinning import BackgroundSpin
from .topics import RECORDER_NODE

DISCOVERY_PERIOD = 0.1  # [s] between looks at the graph for new topics (rosbag2's default)
# Messages a subscription may hold before the recorder takes them: a busy process must
# not make it drop the 100 Hz joint states.
QUEUE_DEPTH = 1000


def offered_qos(profile: QoSProfile) -> dict:
    """Return a publisher's QoS as rosbag2 stores it (policies by name, durations in sec, nsec)."""
    def duration(value) -> dict:
        nanoseconds = value.nanoseconds
        return {'sec': nanoseconds // 1_000_000_000, 'nsec': nanoseconds % 1_000_000_000}

    return {'history': HistoryPolicy(profile.history).name.lower(), 'depth': profile.depth,
            'reliability': ReliabilityPolicy(profile.reliability).name.lower(),
            'durability': DurabilityPolicy(profile.durability).name.lower(),
            'deadline': duration(profile.deadline), 'lifespan': duration(profile.lifespan),
            'liveliness': LivelinessPolicy(profile.liveliness).name.lower(),
            'liveliness_lease_duration': duration(profile.liveliness_lease_duration),
            'avoid_ros_namespace_conventions': bool(profile.avoid_ros_namespace_conventions)}


def subscription_qos(offers: list[QoSProfile]) -> QoSProfile:
    """Return the QoS that receives from every publisher, the latched messages too if it can."""
    reliable = all(p.reliability == ReliabilityPolicy.RELIABLE for p in offers)
    latched = all(p.durability == DurabilityPolicy.TRANSIENT_LOCAL for p in offers)
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST, depth=QUEUE_DEPTH,
        reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
        durability=DurabilityPolicy.TRANSIENT_LOCAL if latched else DurabilityPolicy.VOLATILE)


def message_class(type_name: str):
    """Return the Python class of a message type like 'sensor_msgs/msg/JointState', or None."""
    package, _, name = type_name.rpartition('/')
    try:
        return getattr(importlib.import_module(package.replace('/', '.')), name)
    except (ImportError, AttributeError, ValueError):
        return None


class RecorderNode(Node):
    """Subscribe to every topic of the graph and write what arrives to `writer`."""

    def __init__(self, writer: BagWriter, *, context: Context | None = None):
        super().__init__(RECORDER_NODE, context=context)
        self.writer = writer
        self.lost = 0            # messages not written after a file system error
        self._failed = False
        self._skipped: set[str] = set()
        self._recorded: dict[str, object] = {}
        self._graph_lock = threading.Lock()
        self.subscribe_to_graph()
        self.discovery_timer = self.create_timer(DISCOVERY_PERIOD, self.subscribe_to_graph)

    def subscribe_to_graph(self) -> list[str]:
        """Subscribe to the topics of the graph not recorded yet; return their names."""
        added = []
        with self._graph_lock:
            for topic, types in self.get_topic_names_and_types():
                if topic in self._recorded or topic in self._skipped:
                    continue
                publishers = self.get_publishers_info_by_topic(topic)
                if publishers and self._subscribe(topic, types, publishers):
                    added.append(topic)
        return added

    def _subscribe(self, topic: str, types: list[str], publishers) -> bool:
        message_type = message_class(types[0]) if len(types) == 1 else None
        if message_type is None:
            self._skip(topic, f'of type {" and ".join(types)}, which this Python environment '
                       'does not have' if len(types) == 1 else f'of {len(types)} types')
            return False
        offers = [info.qos_profile for info in publishers]
        try:
            self.writer.add_topic(topic, types[0], [offered_qos(p) for p in offers],
                                  str(publishers[0].topic_type_hash))
        except DefinitionError as error:
            self._skip(topic, str(error))
            return False
        self._recorded[topic] = self.create_subscription(
            message_type, topic, lambda data, info: self._record(topic, data, info),
            subscription_qos(offers), raw=True)
        return True

    def _skip(self, topic: str, why: str) -> None:
        self._skipped.add(topic)
        self.get_logger().warning(f'not recording {topic}: {why}')

    def _record(self, topic: str, data: bytes, info: dict) -> None:
        if self._failed:
            self.lost += 1
            return
        try:
            self.writer.write(topic, data, info.get('source_timestamp') or 0)
        except OSError as error:
            self._failed = True
            self.lost += 1
            self.get_logger().error(f'cannot write {self.writer.path}: {error}; the messages '
                                    'from now on are lost')


class Recording:
    """A recorder node spinning in its own thread, and the file it writes."""

    def __init__(self, writer: BagWriter, context: Context | None = None):
        self.writer = writer
        self.node = RecorderNode(writer, context=context)
        self._spin = BackgroundSpin([self.node], context=context, name='ftplan-recorder')

    def stop(self) -> dict[str, int]:
        """Stop recording, close the file; return the messages written per topic."""
        self._spin.stop()
        self.writer.close()
        return self.writer.counts()
