"""Joint limits beyond position: velocity, acceleration and jerk, and their scaling.

Velocity comes from the URDF (`<limit velocity=...>`), acceleration and jerk from a
joint_limits.yaml in MoveIt's format:

    joint_limits:
      panda_joint1: {has_velocity_limits: true, max_velocity: 2.175,
                     has_acceleration_limits: true, max_acceleration: 15.0,
                     has_jerk_limits: true, max_jerk: 7500.0}

A limit the file gives replaces the URDF's; a joint the file leaves out keeps what it
had. A robot that gives none (planar robots, DH tables, a URDF velocity of 0) gets the
documented defaults below; jerk is unbounded unless given. Scaling factors in (0, 1]
multiply the limits as MoveIt's `max_velocity_scaling_factor` and
`max_acceleration_scaling_factor` do (jerk scales with acceleration). Units: rad/s,
rad/s², rad/s³.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import InputError
from ..validation import check_keys, mapping, number

DEFAULT_MAX_VELOCITY = 1.0       # [rad/s] of a joint whose robot gives none
DEFAULT_MAX_ACCELERATION = 2.0   # [rad/s²] of a joint whose robot gives none

_KEYS = ('has_velocity_limits', 'max_velocity', 'has_acceleration_limits',
         'max_acceleration', 'has_jerk_limits', 'max_jerk', 'has_position_limits',
         'max_position', 'min_position')
_KINDS = (('velocity', 'max_velocity', 'has_velocity_limits'),
          ('acceleration', 'max_acceleration', 'has_acceleration_limits'),
          ('jerk', 'max_jerk', 'has_jerk_limits'))


@dataclass(frozen=True, eq=False)
class MotionLimits:
    """Per-joint bounds (n,): `velocity` [rad/s], `acceleration` [rad/s²], `jerk` [rad/s³].

    Velocity and acceleration are finite and > 0; jerk is inf where unbounded.
    """

    velocity: np.ndarray
    acceleration: np.ndarray
    jerk: np.ndarray

    def __post_init__(self):
        for name in ('velocity', 'acceleration', 'jerk'):
            values = np.array(getattr(self, name), dtype=float)
            values.flags.writeable = False
            object.__setattr__(self, name, values)
        if not (np.all(np.isfinite(self.velocity)) and np.all(np.isfinite(self.acceleration))
                and np.all(self.velocity > 0.0) and np.all(self.acceleration > 0.0)
                and np.all(self.jerk > 0.0)):
            raise ValueError('velocity and acceleration limits must be finite and > 0, '
                             'jerk limits > 0')

    @property
    def jerk_bounded(self) -> bool:
        """Whether any joint has a jerk limit."""
        return bool(np.any(np.isfinite(self.jerk)))

    def scaled(self, velocity_scaling: float, acceleration_scaling: float) -> MotionLimits:
        """Return the limits times the scaling factors (each in (0, 1]; jerk with acceleration)."""
        for name, value in (('max_velocity_scaling_factor', velocity_scaling),
                            ('max_acceleration_scaling_factor', acceleration_scaling)):
            check_scaling_factor(value, name)
        return MotionLimits(self.velocity * velocity_scaling,
                            self.acceleration * acceleration_scaling,
                            self.jerk * acceleration_scaling)

    def capped(self, max_velocity: float) -> MotionLimits:
        """Return the limits with every joint's velocity at most `max_velocity` [rad/s]."""
        return MotionLimits(np.minimum(self.velocity, max_velocity), self.acceleration, self.jerk)


def motion_limits_digest(limits: MotionLimits) -> str:
    """Name motion limits by a digest of every number: 12 hex digits.

    Of the limits as a plan is timed within them, scaling factors applied: a file and
    factors giving the same limits give the same digest. Unbounded jerk counts as None.
    """
    values = [[float(v) if math.isfinite(v) else None for v in row]
              for row in (limits.velocity, limits.acceleration, limits.jerk)]
    return hashlib.sha256(repr(values).encode()).hexdigest()[:12]


def check_scaling_factor(value: Any, where: str) -> float:
    """Return a scaling factor in (0, 1]; else InputError naming `where`."""
    value = number(value, where)
    if not 0.0 < value <= 1.0:
        raise InputError(where, f'must be in (0, 1], got {value}')
    return value


def default_motion_limits(n: int, velocity: Sequence[float] | None = None) -> MotionLimits:
    """Return the defaults for n joints; `velocity` [rad/s] (the URDF's) where > 0 and finite."""
    speeds = np.full(n, DEFAULT_MAX_VELOCITY)
    if velocity is not None:
        given = np.asarray(velocity, dtype=float)
        usable = np.isfinite(given) & (given > 0.0)
        speeds[usable] = given[usable]
    return MotionLimits(speeds, np.full(n, DEFAULT_MAX_ACCELERATION), np.full(n, math.inf))


def parse_joint_limits(data: Any, joint_names: Sequence[str], base: MotionLimits,
                       where: str = 'joint_limits') -> MotionLimits:
    """Apply a MoveIt joint_limits.yaml (as plain data) to `base`; InputError names the field.

    Joints of the file that the robot lacks are refused (a typo would go unnoticed);
    position limits are accepted and ignored (they come from the URDF).
    """
    data = mapping(data, where)
    check_keys(data, where, required=('joint_limits',),
               optional=('default_velocity_scaling_factor', 'default_acceleration_scaling_factor'))
    entries = mapping(data['joint_limits'], f'{where}.joint_limits')
    values = {'velocity': base.velocity.copy(), 'acceleration': base.acceleration.copy(),
              'jerk': base.jerk.copy()}
    for name, entry in entries.items():
        field = f'{where}.joint_limits.{name}'
        if name not in joint_names:
            raise InputError(field, f'unknown joint (joints: {", ".join(joint_names)})')
        entry = mapping(entry, field)
        check_keys(entry, field, required=(), optional=_KEYS)
        j = list(joint_names).index(name)
        for kind, key, flag in _KINDS:
            if _flag(entry, flag, field):
                if key not in entry:
                    raise InputError(f'{field}.{key}', f'is missing while {flag} is true')
                values[kind][j] = _positive(entry[key], f'{field}.{key}')
    return MotionLimits(**values)


def _flag(entry: Mapping, key: str, field: str) -> bool:
    value = entry.get(key, False)
    if not isinstance(value, bool):
        raise InputError(f'{field}.{key}', f'must be true or false, got {value!r}')
    return value


def _positive(value: Any, where: str) -> float:
    value = number(value, where)
    if value <= 0.0:
        raise InputError(where, f'must be > 0, got {value}')
    return value


def robot_motion_limits(robot: Any) -> MotionLimits:
    """Return a robot's motion limits: its chain's (URDF, joint_limits file), else the defaults."""
    model = getattr(robot, 'model', None)
    limits = getattr(model, 'motion_limits', None)
    return limits if limits is not None else default_motion_limits(robot.n_joints)
