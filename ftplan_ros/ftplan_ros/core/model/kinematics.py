"""Compiled task maps: the residual of f(θ) against a task point and its Jacobian, by robot kind.

The continuation kernel (continuation.py) calls `task_residual(kind, parameters, x, θ)`
thousands of times per trace, so these run in numba. A robot names its kinematics with
`Robot.kernel_kind` and `Robot.kernel_parameters`:

* PLANAR: a planar chain; parameters are the link lengths [m]; x = (x, y) [m].
* POSITION, AXIS, POSE: a spatial serial chain of revolute joints (`spatial_parameters`
  lays it out) with a task on its tool frame: x = (x, y, z) [m]; (x, y, z, axis) with
  the tool's z axis along the unit `axis`; (x, y, z, qx, qy, qz, qw), a full pose.
* FROZEN + kind: the same chain with some joints held at fixed angles; only the others
  are variables (a curve chosen on a manifold of redundancy r >= 2).

Residuals are "what is left to move": planar and position x - f(θ); pose the position
error and log(R_g R(θ)^T) (world frame), whose Jacobian is the tool's world Jacobian;
axis the position error and minus the two components of the tool axis across `axis`.
Angles [rad], lengths [m].
"""

from __future__ import annotations

import numba
import numpy as np

PLANAR = 0
POSITION = 1
AXIS = 2
POSE = 3
FROZEN = 16  # added to a kind: the chain with some joints frozen (`frozen_parameters`)

_JOINT_FIELDS = 15  # per joint: placement rotation (9, row-major), translation (3), axis (3)


def spatial_parameters(placements: np.ndarray, axes: np.ndarray, tool: np.ndarray,
                       ) -> np.ndarray:
    """Lay out a spatial chain for the kernels: (1 + 15 n + 12,) floats.

    `placements` (n, 4, 4) are the joint frames in their parents' at zero angle, `axes`
    (n, 3) the unit joint axes in their own frames, `tool` (4, 4) the tool frame in the
    last joint's frame.
    """
    rows = [np.concatenate([p[:3, :3].ravel(), p[:3, 3], a]) for p, a in zip(placements, axes,
                                                                                strict=True)]
    return np.concatenate([[float(len(axes))], *rows, tool[:3, :3].ravel(), tool[:3, 3]])


def frozen_parameters(free: np.ndarray, values: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """Lay out a chain with frozen joints: `free` (n,) bool, `values` (n,) [rad] of the frozen."""
    return np.concatenate([[float(len(free))], free.astype(float), values, inner])


@numba.njit(cache=True)
def planar_kinematics(lengths: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """End-effector position (2,) [m] and Jacobian (2, n) [m/rad] of a planar chain.

    :param lengths: (n,) link lengths [m]; joint k turns links k..n-1.
    :param theta: (n,) joint angles [rad].
    """
    n = theta.shape[0]
    xs = np.empty(n)
    ys = np.empty(n)
    phi = 0.0
    for k in range(n):
        phi += theta[k]
        xs[k] = lengths[k] * np.cos(phi)
        ys[k] = lengths[k] * np.sin(phi)
    position = np.zeros(2)
    jac = np.empty((2, n))
    for k in range(n - 1, -1, -1):  # joint k moves links k..n-1
        position[0] += xs[k]
        position[1] += ys[k]
        jac[0, k] = -position[1]
        jac[1, k] = position[0]
    return position, jac


@numba.njit(cache=True)
def planar_frames(lengths: np.ndarray, thetas: np.ndarray) -> np.ndarray:
    """Return frames (N, n+1, 4, 4) of a planar chain at configurations (N, n) [rad].

    The base, then link k at joint k-1 with its x axis along the link.
    """
    count, n = thetas.shape
    out = np.zeros((count, n + 1, 4, 4))
    for k in range(count):
        phi = 0.0
        x = 0.0
        y = 0.0
        for i in range(4):
            out[k, 0, i, i] = 1.0
        for j in range(n):
            phi += thetas[k, j]
            c, s = np.cos(phi), np.sin(phi)
            frame = out[k, j + 1]
            frame[0, 0], frame[0, 1], frame[1, 0], frame[1, 1] = c, -s, s, c
            frame[2, 2] = frame[3, 3] = 1.0
            frame[0, 3], frame[1, 3] = x, y
            x += lengths[j] * c
            y += lengths[j] * s
    return out


@numba.njit(cache=True, inline='always')
def _multiply_rotated(a: np.ndarray, parameters: np.ndarray, base: int, axis: np.ndarray,
                      angle: float, out: np.ndarray) -> None:
    """Write a (3, 3) @ P @ Rot(axis, angle) into out (P row-major at parameters[base:])."""
    c = np.cos(angle)
    s = np.sin(angle)
    v = 1.0 - c
    x, y, z = axis[0], axis[1], axis[2]
    turn = ((c + x * x * v, x * y * v - z * s, x * z * v + y * s),
            (y * x * v + z * s, c + y * y * v, y * z * v - x * s),
            (z * x * v - y * s, z * y * v + x * s, c + z * z * v))
    for i in range(3):
        row0 = a[i, 0] * parameters[base] + a[i, 1] * parameters[base + 3] \
            + a[i, 2] * parameters[base + 6]
        row1 = a[i, 0] * parameters[base + 1] + a[i, 1] * parameters[base + 4] \
            + a[i, 2] * parameters[base + 7]
        row2 = a[i, 0] * parameters[base + 2] + a[i, 1] * parameters[base + 5] \
            + a[i, 2] * parameters[base + 8]
        for j in range(3):
            out[i, j] = row0 * turn[0][j] + row1 * turn[1][j] + row2 * turn[2][j]


@numba.njit(cache=True)
def _walk(parameters: np.ndarray, theta: np.ndarray, rotations: np.ndarray,
          origins: np.ndarray, axes: np.ndarray) -> None:
    """Fill the frames of a spatial chain at θ (n,).

    rotations (n+2, 3, 3) and origins (n+2, 3) of the base, links 1..n and the tool, and
    the joint axes (n, 3), all in the base frame.
    """
    n = theta.shape[0]
    for i in range(3):
        for j in range(3):
            rotations[0, i, j] = 1.0 if i == j else 0.0
        origins[0, i] = 0.0
    zero = np.zeros(3)
    for k in range(n + 1):
        base = 1 + _JOINT_FIELDS * k
        previous = rotations[k]
        for i in range(3):
            origins[k + 1, i] = origins[k, i] + previous[i, 0] * parameters[base + 9] \
                + previous[i, 1] * parameters[base + 10] + previous[i, 2] * parameters[base + 11]
        if k == n:  # the tool: its placement, no joint
            _multiply_rotated(previous, parameters, base, zero, 0.0, rotations[k + 1])
            break
        axis = parameters[base + 12:base + 15]
        _multiply_rotated(previous, parameters, base, axis, theta[k], rotations[k + 1])
        for i in range(3):  # the joint's own turn leaves its axis where it was
            axes[k, i] = rotations[k + 1, i, 0] * axis[0] + rotations[k + 1, i, 1] * axis[1] \
                + rotations[k + 1, i, 2] * axis[2]


@numba.njit(cache=True)
def spatial_tool(parameters: np.ndarray, theta: np.ndarray,
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Tool position (3,) [m], rotation (3, 3) and world Jacobians (3, n) of a spatial chain.

    Returns (p, R, J_v [m/rad], J_w [1]): column j of J_w is joint j's axis in the base
    frame, column j of J_v its cross product with the tool's offset from the joint.
    """
    n = theta.shape[0]
    rotations = np.empty((n + 2, 3, 3))
    origins = np.empty((n + 2, 3))
    axes = np.empty((n, 3))
    _walk(parameters, theta, rotations, origins, axes)
    position = origins[n + 1].copy()
    jv = np.empty((3, n))
    jw = np.empty((3, n))
    for j in range(n):
        w = axes[j]
        r = position - origins[j + 1]
        jw[:, j] = w
        jv[0, j] = w[1] * r[2] - w[2] * r[1]
        jv[1, j] = w[2] * r[0] - w[0] * r[2]
        jv[2, j] = w[0] * r[1] - w[1] * r[0]
    return position, rotations[n + 1].copy(), jv, jw


@numba.njit(cache=True)
def rotation_log(e: np.ndarray) -> np.ndarray:
    """Rotation vector (3,) [rad] of the rotation matrix e (3, 3): exp(hat(ω)) = e."""
    cosine = min(1.0, max(-1.0, 0.5 * (e[0, 0] + e[1, 1] + e[2, 2] - 1.0)))
    angle = np.arccos(cosine)
    twice_sine_axis = np.array([e[2, 1] - e[1, 2], e[0, 2] - e[2, 0], e[1, 0] - e[0, 1]])
    if angle < 1e-6:
        return 0.5 * twice_sine_axis
    if np.pi - angle > 1e-4:
        return angle / (2.0 * np.sin(angle)) * twice_sine_axis
    # Near a half turn the antisymmetric part vanishes: the axis is in the symmetric part.
    symmetric = 0.5 * (e + e.T) - cosine * np.eye(3)
    k = np.argmax(np.array([symmetric[0, 0], symmetric[1, 1], symmetric[2, 2]]))
    axis = symmetric[:, k] / np.sqrt(max(symmetric[k, k], 1e-300) * (1.0 - cosine))
    if axis @ twice_sine_axis < 0.0:
        axis = -axis
    return angle * axis


@numba.njit(cache=True)
def quaternion_rotation(q: np.ndarray) -> np.ndarray:
    """Rotation matrix (3, 3) of the quaternion (x, y, z, w), normalised first."""
    x, y, z, w = q / np.sqrt(q @ q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


@numba.njit(cache=True)
def axis_basis(axis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors (3,) that make a right-handed frame with the unit `axis` as its z."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    first = np.cross(helper, axis)
    first = first / np.sqrt(first @ first)
    return first, np.cross(axis, first)


@numba.njit(cache=True)
def _direct_residual(kind: int, parameters: np.ndarray, target: np.ndarray,
                     theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if kind == PLANAR:
        position, jac = planar_kinematics(parameters, theta)
        return target - position, jac
    position, rotation, jv, jw = spatial_tool(parameters, theta)
    n = theta.shape[0]
    if kind == POSITION:
        return target[:3] - position, jv
    if kind == POSE:
        residual = np.empty(6)
        residual[:3] = target[:3] - position
        residual[3:] = rotation_log(quaternion_rotation(target[3:7]) @ rotation.T)
        jac = np.empty((6, n))
        jac[:3] = jv
        jac[3:] = jw
        return residual, jac
    if kind == AXIS:
        tool_axis = np.ascontiguousarray(rotation[:, 2])
        first, second = axis_basis(np.ascontiguousarray(target[3:6]))
        residual = np.empty(5)
        residual[:3] = target[:3] - position
        residual[3] = -(first @ tool_axis)
        residual[4] = -(second @ tool_axis)
        jac = np.empty((5, n))
        jac[:3] = jv
        for j in range(n):
            turn = np.cross(np.ascontiguousarray(jw[:, j]), tool_axis)  # d(tool axis)/dθ_j
            jac[3, j] = first @ turn
            jac[4, j] = second @ turn
        return residual, jac
    raise ValueError('no compiled kinematics for this kind of robot')


@numba.njit(cache=True)
def _expand(kind: int, parameters: np.ndarray, theta: np.ndarray,
            ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """Return (kind, parameters, θ) of the whole chain and the columns of θ's joints in it."""
    if kind < FROZEN:
        return kind, parameters, theta, np.arange(theta.shape[0])
    n_full = int(parameters[0])
    columns = np.flatnonzero(parameters[1:1 + n_full] > 0.5)
    full = parameters[1 + n_full:1 + 2 * n_full].copy()
    full[columns] = theta
    return kind - FROZEN, parameters[1 + 2 * n_full:], full, columns



@numba.njit(cache=True)
def task_residual(kind: int, parameters: np.ndarray, target: np.ndarray, theta: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Residual (m,) and its Jacobian (m, n) [per rad] of θ (n,) [rad] against task point x.

    Newton's step δθ solves J δθ = residual; see the module docstring for each kind.
    """
    base, parameters_, full, columns = _expand(kind, parameters, theta)
    residual, jac = _direct_residual(base, parameters_, target, full)
    if kind < FROZEN:
        return residual, jac
    return residual, np.ascontiguousarray(jac[:, columns])

@numba.njit(cache=True)
def task_residuals(kind: int, parameters: np.ndarray, target: np.ndarray, thetas: np.ndarray,
                   m: int) -> tuple[np.ndarray, np.ndarray]:
    """`task_residual` for configurations (N, n): residuals (N, m) and Jacobians (N, m, n)."""
    count, n = thetas.shape
    residuals = np.empty((count, m))
    jacobians = np.empty((count, m, n))
    for k in range(count):
        residual, jac = task_residual(kind, parameters, target, np.ascontiguousarray(thetas[k]))
        residuals[k] = residual
        jacobians[k] = jac
    return residuals, jacobians


@numba.njit(cache=True)
def task_errors(kind: int, parameters: np.ndarray, target: np.ndarray, thetas: np.ndarray,
                ) -> np.ndarray:
    """Measure distances (N, 2) of configurations (N, n) from task point x.

    Column 0 [m] is the position's, column 1 [rad] the orientation's: the rotation angle to
    the goal pose, or the angle between tool axis and `axis`; 0 for position tasks.
    """
    out = np.zeros((thetas.shape[0], 2))
    for k in range(thetas.shape[0]):
        base, parameters_, theta, _ = _expand(kind, parameters, np.ascontiguousarray(thetas[k]))
        if base == PLANAR:
            position, _ = planar_kinematics(parameters_, theta)
            out[k, 0] = np.sqrt(np.sum((target - position) ** 2))
            continue
        position, rotation, _, _ = spatial_tool(parameters_, theta)
        out[k, 0] = np.sqrt(np.sum((target[:3] - position) ** 2))
        if base == POSE:
            log = rotation_log(quaternion_rotation(target[3:7]) @ rotation.T)
            out[k, 1] = np.sqrt(log @ log)
        elif base == AXIS:
            axis = np.ascontiguousarray(target[3:6])
            cosine = np.ascontiguousarray(rotation[:, 2]) @ axis / np.sqrt(axis @ axis)
            out[k, 1] = np.arccos(min(1.0, max(-1.0, cosine)))
    return out


@numba.njit(cache=True)
def chain_frames(parameters: np.ndarray, thetas: np.ndarray) -> np.ndarray:
    """Frames (N, n+2, 4, 4) of a spatial chain at configurations (N, n) [rad], in its base.

    Frame 0 is the base (identity), frame j+1 the frame of the link joint j turns (the
    joint's frame, rotated), and the last frame the tool.
    """
    count, n = thetas.shape
    out = np.zeros((count, n + 2, 4, 4))
    rotations = np.empty((n + 2, 3, 3))
    origins = np.empty((n + 2, 3))
    axes = np.empty((n, 3))
    for k in range(count):
        _walk(parameters, thetas[k], rotations, origins, axes)
        for f in range(n + 2):
            out[k, f, :3, :3] = rotations[f]
            out[k, f, :3, 3] = origins[f]
            out[k, f, 3, 3] = 1.0
    return out


@numba.njit(cache=True)
def solve_in_place(matrix, rhs):
    """Solve matrix · X = rhs (n, n), (n, k) by elimination with partial pivoting.

    `rhs` becomes X and `matrix` is overwritten; returns False, leaving both half done,
    when a pivot is exactly 0 (the matrix is singular). On the small systems of a trace
    or a Newton step it beats numba's LAPACK calls (det and solve): about 0.1 against 2 µs
    for n = 3 and 1.4 against 5 µs for n = 7, on this project's machines.
    """
    n = matrix.shape[0]
    for c in range(n):
        pivot = c
        for r in range(c + 1, n):
            if abs(matrix[r, c]) > abs(matrix[pivot, c]):
                pivot = r
        if matrix[pivot, c] == 0.0:
            return False
        if pivot != c:
            for k in range(c, n):
                matrix[c, k], matrix[pivot, k] = matrix[pivot, k], matrix[c, k]
            for k in range(rhs.shape[1]):
                rhs[c, k], rhs[pivot, k] = rhs[pivot, k], rhs[c, k]
        for r in range(c + 1, n):
            factor = matrix[r, c] / matrix[c, c]
            for k in range(c + 1, n):
                matrix[r, k] -= factor * matrix[c, k]
            for k in range(rhs.shape[1]):
                rhs[r, k] -= factor * rhs[c, k]
    for c in range(n - 1, -1, -1):
        for k in range(rhs.shape[1]):
            value = rhs[c, k]
            for j in range(c + 1, n):
                value -= matrix[c, j] * rhs[j, k]
            rhs[c, k] = value / matrix[c, c]
    return True


@numba.njit(cache=True)
def project_seeds(kind: int, parameters: np.ndarray, target: np.ndarray, thetas: np.ndarray,
                  m: int, movable: np.ndarray, periodic: np.ndarray, lower: np.ndarray,
                  upper: np.ndarray, tolerance: float, max_iterations: int) -> np.ndarray:
    """Damped least-squares Newton from each seed (N, n) [rad] towards f(θ) = target.

    Moves the seeds in place and returns their residual norms (N,) at the end. Only the
    `movable` joints step; each step is at most 0.5 rad long, and joints that are not
    `periodic` are clipped to [lower, upper] after it. A seed stops once its residual
    is below `tolerance`; one whose residual or Jacobian is not finite (a seed that is
    not) gets an infinite residual norm.
    """
    count, n = thetas.shape
    columns = np.flatnonzero(movable)
    errors = np.empty(count)
    gram, weights, step = np.empty((m, m)), np.empty((m, 1)), np.empty(columns.shape[0])
    for k in range(count):
        theta = np.ascontiguousarray(thetas[k])
        error = np.inf
        for iteration in range(max_iterations + 1):
            residual, jac = task_residual(kind, parameters, target, theta)
            error = np.sqrt(residual @ residual)
            if not np.isfinite(error) or not np.all(np.isfinite(jac)):
                error = np.inf
                break
            if error < tolerance or iteration == max_iterations:
                break
            # The damped step J^T (J J^T + d I)^-1 r over the movable columns, in loops:
            # numba's BLAS and LAPACK calls cost more than these tiny products.
            damping = 1e-6 if error < 1e-3 else 1e-3
            for i in range(m):
                for j in range(m):
                    total = damping if i == j else 0.0
                    for c in columns:
                        total += jac[i, c] * jac[j, c]
                    gram[i, j] = total
                weights[i, 0] = residual[i]
            solve_in_place(gram, weights)  # damped: never singular
            length2 = 0.0
            for i in range(columns.shape[0]):
                total = 0.0
                for j in range(m):
                    total += jac[j, columns[i]] * weights[j, 0]
                step[i] = total
                length2 += total * total
            scale = min(1.0, 0.5 / np.sqrt(length2)) if length2 > 0.0 else 1.0  # stay local
            for i in range(columns.shape[0]):
                theta[columns[i]] += scale * step[i]
            for j in range(n):
                if not periodic[j]:
                    theta[j] = min(max(theta[j], lower[j]), upper[j])
        thetas[k] = theta
        errors[k] = error
    return errors
