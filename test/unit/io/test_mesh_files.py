"""Collision meshes as users have them (core/io/mesh_files.py): formats and where they are.

The test robot (ftplan_testing.bot_urdf) has one mesh link, l2, scaled by BOT_MESH_SCALE.
Its mesh is written here in each format, as a tetrahedron and as a convex hull of 300
triangles, and looked up by `package://` through a fake install (share/PKG), a fake ROS 1
workspace, `mesh_dirs` and the URDF's own package folder, by `file://` and by path.
"""

import numpy as np
import pytest
import yaml
from ftplan_testing import BOT_MESH_SCALE, TETRAHEDRON, bot_urdf, convex_hull, write_mesh

from ftplan_ros.core.errors import InputError
from ftplan_ros.core.io.scene_file import load_scene, robot_from_urdf

PACKAGE_URI = 'package://fake_robot/meshes/link.stl'


@pytest.fixture(autouse=True)
def no_ros_environment(monkeypatch):
    """Neither variable set unless a test sets it (the Makefile exports AMENT_PREFIX_PATH)."""
    monkeypatch.delenv('AMENT_PREFIX_PATH', raising=False)
    monkeypatch.delenv('ROS_PACKAGE_PATH', raising=False)


def mesh_of(robot):
    """The vertices (V, 3) and faces (F, 3) of the robot's one mesh."""
    shape = next(item.shape for item in robot.collision_shapes if item.shape.kind == 'mesh')
    return shape.vertices, shape.faces


def same_triangles(loaded, expected, atol=1e-6) -> bool:
    """Whether two meshes (vertices, faces) have the same triangles, corners in the same turn."""
    (v, f), (w, g) = loaded, expected
    nearest = np.argmin(np.linalg.norm(v[:, None, :] - w[None, :, :], axis=2), axis=1)
    if not np.allclose(v, w[nearest], atol=atol, rtol=0.0):
        return False

    def turns(faces):
        return sorted(tuple(np.roll(face, -int(np.argmin(face)))) for face in faces)
    return turns(nearest[f]) == turns(g)


@pytest.mark.parametrize('suffix', ['.stl', '.obj', '.dae'])
@pytest.mark.parametrize('mesh', [TETRAHEDRON, convex_hull()], ids=['tetrahedron', 'hull300'])
def test_stl_obj_and_collada_meshes_load_as_written_and_scaled(tmp_path, suffix, mesh):
    vertices, faces = mesh
    write_mesh(tmp_path / f'link{suffix}', vertices, faces)
    robot = robot_from_urdf(bot_urdf(f'link{suffix}'), 'tcp', directory=tmp_path)
    assert same_triangles(mesh_of(robot), (vertices * np.asarray(BOT_MESH_SCALE), faces))
    assert len(faces) in (4, 300)


def test_a_collada_mesh_in_millimetres_comes_out_in_metres(tmp_path):
    from ftplan_testing import write_collada
    vertices, faces = convex_hull()
    write_collada(tmp_path / 'link.dae', vertices, faces, unit=0.001)
    robot = robot_from_urdf(bot_urdf('link.dae'), 'tcp', directory=tmp_path)
    assert same_triangles(mesh_of(robot), (vertices * np.asarray(BOT_MESH_SCALE), faces))


def test_a_collada_unit_that_is_no_length_is_refused_naming_the_mesh(tmp_path):
    from ftplan_testing import write_collada
    write_collada(tmp_path / 'link.dae', *TETRAHEDRON)
    text = (tmp_path / 'link.dae').read_text().replace('meter="1"', 'meter="-2"')
    (tmp_path / 'link.dae').write_text(text)
    with pytest.raises(InputError, match=r"^robot\.file: link 'l2': collision mesh link\.dae: "
                       r'its <unit meter="-2"> is not a length'):
        robot_from_urdf(bot_urdf('link.dae'), 'tcp', directory=tmp_path)


def package_mesh(folder, mesh=TETRAHEDRON):
    """Write the fake package's mesh into `folder`/meshes/link.stl; return `folder`."""
    (folder / 'meshes').mkdir(parents=True)
    write_mesh(folder / 'meshes' / 'link.stl', *mesh)
    return folder


def test_package_uris_resolve_through_ament_prefix_path(tmp_path, monkeypatch):
    package_mesh(tmp_path / 'install' / 'share' / 'fake_robot')
    monkeypatch.setenv('AMENT_PREFIX_PATH', f'{tmp_path / "other"}:{tmp_path / "install"}')
    robot = robot_from_urdf(bot_urdf(PACKAGE_URI), 'tcp')
    assert same_triangles(mesh_of(robot), (TETRAHEDRON[0] * BOT_MESH_SCALE, TETRAHEDRON[1]))


def test_package_uris_resolve_through_ros_package_path_by_package_xml_name(tmp_path,
                                                                         monkeypatch):
    """rospack crawls the folders; the package is the folder whose package.xml names it."""
    package = package_mesh(tmp_path / 'ws' / 'src' / 'vendor_repo' / 'description')
    (package / 'package.xml').write_text('<package format="3">\n  <name>fake_robot</name>\n'
                                         '</package>\n')
    decoy = package_mesh(tmp_path / 'ws' / 'src' / 'fake_robot', convex_hull())
    (decoy / 'package.xml').write_text('<package><name>another_robot</name></package>')
    monkeypatch.setenv('ROS_PACKAGE_PATH', str(tmp_path / 'ws' / 'src'))
    robot = robot_from_urdf(bot_urdf(PACKAGE_URI), 'tcp')
    assert len(mesh_of(robot)[1]) == 4


def test_mesh_dirs_hold_packages_and_come_before_the_environment(tmp_path, monkeypatch):
    package_mesh(tmp_path / 'install' / 'share' / 'fake_robot')
    package_mesh(tmp_path / 'mine' / 'fake_robot', convex_hull())
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(tmp_path / 'install'))
    robot = robot_from_urdf(bot_urdf(PACKAGE_URI), 'tcp', mesh_dirs=[tmp_path / 'mine'])
    assert len(mesh_of(robot)[1]) == 300
    assert len(mesh_of(robot_from_urdf(bot_urdf(PACKAGE_URI), 'tcp'))[1]) == 4


def test_a_urdf_inside_its_package_finds_the_package_s_meshes(tmp_path):
    package = package_mesh(tmp_path / 'src' / 'fake_robot')
    (package / 'urdf').mkdir()
    (package / 'urdf' / 'robot.urdf').write_text(bot_urdf(PACKAGE_URI))
    scene = tmp_path / 'scene.yaml'
    scene.write_text(yaml.safe_dump({'robot': {'type': 'urdf', 'tip_link': 'tcp',
                                               'file': 'src/fake_robot/urdf/robot.urdf'}}))
    assert len(mesh_of(load_scene(scene).robot)[1]) == 4


def test_the_mesh_dirs_key_is_relative_to_the_yaml(tmp_path):
    package_mesh(tmp_path / 'config' / 'meshes' / 'fake_robot')
    (tmp_path / 'robot.urdf').write_text(bot_urdf(PACKAGE_URI))
    scene = tmp_path / 'config' / 'scene.yaml'
    robot = {'type': 'urdf', 'file': '../robot.urdf', 'tip_link': 'tcp', 'mesh_dirs': ['meshes']}
    scene.write_text(yaml.safe_dump({'robot': robot}))
    assert len(mesh_of(load_scene(scene).robot)[1]) == 4
    robot['mesh_dirs'] = ['meshes', 3]
    scene.write_text(yaml.safe_dump({'robot': robot}))
    with pytest.raises(InputError, match=r'^robot\.mesh_dirs\[1\]: must be the path of a folder'):
        load_scene(scene)


def test_file_uris_and_absolute_paths(tmp_path):
    path = write_mesh(tmp_path / 'link.obj', *convex_hull())
    for uri in (f'file://{path}', str(path)):
        assert len(mesh_of(robot_from_urdf(bot_urdf(uri), 'tcp'))[1]) == 300


def test_a_missing_package_mesh_names_the_uri_every_place_looked_and_the_fix(tmp_path,
                                                                           monkeypatch):
    monkeypatch.setenv('AMENT_PREFIX_PATH', str(tmp_path / 'install'))
    monkeypatch.setenv('ROS_PACKAGE_PATH', str(tmp_path / 'ws'))
    with pytest.raises(InputError) as error:
        robot_from_urdf(bot_urdf(PACKAGE_URI), 'tcp', mesh_dirs=[tmp_path / 'mine'])
    text = str(error.value)
    assert text.startswith(f"robot.file: link 'l2': collision mesh '{PACKAGE_URI}' was not "
                           f"found; looked in {tmp_path / 'mine' / 'fake_robot' / 'meshes'}")
    assert str(tmp_path / 'install' / 'share' / 'fake_robot' / 'meshes' / 'link.stl') in text
    assert f"ROS_PACKAGE_PATH ['{tmp_path / 'ws'}']" in text
    assert "put the folder holding 'fake_robot' in robot.mesh_dirs" in text
    assert '\n' not in text


@pytest.mark.parametrize('uri, words', [
    ('http://example.com/link.stl', 'has a scheme ftplan does not read'),
    ('package://fake_robot', 'names no package and file'),
    ('file://meshes/link.stl', 'is not an absolute file URI'),
    ('meshes/link.stl', 'was not found; looked in'),
])
def test_uris_that_name_no_file_are_refused_naming_the_link(tmp_path, uri, words):
    with pytest.raises(InputError, match=rf"^robot\.file: link 'l2': .*{words}"):
        robot_from_urdf(bot_urdf(uri), 'tcp', directory=tmp_path)
