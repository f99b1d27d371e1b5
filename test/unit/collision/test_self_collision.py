"""Which link pairs are checked for self-collision (core/collision/self_collision.py).

Three capsule links of 0.5 m (radius 0.05) turning about parallel z axes, on a base
without geometry: links 1 and 3 are the one pair neither adjacent nor without geometry.
Folded back at joint b (θ_b near π), link 3 lies on link 1; near straight they stay
0.4 m apart. Their capsules lie in one plane, so whether they touch is a distance between
segments, which the referee below computes on its own.
"""

from dataclasses import replace

import numpy as np
import pytest

from ftplan_ros.core.collision.self_collision import (
    ALWAYS_FRACTION,
    adjacent_pairs,
    choose_exceptions,
    pair_contacts,
    sample_collisions,
    sample_disabled_pairs,
)
from ftplan_ros.core.model.dh import DHRow, chain_from_dh

FOLDED = (np.pi - 0.15, np.pi + 0.15)  # [rad] joint ranges about a fold
STRAIGHT = (-0.2, 0.2)
RADIUS = 0.05  # [m]


def folding_arm(b=None, c=None):
    """The arm of the module docstring, joints b and c within the given limits (or none)."""
    rows = [DHRow(a=0.5, alpha=0.0, d=0.0), DHRow(a=0.5, alpha=0.0, d=0.0, limits=b),
            DHRow(a=0.5, alpha=0.0, d=0.0, limits=c)]
    return chain_from_dh(rows, ['a', 'b', 'c'], RADIUS)


def segment_distance(p, q, r, s):
    """Distance [m] between segments pq and rs in the plane (N, 2 each).

    0 where they cross; else the least distance from an end of one to the other.
    """
    def to_segment(x, a, b):
        t = np.clip(np.einsum('ij,ij->i', x - a, b - a) / np.einsum('ij,ij->i', b - a, b - a),
                    0.0, 1.0)
        return np.linalg.norm(a + t[:, None] * (b - a) - x, axis=1)

    def turn(a, b, c):
        u, v = b - a, c - a
        return np.sign(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])

    crossing = (turn(p, q, r) != turn(p, q, s)) & (turn(r, s, p) != turn(r, s, q))
    ends = np.min([to_segment(p, r, s), to_segment(q, r, s), to_segment(r, p, q),
                   to_segment(s, p, q)], axis=0)
    return np.where(crossing, 0.0, ends)


def test_links_1_and_3_touch_where_their_capsules_come_within_two_radii(rng):
    """Against the referee's distance between the capsules' segments."""
    thetas = rng.uniform(-np.pi, np.pi, (400, 3))
    thetas[:200, 1] = rng.uniform(*FOLDED, 200)  # half of them folded, most touching
    pairs, touching = pair_contacts(folding_arm(), thetas)
    assert pairs == [(1, 3)]
    angles = np.cumsum(thetas, axis=1)
    joints = np.concatenate([np.zeros((len(thetas), 1, 2)), np.cumsum(
        0.5 * np.stack([np.cos(angles), np.sin(angles)], axis=2), axis=1)], axis=1)
    distance = segment_distance(joints[:, 0], joints[:, 1], joints[:, 2], joints[:, 3])
    clear = np.abs(distance - 2 * RADIUS) > 1e-9
    assert np.array_equal(touching[clear, 0], distance[clear] < 2 * RADIUS)
    assert 20 < np.count_nonzero(touching[:, 0]) < 380 and np.count_nonzero(clear) > 390


def test_pairs_always_touching_or_never_touching_in_the_samples_are_exempt(rng):
    """Only pairs with geometry are sampled: the base's is not among them."""
    adjacent = {(1, 2): 'adjacent', (2, 3): 'adjacent'}
    assert sample_disabled_pairs(folding_arm(b=FOLDED), 200, rng) == adjacent | {
        (1, 3): 'always'}
    assert sample_disabled_pairs(folding_arm(b=STRAIGHT, c=STRAIGHT), 200, rng) == adjacent | {
        (1, 3): 'never'}
    # Free joints: links 1 and 3 touch in some samples only, so their pair is checked.
    counts = sample_collisions(folding_arm(), 1000, rng)
    assert 0 < counts[(1, 3)] < ALWAYS_FRACTION * 1000
    assert choose_exceptions(folding_arm(), counts, 1000) == adjacent


def test_never_false_keeps_the_pairs_that_never_touched_checked(rng):
    arm = folding_arm(b=STRAIGHT, c=STRAIGHT)
    assert sample_disabled_pairs(arm, 200, rng, never=False) == {(1, 2): 'adjacent',
                                                                (2, 3): 'adjacent'}


@pytest.mark.parametrize('share, why', [(0.95, 'always'), (0.9499, None), (0.0, 'never'),
                                        (0.0001, None)])
def test_always_means_at_least_95_percent_of_the_samples(share, why):
    counts = {(1, 3): round(share * 10_000)}
    assert choose_exceptions(folding_arm(), counts, 10_000).get((1, 3)) == why


def test_links_without_geometry_join_their_neighbours_as_adjacent():
    """As MoveIt counts adjacency: link 2 has nothing to collide with, so 1 and 3 are joined
    through it (and none of the three pairs is sampled)."""
    arm = folding_arm()
    bare = replace(arm, shapes=tuple(item for item in arm.shapes if item.link != 2))
    assert adjacent_pairs(arm) == {(1, 2), (2, 3)}
    assert adjacent_pairs(bare) == {(1, 3)}
    assert sample_collisions(bare, 50, np.random.default_rng(0)) == {}
