"""A node's scene: the `scene_file`, with its robot from the file or from /robot_description.

A scene file may leave the robot out. Then the robot comes from the URDF that
robot_state_publisher publishes on /robot_description (std_msgs/String, transient
local), as the chain from `base_link` ('' = the URDF's root link) to `tip_link` with the
tool at `tip_offset` [m] in the tip link's frame, and self-collision exceptions
`disabled_collisions` (link names in pairs, flattened: [a1, b1, a2, b2, ...]; empty =
the core's default: adjacent links and links touching at the zero configuration).
Until a robot is there, `scene` is None and the node refuses work with `waiting`. A
URDF that cannot be used (or a scene file that does not fit it) is reported on
/diagnostics as '<node>: robot_description' and the last good robot stays. When the
scene file has a robot, /robot_description is not used (logged once at start).
"""

from __future__ import annotations

import traceback
from collections.abc import Callable

import numpy as np
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_msgs.msg import String

from ftplan_ros.core import InputError, Scene, load_scene, robot_from_urdf
from ftplan_ros.core.io.scene_file import MissingRobotError

from .params import array_parameter, declare, declare_array, default_scene_file
from .qos import LATCHED_QOS
from .reporting import Diagnostics
from .topics import ROBOT_DESCRIPTION

WAITING = f'waiting for {ROBOT_DESCRIPTION}: the scene file has no robot'


def robot_is_missing(error: InputError) -> bool:
    """Whether `load_scene` failed only because the scene file has no robot."""
    return isinstance(error, MissingRobotError)


class SceneSource:
    """Declare and load `scene_file` (and the robot-description parameters) for a node.

    `on_scene(scene)` runs after every new robot from /robot_description (in the
    subscription's callback); the first scene of a file with a robot is there at once.
    """

    def __init__(self, node: Node, diagnostics: Diagnostics,
                 on_scene: Callable[[Scene], None] | None = None):
        self._node = node
        self._diagnostics = diagnostics
        self._on_scene = on_scene
        self._xml: str | None = None
        self.path = declare(node, 'scene_file', default_scene_file(),
                            'Scene YAML: robot (or none: the robot comes from '
                            '/robot_description), static obstacles and task (obstacles from '
                            '/ftplan/obstacles add to the static ones).', read_only=True)
        if not self.path:
            raise InputError('scene_file', 'is empty; give the path of a scene YAML')
        self._declare_description_parameters()
        self.scene: Scene | None = None
        self.subscription = None
        try:
            self.scene = load_scene(self.path)
        except InputError as error:
            if not robot_is_missing(error):
                raise
        log = node.get_logger()
        if self.scene is not None:
            self._log_scene(self.scene, self.path)
            log.info(f'the scene file has a robot: {ROBOT_DESCRIPTION} is not used')
            return
        self._check_description_parameters()
        self.subscription = node.create_subscription(
            String, ROBOT_DESCRIPTION, self.robot_description_callback, LATCHED_QOS)
        log.info(f'scene file {self.path} has no robot: waiting for {ROBOT_DESCRIPTION}')

    @property
    def waiting(self) -> str:
        """Why there is no scene yet (empty once there is one)."""
        return '' if self.scene is not None else WAITING

    def _declare_description_parameters(self) -> None:
        node = self._node
        declare(node, 'base_link', '', 'Robot from /robot_description (scene without a robot): '
                'the base link of the chain ("" = the URDF\'s root link).', read_only=True)
        declare(node, 'tip_link', '', 'Robot from /robot_description: the tip link of the '
                'chain (needed when the scene file has no robot).', read_only=True)
        declare(node, 'tip_offset', [0.0, 0.0, 0.0], 'Robot from /robot_description: the tool '
                'point [m] in the tip link\'s frame.', read_only=True)
        declare_array(node, 'disabled_collisions', Parameter.Type.STRING_ARRAY,
                      'Robot from /robot_description: link pairs never checked for '
                      'self-collision, flattened [a1, b1, a2, b2, ...] (empty: adjacent links '
                      'and links touching at the zero configuration).', read_only=True)

    def _check_description_parameters(self) -> None:
        """Raise InputError when the parameters cannot describe a robot (at start)."""
        node = self._node
        if not node.get_parameter('tip_link').value:
            raise InputError('tip_link', f'is empty, but scene file {self.path} has no robot: '
                             f'name the tip link of the chain in {ROBOT_DESCRIPTION}')
        offset = list(node.get_parameter('tip_offset').value)
        if len(offset) != 3 or not np.all(np.isfinite(offset)):
            raise InputError('tip_offset', f'needs 3 finite numbers [m], got {offset}')
        pairs = array_parameter(node, 'disabled_collisions')
        if len(pairs) % 2:
            raise InputError('disabled_collisions', f'holds {len(pairs)} link names: it needs '
                             'pairs [a1, b1, a2, b2, ...]')

    def robot_description_callback(self, msg: String) -> None:
        """Build the arm from a URDF; a bad one is reported and the last good robot kept."""
        if msg.data == self._xml:
            return
        node = self._node
        try:
            scene = self._scene_from_urdf(msg.data)
        except Exception as error:  # noqa: BLE001 - any bad URDF must leave the node up
            if not isinstance(error, InputError):
                node.get_logger().error(traceback.format_exc())
            kept = 'keeping the last good robot' if self.scene is not None else WAITING
            self._diagnostics.report('robot_description', 'ERROR',
                                     f'ignored {ROBOT_DESCRIPTION}: {error}; {kept}',
                                     {'scene_file': self.path}, log=True)
            return
        self._xml = msg.data
        self.scene = scene
        if self._on_scene is not None:
            self._on_scene(scene)
        robot = scene.robot
        self._diagnostics.report(
            'robot_description', 'OK', f'robot from {ROBOT_DESCRIPTION}: {robot.n_joints} '
            f'joints {list(robot.joint_names)}', {'scene_file': self.path,
                                                  'joints': ','.join(robot.joint_names)},
            log=True)

    def _scene_from_urdf(self, xml: str) -> Scene:
        node = self._node
        pairs = array_parameter(node, 'disabled_collisions')
        arm = robot_from_urdf(
            xml, node.get_parameter('tip_link').value,
            node.get_parameter('base_link').value or None,
            list(node.get_parameter('tip_offset').value),
            [pairs[k:k + 2] for k in range(0, len(pairs), 2)] if pairs else None)
        return load_scene(self.path, robot=arm)

    def _log_scene(self, scene: Scene, path: str) -> None:
        self._node.get_logger().info(
            f'scene {scene.name} from {path}: {scene.robot.n_joints} joints '
            f'{list(scene.robot.joint_names)}, {len(scene.obstacles)} static obstacles, '
            f'frame {scene.frame_id!r}')
