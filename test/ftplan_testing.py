"""Test helpers shared by the unit tests: the repository's paths, scenes and robots.

(Not in conftest.py: test/ros has a conftest.py of its own, and the two would clash as
modules named `conftest`.)
"""

import struct
import subprocess
import sys
from functools import cache
from pathlib import Path

import numpy as np
import yaml
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import ConvexHull

from ftplan_ros.core.collision.checker import CollisionChecker
from ftplan_ros.core.io.scene_file import parse_scene
from ftplan_ros.core.model.scene import Scene
from ftplan_ros.core.paper.manifolds import trace_self_motion_manifolds

REPO = Path(__file__).resolve().parents[1]
SCENES = REPO / 'config' / 'scenes'
ROBOTS = REPO / 'config' / 'robots'
TEST_SCENES = REPO / 'test' / 'ros' / 'scenes'  # the tests' own scenes


def ftplan(*args, cwd=None) -> subprocess.CompletedProcess:
    """Run the `ftplan` command with `args` as a user would; its output is text."""
    return subprocess.run([sys.executable, '-m', 'ftplan_ros.cli', *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=300)


def one_line_error(run: subprocess.CompletedProcess, field: str) -> None:
    """The CLI's bad-input answer: exit 2 and one line naming the field, no traceback."""
    assert run.returncode == 2, run.stderr
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith('ftplan: error: ') and field in lines[0], \
        run.stderr


def paper_scene(start=(2.0, 0.0), obstacles=(), tolerance=0.01) -> Scene:
    """The paper's 3R arm (links of 1 m) moving its tip from `start` to [1, 0]."""
    return parse_scene({
        'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]},
        'obstacles': [{'type': 'sphere', 'center': list(c), 'radius': r} for c, r in obstacles],
        'task': {'start': list(start), 'goal': [1.0, 0.0], 'goal_tolerance': tolerance}})


def clearest_start(scene: Scene) -> np.ndarray:
    """The sim's default start (n,) [rad]: the clearest traced point of M_s."""
    checker = CollisionChecker(scene.robot, scene.obstacles)
    points = np.vstack([b.points for b in trace_self_motion_manifolds(
        scene.robot, np.array(scene.task.start), np.random.default_rng(0))])
    return points[int(np.argmax(checker.min_clearance(points)))]


def jacobian(robot, theta):
    """The task Jacobian (m, n) of a robot at θ (n,) [rad], as the planner computes it."""
    from ftplan_ros.core.model.robot import task_residuals
    theta = np.asarray(theta, dtype=float)
    return task_residuals(robot, robot.forward_kinematics(theta), theta)[1][0]


def triangle_points(corners, count):
    """Barycentric grid points (m, n) of a triangle (3, n) or triangles (T, 3, n), corners
    included: `count` steps along each side. Dense samples to check a certificate against."""
    weights = np.array([(i, j, count - i - j) for i in range(count + 1)
                        for j in range(count + 1 - i)], dtype=float) / count
    corners = np.asarray(corners, dtype=float)
    return np.einsum('wk,...kn->...wn', weights, corners).reshape(-1, corners.shape[-1])


def within_limits(robot, thetas) -> bool:
    """Whether configurations (..., n) [rad] keep the robot's joint limits (within 1e-9 rad)."""
    limits = robot.limits
    return np.all((thetas >= limits[:, 0] - 1e-9) & (thetas <= limits[:, 1] + 1e-9)
                  | robot.periodic)


@cache
def robot_config(name: str, task_kind: str = 'pose'):
    """The robot of config/robots/<name>.yaml, bound to `task_kind` when it is spatial."""
    robot = parse_scene({'robot': f'{name}.yaml'}, directory=ROBOTS).robot
    return robot if robot.task_kind == 'planar' else robot.with_task_kind(task_kind)


# bench/crowded.py's settings for tests: up to six disks, each draw proved on 64^3 cells.
CROWDED = {'disks': 6, 'attempts': 12, 'cells': 64}


@cache
def make_crowded(seed: int) -> Scene:
    """The crowded scene (bench/crowded.py) of `seed` with the settings CROWDED."""
    from ftplan_ros.bench.crowded import crowded_scene
    return crowded_scene(np.random.default_rng(seed), **CROWDED)


# The Barrett WAM's first four joints (standard DH): a spherical shoulder and an elbow.
WAM4 = {
    'type': 'dh', 'link_radius': 0.04, 'tip_offset': [0.0, 0.0, 0.35],
    'joint_names': ['wam_j1', 'wam_j2', 'wam_j3', 'wam_j4'],
    'rows': [{'a': 0.0, 'alpha': -np.pi / 2, 'd': 0.0},
             {'a': 0.0, 'alpha': np.pi / 2, 'd': 0.0, 'limits': [-2.0, 2.0]},
             {'a': 0.045, 'alpha': -np.pi / 2, 'd': 0.55, 'limits': [-2.8, 2.8]},
             {'a': -0.045, 'alpha': np.pi / 2, 'd': 0.0, 'limits': [-0.9, 3.1]}],
}


@cache
def wam4(task_kind: str = 'position'):
    """The 4-DOF WAM of `WAM4` (joint 1 without limits), bound to `task_kind`."""
    return parse_scene({'robot': WAM4}).robot.with_task_kind(task_kind)


TETRAHEDRON = (np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]]),
               np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
CUBE = (np.array([[x, y, z] for x in (-0.05, 0.05) for y in (-0.05, 0.05)
                  for z in (-0.05, 0.05)]),
        np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]))


def capsule_hull(length: float = 0.2, radius: float = 0.05, points: int = 152, seed: int = 0,
                 ) -> tuple[np.ndarray, np.ndarray]:
    """A convex mesh (vertices, faces) like a robot link's collision hull, along z [m].

    The hull of `points` random points on a capsule's surface (core from z = 0 to
    `length`): 2 points - 4 triangles (300 for 152 points), like the Panda's meshes.
    """
    rng = np.random.default_rng(seed)
    directions = rng.normal(size=(points, 3))
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    vertices = radius * directions
    tube = rng.random(points) < 0.6  # on the tube, else on a cap
    radial = directions[tube, :2] / np.linalg.norm(directions[tube, :2], axis=1)[:, None]
    vertices[tube, :2] = radius * radial
    vertices[tube, 2] = rng.uniform(0.0, length, tube.sum())
    vertices[~tube & (directions[:, 2] > 0), 2] += length
    hull = ConvexHull(vertices)
    return vertices[hull.vertices], _reindex(hull.simplices, hull.vertices)


def torus(major: float = 0.06, minor: float = 0.02, around: int = 24, across: int = 12,
          ) -> tuple[np.ndarray, np.ndarray]:
    """A non-convex mesh (vertices, faces): a torus about z [m], 2 * around * across triangles."""
    u, v = np.meshgrid(np.arange(around) * 2 * np.pi / around,
                       np.arange(across) * 2 * np.pi / across, indexing='ij')
    vertices = np.stack([(major + minor * np.cos(v)) * np.cos(u),
                         (major + minor * np.cos(v)) * np.sin(u), minor * np.sin(v)],
                        axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(around), np.arange(across), indexing='ij')
    a, b = i * across + j, ((i + 1) % around) * across + j
    c, d = ((i + 1) % around) * across + (j + 1) % across, i * across + (j + 1) % across
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                            np.stack([a, c, d], -1).reshape(-1, 3)])
    return vertices, faces


def _reindex(faces: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """Faces over the points `kept` (their indices into the old points), renumbered."""
    new = np.full(kept.max() + 1, -1)
    new[kept] = np.arange(len(kept))
    return new[faces]


def write_binary_stl(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Write a triangle mesh as a binary STL file (80-byte header, 50 bytes a triangle)."""
    with open(path, 'wb') as out:
        out.write(b'ftplan test mesh'.ljust(80, b' '))
        out.write(struct.pack('<I', len(faces)))
        for face in faces:
            a, b, c = (np.asarray(vertices[k], dtype=float) for k in face)
            normal = np.cross(b - a, c - a)
            normal /= np.linalg.norm(normal)
            out.write(struct.pack('<12fH', *normal, *a, *b, *c, 0))


def write_obj(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    """Write a triangle mesh as a Wavefront OBJ file (1-based face indices)."""
    lines = [f'v {x:.17g} {y:.17g} {z:.17g}' for x, y, z in np.asarray(vertices, dtype=float)]
    lines += [f'f {a + 1} {b + 1} {c + 1}' for a, b, c in faces]
    path.write_text('# ftplan test mesh\n' + '\n'.join(lines) + '\n')


def write_collada(path: Path, vertices: np.ndarray, faces: np.ndarray, unit: float = 1.0) -> None:
    """Write a triangle mesh as a COLLADA file whose coordinates are in units of `unit` [m]."""
    numbers = ' '.join(f'{v:.17g}' for v in (np.asarray(vertices, dtype=float) / unit).ravel())
    indices = ' '.join(str(k) for k in np.asarray(faces).ravel())
    path.write_text(f'''<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="unit" meter="{unit:g}"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="m"><mesh>
    <source id="p"><float_array id="pa" count="{3 * len(vertices)}">{numbers}</float_array>
      <technique_common><accessor source="#pa" count="{len(vertices)}" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="{len(faces)}"><input semantic="VERTEX" source="#v" offset="0"/>
      <p>{indices}</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#m"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
''')


def write_mesh(path: Path, vertices: np.ndarray, faces: np.ndarray) -> Path:
    """Write a triangle mesh in the format its suffix names (.stl, .obj, .dae); return `path`."""
    {'.stl': write_binary_stl, '.obj': write_obj, '.dae': write_collada}[path.suffix](
        path, vertices, faces)
    return path


def convex_hull(points: int = 152, axes=(0.06, 0.04, 0.1)):
    """A convex mesh of 2 * points - 4 triangles (300 for 152 points) [m], faces outward.

    Its vertices lie on an ellipsoid of semi-axes `axes`, spread as a Fibonacci lattice.
    """
    from scipy.spatial import ConvexHull
    k = np.arange(points) + 0.5
    polar, azimuth = np.arccos(1.0 - 2.0 * k / points), np.pi * (1.0 + 5.0 ** 0.5) * k
    vertices = np.stack([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth),
                         np.cos(polar)], axis=1) * np.asarray(axes)
    faces = ConvexHull(vertices).simplices
    corners = vertices[faces]
    outward = np.einsum('ij,ij->i', np.cross(corners[:, 1] - corners[:, 0],
                                             corners[:, 2] - corners[:, 0]), corners[:, 0]) > 0
    return vertices, np.where(outward[:, None], faces, faces[:, ::-1])


# A 4-joint arm with what URDFs have: a continuous joint, an axis not along x, y or z,
# fixed joints folded in (a bracket with a sphere, the TCP), a finger on a prismatic joint
# off the chain, and a link whose collision geometry is a mesh (scaled).
BOT_MESH_SCALE = (1.0, 2.0, 1.0)
BOT_MESH_ORIGIN = ((0.0, 0.0, 0.1), (0.1, 0.2, 0.3))  # xyz, rpy in link l2
BOT_TIP_OFFSET = (0.01, 0.0, 0.02)


def bot_urdf(mesh: str = 'tet.stl') -> str:
    """The test robot's URDF, its mesh link pointing at the file `mesh`."""
    (mx, my, mz), (mr, mp, myaw) = BOT_MESH_ORIGIN
    scale = ' '.join(str(v) for v in BOT_MESH_SCALE)
    return f'''<?xml version="1.0"?>
<robot name="testbot">
  <link name="base">
    <collision><origin xyz="0 0 0.05"/><geometry><box size="0.2 0.2 0.1"/></geometry></collision>
  </link>
  <joint name="spin" type="continuous">
    <parent link="base"/><child link="l1"/><origin xyz="0 0 0.1" rpy="0 0 0.3"/>
    <axis xyz="0 0 1"/>
  </joint>
  <link name="l1">
    <collision><origin xyz="0 0 0.15"/><geometry><cylinder radius="0.04" length="0.3"/></geometry>
    </collision>
  </link>
  <joint name="tilt" type="revolute">
    <parent link="l1"/><child link="l2"/><origin xyz="0.02 0 0.3" rpy="0.2 -0.1 0.4"/>
    <axis xyz="0 0.6 0.8"/><limit lower="-2.0" upper="2.5" effort="1" velocity="1"/>
  </joint>
  <link name="l2">
    <collision><origin xyz="{mx} {my} {mz}" rpy="{mr} {mp} {myaw}"/>
      <geometry><mesh filename="{mesh}" scale="{scale}"/></geometry></collision>
  </link>
  <joint name="bracket" type="fixed">
    <parent link="l2"/><child link="l2b"/><origin xyz="0 0.05 0.25" rpy="0 0.5 0"/>
  </joint>
  <link name="l2b"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <joint name="elbow" type="revolute">
    <parent link="l2b"/><child link="l3"/><origin xyz="0 0 0.1"/>
    <axis xyz="1 0 0"/><limit lower="-1.5" upper="1.5" effort="1" velocity="1"/>
  </joint>
  <link name="l3">
    <collision><origin xyz="0 0 0.12"/><geometry><box size="0.05 0.06 0.24"/></geometry>
    </collision>
  </link>
  <joint name="wrist" type="revolute">
    <parent link="l3"/><child link="hand"/><origin xyz="0 0 0.24"/>
    <axis xyz="0 1 0"/><limit lower="-2.0" upper="2.0" effort="1" velocity="1"/>
  </joint>
  <link name="hand">
    <collision><origin xyz="0 0 0.03"/><geometry><box size="0.08 0.04 0.06"/></geometry>
    </collision>
  </link>
  <joint name="tcp_joint" type="fixed">
    <parent link="hand"/><child link="tcp"/><origin xyz="0 0 0.1" rpy="0 0 0.7"/>
  </joint>
  <link name="tcp"/>
  <joint name="finger_joint" type="prismatic">
    <parent link="hand"/><child link="finger"/><origin xyz="0 0.02 0.06"/>
    <axis xyz="0 1 0"/><limit lower="0" upper="0.04" effort="1" velocity="1"/>
  </joint>
  <link name="finger">
    <collision><origin xyz="0 0 0.02"/><geometry><box size="0.02 0.02 0.04"/></geometry>
    </collision>
  </link>
</robot>
'''


def write_bot(directory: Path) -> Path:
    """Write the test robot's URDF and its mesh (a tetrahedron) into `directory`."""
    write_binary_stl(directory / 'tet.stl', *TETRAHEDRON)
    path = directory / 'testbot.urdf'
    path.write_text(bot_urdf())
    return path


def bot(urdf: Path, task_kind: str = 'position'):
    """The test robot of the URDF file `urdf` (`write_bot`), base to `tcp`."""
    from ftplan_ros.core.io.scene_file import robot_from_urdf
    return robot_from_urdf(urdf.read_text(), 'tcp', tip_offset=BOT_TIP_OFFSET,
                           mesh_dirs=[str(urdf.parent)], task_kind=task_kind)


# A 4-joint arm as a CAD export gives it: its links are cylinders, and `upper` and `fore`
# meet end to end on the axes of `pitch` and `roll` (two links apart, the `knuckle` between
# them). The joint sits 1 µm beyond the end of `upper` (the export's rounding): straight,
# the two are that far apart; any turn of pitch or roll sinks the rim of `fore` into
# `upper`, so every configuration but the straight one collides unless that pair is exempt.
CAD_ARM_GAP = 1e-6  # [m]
CAD_ARM = f'''<robot name="cad_arm">
  <link name="base">
    <collision><origin xyz="0 0 0.05"/>
      <geometry><cylinder radius="0.08" length="0.1"/></geometry></collision>
  </link>
  <joint name="yaw" type="revolute">
    <parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-2.5" upper="2.5" effort="1" velocity="1"/>
  </joint>
  <link name="upper">
    <collision><origin xyz="0.1 0 0.15"/>
      <geometry><cylinder radius="0.05" length="0.3"/></geometry></collision>
  </link>
  <joint name="pitch" type="revolute">
    <parent link="upper"/><child link="knuckle"/><origin xyz="0.1 0 {0.3 + CAD_ARM_GAP}"/>
    <axis xyz="0 1 0"/><limit lower="-2.0" upper="2.0" effort="1" velocity="1"/>
  </joint>
  <link name="knuckle">
    <collision><origin rpy="1.5707963267948966 0 0"/>
      <geometry><cylinder radius="0.03" length="0.14"/></geometry></collision>
  </link>
  <joint name="roll" type="revolute">
    <parent link="knuckle"/><child link="fore"/><origin xyz="0 0 0"/>
    <axis xyz="1 0 0"/><limit lower="-2.0" upper="2.0" effort="1" velocity="1"/>
  </joint>
  <link name="fore">
    <collision><origin xyz="0 0 0.15"/>
      <geometry><cylinder radius="0.05" length="0.3"/></geometry></collision>
  </link>
  <joint name="wrist" type="revolute">
    <parent link="fore"/><child link="hand"/><origin xyz="0 0 0.3"/>
    <axis xyz="0 1 0"/><limit lower="-2.0" upper="2.0" effort="1" velocity="1"/>
  </joint>
  <link name="hand">
    <collision><origin xyz="0 0 0.1"/>
      <geometry><cylinder radius="0.04" length="0.2"/></geometry></collision>
  </link>
  <joint name="tip_joint" type="fixed">
    <parent link="hand"/><child link="tip"/><origin xyz="0 0 0.2"/>
  </joint>
  <link name="tip"/>
</robot>
'''
CAD_ARM_TASK = {'start': [0.45, 0.1, 0.55], 'goal': [0.35, -0.25, 0.45], 'goal_tolerance': 0.005}
# The CAD arm with `upper` 3 cm shorter, its joints where they were: `upper` and `fore`
# touch in 91 % of random configurations, too few for MoveIt's sampling to exempt them,
# and in every start configuration of CAD_ARM_TASK. CAD_ARM_SRDF exempts every pair, as
# MoveIt's setup assistant writes them (adjacent, never touching) plus that one.
CAD_ARM_SHORT_UPPER = CAD_ARM.replace(
    '<origin xyz="0.1 0 0.15"/>\n      <geometry><cylinder radius="0.05" length="0.3"/>',
    '<origin xyz="0.1 0 0.135"/>\n      <geometry><cylinder radius="0.05" length="0.27"/>')
_CAD_ARM_LINKS = ('base', 'upper', 'knuckle', 'fore', 'hand')
CAD_ARM_SRDF = '<robot name="cad_arm">{}</robot>'.format(''.join(
    f'<disable_collisions link1="{a}" link2="{b}" reason="User"/>'
    for k, a in enumerate(_CAD_ARM_LINKS) for b in _CAD_ARM_LINKS[k + 1:]))


def write_cad_arm(directory: Path, **robot) -> Path:
    """Write the CAD arm's URDF and a scene of it (a position task; `robot`: more keys)."""
    (directory / 'cad_arm.urdf').write_text(CAD_ARM)
    scene = {'robot': {'type': 'urdf', 'file': 'cad_arm.urdf', 'base_link': 'base',
                       'tip_link': 'tip', **robot}, 'task': CAD_ARM_TASK}
    path = directory / 'cad_arm.yaml'
    path.write_text(yaml.safe_dump(scene))
    return path


MESH_ARM_JOINTS = (('z', 0.1), ('y', 0.3), ('y', 0.3), ('y', 0.3))  # axis, offset [m]


def mesh_arm(directory: Path, task_kind: str = 'position'):
    """A 4-joint arm whose links are convex STL hulls like the Panda's (`capsule_hull`).

    Joints turn about z, y, y, y, each 0.3 m beyond the last along the straight arm;
    each link is a hull 0.05 m thick and 0.35 m long from its joint, so links overlap
    their neighbours (exempt) and pass close to the links two away: their bounding
    spheres meet where the hulls are centimetres apart.
    """
    from ftplan_ros.core.io.scene_file import robot_from_urdf
    links, joints = ['  <link name="base"/>'], []
    for k, (axis, offset) in enumerate(MESH_ARM_JOINTS):
        write_binary_stl(directory / f'link{k + 1}.stl', *capsule_hull(0.25, 0.05, seed=k))
        parent = 'base' if k == 0 else f'link{k}'
        vector = {'z': '0 0 1', 'y': '0 1 0'}[axis]
        joints.append(f'  <joint name="j{k + 1}" type="revolute"><parent link="{parent}"/>'
                      f'<child link="link{k + 1}"/><origin xyz="0 0 {offset}"/>'
                      f'<axis xyz="{vector}"/><limit lower="-2.6" upper="2.6" effort="1" '
                      'velocity="1"/></joint>')
        links.append(f'  <link name="link{k + 1}"><collision><origin xyz="0 0 0.05"/><geometry>'
                     f'<mesh filename="link{k + 1}.stl"/></geometry></collision></link>')
    joints.append('  <joint name="tip_joint" type="fixed"><parent link="link4"/>'
                  '<child link="tip"/><origin xyz="0 0 0.35"/></joint>')
    xml = '<robot name="mesh_arm">\n' + '\n'.join(links + ['  <link name="tip"/>'] + joints) \
        + '\n</robot>\n'
    (directory / 'mesh_arm.urdf').write_text(xml)
    adjacent = [['base', 'link1']] + [[f'link{k}', f'link{k + 1}'] for k in range(1, 4)]
    return robot_from_urdf(xml, 'tip', disabled_collisions=adjacent,
                           mesh_dirs=[str(directory)], task_kind=task_kind)


def slice_distance(surface, joint, theta):
    """Length [rad] of a shortest path from θ to the goal row in the web's slice at θ_joint.

    A referee for `recover`, built from coordinates alone: each triangle's points at the
    level (corners on it, crossings of its sides) are joined pairwise. Corners with equal
    coordinates are one point, and so are the crossings of sides whose ends have equal
    coordinates (the web's sheets are joined where they share points, not where they
    merely pass through one). The goal row's points (top waypoints, crossings of the top
    rungs) are the targets. θ, on a nominal segment, is joined to the points of the
    triangles whose side it lies on.
    """
    level = theta[joint]
    paths = surface.paths
    n_paths, n_waypoints, n = paths.shape
    # A path equal to the one before it closes a sheet: no strip joins it to the next.
    strips = [k for k in range(n_paths - 1) if k == 0 or not np.array_equal(paths[k],
                                                                             paths[k - 1])]
    k, w = (index.ravel() for index in np.meshgrid(strips, np.arange(n_waypoints - 1),
                                                  indexing='ij'))

    def corners_at(*steps):
        return np.stack([np.stack([k + dk, w + dw], axis=1) for dk, dw in steps], axis=1)

    corners = np.concatenate([corners_at((0, 0), (1, 0), (1, 1)),
                              corners_at((0, 0), (1, 1), (0, 1))])  # (T, 3, (path, waypoint))
    slots, keys, tops = [], [], []
    holds_theta = np.zeros(len(corners), dtype=bool)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        p = paths[corners[:, a, 0], corners[:, a, 1]]
        q = paths[corners[:, b, 0], corners[:, b, 1]]
        on_top = corners[:, a, 1] == n_waypoints - 1
        slots.append(np.where((p[:, joint] == level)[:, None], p, np.nan))
        keys.append(np.hstack([p, p]))
        tops.append(on_top)
        differ = p != q
        first = np.argmax(differ, axis=1)
        swap = (q[np.arange(len(q)), first] < p[np.arange(len(p)), first])[:, None]
        p, q = np.where(swap, q, p), np.where(swap, p, q)
        with np.errstate(divide='ignore', invalid='ignore'):
            crossing = p + ((level - p[:, joint]) / (q[:, joint] - p[:, joint]))[:, None] * (q - p)
        strict = (p[:, joint] - level) * (q[:, joint] - level) < 0
        slots.append(np.where(strict[:, None], crossing, np.nan))
        keys.append(np.hstack([p, q]))
        tops.append(on_top & (corners[:, b, 1] == n_waypoints - 1))
        along = np.clip(np.einsum('ij,ij->i', theta - p, q - p)
                        / np.maximum(np.einsum('ij,ij->i', q - p, q - p), 1e-300), 0.0, 1.0)
        holds_theta |= np.linalg.norm(p + along[:, None] * (q - p) - theta, axis=1) < 1e-9
    slots = np.stack(slots + [np.where(holds_theta[:, None], theta, np.nan)], axis=1)
    used = ~np.isnan(slots).any(axis=2)
    slots[..., joint] = level
    keys = np.stack(keys + [np.tile(np.hstack([theta, theta]), (len(corners), 1))], axis=1)
    tops = np.stack(tops + [np.zeros(len(corners), dtype=bool)], axis=1)
    _, first, number = np.unique(np.vstack([keys[used], np.hstack([theta, theta])]), axis=0,
                                 return_index=True, return_inverse=True)
    points = np.vstack([slots[used], theta[None, :]])[first]
    slot_node = np.full(used.shape, -1)
    slot_node[used] = number[:-1]
    u, v = (slot_node[:, pairs].ravel() for pairs in np.triu_indices(7, 1))
    keep = (u >= 0) & (v >= 0) & (u != v)
    arcs = np.unique(np.sort(np.stack([u[keep], v[keep]], axis=1), axis=1), axis=0)
    weights = np.linalg.norm(points[arcs[:, 0]] - points[arcs[:, 1]], axis=1) + 1e-12
    graph = coo_matrix((weights, tuple(arcs.T)), shape=(len(points),) * 2)
    distance = dijkstra(graph, directed=False, indices=number[-1])
    return distance[np.unique(slot_node[used & tops])].min()
