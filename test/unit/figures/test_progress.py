"""Joint space as one panel per joint against progress (figures/progress.py)."""

import numpy as np
import pytest

from ftplan_ros import figures
from ftplan_ros.core.model.paths import cumulative_fractions

from .drawn import artists, only


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
