"""The failure surface's web (core/paper/failure_surface.py): choosing hits, numbering points."""

import numpy as np
import pytest

from ftplan_ros.core.paper.failure_planes import FailurePlaneHit
from ftplan_ros.core.paper.failure_surface import FailureSurface, choose_hits, smallest_windows


def _windows_by_definition(hits: list[list[float]], lap: float) -> list[tuple[float, float]]:
    """Each left hit's window to the nearest right end completing the joints, O(H^2)."""
    flat = sorted((p, j) for j, positions in enumerate(hits) for p in positions)
    windows = []
    for left in range(len(flat)):
        for right in range(left, len(flat)):
            if len({j for _, j in flat[left:right + 1]}) == len(hits):
                window = (flat[left][0], flat[right][0])
                if window not in windows and window[0] < lap:
                    windows.append(window)
                break
    return sorted(windows, key=lambda w: w[1] - w[0])


def test_smallest_windows_and_the_hits_nearest_each_windows_middle():
    """The batched sweep against its definition: windows, then inside and nearest the middle."""
    rng = np.random.default_rng(4)
    for _ in range(200):
        n_starts, n_joints, lap = rng.integers(1, 4), rng.integers(1, 4), rng.uniform(5, 25)
        hits = [[[FailurePlaneHit(j, np.full(3, float(k)), float(p)) for k, p in
                  enumerate(np.sort(np.round(rng.uniform(0, 20, rng.integers(1, 6)), 1)))]
                 for j in range(n_joints)] for _ in range(n_starts)]
        flat = [(s, j, h) for s, per_start in enumerate(hits)
                for j, joint_hits in enumerate(per_start) for h in joint_hits]
        # Shuffled, but each start's hits of a joint in order along the arc, as promised.
        keys = rng.random(len(flat))
        groups = np.array([s * n_joints + j for s, j, _ in flat])
        for group in np.unique(groups):
            keys[groups == group] = np.sort(keys[groups == group])
        flat = [flat[i] for i in np.argsort(keys)]
        owners, windows, chosen = smallest_windows(
            np.array([s for s, _, _ in flat]), np.array([j for _, j, _ in flat]),
            np.array([h.position for _, _, h in flat]), n_starts, n_joints, lap)
        for s, per_start in enumerate(hits):
            mine = owners == s
            assert [tuple(w) for w in windows[mine]] == _windows_by_definition(
                [[h.position for h in joint_hits] for joint_hits in per_start], lap)
            for window, row in zip(windows[mine], chosen[mine], strict=True):
                middle = 0.5 * (window[0] + window[1])
                for j, joint_hits in enumerate(per_start):
                    inside = [h for h in joint_hits if window[0] <= h.position <= window[1]]
                    picked = flat[row[j]]
                    assert picked[:2] == (s, j)
                    assert picked[2] is min(inside, key=lambda h: abs(h.position - middle))
                assert [h.position for h in choose_hits(per_start, tuple(window))] == \
                    [flat[k][2].position for k in row]
    with pytest.raises(ValueError, match='holds no hit'):
        choose_hits([[FailurePlaneHit(0, np.zeros(3), 5.0)]], (0.0, 1.0))


def test_web_points_and_segments_are_numbered_by_their_coordinates():
    """`vertex_ids` and `edge_ids` against numbering the distinct rows with np.unique.

    Webs on a coarse lattice, with padded columns, a repeated path, the shared θ_s and,
    in a third of them, joint 1 the same at many points, where the ids come from sorting
    by the other joints.
    """
    rng = np.random.default_rng(11)
    for trial in range(300):
        shape = (int(rng.integers(1, 9)), int(rng.integers(1, 9)), int(rng.integers(1, 4)))
        paths = rng.integers(0, rng.choice([2, 4, 1000]), shape) * 0.25
        for k in range(len(paths)):
            if rng.random() < 0.5:
                end = int(rng.integers(1, paths.shape[1] + 1))
                paths[k, end:] = paths[k, end - 1]
        paths[:, 0] = paths[0, 0]
        if len(paths) > 2 and rng.random() < 0.5:
            paths[2] = paths[1]
        if trial % 3 == 0:
            paths[..., 0] = 1.0
        surface = FailureSurface(paths, 0, (), (0,))
        _, points = np.unique(surface.vertices, axis=0, return_inverse=True)
        assert np.array_equal(surface.vertex_ids, points.reshape(-1)), trial
        ends = np.sort(points.reshape(-1)[surface.edges], axis=1)
        _, segments = np.unique(ends, axis=0, return_inverse=True)
        pairs = np.unique(np.stack([segments.reshape(-1), surface.edge_ids]), axis=1)
        assert pairs.shape[1] == segments.max(initial=-1) + 1, trial  # the same partition
        assert np.array_equal(np.unique(surface.edge_ids), np.arange(pairs.shape[1])), trial
        assert (surface.point_count, surface.segment_count) == (points.max() + 1,
                                                                 pairs.shape[1]), trial
