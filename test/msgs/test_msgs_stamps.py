import math

import pytest
from builtin_interfaces.msg import Duration, Time

from ftplan_msgs_py.stamps import (
    duration_to_seconds,
    seconds_to_duration,
    seconds_to_time,
    time_to_seconds,
)


def test_time_round_trip():
    msg = seconds_to_time(12.25)
    assert (msg.sec, msg.nanosec) == (12, 250_000_000)
    assert time_to_seconds(msg) == 12.25


def test_wall_clock_time_keeps_sub_microsecond_precision():
    msg = seconds_to_time(1_700_000_000.123456789)
    assert msg.sec == 1_700_000_000
    # A float at 1.7e9 s resolves about 0.24 us; scaling by 1e9 first would lose more.
    assert abs(msg.nanosec - 123_456_789) < 300


def test_rounding_carries_into_seconds():
    msg = seconds_to_time(2.9999999999)
    assert (msg.sec, msg.nanosec) == (3, 0)


def test_hand_built_time_is_read():
    assert time_to_seconds(Time(sec=3, nanosec=1)) == pytest.approx(3.000000001, abs=1e-12)


def test_negative_duration_uses_negative_seconds_and_positive_nanoseconds():
    msg = seconds_to_duration(-0.25)
    assert (msg.sec, msg.nanosec) == (-1, 750_000_000)
    assert duration_to_seconds(msg) == -0.25


def test_duration_round_trip():
    assert duration_to_seconds(seconds_to_duration(1.5)) == 1.5
    assert duration_to_seconds(Duration(sec=2, nanosec=5)) == pytest.approx(2.000000005)


@pytest.mark.parametrize('convert', [seconds_to_time, seconds_to_duration])
@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_non_finite_seconds_are_rejected(convert, bad):
    with pytest.raises(ValueError, match='non-finite'):
        convert(bad)


def test_negative_time_is_rejected():
    with pytest.raises(ValueError, match='outside'):
        seconds_to_time(-1.0)


@pytest.mark.parametrize('convert', [seconds_to_time, seconds_to_duration])
def test_seconds_beyond_int32_are_rejected(convert):
    with pytest.raises(ValueError, match='int32'):
        convert(2.0**31)


def test_non_numeric_seconds_are_rejected():
    with pytest.raises(ValueError, match='numeric'):
        seconds_to_time('soon')


def test_array_of_seconds_is_rejected():
    with pytest.raises(ValueError, match='single number'):
        seconds_to_duration([1.0, 2.0])


def test_unnormalised_nanoseconds_are_rejected():
    with pytest.raises(ValueError, match=r'Time\.nanosec'):
        time_to_seconds(Time(sec=1, nanosec=1_000_000_000))
    with pytest.raises(ValueError, match=r'Duration\.nanosec'):
        duration_to_seconds(Duration(sec=1, nanosec=2_000_000_000))
