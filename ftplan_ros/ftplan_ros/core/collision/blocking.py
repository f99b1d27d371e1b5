"""What keeps a self-motion manifold from being free: the obstacle or link pair that blocks it.

When no point of M_s (or M_g) is free, the planner says which obstacle or pair of links
blocks most of its points, and what to do about it. Up to SAMPLED points spread along the
manifold are measured exactly (the checker's refined distances, below the margin): per
pair of links, and per obstacle for the points an obstacle blocks. A pair is named by the
URDF links whose shapes touch most (a chain link carries the links folded into it: the
hand on the last one). Step 2 marks points free by cheap lower bounds; where exact
distances find sampled points clear, that is said too: the bounds are then too loose for
the robot's geometry, not the scene too full.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

import numpy as np

from ..model.scene import Obstacle
from .checker import CollisionChecker
from .self_collision import Contacts

SAMPLED = 100  # points of a manifold measured exactly
NAMED = 3  # blockers named in a report


@dataclass(frozen=True)
class Blocker:
    """An obstacle or a pair of links, and the share of the sampled points it blocks."""

    kind: str  # 'obstacle' or 'links'
    name: str
    share: float  # of the sampled points, 0..1
    advice: str

    def blocks(self) -> str:
        """Say how much it blocks: 'blocks 93 % of', 'overlap in every one of'."""
        verb = 'blocks' if self.kind == 'obstacle' else 'overlap in'
        return f'{verb} {"every one" if self.share == 1.0 else f"{100.0 * self.share:.0f} %"} of'

    def to_json(self) -> dict:
        """Return the blocker as plain data (the plan result's stats)."""
        return {'kind': self.kind, 'name': self.name, 'share': self.share,
                'advice': self.advice}


@dataclass(frozen=True)
class Blocking:
    """What blocks the sampled points of a manifold: blockers, most first, and the clear ones."""

    blockers: tuple[Blocker, ...]
    sampled: int
    clear: int  # sampled points with every exact distance above the margin

    def describe(self, which: str) -> str:
        """Say it in a sentence or two; `which` is 'start' or 'goal'."""
        points = f'sampled {which} configurations'
        parts = []
        if self.clear:
            parts.append(f'exact distances find {self.clear} of {self.sampled} {points} '
                         'clear: Step 2\'s cheap lower bounds are too loose for this robot\'s '
                         'geometry (meshes, thin links), not the scene too full')
        if self.blockers:
            first, *others = self.blockers
            parts.append(f'{first.name} {first.blocks()} the {self.sampled} {points}: '
                         f'{first.advice}')
            if others:
                parts.append('also ' + ', '.join(f'{b.name} ({100.0 * b.share:.0f} %)'
                                                 for b in others))
        return '; '.join(parts) or f'no obstacle or pair of links blocks the {points}'

    def to_json(self) -> dict:
        """Return it as plain data (the plan result's stats)."""
        return {'sampled': self.sampled, 'clear': self.clear,
                'blockers': [b.to_json() for b in self.blockers]}


def find_blocking(checker: CollisionChecker, points: np.ndarray, margin: float) -> Blocking:
    """Measure up to SAMPLED of a manifold's points (k, n) [rad] spread along it.

    A point is blocked by a channel whose clearance is <= `margin` [m] (Step 2's test).
    """
    index = np.unique(np.linspace(0, len(points) - 1, min(SAMPLED, len(points))).round())
    thetas = np.asarray(points, dtype=float)[index.astype(int)]
    clearance = checker.clearance(thetas, needed=margin)
    blocked = ~(clearance > margin)  # NaN blocks
    links = checker.channel_links
    counts = Counter()
    names = {}
    for a, b in sorted({(int(a), int(b)) for a, b in links[links[:, 1] >= 0]}):
        hit = blocked[:, (links[:, 0] == a) & (links[:, 1] == b)].any(axis=1)
        if hit.any():
            key = ('pair', a, b)
            counts[key] = int(hit.sum())
            names[key] = _pair_name(checker, a, b, thetas[hit])
    by_obstacles = blocked[:, links[:, 1] < 0].any(axis=1)
    if by_obstacles.any():
        for p, hits in _obstacle_hits(checker, thetas[by_obstacles], margin).items():
            counts[('obstacle', p)] = hits
    ranked = sorted(counts.items(), key=lambda item: (-item[1], item[0]))[:NAMED]
    blockers = tuple(_blocker(checker, key, names.get(key), hits / len(thetas))
                     for key, hits in ranked)
    return Blocking(blockers, len(thetas), int(np.count_nonzero(~blocked.any(axis=1))))


def _obstacle_hits(checker: CollisionChecker, thetas: np.ndarray, margin: float,
                   ) -> dict[int, int]:
    """Count, per obstacle, the configurations (N, n) it blocks, one checker per obstacle."""
    out = {}
    for p, obstacle in enumerate(checker.obstacles):
        single = CollisionChecker(checker.robot, [obstacle])
        moving = single.channel_links[:, 1] < 0
        needed = np.where(moving, margin, -np.inf)[None, :]  # links apart: not measured again
        clearance = single.clearance(thetas, needed=np.broadcast_to(needed, (len(thetas),
                                                                             len(moving))))
        hits = int(np.count_nonzero(~(clearance[:, moving] > margin).all(axis=1)))
        if hits:
            out[p] = hits
    return out


def _pair_name(checker: CollisionChecker, a: int, b: int, thetas: np.ndarray) -> str:
    """Name links a and b by the URDF links whose shapes touch in most of `thetas`."""
    robot = checker.robot
    contacts = Contacts(robot, [(a, b)])
    touching = contacts.shapes_touching(thetas).sum(axis=0)
    names = [robot.link_names[a], robot.link_names[b]]
    if len(touching) and touching.max() > 0:
        s, t, _ = contacts.shape_pairs[int(np.argmax(touching))]
        names = [contacts.shapes[s].urdf_link or names[0], contacts.shapes[t].urdf_link or names[1]]
    return ' / '.join(names)


def _blocker(checker: CollisionChecker, key: tuple, pair_name: str | None,
             share: float) -> Blocker:
    if key[0] == 'obstacle':
        p = key[1]
        return Blocker('obstacle', f'obstacle {p} ({_obstacle_text(checker.obstacles[p])})',
                       share, 'move it, or the task point')
    names = checker.robot.link_names
    a, b = names[key[1]], names[key[2]]
    return Blocker('links', pair_name, share, f'if they may touch, exempt them: add [{a}, {b}] to '
                   'robot.disabled_collisions or give the robot\'s SRDF (robot.srdf, '
                   '/robot_description_semantic)')


def _obstacle_text(obstacle: Obstacle) -> str:
    centre = ', '.join(f'{v:.2f}' for v in obstacle.center)
    return f'{obstacle.shape} at [{centre}]'
