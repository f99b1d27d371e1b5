import re
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.patches import Circle, Polygon
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ftplan_ros import figures
from ftplan_ros.core import (
    CollisionChecker,
    Obstacle,
    PlanarChain,
    PlanResult,
    load_scene,
    parse_scene,
    plan,
    recover,
)
from ftplan_ros.core.model.angles import wrap_angle
from ftplan_ros.core.model.paths import cumulative_fractions, path_until, point_at_fraction
from ftplan_ros.core.planning.drill import drilled_motion
from ftplan_ros.figures import spatial

REPO = Path(__file__).resolve().parents[2]
PNG_SIGNATURE = b'\x89PNG\r\n\x1a\n'


@pytest.fixture(scope='module')
def scene():
    return load_scene(REPO / 'config' / 'scenes' / 'fig3a.yaml')


@pytest.fixture(scope='module')
def result(scene):
    result = plan(scene)
    assert result.feasible, result.reason
    return result


@pytest.fixture(scope='module')
def drill_motion(result):
    """A drill as `drill_once` runs it: joint 2 locks 45 % along the nominal path."""
    joint, progress = 1, 0.45
    before = path_until(result.nominal_path, progress)
    rescue = recover(result.surface, point_at_fraction(result.nominal_path, progress), joint)
    return np.vstack([before, rescue.path]), len(before) - 1, joint


def artists(ax, gid):
    return [artist for artist in ax.get_children() if artist.get_gid() == gid]


def only(ax, gid):
    found = artists(ax, gid)
    assert len(found) == 1, f'{len(found)} artists with gid {gid!r}'
    return found[0]


def joint_angles(points):
    """Relative joint angles (n,) [rad] of an arm drawn through base, joints and tip (n+1, 2)."""
    steps = np.diff(points, axis=0)
    absolute = np.arctan2(steps[:, 1], steps[:, 0])
    return np.diff(absolute, prepend=0.0)


def arm_points(line):
    return np.column_stack(line.get_data())


def test_workspace_figure_draws_obstacles_theta_s_and_the_hits(scene, result):
    figure = figures.workspace_figure(scene, result)
    (ax,) = figure.axes
    # One disk per obstacle, where the obstacle is, and no other patch.
    assert len(ax.patches) == len(scene.obstacles)
    for patch, obstacle in zip(ax.patches, scene.obstacles, strict=True):
        assert isinstance(patch, Circle) and patch.get_gid() == 'obstacle'
        assert np.allclose(patch.center, obstacle.center[:2])
        assert patch.radius == pytest.approx(obstacle.radius)
    # The arm at θ_s plus one arm per failure-plane hit, nothing else.
    arms = sorted(line.get_gid() for line in ax.lines if line.get_gid().startswith('arm:'))
    assert arms == ['arm:H1', 'arm:H2', 'arm:H3', 'arm:theta_s']
    start = only(ax, 'arm:theta_s')
    assert np.allclose(arm_points(start), scene.robot.joint_positions(result.theta_s))
    assert np.allclose(arm_points(start)[-1], scene.task.start, atol=1e-6)
    assert start.get_linewidth() > 2.0 and start.get_color() == 'k'
    colours = set()
    for i in range(scene.robot.n_joints):
        hit = only(ax, f'arm:H{i + 1}')
        assert hit.get_label() == f'H{i + 1} hit'
        assert np.linalg.norm(arm_points(hit)[-1] - scene.task.goal) <= scene.task.goal_tolerance
        # Joint i keeps its θ_s angle: the drawn arm lies in the failure plane H_i(θ_s).
        drawn = joint_angles(arm_points(hit))
        assert abs(wrap_angle(drawn[i] - result.theta_s[i])) < 1e-6
        colours.add(hit.get_color())
    assert len(colours) == scene.robot.n_joints
    trace = only(ax, 'trace')
    assert trace.get_linestyle() == '--'
    xy = np.column_stack(trace.get_data())
    assert np.allclose(xy[0], scene.task.start, atol=1e-6)
    assert np.linalg.norm(xy[-1] - scene.task.goal) <= scene.task.goal_tolerance
    assert only(ax, 'x_s').get_label() and only(ax, 'x_g').get_label()
    assert ax.get_xlabel() == 'x [m]' and ax.get_ylabel() == 'y [m]'
    assert ax.get_aspect() == 1.0
    for value in np.degrees(result.theta_s):
        assert f'{value:.1f}°' in ax.get_title()
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert {'H1 hit', 'H2 hit', 'H3 hit', r'$\theta_s$'} <= set(labels)


def test_joint_space_figure_draws_manifolds_theta_s_hits_and_the_surface(scene, result):
    figure = figures.joint_space_figure(scene, result)
    (ax,) = figure.axes
    assert ax.name == '3d'
    for label in (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()):
        assert label.endswith('[deg]')
    assert np.allclose(np.column_stack(only(ax, 'theta_s').get_data_3d())[0],
                       np.degrees(result.theta_s))
    surface = result.surface
    for i, path in enumerate(surface.hit_paths):
        hit = np.column_stack(only(ax, f'hit:H{i + 1}').get_data_3d())[0]
        assert np.allclose(hit, np.degrees(surface.goal_points[path]))
        assert hit[i] == pytest.approx(np.degrees(result.theta_s[i]))  # on H_i(θ_s)
    web = only(ax, 'S_F')
    assert isinstance(web, Poly3DCollection)
    figure.canvas.draw()
    assert len(web.get_paths()) == len(surface.triangles)
    boundary = np.column_stack(only(ax, 'S_F:boundary').get_data_3d())
    assert np.allclose(boundary[0], np.degrees(result.theta_s))
    nominal = np.column_stack(only(ax, 'nominal').get_data_3d())
    assert np.allclose(nominal, np.degrees(result.nominal_path))
    # Manifolds: dashed, one line per branch, wrapped and broken where they cross the seam.
    for gid, branches in (('M_s', result.start_manifolds), ('M_g', result.goal_manifolds)):
        lines = artists(ax, gid)
        assert len(lines) == len(branches)
        for line in lines:
            assert line.get_linestyle() == '--'
            points = np.column_stack(line.get_data_3d())
            finite = points[np.isfinite(points).all(axis=1)]
            assert np.all((finite > -180.0 - 1e-9) & (finite <= 180.0 + 1e-9))
            steps = np.abs(np.diff(points, axis=0))
            assert np.all(steps[np.isfinite(steps).all(axis=1)] < 180.0)
    assert any(np.isnan(np.column_stack(line.get_data_3d())).any()
               for line in artists(ax, 'M_g')), 'M_g of fig3a crosses the seam'
    candidates = np.column_stack(only(ax, 'Theta_S').get_data_3d())
    assert len(candidates) == len(result.necessary_starts)
    # C-space obstacles: every drawn cell centre collides.
    cells = np.radians(np.column_stack(only(ax, 'C_obs').get_data_3d()))
    assert len(cells) > 100
    checker = CollisionChecker(scene.robot, scene.obstacles)
    assert np.all(checker.min_clearance(cells) <= 0.0)
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert r'$\mathcal{S}_F$' in labels and r'$\theta_s$' in labels


def test_c_space_cells_are_the_surface_of_the_checker_s_obstacles():
    robot = PlanarChain((1.0, 1.0, 1.0), ('a', 'b', 'c'), link_radius=0.05)
    obstacles = [Obstacle('box', (1.3, 0.9, 0.0), size=(0.5, 0.2, 1.0), rpy=(0.0, 0.0, 0.6)),
                 Obstacle('cylinder', (-1.2, 0.9, 0.2), radius=0.15, length=1.0,
                          rpy=(0.8, 0.0, 0.3)),
                 Obstacle('sphere', (0.8, -1.2, 0.1), radius=0.3)]
    cells = 12
    drawn = figures._c_space_obstacle_cells(robot, obstacles, cells)
    # The same grid, every cell through the checker, then its colliding cells with a free
    # neighbour (all joints wrap).
    axis = -np.pi + (np.arange(cells) + 0.5) * 2.0 * np.pi / cells
    grid = np.stack(np.meshgrid(axis, axis, axis, indexing='ij'), axis=-1).reshape(-1, 3)
    solid = (CollisionChecker(robot, obstacles).min_clearance(grid) <= 0.0)
    solid = solid.reshape(cells, cells, cells)
    free_neighbour = np.zeros_like(solid)
    for k in range(3):
        for shift in (1, -1):
            free_neighbour |= ~np.roll(solid, shift, axis=k)
    expected = grid[(solid & free_neighbour).ravel()]
    assert 0 < len(expected) < len(grid)
    assert len(drawn) == len(expected)
    assert set(map(tuple, np.round(drawn, 9))) == set(map(tuple, np.round(expected, 9)))


def test_obstacle_sections_are_drawn_where_they_cut_the_arm_plane(scene):
    obstacles = (Obstacle('box', (1.0, 1.0, 0.0), size=(0.4, 0.2, 1.0), rpy=(0.0, 0.0, 0.5)),
                 Obstacle('sphere', (-1.0, 0.0, 0.3), radius=0.5),
                 Obstacle('sphere', (0.0, -1.0, 0.6), radius=0.5),      # above the plane
                 Obstacle('cylinder', (-1.0, -1.0, 0.0), radius=0.2, length=0.4),
                 Obstacle('cylinder', (1.0, -1.0, 0.0), radius=0.2, length=2.0,
                          rpy=(np.pi / 3, 0.0, 0.0)))
    boxed = type(scene)(scene.robot, obstacles, scene.task, scene.frame_id, 'shapes')
    refused = PlanResult(False, scene.robot.joint_names, reason='not planned')
    (ax,) = figures.workspace_figure(boxed, refused).axes
    box, sphere, upright, tilted = ax.patches
    assert isinstance(box, Polygon)
    c, s = np.cos(0.5), np.sin(0.5)
    corners = np.array([[1.0, 1.0]]) + np.array([[0.2, 0.1], [-0.2, 0.1], [-0.2, -0.1],
                                                 [0.2, -0.1]]) @ np.array([[c, s], [-s, c]])
    drawn = box.get_xy()[:-1]
    assert len(drawn) == 4
    assert all(np.min(np.linalg.norm(drawn - corner, axis=1)) < 1e-9 for corner in corners)
    assert sphere.radius == pytest.approx(0.4)  # sqrt(0.5² - 0.3²)
    assert isinstance(upright, Circle) and upright.radius == pytest.approx(0.2)
    # A cylinder tilted by 60° about x cuts the plane in an ellipse 0.4 wide, 0.8 long.
    extent = np.ptp(tilted.get_xy(), axis=0)
    assert extent == pytest.approx([0.4, 0.8], rel=0.01)


def test_an_infeasible_result_is_drawn_with_its_reason(scene):
    refused = PlanResult(False, scene.robot.joint_names,
                         reason='every start configuration collides (M_s^F is empty)')
    (ax,) = figures.workspace_figure(scene, refused).axes
    assert len(ax.patches) == len(scene.obstacles)
    assert not [line for line in ax.lines if line.get_gid().startswith('arm:')]
    assert artists(ax, 'x_s') and artists(ax, 'x_g')
    assert 'every start configuration collides' in ax.get_title().replace('\n', ' ')
    (ax3,) = figures.joint_space_figure(scene, refused, grid_cells=0).axes
    assert not artists(ax3, 'S_F') and not artists(ax3, 'theta_s')


def test_a_start_the_planner_rejects_is_drawn_in_both_panels(scene, result):
    # An obstacle on the elbow of the chosen θ_s: that start is no longer failure-tolerant.
    elbow = scene.robot.joint_positions(result.theta_s)[1]
    blocked = scene.with_obstacles([Obstacle('sphere', (*elbow, 0.0), radius=0.1)])
    refused = plan(blocked, start_configuration=result.theta_s)
    assert not refused.feasible and refused.reason
    figure = figures.plan_figure(blocked, refused, grid_cells=16)
    workspace, joint_space = figure.axes
    assert 'no failure-tolerant plan' in figure.get_suptitle()
    assert refused.reason[:30] in workspace.get_title().replace('\n', ' ')
    assert len(workspace.patches) == len(blocked.obstacles)
    assert joint_space.name == '3d'
    assert artists(joint_space, 'M_s') and artists(joint_space, 'M_g')
    assert not artists(joint_space, 'S_F')


def test_plan_figure_puts_workspace_left_and_joint_space_right(scene, result):
    figure = figures.plan_figure(scene, result, grid_cells=8)
    left, right = figure.axes
    assert left.name == 'rectilinear' and right.name == '3d'
    assert left.get_position().x0 < right.get_position().x0
    assert artists(left, 'arm:theta_s') and artists(right, 'S_F')
    assert 'failure-tolerant plan' in figure.get_suptitle()


def test_motion_figure_marks_the_failure_and_the_final_configuration(scene, drill_motion):
    motion, failure_index, joint = drill_motion
    (ax,) = figures.motion_figure(scene, motion, failure_index, joint).axes
    robot = scene.robot
    failed = only(ax, 'arm:failure')
    assert np.allclose(arm_points(failed), robot.joint_positions(motion[failure_index]))
    assert failed.get_color() == figures.FAILURE_COLOUR
    circle = np.column_stack(only(ax, 'locked_joint').get_data())[0]
    assert np.allclose(circle, robot.joint_positions(motion[failure_index])[joint])
    final = only(ax, 'arm:final')
    assert np.linalg.norm(arm_points(final)[-1] - scene.task.goal) <= scene.task.goal_tolerance
    assert len(artists(ax, 'snapshot')) == figures.SNAPSHOTS
    before, after = only(ax, 'trace'), only(ax, 'trace:recovery')
    assert np.allclose(before.get_xydata()[-1], after.get_xydata()[0])
    assert len(ax.patches) == len(scene.obstacles)
    title = ax.get_title()
    assert robot.joint_names[joint] in title
    assert f'{np.degrees(motion[failure_index, joint]):.1f}°' in title
    assert artists(ax, 'x_g')


def test_motion_figure_without_a_failure_and_its_input_checks(scene, result):
    (ax,) = figures.motion_figure(scene, result.nominal_path, None, None, title='nominal').axes
    assert ax.get_title() == 'nominal'
    assert not artists(ax, 'arm:failure') and not artists(ax, 'locked_joint')
    assert artists(ax, 'arm:final')
    with pytest.raises(ValueError, match='shape'):
        figures.motion_figure(scene, result.nominal_path[:, :2], None, None)
    with pytest.raises(ValueError, match='failure_index'):
        figures.motion_figure(scene, result.nominal_path, len(result.nominal_path), 0)
    with pytest.raises(ValueError, match='locked_joint'):
        figures.motion_figure(scene, result.nominal_path, 3, 5)
    with pytest.raises(ValueError, match='failure_index'):
        figures.motion_figure(scene, result.nominal_path, None, 0)


def test_save_figure_writes_a_png(tmp_path, scene, drill_motion):
    motion, failure_index, joint = drill_motion
    figure = figures.motion_figure(scene, motion, failure_index, joint)
    path = figures.save_figure(figure, tmp_path / 'drills' / 'new' / 'drill.png')
    assert path == tmp_path / 'drills' / 'new' / 'drill.png'
    data = path.read_bytes()
    assert data.startswith(PNG_SIGNATURE)
    width, height = struct.unpack('>II', data[16:24])  # the IHDR chunk
    # The image holds everything drawn, the legend beside the axes included.
    tight = figure.get_tightbbox(figure.canvas.get_renderer())
    expected = (np.array([tight.width, tight.height]) + 0.2) * figures.DPI  # 0.1 in padding
    assert np.all(np.abs(np.array([width, height]) - expected) <= 2)
    with pytest.raises(ValueError, match='.png'):
        figures.save_figure(figure, tmp_path / 'drill.svg')


def test_figures_never_load_pyplot_and_the_core_never_imports_them():
    code = ('import sys, ftplan_ros.figures; '
            'sys.exit("matplotlib.pyplot" in sys.modules)')
    assert subprocess.run([sys.executable, '-c', code], timeout=300).returncode == 0
    imports_figures = re.compile(r'^\s*(from|import)\s+[\w.]*figures', re.MULTILINE)
    for source in (REPO / 'ftplan_ros' / 'ftplan_ros' / 'core').glob('*.py'):
        assert not imports_figures.search(source.read_text()), source.name


# --- spatial arms ------------------------------------------------------------------------

PANDA_SCENE = {
    'robot': '../robots/panda.yaml',
    'obstacles': [{'type': 'box', 'center': [0.5, 0.0, 0.2], 'size': [0.3, 0.6, 0.02]}],
    'task': {'start': {'position': [0.5, -0.2, 0.4], 'orientation': [1.0, 0.0, 0.0, 0.0]},
             'goal': {'position': [0.5, 0.2, 0.4], 'orientation': [1.0, 0.0, 0.0, 0.0]},
             'goal_tolerance': 0.005, 'orientation_tolerance': 0.01},
    # The elbow keeps its angle along the self-motion of a pose: it cannot be tolerated.
    'tolerate': ['panda_joint1', 'panda_joint2', 'panda_joint3', 'panda_joint5',
                 'panda_joint6', 'panda_joint7'],
}


@pytest.fixture(scope='module')
def panda_scene():
    return parse_scene(PANDA_SCENE, 'panda_box', REPO / 'config' / 'scenes')


@pytest.fixture(scope='module')
def panda_result(panda_scene):
    result = plan(panda_scene, rng=np.random.default_rng(0))
    assert result.feasible, result.reason
    return result


def points_3d(line):
    return np.column_stack(line.get_data_3d())


def test_spatial_workspace_draws_the_arm_at_theta_s_the_hits_and_the_obstacles(
        panda_scene, panda_result):
    robot, task = panda_scene.robot, panda_scene.task
    figure = figures.workspace_figure(panda_scene, panda_result)
    (ax,) = figure.axes
    assert ax.name == '3d'
    figure.canvas.draw()
    start = only(ax, 'arm:theta_s')
    assert np.allclose(points_3d(start), robot.skeleton(panda_result.theta_s))
    assert np.allclose(points_3d(start)[-1], task.start[:3], atol=1e-4)
    assert start.get_linewidth() > 2.0 and start.get_color() == 'k'
    # One thin arm per tolerated joint, in its own colour, none for the elbow.
    tolerated = panda_result.tolerated_joints
    assert tolerated == (0, 1, 2, 4, 5, 6)
    arms = sorted(line.get_gid() for line in ax.lines if line.get_gid().startswith('arm:'))
    assert arms == sorted([f'arm:H{i + 1}' for i in tolerated] + ['arm:theta_s'])
    for i, hit in zip(tolerated, panda_result.failure_plane_hits, strict=True):
        line = only(ax, f'arm:H{i + 1}')
        assert np.allclose(points_3d(line), robot.skeleton(hit))
        assert np.linalg.norm(points_3d(line)[-1] - task.goal[:3]) <= task.goal_tolerance
        assert line.get_label() == f'H{i + 1} hit ({robot.joint_names[i]} locked)'
        assert line.get_linewidth() < start.get_linewidth()
    assert len({only(ax, f'arm:H{i + 1}').get_color() for i in tolerated}) == len(tolerated)
    # The box as one collection of faces; the tool's path from x_s to x_g.
    (box,) = artists(ax, 'obstacle')
    assert isinstance(box, Poly3DCollection)
    trace = points_3d(only(ax, 'trace'))
    assert np.allclose(trace[0], task.start[:3], atol=1e-4)
    assert np.linalg.norm(trace[-1] - task.goal[:3]) <= task.goal_tolerance
    assert artists(ax, 'x_s') and artists(ax, 'x_g')
    assert artists(ax, 'x_s:frame') and artists(ax, 'x_g:frame')  # a pose task's axes
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ('x [m]', 'y [m]', 'z [m]')
    # Equal scale: the box's sides are in the ratio of the axes' ranges.
    ranges = np.array([np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim()), np.ptp(ax.get_zlim())])
    assert np.allclose(ax.get_box_aspect() / ranges, ax.get_box_aspect()[0] / ranges[0])
    title = ax.get_title()
    for value in np.degrees(panda_result.theta_s):
        assert f'{value:.1f}°' in title
    assert 'any joint but panda_joint4' in title.replace('\n', ' ')


def test_spatial_joint_space_has_a_panel_per_joint_with_the_hits_at_progress_one(
        panda_scene, panda_result):
    robot, surface = panda_scene.robot, panda_result.surface
    figure = figures.joint_space_figure(panda_scene, panda_result)
    panels = figure.axes
    assert len(panels) == robot.n_joints
    figure.canvas.draw()
    lower, upper = np.degrees(panda_result.hypercube)
    theta_s = np.degrees(panda_result.theta_s)
    hits = np.degrees(panda_result.failure_plane_hits)
    progress = cumulative_fractions(panda_result.nominal_path)
    for j, ax in enumerate(panels):
        assert ax.get_ylabel().endswith('[deg]')
        assert ax.get_shared_x_axes().joined(ax, panels[0])
        nominal = only(ax, 'nominal')
        assert np.allclose(nominal.get_xdata(), progress)
        assert np.allclose(nominal.get_ydata(), np.degrees(panda_result.nominal_path[:, j]))
        assert np.allclose(only(ax, 'theta_s').get_xydata(), [[0.0, theta_s[j]]])
        for k, i in enumerate(panda_result.tolerated_joints):
            assert np.allclose(only(ax, f'hit:H{i + 1}').get_xydata(), [[1.0, hits[k, j]]])
        band = only(ax, 'hypercube')
        assert (band.get_y(), band.get_y() + band.get_height()) == pytest.approx(
            (lower[j], upper[j]))
        goal = np.degrees(surface.goal_points[:, j])
        assert np.allclose(only(ax, 'M_g^F').get_xydata(),
                           [[1.0, goal.min()], [1.0, goal.max()]])
        start = only(ax, 'M_s').get_ydata()
        assert start[0] <= theta_s[j] + 1e-6 and theta_s[j] - 1e-6 <= start[1]
        assert artists(ax, 'S_F')
    for k, i in enumerate(panda_result.tolerated_joints):  # the locked joint keeps θ_s
        assert hits[k, i] == pytest.approx(theta_s[i])
    names = [text.get_text() for text in panels[3].texts]
    assert names == ['panda_joint4 (not tolerated)']
    assert 'progress' in panels[-1].get_xlabel()


def test_spatial_plan_figure_puts_the_3d_arm_beside_the_joint_panels(panda_scene, panda_result):
    figure = figures.plan_figure(panda_scene, panda_result)
    workspace, *panels = figure.axes
    assert workspace.name == '3d' and len(panels) == panda_scene.robot.n_joints
    assert artists(workspace, 'arm:theta_s') and all(artists(ax, 'nominal') for ax in panels)
    figure.canvas.draw()
    assert workspace.get_window_extent().x1 < panels[0].get_window_extent().x0
    assert figure.get_suptitle() == 'panda_box: failure-tolerant plan'


def test_an_infeasible_spatial_result_is_drawn_with_its_reason(panda_scene):
    reason = ('no start configuration lets the plan survive a lock of panda_joint4: the '
              'elbow keeps its angle along the self-motion of the pose')
    refused = PlanResult(False, panda_scene.robot.joint_names, reason=reason)
    figure = figures.plan_figure(panda_scene, refused)
    workspace, *panels = figure.axes
    figure.canvas.draw()
    assert len(artists(workspace, 'obstacle')) == 1
    assert artists(workspace, 'x_s') and artists(workspace, 'x_g')
    assert not [line for line in workspace.lines if line.get_gid().startswith('arm:')]
    assert reason in workspace.get_title().replace('\n', ' ')
    assert len(panels) == panda_scene.robot.n_joints
    assert not any(artists(ax, 'S_F') or artists(ax, 'theta_s') for ax in panels)
    assert all(artists(ax, 'limit') for ax in panels)  # every Panda joint has limits


def test_spatial_obstacles_are_posed_and_clipped_to_the_view(panda_scene):
    floor = Obstacle('box', (0.0, 0.0, -0.05), size=(20.0, 20.0, 0.1))
    tilted = Obstacle('cylinder', (0.4, 0.3, 0.3), radius=0.05, length=0.4,
                      rpy=(np.pi / 2, 0.0, 0.0))
    ball = Obstacle('sphere', (0.3, -0.3, 0.5), radius=0.1)
    scene = panda_scene.with_obstacles([floor, tilted, ball])
    refused = PlanResult(False, scene.robot.joint_names, reason='not planned')
    (ax,) = figures.workspace_figure(scene, refused).axes
    assert len(artists(ax, 'obstacle')) == len(scene.obstacles)
    # The 20 m floor does not swallow the view: it spans the Panda's reach at most.
    assert all(np.ptp(limits) < 2.6 for limits in (ax.get_xlim(), ax.get_ylim()))
    # Faces: a cylinder turned by 90° about x lies along y; a clipped face keeps its plane.
    faces = np.vstack(spatial._obstacle_faces(tilted))
    assert np.ptp(faces, axis=0) == pytest.approx([0.1, 0.4, 0.1], abs=1e-3)
    sphere = np.vstack(spatial._obstacle_faces(ball))
    assert np.allclose(np.linalg.norm(sphere - ball.center, axis=1), ball.radius)
    lower, upper = np.array([-1.0, -1.0, -0.02]), np.array([1.0, 1.0, 1.0])
    clipped = [spatial._clip_polygon(face, lower, upper)
               for face in spatial._obstacle_faces(floor)]
    (top,) = [face for face in clipped if len(face)]  # the rest lies outside the box
    assert np.allclose(np.sort(top[:, :2], axis=0)[[0, -1]], [[-1.0, -1.0], [1.0, 1.0]])
    assert np.allclose(top[:, 2], 0.0)


def test_spatial_motion_figure_marks_the_locked_joint(panda_scene, panda_result):
    robot, task = panda_scene.robot, panda_scene.task
    joint = 1
    motion, lock_index, locked_value = drilled_motion(panda_result, joint, 0.45)
    figure = figures.motion_figure(panda_scene, motion, lock_index, joint)
    (ax,) = figure.axes
    figure.canvas.draw()
    failed = only(ax, 'arm:failure')
    assert failed.get_color() == figures.FAILURE_COLOUR
    assert np.allclose(points_3d(failed), robot.skeleton(motion[lock_index]))
    ring = only(ax, 'locked_joint')
    assert np.allclose(points_3d(ring)[0], robot.skeleton(motion[lock_index])[joint + 1])
    assert ring.get_label() == f'panda_joint2 locked at {np.degrees(locked_value):.1f}°'
    final = points_3d(only(ax, 'arm:final'))
    assert np.linalg.norm(final[-1] - task.goal[:3]) <= task.goal_tolerance
    assert len(artists(ax, 'snapshot')) == figures.SNAPSHOTS
    before, after = points_3d(only(ax, 'trace')), points_3d(only(ax, 'trace:recovery'))
    assert np.allclose(before[-1], after[0])
    assert len(artists(ax, 'obstacle')) == 1
    title = ax.get_title()
    assert 'panda_joint2 locked at' in title and 'mm and' in title  # position and angle
