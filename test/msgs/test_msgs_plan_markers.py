import math

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point
from std_msgs.msg import Header
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py.plan_markers import (
    DEFAULT_JOINT_SPACE_FRAME,
    create_plan_markers,
    read_plan_markers,
)

BASE = 'base_link'
ARM = np.array([[0.0, 0.0], [1.0, 0.0], [1.5, 0.8], [2.0, 0.0]])
# A 7-joint arm's skeleton: base, seven joint origins, tool (k, 3) [m].
ARM_3D = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.333], [0.0, 0.0, 0.333], [0.0, 0.0, 0.649],
                   [0.083, 0.0, 0.649], [0.0, 0.0, 1.033], [0.0, 0.0, 1.033],
                   [0.088, 0.0, 1.033], [0.088, 0.0, 0.926]])
EE_PATH = np.array([[2.0, 0.0, 0.0], [1.5, 0.2, 0.0], [1.0, 0.0, 0.0]])
MANIFOLD = [np.array([[0.0, 0.1, 0.2, 9.0], [0.3, 0.4, 0.5, 9.0]]),
            np.array([[1.0, 1.1, 1.2, 9.0], [1.3, 1.4, 1.5, 9.0], [1.6, 1.7, 1.8, 9.0]])]
HITS = np.array([[0.5, -0.5, 1.0], [1.0, 0.0, -1.0]])
SURFACE = np.arange(2 * 3 * 3, dtype=float).reshape(2, 3, 3) / 10.0


def full_plan():
    return create_plan_markers(
        BASE, Time(sec=5),
        arm_polylines={'arm_theta_s': ARM, 'arm_hit_1': ARM[::-1]},
        end_effector_path=EE_PATH,
        joint_space_curves={'manifold_start': MANIFOLD},
        joint_space_points={'failure_plane_hits': HITS},
        surface_paths=SURFACE,
    )


def by_ns(msg):
    result = {}
    for marker in msg.markers[1:]:
        result.setdefault(marker.ns, []).append(marker)
    return result


def test_starts_with_deleteall():
    msg = full_plan()
    assert msg.markers[0].action == Marker.DELETEALL
    assert all(m.action == Marker.ADD for m in msg.markers[1:])


def test_no_objects_gives_only_deleteall():
    msg = create_plan_markers(BASE)
    assert [m.action for m in msg.markers] == [Marker.DELETEALL]
    assert read_plan_markers(msg) == {}


def test_round_trip_of_every_object():
    read = read_plan_markers(full_plan())
    assert set(read) == {'arm_theta_s', 'arm_hit_1', 'end_effector_path', 'manifold_start',
                         'failure_plane_hits', 'failure_surface'}
    line, joints = read['arm_theta_s']          # a LINE_STRIP and a SPHERE_LIST
    assert np.allclose(line, np.column_stack([ARM, np.zeros(len(ARM))]))
    assert np.array_equal(joints, line)
    assert np.allclose(read['arm_hit_1'][0][:, :2], ARM[::-1])
    assert np.allclose(read['end_effector_path'][0], EE_PATH)
    assert len(read['manifold_start']) == 2
    for got, curve in zip(read['manifold_start'], MANIFOLD, strict=True):
        assert np.allclose(got, curve[:, :3])  # the fourth joint is dropped
    assert np.allclose(read['failure_plane_hits'][0], HITS)


def test_failure_surface_holds_path_and_rung_segments():
    (segments,) = read_plan_markers(full_plan())['failure_surface']
    K, W, _ = SURFACE.shape
    pairs = segments.reshape(-1, 2, 3)
    assert len(pairs) == K * (W - 1) + (K - 1) * W
    as_set = {tuple(np.round(pair.ravel(), 9)) for pair in pairs}
    # A segment along path 1 and the rung between paths 0 and 1 at waypoint 2.
    assert tuple(np.round(np.concatenate([SURFACE[1, 0], SURFACE[1, 1]]), 9)) in as_set
    assert tuple(np.round(np.concatenate([SURFACE[0, 2], SURFACE[1, 2]]), 9)) in as_set


def test_single_point_surface_has_no_marker():
    msg = create_plan_markers(BASE, surface_paths=np.zeros((1, 1, 3)))
    assert 'failure_surface' not in read_plan_markers(msg)


def test_a_spatial_arm_is_a_line_through_its_skeleton_and_spheres_at_its_joints():
    msg = create_plan_markers(BASE, arm_polylines={'arm_theta_s': ARM_3D},
                              end_effector_path=ARM_3D[-3:])
    line, joints = by_ns(msg)['arm_theta_s']
    assert (line.id, line.type, joints.id, joints.type) == (0, Marker.LINE_STRIP, 1,
                                                            Marker.SPHERE_LIST)
    assert joints.scale.x == joints.scale.y == joints.scale.z > 0.0
    read = read_plan_markers(msg)
    assert np.allclose(read['arm_theta_s'][0], ARM_3D)
    assert np.allclose(read['arm_theta_s'][1], ARM_3D)
    assert np.allclose(read['end_effector_path'][0], ARM_3D[-3:])


def test_frames_types_ids_and_stamps():
    groups = by_ns(full_plan())
    for ns in ('arm_theta_s', 'arm_hit_1'):
        line, joints = groups[ns]
        assert line.header.frame_id == joints.header.frame_id == BASE
        assert (line.type, joints.type) == (Marker.LINE_STRIP, Marker.SPHERE_LIST)
    (marker,) = groups['end_effector_path']
    assert marker.header.frame_id == BASE and marker.type == Marker.LINE_STRIP
    assert [m.id for m in groups['manifold_start']] == [0, 1]
    assert all(m.type == Marker.LINE_STRIP for m in groups['manifold_start'])
    assert groups['failure_plane_hits'][0].type == Marker.SPHERE_LIST
    assert groups['failure_surface'][0].type == Marker.LINE_LIST
    for ns in ('manifold_start', 'failure_plane_hits', 'failure_surface'):
        assert all(m.header.frame_id == DEFAULT_JOINT_SPACE_FRAME for m in groups[ns])
    assert all(m.header.stamp.sec == 5 for m in full_plan().markers)


def test_custom_joint_space_frame():
    msg = create_plan_markers(BASE, joint_space_frame='js', joint_space_points={'p': HITS})
    assert msg.markers[1].header.frame_id == 'js'


def test_each_namespace_has_its_own_colour_and_sensible_widths():
    groups = by_ns(full_plan())
    colours = {}
    for ns, group in groups.items():
        rgba = {(m.color.r, m.color.g, m.color.b) for m in group}
        assert len(rgba) == 1, ns
        colours[ns] = rgba.pop()
        assert all(m.color.a > 0.0 for m in group)
    assert len(set(colours.values())) == len(colours)
    for group in groups.values():
        for marker in group:
            if marker.type in (Marker.LINE_STRIP, Marker.LINE_LIST):
                assert 0.01 <= marker.scale.x <= 0.02
            else:
                assert marker.scale.x == marker.scale.y == marker.scale.z > 0.0


def test_namespace_used_twice_is_rejected():
    with pytest.raises(ValueError, match="namespace 'end_effector_path' is used twice"):
        create_plan_markers(BASE, arm_polylines={'end_effector_path': ARM},
                            end_effector_path=EE_PATH)
    with pytest.raises(ValueError, match="namespace 'm' is used twice"):
        create_plan_markers(BASE, joint_space_curves={'m': MANIFOLD},
                            joint_space_points={'m': HITS})


def test_empty_namespace_is_rejected():
    with pytest.raises(ValueError, match='namespace must be a non-empty string'):
        create_plan_markers(BASE, arm_polylines={'': ARM})


@pytest.mark.parametrize('polyline', [ARM[:1], np.zeros((3, 4)), np.zeros(3)])
def test_bad_workspace_polylines_are_rejected(polyline):
    with pytest.raises(ValueError, match=r"arm_polylines\['arm'\] has shape"):
        create_plan_markers(BASE, arm_polylines={'arm': polyline})
    with pytest.raises(ValueError, match='end_effector_path has shape'):
        create_plan_markers(BASE, end_effector_path=polyline)


def test_joint_space_objects_need_three_joints():
    with pytest.raises(ValueError, match=r"joint_space_points\['hits'\] has shape \(2, 2\)"):
        create_plan_markers(BASE, joint_space_points={'hits': np.zeros((2, 2))})
    with pytest.raises(ValueError, match=r"joint_space_curves\['m'\]\[1\] has shape"):
        create_plan_markers(BASE, joint_space_curves={'m': [np.zeros((2, 3)),
                                                            np.zeros((1, 3))]})
    with pytest.raises(ValueError, match=r'surface_paths has shape \(2, 2, 2\)'):
        create_plan_markers(BASE, surface_paths=np.zeros((2, 2, 2)))


def test_non_finite_inputs_are_rejected():
    curve = np.zeros((3, 3))
    curve[1, 0] = math.nan
    with pytest.raises(ValueError, match='non-finite'):
        create_plan_markers(BASE, joint_space_curves={'m': [curve]})
    with pytest.raises(ValueError, match='surface_paths has a non-finite value'):
        create_plan_markers(BASE, surface_paths=np.full((2, 2, 3), math.inf))


def test_empty_frames_are_rejected():
    with pytest.raises(ValueError, match='frame_id'):
        create_plan_markers('')
    with pytest.raises(ValueError, match='joint_space_frame'):
        create_plan_markers(BASE, joint_space_frame='')


def test_read_hand_built_markers_skips_non_add_actions():
    msg = MarkerArray(markers=[
        Marker(action=Marker.DELETEALL),
        Marker(header=Header(frame_id=BASE), ns='a', id=0, type=Marker.LINE_STRIP,
               points=[Point(x=1.0), Point(y=2.0)]),
        Marker(ns='a', id=1, action=Marker.DELETE),
        Marker(ns='b', id=3, type=Marker.SPHERE_LIST, points=[]),
    ])
    read = read_plan_markers(msg)
    assert list(read) == ['a', 'b']
    assert np.allclose(read['a'][0], [[1.0, 0.0, 0.0], [0.0, 2.0, 0.0]])
    assert read['b'][0].shape == (0, 3)


def test_read_rejects_non_finite_points():
    msg = MarkerArray(markers=[Marker(ns='a', id=4, points=[Point(x=math.nan)])])
    with pytest.raises(ValueError, match="marker ns='a' id=4 has a non-finite value"):
        read_plan_markers(msg)
