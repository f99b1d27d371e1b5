"""The `Robot` protocol: one conformance suite that every robot class passes.

Planar chains, DH and URDF chains bound to each kind of task, and a chain with frozen
joints (the curves of redundancy >= 2) are all checked against independent computations:
the tool frame, scipy's rotations, central finite differences, and points sampled on
every collision shape.
"""

import re
import xml.etree.ElementTree as ElementTree
from collections import defaultdict

import numpy as np
import pytest
from ftplan_testing import ROBOTS, WAM4, bot, robot_config, wam4
from scipy.spatial.transform import Rotation

from ftplan_ros.core.collision.checker import CollisionChecker
from ftplan_ros.core.errors import InputError
from ftplan_ros.core.model import kinematics
from ftplan_ros.core.model.geometry import KINDS
from ftplan_ros.core.model.robot import PlanarChain, robot_digest, task_errors, task_residuals
from ftplan_ros.core.model.spatial import SpatialArm
from ftplan_ros.core.model.task_space import POINT_SIZE, TASK_DIM
from ftplan_ros.core.planning.curves import FrozenJoints

PAPER = PlanarChain((1.0, 1.0, 1.0), ('joint1', 'joint2', 'joint3'))
LIMITED = PlanarChain((1.0, 0.7, 0.4), ('a', 'b', 'c'), link_radius=0.05,
                      joint_limits=(None, (-1.0, 2.0), (-2.5, 0.5)))
FROZEN = ((1, 4), (0.3, -0.5))  # panda_joint2 and panda_joint5 held at these angles [rad]


def urdf_limits(path, names):
    """Joint limits (lower, upper) [rad] or None (continuous) read from a URDF file."""
    joints = {joint.get('name'): joint for joint in ElementTree.parse(path).getroot().iter('joint')}
    out = []
    for name in names:
        joint = joints[name]
        limit = joint.find('limit')
        out.append(None if joint.get('type') == 'continuous'
                   else (float(limit.get('lower')), float(limit.get('upper'))))
    return out


PANDA_LIMITS = urdf_limits(ROBOTS / 'panda.urdf', [f'panda_joint{k}' for k in range(1, 8)])
IIWA_LIMITS = urdf_limits(ROBOTS / 'iiwa14.urdf', [f'iiwa_joint_{k}' for k in range(1, 8)])
BOT_JOINTS = ['spin', 'tilt', 'elbow', 'wrist']

# name: (build the robot from the test URDF's path, its joint limits or None if continuous)
CASES = {
    'planar-paper': (lambda urdf: PAPER, [None] * 3),
    'planar-limits-radius': (lambda urdf: LIMITED, list(LIMITED.joint_limits)),
    'dh-wam4-position': (lambda urdf: wam4('position'),
                         [row.get('limits') and tuple(row['limits']) for row in WAM4['rows']]),
    'panda-pose': (lambda urdf: robot_config('panda', 'pose'), PANDA_LIMITS),
    'panda-position': (lambda urdf: robot_config('panda', 'position'), PANDA_LIMITS),
    'panda-axis': (lambda urdf: robot_config('panda', 'axis'), PANDA_LIMITS),
    'iiwa-pose': (lambda urdf: robot_config('iiwa14', 'pose'), IIWA_LIMITS),
    'iiwa-position': (lambda urdf: robot_config('iiwa14', 'position'), IIWA_LIMITS),
    'iiwa-axis': (lambda urdf: robot_config('iiwa14', 'axis'), IIWA_LIMITS),
    'urdf-testbot-position': (lambda urdf: bot(urdf, 'position'), None),
    'urdf-testbot-pose': (lambda urdf: bot(urdf, 'pose'), None),
    'frozen-panda-position': (lambda urdf: FrozenJoints(robot_config('panda', 'position'),
                                                        *FROZEN),
                              [lim for j, lim in enumerate(PANDA_LIMITS) if j not in FROZEN[0]]),
}


@pytest.fixture(scope='module', params=list(CASES))
def case(request, bot_urdf_file):
    build, limits = CASES[request.param]
    if limits is None:
        limits = urdf_limits(bot_urdf_file, BOT_JOINTS)
    return build(bot_urdf_file), limits


@pytest.fixture(scope='module')
def robot(case):
    return case[0]


def sample(robot, rng, shape=()):
    """Configurations (*shape, n) [rad] drawn uniformly within the joint limits."""
    limits = robot.limits
    return rng.uniform(limits[:, 0], limits[:, 1], size=tuple(shape) + (robot.n_joints,))


def tool_frame(robot, thetas):
    """Tool frames (..., 4, 4), computed without the robot's forward kinematics when planar."""
    if isinstance(robot, FrozenJoints):
        return tool_frame(robot.robot, robot.expand(thetas))
    if isinstance(robot, SpatialArm):
        return robot.tool_frames(thetas)
    phi = np.cumsum(thetas, axis=-1)
    lengths = np.asarray(robot.link_lengths)
    out = np.zeros(np.shape(thetas)[:-1] + (4, 4))
    out[..., 0, 0] = out[..., 1, 1] = np.cos(phi[..., -1])
    out[..., 1, 0] = np.sin(phi[..., -1])
    out[..., 0, 1] = -np.sin(phi[..., -1])
    out[..., 2, 2] = out[..., 3, 3] = 1.0
    out[..., 0, 3] = np.sum(lengths * np.cos(phi), axis=-1)
    out[..., 1, 3] = np.sum(lengths * np.sin(phi), axis=-1)
    return out


def reference_errors(kind, x, frame):
    """Position [m] and orientation [rad] errors of a tool frame (4, 4) from task point x."""
    x = np.asarray(x, dtype=float)
    if kind == 'planar':
        return np.array([np.linalg.norm(x - frame[:2, 3]), 0.0])
    distance = np.linalg.norm(x[:3] - frame[:3, 3])
    if kind == 'position':
        return np.array([distance, 0.0])
    if kind == 'axis':
        cosine = frame[:3, 2] @ x[3:6] / np.linalg.norm(x[3:6])
        return np.array([distance, np.arccos(np.clip(cosine, -1.0, 1.0))])
    turn = Rotation.from_quat(x[3:7]) * Rotation.from_matrix(frame[:3, :3]).inv()
    return np.array([distance, turn.magnitude()])


def position_size(robot):
    return 2 if robot.task_kind == 'planar' else 3


def test_sizes_and_output_shapes(robot, rng):
    n, links, kind = robot.n_joints, len(robot.link_names), robot.task_kind
    assert len(robot.joint_names) == n == len(set(robot.joint_names))
    assert robot.task_dim == TASK_DIM[kind]
    assert robot.limits.shape == (n, 2)
    assert robot.periodic.shape == (n,) and robot.periodic.dtype == bool
    assert robot.frame_lever_arms().shape == (links, n)
    assert robot.tip_lever_arms().shape == (n,)
    assert robot.kernel_parameters.ndim == 1
    x = robot.forward_kinematics(sample(robot, rng))
    assert x.shape == (POINT_SIZE[kind],)
    for batch in [(), (5,), (2, 3)]:
        thetas = sample(robot, rng, batch)
        assert robot.forward_kinematics(thetas).shape == batch + (POINT_SIZE[kind],)
        assert robot.link_frames(thetas).shape == batch + (links, 4, 4)
        skeleton = robot.skeleton(thetas)
        assert skeleton.shape[:len(batch)] == batch and skeleton.shape[-1] == 3
        assert skeleton.shape[-2] >= 2
        assert task_errors(robot, x, thetas).shape == batch + (2,)
    residuals, jacobians = task_residuals(robot, x, sample(robot, rng, (6,)))
    assert residuals.shape == (6, robot.task_dim)
    assert jacobians.shape == (6, robot.task_dim, n)
    residuals, jacobians = task_residuals(robot, x, sample(robot, rng))
    assert residuals.shape == (1, robot.task_dim) and jacobians.shape == (1, robot.task_dim, n)
    assert isinstance(robot.can_reach(x), bool)


def test_forward_kinematics_is_the_task_point_of_the_tool(robot, rng):
    thetas = sample(robot, rng, (30,))
    frames = tool_frame(robot, thetas)
    x = robot.forward_kinematics(thetas)
    dim = position_size(robot)
    assert np.allclose(x[:, :dim], frames[:, :dim, 3], atol=1e-12)
    if robot.task_kind == 'axis':
        assert np.allclose(x[:, 3:], frames[:, :3, 2], atol=1e-12)
    if robot.task_kind == 'pose':
        assert np.allclose(np.linalg.norm(x[:, 3:], axis=1), 1.0, atol=1e-12)
        assert np.allclose(Rotation.from_quat(x[:, 3:]).as_matrix(), frames[:, :3, :3],
                           atol=1e-12)
    # The skeleton: from the base through every link's origin (its joint) to the tool.
    skeleton = robot.skeleton(thetas)
    links = robot.link_frames(thetas)
    assert np.allclose(skeleton[:, 0], 0.0, atol=1e-15)
    assert np.allclose(skeleton[:, -1, :dim], x[:, :dim], atol=1e-12)
    gaps = np.linalg.norm(links[:, 1:, None, :3, 3] - skeleton[:, None, :, :], axis=-1)
    assert np.all(gaps.min(axis=2) < 1e-12)
    if robot.task_kind == 'planar':
        assert np.all(skeleton[..., 2] == 0.0)


def test_jacobian_is_the_derivative_of_the_residual(robot, rng):
    """Newton's J solves J δθ = residual: it is minus the residual's derivative.

    For a pose the residual's rotation part is log(R_g R(θ)^T), whose derivative is -J_w
    (the world angular velocity) at the goal: the pose's goal is the tool's own pose there.
    """
    n, h = robot.n_joints, 1e-6
    for theta in sample(robot, rng, (8,)):
        targets = [robot.forward_kinematics(theta)]
        if robot.task_kind != 'pose':
            targets.append(robot.forward_kinematics(sample(robot, rng)))
        for x in targets:
            _, jacobian = task_residuals(robot, x, theta)
            plus = task_residuals(robot, x, theta + h * np.eye(n))[0]  # (n, m)
            minus = task_residuals(robot, x, theta - h * np.eye(n))[0]
            numeric = -(plus - minus).T / (2.0 * h)
            assert np.allclose(jacobian[0], numeric, atol=1e-7, rtol=0.0)
        residual, _ = task_residuals(robot, targets[0], theta)
        assert np.allclose(residual, 0.0, atol=1e-12)


def test_jacobian_predicts_how_the_tool_moves(robot, rng):
    """J δ against the tool's change of position and orientation for a tiny step δ."""
    dim = position_size(robot)
    for theta in sample(robot, rng, (8,)):
        delta = 1e-6 * rng.normal(size=robot.n_joints)
        _, jacobian = task_residuals(robot, robot.forward_kinematics(theta), theta)
        before, after = tool_frame(robot, theta), tool_frame(robot, theta + delta)
        predicted = jacobian[0] @ delta
        assert np.allclose(after[:dim, 3] - before[:dim, 3], predicted[:dim], atol=1e-10,
                           rtol=0.0)
        turn = Rotation.from_matrix(after[:3, :3] @ before[:3, :3].T).as_rotvec()
        if robot.task_kind == 'pose':
            assert np.allclose(turn, predicted[3:], atol=1e-10, rtol=0.0)
        if robot.task_kind == 'axis':  # the rows measure the axis's turn in two directions
            moved = np.linalg.norm(after[:3, 2] - before[:3, 2])
            assert np.linalg.norm(predicted[3:]) == pytest.approx(moved, abs=1e-10)


def test_task_errors_vanish_at_the_tool_and_match_an_independent_computation(robot, rng):
    thetas = sample(robot, rng, (20,))
    own = np.array([task_errors(robot, x, theta)
                    for x, theta in zip(robot.forward_kinematics(thetas), thetas, strict=True)])
    assert np.all(own[:, 0] < 1e-12)
    assert np.all(own[:, 1] < 1e-7)  # arccos of a cosine rounded to 1 is ~1e-8
    frames = tool_frame(robot, thetas)
    for x in robot.forward_kinematics(sample(robot, rng, (5,))):
        errors = task_errors(robot, x, thetas)
        expected = np.array([reference_errors(robot.task_kind, x, frame) for frame in frames])
        assert np.allclose(errors[:, 0], expected[:, 0], atol=1e-12)
        assert np.allclose(errors[:, 1], expected[:, 1], atol=1e-7)


def shape_points(item, rng):
    """Points (P, 3) in a shape's link frame whose motion its channel's lever arms bound.

    Spheres and capsules: their cores (their distances are the cores' minus the radius);
    other shapes: corners, rims, vertices and random points on their surfaces.
    """
    shape = item.shape
    if shape.kind == 'sphere':
        local = np.zeros((1, 3))
    elif shape.kind == 'capsule':
        local = np.outer(np.linspace(-0.5, 0.5, 9) * shape.length, [0.0, 0.0, 1.0])
    elif shape.kind == 'box':
        half = 0.5 * np.asarray(shape.size)
        corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
        faces = rng.uniform(-1.0, 1.0, (30, 3))
        faces[np.arange(30), rng.integers(3, size=30)] = rng.choice([-1.0, 1.0], 30)
        local = np.vstack([corners, faces]) * half
    elif shape.kind == 'cylinder':
        angle = rng.uniform(0.0, 2.0 * np.pi, 40)
        z = np.concatenate([np.full(20, -0.5), np.full(20, 0.5)]) * shape.length
        rim = np.stack([shape.radius * np.cos(angle), shape.radius * np.sin(angle), z], axis=1)
        side = rng.uniform(-0.5, 0.5, 20) * shape.length
        local = np.vstack([rim, np.stack([shape.radius * np.cos(angle[:20]),
                                          shape.radius * np.sin(angle[:20]), side], axis=1)])
    else:
        weights = rng.dirichlet(np.ones(3), size=len(shape.faces))
        local = np.vstack([shape.vertices,
                           np.einsum('fk,fkd->fd', weights, shape.vertices[shape.faces])])
    return local @ item.placement[:3, :3].T + item.placement[:3, 3]


def channel_shapes(robot, checker):
    """Each channel's shapes as ((link, k), ...) from its name: link's k-th collision shape."""
    out = []
    for name in checker.channel_names:
        parts = []
        for part in name.split(' / '):
            link, k = re.fullmatch(r'(.+)\[(\d+)\]', part).groups()
            parts.append((robot.link_names.index(link), int(k)))
        out.append(tuple(parts))
    return out


def moved(points, before, after):
    """Largest distance [m] points (P, 3) move when their frame goes from `before` to `after`."""
    return float(np.max(np.linalg.norm(points @ (after[:3, :3] - before[:3, :3]).T
                                       + after[:3, 3] - before[:3, 3], axis=1)))


def test_lever_arms_bound_how_far_every_shape_moves(robot, rng):
    """Every sampled point of every channel's shape moves at most Σ_a arms[c, a] |Δθ_a|.

    A pair channel's bound is on the motion of its second shape relative to the first
    shape's link. The tool point moves at most tip_lever_arms · |Δθ|.
    """
    checker = CollisionChecker(robot, [])
    arms = checker.lever_arms()
    assert arms.shape == (checker.n_channels, robot.n_joints) and np.all(arms >= 0.0)
    number = defaultdict(int)
    points = {}
    for item in robot.collision_shapes:
        points[item.link, number[item.link]] = shape_points(item, rng)
        number[item.link] += 1
    channels = channel_shapes(robot, checker)
    assert len(channels) == checker.n_channels
    too_far = []
    for _ in range(25):
        theta = sample(robot, rng)
        step = rng.uniform(-0.3, 0.3, robot.n_joints)
        before, after = robot.link_frames(theta), robot.link_frames(theta + step)
        for c, shapes in enumerate(channels):
            bound = arms[c] @ np.abs(step) + 1e-12
            if len(shapes) == 1:
                (link, k), = shapes
                distance = moved(points[link, k], before[link], after[link])
            else:
                (first, _), (link, k) = shapes
                distance = moved(points[link, k], np.linalg.inv(before[first]) @ before[link],
                                 np.linalg.inv(after[first]) @ after[link])
            if distance > bound:
                too_far.append(f'{checker.channel_names[c]}: moved {distance:.4f} m > bound '
                               f'{bound:.4f} m for step {np.round(step, 3).tolist()}')
        tip = np.linalg.norm(tool_frame(robot, theta + step)[:3, 3]
                             - tool_frame(robot, theta)[:3, 3])
        assert tip <= robot.tip_lever_arms() @ np.abs(step) + 1e-12
    assert not too_far, f'{len(too_far)} violations, e.g. ' + '; '.join(too_far[:3])


def test_frame_lever_arms_vanish_where_a_joint_does_not_turn_the_link(robot, rng):
    arms = robot.frame_lever_arms()
    assert np.all(arms >= 0.0) and np.all(arms[0] == 0.0)
    theta = sample(robot, rng)
    frames = robot.link_frames(theta)
    for a in range(robot.n_joints):
        turned = robot.link_frames(theta + 0.5 * np.eye(robot.n_joints)[a])
        still = np.all(np.abs(turned - frames) < 1e-12, axis=(1, 2))
        assert still[0]
        assert np.all(arms[still, a] == 0.0), f'joint {a} turns none of {np.flatnonzero(still)}'


def test_limits_and_periodic_joints(case):
    robot, expected = case
    assert list(robot.periodic) == [lim is None for lim in expected]
    for j, lim in enumerate(expected):
        assert tuple(robot.limits[j]) == pytest.approx((-np.pi, np.pi) if lim is None else lim)


def test_link_frames_are_rigid_and_start_at_the_base(robot, rng):
    frames = robot.link_frames(sample(robot, rng, (10,)))
    assert np.array_equal(frames[:, 0], np.broadcast_to(np.eye(4), (10, 4, 4)))
    rotations = frames[..., :3, :3]
    assert np.allclose(rotations @ np.swapaxes(rotations, -1, -2), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(rotations), 1.0, atol=1e-12)
    assert np.all(frames[..., 3, :] == [0.0, 0.0, 0.0, 1.0])


def test_kernel_parameters_give_the_residuals_of_task_residuals(robot, rng):
    thetas = sample(robot, rng, (5,))
    x = np.asarray(robot.forward_kinematics(sample(robot, rng)), dtype=float)
    residuals, jacobians = task_residuals(robot, x, thetas)
    for k, theta in enumerate(thetas):
        residual, jacobian = kinematics.task_residual(robot.kernel_kind, robot.kernel_parameters,
                                                   x, np.ascontiguousarray(theta))
        assert np.array_equal(residual, residuals[k])
        assert np.array_equal(jacobian, jacobians[k])


def test_collision_shapes_and_self_collision_pairs_are_well_formed(robot):
    links = len(robot.link_names)
    with_geometry = {item.link for item in robot.collision_shapes}
    for item in robot.collision_shapes:
        assert 0 <= item.link < links and item.shape.kind in KINDS
        assert item.placement.shape == (4, 4)
        rotation = item.placement[:3, :3]
        assert np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-12)
        assert np.all(item.placement[3] == [0.0, 0.0, 0.0, 1.0])
        assert item.shape.radius >= 0.0 and item.shape.length >= 0.0
        assert min(item.shape.size) >= 0.0
    pairs = robot.self_collision_pairs
    assert len(set(pairs)) == len(pairs)
    for a, b in pairs:
        assert 0 <= a < b < links and {a, b} <= with_geometry


def test_reach_holds_every_tool_point_and_not_a_far_one(robot, rng):
    for x in robot.forward_kinematics(sample(robot, rng, (20,))):
        assert robot.can_reach(x)
        far = x.copy()
        far[:position_size(robot)] = 100.0
        assert not robot.can_reach(far)


# Planar chains --------------------------------------------------------------------------

def test_planar_forward_kinematics_by_hand(rng):
    arm = PlanarChain((1.0, 0.7, 0.4), ('a', 'b', 'c'), link_radius=0.05)
    assert np.allclose(arm.forward_kinematics([0.0, 0.0, 0.0]), [2.1, 0.0])
    assert np.allclose(arm.forward_kinematics([np.pi / 2, 0.0, 0.0]), [0.0, 2.1])
    assert np.allclose(arm.forward_kinematics([0.0, np.pi / 2, -np.pi / 2]), [1.4, 0.7])
    thetas = rng.uniform(-np.pi, np.pi, (50, 3))
    assert np.allclose(arm.forward_kinematics(thetas), arm.joint_positions(thetas)[:, -1])


def test_planar_reach_is_an_annulus():
    arm = PlanarChain((1.0, 0.3, 0.2), ('a', 'b', 'c'))
    assert arm.can_reach(np.array([1.0, 0.0]))
    assert arm.can_reach(np.array([0.5, 0.0]))
    assert not arm.can_reach(np.array([0.49, 0.0]))   # inner radius 1.0 - 0.5
    assert not arm.can_reach(np.array([1.51, 0.0]))


def test_planar_lever_arms_by_hand():
    arm = PlanarChain((1.0, 0.7, 0.4), ('a', 'b', 'c'))
    assert np.allclose(arm.frame_lever_arms(), [[0, 0, 0], [0, 0, 0], [1.0, 0, 0],
                                                [1.7, 0.7, 0]])
    assert np.allclose(arm.tip_lever_arms(), [2.1, 1.1, 0.4])


def test_planar_mismatched_names_and_limits_are_rejected():
    with pytest.raises(InputError, match='robot.joint_names'):
        PlanarChain((1.0, 1.0), ('a',))
    with pytest.raises(InputError, match='robot.joint_limits'):
        PlanarChain((1.0, 1.0), ('a', 'b'), joint_limits=((0.0, 1.0),))


@pytest.mark.parametrize('radius', [-0.5, float('nan'), float('inf'), True, '0.1'])
def test_a_planar_chain_refuses_a_link_radius_that_is_not_a_finite_length(radius):
    """Built in Python, not parsed: a negative radius would read as extra clearance."""
    with pytest.raises(InputError, match='robot.link_radius'):
        PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'), link_radius=radius)


def test_the_robot_digest_names_the_model_and_nothing_else():
    """Issue 33: a plan for a robot whose model changed (same joint names) must be told."""
    panda = robot_config('panda')
    assert robot_digest(panda) == robot_digest(robot_config('panda'))     # stable
    assert robot_digest(panda.with_task_kind('position')) == robot_digest(panda)
    assert robot_digest(PAPER) == robot_digest(PlanarChain((1.0, 1.0, 1.0), PAPER.joint_names))
    others = [PlanarChain((1.0, 1.0, 1.1), PAPER.joint_names),          # a link length
              PlanarChain((1.0, 1.0, 1.0), PAPER.joint_names, link_radius=0.01),  # a shape
              PlanarChain((1.0, 1.0, 1.0), PAPER.joint_names,
                          joint_limits=(None, None, (-3.0, 3.0))),       # a limit
              PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c')),             # the names
              robot_config('iiwa14')]
    digests = {robot_digest(robot) for robot in [PAPER, *others]}
    assert len(digests) == len(others) + 1
    assert all(len(d) == 12 and int(d, 16) >= 0 for d in digests)
