"""A planar arm drawn in its plane (figures/planar.py): the workspace and the motion figures."""

import numpy as np
import pytest
from matplotlib.patches import Circle, Polygon

from ftplan_ros import figures
from ftplan_ros.core import Obstacle, PlanResult
from ftplan_ros.core.model.angles import wrap_angle

from .drawn import arm_points, artists, only


def joint_angles(points):
    """Relative joint angles (n,) [rad] of an arm drawn through base, joints and tip (n+1, 2)."""
    steps = np.diff(points, axis=0)
    absolute = np.arctan2(steps[:, 1], steps[:, 0])
    return np.diff(absolute, prepend=0.0)


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
