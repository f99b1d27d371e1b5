"""A Franka Panda pose task for the ROS tests, written as scene files into a test's tmp_path.

The task moves the hand from pose X_S to pose X_G (found by sampling: X_S = FK(Q_S)). No
plan survives an elbow (panda_joint4) lock there (its failure plane misses M_g^F from
every start), and the plan for the other six joints has no recovery path in S_F for an
elbow lock in the middle of the nominal path: the tests use both facts.
"""

from __future__ import annotations

from pathlib import Path

import yaml
from ros_support import REPO

ROBOTS = REPO / 'config' / 'robots'
PANDA_URDF = ROBOTS / 'panda.urdf'
JOINTS = [f'panda_joint{k}' for k in range(1, 8)]
TOLERATED = [name for name in JOINTS if name != 'panda_joint4']
FINGERS = ['panda_finger_joint1', 'panda_finger_joint2']
BASE_LINK = 'panda_link0'
TIP_LINK = 'panda_hand_tcp'
Q_S = [1.3298407722778776, 0.1538042699104949, 2.5210706668806018, -0.6226076305271602,
       -2.88143148691406, 3.2149141227351365, -2.702685025334956]
X_S = {'position': [-0.2861611204782362, -0.185296202784198, 1.1639758698076925],
       'orientation': [0.07812132917851586, -0.2707766778876545, 0.31066640128316275,
                       0.907779398176273]}
X_G = {'position': [-0.6025008726476115, -0.06998277430000695, 0.8542864467771099],
       'orientation': [0.10193744319987154, -0.6758895911070089, -0.03972719244674928,
                       0.7288372716096319]}
GOAL_TOLERANCE = 0.005       # [m]
ORIENTATION_TOLERANCE = 0.01  # [rad]
ELBOW_CLEAR_BOX = {'type': 'box', 'center': [0.45, 0.35, 0.3], 'size': [0.2, 0.2, 0.2]}


def disabled_collisions() -> list[str]:
    """The Panda's self-collision exceptions as the flat parameter list [a1, b1, ...]."""
    robot = yaml.safe_load((ROBOTS / 'panda.yaml').read_text())['robot']
    return [name for pair in robot['disabled_collisions'] for name in pair]


def description_parameters() -> dict:
    """Node parameters that build the Panda from /robot_description."""
    return {'base_link': BASE_LINK, 'tip_link': TIP_LINK,
            'disabled_collisions': disabled_collisions()}


def panda_scene(directory: Path, name: str = 'panda_pose', *, robot: bool = True,
                task: bool = True, tolerate: bool = True, obstacles: bool = True) -> Path:
    """Write a Panda scene YAML into `directory` and return its path.

    Without `robot` the scene leaves the robot to /robot_description.
    """
    data: dict = {}
    if robot:
        data['robot'] = str(ROBOTS / 'panda.yaml')
    if obstacles:
        data['obstacles'] = [ELBOW_CLEAR_BOX]
    if task:
        data['task'] = {'start': X_S, 'goal': X_G, 'goal_tolerance': GOAL_TOLERANCE,
                        'orientation_tolerance': ORIENTATION_TOLERANCE}
    if tolerate:
        data['tolerate'] = TOLERATED
    path = Path(directory) / f'{name}.yaml'
    path.write_text(yaml.safe_dump(data))
    return path
