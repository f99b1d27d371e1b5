"""Issue 33: obstacle updates applied in order, and lost ones detected (no ROS, no DDS).

UpdateStreams reads the publication sequence numbers DDS gives the updates; ObstacleSet
applies the updates and knows, until a full set comes, that some were lost.
"""

import numpy as np
import pytest
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_ros.core import load_scene
from ftplan_ros.nodes.obstacle_updates import Gap, UpdateStreams
from ftplan_ros.nodes.obstacles import ObstacleSet, is_full_set

FIG3A = load_scene('config/scenes/fig3a.yaml')


def sphere(key: int, action: int = Marker.ADD, x: float = 5.0) -> Marker:
    return Marker(header=Header(frame_id='base_link'), ns='u', id=key, type=Marker.SPHERE,
                  action=action, pose=Pose(position=Point(x=x), orientation=Quaternion(w=1.0)),
                  scale=Vector3(x=0.2, y=0.2, z=0.2))


def update(*markers: Marker) -> MarkerArray:
    return MarkerArray(markers=list(markers))


def full(*markers: Marker) -> MarkerArray:
    return update(Marker(action=Marker.DELETEALL), *markers)


def test_consecutive_numbers_of_one_publisher_lose_nothing():
    streams = UpdateStreams()
    assert [streams.receive(n) for n in range(1, 11)] == [None] * 10


@pytest.mark.parametrize('numbers, gap, text', [
    ([1, 2, 5], Gap(5, 3), 'updates 3 to 4 were not received'),
    ([1, 2, 4], Gap(4, 3), 'update 3 was not received'),
    ([57], Gap(57, None), 'update 57 arrived without update 56 before it'),  # a late joiner
])
def test_a_jump_in_the_numbers_is_a_gap_that_names_the_missing_updates(numbers, gap, text):
    streams = UpdateStreams()
    found = [streams.receive(n) for n in numbers]
    assert found[:-1] == [None] * (len(numbers) - 1) and found[-1] == gap
    assert gap.describe() == text


def test_two_publishers_interleaved_lose_nothing_and_a_gap_in_either_is_seen():
    streams = UpdateStreams()
    assert [streams.receive(n) for n in (1, 2, 1, 3, 2, 4, 3)] == [None] * 7
    assert streams.receive(9) == Gap(9)          # two streams: which one broke is unknown
    assert streams.receive(5) is None and streams.receive(10) is None


def test_a_stream_continues_after_its_gap():
    streams = UpdateStreams()
    streams.receive(1)
    assert streams.receive(7) == Gap(7, 2)
    assert streams.receive(8) is None


def test_unnumbered_updates_are_said_to_be_undetectable():
    streams = UpdateStreams()
    assert streams.receive(None) is None and streams.receive(0) is None
    assert not streams.numbered


def test_the_least_recently_heard_publishers_are_forgotten():
    streams = UpdateStreams(most=2)
    for first in (1, 1, 1):                      # three publishers start
        streams.receive(first)
    assert streams.receive(2) is None and streams.receive(2) is None
    assert streams.receive(2) == Gap(2)          # the third 2 has no stream left


def test_updates_apply_in_order_and_deletes_meet_their_adds():
    obstacles = ObstacleSet(FIG3A)
    for k in range(10):
        obstacles.update(update(sphere(k, x=5.0 + k), sphere(k - 2, Marker.DELETE)))
    assert sorted(obstacles.shapes) == [('u', 8), ('u', 9)] and not obstacles.lost


def test_a_loss_holds_until_a_full_set_is_applied():
    obstacles = ObstacleSet(FIG3A)
    obstacles.update(update(sphere(1)))
    obstacles.update(update(sphere(2)), lost='updates 2 to 4 were lost')
    assert obstacles.lost == 'updates 2 to 4 were lost' and len(obstacles) == 2
    obstacles.update(update(sphere(3)))
    assert obstacles.lost and len(obstacles) == 3
    obstacles.update(full(sphere(4)))
    assert obstacles.lost == '' and sorted(obstacles.shapes) == [('u', 4)]
    assert is_full_set(full()) and not is_full_set(update(sphere(1)))


def test_a_refused_update_still_records_the_loss_before_it():
    obstacles = ObstacleSet(FIG3A)
    bad = sphere(1)
    bad.scale.x = 0.0
    with pytest.raises(ValueError, match='scale'):
        obstacles.update(full(bad), lost='update 1 was not received')
    assert obstacles.lost.startswith('update 1 was not received; an obstacle update was '
                                     'refused (') and len(obstacles) == 0


def test_a_refused_update_leaves_the_set_incomplete_until_a_full_set():
    """Review of issue 33: the set stayed 'complete' after a refused array, so a plan was
    served for a goal that the refused array covered."""
    obstacles = ObstacleSet(FIG3A)
    obstacles.update(full(sphere(1)))
    bad = sphere(2)
    bad.scale.x = float('nan')
    with pytest.raises(ValueError, match='scale'):
        obstacles.update(update(bad))
    assert obstacles.lost.startswith('an obstacle update was refused (')
    assert sorted(obstacles.shapes) == [('u', 1)]
    obstacles.update(update(sphere(3)))
    assert obstacles.lost                        # an update is not a full set
    obstacles.update(full(sphere(4)))
    assert obstacles.lost == '' and sorted(obstacles.shapes) == [('u', 4)]


def test_the_checker_is_built_for_the_set_as_it_is_when_asked():
    obstacles = ObstacleSet(FIG3A)
    static = obstacles.checker
    assert obstacles.checker is static           # no change: no new build
    obstacles.update(full(sphere(1)))
    checker = obstacles.checker
    assert checker is not static
    assert len(checker.obstacles) == len(FIG3A.obstacles) + 1


def test_a_loss_before_the_robot_is_applied_in_order_with_the_updates():
    obstacles = ObstacleSet(None)
    obstacles.update(update(sphere(1)))
    obstacles.update(update(sphere(2)), lost='update 2 was not received')
    obstacles.update(full(sphere(3)))
    obstacles.update(update(sphere(4)), lost='update 5 was not received')
    assert obstacles.lost == ''                  # nothing applied yet
    obstacles.rebase(FIG3A)
    assert obstacles.lost == 'update 5 was not received'
    assert sorted(obstacles.shapes) == [('u', 3), ('u', 4)]


def test_updates_dropped_while_waiting_for_the_robot_are_a_loss():
    obstacles = ObstacleSet(None)
    for k in range(101):
        obstacles.update(update(sphere(k)))
    obstacles.rebase(FIG3A)
    assert obstacles.lost == ('obstacle updates were lost (more than 100 arrived before the '
                              'robot: the oldest were dropped)')
    assert len(obstacles) == 100
    assert np.isfinite(obstacles.checker.min_clearance(np.zeros((1, 3)))).all()
