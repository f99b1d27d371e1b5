"""The ROS-free core of ftplan: the paper's algorithm (Steps 1-7) and its self-check.

Nothing below this package imports rclpy. Typical use:

    scene = load_scene('config/scenes/fig3a.yaml')
    result = plan(scene)                       # PlanResult; result.feasible is a guarantee
    rescue = recover(result.surface, theta, joint)   # joint locked at θ on the nominal path
"""

from .collision import CollisionChecker
from .errors import InputError
from .failure_surface import FailureSurface
from .manifolds import ManifoldCache, ManifoldOptions, SelfMotionManifold, self_motion_path
from .options import PlannerOptions
from .planner import check_plannable, plan
from .recovery import RecoveryPath, locate_on_nominal_path, recover
from .result import PlanResult
from .robot import PlanarChain, Robot, task_errors
from .scene import (
    Obstacle,
    Scene,
    Task,
    load_scene,
    parse_scene,
    robot_from_urdf,
    scene_to_dict,
)
from .spatial import SpatialArm
from .verification import VerificationOptions
from .warmup import load_kernels

__all__ = [
    'CollisionChecker', 'FailureSurface', 'InputError', 'ManifoldCache', 'ManifoldOptions',
    'Obstacle', 'PlanResult', 'PlanarChain', 'PlannerOptions', 'RecoveryPath', 'Robot',
    'Scene', 'SelfMotionManifold', 'SpatialArm', 'Task', 'VerificationOptions',
    'check_plannable', 'load_kernels', 'load_scene', 'locate_on_nominal_path', 'parse_scene',
    'plan', 'recover', 'robot_from_urdf', 'scene_to_dict', 'self_motion_path', 'task_errors',
]
