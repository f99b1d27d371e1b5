"""Chains from URDF against Pinocchio on the full model, and URDFs that must be refused.

Pinocchio is the reference: placements from `framesForwardKinematics` and frame
Jacobians in LOCAL_WORLD_ALIGNED on the URDF's full model (continuous joints as
(cos, sin), joints off the chain at 0), at random configurations.
"""

import re

import numpy as np
import pinocchio as pin
import pytest
import yaml
from ftplan_testing import (
    BOT_MESH_SCALE,
    BOT_TIP_OFFSET,
    ROBOTS,
    TETRAHEDRON,
    bot,
    bot_urdf,
    robot_config,
    write_binary_stl,
)

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.scene_file import load_scene, robot_from_urdf
from ftplan_ros.core.model.cover import assign_triangles
from ftplan_ros.core.model.robot import task_residuals
from ftplan_ros.core.model.urdf import chain_from_urdf

PEDESTAL = ('<link name="world"/>\n  <joint name="mount" type="fixed"><parent link="world"/>'
            '<child link="base"/><origin xyz="0.1 0.2 0.3" rpy="0.1 0 0.5"/></joint>\n  ')


def on_pedestal(xml: str) -> str:
    """The URDF with its base mounted on a fixed joint, off the root link `world`."""
    return xml.replace('<link name="base">', PEDESTAL + '<link name="base">', 1)


@pytest.fixture(scope='module', params=['panda', 'iiwa14', 'bot', 'bot-on-a-pedestal'])
def arm(request, bot_urdf_file):
    """(arm bound to poses, its URDF text, base link, tip link, tip offset, mesh folder)."""
    if request.param in ('panda', 'iiwa14'):
        robot = robot_config(request.param, 'pose')
        xml = (ROBOTS / f'{request.param}.urdf').read_text()
        return robot, xml, robot.link_names[0], robot.model.tool_frame, np.zeros(3), ROBOTS
    xml = bot_urdf_file.read_text()
    base = None
    if request.param == 'bot-on-a-pedestal':
        xml, base = on_pedestal(xml), 'base'
    robot = robot_from_urdf(xml, 'tcp', base, BOT_TIP_OFFSET,
                            mesh_dirs=[str(bot_urdf_file.parent)])
    return robot, xml, 'base', 'tcp', np.asarray(BOT_TIP_OFFSET), bot_urdf_file.parent


class Reference:
    """Pinocchio's full model of a URDF, with a frame at the arm's tool point."""

    def __init__(self, xml, base_link, tip_link, tip_offset):
        self.model = pin.buildModelFromXML(xml)
        self.data = self.model.createData()
        self.base = self.model.getFrameId(base_link)
        tip = self.model.getFrameId(tip_link)
        frame = self.model.frames[tip]
        self.tool = self.model.addFrame(pin.Frame(
            'ftplan_test_tool', frame.parentJoint, tip,
            frame.placement * pin.SE3(np.eye(3), np.asarray(tip_offset)),
            pin.FrameType.OP_FRAME))
        self.data = self.model.createData()

    def configuration(self, names, theta):
        """Full q: the chain's joints at θ, continuous ones as (cos, sin), the others at 0."""
        q = pin.neutral(self.model)
        for name, value in zip(names, theta, strict=True):
            joint = self.model.joints[self.model.getJointId(name)]
            if joint.nq == 2:
                q[joint.idx_q:joint.idx_q + 2] = np.cos(value), np.sin(value)
            else:
                q[joint.idx_q] = value
        return q

    def placements(self, names, links, theta):
        """Link frames (L, 4, 4) and tool frame (4, 4) in the base link's frame."""
        q = self.configuration(names, theta)
        pin.framesForwardKinematics(self.model, self.data, q)
        base = self.data.oMf[self.base]
        frames = [(base.actInv(self.data.oMf[self.model.getFrameId(link)])).homogeneous
                  for link in links]
        return np.array(frames), base.actInv(self.data.oMf[self.tool]).homogeneous

    def jacobian(self, names, theta):
        """The tool's frame Jacobian (6, n), LOCAL_WORLD_ALIGNED, rotated into the base frame."""
        q = self.configuration(names, theta)
        jacobian = pin.computeFrameJacobian(self.model, self.data, q, self.tool,
                                            pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        columns = [self.model.joints[self.model.getJointId(name)].idx_v for name in names]
        pin.framesForwardKinematics(self.model, self.data, q)
        to_base = self.data.oMf[self.base].rotation.T
        jacobian = jacobian[:, columns]
        return np.vstack([to_base @ jacobian[:3], to_base @ jacobian[3:]])


def test_frames_and_jacobians_equal_pinocchio(arm, rng):
    robot, xml, base, tip, offset, _ = arm
    reference = Reference(xml, base, tip, offset)
    names = robot.joint_names
    for theta in rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (50, robot.n_joints)):
        links, tool = reference.placements(names, robot.link_names, theta)
        assert np.allclose(robot.link_frames(theta), links, atol=1e-9, rtol=0.0)
        assert np.allclose(robot.tool_frames(theta), tool, atol=1e-9, rtol=0.0)
        _, jacobian = task_residuals(robot, robot.forward_kinematics(theta), theta)
        assert np.allclose(jacobian[0], reference.jacobian(names, theta), atol=1e-9, rtol=0.0)


def test_collision_shapes_are_posed_as_pinocchio_poses_the_geometry(arm, rng):
    """Every <collision> element, fixed and locked links' included, in Pinocchio's place."""
    robot, xml, base, tip, offset, meshes = arm
    reference = Reference(xml, base, tip, offset)
    geometry = pin.buildGeomFromUrdfString(reference.model, xml, pin.GeometryType.COLLISION,
                                           package_dirs=[str(meshes)])
    shapes = robot.collision_shapes
    assert len(shapes) == len(geometry.geometryObjects)
    geometry_data = geometry.createData()
    for theta in rng.uniform(robot.limits[:, 0], robot.limits[:, 1], (10, robot.n_joints)):
        q = reference.configuration(robot.joint_names, theta)
        pin.framesForwardKinematics(reference.model, reference.data, q)
        pin.updateGeometryPlacements(reference.model, reference.data, geometry, geometry_data)
        base_pose = reference.data.oMf[reference.base]
        frames = robot.link_frames(theta)
        for item, placed in zip(shapes, geometry_data.oMg, strict=True):
            expected = base_pose.actInv(placed).homogeneous
            assert np.allclose(frames[item.link] @ item.placement, expected, atol=1e-9)


def test_locked_fingers_ride_on_the_last_link(bot_urdf_file):
    robot = bot(bot_urdf_file)
    assert robot.joint_names == ('spin', 'tilt', 'elbow', 'wrist')
    assert robot.link_names == ('base', 'l1', 'l2', 'l3', 'hand')
    finger = [item for item in robot.collision_shapes
              if item.shape.kind == 'box' and item.shape.size == pytest.approx((0.02, 0.02, 0.04))]
    assert len(finger) == 1 and finger[0].link == 4
    # hand -> finger joint (0, 0.02, 0.06) at 0, then the box's origin (0, 0, 0.02)
    assert np.allclose(finger[0].placement, [[1, 0, 0, 0], [0, 1, 0, 0.02], [0, 0, 1, 0.08],
                                             [0, 0, 0, 1]], atol=1e-12)
    panda = robot_config('panda')
    fingers = [item for item in panda.collision_shapes
               if item.shape.kind == 'box'
               and item.shape.size == pytest.approx((0.028, 0.029, 0.062))]
    assert len(fingers) == 2 and {item.link for item in fingers} == {7}
    assert panda.n_joints == 7 and 'panda_finger_joint1' not in panda.joint_names


def test_fixed_joints_fold_their_links_into_the_chain(bot_urdf_file):
    robot = bot(bot_urdf_file)
    kinds = [(item.link, item.shape.kind) for item in robot.collision_shapes]
    assert kinds == [(0, 'box'), (1, 'cylinder'), (2, 'mesh'), (2, 'sphere'), (3, 'box'),
                     (4, 'box'), (4, 'box')]
    sphere = next(item for item in robot.collision_shapes if item.shape.kind == 'sphere')
    assert sphere.shape.radius == pytest.approx(0.05)
    assert np.allclose(sphere.placement[:3, 3], [0.0, 0.05, 0.25])  # the bracket's origin


def test_mesh_vertices_are_the_stl_file_scaled(bot_urdf_file):
    mesh = next(item.shape for item in bot(bot_urdf_file).collision_shapes
                if item.shape.kind == 'mesh')
    vertices, faces = TETRAHEDRON
    expected = vertices * np.asarray(BOT_MESH_SCALE)
    assert len(mesh.faces) == len(faces)
    # STL stores float32: compare to its precision.
    assert np.allclose(np.sort(mesh.vertices, axis=0), np.sort(expected, axis=0), atol=1e-7)
    assert len(np.unique(np.round(mesh.vertices, 6), axis=0)) == len(vertices)


def test_a_mesh_mirrored_by_a_negative_scale_is_covered_as_it_is(urdf_file):
    xml = bot_urdf().replace('scale="1.0 2.0 1.0"', 'scale="-1.0 2.0 1.0"')
    assert 'scale="-1.0 2.0 1.0"' in xml
    path = urdf_file(xml)
    robot = robot_from_urdf(xml, 'tcp', mesh_dirs=[str(path.parent)])
    mesh = next(item.shape for item in robot.collision_shapes if item.shape.kind == 'mesh')
    vertices, _ = TETRAHEDRON
    expected = vertices * np.array([-1.0, 2.0, 1.0])
    assert np.allclose(np.sort(mesh.vertices, axis=0), np.sort(expected, axis=0), atol=1e-7)
    assert assign_triangles(mesh.vertices[mesh.faces], list(mesh.cover.pieces)) is not None


def test_continuous_and_unaligned_joints(bot_urdf_file):
    robot = bot(bot_urdf_file)
    assert list(robot.periodic) == [True, False, False, False]
    assert np.allclose(robot.limits[0], [-np.pi, np.pi])
    assert np.allclose(robot.limits[1:], [[-2.0, 2.5], [-1.5, 1.5], [-2.0, 2.0]])
    assert np.allclose(robot.model.axes[1], [0.0, 0.6, 0.8])
    theta = np.array([0.4, 0.3, -0.2, 0.1])
    assert np.allclose(robot.tool_frames(theta), robot.tool_frames(theta + [2 * np.pi, 0, 0, 0]))


FLOATING = bot_urdf().replace('type="continuous"', 'type="floating"')
PLANAR = bot_urdf().replace('type="continuous"', 'type="planar"')
PRISMATIC = bot_urdf().replace('<joint name="elbow" type="revolute"',
                               '<joint name="elbow" type="prismatic"')


def with_mimic(follower: str, leader: str) -> str:
    """The bot's URDF with joint `follower` mimicking `leader` (multiplier 1, offset 0)."""
    xml = bot_urdf()
    at = xml.index(f'<joint name="{follower}"')
    end = xml.index('</joint>', at)
    return xml[:end] + f'<mimic joint="{leader}"/>' + xml[end:]


@pytest.mark.parametrize('xml, tip, base, field, words', [
    pytest.param('<robot name="x"><link name="a"></robot>', 'tcp', None, 'robot.file',
                 'not valid XML', id='malformed-xml'),
    pytest.param('<html><body/></html>', 'tcp', None, 'robot.file', 'not a URDF',
                 id='not-a-urdf'),
    pytest.param(bot_urdf(), 'tcp', 'plinth', 'robot.base_link', "no link 'plinth'",
                 id='missing-base-link'),
    pytest.param(bot_urdf(), 'gripper', None, 'robot.tip_link', "no link 'gripper'",
                 id='missing-tip-link'),
    pytest.param(PRISMATIC, 'tcp', None, 'robot.file', "'elbow'.* is prismatic",
                 id='prismatic-in-the-chain'),
    pytest.param(FLOATING, 'tcp', None, 'robot.file', "'spin'.* is floating", id='floating'),
    pytest.param(PLANAR, 'tcp', None, 'robot.file', "'spin'.* is floating or multi-axis",
                 id='planar'),
    pytest.param(bot_urdf().replace('<axis xyz="1 0 0"/>', '<axis xyz="0 0 0"/>'), 'tcp', None,
                 'robot.file', "'elbow'.* axis", id='zero-axis'),
    pytest.param(bot_urdf('missing.stl'), 'tcp', None, 'robot.file',
                 "link 'l2': collision mesh 'missing.stl' was not found; looked in",
                 id='missing-mesh-file'),
    pytest.param(bot_urdf('garbage.stl'), 'tcp', None, 'robot.file',
                 r"link 'l2': collision mesh /.*/garbage\.stl was found but could not be read "
                 r'\(.+\): give an STL, OBJ or COLLADA file$', id='garbage-mesh-file'),
    pytest.param(bot_urdf('empty.stl'), 'tcp', None, 'robot.file',
                 r"link 'l2': collision mesh /.*/empty\.stl was found but could not be read "
                 r'\(File is empty\)', id='empty-mesh-file'),
    pytest.param(with_mimic('elbow', 'tilt'), 'tcp', None, 'robot.file',
                 "'elbow' mimics 'tilt'.* coupled joints are not supported", id='mimic-in-chain'),
    pytest.param(with_mimic('finger_joint', 'wrist'), 'tcp', None, 'robot.file',
                 "'finger_joint' mimics 'wrist', and 'wrist' moves the chain",
                 id='mimic-of-a-chain-joint'),
    pytest.param(bot_urdf(), 'l1', 'l3', 'robot.base_link', "'l3' moves with joint 'elbow'",
                 id='base-below-the-tip'),
    pytest.param(bot_urdf(), 'base', None, 'robot.tip_link', "no joint moves 'base'",
                 id='tip-is-the-base'),
])
def test_bad_urdfs_give_one_line_naming_the_field(urdf_file, xml, tip, base, field, words):
    path = urdf_file(xml)
    scene = path.parent / 'scene.yaml'
    robot = {'type': 'urdf', 'file': path.name, 'tip_link': tip}
    if base is not None:
        robot['base_link'] = base
    scene.write_text(yaml.safe_dump({'robot': robot}))
    with pytest.raises(InputError, match=field):
        load_scene(scene)
    with pytest.raises(InputError, match=field) as error:
        robot_from_urdf(path.read_text(), tip, base, mesh_dirs=[str(path.parent)])
    assert '\n' not in str(error.value)
    assert re.search(words, str(error.value)), str(error.value)


def test_a_mimic_joint_off_the_chain_following_one_off_the_chain_is_accepted(urdf_file):
    """The two fingers of a gripper: both held still, so the coupling changes nothing."""
    xml = bot_urdf().replace(
        '<link name="finger">', '<link name="finger">\n  </link>\n  <joint name="finger2" '
        'type="prismatic"><parent link="hand"/><child link="finger_b"/><axis xyz="0 1 0"/>'
        '<limit lower="0" upper="0.04" effort="1" velocity="1"/><mimic joint="finger_joint"/>'
        '</joint>\n  <link name="finger_b">', 1)
    path = urdf_file(xml)
    arm = robot_from_urdf(xml, 'tcp', mesh_dirs=[str(path.parent)])
    assert arm.joint_names == ('spin', 'tilt', 'elbow', 'wrist')


def test_a_chain_longer_than_the_bound_is_refused_before_it_is_built():
    """Review of issue 33: a chain of 999 joints (270 kB, within every bound of the URDF's
    size) kept chain_from_urdf busy for more than 170 s; a planner's robot thread 104 s."""
    links = ''.join(f'<link name="l{k}"/>' for k in range(41))
    joints = ''.join(f'<joint name="j{k}" type="revolute"><parent link="l{k}"/><child '
                     f'link="l{k + 1}"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/><limit '
                     'lower="-1" upper="1" effort="1" velocity="1"/></joint>' for k in range(40))
    with pytest.raises(InputError, match=r"robot\.tip_link: 40 joints move 'l40' relative to "
                       r"'l0': ftplan plans for chains of at most 32"):
        chain_from_urdf(f'<robot name="long">{links}{joints}</robot>', 'l40')


def test_chain_from_urdf_names_its_caller(urdf_file):
    with pytest.raises(InputError, match=r'^arm\.tip_link'):
        chain_from_urdf(bot_urdf(), 'gripper', where='arm')


ONE_JOINT = '''<robot name="one"><link name="base"/><link name="arm">
  <collision><geometry><box size="0.2 0.2 0.1"/></geometry></collision></link>
  <link name="tip"/>
  <joint name="turn" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="tool" type="fixed"><parent link="arm"/><child link="tip"/>
    <origin xyz="0.5 0 0"/></joint></robot>'''


def test_a_chain_of_one_joint_with_geometry_on_one_link_is_read():
    """Its Jacobian came back (6,) and the self-collision pairs of one link failed to stack:
    both raised (IndexError, ValueError) instead of giving the arm."""
    robot = robot_from_urdf(ONE_JOINT, 'tip', task_kind='position')
    assert robot.joint_names == ('turn',)
    assert np.allclose(robot.model.axes, [[0.0, 0.0, 1.0]])
    assert robot.model.self_collision_pairs == ()
    assert np.allclose(robot.forward_kinematics(np.array([np.pi / 2])), [0.0, 0.5, 0.0])


def test_a_chain_whose_moving_links_have_no_collision_geometry_is_refused():
    """Review of issue 34 on vendor URDFs: a URDF without <collision> elements crashed
    the loader with numpy's 'zero-size array to reduction operation minimum'."""
    bare = ONE_JOINT.replace('<collision><geometry><box size="0.2 0.2 0.1"/></geometry>'
                             '</collision>', '')
    with pytest.raises(InputError, match=r"robot\.file: no link that the joints 'base' -> "
                       r"'tip' move has <collision> geometry"):
        robot_from_urdf(bare, 'tip', task_kind='position')


@pytest.mark.parametrize('scale, corner, words', [
    (3000.0, 0.0, r"is 600 m across \(at most 10 m\): is it in millimetres\? give "
                  r'scale="0.001 0.001 0.001"'),
    (1.0, np.nan, 'has a vertex that is not finite'),
    (1.0, np.inf, 'has a vertex that is not finite'),
], ids=['millimetres-as-metres', 'nan', 'inf'])
def test_a_mesh_too_wide_or_not_finite_is_refused_naming_link_and_file(urdf_file, scale, corner,
                                                                     words):
    """Such a mesh was cut into triangles of 2 cm until the memory ran out."""
    vertices, faces = TETRAHEDRON
    vertices = scale * vertices
    vertices[1, 0] += corner
    path = urdf_file(bot_urdf('wide.stl'))
    with np.errstate(invalid='ignore'):  # the normal of a face with an inf corner
        write_binary_stl(path.parent / 'wide.stl', vertices, faces)
    with pytest.raises(InputError, match=rf"^robot\.file: mesh {re.escape(str(path.parent))}"
                       rf"/wide\.stl of link 'l2' {words}"):
        robot_from_urdf(path.read_text(), 'tcp', mesh_dirs=[str(path.parent)])


def test_a_link_named_as_a_joint_gets_one_line_naming_it(urdf_file):
    """anymal.urdf names a link and a joint LF_HAA: Pinocchio's buildReducedModel raised
    'Several frames match the filter' through the loader."""
    xml = bot_urdf().replace('name="finger"', 'name="finger_joint"').replace(
        'link="finger"', 'link="finger_joint"')
    path = urdf_file(xml)
    with pytest.raises(InputError, match=r"robot\.file: cannot hold the joints off the chain "
                       r"still: .*link 'finger_joint' has the name of a joint: rename one"):
        robot_from_urdf(xml, 'tcp', mesh_dirs=[str(path.parent)])


def test_limits_of_a_whole_turn_rounded_up_are_a_whole_turn():
    """UR's URDFs write ±2π as ±6.28318530718, 4e-13 rad too wide: they were refused."""
    robot = robot_from_urdf(ONE_JOINT.replace('lower="-1" upper="1"', 'lower="-6.28318530718" '
                                              'upper="6.2832"'), 'tip', task_kind='position')
    assert robot.limits[0].tolist() == [-2.0 * np.pi, 2.0 * np.pi]
    with pytest.raises(InputError, match=r"^robot\.file: joint 'turn' has limits \[-6.3, 1.0\]"):
        robot_from_urdf(ONE_JOINT.replace('lower="-1"', 'lower="-6.3"'), 'tip')
