"""The one latched QoS profile of ftplan (like nav2's map_server map topic), and its queues.

Obstacles and plan results keep their last message for subscribers that join late:
`KEEP_LAST` depth 1, `RELIABLE`, `TRANSIENT_LOCAL`. Publishers and subscribers of those
topics must both use it, but for the queue depth, which DDS does not match: the nodes read
/ftplan/obstacles, a stream of updates, with OBSTACLE_QOS, deep enough for a burst to wait
for a busy node instead of overwriting the updates it has not read yet.
"""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

LATCHED_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    reliability=ReliabilityPolicy.RELIABLE,
)

# Obstacle updates a node may be behind by before the oldest are dropped (and the loss is
# detected: obstacle_updates.py). Memory is only used while it is behind.
OBSTACLE_QUEUE_DEPTH = 1000
OBSTACLE_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=OBSTACLE_QUEUE_DEPTH,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
    reliability=ReliabilityPolicy.RELIABLE,
)

# Events and commands: reliable, volatile, a short queue.
EVENT_QOS_DEPTH = 10

# Service requests: a node serves one at a time (a plan takes a while) and the others wait
# in this queue; rclpy's default queue of 10 dropped the rest without a word (issue 10).
SERVICE_QUEUE_DEPTH = 1000
SERVICE_QOS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=SERVICE_QUEUE_DEPTH,
    durability=DurabilityPolicy.VOLATILE,
    reliability=ReliabilityPolicy.RELIABLE,
)
