"""The paper's surface search (core/planning/surface_search.py): fail-closed screens, fans."""

import numpy as np
import pytest

from ftplan_ros.core import CollisionChecker, ManifoldCache, PlannerOptions
from ftplan_ros.core.planning.surface_search import SurfaceSearch, straight_fans


class _NanChecker(CollisionChecker):
    """A checker whose clearances are all NaN, as a broken distance would give."""

    def clearance(self, thetas, needed=np.inf, refine=True):
        return np.full_like(super().clearance(thetas, needed, refine), np.nan)


def test_a_nan_clearance_reads_as_a_collision(fig3a):
    """The search's own screens of θ_s and of the web's vertices fail closed on NaN."""
    scene, result = fig3a
    search = SurfaceSearch(scene, PlannerOptions(), np.random.default_rng(0),
                           lambda line: None, ManifoldCache())
    webs = []
    build = search._fine_surface
    search._fine_surface = lambda *args: webs.append(args) or build(*args)
    assert search.run(result.theta_s).feasible and webs
    assert search._given_start(result.theta_s).shape == (1, 3)
    search.checker = _NanChecker(scene.robot, scene.obstacles)
    assert search._fine_surface(*webs[-1]) is None
    assert search._given_start(result.theta_s).shape == (0, 3)


def test_a_search_whose_webs_all_fail_to_build_says_so(fig3a):
    """When no fine web is clear at its vertices, no surface was checked: the reason says
    that, not that the check failed."""
    scene, _ = fig3a
    search = SurfaceSearch(scene, PlannerOptions(), np.random.default_rng(0),
                           lambda line: None, ManifoldCache())
    search._fine_surface = lambda *args: None
    result = search.run()
    assert not result.feasible
    assert 'best failure surfaces proposed reached the self-check' in result.reason
    assert 'check failed' not in result.reason


@pytest.mark.parametrize('n', [3, 7])
def test_ranking_fans_are_the_points_along_each_straight_path(n):
    """straight_fans (P, W, G, n) against start + w/W (goal - start), written with arrays."""
    rng = np.random.default_rng(2)
    starts, goals = rng.normal(size=(40, n)), rng.normal(size=(40, 6, n))
    steps = np.arange(1, 9)[None, :, None, None] / 8
    expected = starts[:, None, None, :] + steps * (goals[:, None] - starts[:, None, None, :])
    assert np.array_equal(straight_fans(starts, goals, 8), expected)
