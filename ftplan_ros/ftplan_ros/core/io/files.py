"""Reading the files a user gives: bounded in size, UTF-8, YAML with its traps closed.

PyYAML (YAML 1.1) reads an unquoted `1e-9` as a string and lets a key appear twice,
the second value silently winning; `load_yaml` reads such numbers as floats and refuses
duplicate keys. A path that is not a regular file (a directory, /dev/zero) or is larger
than `LARGEST_FILE` is refused before reading. Errors are InputError naming the file.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from ..errors import InputError

LARGEST_FILE = 10 * 1024 * 1024  # [bytes] scenes, robot configs, URDFs, study specs

# YAML 1.2's floats: also `1e-9`, `1E5`, `.5e3` (YAML 1.1 wants a dot and a signed exponent).
_FLOAT = re.compile(r'''^(?:[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?(?:[eE][-+]?[0-9]+)?
                    |[-+]?\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                    |[-+]?\.(?:inf|Inf|INF)
                    |\.(?:nan|NaN|NAN))$''', re.X)


class _Loader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 floats and no duplicate keys."""


_Loader.yaml_implicit_resolvers = {
    first: [(tag, regexp) for tag, regexp in resolvers if tag != 'tag:yaml.org,2002:float']
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()}
_Loader.add_implicit_resolver('tag:yaml.org,2002:float', _FLOAT, list('-+0123456789.'))


def _mapping_without_duplicates(loader: _Loader, node: yaml.MappingNode) -> dict:
    keys = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=True)
        if key in keys:
            raise yaml.constructor.ConstructorError(
                None, None, f'duplicate key {key!r}', key_node.start_mark)
        keys.add(key)
    return loader.construct_mapping(node, deep=True)


_Loader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
                        _mapping_without_duplicates)


def read_text(path: str | Path, where: str) -> str:
    """Return a regular UTF-8 file's text; InputError `where` for anything else."""
    path = Path(path)
    try:
        if not path.is_file():
            raise InputError(where, 'is not a regular file' if path.exists()
                             else f'cannot read {path.name} (no such file)')
        size = path.stat().st_size
        if size > LARGEST_FILE:
            raise InputError(where, f'{path.name} is {size} bytes, more than the '
                             f'{LARGEST_FILE} a scene, robot or URDF file may have')
        return path.read_text(encoding='utf-8')
    except OSError as error:
        raise InputError(where, f'cannot read {path.name} ({error.strerror})') from None
    except UnicodeDecodeError:
        raise InputError(where, f'{path.name} is not UTF-8 text') from None


def load_yaml(text: str, where: str) -> Any:
    """Parse YAML text (see the module docstring); InputError `where` with line and column."""
    try:
        return yaml.load(text, Loader=_Loader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as error:
        mark = getattr(error, 'problem_mark', None)
        at = f' at line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        problem = getattr(error, 'problem', None) or str(error).splitlines()[0]
        raise InputError(where, f'malformed YAML{at}: {problem}') from None
