"""Convert between float seconds and builtin_interfaces Time and Duration."""

import math

from builtin_interfaces.msg import Duration, Time

from ftplan_msgs_py._validation import INT32_MAX, INT32_MIN, finite_float

_NS_PER_S = 1_000_000_000


def _split_seconds(t: float, field: str, min_sec: int) -> tuple[int, int]:
    value = finite_float(t, field)
    # Split before scaling: value * 1e9 would lose nanoseconds for wall-clock times.
    sec = math.floor(value)
    nanosec = round((value - sec) * _NS_PER_S)
    if nanosec == _NS_PER_S:
        sec, nanosec = sec + 1, 0
    if not min_sec <= sec <= INT32_MAX:
        raise ValueError(
            f'{field} = {value} s is outside [{min_sec}, {INT32_MAX}] s, '
            'the range of the int32 seconds field'
        )
    return sec, nanosec


def _join_seconds(sec: int, nanosec: int, what: str) -> float:
    if not 0 <= nanosec < _NS_PER_S:
        raise ValueError(f'{what}.nanosec = {nanosec} must be in [0, 1e9); normalise the stamp')
    return sec + nanosec / _NS_PER_S


def seconds_to_time(t: float) -> Time:
    """Create a Time from `t` seconds since the epoch (finite, >= 0), rounded to 1 ns."""
    sec, nanosec = _split_seconds(t, 'time', 0)
    return Time(sec=sec, nanosec=nanosec)


def time_to_seconds(msg: Time) -> float:
    """Read a Time as float seconds; nanosec must be below 1e9."""
    return _join_seconds(msg.sec, msg.nanosec, 'Time')


def time_to_nanoseconds(msg: Time) -> int:
    """Read a Time as integer nanoseconds since the epoch, as rclpy's Time.from_msg does.

    :raises ValueError: when sec is negative (before the epoch, which rclpy refuses) or
        nanosec is not below 1e9, naming the field.
    """
    if msg.sec < 0:
        raise ValueError(f'Time.sec = {msg.sec} is before the epoch; stamps must be >= 0')
    _join_seconds(msg.sec, msg.nanosec, 'Time')
    return msg.sec * _NS_PER_S + msg.nanosec


def seconds_to_duration(t: float) -> Duration:
    """Create a Duration from `t` seconds (finite, may be negative), rounded to 1 ns.

    A negative duration has negative `sec` and 0 <= `nanosec` < 1e9, as in rclpy.
    """
    sec, nanosec = _split_seconds(t, 'duration', INT32_MIN)
    return Duration(sec=sec, nanosec=nanosec)


def duration_to_seconds(msg: Duration) -> float:
    """Read a Duration as float seconds; nanosec must be below 1e9."""
    return _join_seconds(msg.sec, msg.nanosec, 'Duration')
