"""MoveIt joint_limits.yaml files: read, validate, apply to a robot's motion limits."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ..model.motion_limits import MotionLimits, parse_joint_limits
from .files import load_yaml, read_text


def load_joint_limits(path: str | Path, joint_names: Sequence[str], base: MotionLimits,
                      where: str = 'joint_limits') -> MotionLimits:
    """Read a joint_limits.yaml file and apply it to `base` (model/motion_limits.py).

    Bad files raise InputError naming the field, e.g. `joint_limits.joint_limits.j1.max_jerk`.
    """
    text = read_text(path, where)
    return parse_joint_limits(load_yaml(text, f'{where} file {Path(path).name}'), joint_names,
                              base, where)
