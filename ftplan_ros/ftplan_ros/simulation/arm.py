"""The simulated arm behind a small interface, so that another can take its place.

The sim node (nodes/sim.py) drives an `Arm` by its own clock: it hands it commands
(`follow`), stops (`stop`), lock events (`lock`) and resets (`reset`), and steps it
(`step`), which returns the path the arm swept and the locks that took effect meanwhile;
the node checks the sweep for collisions (clearance.py) and publishes the joint states.
`KinematicArm` (kinematic.py) follows its commands exactly, like a position-controlled
arm; `MujocoArm` (mujoco_arm.py) simulates its dynamics, and its steps say also the
joints' velocities and torques and the contacts MuJoCo found.

Angles [rad] (lifted: a periodic joint's angle goes on past ±π as commanded), times [s]
on the sim's clock, stamps ROS time [ns].
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from ftplan_ros.execution.locks import DEFAULT_LOCK_ANGLE_TOLERANCE


@dataclass(frozen=True)
class ArmOptions:
    """How the arm moves and locks (the sim node's parameters of the same names)."""

    max_joint_speed: float = 2.0         # [rad/s] of every joint; faster commands slow down
    brake_on_lock: bool = True           # a lock brakes the free joints (acceleration limits)
    lock_angle_tolerance: float = DEFAULT_LOCK_ANGLE_TOLERANCE  # [rad] from where the joint is


@dataclass(frozen=True)
class HeldJoint:
    """A locked joint a command would have moved, by up to `moved` [rad], held at `angle`."""

    joint: int
    moved: float
    angle: float


@dataclass(frozen=True)
class Following:
    """How the arm takes a command: the locked joints it holds, and how much slower it goes."""

    held: tuple[HeldJoint, ...] = ()
    slowdown: float = 1.0   # the largest factor a step of the command was slowed down by


@dataclass(frozen=True, eq=False)
class Locked:
    """Joint `joint` locked at `angle` [rad]; `jump` (k, n) is the sweep to that angle, if any."""

    joint: int
    angle: float
    jump: np.ndarray | None = None


@dataclass(frozen=True)
class Scheduled:
    """Joint `joint` locks `seconds` [s] from now, where its command puts the arm then."""

    joint: int
    seconds: float


@dataclass(frozen=True)
class Refused:
    """A lock event for joint `joint` that cannot be taken, and why."""

    joint: int
    problem: str


LockOutcome = Locked | Scheduled | Refused


@dataclass(frozen=True)
class Contact:
    """Bodies `first` and `second` came into contact, up to `depth` [m] deep (> 0)."""

    first: str
    second: str
    depth: float


@dataclass(frozen=True, eq=False)
class Step:
    """What one step of the arm did: the path it swept (None: it stood) and the locks due.

    A physical arm says too how fast its joints move [rad/s] and their torques [Nm]
    (None: not simulated), and which contacts began.
    """

    swept: np.ndarray | None                       # (k, n) from where it was to where it is
    locks: list[LockOutcome] = field(default_factory=list)
    velocity: np.ndarray | None = None             # (n,) [rad/s] at the end of the step
    effort: np.ndarray | None = None               # (n,) [Nm] at the end of the step
    contacts: list[Contact] = field(default_factory=list)


class Arm(Protocol):
    """What the sim node asks of a simulated arm."""

    q: np.ndarray                  # (n,) the configuration now
    locked: Mapping[int, float]    # locked joints and their angles [rad]
    time: float                    # [s] the arm's clock, advanced by `step`
    options: ArmOptions

    @property
    def moving(self) -> bool:
        """Whether a command is under way."""

    def follow(self, positions: np.ndarray, times: np.ndarray, stamp_ns: int, now_ns: int,
               ) -> Following:
        """Follow positions (k, n) at times (k,) [s] from ROS time `stamp_ns` (now `now_ns`)."""

    def stop(self) -> None:
        """Stop where the arm is."""

    def lock(self, joint: int, angle: float | None, stamp_ns: int, now_ns: int = 0,
             ) -> LockOutcome | None:
        """Lock `joint` (at `angle`, None: where it is) at ROS time `stamp_ns` (0: now).

        `now_ns` is the ROS time now (0: unknown). None when the joint is locked, or
        scheduled to lock, already.
        """

    def step(self, dt: float) -> Step:
        """Move on by `dt` [s]."""

    def reset(self, q: np.ndarray) -> None:
        """Stand at q (n,), every joint free, nothing commanded or scheduled."""
