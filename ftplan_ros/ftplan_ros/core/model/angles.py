"""Joint angles on the torus: wrapping to (-π, π] for joints without limits."""

import numba
import numpy as np


def wrap_angle(angle: np.ndarray | float) -> np.ndarray:
    """Wrap angles [rad] to (-π, π]."""
    return np.pi - np.mod(np.pi - np.asarray(angle, dtype=float), 2.0 * np.pi)


@numba.njit(cache=True, inline='always')
def wrap_one(angle):
    """`wrap_angle` of one angle [rad], compiled: for numba kernels."""
    return np.pi - (np.pi - angle) % (2.0 * np.pi)


@numba.njit(cache=True)
def wrap_steps(steps, periodic):
    """Take steps (..., n) [rad] the shortest way round in their periodic components (n,).

    Compiled, for kernels and for the many small steps of the trace and the sheet
    builder; the steps are wrapped in place when they are contiguous, so pass a temporary.
    """
    out = np.ascontiguousarray(steps)
    flat = out.reshape(-1)
    for k in range(flat.shape[0]):
        if periodic[k % periodic.shape[0]]:
            flat[k] = wrap_one(flat[k])
    return out


def wrap_configuration(thetas: np.ndarray, periodic: np.ndarray) -> np.ndarray:
    """Wrap the periodic components of configurations (..., n) [rad] to (-π, π]."""
    thetas = np.asarray(thetas, dtype=float)
    return np.where(periodic, wrap_angle(thetas), thetas)


def whole_turns(a: np.ndarray, b: np.ndarray, periodic: np.ndarray) -> np.ndarray:
    """Return the shift (..., n) [rad] that brings b next to a: whole turns on periodic joints.

    b + shift lies within π of a in every periodic joint; the other joints never shift (0).
    """
    turns = np.round((np.asarray(a, dtype=float) - np.asarray(b, dtype=float)) / (2.0 * np.pi))
    return np.where(periodic, 2.0 * np.pi * turns, 0.0)


def configuration_difference(a: np.ndarray, b: np.ndarray, periodic: np.ndarray) -> np.ndarray:
    """Shortest joint-space step a - b (..., n) [rad], going round for periodic joints."""
    diff = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    return np.where(periodic, wrap_angle(diff), diff)
