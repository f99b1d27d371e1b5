import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py.obstacles import (
    DEFAULT_OBSTACLE_COLOR,
    ObstacleShape,
    create_obstacle_markers,
    read_obstacle_markers,
)

BASE = 'base_link'


def marker(ns='obstacles', marker_id=0, marker_type=Marker.SPHERE, action=Marker.ADD,
           frame_id=BASE, center=(1.2, 0.6, 0.0), scale=(0.4, 0.4, 0.4),
           orientation=(0.0, 0.0, 0.0, 1.0)):
    return Marker(
        header=Header(frame_id=frame_id),
        ns=ns,
        id=marker_id,
        type=marker_type,
        action=action,
        pose=Pose(position=Point(x=center[0], y=center[1], z=center[2]),
                  orientation=Quaternion(x=orientation[0], y=orientation[1],
                                         z=orientation[2], w=orientation[3])),
        scale=Vector3(x=scale[0], y=scale[1], z=scale[2]),
    )


def markers(*items):
    return MarkerArray(markers=list(items))


def shape(ns='obstacles', marker_id=0, kind='sphere', center=(1.0, 0.0, 0.0),
          scale=(0.4, 0.4, 0.4), orientation=(0.0, 0.0, 0.0, 1.0)):
    return ObstacleShape((ns, marker_id), kind, np.array(center, dtype=float),
                         np.array(scale, dtype=float), np.array(orientation, dtype=float))


def test_read_sphere_box_and_cylinder():
    msg = markers(
        marker(marker_id=0, marker_type=Marker.SPHERE),
        marker(marker_id=1, marker_type=Marker.CUBE, center=(0.0, -1.0, 0.5),
               scale=(0.2, 0.3, 0.4)),
        marker(ns='posts', marker_id=0, marker_type=Marker.CYLINDER, scale=(0.1, 0.1, 2.0),
               orientation=(0.0, 0.0, 0.0, 2.0)),
    )
    obstacles = read_obstacle_markers(msg, BASE)
    assert set(obstacles) == {('obstacles', 0), ('obstacles', 1), ('posts', 0)}
    sphere, box, cylinder = (obstacles[k] for k in (('obstacles', 0), ('obstacles', 1),
                                                    ('posts', 0)))
    assert sphere.shape == 'sphere' and sphere.key == ('obstacles', 0)
    assert np.allclose(sphere.center, [1.2, 0.6, 0.0])
    assert np.allclose(sphere.scale, [0.4, 0.4, 0.4])
    assert box.shape == 'box'
    assert np.allclose(box.center, [0.0, -1.0, 0.5])
    assert np.allclose(box.scale, [0.2, 0.3, 0.4])
    assert cylinder.shape == 'cylinder'
    assert np.allclose(cylinder.scale, [0.1, 0.1, 2.0])
    assert np.allclose(cylinder.orientation, [0.0, 0.0, 0.0, 1.0])  # normalised from w=2


def test_read_returns_read_only_arrays():
    obstacle = read_obstacle_markers(markers(marker()), BASE)[('obstacles', 0)]
    with pytest.raises(ValueError, match='read-only'):
        obstacle.center[0] = 5.0


def test_add_replaces_the_same_key_and_modify_is_add():
    msg = markers(marker(center=(1.0, 0.0, 0.0)),
                  marker(action=Marker.MODIFY, center=(2.0, 0.0, 0.0)))
    obstacles = read_obstacle_markers(msg, BASE)
    assert list(obstacles) == [('obstacles', 0)]
    assert np.allclose(obstacles[('obstacles', 0)].center, [2.0, 0.0, 0.0])


def test_same_id_in_different_namespaces_are_different_obstacles():
    obstacles = read_obstacle_markers(markers(marker(ns='a'), marker(ns='b')), BASE)
    assert set(obstacles) == {('a', 0), ('b', 0)}


def test_delete_removes_one_key_and_tolerates_missing_ones():
    current = read_obstacle_markers(markers(marker(marker_id=0), marker(marker_id=1)), BASE)
    # A DELETE marker is not checked for type or frame: it only names a key.
    msg = markers(marker(marker_id=0, action=Marker.DELETE, marker_type=Marker.ARROW,
                         frame_id='elsewhere'),
                  marker(marker_id=7, action=Marker.DELETE))
    obstacles = read_obstacle_markers(msg, BASE, current)
    assert list(obstacles) == [('obstacles', 1)]


def test_deleteall_clears_current_and_earlier_markers_but_not_later_ones():
    current = read_obstacle_markers(markers(marker(ns='old')), BASE)
    msg = markers(marker(ns='early'), marker(action=Marker.DELETEALL), marker(ns='late'))
    assert list(read_obstacle_markers(msg, BASE, current)) == [('late', 0)]


def test_deleteall_last_leaves_nothing():
    msg = markers(marker(marker_id=0), marker(marker_id=1), marker(action=Marker.DELETEALL))
    assert read_obstacle_markers(msg, BASE) == {}


def test_add_after_delete_restores_the_key():
    msg = markers(marker(), marker(action=Marker.DELETE), marker(center=(3.0, 0.0, 0.0)))
    obstacles = read_obstacle_markers(msg, BASE)
    assert np.allclose(obstacles[('obstacles', 0)].center, [3.0, 0.0, 0.0])


def test_current_is_never_mutated():
    current = read_obstacle_markers(markers(marker(ns='old')), BASE)
    snapshot = dict(current)
    updated = read_obstacle_markers(markers(marker(ns='new')), BASE, current)
    assert set(updated) == {('old', 0), ('new', 0)}
    assert current == snapshot


def test_an_error_applies_nothing():
    current = read_obstacle_markers(markers(marker(ns='old')), BASE)
    snapshot = dict(current)
    msg = markers(marker(action=Marker.DELETEALL), marker(ns='new'),
                  marker(ns='bad', scale=(0.0, 0.4, 0.4)))
    with pytest.raises(ValueError, match='scale'):
        read_obstacle_markers(msg, BASE, current)
    assert current == snapshot


def test_wrong_frame_names_both_frames():
    with pytest.raises(ValueError, match="ns='obstacles' id=0 is in frame 'map'.*'base_link'"):
        read_obstacle_markers(markers(marker(frame_id='map')), BASE)


def test_unsupported_marker_type_is_named():
    with pytest.raises(ValueError, match="ns='walls' id=3 has type ARROW"):
        read_obstacle_markers(markers(marker(ns='walls', marker_id=3,
                                             marker_type=Marker.ARROW)), BASE)
    with pytest.raises(ValueError, match='has type 99'):
        read_obstacle_markers(markers(marker(marker_type=99)), BASE)


def test_unknown_action_is_rejected():
    with pytest.raises(ValueError, match='unknown action 7'):
        read_obstacle_markers(markers(marker(action=7)), BASE)


@pytest.mark.parametrize('scale', [(0.0, 0.4, 0.4), (0.4, -0.1, 0.4)])
def test_non_positive_scale_is_rejected(scale):
    with pytest.raises(ValueError, match=r'scale .* must be > 0'):
        read_obstacle_markers(markers(marker(scale=scale)), BASE)


@pytest.mark.parametrize('field', ['center', 'scale', 'orientation'])
def test_non_finite_pose_or_scale_is_rejected(field):
    values = {'center': (1.0, math.nan, 0.0), 'scale': (0.4, 0.4, math.inf),
              'orientation': (0.0, 0.0, math.nan, 1.0)}
    with pytest.raises(ValueError, match=f'{field} has a non-finite value'):
        read_obstacle_markers(markers(marker(**{field: values[field]})), BASE)


def test_zero_quaternion_is_rejected():
    with pytest.raises(ValueError, match='zero orientation quaternion'):
        read_obstacle_markers(markers(marker(orientation=(0.0, 0.0, 0.0, 0.0))), BASE)


def test_empty_frame_id_argument_is_rejected():
    with pytest.raises(ValueError, match='frame_id must be a non-empty frame name'):
        read_obstacle_markers(markers(), '')


def test_create_round_trip():
    half_turn_z = (0.0, 0.0, 1.0, 0.0)
    obstacles = [
        shape(marker_id=0, kind='sphere', center=(1.2, 0.6, 0.0)),
        shape(marker_id=1, kind='box', scale=(0.1, 0.2, 0.3), orientation=half_turn_z),
        shape(ns='posts', marker_id=4, kind='cylinder', scale=(0.2, 0.2, 1.0)),
    ]
    msg = create_obstacle_markers(obstacles, BASE, stamp=Time(sec=3))
    read = read_obstacle_markers(msg, BASE)
    assert list(read) == [o.key for o in obstacles]
    for original in obstacles:
        got = read[original.key]
        assert got.shape == original.shape
        assert np.allclose(got.center, original.center)
        assert np.allclose(got.scale, original.scale)
        assert np.allclose(got.orientation, original.orientation)


def test_create_layout_of_markers():
    msg = create_obstacle_markers([shape(ns='obs', marker_id=5, kind='box')], BASE,
                                  stamp=Time(sec=3, nanosec=4))
    clear, box = msg.markers
    assert clear.action == Marker.DELETEALL
    assert clear.header.frame_id == BASE
    assert (box.ns, box.id, box.type, box.action) == ('obs', 5, Marker.CUBE, Marker.ADD)
    assert box.header.frame_id == BASE
    assert (box.header.stamp.sec, box.header.stamp.nanosec) == (3, 4)
    assert np.allclose([box.color.r, box.color.g, box.color.b, box.color.a],
                       DEFAULT_OBSTACLE_COLOR)


def test_create_without_clear_first_only_adds_and_keeps_existing_obstacles():
    current = read_obstacle_markers(markers(marker(ns='old')), BASE)
    msg = create_obstacle_markers([shape(ns='new')], BASE, clear_first=False,
                                  color=(0.0, 1.0, 0.0, 1.0))
    assert [m.action for m in msg.markers] == [Marker.ADD]
    assert msg.markers[0].color.g == 1.0
    assert set(read_obstacle_markers(msg, BASE, current)) == {('old', 0), ('new', 0)}


def test_create_with_clear_first_replaces_existing_obstacles():
    current = read_obstacle_markers(markers(marker(ns='old')), BASE)
    msg = create_obstacle_markers([shape(ns='new')], BASE)
    assert set(read_obstacle_markers(msg, BASE, current)) == {('new', 0)}


def test_create_normalises_orientation():
    msg = create_obstacle_markers([shape(orientation=(0.0, 0.0, 0.0, 3.0))], BASE)
    assert msg.markers[1].pose.orientation.w == pytest.approx(1.0)


def test_created_markers_do_not_share_headers():
    msg = create_obstacle_markers([shape(marker_id=0), shape(marker_id=1)], BASE)
    msg.markers[1].header.frame_id = 'changed'
    assert msg.markers[0].header.frame_id == BASE
    assert msg.markers[2].header.frame_id == BASE


def test_create_rejects_duplicate_keys():
    with pytest.raises(ValueError, match="ns='obstacles' id=0 appears twice"):
        create_obstacle_markers([shape(), shape()], BASE)


def test_create_rejects_unknown_shape():
    with pytest.raises(ValueError, match="has shape 'cone'"):
        create_obstacle_markers([shape(kind='cone')], BASE)


@pytest.mark.parametrize('key', [('obs',), ('obs', 'one'), (3, 0), ['obs', 0], ('obs', 2**31)])
def test_create_rejects_bad_keys(key):
    bad = shape()._replace(key=key)
    with pytest.raises(ValueError, match='obstacle key'):
        create_obstacle_markers([bad], BASE)


@pytest.mark.parametrize('color', [(1.0, 0.0, 0.0), (1.5, 0.0, 0.0, 1.0), (0, 0, -0.1, 1)])
def test_create_rejects_bad_color(color):
    with pytest.raises(ValueError, match=r'color must be \(r, g, b, a\)'):
        create_obstacle_markers([shape()], BASE, color=color)


def test_create_rejects_wrongly_shaped_fields():
    with pytest.raises(ValueError, match=r'center has shape \(2,\)'):
        create_obstacle_markers([shape(center=(1.0, 0.0))], BASE)
    with pytest.raises(ValueError, match=r'orientation has shape \(3,\)'):
        create_obstacle_markers([shape(orientation=(0.0, 0.0, 1.0))], BASE)


def test_create_rejects_zero_quaternion_and_bad_scale():
    with pytest.raises(ValueError, match='zero orientation quaternion'):
        create_obstacle_markers([shape(orientation=(0.0, 0.0, 0.0, 0.0))], BASE)
    with pytest.raises(ValueError, match='must be > 0'):
        create_obstacle_markers([shape(scale=(0.1, 0.0, 0.1))], BASE)


def test_create_rejects_empty_frame():
    with pytest.raises(ValueError, match='frame_id'):
        create_obstacle_markers([shape()], '')
