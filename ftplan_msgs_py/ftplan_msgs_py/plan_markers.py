"""Create and read the RViz markers that show a plan result.

Workspace objects (arm poses, the end-effector path) are drawn in 3-D in the base frame
[m]; an arm pose is a LINE_STRIP through its skeleton (base, joints, tool) plus a
SPHERE_LIST at its points, ids 0 and 1 of one namespace (planar arms give z = 0).
Joint-space objects (self-motion manifolds, failure-plane hits, the failure surface S_F)
are drawn in a separate frame whose x, y, z are the first three joint angles [rad].
"""

import colorsys
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point, Vector3
from numpy.typing import ArrayLike, NDArray
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

from ftplan_msgs_py._validation import (
    finite_array,
    frame,
    mapping_items,
    sequence,
    stamp_or_zero,
)

END_EFFECTOR_NS = 'end_effector_path'
FAILURE_SURFACE_NS = 'failure_surface'
DEFAULT_JOINT_SPACE_FRAME = 'ftplan_joint_space'
WORKSPACE_LINE_WIDTH = 0.02  # [m]
ARM_JOINT_DIAMETER = 0.04  # [m]
JOINT_SPACE_LINE_WIDTH = 0.01  # [rad], drawn as metres
JOINT_SPACE_POINT_DIAMETER = 0.05  # [rad], drawn as metres
_GOLDEN_RATIO_CONJUGATE = 0.618033988749895
_SURFACE_ALPHA = 0.6


class _Part(NamedTuple):
    marker_type: int
    scale: tuple[float, float, float]
    points: NDArray[np.float64]


class _Layer(NamedTuple):
    """One namespace: its markers (ids 0, 1, ...) share a frame and a colour."""

    ns: str
    frame_id: str
    parts: list[_Part]
    alpha: float = 1.0


def _color(index: int, alpha: float) -> ColorRGBA:
    # Golden-ratio hue steps keep any number of namespaces apart in colour.
    hue = (index * _GOLDEN_RATIO_CONJUGATE) % 1.0
    r, g, b = colorsys.hsv_to_rgb(hue, 0.85, 0.95)
    return ColorRGBA(r=r, g=g, b=b, a=alpha)


def _workspace_polyline(value: ArrayLike, field: str) -> NDArray[np.float64]:
    points = finite_array(value, field)
    if points.ndim != 2 or points.shape[1] not in (2, 3) or len(points) < 2:
        raise ValueError(
            f'{field} has shape {points.shape}; pass (k, 2) or (k, 3) positions [m], k >= 2'
        )
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    return points


def _joint_space_points(value: ArrayLike, field: str, min_points: int) -> NDArray[np.float64]:
    points = finite_array(value, field)
    if points.ndim != 2 or points.shape[1] < 3 or len(points) < min_points:
        raise ValueError(
            f'{field} has shape {points.shape}; pass (k, n) joint angles [rad] with n >= 3 '
            f'and k >= {min_points}'
        )
    return points[:, :3]


def _surface_segments(value: ArrayLike) -> NDArray[np.float64]:
    """Return the (2m, 3) end points of the path and rung segments of a (K, W, n) web."""
    web = finite_array(value, 'surface_paths')
    if web.ndim != 3 or web.shape[2] < 3:
        raise ValueError(
            f'surface_paths has shape {web.shape}; pass (K, W, n) joint angles [rad], n >= 3'
        )
    xyz = web[:, :, :3]
    along_paths = np.stack([xyz[:, :-1], xyz[:, 1:]], axis=2).reshape(-1, 3)
    rungs = np.stack([xyz[:-1], xyz[1:]], axis=2).reshape(-1, 3)
    return np.concatenate([along_paths, rungs])


def _line(width: float) -> tuple[float, float, float]:
    return (width, 0.0, 0.0)


def _spheres(diameter: float) -> tuple[float, float, float]:
    return (diameter, diameter, diameter)


def create_plan_markers(
    frame_id: str,
    stamp: Time | None = None,
    *,
    arm_polylines: Mapping[str, ArrayLike] | None = None,
    end_effector_path: ArrayLike | None = None,
    joint_space_frame: str = DEFAULT_JOINT_SPACE_FRAME,
    joint_space_curves: Mapping[str, Sequence[ArrayLike]] | None = None,
    joint_space_points: Mapping[str, ArrayLike] | None = None,
    surface_paths: ArrayLike | None = None,
) -> MarkerArray:
    """Create the MarkerArray of a plan result for RViz.

    The array starts with DELETEALL, so it replaces whatever was shown. Each namespace
    gets its own colour.

    :param frame_id: the base frame of the workspace objects.
    :param stamp: stamp of every marker; None leaves it zero.
    :param arm_polylines: ns -> (k, 2|3) points [m] of one arm pose, base to tool (e.g.
        'arm_theta_s', 'arm_hit_1'): a LINE_STRIP (id 0) and a SPHERE_LIST (id 1) at the
        points; 2-D points get z = 0.
    :param end_effector_path: (k, 2|3) positions [m], a LINE_STRIP in 'end_effector_path'.
    :param joint_space_frame: the frame of the joint-space objects.
    :param joint_space_curves: ns -> list of (k, n) joint paths [rad] (e.g. sampled
        self-motion manifolds), one LINE_STRIP each, ids 0, 1, ...
    :param joint_space_points: ns -> (k, n) configurations [rad], one SPHERE_LIST.
    :param surface_paths: (K, W, n) failure surface [rad]: a LINE_LIST in 'failure_surface'
        of the segments along each path and the rungs between adjacent paths.
    :return: the MarkerArray.
    :raises ValueError: on a bad shape, a non-finite value, a line with fewer than two
        points, or a namespace used twice.
    """
    base = frame(frame_id, 'frame_id')
    joint_frame = frame(joint_space_frame, 'joint_space_frame')
    layers = [_arm_layer(_namespace(ns, 'arm_polylines'), base, polyline)
              for ns, polyline in mapping_items(arm_polylines, 'arm_polylines')]
    if end_effector_path is not None:
        layers.append(_Layer(END_EFFECTOR_NS, base, [_Part(
            Marker.LINE_STRIP, _line(WORKSPACE_LINE_WIDTH),
            _workspace_polyline(end_effector_path, 'end_effector_path'))]))
    for ns, curves in mapping_items(joint_space_curves, 'joint_space_curves'):
        _namespace(ns, 'joint_space_curves')
        layers.append(_Layer(ns, joint_frame, [
            _Part(Marker.LINE_STRIP, _line(JOINT_SPACE_LINE_WIDTH),
                  _joint_space_points(curve, f'joint_space_curves[{ns!r}][{i}]', 2))
            for i, curve in enumerate(sequence(curves, f'joint_space_curves[{ns!r}]'))]))
    for ns, points in mapping_items(joint_space_points, 'joint_space_points'):
        _namespace(ns, 'joint_space_points')
        layers.append(_Layer(ns, joint_frame, [_Part(
            Marker.SPHERE_LIST, _spheres(JOINT_SPACE_POINT_DIAMETER),
            _joint_space_points(points, f'joint_space_points[{ns!r}]', 0))]))
    if surface_paths is not None:
        segments = _surface_segments(surface_paths)
        if len(segments):
            layers.append(_Layer(FAILURE_SURFACE_NS, joint_frame, [_Part(
                Marker.LINE_LIST, _line(JOINT_SPACE_LINE_WIDTH), segments)], _SURFACE_ALPHA))
    _check_namespaces(layers)
    return MarkerArray(markers=_markers(layers, base, stamp))


def _arm_layer(ns: str, frame_id: str, polyline: ArrayLike) -> _Layer:
    points = _workspace_polyline(polyline, f'arm_polylines[{ns!r}]')
    return _Layer(ns, frame_id, [_Part(Marker.LINE_STRIP, _line(WORKSPACE_LINE_WIDTH), points),
                                 _Part(Marker.SPHERE_LIST, _spheres(ARM_JOINT_DIAMETER), points)])


def _namespace(ns: object, field: str) -> str:
    """Return a marker namespace (a key of `field`) after checking it is a non-empty string."""
    if not isinstance(ns, str) or not ns:
        raise ValueError(f'{field} has the key {ns!r}; a marker namespace must be a '
                         'non-empty string')
    return ns


def _check_namespaces(layers: list[_Layer]) -> None:
    seen: set[str] = set()
    for layer in layers:
        if not isinstance(layer.ns, str) or not layer.ns:
            raise ValueError(f'marker namespace must be a non-empty string, got {layer.ns!r}')
        if layer.ns in seen:
            raise ValueError(
                f'marker namespace {layer.ns!r} is used twice; RViz would overwrite one '
                'with the other, so give each object its own namespace'
            )
        seen.add(layer.ns)


def _markers(layers: list[_Layer], base: str, stamp: Time | None) -> list[Marker]:
    """Return a DELETEALL, then one ADD marker per part of each layer (ids 0, 1, ... per ns)."""
    marker_stamp = stamp_or_zero(stamp)
    markers = [Marker(header=Header(stamp=stamp_or_zero(marker_stamp), frame_id=base),
                      action=Marker.DELETEALL)]
    for index, layer in enumerate(layers):
        for marker_id, part in enumerate(layer.parts):
            markers.append(Marker(
                header=Header(stamp=stamp_or_zero(marker_stamp), frame_id=layer.frame_id),
                ns=layer.ns,
                id=marker_id,
                type=part.marker_type,
                action=Marker.ADD,
                scale=Vector3(x=part.scale[0], y=part.scale[1], z=part.scale[2]),
                color=_color(index, layer.alpha),
                points=[Point(x=x, y=y, z=z) for x, y, z in part.points.tolist()],
            ))
    return markers


def read_plan_markers(msg: MarkerArray) -> dict[str, list[NDArray[np.float64]]]:
    """Read the points of each marker, grouped by namespace.

    Markers whose action is not ADD (e.g. the leading DELETEALL) are skipped. Points are
    returned in the marker's own coordinates; `create_plan_markers` uses identity poses.

    :param msg: the MarkerArray.
    :return: ns -> list of (k, 3) point arrays, one per marker, in message order.
    :raises ValueError: on a non-finite point.
    """
    result: dict[str, list[NDArray[np.float64]]] = {}
    for marker in msg.markers:
        if marker.action != Marker.ADD:
            continue
        points = finite_array(
            [(p.x, p.y, p.z) for p in marker.points],
            f'points of marker ns={marker.ns!r} id={marker.id}',
        ).reshape(-1, 3)
        result.setdefault(marker.ns, []).append(points)
    return result
