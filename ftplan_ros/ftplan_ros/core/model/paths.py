"""Joint-space polylines (k, n) [rad]: length, points by fraction of length, dense samples."""

import numpy as np


def path_length(path: np.ndarray) -> float:
    """Joint-space length [rad] of a polyline (k, n)."""
    return float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))


def cumulative_fractions(path: np.ndarray) -> np.ndarray:
    """Fraction (k,) of the length travelled at each vertex, from 0 to 1."""
    travelled = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path, axis=0), axis=1))])
    total = travelled[-1]
    return travelled / total if total > 0 else np.linspace(0.0, 1.0, len(path))


def point_at_fraction(path: np.ndarray, fraction: float) -> np.ndarray:
    """Return the point (n,) [rad] reached after `fraction` (0..1) of the polyline's length."""
    fractions = cumulative_fractions(path)
    fraction = float(np.clip(fraction, 0.0, 1.0))
    w = int(np.clip(np.searchsorted(fractions, fraction, side='right') - 1, 0, len(path) - 2))
    span = fractions[w + 1] - fractions[w]
    t = 0.0 if span == 0 else (fraction - fractions[w]) / span
    return path[w] + t * (path[w + 1] - path[w])


def path_until(path: np.ndarray, fraction: float) -> np.ndarray:
    """Return the part (j, n) [rad] of the polyline up to `fraction` of its length."""
    fractions = cumulative_fractions(path)
    kept = path[fractions < fraction]
    return np.vstack([kept, point_at_fraction(path, fraction)[None, :]])


def densify(path: np.ndarray, max_step: float) -> np.ndarray:
    """Points (m, n) along the polyline no more than `max_step` [rad] apart (∞-norm)."""
    pieces = [path[:1]]
    for a, b in zip(path[:-1], path[1:], strict=True):
        steps = max(1, int(np.ceil(np.max(np.abs(b - a)) / max_step)))
        t = np.arange(1, steps + 1)[:, None] / steps
        pieces.append(a + t * (b - a))
    return np.vstack(pieces)
