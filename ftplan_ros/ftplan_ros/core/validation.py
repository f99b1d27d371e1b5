"""Validating plain data from YAML or JSON: each check raises InputError naming its field.

Every number is finite and within ±LARGEST_NUMBER: the clearance bounds allow for float
rounding of about 1e-6 m, which holds for coordinates up to there (and no scene is
bigger).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from .errors import InputError

LARGEST_NUMBER = 1.0e6  # [m or rad] largest magnitude of any number read


def mapping(data: Any, where: str) -> Mapping:
    """Return `data` if it is a mapping."""
    if not isinstance(data, Mapping):
        raise InputError(where, f'must be a mapping, got {type(data).__name__}')
    return data


def sequence(data: Any, where: str) -> list:
    """Return `data` as a list if it is a sequence (not a string)."""
    if isinstance(data, (str, bytes)) or not isinstance(data, Sequence):
        raise InputError(where, f'must be a list, got {type(data).__name__}')
    return list(data)


def check_keys(data: Mapping, where: str, required: tuple, optional: tuple) -> None:
    """Refuse keys not in `required` + `optional`, and missing required keys."""
    for key in data:
        if key not in required and key not in optional:
            allowed = ', '.join(required + optional)
            raise InputError(f'{where}.{key}', f'unknown key (allowed: {allowed})')
    for key in required:
        if key not in data:
            raise InputError(f'{where}.{key}', 'is missing')


def number(value: Any, where: str) -> float:
    """Return a finite float within ±LARGEST_NUMBER (booleans are not numbers)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(where, f'must be a number, got {value!r}')
    try:
        value = float(value)
    except OverflowError:
        value = math.inf
    if not math.isfinite(value):
        raise InputError(where, f'must be finite, got {value}')
    if abs(value) > LARGEST_NUMBER:
        raise InputError(where, f'must be within ±{LARGEST_NUMBER:g}, got {value:g}')
    return value


def nonnegative(value: Any, where: str) -> float:
    """Return `number` of the value, refusing one below 0 (a radius, say)."""
    value = number(value, where)
    if value < 0.0:
        raise InputError(where, f'must be >= 0, got {value}')
    return value


def integer(value: Any, where: str, least: int | None = None) -> int:
    """Return an int (not a bool), at least `least`."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(where, f'must be an integer, got {value!r}')
    if least is not None and value < least:
        raise InputError(where, f'must be an integer >= {least}, got {value}')
    return value


def vector(data: Any, where: str, length: int | None = None) -> list[float]:
    """Return a list of numbers, of `length` when given."""
    items = sequence(data, where)
    if length is not None and len(items) != length:
        raise InputError(where, f'needs {length} values, got {len(items)}')
    return [number(item, f'{where}[{k}]') for k, item in enumerate(items)]
