"""A spatial serial chain of revolute joints, with its links' collision geometry.

`ChainModel` is what a URDF (urdf.py) or a DH table (dh.py) comes down to: for each
joint its frame in its parent's at zero angle and its unit axis, the tool frame in the
last joint's, joint limits (position; velocity, acceleration and jerk in
`motion_limits`), and the collision shapes of every link in the link's frame.
Link 0 is the base; link j >= 1 is the body joint j-1 turns, and its frame is that
joint's. Lengths [m], angles [rad]. `SpatialArm` (spatial.py) binds it to a task.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from . import kinematics
from .motion_limits import MotionLimits
from .robot import LinkShape


@dataclass(frozen=True, eq=False)
class ChainModel:
    """An arm: kinematics, limits and collision geometry (see the module docstring).

    `placements` (n, 4, 4): joint j's frame in joint j-1's frame (in the base frame for
    j = 0) at zero angle; `axes` (n, 3): unit axes in the joints' own frames; `tool`
    (4, 4): the tool frame in the last joint's frame. `joint_limits[j]` is (lower,
    upper) [rad] or None for a continuous joint. `link_names` has n + 1 names, the base
    first. `disabled_pairs` are link pairs never checked for self-collision;
    `exempt_urdf_pairs` are pairs of URDF links whose shapes are never checked, also
    where their chain links are (an SRDF's exemptions of links folded into others).
    `motion_limits` are the joints' velocity, acceleration and jerk limits (None: the
    defaults of motion_limits.py).
    """

    name: str
    joint_names: tuple[str, ...]
    link_names: tuple[str, ...]
    placements: np.ndarray
    axes: np.ndarray
    tool: np.ndarray
    joint_limits: tuple[tuple[float, float] | None, ...]
    shapes: tuple[LinkShape, ...] = ()
    disabled_pairs: frozenset[tuple[int, int]] = field(default_factory=frozenset)
    exempt_urdf_pairs: frozenset[frozenset[str]] = field(default_factory=frozenset)
    tool_frame: str = 'tool'
    motion_limits: MotionLimits | None = None

    def __post_init__(self):
        n = len(self.joint_names)
        for what, value, shape in (('placements', self.placements, (n, 4, 4)),
                                   ('axes', self.axes, (n, 3)), ('tool', self.tool, (4, 4))):
            if np.shape(value) != shape:
                raise ValueError(f'{what} must have shape {shape}, got {np.shape(value)}')
        if len(self.link_names) != n + 1 or len(self.joint_limits) != n:
            raise ValueError('a chain of n joints has n + 1 links and n joint limits')

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return len(self.joint_names)

    @cached_property
    def parameters(self) -> np.ndarray:
        """The chain laid out for the compiled kernels (`kinematics.spatial_parameters`)."""
        return kinematics.spatial_parameters(self.placements, self.axes, self.tool)

    def frames(self, thetas: np.ndarray) -> np.ndarray:
        """Frames (..., n+2, 4, 4) in the base frame: base, links 1..n, tool."""
        thetas = np.asarray(thetas, dtype=float)
        flat = np.require(thetas.reshape(-1, self.n_joints), requirements='CW')  # as warmed
        out = kinematics.chain_frames(self.parameters, flat)
        return out.reshape(thetas.shape[:-1] + out.shape[1:])

    @cached_property
    def _offsets(self) -> np.ndarray:
        """(n,) distance [m] between the origins of joint j-1 and joint j (j = 0: from the base)."""
        return np.linalg.norm(self.placements[:, :3, 3], axis=1)

    def frame_lever_arms(self) -> np.ndarray:
        """(n+1, n) R[j, a] [m]: bound on the distance from joint a's axis to link j's origin.

        Joint a's axis passes through its origin; link j's origin is joint j-1's, at most
        Σ_{i=a+1}^{j-1} d_i from joint a's origin (d_i the joint offsets).
        """
        n = self.n_joints
        arms = np.zeros((n + 1, n))
        for j in range(1, n + 1):
            for a in range(j):
                arms[j, a] = self._offsets[a + 1:j].sum()
        return arms

    def tip_lever_arms(self) -> np.ndarray:
        """(n,) bound [m] on the distance from joint a's axis to the tool point."""
        tool = float(np.linalg.norm(self.tool[:3, 3]))
        return np.array([self._offsets[a + 1:].sum() + tool for a in range(self.n_joints)])

    @cached_property
    def self_collision_pairs(self) -> tuple[tuple[int, int], ...]:
        """Link pairs (a, b), a < b, both with geometry and not disabled."""
        links = sorted({item.link for item in self.shapes})
        return tuple((a, b) for k, a in enumerate(links) for b in links[k + 1:]
                     if (a, b) not in self.disabled_pairs)
