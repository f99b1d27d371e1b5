"""Robot models behind one small interface: the kinematic function f of the paper (Sec. II).

The algorithm only uses what `Robot` declares, so a spatial chain plugs in beside
`PlanarChain` without touching it. Configurations are arrays of shape (n,) or (..., n)
in radians; positions are in metres in the robot base frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import numba
import numpy as np

from .errors import InputError

PLANAR = 0  # `Robot.kernel_kind` of PlanarChain


class Robot(Protocol):
    """What the planner needs to know about an arm."""

    joint_names: tuple[str, ...]
    link_radius: float

    @property
    def n_joints(self) -> int:
        """Number of joints n."""

    @property
    def task_dim(self) -> int:
        """Dimension m of the end-effector position x = f(θ)."""

    @property
    def periodic(self) -> np.ndarray:
        """(n,) bool: True for joints without limits, whose angle wraps to (-π, π]."""

    @property
    def limits(self) -> np.ndarray:
        """(n, 2) lower and upper joint limits [rad]; (-π, π] for periodic joints."""

    def forward_kinematics(self, thetas: np.ndarray) -> np.ndarray:
        """End-effector position (..., m) [m] of configurations (..., n) [rad]."""

    def jacobian(self, thetas: np.ndarray) -> np.ndarray:
        """Position Jacobian (..., m, n) [m/rad] of configurations (..., n) [rad]."""

    @property
    def kernel_kind(self) -> int:
        """Which compiled kinematics `chain_kinematics` runs for this robot (e.g. PLANAR)."""

    @property
    def kernel_parameters(self) -> np.ndarray:
        """The float array that `chain_kinematics` takes as this robot's parameters."""

    def link_segments(self, thetas: np.ndarray) -> np.ndarray:
        """Core segments (..., L, 2, 3) [m] of the L link capsules, in the base frame."""

    def link_lever_arms(self) -> np.ndarray:
        """(L, n) bound [m] on the distance from joint a's axis to any point of link j.

        Row j, column a bounds how fast link j moves when joint a turns: a point of link
        j moves at most Σ_a R[j, a] |Δθ_a| along a straight joint-space segment Δθ.
        """

    def tip_lever_arms(self) -> np.ndarray:
        """(n,) bound [m] on the distance from each joint axis to the end effector."""

    def can_reach(self, x: np.ndarray) -> bool:
        """Whether some configuration puts the end effector at x (m,) [m]."""


@dataclass(frozen=True)
class PlanarChain:
    """A planar serial chain of n revolute joints with parallel axes (z) in the plane z = 0.

    Link k runs from joint k to joint k+1 (the last link ends at the end effector); its
    capsule has radius `link_radius` [m] around that segment. Joints without limits wrap.
    """

    link_lengths: tuple[float, ...]
    joint_names: tuple[str, ...]
    link_radius: float = 0.0
    joint_limits: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        if len(self.joint_names) != len(self.link_lengths):
            raise InputError(
                'robot.joint_names',
                f'{len(self.joint_names)} names for {len(self.link_lengths)} links')
        if self.joint_limits is not None and len(self.joint_limits) != len(self.link_lengths):
            raise InputError(
                'robot.joint_limits',
                f'{len(self.joint_limits)} limits for {len(self.link_lengths)} joints')

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return len(self.link_lengths)

    @property
    def task_dim(self) -> int:
        """The planar end-effector position has m = 2 components."""
        return 2

    @cached_property
    def periodic(self) -> np.ndarray:
        """(n,) bool: True for joints without limits."""
        periodic = np.array([lim is None for lim in self.joint_limits or
                             (None,) * self.n_joints], dtype=bool)
        periodic.flags.writeable = False
        return periodic

    @cached_property
    def limits(self) -> np.ndarray:
        """(n, 2) joint limits [rad]; (-π, π] for periodic joints."""
        out = np.tile([-np.pi, np.pi], (self.n_joints, 1))
        for j, lim in enumerate(self.joint_limits or ()):
            if lim is not None:
                out[j] = lim
        out.flags.writeable = False
        return out

    def _absolute_angles(self, thetas: np.ndarray) -> np.ndarray:
        return np.cumsum(np.asarray(thetas, dtype=float), axis=-1)

    def joint_positions(self, thetas: np.ndarray) -> np.ndarray:
        """Positions (..., n+1, 2) [m] of the base, every joint and the end effector."""
        phi = self._absolute_angles(thetas)
        steps = np.asarray(self.link_lengths)[..., None] * np.stack(
            [np.cos(phi), np.sin(phi)], axis=-1)
        zero = np.zeros(steps.shape[:-2] + (1, 2))
        return np.concatenate([zero, np.cumsum(steps, axis=-2)], axis=-2)

    def forward_kinematics(self, thetas: np.ndarray) -> np.ndarray:
        """End-effector position (..., 2) [m] of configurations (..., n) [rad]."""
        phi = self._absolute_angles(thetas)
        lengths = np.asarray(self.link_lengths)
        return np.stack([np.sum(lengths * np.cos(phi), axis=-1),
                         np.sum(lengths * np.sin(phi), axis=-1)], axis=-1)

    def jacobian(self, thetas: np.ndarray) -> np.ndarray:
        """Position Jacobian (..., 2, n) [m/rad]: column a sums the links from joint a on."""
        phi = self._absolute_angles(thetas)
        lengths = np.asarray(self.link_lengths)
        # Reverse cumulative sums: joint a moves every link k >= a.
        dx = -np.cumsum((lengths * np.sin(phi))[..., ::-1], axis=-1)[..., ::-1]
        dy = np.cumsum((lengths * np.cos(phi))[..., ::-1], axis=-1)[..., ::-1]
        return np.stack([dx, dy], axis=-2)

    @property
    def kernel_kind(self) -> int:
        """PLANAR: `chain_kinematics` runs `planar_kinematics`."""
        return PLANAR

    @cached_property
    def kernel_parameters(self) -> np.ndarray:
        """The link lengths (n,) [m], the parameters of `planar_kinematics`."""
        return np.array(self.link_lengths, dtype=float)

    def link_segments(self, thetas: np.ndarray) -> np.ndarray:
        """Core segments (..., n, 2, 3) [m] of the link capsules, at z = 0."""
        points = self.joint_positions(thetas)
        points = np.concatenate([points, np.zeros(points.shape[:-1] + (1,))], axis=-1)
        return np.stack([points[..., :-1, :], points[..., 1:, :]], axis=-2)

    def link_lever_arms(self) -> np.ndarray:
        """(n, n) R[j, a] = Σ_{k=a..j} ℓ_k [m]: farthest point of link j from joint a."""
        lengths = np.asarray(self.link_lengths)
        n = self.n_joints
        arms = np.zeros((n, n))
        for j in range(n):
            for a in range(j + 1):
                arms[j, a] = lengths[a:j + 1].sum()
        return arms

    def tip_lever_arms(self) -> np.ndarray:
        """(n,) Σ_{k>=a} ℓ_k [m]: farthest the end effector can be from joint a."""
        return np.cumsum(np.asarray(self.link_lengths)[::-1])[::-1].copy()

    def can_reach(self, x: np.ndarray) -> bool:
        """Whether x (2,) [m] lies in the annulus the chain sweeps."""
        lengths = np.asarray(self.link_lengths)
        outer = lengths.sum()
        inner = max(0.0, 2.0 * lengths.max() - outer)
        return bool(inner - 1e-12 <= np.linalg.norm(x) <= outer + 1e-12)


@numba.njit(cache=True)
def planar_kinematics(lengths: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """End-effector position (2,) [m] and Jacobian (2, n) [m/rad] of a planar chain.

    :param lengths: (n,) link lengths [m]; joint k turns links k..n-1.
    :param theta: (n,) joint angles [rad].
    """
    n = theta.shape[0]
    xs = np.empty(n)
    ys = np.empty(n)
    phi = 0.0
    for k in range(n):
        phi += theta[k]
        xs[k] = lengths[k] * np.cos(phi)
        ys[k] = lengths[k] * np.sin(phi)
    position = np.zeros(2)
    jac = np.empty((2, n))
    for k in range(n - 1, -1, -1):  # joint k moves links k..n-1
        position[0] += xs[k]
        position[1] += ys[k]
        jac[0, k] = -position[1]
        jac[1, k] = position[0]
    return position, jac


@numba.njit(cache=True)
def chain_kinematics(kind: int, parameters: np.ndarray, theta: np.ndarray,
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Position (m,) [m] and Jacobian (m, n) [m/rad] of θ (n,) [rad], compiled, by robot kind.

    The compiled kernels (continuation.py) call this; a new kind of chain adds its branch.
    """
    if kind == PLANAR:
        return planar_kinematics(parameters, theta)
    raise ValueError('no compiled kinematics for this kind of robot')
