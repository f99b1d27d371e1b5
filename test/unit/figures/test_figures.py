"""The figures package's own functions (figures/__init__.py): plan figures, PNGs, no pyplot."""

import re
import struct
import subprocess
import sys

import numpy as np
import pytest
from ftplan_testing import REPO

from ftplan_ros import figures
from ftplan_ros.core import Obstacle, plan

from .drawn import artists

PNG_SIGNATURE = b'\x89PNG\r\n\x1a\n'


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
    sources = sorted((REPO / 'ftplan_ros' / 'ftplan_ros' / 'core').rglob('*.py'))
    assert len(sources) >= 40, f'found {len(sources)} modules of the core: is the walk broken?'
    for source in sources:
        assert not imports_figures.search(source.read_text()), source.name


def test_spatial_plan_figure_puts_the_3d_arm_beside_the_joint_panels(panda_scene, panda_result):
    figure = figures.plan_figure(panda_scene, panda_result)
    workspace, *panels = figure.axes
    assert workspace.name == '3d' and len(panels) == panda_scene.robot.n_joints
    assert artists(workspace, 'arm:theta_s') and all(artists(ax, 'nominal') for ax in panels)
    figure.canvas.draw()
    assert workspace.get_window_extent().x1 < panels[0].get_window_extent().x0
    assert figure.get_suptitle() == 'panda_box: failure-tolerant plan'

