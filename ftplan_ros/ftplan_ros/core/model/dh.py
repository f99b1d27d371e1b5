"""Spatial chains from Denavit-Hartenberg tables, for the arms of papers.

Standard (distal) DH: row j takes frame j-1 to frame j by Rot_z(θ_j + offset_j),
Trans_z(d_j), Trans_x(a_j), Rot_x(α_j); joint j turns about frame j-1's z axis. The tool
sits at `tip_offset` [m] in the last frame. Each link is a capsule of radius
`link_radius` [m] from its joint to the next (or to the last frame's origin).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .chain import ChainModel
from .geometry import Shape, transform
from .robot import LinkShape


@dataclass(frozen=True)
class DHRow:
    """One joint's DH parameters: a, d [m], alpha, offset [rad], limits (lower, upper) or None."""

    a: float
    alpha: float
    d: float
    offset: float = 0.0
    limits: tuple[float, float] | None = None


def chain_from_dh(rows: Sequence[DHRow], joint_names: Sequence[str], link_radius: float,
                  tip_offset: Sequence[float] = (0.0, 0.0, 0.0), name: str = 'dh') -> ChainModel:
    """Build the chain of a DH table (see the module docstring)."""
    n = len(rows)
    after = [_distal(row) for row in rows]  # frame j-1 (rotated) to frame j
    placements = np.empty((n, 4, 4))
    for j, row in enumerate(rows):
        before = np.eye(4) if j == 0 else after[j - 1]
        placements[j] = before @ transform(_rot_z(row.offset), np.zeros(3))
    tool = after[-1] @ transform(np.eye(3), tip_offset)
    shapes = []
    for j in range(n):
        end = (after[j] if j < n - 1 else tool)[:3, 3]
        length = float(np.linalg.norm(end))
        if length == 0.0:
            shapes.append(LinkShape(j + 1, Shape('sphere', radius=link_radius), np.eye(4)))
            continue
        direction = end / length
        shapes.append(LinkShape(j + 1, Shape('capsule', radius=link_radius, length=length),
                                transform(_z_onto(direction), 0.5 * end)))
    links = ('base',) + tuple(f'link{j + 1}' for j in range(n))
    return ChainModel(name, tuple(joint_names), links, placements,
                      np.tile([0.0, 0.0, 1.0], (n, 1)), tool,
                      tuple(row.limits for row in rows), tuple(shapes))


def _distal(row: DHRow) -> np.ndarray:
    """Trans_z(d) Trans_x(a) Rot_x(α) as a transform (4, 4)."""
    c, s = np.cos(row.alpha), np.sin(row.alpha)
    return transform(np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]),
                     (row.a, 0.0, row.d))


def _rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _z_onto(direction: np.ndarray) -> np.ndarray:
    """Return a rotation (3, 3) taking the z axis onto the unit `direction`."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(direction[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, direction)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(direction, x), direction])
