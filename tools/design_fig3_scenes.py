"""Design the Fig. 3-like scenes in config/scenes/ the way the paper made its own (Sec. V).

The paper's obstacle positions are not published, only the start configurations that
survived them (Table I). This script adds disks of radius 0.2 m one at a time, at seeded
random places, and keeps a disk only when the paper's θ_s is still a verified
failure-tolerant start and fewer other starts survive ("obstacles were added until
eventually, the robot was left with a single feasible start configuration").

    .venv/bin/python tools/design_fig3_scenes.py [--seed 7] [--trials 400]

It rewrites config/scenes/fig3a.yaml, fig3b.yaml and fig3c.yaml.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import yaml

from ftplan_ros.core.io.fingerprint import scene_to_dict
from ftplan_ros.core.io.scene_file import parse_scene
from ftplan_ros.core.model.angles import wrap_angle
from ftplan_ros.core.model.scene import Obstacle, Scene
from ftplan_ros.core.paper.manifolds import ManifoldCache
from ftplan_ros.core.planning.planner import plan

SCENES = Path(__file__).resolve().parents[1] / 'config' / 'scenes'

# Table I of the paper [deg], with its start positions [m].
PAPER = {
    'fig3a': ([2.0, 0.0], [-73.3, 114.0, -23.0], 'squeezed through random disks'),
    'fig3b': ([2.0, 0.0], [66.7, -119.1, 45.1], 'a walled, pipe-like arrangement'),
    'fig3c': ([2.5, 0.0], [23.5, -73.0, 70.9], 'random disks, start farther out'),
}
RADIUS = 0.2
GAP = 0.03  # [m] the disks keep this far from the paper θ_s's failure surface


def survivors(scene: Scene, cache: ManifoldCache, theta_s: np.ndarray) -> np.ndarray:
    """Proposed starts (p, n) [rad] other than those within 3 deg of the paper's θ_s."""
    proposed = plan(scene, cache=cache).proposed_starts
    far = np.max(np.abs(wrap_angle(proposed - theta_s)), axis=1) > np.radians(3.0)
    return proposed[far]


def clear_of(surface_points: np.ndarray, robot, center: np.ndarray) -> np.ndarray:
    """Slide a disk centre (2,) [m] until the disk clears the arm at every surface point."""
    for _ in range(4):
        segments = robot.link_segments(surface_points)[..., :2]  # (k, L, 2, 2)
        start, direction = segments[..., 0, :], segments[..., 1, :] - segments[..., 0, :]
        t = np.clip(np.einsum('kld,kld->kl', center - start, direction)
                    / np.einsum('kld,kld->kl', direction, direction), 0.0, 1.0)
        nearest = start + t[..., None] * direction
        gaps = np.linalg.norm(center - nearest, axis=-1)
        k, j = np.unravel_index(np.argmin(gaps), gaps.shape)
        if gaps[k, j] >= RADIUS + GAP:
            break
        away = (center - nearest[k, j]) / max(gaps[k, j], 1e-9)
        center = center + (RADIUS + GAP - gaps[k, j]) * away
    return center


def design(name: str, rng: np.random.Generator, trials: int, target: int) -> Scene:
    """Add disks while the paper's θ_s stays feasible and the other starts die out.

    Each disk is dropped on the arm of a surviving start (or on its way towards a random
    goal configuration), then slid just clear of the paper θ_s's own failure surface, so
    that it can kill the neighbours of θ_s without killing θ_s.
    """
    start, theta_deg, _ = PAPER[name]
    theta_s = np.radians(theta_deg)
    scene = parse_scene({'robot': {'type': 'planar', 'link_lengths': [1.0, 1.0, 1.0]},
                         'task': {'start': start, 'goal': [1.0, 0.0],
                                  'goal_tolerance': 0.01}}, name=name)
    robot = scene.robot
    cache = ManifoldCache()  # filled by plan() itself, exactly as a default plan() samples
    first = plan(scene, cache=cache, start_configuration=theta_s)
    own = first.surface.vertices
    goals = np.vstack([b.points for b in first.goal_manifolds])
    others = survivors(scene, cache, theta_s)
    for trial in range(trials):
        if len(others) <= target:
            break
        theta = others[rng.integers(len(others))]
        if rng.uniform() < 0.5:
            theta = theta + rng.uniform() * (goals[rng.integers(len(goals))] - theta)
        points = robot.joint_positions(theta)
        link = rng.integers(robot.n_joints)
        point = clear_of(own, robot, points[link] + rng.uniform() * (points[link + 1]
                                                                      - points[link]))
        center = (round(float(point[0]), 3), round(float(point[1]), 3), 0.0)
        if np.hypot(*center[:2]) < 0.5 or any(
                np.hypot(center[0] - ob.center[0], center[1] - ob.center[1]) < 2.0 * RADIUS
                for ob in scene.obstacles):
            continue
        trial_scene = scene.with_obstacles([Obstacle('sphere', center, radius=RADIUS)])
        checked = plan(trial_scene, cache=cache, start_configuration=theta_s)
        if not checked.feasible:
            continue
        remaining = survivors(trial_scene, cache, theta_s)
        if len(remaining) < len(others):
            scene, others, own = trial_scene, remaining, checked.surface.vertices
            print(f'{name}: trial {trial}: disk at {center[:2]} leaves {len(others)} other '
                  'starts', flush=True)
    return scene


def main() -> None:
    """Design the three scenes and write them as YAML."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--seed', type=int, default=7)
    parser.add_argument('--trials', type=int, default=1500)
    parser.add_argument('--target', type=int, default=0,
                        help='stop when this few other starts survive')
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    for name, (_, theta_deg, story) in PAPER.items():
        scene = design(name, rng, args.trials, args.target)
        header = (f'# Fig. 3({name[-1]})-like scene: {story}. Disks of radius {RADIUS} m were\n'
                  f'# added by tools/design_fig3_scenes.py --seed {args.seed} while the '
                  f'paper\'s theta_s\n# {theta_deg} deg stayed a verified failure-tolerant '
                  'start and fewer others survived.\n')
        data = scene_to_dict(scene)
        data['robot'] = '../robots/planar3r.yaml'
        text = yaml.safe_dump(data, sort_keys=False, default_flow_style=None)
        (SCENES / f'{name}.yaml').write_text(header + text)
        print(f'wrote {name}.yaml with {len(scene.obstacles)} disks')


if __name__ == '__main__':
    main()
