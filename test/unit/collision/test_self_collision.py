"""Which link pairs are checked for self-collision (core/collision/self_collision.py).

Three capsule links of 0.5 m (radius 0.05) turning about parallel z axes, on a base
without geometry: links 1 and 3 are the one pair neither adjacent nor without geometry.
Folded back at joint b (θ_b near π), link 3 lies on link 1; near straight they stay
0.4 m apart.
"""

import numpy as np

from ftplan_ros.core.collision.self_collision import (
    default_disabled_pairs,
    reference_configuration,
    sample_disabled_pairs,
)
from ftplan_ros.core.model.dh import DHRow, chain_from_dh

ADJACENT = {(0, 1), (1, 2), (2, 3)}  # joints a, b, c: base to link 1, link 1 to 2, 2 to 3
FOLDED = (np.pi - 0.15, np.pi + 0.15)  # [rad] joint ranges about a fold
STRAIGHT = (-0.2, 0.2)


def folding_arm(b=None, c=None):
    """The arm of the module docstring, joints b and c within the given limits (or none)."""
    rows = [DHRow(a=0.5, alpha=0.0, d=0.0), DHRow(a=0.5, alpha=0.0, d=0.0, limits=b),
            DHRow(a=0.5, alpha=0.0, d=0.0, limits=c)]
    return chain_from_dh(rows, ['a', 'b', 'c'], 0.05)


def test_by_default_adjacent_links_and_links_touching_midway_in_their_ranges_are_exempt():
    straight = folding_arm()  # joints without limits: the reference configuration is 0
    assert np.array_equal(reference_configuration(straight), [0.0, 0.0, 0.0])
    assert default_disabled_pairs(straight) == ADJACENT
    folded = folding_arm(b=FOLDED)
    assert np.allclose(reference_configuration(folded), [0.0, np.pi, 0.0])
    assert default_disabled_pairs(folded) == ADJACENT | {(1, 3)}


def test_sampled_pairs_are_exempt_as_adjacent_touching_midway_or_never_touching():
    """Only pairs with geometry are sampled: the base's is not among them."""
    rng = np.random.default_rng(2)
    assert sample_disabled_pairs(folding_arm(b=FOLDED), 200, rng) == {
        (1, 2): 'adjacent', (2, 3): 'adjacent', (1, 3): 'default'}
    assert sample_disabled_pairs(folding_arm(b=STRAIGHT, c=STRAIGHT), 200, rng) == {
        (1, 2): 'adjacent', (2, 3): 'adjacent', (1, 3): 'never'}
    # Free joints: links 1 and 3 touch in some samples only, so their pair is checked.
    assert sample_disabled_pairs(folding_arm(), 200, rng) == {
        (1, 2): 'adjacent', (2, 3): 'adjacent'}
