"""The ros2msg schema of a message type: its .msg text and those of the types it nests.

MCAP's `ros2msg` schema encoding (the MCAP specification's appendix) is the type's own
.msg text, then each type it uses, once, each after a line of 80 '=' and a line
'MSG: package/Type'. rosbag2's MCAP storage gathers them as this module does: the
dependencies of a definition in sorted order, depth first, each type the first time it
is met, read from `<prefix>/share/<package>/msg/<Type>.msg` of the installed interface
packages. The prefixes are those of AMENT_PREFIX_PATH (a ROS 2 install), then the Python
environment's own (where the ROS 2 wheels put the definitions).
"""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Sequence
from pathlib import Path

SEPARATOR = '=' * 80

_PRIMITIVES = frozenset({'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8',
                         'int16', 'uint16', 'int32', 'uint32', 'int64', 'uint64', 'string',
                         'wstring'})
# A field's type at the start of a line ('geometry_msgs/Pose[] poses': geometry_msgs/Pose);
# comments start with '#' and never match. Bounded strings ('string<=8') are primitives.
_FIELD_TYPE = re.compile(r'^\s*([A-Za-z0-9_/]+)(?:\[[^\]]*\])?\s+', re.MULTILINE)
# 'sensor_msgs/msg/JointState' or 'sensor_msgs/JointState'
_TYPE_NAME = re.compile(r'^([A-Za-z][A-Za-z0-9_]*)/(?:msg/)?([A-Za-z][A-Za-z0-9_]*)$')
_MOST_NESTED = 50  # levels: a definition nested deeper is taken for a cycle


class DefinitionError(LookupError):
    """A message type whose .msg definition (or one it nests) cannot be found or read."""


def interface_prefixes() -> list[Path]:
    """Return the prefixes searched for definitions: AMENT_PREFIX_PATH's, then sys.prefix."""
    paths = [Path(p) for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    return paths + [Path(sys.prefix)]


def message_definition(type_name: str, prefixes: Sequence[Path] | None = None) -> str:
    """Return the ros2msg schema text of `type_name` (e.g. 'sensor_msgs/msg/JointState').

    Raises DefinitionError naming the type whose .msg is missing from every prefix.
    """
    prefixes = interface_prefixes() if prefixes is None else list(prefixes)
    seen: set[str] = set()

    def append_nested(name: str, depth: int) -> str:
        if depth > _MOST_NESTED:
            raise DefinitionError(f'{type_name} nests types more than {_MOST_NESTED} deep')
        text = _read_definition(name, prefixes)
        for dependency in sorted(_dependencies(text, _package(name))):
            if dependency not in seen:
                seen.add(dependency)
                text += f'\n{SEPARATOR}\nMSG: {dependency}\n' + append_nested(dependency,
                                                                             depth + 1)
        return text

    return append_nested(type_name, 0)


def _package(type_name: str) -> str:
    match = _TYPE_NAME.match(type_name)
    if match is None:
        raise DefinitionError(f'{type_name!r} is not a message type name like '
                              'sensor_msgs/msg/JointState')
    return match.group(1)


def _dependencies(text: str, package: str) -> set[str]:
    """Return the non-primitive field types of a .msg text, each as 'package/Type'."""
    found = set()
    for field_type in _FIELD_TYPE.findall(text):
        if field_type not in _PRIMITIVES:
            found.add(field_type if '/' in field_type else f'{package}/{field_type}')
    return found


def _read_definition(type_name: str, prefixes: Sequence[Path]) -> str:
    package = _package(type_name)
    name = _TYPE_NAME.match(type_name).group(2)
    for prefix in prefixes:
        path = prefix / 'share' / package / 'msg' / f'{name}.msg'
        if path.is_file():
            try:
                return path.read_text(encoding='utf-8')
            except (OSError, UnicodeDecodeError) as error:
                raise DefinitionError(f'cannot read the definition of {type_name}: '
                                      f'{error}') from None
    raise DefinitionError(f'no definition of {type_name}: share/{package}/msg/{name}.msg is '
                          f'in none of the prefixes {", ".join(map(str, prefixes))}')
