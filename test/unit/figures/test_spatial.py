"""A spatial arm drawn in 3-D (figures/spatial.py): workspace, obstacles and motion."""

import numpy as np
import pytest
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ftplan_ros import figures
from ftplan_ros.core import Obstacle, PlanResult
from ftplan_ros.core.planning.drill import drilled_motion
from ftplan_ros.figures import spatial

from .drawn import artists, only, points_3d


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
