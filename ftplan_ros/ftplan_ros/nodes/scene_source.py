"""A node's scene: the `scene_file`, with its robot from the file or from /robot_description.

A scene file may leave the robot out. Then the robot comes from the URDF that
robot_state_publisher publishes on /robot_description (std_msgs/String, transient
local), as the chain from `base_link` ('' = the URDF's root link) to `tip_link` with the
tool at `tip_offset` [m] in the tip link's frame. Its self-collision exceptions come
from one place: the `disabled_collisions` parameter (link names in pairs, flattened:
[a1, b1, a2, b2, ...]) when it is set, else the SRDF that MoveIt's move_group publishes
on /robot_description_semantic (std_msgs/String, transient local; core/srdf.py), else
MoveIt's sampled default (core/io/sampled_exceptions.py: cached per robot, logged).

The robot is built again whenever either description changes, in a thread of its own,
and its compiled kernels are run there once (core/warmup.py: seconds for a robot of a
thousand shapes, and the node's own `load_kernels` then returns at once): the node goes
on serving its other callbacks meanwhile, with the last good robot. A
description that arrives during a build supersedes the one being built (that result is
dropped); a finished robot is handed to the node in its default callback group, where
the subscription callback used to build it. Until a robot is there, `scene` is None
and the node refuses work with `waiting`. A description that cannot be used (or a
scene file that does not fit it) is reported on /diagnostics as '<node>:
robot_description' (or '<node>: robot_description_semantic' for the SRDF) and the last
good robot stays. When the scene file has a robot, neither topic is used (logged once
at start).
"""

from __future__ import annotations

import threading
import traceback
from collections.abc import Callable

import numpy as np
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter
from std_msgs.msg import String

from ftplan_ros.core import InputError, Scene, load_kernels, load_scene, robot_from_urdf
from ftplan_ros.core.io.scene_file import MissingRobotError

from .params import array_parameter, declare, declare_array, default_scene_file
from .qos import LATCHED_QOS
from .reporting import Diagnostics
from .topics import ROBOT_DESCRIPTION, ROBOT_DESCRIPTION_SEMANTIC

WAITING = f'waiting for {ROBOT_DESCRIPTION}: the scene file has no robot'
# What rclpy raises when a destroyed node's guard condition is triggered (a build that
# ends after its node): rclpy gives it no public name.
_InvalidHandle = _rclpy.InvalidHandle


def robot_is_missing(error: InputError) -> bool:
    """Whether `load_scene` failed only because the scene file has no robot."""
    return isinstance(error, MissingRobotError)


class SceneSource:
    """Declare and load `scene_file` (and the robot-description parameters) for a node.

    `on_scene(scene)` runs after every new robot from the descriptions (in the node's
    default callback group); the first scene of a file with a robot is there at once.
    """

    def __init__(self, node: Node, diagnostics: Diagnostics,
                 on_scene: Callable[[Scene], None] | None = None):
        self._node = node
        self._diagnostics = diagnostics
        self._on_scene = on_scene
        self.path = declare(node, 'scene_file', default_scene_file(),
                            'Scene YAML: robot (or none: the robot comes from '
                            '/robot_description), static obstacles and task (obstacles from '
                            '/ftplan/obstacles add to the static ones).', read_only=True)
        if not self.path:
            raise InputError('scene_file', 'is empty; give the path of a scene YAML')
        self._declare_description_parameters()
        self.scene: Scene | None = None
        self.subscription = None
        self.semantic_subscription = None
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
        self._lock = threading.Lock()
        self._texts: dict[str, str | None] = {'urdf': None, 'srdf': None}  # latest received
        self._version = 0  # counts the texts received
        self._building = False
        # The newest texts' build, to hand over: (scene, where its exceptions come from).
        self._built: tuple[Scene, str] | Exception | None = None
        self._built_guard = node.create_guard_condition(self.built_callback)
        self.subscription = node.create_subscription(
            String, ROBOT_DESCRIPTION, self.robot_description_callback, LATCHED_QOS)
        if self._disabled_pairs:
            log.info(f'disabled_collisions is set: {ROBOT_DESCRIPTION_SEMANTIC} is not used')
        else:
            self.semantic_subscription = node.create_subscription(
                String, ROBOT_DESCRIPTION_SEMANTIC, self.robot_description_semantic_callback,
                LATCHED_QOS)
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
                      'self-collision, flattened [a1, b1, a2, b2, ...] (empty: the SRDF\'s on '
                      '/robot_description_semantic, else MoveIt\'s sampled default: adjacent '
                      'links, links touching in >= 95 % or in none of 10,000 random '
                      'configurations).', read_only=True)

    def _check_description_parameters(self) -> None:
        """Read the parameters once (they are read-only); InputError when they cannot serve."""
        node = self._node
        self._tip_link = node.get_parameter('tip_link').value
        self._base_link = node.get_parameter('base_link').value or None
        if not self._tip_link:
            raise InputError('tip_link', f'is empty, but scene file {self.path} has no robot: '
                             f'name the tip link of the chain in {ROBOT_DESCRIPTION}')
        self._tip_offset = list(node.get_parameter('tip_offset').value)
        if len(self._tip_offset) != 3 or not np.all(np.isfinite(self._tip_offset)):
            raise InputError('tip_offset', f'needs 3 finite numbers [m], got {self._tip_offset}')
        names = array_parameter(node, 'disabled_collisions')
        if len(names) % 2:
            raise InputError('disabled_collisions', f'holds {len(names)} link names: it needs '
                             'pairs [a1, b1, a2, b2, ...]')
        self._disabled_pairs = [names[k:k + 2] for k in range(0, len(names), 2)]

    def robot_description_callback(self, msg: String) -> None:
        """Take a URDF: the robot is built from it (with the latest SRDF) off this thread."""
        self._receive('urdf', msg.data)

    def robot_description_semantic_callback(self, msg: String) -> None:
        """Take an SRDF: the robot is built again with its exceptions, off this thread."""
        self._receive('srdf', msg.data)

    def _receive(self, kind: str, text: str) -> None:
        """Keep the newest text; start a build unless one runs (it builds the newest next)."""
        with self._lock:
            if text == self._texts[kind]:
                return
            self._texts[kind] = text
            self._version += 1
            if self._building:
                return
            self._building = True
        threading.Thread(target=self._build_newest, daemon=True,
                         name=f'{self._node.get_name()}-robot-description').start()

    def _build_newest(self) -> None:
        """Build until the texts built are the newest, then hand the result to the node."""
        while True:
            with self._lock:
                version, texts = self._version, dict(self._texts)
            built = self._build(texts['urdf'], texts['srdf'])
            with self._lock:
                if version != self._version:
                    continue  # superseded while it was built: build the newest
                self._building = False
                if built is None:
                    return
                self._built = built
            try:
                self._built_guard.trigger()
            except _InvalidHandle:  # the node was destroyed meanwhile
                pass
            return

    def _build(self, urdf: str | None, srdf: str | None,
               ) -> tuple[Scene, str] | Exception | None:
        """Return (scene, where its exceptions come from), the error, or None (no URDF yet)."""
        if urdf is None:
            return None
        if self._disabled_pairs:
            exceptions = 'from the disabled_collisions parameter'
        elif srdf is not None:
            exceptions = f'from {ROBOT_DESCRIPTION_SEMANTIC}'
        else:
            exceptions = 'sampled as MoveIt\'s setup assistant does (logged)'
        try:
            arm = robot_from_urdf(urdf, self._tip_link, self._base_link, self._tip_offset,
                                  self._disabled_pairs or None, srdf=srdf)
            scene = load_scene(self.path, robot=arm)
            load_kernels(scene.robot)  # here, not in the node's callback: seconds for big ones
            return scene, exceptions
        except InputError as error:
            return error
        except Exception as error:  # noqa: BLE001 - any bad description must leave the node up
            self._node.get_logger().error(traceback.format_exc())
            return error

    def built_callback(self) -> None:
        """Use a finished build, or report why it failed (the last good robot stays)."""
        with self._lock:
            built, self._built = self._built, None
        if built is None:
            return
        if isinstance(built, Exception):
            self._report_failure(built)
            return
        self.scene, exceptions = built
        if self._on_scene is not None:
            self._on_scene(self.scene)
        robot = self.scene.robot
        self._diagnostics.report(
            'robot_description', 'OK', f'robot from {ROBOT_DESCRIPTION}: {robot.n_joints} '
            f'joints {list(robot.joint_names)}, self-collision exceptions {exceptions}',
            {'scene_file': self.path, 'joints': ','.join(robot.joint_names)}, log=True)

    def _report_failure(self, error: Exception) -> None:
        semantic = isinstance(error, InputError) and error.field == 'robot.srdf'
        topic = ROBOT_DESCRIPTION_SEMANTIC if semantic else ROBOT_DESCRIPTION
        kept = 'keeping the last good robot' if self.scene is not None else WAITING
        self._diagnostics.report(topic.lstrip('/'), 'ERROR', f'ignored {topic}: {error}; {kept}',
                                 {'scene_file': self.path}, log=True)

    def _log_scene(self, scene: Scene, path: str) -> None:
        self._node.get_logger().info(
            f'scene {scene.name} from {path}: {scene.robot.n_joints} joints '
            f'{list(scene.robot.joint_names)}, {len(scene.obstacles)} static obstacles, '
            f'frame {scene.frame_id!r}')
