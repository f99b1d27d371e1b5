"""Input checks shared by the converters; every failure is a ValueError naming the field."""

from collections.abc import Iterable, Mapping, Sequence

import numpy as np
from builtin_interfaces.msg import Time
from numpy.typing import ArrayLike, NDArray

INT32_MIN = -(2**31)
INT32_MAX = 2**31 - 1


def finite_array(value: ArrayLike, field: str) -> NDArray[np.float64]:
    """Return `value` as a new float64 array, rejecting non-numeric and non-finite entries."""
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(
            f'{field} must be a numeric array, got {value!r:.80}: {error}'
        ) from error
    if not np.all(np.isfinite(array)):
        index = tuple(int(i) for i in np.argwhere(~np.isfinite(array))[0])
        raise ValueError(
            f'{field} has a non-finite value {array[index]} at index {index}; '
            'pass finite numbers only'
        )
    return array


def finite_float(value: float, field: str) -> float:
    """Return `value` as a finite float."""
    array = finite_array(value, field)
    if array.shape != ():
        raise ValueError(f'{field} must be a single number, got shape {array.shape}')
    return float(array)


def joint_vector(value: ArrayLike, field: str, names: Sequence[str]) -> NDArray[np.float64]:
    """Return `value` as a finite (n,) array with n = len(names); errors name the joint."""
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f'{field} must be a numeric array, got {value!r:.80}') from error
    if array.shape != (len(names),):
        raise ValueError(
            f'{field} has shape {array.shape} but there are {len(names)} joints {list(names)}; '
            'pass one value per joint'
        )
    check_finite_joints(array, field, names)
    return array


def check_finite_joints(values: NDArray[np.float64], field: str, names: Sequence[str]) -> None:
    """Raise if any entry of the (n,) `values` is NaN or infinite, naming that joint."""
    for name, value in zip(names, values, strict=True):
        if not np.isfinite(value):
            raise ValueError(f'{field} of joint {name!r} is {value}; pass a finite value')


def joint_names(names: Sequence[str], field: str) -> list[str]:
    """Return `names` as a list after checking it holds unique, non-empty strings."""
    if isinstance(names, str):
        raise ValueError(f'{field} must be a sequence of joint names, not the string {names!r}')
    try:
        result = list(names)
    except TypeError:
        raise ValueError(f'{field} must be a sequence of joint names, got {names!r:.80}') from None
    if not result:
        raise ValueError(f'{field} is empty; pass at least one joint name')
    for name in result:
        if not isinstance(name, str) or not name:
            raise ValueError(f'{field} must hold non-empty strings, got {name!r}')
    index_by_name(result, field)
    return result


def mapping_items(value: object, field: str) -> list[tuple[object, object]]:
    """Return the (key, value) pairs of a mapping; None counts as empty."""
    if value is None:
        return []
    if not isinstance(value, Mapping):
        raise ValueError(f'{field} must be a mapping (e.g. a dict) or None, got {value!r:.80}')
    return list(value.items())


def sequence(value: object, field: str) -> list:
    """Return the items of a list-like value (not a string or a mapping) as a list."""
    if isinstance(value, (str, bytes, Mapping)):
        raise ValueError(f'{field} must be a sequence, got {value!r:.80}')
    try:
        return list(value)
    except TypeError:
        raise ValueError(f'{field} must be a sequence, got {value!r:.80}') from None


def index_by_name(names: Iterable[str], field: str) -> dict[str, int]:
    """Map each name to its position, rejecting duplicates."""
    index: dict[str, int] = {}
    for i, name in enumerate(names):
        if name in index:
            raise ValueError(f'{field} lists joint {name!r} twice; joint names must be unique')
        index[name] = i
    return index


def select_joints(
    available: Mapping[str, int], wanted: Sequence[str], field: str
) -> list[int]:
    """Return the indices of `wanted` in `available`, naming every missing joint."""
    missing = [name for name in wanted if name not in available]
    if missing:
        raise ValueError(
            f'{field} lacks joint(s) {missing}; it has {list(available)}. '
            'Publish every joint of the robot or fix the joint names'
        )
    return [available[name] for name in wanted]


def frame(frame_id: str, field: str) -> str:
    """Return `frame_id` after checking it is a non-empty string."""
    if not isinstance(frame_id, str) or not frame_id:
        raise ValueError(f'{field} must be a non-empty frame name, got {frame_id!r}')
    return frame_id


def optional_frame(frame_id: str, field: str) -> str:
    """Return `frame_id` after checking it is a string, possibly empty."""
    if not isinstance(frame_id, str):
        raise ValueError(f'{field} must be a string (may be empty), got {frame_id!r}')
    return frame_id


def stamp_or_zero(stamp: Time | None) -> Time:
    """Return a copy of `stamp`, or a zero Time when it is None."""
    if stamp is None:
        return Time()
    if not isinstance(stamp, Time):
        raise ValueError(
            f'stamp must be a builtin_interfaces/Time or None, got {type(stamp).__name__}; '
            'use seconds_to_time() or node.get_clock().now().to_msg()'
        )
    return Time(sec=stamp.sec, nanosec=stamp.nanosec)
