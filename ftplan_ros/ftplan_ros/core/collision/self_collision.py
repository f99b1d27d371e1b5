"""Which pairs of links to check for self-collision, as MoveIt's setup assistant chooses.

Pairs that can never collide cost time, and pairs that always touch (adjacent links,
overlapping housings) would make every configuration collide: both are exempted.
`default_disabled_pairs` is what a robot without a written list gets (adjacent links and
links touching at the reference configuration); `sample_disabled_pairs` is the full
analysis `tools/self_collision_pairs.py` writes into a robot's config.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..model.chain import ChainModel
from ..model.spatial import SpatialArm
from .checker import CollisionChecker

ALWAYS_FRACTION = 0.95  # a pair touching in this share of the samples counts as always


def reference_configuration(model: ChainModel) -> np.ndarray:
    """Return the middle of every joint's range [rad] (0 for continuous joints)."""
    return SpatialArm(model).limits.mean(axis=1)


def pair_clearances(model: ChainModel, thetas: np.ndarray,
                    ) -> tuple[tuple[tuple[int, int], ...], np.ndarray]:
    """Every pair of links with geometry and their distances (N, pairs) [m] at thetas (N, n).

    Exact where they touch (<= 0), lower bounds above.
    """
    everything = replace(model, disabled_pairs=frozenset())
    checker = CollisionChecker(SpatialArm(everything, 'position'), [])
    if not checker.pairs:  # fewer than two links with geometry
        return (), np.zeros((len(thetas), 0))
    clearance = checker.clearance(thetas, needed=0.0)
    links = checker.channel_links
    distances = np.stack([clearance[:, (links[:, 0] == a) & (links[:, 1] == b)].min(axis=1)
                          for a, b in checker.pairs], axis=1).reshape(len(thetas), -1)
    return checker.pairs, distances


def default_disabled_pairs(model: ChainModel) -> frozenset[tuple[int, int]]:
    """Adjacent links, and links that touch at the reference configuration."""
    pairs, distances = pair_clearances(model, reference_configuration(model)[None, :])
    touching = {pair for pair, distance in zip(pairs, distances[0], strict=True)
                if distance <= 0.0}
    return frozenset(model.adjacent_pairs() | touching)


def sample_disabled_pairs(model: ChainModel, samples: int, rng: np.random.Generator,
                          ) -> dict[tuple[int, int], str]:
    """Choose the pairs to exempt, with why.

    'adjacent', 'default' (touching at the reference configuration), 'always' (touching
    in >= 95 % of random samples) or 'never' (apart in every sample).
    """
    limits = SpatialArm(model).limits
    thetas = rng.uniform(limits[:, 0], limits[:, 1], size=(samples, model.n_joints))
    pairs, distances = pair_clearances(model, thetas)
    _, reference = pair_clearances(model, reference_configuration(model)[None, :])
    touching = distances <= 0.0
    out: dict[tuple[int, int], str] = {}
    for k, pair in enumerate(pairs):
        if pair in model.adjacent_pairs():
            out[pair] = 'adjacent'
        elif reference[0, k] <= 0.0:
            out[pair] = 'default'
        elif touching[:, k].mean() >= ALWAYS_FRACTION:
            out[pair] = 'always'
        elif not touching[:, k].any():
            out[pair] = 'never'
    return out
