"""What the executor's verbs take (the moment) and give back (actions for the node).

The executor never reads a clock and never publishes: each verb gets the `Moment` of
its call and returns the actions it decided, in order, for the node to carry out
(nodes/executor.py): command a path, stop the arm, report the execution status, report
a refused input.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

from .command import Command
from .state import Execution, State


class Moment(NamedTuple):
    """When a verb is called: monotonic time [s] for timeouts, ROS time [ns] for stamps."""

    monotonic: float
    ros_ns: int


@dataclass(frozen=True)
class Stop:
    """Ask the controller to stop the arm where it is."""


@dataclass(frozen=True, eq=False)
class Status:
    """Report the execution status: `message` at `level` ('OK', 'WARN', 'ERROR').

    `execution` is a copy of the run as it was at the report; `tolerated_joints` are the
    joints the run's plan (else the held plan) tolerates.
    """

    message: str
    level: str
    log: bool
    state: State
    plan: str                              # the held plan's key ('' without one)
    names: tuple[str, ...]                 # the arm's joints
    execution: Execution | None
    locked_joints: tuple[str, ...]         # locked and not yet repaired
    tolerated_joints: tuple[str, ...] | None


@dataclass(frozen=True)
class Rejected:
    """Report an input that was refused (logged, WARN), about `joint` if set."""

    message: str
    joint: str = ''


Action = Command | Stop | Status | Rejected


@dataclass(frozen=True)
class Answer:
    """The answer to a request (execute, reset) and the actions it led to."""

    success: bool
    message: str
    actions: list[Action] = field(default_factory=list)
