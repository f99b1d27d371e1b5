"""A spatial arm bound to a task: the `Robot` of chains from URDF or DH.

The same `ChainModel` serves position, tool-axis and pose tasks; `SpatialArm(model,
'pose')` is the arm as the planner sees it for 6-D poses (m = 6, so a 7-joint arm has
one degree of redundancy). Angles [rad], lengths [m], frames in the robot's base frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from . import kinematics
from .chain import ChainModel
from .robot import LinkShape
from .task_space import TASK_DIM, points_from_frames

_KERNEL_KIND = {'position': kinematics.POSITION, 'axis': kinematics.AXIS, 'pose': kinematics.POSE}


@dataclass(frozen=True)
class SpatialArm:
    """`model` doing tasks of `task_kind` ('position', 'axis' or 'pose')."""

    model: ChainModel
    task_kind: str = 'pose'

    def __post_init__(self):
        if self.task_kind not in _KERNEL_KIND:
            raise ValueError(f'a spatial arm does position, axis or pose tasks, not '
                             f'{self.task_kind!r}')

    def with_task_kind(self, task_kind: str) -> SpatialArm:
        """Return the same arm for another kind of task."""
        return SpatialArm(self.model, task_kind)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The chain's joint names, base to tool."""
        return self.model.joint_names

    @property
    def n_joints(self) -> int:
        """Number of joints n."""
        return self.model.n_joints

    @property
    def joint_chain_index(self) -> np.ndarray:
        """(n,) 0..n-1: joint a turns links a+1..n."""
        return np.arange(self.n_joints)

    @property
    def task_dim(self) -> int:
        """m: 3 for positions, 5 for a tool axis, 6 for poses."""
        return TASK_DIM[self.task_kind]

    @cached_property
    def periodic(self) -> np.ndarray:
        """(n,) bool: True for continuous joints."""
        periodic = np.array([lim is None for lim in self.model.joint_limits], dtype=bool)
        periodic.flags.writeable = False
        return periodic

    @cached_property
    def limits(self) -> np.ndarray:
        """(n, 2) joint limits [rad]; (-π, π] for continuous joints."""
        out = np.array([lim if lim is not None else (-np.pi, np.pi)
                        for lim in self.model.joint_limits], dtype=float).reshape(-1, 2)
        out.flags.writeable = False
        return out

    def forward_kinematics(self, thetas: np.ndarray) -> np.ndarray:
        """Task points (..., k) of configurations (..., n) [rad] (task_space.py's table)."""
        return points_from_frames(self.task_kind, self.model.frames(thetas)[..., -1, :, :])

    def tool_frames(self, thetas: np.ndarray) -> np.ndarray:
        """Tool frames (..., 4, 4) in the base frame at configurations (..., n) [rad]."""
        return self.model.frames(thetas)[..., -1, :, :]

    @property
    def kernel_kind(self) -> int:
        """POSITION, AXIS or POSE: the task map `kinematics.task_residual` runs."""
        return _KERNEL_KIND[self.task_kind]

    @property
    def kernel_parameters(self) -> np.ndarray:
        """The chain laid out for the kinematics."""
        return self.model.parameters

    @property
    def link_names(self) -> tuple[str, ...]:
        """The base link, then the link each joint turns."""
        return self.model.link_names

    def link_frames(self, thetas: np.ndarray) -> np.ndarray:
        """Frames (..., n+1, 4, 4) of the base and the links at configurations (..., n)."""
        return self.model.frames(thetas)[..., :-1, :, :]

    @property
    def collision_shapes(self) -> tuple[LinkShape, ...]:
        """The links' collision geometry (URDF `<collision>` or DH capsules)."""
        return self.model.shapes

    @property
    def self_collision_pairs(self) -> tuple[tuple[int, int], ...]:
        """Link pairs checked for self-collision (all but the disabled ones)."""
        return self.model.self_collision_pairs

    @property
    def exempt_urdf_pairs(self) -> frozenset[frozenset[str]]:
        """URDF link pairs never checked (`ChainModel.exempt_urdf_pairs`)."""
        return self.model.exempt_urdf_pairs

    def frame_lever_arms(self) -> np.ndarray:
        """(n+1, n) [m]: see `ChainModel.frame_lever_arms`."""
        return self.model.frame_lever_arms()

    def tip_lever_arms(self) -> np.ndarray:
        """(n,) [m]: see `ChainModel.tip_lever_arms`."""
        return self.model.tip_lever_arms()

    def skeleton(self, thetas: np.ndarray) -> np.ndarray:
        """Return base, joint origins and tool point (..., n+2, 3) [m]."""
        return self.model.frames(thetas)[..., :3, 3]

    def can_reach(self, x: np.ndarray) -> bool:
        """Whether x's position is within the arm's reach from its first joint."""
        first = self.model.placements[0, :3, 3]
        reach = self.model.tip_lever_arms()[0]
        return bool(np.linalg.norm(np.asarray(x, dtype=float)[:3] - first) <= reach + 1e-12)
