"""How long the planner is deaf while it builds a big robot from /robot_description.

    .venv/bin/python benchmarks/description_latency.py [--links 960] [--tags 6000] [--rounds 3]

A planner (in this process, as the tests run it) has the Panda from /robot_description.
Then the Panda with `--links` more links and `--tags` Gazebo tags arrives (960 and 6000:
1.1 MB, about as slow to build as the bounds allow), while joint states go out at
100 Hz, alternately good and bad, so that the planner answers each on /diagnostics. Per
round: the build time (the URDF sent until the robot's OK status) and the longest gap
between the planner's answers while it built (their stamps): how long it was deaf. Each
round starts again from the plain Panda.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / 'test'))  # the big URDF
sys.path.insert(0, str(REPO / 'test' / 'ros'))  # the tests' harness and domain claim

from descriptions import PANDA_URDF, heavy_panda  # noqa: E402
from ros_support import RosHarness, wait_for  # noqa: E402  (claims a ROS_DOMAIN_ID first)
from sensor_msgs.msg import JointState  # noqa: E402
from spatial_scenes import BASE_LINK, JOINTS, Q_S, TIP_LINK, panda_scene  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from ftplan_msgs_py import create_joint_state, time_to_seconds  # noqa: E402
from ftplan_ros.nodes.planner import PlannerNode  # noqa: E402
from ftplan_ros.nodes.qos import LATCHED_QOS  # noqa: E402

STATUS = 'ftplan_planner: robot_description'
JOINT_STATUS = 'ftplan_planner: joint_states'
RATE = 100.0  # [Hz] joint states


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--links', type=int, default=960)
    parser.add_argument('--tags', type=int, default=6000)
    parser.add_argument('--rounds', type=int, default=3)
    args = parser.parse_args()
    big = heavy_panda(args.links, gazebo_tags=args.tags)
    print(f'the big URDF: {len(big.encode())} bytes, {13 + args.links} links')
    ros = RosHarness()
    try:
        with_planner(ros, big, args.rounds)
    finally:
        ros.close()
    return 0


def with_planner(ros: RosHarness, big: str, rounds: int) -> None:
    scene = panda_scene(Path(tempfile.mkdtemp(prefix='ftplan-latency-')), robot=False)
    ros.make(PlannerNode, scene, base_link=BASE_LINK, tip_link=TIP_LINK)
    ros.probe.advertise(JointState, '/joint_states')
    for _ in range(rounds):
        publish_description(ros, PANDA_URDF.read_text())
        build, deaf, answers = one_round(ros, big)
        print(f'build {build:.2f} s, longest deaf {deaf:.3f} s, {answers} joint states '
              'answered during the build')


def publish_description(ros: RosHarness, text: str) -> float:
    """Publish a URDF; return the stamp [s] of the robot's OK status once it is there."""
    before = len(ros.probe.statuses(STATUS))
    sent = time.time()
    ros.probe.publish(String, '/robot_description', String(data=text), LATCHED_QOS)
    wait_for(lambda: ros.probe.statuses(STATUS)[before:], 300.0, 'the robot')
    assert ros.probe.statuses(STATUS)[-1].level == 'OK', ros.probe.statuses(STATUS)[-1]
    return sent


def one_round(ros: RosHarness, big: str) -> tuple[float, float, int]:
    """Send the big URDF with joint states going; return build [s], deaf [s], answers."""
    stop = threading.Event()
    threading.Thread(target=joint_states, args=(ros, stop), daemon=True).start()
    time.sleep(0.5)
    start = len(ros.probe.received('/diagnostics'))
    sent = publish_description(ros, big)
    stop.set()
    stamps, built = [sent], None
    for array in ros.probe.received('/diagnostics')[start:]:
        names = [status.name for status in array.status]
        if STATUS in names:
            built = time_to_seconds(array.header.stamp)
            break
        if JOINT_STATUS in names and time_to_seconds(array.header.stamp) > sent:
            stamps.append(time_to_seconds(array.header.stamp))
    stamps.append(built)
    gaps = [b - a for a, b in zip(stamps, stamps[1:], strict=False)]
    return built - sent, max(gaps), len(stamps) - 2


def joint_states(ros: RosHarness, stop: threading.Event) -> None:
    good = create_joint_state(JOINTS, Q_S)
    bad = JointState(name=JOINTS, position=[math.nan] * len(JOINTS))
    publisher = ros.probe.publishers_['/joint_states']
    sent = 0
    while not stop.is_set():
        publisher.publish(bad if sent % 2 else good)
        sent += 1
        time.sleep(1.0 / RATE)


if __name__ == '__main__':
    sys.exit(main())
