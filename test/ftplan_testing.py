"""Test helpers shared by the unit tests: the repository's paths and the paper's scenes.

(Not in conftest.py: test/ros has a conftest.py of its own, and the two would clash as
modules named `conftest`.)
"""

from pathlib import Path

from ftplan_ros.core.scene import Scene, parse_scene

REPO = Path(__file__).resolve().parents[1]
SCENES = REPO / 'config' / 'scenes'


def paper_scene(start=(2.0, 0.0), obstacles=(), tolerance=0.01) -> Scene:
    """The paper's 3R arm (links of 1 m) moving its tip from `start` to [1, 0]."""
    return parse_scene({
        'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]},
        'obstacles': [{'type': 'sphere', 'center': list(c), 'radius': r} for c, r in obstacles],
        'task': {'start': list(start), 'goal': [1.0, 0.0], 'goal_tolerance': tolerance}})


def jacobian(robot, theta):
    """The task Jacobian (m, n) of a robot at θ (n,) [rad], as the planner computes it."""
    import numpy as np

    from ftplan_ros.core.robot import task_residuals
    theta = np.asarray(theta, dtype=float)
    return task_residuals(robot, robot.forward_kinematics(theta), theta)[1][0]
