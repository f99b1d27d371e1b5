"""Convert between obstacle shapes and visualization_msgs/MarkerArray.

Obstacles arrive on `/ftplan/obstacles` as SPHERE, CYLINDER and CUBE markers in the robot
base frame, keyed by (ns, id) like RViz keys them; DELETE and DELETEALL are honoured.
"""

from collections.abc import Iterable, Mapping
from typing import NamedTuple

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from numpy.typing import ArrayLike, NDArray
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py._validation import (
    INT32_MAX,
    INT32_MIN,
    finite_array,
    frame,
    sequence,
    stamp_or_zero,
)

ObstacleKey = tuple[str, int]

DEFAULT_OBSTACLE_COLOR = (0.8, 0.3, 0.3, 0.8)

_TYPE_BY_SHAPE = {'sphere': Marker.SPHERE, 'box': Marker.CUBE, 'cylinder': Marker.CYLINDER}
_SHAPE_BY_TYPE = {marker_type: shape for shape, marker_type in _TYPE_BY_SHAPE.items()}
_TYPE_NAMES = {
    getattr(Marker, name): name
    for name in (
        'ARROW', 'CUBE', 'SPHERE', 'CYLINDER', 'LINE_STRIP', 'LINE_LIST', 'CUBE_LIST',
        'SPHERE_LIST', 'POINTS', 'TEXT_VIEW_FACING', 'MESH_RESOURCE', 'TRIANGLE_LIST',
        'ARROW_STRIP',
    )
    if hasattr(Marker, name)
}


class ObstacleShape(NamedTuple):
    """One obstacle in the base frame, as a marker describes it.

    `scale` is the marker scale [m]: full diameters for a sphere, full extents for a box,
    and for a cylinder the diameters in x, y and the height in z. `orientation` is a unit
    quaternion (x, y, z, w). Shapes returned by `read_obstacle_markers` hold read-only arrays.
    """

    key: ObstacleKey
    shape: str
    center: NDArray[np.float64]
    scale: NDArray[np.float64]
    orientation: NDArray[np.float64]


def _read_only(array: NDArray[np.float64]) -> NDArray[np.float64]:
    array.flags.writeable = False
    return array


def _check_obstacle(
    key: ObstacleKey,
    shape: str,
    center: ArrayLike,
    scale: ArrayLike,
    orientation: ArrayLike,
    where: str,
) -> ObstacleShape:
    """Validate one obstacle's fields and return it with a normalised, read-only pose."""
    if not isinstance(shape, str) or shape not in _TYPE_BY_SHAPE:
        raise ValueError(
            f'{where} has shape {shape!r}; use one of {sorted(_TYPE_BY_SHAPE)}'
        )
    position = finite_array(center, f'{where} center')
    size = finite_array(scale, f'{where} scale')
    quaternion = finite_array(orientation, f'{where} orientation')
    for field, array, length in (('center', position, 3), ('scale', size, 3),
                                 ('orientation', quaternion, 4)):
        if array.shape != (length,):
            raise ValueError(f'{where} {field} has shape {array.shape}; pass ({length},)')
    if np.any(size <= 0.0):
        raise ValueError(f'{where} scale {size.tolist()} must be > 0 in x, y and z [m]')
    norm = float(np.linalg.norm(quaternion))
    if norm < 1e-9:
        raise ValueError(
            f'{where} has a zero orientation quaternion; use (0, 0, 0, 1) for no rotation'
        )
    return ObstacleShape(
        key, shape, _read_only(position), _read_only(size), _read_only(quaternion / norm)
    )


def _describe(key: ObstacleKey) -> str:
    return f'obstacle marker ns={key[0]!r} id={key[1]}'


def _shape_from_marker(marker: Marker, frame_id: str) -> ObstacleShape:
    key = (marker.ns, marker.id)
    where = _describe(key)
    if marker.type not in _SHAPE_BY_TYPE:
        type_name = _TYPE_NAMES.get(marker.type, str(marker.type))
        raise ValueError(
            f'{where} has type {type_name}; obstacles must be SPHERE, CYLINDER or CUBE'
        )
    if marker.header.frame_id != frame_id:
        raise ValueError(
            f'{where} is in frame {marker.header.frame_id!r} but obstacles must be in '
            f'{frame_id!r}; publish it in {frame_id!r}'
        )
    p, o, s = marker.pose.position, marker.pose.orientation, marker.scale
    return _check_obstacle(
        key,
        _SHAPE_BY_TYPE[marker.type],
        (p.x, p.y, p.z),
        (s.x, s.y, s.z),
        (o.x, o.y, o.z, o.w),
        where,
    )


def read_obstacle_markers(
    msg: MarkerArray,
    frame_id: str,
    current: Mapping[ObstacleKey, ObstacleShape] | None = None,
) -> dict[ObstacleKey, ObstacleShape]:
    """Apply the markers of `msg`, in order, to a copy of the obstacle set `current`.

    ADD (= MODIFY) inserts or replaces the obstacle keyed (ns, id); DELETE removes it
    (a missing key is fine); DELETEALL clears every obstacle, including earlier markers
    of the same message. All-or-nothing: on any error `current` is left untouched.

    :param msg: markers of type SPHERE, CYLINDER or CUBE (only ADD markers are checked).
    :param frame_id: the base frame every ADD marker must be stamped in.
    :param current: the obstacles known so far; None means none.
    :return: the new obstacle set, keyed (ns, id).
    :raises ValueError: on another marker type or action, a wrong frame, a scale that is
        not > 0, a zero quaternion or a non-finite pose.
    """
    base = frame(frame_id, 'frame_id')
    obstacles = dict(current) if current is not None else {}
    for marker in msg.markers:
        if marker.action == Marker.ADD:
            obstacle = _shape_from_marker(marker, base)
            obstacles[obstacle.key] = obstacle
        elif marker.action == Marker.DELETE:
            obstacles.pop((marker.ns, marker.id), None)
        elif marker.action == Marker.DELETEALL:
            obstacles.clear()
        else:
            raise ValueError(
                f'{_describe((marker.ns, marker.id))} has unknown action {marker.action}; '
                'use ADD, DELETE or DELETEALL'
            )
    return obstacles


def _check_color(color: ArrayLike) -> tuple[float, float, float, float]:
    rgba = finite_array(color, 'color')
    if rgba.shape != (4,) or np.any(rgba < 0.0) or np.any(rgba > 1.0):
        raise ValueError(f'color must be (r, g, b, a) with each in [0, 1], got {rgba.tolist()}')
    r, g, b, a = rgba.tolist()
    return r, g, b, a


def _check_key(key: object) -> ObstacleKey:
    if not (
        isinstance(key, tuple)
        and len(key) == 2
        and isinstance(key[0], str)
        and isinstance(key[1], int | np.integer)
        and INT32_MIN <= key[1] <= INT32_MAX
    ):
        raise ValueError(f'obstacle key must be a (ns: str, id: int32) tuple, got {key!r}')
    return key[0], int(key[1])


def create_obstacle_markers(
    obstacles: Iterable[ObstacleShape],
    frame_id: str,
    stamp: Time | None = None,
    color: ArrayLike = DEFAULT_OBSTACLE_COLOR,
    clear_first: bool = True,
) -> MarkerArray:
    """Create a MarkerArray with one ADD marker per obstacle, keyed by its (ns, id).

    :param obstacles: the obstacles; their keys must be unique.
    :param frame_id: the base frame the obstacles are expressed in.
    :param stamp: header stamp; None leaves it zero.
    :param color: (r, g, b, a) in [0, 1] for every marker.
    :param clear_first: start with a DELETEALL marker, so the array replaces all
        obstacles instead of adding to them.
    :return: the MarkerArray.
    """
    base = frame(frame_id, 'frame_id')
    r, g, b, a = _check_color(color)
    header_stamp = stamp_or_zero(stamp)

    def header() -> Header:
        # A fresh Header per marker: message fields hold references, so sharing one
        # would let an edit to one marker leak into all of them.
        return Header(stamp=stamp_or_zero(header_stamp), frame_id=base)

    markers = []
    if clear_first:
        markers.append(Marker(header=header(), action=Marker.DELETEALL))
    seen: set[ObstacleKey] = set()
    for index, obstacle in enumerate(sequence(obstacles, 'obstacles')):
        if not isinstance(obstacle, ObstacleShape):
            raise ValueError(f'obstacles[{index}] is a {type(obstacle).__name__}, not an '
                             'ObstacleShape')
        key = _check_key(obstacle.key)
        if key in seen:
            raise ValueError(f'{_describe(key)} appears twice; give each obstacle its own key')
        seen.add(key)
        checked = _check_obstacle(
            key, obstacle.shape, obstacle.center, obstacle.scale, obstacle.orientation,
            _describe(key),
        )
        x, y, z = checked.center.tolist()
        qx, qy, qz, qw = checked.orientation.tolist()
        sx, sy, sz = checked.scale.tolist()
        markers.append(Marker(
            header=header(),
            ns=key[0],
            id=key[1],
            type=_TYPE_BY_SHAPE[checked.shape],
            action=Marker.ADD,
            pose=Pose(position=Point(x=x, y=y, z=z),
                      orientation=Quaternion(x=qx, y=qy, z=qz, w=qw)),
            scale=Vector3(x=sx, y=sy, z=sz),
            color=ColorRGBA(r=r, g=g, b=b, a=a),
        ))
    return MarkerArray(markers=markers)
