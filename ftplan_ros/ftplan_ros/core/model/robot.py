"""Robot models behind one small interface: the kinematic function f of the paper (Sec. II).

The algorithm only uses what `Robot` declares, so the planar chain of the paper and
spatial chains from URDF or DH (spatial.py) go through the same code. Configurations
are arrays of shape (n,) or (..., n) in radians; positions are in metres in the robot
base frame. `task_residuals` and `task_errors` are the task-error map every algorithm
uses: none writes x - f(θ) itself.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import numpy as np

from ..errors import InputError
from ..validation import nonnegative
from . import kinematics
from .geometry import Shape, transform

# Takes a capsule's core segment from its local z axis onto the link's x axis.
_Z_TO_X = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])


class Robot(Protocol):
    """What the planner needs to know about an arm bound to a kind of task.

    Joints are revolute, numbered 0..n-1 from the base. Links are numbered 0..L-1: link
    0 is the base (it never moves) and link j >= 1 is turned by the joints whose
    `joint_chain_index` is below j (joints 0..j-1 of a whole chain; a chain with frozen
    joints skips them).
    """

    joint_names: tuple[str, ...]

    @property
    def n_joints(self) -> int:
        """Number of joints n."""

    @property
    def joint_chain_index(self) -> np.ndarray:
        """(n,) int: each joint's place in the chain; joint a turns link j when index < j."""

    @property
    def task_kind(self) -> str:
        """What the tool must do: 'planar', 'position', 'axis' or 'pose' (task_space.py)."""

    @property
    def task_dim(self) -> int:
        """Dimension m of the task (2 planar, 3 position, 5 axis, 6 pose); r = n - m."""

    @property
    def periodic(self) -> np.ndarray:
        """(n,) bool: True for joints without limits, whose angle wraps to (-π, π]."""

    @property
    def limits(self) -> np.ndarray:
        """(n, 2) lower and upper joint limits [rad]; (-π, π] for periodic joints."""

    def forward_kinematics(self, thetas: np.ndarray) -> np.ndarray:
        """Task points (..., k) of configurations (..., n) [rad] (task_space.point_size)."""

    @property
    def kernel_kind(self) -> int:
        """Which compiled task map `kinematics.task_residual` runs for this robot."""

    @property
    def kernel_parameters(self) -> np.ndarray:
        """The float array that `kinematics.task_residual` takes as this robot's parameters."""

    @property
    def link_names(self) -> tuple[str, ...]:
        """Names of the L links, the base first."""

    def link_frames(self, thetas: np.ndarray) -> np.ndarray:
        """Frames (..., L, 4, 4) of the links in the base frame at configurations (..., n)."""

    @property
    def collision_shapes(self) -> tuple[LinkShape, ...]:
        """The links' collision geometry, each shape posed in its link's frame."""

    @property
    def self_collision_pairs(self) -> tuple[tuple[int, int], ...]:
        """Link pairs (a, b), a < b, whose distance must stay positive."""

    @property
    def exempt_urdf_pairs(self) -> frozenset[frozenset[str]]:
        """Pairs of URDF links (`LinkShape.urdf_link`) whose shapes are never checked."""

    def frame_lever_arms(self) -> np.ndarray:
        """(L, n) bound [m] on the distance from joint a's axis to the origin of link j's frame.

        Zero where joint a does not turn link j (a >= j). With the extent of a shape from
        its link's origin added, it bounds how fast the shape moves when joint a turns:
        a point of it moves at most Σ_a (R[j, a] + extent) |Δθ_a| along a straight
        joint-space segment Δθ (checker.py).
        """

    def tip_lever_arms(self) -> np.ndarray:
        """(n,) bound [m] on the distance from each joint axis to the tool point."""

    def skeleton(self, thetas: np.ndarray) -> np.ndarray:
        """Points (..., k, 3) [m] to draw the arm by: base, joints, tool."""

    def can_reach(self, x: np.ndarray) -> bool:
        """Whether the task point x might be reachable (a quick necessary check)."""


@dataclass(frozen=True, eq=False)
class LinkShape:
    """A collision shape of link `link`, posed by `placement` (4, 4) in the link's frame.

    `urdf_link` names the URDF link the shape comes from (a link folded into `link` by a
    fixed or locked joint, or `link` itself); '' for chains not read from a URDF.
    """

    link: int
    shape: Shape
    placement: np.ndarray
    urdf_link: str = ''


@dataclass(frozen=True)
class PlanarChain:
    """A planar serial chain of n revolute joints with parallel axes (z) in the plane z = 0.

    Link k (1..n) runs from joint k-1 to joint k (the last link ends at the end effector);
    its capsule has radius `link_radius` [m] around that segment. Joints without limits
    wrap.
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
        nonnegative(self.link_radius, 'robot.link_radius')  # negative: it would read as clearance

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

    @property
    def joint_chain_index(self) -> np.ndarray:
        """(n,) 0..n-1: joint a turns links a+1..n."""
        return np.arange(self.n_joints)

    @property
    def task_kind(self) -> str:
        """A planar arm positions its tool in the plane."""
        return 'planar'

    @property
    def kernel_kind(self) -> int:
        """PLANAR: `kinematics.task_residual` runs `planar_kinematics`."""
        return kinematics.PLANAR

    @cached_property
    def kernel_parameters(self) -> np.ndarray:
        """The link lengths (n,) [m], the parameters of `planar_kinematics`."""
        return np.array(self.link_lengths, dtype=float)

    @cached_property
    def link_names(self) -> tuple[str, ...]:
        """'base', then 'link1'..'linkn'."""
        return ('base',) + tuple(f'link{k + 1}' for k in range(self.n_joints))

    def link_frames(self, thetas: np.ndarray) -> np.ndarray:
        """Frames (..., n+1, 4, 4): the base, then link k at joint k-1 with x along the link."""
        thetas = np.asarray(thetas, dtype=float)
        flat = np.ascontiguousarray(thetas.reshape(-1, self.n_joints))
        frames = kinematics.planar_frames(self.kernel_parameters, flat)
        return frames.reshape(thetas.shape[:-1] + frames.shape[1:])

    @cached_property
    def collision_shapes(self) -> tuple[LinkShape, ...]:
        """A capsule of radius `link_radius` along each link; the base is a ball of it."""
        base = LinkShape(0, Shape('sphere', radius=self.link_radius), np.eye(4))
        return (base,) + tuple(
            LinkShape(k + 1, Shape('capsule', radius=self.link_radius, length=length),
                      transform(_Z_TO_X, (0.5 * length, 0.0, 0.0)))
            for k, length in enumerate(self.link_lengths))

    @property
    def self_collision_pairs(self) -> tuple[tuple[int, int], ...]:
        """None: the paper's arm folds onto itself."""
        return ()

    @property
    def exempt_urdf_pairs(self) -> frozenset[frozenset[str]]:
        """None: the arm has no URDF."""
        return frozenset()

    def frame_lever_arms(self) -> np.ndarray:
        """(n+1, n) R[j, a] = Σ_{k=a..j-2} ℓ_k [m]: joint a to link j's origin (joint j-1)."""
        lengths = np.asarray(self.link_lengths)
        n = self.n_joints
        arms = np.zeros((n + 1, n))
        for j in range(1, n + 1):
            for a in range(j):
                arms[j, a] = lengths[a:j - 1].sum()
        return arms

    def tip_lever_arms(self) -> np.ndarray:
        """(n,) Σ_{k>=a} ℓ_k [m]: farthest the end effector can be from joint a."""
        return np.cumsum(np.asarray(self.link_lengths)[::-1])[::-1].copy()

    def skeleton(self, thetas: np.ndarray) -> np.ndarray:
        """Return base, joints and end effector (..., n+1, 3) [m], at z = 0."""
        points = self.joint_positions(thetas)
        return np.concatenate([points, np.zeros(points.shape[:-1] + (1,))], axis=-1)

    def can_reach(self, x: np.ndarray) -> bool:
        """Whether x (2,) [m] lies in the annulus the chain sweeps."""
        lengths = np.asarray(self.link_lengths)
        outer = lengths.sum()
        inner = max(0.0, 2.0 * lengths.max() - outer)
        return bool(inner - 1e-12 <= np.linalg.norm(x) <= outer + 1e-12)


def task_residuals(robot: Robot, x: np.ndarray, thetas: np.ndarray,
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Residuals (N, m) of configurations (N, n) [rad] against task point x, and Jacobians.

    A Newton step δθ (n,) solves J δθ = residual (kinematics.task_residual says how each
    task measures it); the Jacobians are (N, m, n).
    """
    thetas = np.ascontiguousarray(np.atleast_2d(thetas), dtype=float)
    return kinematics.task_residuals(robot.kernel_kind, robot.kernel_parameters,
                                  np.asarray(x, dtype=float), thetas, robot.task_dim)


def task_errors(robot: Robot, x: np.ndarray, thetas: np.ndarray) -> np.ndarray:
    """Distances (..., 2) of configurations (..., n) [rad] from task point x.

    Column 0 is the tool's distance [m] from x's position, column 1 the angle [rad]
    between the tool's orientation (or axis) and x's (0 for position tasks).
    """
    thetas = np.asarray(thetas, dtype=float)
    flat = np.ascontiguousarray(thetas.reshape(-1, thetas.shape[-1]))
    out = kinematics.task_errors(robot.kernel_kind, robot.kernel_parameters,
                              np.asarray(x, dtype=float), flat)
    return out.reshape(thetas.shape[:-1] + (2,))


def geometry_sha256(robot: Robot) -> str:
    """Return a SHA-256 (hex) of what the kernels and collision checks use of the robot.

    That is its kinematic parameters, collision shapes and self-collision pairs.
    """
    geometry = hashlib.sha256(np.ascontiguousarray(robot.kernel_parameters).tobytes())
    for link in robot.collision_shapes:
        shape = link.shape
        geometry.update(repr((link.link, shape.kind, shape.radius, shape.size,
                              shape.length)).encode())
        for array in (link.placement, shape.vertices, shape.faces):
            geometry.update(np.ascontiguousarray(array).tobytes())
    geometry.update(repr(robot.self_collision_pairs).encode())
    if robot.exempt_urdf_pairs:  # robots without them keep the digests they had
        geometry.update(repr(sorted(sorted(pair) for pair in robot.exempt_urdf_pairs)).encode())
    return geometry.hexdigest()


def robot_digest(robot: Robot) -> str:
    """Name the robot's model by a digest: 12 hex digits.

    It covers what a plan depends on: joint names, limits [rad] (periodic joints too), the
    chain the joints sit in, and `geometry_sha256`; not the task kind, which the same
    model takes on per request. A plan made for one robot is stale for a robot of
    another digest, even one with the same joint names.
    """
    limits = [[float(v) if math.isfinite(v) else None for v in row] for row in robot.limits]
    text = repr((tuple(robot.joint_names), limits, robot.periodic.tolist(),
                 robot.joint_chain_index.tolist(), geometry_sha256(robot)))
    return hashlib.sha256(text.encode()).hexdigest()[:12]
