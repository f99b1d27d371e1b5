"""Chains from DH tables against the standard-DH product of matrices, written out by hand."""

import numpy as np
import pytest
from ftplan_testing import WAM4, wam4

from ftplan_ros.core.io.scene_file import parse_scene
from ftplan_ros.core.model.dh import DHRow, chain_from_dh
from ftplan_ros.core.model.spatial import SpatialArm


def rot_z(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def rot_x(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]])


def translation(x, y, z):
    out = np.eye(4)
    out[:3, 3] = x, y, z
    return out


def dh_frames(rows, theta, tip):
    """Frames by hand: joint j turns about z of frame j-1 (the frame `before[j]`).

    Returns (before (n, 4, 4): frame j-1 turned by joint j, i.e. the link's frame; the
    frames after each row (n, 4, 4); the tool (4, 4)).
    """
    product = np.eye(4)
    before, after = [], []
    for row, angle in zip(rows, theta, strict=True):
        turned = product @ rot_z(angle + row.offset)
        before.append(turned)
        product = turned @ translation(0, 0, row.d) @ translation(row.a, 0, 0) @ rot_x(row.alpha)
        after.append(product)
    return np.array(before), np.array(after), product @ translation(*tip)


def random_table(rng, n):
    return [DHRow(a=rng.uniform(-0.3, 0.3), alpha=rng.uniform(-np.pi, np.pi),
                  d=rng.uniform(-0.3, 0.3), offset=rng.uniform(-np.pi, np.pi))
            for _ in range(n)]


WAM_ROWS = [DHRow(r['a'], r['alpha'], r['d'], limits=r.get('limits') and tuple(r['limits']))
            for r in WAM4['rows']]


@pytest.mark.parametrize('table', ['wam4', 'random5', 'random7'])
def test_frames_equal_the_product_of_dh_matrices(table, rng):
    if table == 'wam4':
        rows, tip = WAM_ROWS, WAM4['tip_offset']
    else:
        rows, tip = random_table(rng, int(table[-1])), rng.uniform(-0.2, 0.2, 3)
    arm = SpatialArm(chain_from_dh(rows, [f'j{k}' for k in range(len(rows))], 0.03, tip))
    for theta in rng.uniform(-np.pi, np.pi, (20, len(rows))):
        before, _, tool = dh_frames(rows, theta, tip)
        assert np.allclose(arm.tool_frames(theta), tool, atol=1e-12)
        assert np.allclose(arm.link_frames(theta)[1:], before, atol=1e-12)
        assert np.allclose(arm.link_frames(theta)[0], np.eye(4))


def test_the_wam_scene_robot_is_the_table():
    arm = wam4()
    assert arm.joint_names == ('wam_j1', 'wam_j2', 'wam_j3', 'wam_j4')
    theta = np.array([0.3, -0.4, 0.5, 1.2])
    assert np.allclose(arm.tool_frames(theta),
                       dh_frames(WAM_ROWS, theta, WAM4['tip_offset'])[2])
    # Zero angles: the shoulder at the origin, the elbow 0.55 m up and 0.045 m out, the
    # tool 0.35 m above the shoulder.
    assert np.allclose(arm.forward_kinematics(np.zeros(4)), [0.0, 0.0, 0.9])
    assert np.allclose(arm.skeleton(np.zeros(4))[1:4], 0.0)  # joints 1-3 at the shoulder
    assert np.allclose(arm.skeleton(np.zeros(4))[4], [0.045, 0.0, 0.55])


@pytest.mark.parametrize('table', ['wam4', 'random6'])
def test_links_are_capsules_from_joint_to_joint(table, rng):
    if table == 'wam4':
        rows, tip = WAM_ROWS, WAM4['tip_offset']
    else:
        rows, tip = random_table(rng, 6), rng.uniform(-0.2, 0.2, 3)
    radius = 0.04
    arm = SpatialArm(chain_from_dh(rows, [f'j{k}' for k in range(len(rows))], radius, tip))
    shapes = arm.collision_shapes
    assert [item.link for item in shapes] == list(range(1, len(rows) + 1))
    for theta in rng.uniform(-np.pi, np.pi, (5, len(rows))):
        before, after, tool = dh_frames(rows, theta, tip)
        frames = arm.link_frames(theta)
        for j, item in enumerate(shapes):
            start = before[j][:3, 3]
            end = (after[j] if j < len(rows) - 1 else tool)[:3, 3]
            pose = frames[item.link] @ item.placement
            assert item.shape.radius == radius
            if np.linalg.norm(end - start) < 1e-12:
                assert item.shape.kind == 'sphere'
                assert np.allclose(pose[:3, 3], start, atol=1e-12)
                continue
            assert item.shape.kind == 'capsule'
            assert item.shape.length == pytest.approx(np.linalg.norm(end - start))
            ends = pose[:3, 3] + np.outer([-0.5, 0.5], pose[:3, 2]) * item.shape.length
            assert np.allclose(ends, [start, end], atol=1e-12)


def test_a_spherical_shoulder_gives_spheres_between_its_joints():
    arm = wam4()
    kinds = [item.shape.kind for item in arm.collision_shapes]
    assert kinds == ['sphere', 'sphere', 'capsule', 'capsule']  # joints 1-3 meet


def test_joint_limits_and_offsets_from_the_scene(rng):
    rows = [{'a': 0.1, 'alpha': 0.5, 'd': 0.2, 'offset': 0.3, 'limits': [-1.0, 1.5]},
            {'a': 0.2, 'alpha': -0.4, 'd': 0.0},
            {'a': 0.0, 'alpha': 0.0, 'd': 0.1, 'offset': -0.2}]
    arm = parse_scene({'robot': {'type': 'dh', 'rows': rows, 'tip_offset': [0, 0, 0.05]}}).robot
    assert arm.joint_names == ('joint1', 'joint2', 'joint3')
    assert list(arm.periodic) == [False, True, True]
    assert np.allclose(arm.limits, [[-1.0, 1.5], [-np.pi, np.pi], [-np.pi, np.pi]])
    table = [DHRow(**row) for row in
             [{k: v for k, v in r.items() if k != 'limits'} for r in rows]]
    theta = rng.uniform(-1.0, 1.0, 3)
    assert np.allclose(arm.tool_frames(theta), dh_frames(table, theta, [0, 0, 0.05])[2])

