"""Random scenes for the paper's arm and the referee of a plan, for the benchmarks.

`random_scene` draws a random start and goal and random disks; `referee_accepts`, the
referee of a plan, checks its nominal path at 9 moments for every joint with an
over-approximating flood fill in the failure plane (1 deg cells,
`exhaustive.recoverable_in_plane`), whose "no" would prove the plan wrong. The recall
benchmark (recall.py) uses both.
"""

from __future__ import annotations

import numpy as np

from ..core import CollisionChecker, parse_scene
from ..core.grid.exhaustive import recoverable_in_plane
from ..core.model.paths import point_at_fraction
from ..core.model.scene import Scene


def random_task(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Draw a start 1.8-2.6 m and a goal 0.9-1.5 m from the base (2,) [m], in any direction."""
    start = _polar(rng.uniform(1.8, 2.6), rng.uniform(-np.pi, np.pi))
    goal = _polar(rng.uniform(0.9, 1.5), rng.uniform(-np.pi, np.pi))
    return start, goal


def random_scene(rng: np.random.Generator, disks: int) -> Scene:
    """Make the paper's arm a random task among `disks` random disks clear of base, start, goal."""
    start, goal = random_task(rng)
    obstacles = []
    while len(obstacles) < disks:
        radius = rng.uniform(0.1, 0.3)
        center = _polar(rng.uniform(0.3, 3.0), rng.uniform(-np.pi, np.pi))
        if min(np.linalg.norm(center), np.linalg.norm(center - start),
               np.linalg.norm(center - goal)) > radius + 0.05:
            obstacles.append({'type': 'sphere', 'center': center.round(3).tolist(),
                              'radius': round(float(radius), 3)})
    return parse_scene({'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]},
                        'obstacles': obstacles,
                        'task': {'start': start.round(3).tolist(),
                                 'goal': goal.round(3).tolist()}}, name='random')


def referee_accepts(checker: CollisionChecker, result, x_goal: np.ndarray,
                   goal_tolerance: float, moments: int = 9, cells: int = 360) -> bool:
    """Whether every lock at `moments` points of the nominal path may still reach x_g.

    Reaching means coming within `goal_tolerance` [m], as the guarantee says; False
    proves the plan's guarantee wrong.
    """
    return all(recoverable_in_plane(checker, point_at_fraction(result.nominal_path, f), joint,
                                    x_goal, cells, goal_tolerance=goal_tolerance)
               for f in np.linspace(0.0, 1.0, moments)
               for joint in range(checker.robot.n_joints))


def _polar(radius: float, angle: float) -> np.ndarray:
    return radius * np.array([np.cos(angle), np.sin(angle)])
