"""Status reports on /diagnostics, one DiagnosticStatus per report.

A node's statuses are named '<node name>: <topic>', e.g. 'ftplan_executor: execution';
values are text (ftplan_msgs_py stringifies them). Bad input is both logged and reported.
"""

from __future__ import annotations

from collections.abc import Mapping

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node

from ftplan_msgs_py import create_diagnostic_array, create_diagnostic_status

from .topics import DIAGNOSTICS


def stamp_key(stamp: Time) -> str:
    """Return a Time as 'sec.nanosec' text: how reports name the plan they are about."""
    return f'{stamp.sec}.{stamp.nanosec:09d}'


def format_vector(values) -> str:
    """Return (n,) numbers as '[a, b, c]' with 6 decimals."""
    return '[' + ', '.join(f'{float(v):.6f}' for v in values) + ']'


def parse_vector(text: str) -> list[float]:
    """Read back a `format_vector` text '[a, b, c]' as numbers."""
    return [float(v) for v in text.strip('[] ').split(',')]


def parse_number(text: str | None) -> float:
    """Read a numeric status value; NaN when it is missing or not a number."""
    try:
        return float(text)
    except (TypeError, ValueError):
        return float('nan')


class Diagnostics:
    """Publish a node's statuses on /diagnostics and, when asked, log them too."""

    def __init__(self, node: Node):
        self._node = node
        self._publisher = node.create_publisher(DiagnosticArray, DIAGNOSTICS, 10)

    def status_name(self, topic: str) -> str:
        """Return the status name '<node name>: <topic>'."""
        return f'{self._node.get_name()}: {topic}'

    def report(self, topic: str, level: str, message: str,
               values: Mapping[str, object] | None = None, log: bool = False) -> None:
        """Publish one status; with `log`, also write `message` to the node's log."""
        if log:
            # rclpy wants one severity per call site, hence one call per level.
            logger = self._node.get_logger()
            if level == 'OK':
                logger.info(message)
            elif level == 'ERROR':
                logger.error(message)
            else:
                logger.warning(message)
        status = create_diagnostic_status(self.status_name(topic), level, message, values)
        stamp = self._node.get_clock().now().to_msg()
        self._publisher.publish(create_diagnostic_array([status], stamp))

    def rejected(self, topic: str, message: str,
                 values: Mapping[str, object] | None = None) -> None:
        """Log and report bad input that was ignored (WARN)."""
        self.report(topic, 'WARN', message, values, log=True)
