"""Crowded scenes for the paper's arm, built the way the paper built its Fig. 3.

Start from a random task without obstacles (start 1.8-2.6 m, goal 0.9-1.5 m from the base,
links of 1 m; drawn again until the existence decision proves it has a plan) and add disks one at
a time, each next to a link of an obstacle-free configuration of M_s or M_g (exact
inverse kinematics), at a small gap: the arm's own poses are crowded in. A disk is kept
only while the existence decision still proves that a failure-tolerant plan exists
(core/grid/existence.py); the scene is done after `disks` kept disks or `attempts` tries. Every
crowded scene therefore has a plan, and most are tight.
"""

from __future__ import annotations

import numpy as np

from ..core import parse_scene
from ..core.collision.distance_kernels import planar_link_clearances
from ..core.grid.existence import Existence, decide_existence
from ..core.grid.tolerant_set import preimage_samples
from ..core.model.scene import Scene
from .scenes import random_task

LINKS = (1.0, 1.0, 1.0)
RADII = (0.12, 0.25)   # [m] disk radii
GAPS = (0.02, 0.10)    # [m] from the link the disk is placed next to
TASK_DRAWS = 100       # random tasks tried for one whose plan existence.py proves


def crowded_scene(rng: np.random.Generator, disks: int = 12, attempts: int = 40,
                  cells: int = 128, name: str = 'crowded') -> Scene:
    """Make a crowded scene (see the module docstring); existence is decided on `cells`^3."""
    start, goal = _proved_task(rng, cells, name)
    poses = np.vstack([preimage_samples(np.array(LINKS), start, 90),
                       preimage_samples(np.array(LINKS), goal, 90)])
    obstacles: list[dict] = []
    for _ in range(attempts):
        if len(obstacles) >= disks:
            break
        disk = _disk_beside(rng, poses, obstacles, start, goal)
        if disk is None:
            continue
        trial = _scene(obstacles + [disk], start, goal, name)
        if decide_existence(trial, cells).existence is Existence.YES:
            obstacles.append(disk)
    return _scene(obstacles, start, goal, name)


def _proved_task(rng: np.random.Generator, cells: int, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Draw start and goal [m] until the obstacle-free task has a proved plan."""
    for _ in range(TASK_DRAWS):
        start, goal = random_task(rng)
        if decide_existence(_scene([], start, goal, name), cells).existence is Existence.YES:
            return start, goal
    raise RuntimeError(f'no random task of {TASK_DRAWS} has a plan the existence decision '
                       f'proves on {cells}^3 cells')


def _disk_beside(rng: np.random.Generator, poses: np.ndarray, obstacles: list[dict],
                 start: np.ndarray, goal: np.ndarray) -> dict | None:
    """Draw a disk next to a link of a random obstacle-free pose, clear of base, start and goal."""
    centres = np.array([ob['center'] + [0.0] for ob in obstacles], dtype=float).reshape(-1, 3)
    radii = np.array([ob['radius'] for ob in obstacles], dtype=float)
    free = poses[planar_link_clearances(np.array(LINKS), 0.0, centres, radii,
                                        poses).min(axis=1) > 0]
    if len(free) == 0:
        return None
    theta = free[rng.integers(len(free))]
    phi = np.cumsum(theta)
    joints = np.vstack([[0.0, 0.0], np.cumsum(np.stack([np.cos(phi), np.sin(phi)], 1), axis=0)])
    link = int(rng.integers(3))
    a, b = joints[link], joints[link + 1]
    along = a + rng.uniform(0.3, 1.0) * (b - a)
    normal = np.array([-(b - a)[1], (b - a)[0]]) * rng.choice([-1.0, 1.0])
    radius = float(rng.uniform(*RADII))
    center = along + normal * (radius + rng.uniform(*GAPS))
    if min(np.linalg.norm(center), np.linalg.norm(center - start),
           np.linalg.norm(center - goal)) <= radius + 0.05:
        return None
    return {'type': 'sphere', 'center': center.round(3).tolist(), 'radius': round(radius, 3)}


def _scene(obstacles: list[dict], start: np.ndarray, goal: np.ndarray, name: str) -> Scene:
    return parse_scene({'robot': {'type': 'planar', 'link_lengths': list(LINKS)},
                        'obstacles': obstacles,
                        'task': {'start': start.round(3).tolist(), 'goal': goal.round(3).tolist()}},
                       name=name)
