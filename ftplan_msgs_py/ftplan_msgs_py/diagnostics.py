"""Convert between plain status reports and diagnostic_msgs DiagnosticStatus/Array."""

from collections.abc import Iterable, Mapping
from typing import NamedTuple

import numpy as np
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from std_msgs.msg import Header

from ftplan_msgs_py._validation import mapping_items, sequence, stamp_or_zero

DIAGNOSTIC_LEVELS = {
    'OK': DiagnosticStatus.OK,
    'WARN': DiagnosticStatus.WARN,
    'ERROR': DiagnosticStatus.ERROR,
    'STALE': DiagnosticStatus.STALE,
}
_LEVEL_NAMES = {ord(value): name for name, value in DIAGNOSTIC_LEVELS.items()}


class DiagnosticReading(NamedTuple):
    """A DiagnosticStatus as plain types; `level` is 'OK', 'WARN', 'ERROR' or 'STALE'."""

    name: str
    level: str
    message: str
    values: dict[str, str]
    hardware_id: str = ''


def _format_value(value: object) -> str:
    """Stringify a diagnostic value; floats keep full precision (repr), NaN becomes 'nan'."""
    if isinstance(value, np.ndarray):
        return str(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float):
        return repr(value)
    return str(value)


def _check_text(value: object, field: str, allow_empty: bool = True) -> str:
    if not isinstance(value, str) or (not allow_empty and not value):
        raise ValueError(f'diagnostic {field} must be a{"" if allow_empty else " non-empty"} '
                         f'string, got {value!r}')
    return value


def create_diagnostic_status(
    name: str,
    level: str,
    message: str,
    values: Mapping[str, object] | None = None,
    hardware_id: str = '',
) -> DiagnosticStatus:
    """Create a DiagnosticStatus.

    Values are reported as text, so non-finite floats are allowed here ('nan', 'inf'):
    a diagnostic is where a node reports the bad input it just rejected.

    :param name: the status name, e.g. 'ftplan planner: plan'.
    :param level: 'OK', 'WARN', 'ERROR' or 'STALE'.
    :param message: a one-line human-readable summary.
    :param values: key -> value; values are stringified, floats with repr precision.
    :param hardware_id: the hardware the status is about, if any.
    :return: the DiagnosticStatus.
    """
    if not isinstance(level, str) or level not in DIAGNOSTIC_LEVELS:
        raise ValueError(
            f'diagnostic level {level!r} is unknown; use one of {list(DIAGNOSTIC_LEVELS)}'
        )
    pairs = []
    for key, value in mapping_items(values, 'diagnostic values'):
        pairs.append(KeyValue(key=_check_text(key, 'value key', allow_empty=False),
                              value=_format_value(value)))
    return DiagnosticStatus(
        level=DIAGNOSTIC_LEVELS[level],
        name=_check_text(name, 'name', allow_empty=False),
        message=_check_text(message, 'message'),
        hardware_id=_check_text(hardware_id, 'hardware_id'),
        values=pairs,
    )


def create_diagnostic_array(
    statuses: Iterable[DiagnosticStatus], stamp: Time | None = None
) -> DiagnosticArray:
    """Create a DiagnosticArray of `statuses`, stamped `stamp` (None leaves it zero)."""
    status_list = sequence(statuses, 'statuses')
    for i, status in enumerate(status_list):
        if not isinstance(status, DiagnosticStatus):
            raise ValueError(
                f'statuses[{i}] is a {type(status).__name__}, not a DiagnosticStatus; '
                'build it with create_diagnostic_status()'
            )
    return DiagnosticArray(header=Header(stamp=stamp_or_zero(stamp)), status=status_list)


def read_diagnostic_status(msg: DiagnosticStatus) -> DiagnosticReading:
    """Read a DiagnosticStatus as plain types.

    :raises ValueError: on an unknown level or a key that appears twice.
    """
    level = msg.level if isinstance(msg.level, int) else ord(msg.level)
    if level not in _LEVEL_NAMES:
        raise ValueError(
            f'diagnostic {msg.name!r} has unknown level {level}; expected 0 (OK), 1 (WARN), '
            '2 (ERROR) or 3 (STALE)'
        )
    values: dict[str, str] = {}
    for pair in msg.values:
        if pair.key in values:
            raise ValueError(f'diagnostic {msg.name!r} lists key {pair.key!r} twice')
        values[pair.key] = pair.value
    return DiagnosticReading(msg.name, _LEVEL_NAMES[level], msg.message, values, msg.hardware_id)
