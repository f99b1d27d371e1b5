"""The compiled task maps' helpers (core/model/kinematics.py) against scipy and LAPACK."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftplan_ros.core.model import kinematics
from ftplan_ros.core.model.kinematics import solve_in_place


@pytest.mark.parametrize('angle', [0.0, 1e-9, 1e-6, 1e-3, 0.7, 2.0, np.pi - 1e-3,
                                   np.pi - 1e-5, np.pi - 1e-9, np.pi])
def test_rotation_log_is_scipys_rotation_vector(angle, rng):
    for axis in Rotation.random(20, random_state=rng.integers(1 << 31)).apply([0.0, 0.0, 1.0]):
        log = kinematics.rotation_log(Rotation.from_rotvec(angle * axis).as_matrix())
        assert np.linalg.norm(log) == pytest.approx(angle, abs=1e-7)
        if angle < np.pi - 1e-4:
            assert np.allclose(log, angle * axis, atol=1e-9)
        else:  # a half turn about u is one about -u
            assert min(np.linalg.norm(log - angle * axis),
                       np.linalg.norm(log + angle * axis)) < 1e-6
            assert np.allclose(Rotation.from_rotvec(log).as_matrix(),
                               Rotation.from_rotvec(angle * axis).as_matrix(), atol=1e-7)


def test_quaternions_and_axis_bases(rng):
    for quaternion in Rotation.random(20, random_state=rng.integers(1 << 31)).as_quat():
        scaled = 1.3 * quaternion  # normalised first
        assert np.allclose(kinematics.quaternion_rotation(scaled),
                           Rotation.from_quat(quaternion).as_matrix(), atol=1e-12)
    axes = Rotation.random(20, random_state=rng.integers(1 << 31)).apply([0.0, 0.0, 1.0])
    for axis in np.vstack([axes, np.eye(3), -np.eye(3)]):
        first, second = kinematics.axis_basis(axis)
        frame = np.column_stack([first, second, axis])
        assert np.allclose(frame.T @ frame, np.eye(3), atol=1e-12)
        assert np.linalg.det(frame) == pytest.approx(1.0)


def test_the_traces_small_solve_agrees_with_lapack_and_refuses_a_singular_system():
    rng = np.random.default_rng(3)
    for n in (2, 3, 7):
        for _ in range(50):
            matrix, rhs = rng.normal(size=(n, n)), rng.normal(size=(n, 2))
            solution = rhs.copy()
            assert solve_in_place(matrix.copy(), solution)
            assert np.allclose(solution, np.linalg.solve(matrix, rhs), rtol=1e-9, atol=1e-12)
        singular = rng.normal(size=(n, n))
        singular[:, n // 2] = 0.0  # a zero column: some pivot is exactly 0
        assert not solve_in_place(singular, rng.normal(size=(n, 2)))
