import numpy as np
import pytest

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.robot import PlanarChain, chain_kinematics

ROBOT = PlanarChain((1.0, 0.7, 0.4), ('a', 'b', 'c'), link_radius=0.05)


def test_forward_kinematics_is_the_last_joint_position(rng):
    thetas = rng.uniform(-np.pi, np.pi, (50, 3))
    assert np.allclose(ROBOT.forward_kinematics(thetas), ROBOT.joint_positions(thetas)[:, -1])
    assert np.allclose(ROBOT.forward_kinematics([0.0, 0.0, 0.0]), [2.1, 0.0])
    assert np.allclose(ROBOT.forward_kinematics([np.pi / 2, 0.0, 0.0]), [0.0, 2.1])


def test_jacobian_matches_finite_differences(rng):
    for theta in rng.uniform(-np.pi, np.pi, (20, 3)):
        numeric = np.stack([(ROBOT.forward_kinematics(theta + 1e-6 * e)
                             - ROBOT.forward_kinematics(theta - 1e-6 * e)) / 2e-6
                            for e in np.eye(3)], axis=1)
        assert np.allclose(ROBOT.jacobian(theta), numeric, atol=1e-8)
    batch = rng.uniform(-np.pi, np.pi, (4, 3))
    assert np.allclose(ROBOT.jacobian(batch)[2], ROBOT.jacobian(batch[2]))


def test_lever_arms_bound_how_far_link_points_move(rng):
    arms = ROBOT.link_lever_arms()
    for _ in range(200):
        a = rng.uniform(-np.pi, np.pi, 3)
        b = a + rng.uniform(-0.3, 0.3, 3)
        moved = []
        for t in np.linspace(0, 1, 11):  # points along each link
            pa = ROBOT.link_segments(a)[:, 0] + t * np.diff(ROBOT.link_segments(a), axis=1)[:, 0]
            pb = ROBOT.link_segments(b)[:, 0] + t * np.diff(ROBOT.link_segments(b), axis=1)[:, 0]
            moved.append(np.linalg.norm(pa - pb, axis=1))
        assert np.all(np.max(moved, axis=0) <= arms @ np.abs(b - a) + 1e-12)
        tip = np.linalg.norm(ROBOT.forward_kinematics(a) - ROBOT.forward_kinematics(b))
        assert tip <= ROBOT.tip_lever_arms() @ np.abs(b - a) + 1e-12


def test_reach_is_an_annulus():
    arm = PlanarChain((1.0, 0.3, 0.2), ('a', 'b', 'c'))
    assert arm.can_reach(np.array([1.0, 0.0]))
    assert arm.can_reach(np.array([0.5, 0.0]))
    assert not arm.can_reach(np.array([0.49, 0.0]))   # inner radius 1.0 - 0.5
    assert not arm.can_reach(np.array([1.51, 0.0]))


def test_limits_and_periodic_joints():
    arm = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'), joint_limits=(None, (-1.0, 2.0), None))
    assert list(arm.periodic) == [True, False, True]
    assert np.allclose(arm.limits[1], [-1.0, 2.0])
    assert np.allclose(arm.limits[0], [-np.pi, np.pi])


def test_mismatched_names_are_rejected():
    with pytest.raises(InputError, match='robot.joint_names'):
        PlanarChain((1.0, 1.0), ('a',))


def test_compiled_kinematics_match_the_batched_functions(rng):
    for theta in rng.uniform(-np.pi, np.pi, (20, 3)):
        position, jacobian = chain_kinematics(ROBOT.kernel_kind, ROBOT.kernel_parameters, theta)
        assert np.allclose(position, ROBOT.forward_kinematics(theta), atol=1e-14)
        assert np.allclose(jacobian, ROBOT.jacobian(theta), atol=1e-14)
