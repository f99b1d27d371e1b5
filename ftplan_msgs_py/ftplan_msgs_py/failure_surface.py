"""Convert between the failure surface S_F and std_msgs/Float64MultiArray.

S_F is sent as a web of joint paths: K paths of W waypoints of n joint angles [rad], in
a row-major array with layout dims labelled `path`, `waypoint`, `joint`.
"""

import numpy as np
from numpy.typing import ArrayLike, NDArray
from std_msgs.msg import Float64MultiArray, MultiArrayDimension, MultiArrayLayout

from ftplan_msgs_py._validation import finite_array

FAILURE_SURFACE_LABELS = ('path', 'waypoint', 'joint')


def create_failure_surface(paths: ArrayLike) -> Float64MultiArray:
    """Create the Float64MultiArray of the failure surface `paths`.

    The layout follows the ROS row-major convention: dim[i].stride is the product of the
    sizes of dims i and after, and data_offset is 0.

    :param paths: (K, W, n) joint angles [rad]: K paths of W waypoints each.
    :return: the Float64MultiArray.
    """
    web = finite_array(paths, 'paths')
    if web.ndim != 3:
        raise ValueError(
            f'paths has shape {web.shape}; pass (K, W, n): K paths of W waypoints of n joints'
        )
    K, W, n = web.shape
    dims = [
        MultiArrayDimension(label=label, size=size, stride=stride)
        for label, size, stride in zip(
            FAILURE_SURFACE_LABELS, (K, W, n), (K * W * n, W * n, n), strict=True
        )
    ]
    return Float64MultiArray(
        layout=MultiArrayLayout(dim=dims, data_offset=0), data=web.ravel().tolist()
    )


def read_failure_surface(msg: Float64MultiArray) -> NDArray[np.float64]:
    """Read the failure surface from a Float64MultiArray.

    :param msg: the array; layout dims labelled exactly `path`, `waypoint`, `joint` with
        row-major strides, and exactly K * W * n values after `data_offset`.
    :return: (K, W, n) joint angles [rad].
    :raises ValueError: on other labels, an empty size, inconsistent sizes, strides or
        data length, or a non-finite value.
    """
    labels = tuple(dim.label for dim in msg.layout.dim)
    if labels != FAILURE_SURFACE_LABELS:
        raise ValueError(
            f'failure surface layout labels are {list(labels)}; '
            f'expected {list(FAILURE_SURFACE_LABELS)}'
        )
    shape = tuple(int(dim.size) for dim in msg.layout.dim)
    K, W, n = shape
    if min(shape) < 1:
        raise ValueError(f'failure surface sizes are {list(shape)}; each must be >= 1')
    expected_strides = (K * W * n, W * n, n)
    strides = tuple(int(dim.stride) for dim in msg.layout.dim)
    if strides != expected_strides:
        raise ValueError(
            f'failure surface strides are {list(strides)} for sizes {list(shape)}; a dense '
            f'row-major layout needs {list(expected_strides)}'
        )
    offset = int(msg.layout.data_offset)
    available = len(msg.data) - offset
    if available != K * W * n:
        raise ValueError(
            f'failure surface has {max(available, 0)} values after data_offset {offset} but '
            f'its layout (path={K}, waypoint={W}, joint={n}) needs {K * W * n}'
        )
    web = np.asarray(msg.data, dtype=np.float64)[offset:].reshape(shape)
    if not np.all(np.isfinite(web)):
        k, w, j = (int(i) for i in np.argwhere(~np.isfinite(web))[0])
        raise ValueError(
            f'failure surface value at path {k}, waypoint {w}, joint {j} is {web[k, w, j]}; '
            'every angle must be finite'
        )
    return web
