"""The paper's Fig. 4 for a planar 3R arm (figures/joint_space_3d.py): joint space in 3-D."""

import numpy as np
import pytest
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from ftplan_ros import figures
from ftplan_ros.core import CollisionChecker, Obstacle, PlanarChain

from .drawn import artists, only


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
