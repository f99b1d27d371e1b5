"""Properties of every ftplan_msgs_py reader and creator, checked by hypothesis (issue 10).

Round trips give back what went in; any malformed input, message or Python value, raises
ValueError naming what is wrong, and nothing else. Examples are drawn deterministically
(no example database), so a failure repeats.
"""

import math

import numpy as np
import pytest
from builtin_interfaces.msg import Duration, Time
from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, Pose, PoseStamped, Quaternion, Vector3
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from nav_msgs.msg import Path
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, Header, MultiArrayDimension, MultiArrayLayout
from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py import (
    DIAGNOSTIC_LEVELS,
    FAILURE_SURFACE_LABELS,
    ObstacleShape,
    create_diagnostic_array,
    create_diagnostic_status,
    create_failure_surface,
    create_joint_state,
    create_joint_trajectory,
    create_locked_joint,
    create_obstacle_markers,
    create_path,
    create_plan_markers,
    create_pose,
    duration_to_seconds,
    read_diagnostic_status,
    read_failure_surface,
    read_joint_state,
    read_joint_trajectory,
    read_locked_joint,
    read_obstacle_markers,
    read_path,
    read_path_poses,
    read_plan_markers,
    read_point,
    read_pose,
    read_quaternion,
    seconds_to_duration,
    seconds_to_time,
    time_to_nanoseconds,
    time_to_seconds,
    unit_quaternions,
)

# Norms of vectors near the largest float overflow to inf (and are then refused).
pytestmark = pytest.mark.filterwarnings('ignore:overflow encountered:RuntimeWarning')
PROPERTY = settings(max_examples=60, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.too_slow])

INT32 = st.integers(-2**31, 2**31 - 1)
UINT32 = st.integers(0, 2**32 - 1)
FINITE = st.floats(-1e6, 1e6, allow_nan=False)
ANY_FLOAT = st.floats()                         # NaN and ±inf too
TEXT = st.text(st.characters(codec='ascii', exclude_categories=['Cc']), max_size=6)
NAME = TEXT.filter(bool)
NAMES = st.lists(NAME, min_size=1, max_size=6, unique=True)
# Whatever a caller might pass where an array, a number or a string is expected.
JUNK = st.recursive(
    st.one_of(st.none(), st.booleans(), st.integers(-10**20, 10**20), ANY_FLOAT, TEXT,
              st.binary(max_size=3), st.complex_numbers(max_magnitude=10.0)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.tuples(inner, inner),
                            st.dictionaries(TEXT, inner, max_size=2)),
    max_leaves=8)
SHAPES = ('sphere', 'box', 'cylinder')


def only_value_error(call, *fields):
    """Call; a ValueError is fine (mentioning one of `fields`, if given), nothing else is."""
    try:
        return call()
    except ValueError as error:
        assert not fields or any(f in str(error) for f in fields), str(error)
        return None


def time_msgs():
    return st.builds(Time, sec=INT32, nanosec=UINT32)


def unit_quaternion():
    return arrays(np.float64, 4, elements=st.floats(-1.0, 1.0)).filter(
        lambda q: np.linalg.norm(q) > 0.1).map(lambda q: q / np.linalg.norm(q))


# Joint states ---------------------------------------------------------------------------

@PROPERTY
@given(NAMES, st.data())
def test_joint_states_read_back_by_name_in_any_order_with_extra_joints(names, data):
    q = data.draw(arrays(np.float64, len(names), elements=FINITE))
    stamp = data.draw(st.builds(Time, sec=st.integers(0, 2**31 - 1),
                                nanosec=st.integers(0, 10**9 - 1)))
    msg = create_joint_state(names, q, stamp=stamp)
    assert np.array_equal(read_joint_state(msg, names), q)
    order = data.draw(st.permutations(range(len(names))))
    extra = data.draw(st.lists(NAME.filter(lambda n: n not in names), max_size=2, unique=True))
    shuffled = JointState(name=[names[i] for i in order] + extra,
                          position=[float(q[i]) for i in order] + [math.nan] * len(extra))
    assert np.array_equal(read_joint_state(shuffled, names), q)
    assert time_to_nanoseconds(msg.header.stamp) == stamp.sec * 10**9 + stamp.nanosec


@PROPERTY
@given(st.lists(TEXT, max_size=5), st.lists(ANY_FLOAT, max_size=5),
       st.one_of(NAMES, JUNK))
def test_any_joint_state_is_read_or_refused_with_a_value_error(names, positions, wanted):
    msg = JointState(name=names, position=positions)
    q = only_value_error(lambda: read_joint_state(msg, wanted))
    if q is not None:
        assert q.shape == (len(wanted),) and np.all(np.isfinite(q))


@PROPERTY
@given(JUNK, JUNK, JUNK, JUNK, JUNK)
def test_create_joint_state_refuses_junk_with_a_value_error(names, positions, velocities, frame,
                                                            stamp):
    only_value_error(lambda: create_joint_state(names, positions, velocities, frame_id=frame))
    only_value_error(lambda: create_joint_state(names, [0.0]))
    only_value_error(lambda: create_joint_state(['a'], positions), 'positions')
    only_value_error(lambda: create_joint_state(['a'], [0.0], velocities), 'velocities')
    only_value_error(lambda: create_joint_state(['a'], [0.0], frame_id=frame), 'frame_id')
    only_value_error(lambda: create_joint_state(['a'], [0.0], stamp=stamp), 'stamp')


# Joint trajectories ---------------------------------------------------------------------

@PROPERTY
@given(NAMES, st.integers(0, 5), st.data())
def test_joint_trajectories_read_back(names, k, data):
    positions = data.draw(arrays(np.float64, (k, len(names)), elements=FINITE))
    steps = data.draw(arrays(np.float64, k, elements=st.floats(0.0, 100.0)))
    times = np.cumsum(steps)
    msg = create_joint_trajectory(names, positions, times, data.draw(time_msgs().filter(
        lambda t: t.sec >= 0 and t.nanosec < 10**9)))
    back = read_joint_trajectory(msg, list(reversed(names)))
    assert np.array_equal(back.positions, positions[:, ::-1])
    assert np.allclose(back.times, times, rtol=0.0, atol=1e-6)


@PROPERTY
@given(st.lists(TEXT, max_size=4),
       st.lists(st.tuples(st.lists(ANY_FLOAT, max_size=4), INT32, UINT32), max_size=4),
       st.one_of(NAMES, JUNK))
def test_any_joint_trajectory_is_read_or_refused_with_a_value_error(names, points, wanted):
    msg = JointTrajectory(joint_names=names, points=[
        JointTrajectoryPoint(positions=p, time_from_start=Duration(sec=s, nanosec=ns))
        for p, s, ns in points])
    only_value_error(lambda: read_joint_trajectory(msg, wanted))


@PROPERTY
@given(JUNK, JUNK, JUNK, JUNK)
def test_create_joint_trajectory_refuses_junk_with_a_value_error(names, positions, times, stamp):
    only_value_error(lambda: create_joint_trajectory(names, positions, times, stamp))
    only_value_error(lambda: create_joint_trajectory(names, [[0.0]], [0.0]))
    only_value_error(lambda: create_joint_trajectory(['a'], positions, [0.0]), 'positions',
                     'times_from_start')
    only_value_error(lambda: create_joint_trajectory(['a'], [[0.0]], times), 'times')
    only_value_error(lambda: create_joint_trajectory(['a'], [[0.0]], [0.0], stamp), 'stamp')


# Locked joints ---------------------------------------------------------------------------

@PROPERTY
@given(NAME, st.one_of(st.none(), FINITE))
def test_locked_joint_events_read_back(name, angle):
    assert read_locked_joint(create_locked_joint(name, angle)) == (name, angle)


@PROPERTY
@given(st.lists(TEXT, max_size=3), st.lists(ANY_FLOAT, max_size=3), JUNK, JUNK)
def test_any_locked_joint_event_is_read_or_refused_with_a_value_error(names, positions,
                                                                      name, angle):
    event = only_value_error(lambda: read_locked_joint(JointState(name=names,
                                                                  position=positions)))
    if event is not None:
        assert event.angle is None or math.isfinite(event.angle)
    only_value_error(lambda: create_locked_joint(name, angle))


# Obstacles ---------------------------------------------------------------------------

def obstacle_shapes():
    return st.lists(st.builds(
        lambda ns, key, shape, centre, scale, q: ObstacleShape((ns, key), shape, centre, scale, q),
        TEXT, INT32, st.sampled_from(SHAPES), arrays(np.float64, 3, elements=FINITE),
        arrays(np.float64, 3, elements=st.floats(1e-3, 1e3)), unit_quaternion()),
        max_size=5, unique_by=lambda o: o.key)


@PROPERTY
@given(obstacle_shapes(), NAME)
def test_obstacle_markers_read_back(shapes, frame_id):
    back = read_obstacle_markers(create_obstacle_markers(shapes, frame_id), frame_id)
    assert sorted(back) == sorted(o.key for o in shapes)
    for shape in shapes:
        got = back[shape.key]
        assert got.shape == shape.shape
        assert np.array_equal(got.center, shape.center) and np.array_equal(got.scale, shape.scale)
        assert np.allclose(got.orientation, shape.orientation, atol=1e-12)


def markers():
    return st.lists(st.builds(
        lambda frame, ns, key, kind, action, position, q, scale: Marker(
            header=Header(frame_id=frame), ns=ns, id=key, type=kind, action=action,
            pose=Pose(position=Point(x=position[0], y=position[1], z=position[2]),
                      orientation=Quaternion(x=q[0], y=q[1], z=q[2], w=q[3])),
            scale=Vector3(x=scale[0], y=scale[1], z=scale[2])),
        st.sampled_from(['base_link', 'map', '']), TEXT, st.integers(-3, 3),
        st.one_of(st.sampled_from([Marker.SPHERE, Marker.CUBE, Marker.CYLINDER]), INT32),
        st.one_of(st.sampled_from([Marker.ADD, Marker.DELETE, Marker.DELETEALL]), INT32),
        st.tuples(ANY_FLOAT, ANY_FLOAT, ANY_FLOAT), st.tuples(*[ANY_FLOAT] * 4),
        st.tuples(ANY_FLOAT, ANY_FLOAT, ANY_FLOAT)), max_size=4)


@PROPERTY
@given(markers(), obstacle_shapes())
def test_any_marker_array_is_read_or_refused_with_a_value_error_leaving_the_set(markers,
                                                                              current):
    known = {shape.key: shape for shape in current}
    before = dict(known)
    shapes = only_value_error(lambda: read_obstacle_markers(MarkerArray(markers=markers),
                                                            'base_link', known),
                              'obstacle marker')
    assert known == before                                     # all or nothing
    for shape in (shapes or {}).values():
        assert np.all(np.isfinite(shape.center)) and np.all(shape.scale > 0)
        assert np.linalg.norm(shape.orientation) == pytest.approx(1.0)


def marker_actions():
    """ADD, DELETE and DELETEALL markers of a few keys (so that keys repeat), valid shapes."""
    return st.lists(st.tuples(
        st.sampled_from([Marker.ADD, Marker.ADD, Marker.DELETE, Marker.DELETEALL]),
        st.sampled_from(['a', 'b']), st.integers(0, 2), obstacle_shapes().filter(bool)),
        max_size=8)


@PROPERTY
@given(marker_actions(), obstacle_shapes())
def test_marker_actions_apply_in_order_as_rviz_applies_them(actions, current):
    """The set after the array is the set after each marker in turn, on a copy."""
    known = {shape.key: shape for shape in current}
    expected = dict(known)
    markers = []
    for action, ns, key, (shape, *_) in actions:
        placed = shape._replace(key=(ns, key))
        if action == Marker.ADD:
            expected[placed.key] = placed
        elif action == Marker.DELETE:
            expected.pop(placed.key, None)
        else:
            expected.clear()
        marker = create_obstacle_markers([placed], 'base_link', clear_first=False).markers[0]
        marker.action = action
        markers.append(marker)
    before = dict(known)
    result = read_obstacle_markers(MarkerArray(markers=markers), 'base_link', known)
    assert known == before
    assert sorted(result) == sorted(expected)
    for key, shape in expected.items():
        assert result[key].shape == shape.shape
        assert np.array_equal(result[key].center, shape.center)
        assert np.allclose(result[key].orientation, shape.orientation, atol=1e-12)


@PROPERTY
@given(st.lists(st.one_of(JUNK, obstacle_shapes().map(lambda s: s[0] if s else None)),
                max_size=3), JUNK, JUNK)
def test_create_obstacle_markers_refuses_junk_with_a_value_error(obstacles, frame_id, color):
    only_value_error(lambda: create_obstacle_markers(obstacles, frame_id, color=color))
    only_value_error(lambda: create_obstacle_markers(obstacles, 'base_link'), 'obstacle')
    only_value_error(lambda: create_obstacle_markers([], frame_id), 'frame_id')
    only_value_error(lambda: create_obstacle_markers([], 'base_link', color=color), 'color')
    junk_shape = ObstacleShape(('ns', 0), frame_id, color, obstacles, frame_id)
    only_value_error(lambda: create_obstacle_markers([junk_shape], 'base_link'), 'obstacle')


# Failure surfaces --------------------------------------------------------------------------

@PROPERTY
@given(st.tuples(st.integers(1, 4), st.integers(1, 5), st.integers(1, 7)), st.data())
def test_failure_surfaces_read_back(shape, data):
    paths = data.draw(arrays(np.float64, shape, elements=FINITE))
    assert np.array_equal(read_failure_surface(create_failure_surface(paths)), paths)


@PROPERTY
@given(st.lists(st.tuples(st.one_of(st.sampled_from(FAILURE_SURFACE_LABELS), TEXT),
                          UINT32, UINT32), max_size=4),
       UINT32, st.lists(ANY_FLOAT, max_size=30))
def test_any_float64_multi_array_is_read_or_refused_with_a_value_error(dims, offset, values):
    msg = Float64MultiArray(layout=MultiArrayLayout(
        dim=[MultiArrayDimension(label=label, size=size, stride=stride)
             for label, size, stride in dims], data_offset=offset), data=values)
    web = only_value_error(lambda: read_failure_surface(msg), 'failure surface')
    if web is not None:
        assert web.ndim == 3 and np.all(np.isfinite(web))


@PROPERTY
@given(JUNK)
def test_create_failure_surface_refuses_junk_with_a_value_error(paths):
    only_value_error(lambda: create_failure_surface(paths), 'paths')


# Paths and poses -----------------------------------------------------------------------------

@PROPERTY
@given(st.integers(0, 5), st.sampled_from([2, 3]), st.booleans(), NAME, st.data())
def test_paths_read_back_with_their_orientations(k, dim, oriented, frame_id, data):
    positions = data.draw(arrays(np.float64, (k, dim), elements=FINITE))
    orientations = np.array([data.draw(unit_quaternion()) for _ in range(k)]).reshape(k, 4)
    msg = create_path(positions, frame_id, orientations=orientations if oriented else None)
    expected = np.column_stack([positions, np.zeros(k)]) if dim == 2 else positions
    assert np.array_equal(read_path(msg), expected.reshape(k, 3))
    poses = read_path_poses(msg)
    assert np.allclose(poses.orientation, orientations if oriented else
                       np.tile([0.0, 0.0, 0.0, 1.0], (k, 1)), atol=1e-12)


@PROPERTY
@given(st.lists(st.tuples(st.sampled_from(['', 'base_link', 'map']),
                          st.tuples(*[ANY_FLOAT] * 7)), max_size=4),
       st.sampled_from(['base_link', '']))
def test_any_path_is_read_or_refused_with_a_value_error(poses, frame_id):
    msg = Path(header=Header(frame_id=frame_id), poses=[
        PoseStamped(header=Header(frame_id=frame), pose=Pose(
            position=Point(x=v[0], y=v[1], z=v[2]),
            orientation=Quaternion(x=v[3], y=v[4], z=v[5], w=v[6])))
        for frame, v in poses])
    only_value_error(lambda: read_path(msg), 'Path pose')
    only_value_error(lambda: read_path_poses(msg), 'Path pose')


@PROPERTY
@given(arrays(np.float64, 3, elements=FINITE), unit_quaternion(), st.tuples(*[ANY_FLOAT] * 7))
def test_poses_read_back_and_any_pose_is_read_or_refused(position, quaternion, values):
    back = read_pose(create_pose(position, quaternion))
    assert np.array_equal(back.position, position)
    assert np.allclose(back.orientation, quaternion, atol=1e-12)
    pose = Pose(position=Point(x=values[0], y=values[1], z=values[2]),
                orientation=Quaternion(x=values[3], y=values[4], z=values[5], w=values[6]))
    only_value_error(lambda: read_pose(pose, 'goal.pose'), 'goal.pose')
    only_value_error(lambda: read_point(pose.position, 'start'), 'start')
    only_value_error(lambda: read_quaternion(pose.orientation, 'goal'), 'goal')


@PROPERTY
@given(JUNK, JUNK, JUNK)
def test_pose_and_path_creators_refuse_junk_with_a_value_error(position, orientation, frame_id):
    only_value_error(lambda: create_pose(position, orientation))
    only_value_error(lambda: create_pose(position), 'position')
    only_value_error(lambda: create_pose([0.0, 0.0, 0.0], orientation), 'orientation')
    only_value_error(lambda: unit_quaternions(orientation, 'q'), 'q')
    only_value_error(lambda: create_path(position, frame_id, orientations=orientation))
    only_value_error(lambda: create_path(position, 'base_link'), 'positions')
    only_value_error(lambda: create_path([[0.0, 0.0]], frame_id), 'frame_id')
    only_value_error(lambda: create_path([[0.0, 0.0]], 'map', orientations=orientation),
                     'orientations')


# Stamps ----------------------------------------------------------------------------------------

@PROPERTY
@given(st.floats(0.0, 2.0**31 - 2.0), st.floats(-2.0**31 + 1.0, 2.0**31 - 2.0))
def test_times_and_durations_read_back_to_the_nanosecond(t, d):
    assert time_to_seconds(seconds_to_time(t)) == pytest.approx(t, abs=1e-9 + 1e-15 * t)
    assert duration_to_seconds(seconds_to_duration(d)) == pytest.approx(d,
                                                                       abs=1e-9 + 1e-15 * abs(d))


@PROPERTY
@given(JUNK, INT32, UINT32)
def test_any_stamp_is_read_or_refused_with_a_value_error(t, sec, nanosec):
    only_value_error(lambda: seconds_to_time(t), 'time')
    only_value_error(lambda: seconds_to_duration(t), 'duration')
    stamp = Time(sec=sec, nanosec=nanosec)
    for read in (time_to_seconds, time_to_nanoseconds):
        only_value_error(lambda r=read: r(stamp), 'Time')
    only_value_error(lambda: duration_to_seconds(Duration(sec=sec, nanosec=nanosec)), 'Duration')
    assume(0 <= sec and nanosec < 10**9)
    assert time_to_nanoseconds(stamp) == sec * 10**9 + nanosec


# Diagnostics -------------------------------------------------------------------------------

@PROPERTY
@given(NAME, st.sampled_from(sorted(DIAGNOSTIC_LEVELS)), TEXT,
       st.dictionaries(NAME, st.one_of(TEXT, FINITE, st.integers())), TEXT)
def test_diagnostic_statuses_read_back(name, level, message, values, hardware_id):
    status = create_diagnostic_status(name, level, message, values, hardware_id)
    array = create_diagnostic_array([status])
    reading = read_diagnostic_status(array.status[0])
    assert (reading.name, reading.level, reading.message, reading.hardware_id) == \
        (name, level, message, hardware_id)
    assert sorted(reading.values) == sorted(values)
    for key, value in values.items():
        text = reading.values[key]
        assert text == value if isinstance(value, str) else float(text) == value


@PROPERTY
@given(TEXT, st.integers(0, 255), st.lists(st.tuples(TEXT, TEXT), max_size=4),
       JUNK, JUNK, JUNK, JUNK)
def test_any_diagnostic_is_read_or_refused_with_a_value_error(name, level, pairs, junk_name,
                                                               junk_level, junk_values,
                                                               junk_statuses):
    status = DiagnosticStatus(name=name, level=bytes([level]),
                              values=[KeyValue(key=k, value=v) for k, v in pairs])
    only_value_error(lambda: read_diagnostic_status(status), 'diagnostic')
    only_value_error(lambda: create_diagnostic_status(junk_name, 'OK', 'm'), 'name')
    only_value_error(lambda: create_diagnostic_status('n', 'OK', junk_name), 'message')
    only_value_error(lambda: create_diagnostic_status('n', 'OK', 'm', junk_values), 'value')
    only_value_error(lambda: create_diagnostic_status('n', 'OK', 'm', hardware_id=junk_name),
                     'hardware_id')
    only_value_error(lambda: create_diagnostic_status('n', junk_level, 'm'), 'level')
    only_value_error(lambda: create_diagnostic_array(junk_statuses), 'statuses')
    only_value_error(lambda: create_diagnostic_array([], junk_values), 'stamp')


# Plan markers ------------------------------------------------------------------------------

@PROPERTY
@given(st.integers(2, 5), st.sampled_from([2, 3]), st.integers(3, 7), st.data())
def test_plan_markers_read_back(k, dim, n, data):
    arm = data.draw(arrays(np.float64, (k, dim), elements=FINITE))
    curve = data.draw(arrays(np.float64, (k, n), elements=FINITE))
    points = data.draw(arrays(np.float64, (k - 1, n), elements=FINITE))
    web = data.draw(arrays(np.float64, (2, k, n), elements=FINITE))
    back = read_plan_markers(create_plan_markers(
        'base_link', arm_polylines={'arm': arm}, end_effector_path=arm,
        joint_space_curves={'curves': [curve, curve]}, joint_space_points={'points': points},
        surface_paths=web))
    flat = np.column_stack([arm, np.zeros(k)]) if dim == 2 else arm
    assert [len(v) for v in back.values()] == [2, 1, 2, 1, 1]
    assert np.array_equal(back['arm'][0], flat) and np.array_equal(back['arm'][1], flat)
    assert np.array_equal(back['curves'][1], curve[:, :3])
    assert np.array_equal(back['points'][0], points[:, :3])
    assert len(back['failure_surface'][0]) == 2 * (2 * (k - 1) + k)


@PROPERTY
@given(JUNK, JUNK, JUNK, JUNK, JUNK)
def test_create_plan_markers_refuses_junk_with_a_value_error(frame_id, arm, curves, points, web):
    only_value_error(lambda: create_plan_markers(
        frame_id, arm_polylines=arm, end_effector_path=arm, joint_space_curves=curves,
        joint_space_points=points, surface_paths=web))
    only_value_error(lambda: create_plan_markers('base_link', arm_polylines=arm),
                     'arm_polylines')
    only_value_error(lambda: create_plan_markers('base_link', arm_polylines={'arm': arm}), 'arm')
    only_value_error(lambda: create_plan_markers('base_link', end_effector_path=arm),
                     'end_effector_path')
    only_value_error(lambda: create_plan_markers('base_link', joint_space_curves=curves),
                     'joint_space_curves')
    only_value_error(lambda: create_plan_markers('base_link', joint_space_curves={'c': curves}),
                     'joint_space_curves')
    only_value_error(lambda: create_plan_markers('base_link', joint_space_points=points),
                     'joint_space_points')
    only_value_error(lambda: create_plan_markers('base_link', joint_space_points={'p': points}),
                     'joint_space_points')
    only_value_error(lambda: create_plan_markers('base_link', surface_paths=web), 'surface_paths')
    only_value_error(lambda: create_plan_markers('base_link', joint_space_frame=frame_id),
                     'joint_space_frame')
