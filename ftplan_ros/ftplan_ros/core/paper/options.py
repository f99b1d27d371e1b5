"""The planner's options: resolutions [rad], budgets and the self-check's settings."""

from __future__ import annotations

from dataclasses import dataclass, field

from ..model.motion_limits import MotionLimits
from .manifolds import ManifoldOptions
from .verification import VerificationOptions

# The planner's methods, in the order it tries them (recovery_sheets.py).
METHODS = ('paper_surface', 'recovery_sheets')


@dataclass(frozen=True)
class PlannerOptions:
    """Resolutions [rad] and budgets of the planner."""

    manifold: ManifoldOptions = field(default_factory=ManifoldOptions)
    verification: VerificationOptions = field(default_factory=VerificationOptions)
    column_spacing: float = 0.06      # between the goal points of a web
    waypoint_spacing: float = 0.04    # between the waypoints of a web path, per joint
    coarse_waypoints: int = 8         # waypoints of each path of the ranking fans
    max_verifications: int = 40       # surfaces verified at most
    candidate_refinement: int = 4     # start candidates per manifold step on the retry
    curves: int = 48                  # redundancy >= 2: curves on the manifolds examined at most
    curve_samples: int = 64           # redundancy >= 2: inverse-kinematics samples per task point
    # r = 1, no plan for every tolerated joint: sets of the others planned for, to report
    # which a plan covers (`coverable_joints`); 0 for the answer alone (1-3 s less on a "no").
    coverage_attempts: int = 3
    # The methods tried in turn: the paper's surface always, then where it finds no plan
    # recovery sheets over the failure-tolerant set on a joint grid (planar 3R arms among
    # disks; grid/recovery_sheets.py). Leave 'recovery_sheets' out for the paper's method alone.
    methods: tuple[str, ...] = METHODS
    # Recovery sheets: joint grids classified in turn, each tried pooled to half as many
    # cells per joint first (recovery_sheets.RecoverySheets.run).
    sheet_cells: tuple[int, ...] = (128, 256)
    # The limits stats['max_safe_speed'] is found within (None: the robot's own).
    motion_limits: MotionLimits | None = None
