"""The ROS-free core of ftplan: the paper's algorithm (Steps 1-7) and its self-check.

Nothing below this package imports rclpy. Its subpackages are layers along the data
flow; each imports only from those before it (test/unit/test_layers.py checks it):

    errors, validation   InputError and the checks of numbers every layer uses
    model/        robot (f(θ), task errors), chains from URDF/DH, task spaces, geometry,
                  scene data (obstacles, task)
    collision/    clearances (checker), self-collision pairs, certificates over the
                  continuum (segments, triangles, webs)
    paper/        Steps 1-2 manifolds, 3-4 failure_planes, 5-6 failure_surface,
                  7 recovery; the self-check (verification, slices); result, options
    grid/         planar 3R joint grids: G (tolerant_set), existence proofs, free
                  components and the starts within an arm's reach (start_reach), the
                  recovery sheets, brute-force baselines (exhaustive)
    planning/     plan() (surface_search for r = 1, curves for r >= 2, then the
                  recovery sheets), plans from where the arm stands (reachable, approach),
                  drills, warm-up
    io/           scene YAML -> model objects (scene_file), files, fingerprints

A plan flows: io.scene_file -> Scene (model) -> planning.plan: paper Steps 1-6 over
collision's clearances, grid's sheets where the paper's surface fails -> the self-check
(paper.verification) -> PlanResult; a lock is answered by paper.recovery.recover.
Typical use:

    scene = load_scene('config/scenes/fig3a.yaml')
    result = plan(scene)                       # PlanResult; result.feasible is a guarantee
    rescue = recover(result.surface, theta, joint)   # joint locked at θ on the nominal path
"""

from .collision.checker import CollisionChecker
from .errors import InputError
from .io.fingerprint import scene_to_dict
from .io.scene_file import load_scene, parse_scene, robot_from_urdf
from .model.robot import PlanarChain, Robot, task_errors
from .model.scene import Obstacle, Scene, Task
from .model.spatial import SpatialArm
from .paper.failure_surface import FailureSurface
from .paper.manifolds import ManifoldCache, ManifoldOptions, SelfMotionManifold, self_motion_path
from .paper.options import PlannerOptions
from .paper.recovery import RecoveryPath, locate_on_nominal_path, recover
from .paper.result import PlanResult
from .paper.verification import VerificationOptions
from .planning.planner import check_plannable, plan
from .planning.warmup import load_kernels

__all__ = [
    'CollisionChecker', 'FailureSurface', 'InputError', 'ManifoldCache', 'ManifoldOptions',
    'Obstacle', 'PlanResult', 'PlanarChain', 'PlannerOptions', 'RecoveryPath', 'Robot',
    'Scene', 'SelfMotionManifold', 'SpatialArm', 'Task', 'VerificationOptions',
    'check_plannable', 'load_kernels', 'load_scene', 'locate_on_nominal_path', 'parse_scene',
    'plan', 'recover', 'robot_from_urdf', 'scene_to_dict', 'self_motion_path', 'task_errors',
]
