"""Parameter helpers shared by the nodes: declaration with descriptors and validators.

Every node takes `scene_file`, the path of a scene YAML (robot, static obstacles, task;
scene_source.py loads it). Its default is the installed fig3a scene (found through the
ament index), or the repository's config/scenes/fig3a.yaml when the package is not
installed.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import fields
from pathlib import Path
from typing import Any

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from rclpy.parameter import Parameter

from ftplan_ros.core import InputError

PACKAGE = 'ftplan_ros'
DEFAULT_SCENE = 'fig3a.yaml'
_REPO_CONFIG = Path(__file__).resolve().parents[3] / 'config'

# What a node constructor raises for a bad scene file or parameter: main() exits with 2.
STARTUP_ERRORS = (InputError, ParameterException)

Validator = Callable[[Any], 'str | None']


def config_path(kind: str, name: str) -> Path:
    """Return the installed share/ftplan_ros/config/<kind>/<name>, else the repository's."""
    try:
        from ament_index_python.packages import (
            PackageNotFoundError,
            get_package_share_directory,
        )
        try:
            installed = Path(get_package_share_directory(PACKAGE)) / 'config' / kind / name
            if installed.is_file():
                return installed
        except (PackageNotFoundError, OSError):  # not installed, or no AMENT_PREFIX_PATH
            pass
    except ImportError:  # no ament_index_python: not a ROS install
        pass
    return _REPO_CONFIG / kind / name


def default_scene_file() -> str:
    """Return the path of the default scene (fig3a), installed or in the repository."""
    return str(config_path('scenes', DEFAULT_SCENE))


def declare(node: Node, name: str, default: Any, description: str,
            read_only: bool = False) -> Any:
    """Declare parameter `name` with a description and return its value."""
    descriptor = ParameterDescriptor(description=description, read_only=read_only)
    return node.declare_parameter(name, default, descriptor).value


def declare_array(node: Node, name: str, kind: Parameter.Type, description: str,
                  read_only: bool = False) -> list:
    """Declare an array parameter whose default is empty; return its value ([] if unset).

    rclpy cannot infer a type from an empty list, so the parameter is declared with its
    type and no value: leave it out of a params file to keep it empty.
    """
    descriptor = ParameterDescriptor(description=description, read_only=read_only)
    node.declare_parameter(name, kind, descriptor)
    return array_parameter(node, name)


def array_parameter(node: Node, name: str) -> list:
    """Return the value of an array parameter declared by `declare_array` ([] if unset)."""
    parameter = node.get_parameter_or(name, None)
    if parameter is None or parameter.type_ == Parameter.Type.NOT_SET:
        return []
    return list(parameter.value)


def positive(value: Any) -> str | None:
    """Validate a finite number > 0."""
    if not isinstance(value, (int, float)) or not value > 0 or value == float('inf'):
        return f'must be a finite number > 0, got {value!r}'
    return None


def non_negative(value: Any) -> str | None:
    """Validate a finite number >= 0."""
    if not isinstance(value, (int, float)) or not value >= 0 or value == float('inf'):
        return f'must be a finite number >= 0, got {value!r}'
    return None


def add_validators(node: Node, validators: dict[str, Validator]) -> None:
    """Reject runtime parameter changes that a validator refuses (the reason names it)."""

    def check(parameters: Sequence[Parameter]) -> SetParametersResult:
        for parameter in parameters:
            validator = validators.get(parameter.name)
            if validator is None or parameter.type_ == Parameter.Type.NOT_SET:
                continue
            problem = validator(parameter.value)
            if problem:
                reason = f'{parameter.name}: {problem}'
                node.get_logger().warning(f'rejected parameter change: {reason}')
                return SetParametersResult(successful=False, reason=reason)
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(check)


@contextmanager
def destroyed_if_start_fails(node: Node) -> Iterator[None]:
    """Destroy `node` at once when its start (the body of the block) raises; re-raise.

    A node that fails to start and is left to the garbage collector is destroyed later,
    perhaps after a new node of the same name has started in the process: its /rosout
    publisher went with it, and the new node's log reached the console only. The block
    may include rclpy's own Node.__init__, which can raise half way (a parameter
    override of the wrong type).
    """
    try:
        yield
    except BaseException:
        _destroy_started_part(node)
        raise


def _destroy_started_part(node: Node) -> None:
    """Destroy what exists of `node`, even when Node.__init__ stopped half way."""
    try:
        node.destroy_node()
    except AttributeError:  # Node.__init__ raised before creating what destroy_node ends with
        try:
            node.handle.destroy_when_not_in_use()  # the rcl node, which owns /rosout
        except AttributeError:  # it raised before the rcl node existed: nothing to destroy
            pass


def check_startup_parameters(node: Node, validators: dict[str, Validator]) -> None:
    """Raise InputError for a startup parameter value a validator refuses."""
    for name, validator in validators.items():
        parameter = node.get_parameter_or(name, None)
        if parameter is None or parameter.type_ == Parameter.Type.NOT_SET:
            continue
        problem = validator(parameter.value)
        if problem:
            raise InputError(name, problem)


def options_from_parameters(node: Node, options_class):
    """Return an `options_class` (a dataclass) from the node's parameters of its fields' names."""
    return options_class(**{field.name: node.get_parameter(field.name).value
                            for field in fields(options_class)})
