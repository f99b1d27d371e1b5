"""The planner's answer, as a frozen dataclass that serialises to the contract's JSON."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..model.angles import wrap_configuration
from .failure_planes import failure_hypercube
from .failure_surface import FailureSurface
from .manifolds import SelfMotionManifold


@dataclass(frozen=True, eq=False)
class PlanResult:
    """A failure-tolerant plan, or why there is none.

    `feasible` is a guarantee, checked by `verification.verify_surface`: from every point
    of the nominal path, with any one tolerated joint locked there, a collision-free path
    in that joint's failure hyperplane reaches the goal within its tolerances (the
    tolerated joints are `surface.tolerated`, by name in stats). Angles are radians;
    `theta_s` and the hits are wrapped to (-π, π] on periodic joints, while the paths
    are continuous (they may leave (-π, π] so as not to jump).

    `stats` reports (it is the plan JSON's "stats"); what the planner's later stages
    decide on is in the typed fields after `periodic`.
    """

    feasible: bool
    joint_names: tuple[str, ...]
    reason: str = ''
    surface: FailureSurface | None = None
    stats: dict = field(default_factory=dict)
    # What the planner saw, for figures and diagnostics:
    start_manifolds: tuple[SelfMotionManifold, ...] = ()
    goal_manifolds: tuple[SelfMotionManifold, ...] = ()
    # Θ_s (paper Step 3): (c, n) start candidates meeting the necessary condition, eq. 6
    necessary_starts: np.ndarray | None = None
    proposed_starts: np.ndarray | None = None  # (p, n) of Θ_s with a vertex-free coarse S_F
    periodic: np.ndarray | None = None
    # What the stages after the paper's search decide on:
    goal_free_arcs: int = 0           # obstacle-free arcs of M_g the paper's search had
    # Sets of joints whose failure planes keep the starts from eq. 6, likeliest first:
    blocked_joints: tuple[tuple[str, ...], ...] = ()
    start_preferred: bool = False     # θ_s is one of the starts the caller preferred
    proved_infeasible: bool = False   # a joint grid proved that no plan exists

    @property
    def theta_s(self) -> np.ndarray | None:
        """The chosen start configuration θ_s (n,) [rad]."""
        return None if self.surface is None else self.surface.theta_s

    @property
    def nominal_path(self) -> np.ndarray | None:
        """The nominal joint path (k, n) [rad] from θ_s to a goal configuration on S_F."""
        return None if self.surface is None else self.surface.nominal_path

    @property
    def tolerated_joints(self) -> tuple[int, ...]:
        """Indices of the joints whose lock the plan survives (the surface's)."""
        return () if self.surface is None else self.surface.tolerated

    @property
    def failure_plane_hits(self) -> np.ndarray | None:
        """Return (t, n) [rad]: row k the goal configuration in H_i(θ_s) ∩ M_g^F, wrapped.

        i is the k-th tolerated joint.
        """
        if self.surface is None:
            return None
        hits = self.surface.goal_points[list(self.surface.hit_paths)]
        return wrap_configuration(hits, self.periodic)

    @property
    def hypercube(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The box (lower, upper) (n,) [rad] holding S_F, in the paths' lifted angles.

        For the paper's surface it is the failure hypercube V_sg, spanned by θ_s and the
        goal points (its paths are monotonic between them); the paths of recovery sheets
        bend around obstacles, and the box grows to hold them.
        """
        if self.surface is None:
            return None
        vertices = self.surface.paths.reshape(-1, self.surface.paths.shape[-1])
        return failure_hypercube(self.surface.theta_s, vertices)

    def to_json(self) -> dict:
        """Return the plan result JSON of CONTRACT.md (radians).

        A statistic that is not finite (the clearance of a scene without obstacles is
        infinite) is null: JSON has no infinity.
        """
        out: dict = {'feasible': self.feasible, 'joint_names': list(self.joint_names),
                     'tolerated_joints': list(self.stats.get(
                         'tolerated_joints', [self.joint_names[i] for i in self.tolerated_joints]))}
        if self.surface is not None:
            lower, upper = self.hypercube
            out.update({
                'theta_s': self.theta_s.tolist(),
                'nominal_path': self.nominal_path.tolist(),
                'failure_surface': self.surface.to_dict(),
                'failure_plane_hits': self.failure_plane_hits.tolist(),
                'hypercube': {'lower': lower.tolist(), 'upper': upper.tolist()},
            })
        out['stats'] = {key: _json_value(value) for key, value in self.stats.items()
                        if key != 'tolerated_joints'}
        if not self.feasible:
            out['reason'] = self.reason
        return out


def _json_value(value):
    """Return a statistic as JSON can hold it: non-finite floats become null, also in lists."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {key: _json_value(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_value(item) for item in value]
    return value
