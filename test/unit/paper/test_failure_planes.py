"""Step 3: failure-plane hits against exact 2R inverse kinematics and the paper's Table I."""

import numpy as np
import pytest
from ftplan_testing import SCENES, jacobian

from ftplan_ros.core import load_scene, plan
from ftplan_ros.core.collision.checker import CollisionChecker
from ftplan_ros.core.model.angles import configuration_difference, wrap_angle
from ftplan_ros.core.model.robot import PlanarChain
from ftplan_ros.core.paper.failure_planes import (
    crossing_segments,
    failure_plane_hits,
)
from ftplan_ros.core.paper.manifolds import (
    mark_obstacle_free,
    project_to_preimage,
    trace_self_motion_manifolds,
)

ARM = PlanarChain((1.0, 1.0, 1.0), ('joint1', 'joint2', 'joint3'))
X_GOAL = np.array([1.0, 0.0])
PERIODIC = np.ones(3, dtype=bool)

# Table I of the paper [deg]: start position, θ_s, and the hits on H_1, H_2, H_3.
TABLE_I = {
    'fig3a': ([2.0, 0.0], [-73.3, 114.0, -23.0],
              [[-73.3, 179.4, -105.9], [-113.4, 114.0, 65.8], [-154.0, 178.6, -23.0]]),
    'fig3b': ([2.0, 0.0], [66.7, -119.1, 45.1],
              [[66.7, -179.4, 112.8], [118.7, -119.1, -60.2], [133.3, -179.2, 45.1]]),
    'fig3c': ([2.5, 0.0], [23.5, -73.0, 70.9],
              [[23.5, -178.6, 155.3], [-0.3, -73.0, 179.4], [108.9, -179.4, 70.9]]),
}


def closed_points(branch):
    """A loop's points with its first point repeated (lifted) at the end."""
    return np.vstack([branch.points, branch.points[:1] + branch.period]) if branch.closed \
        else branch.points


def all_hits(theta_s, branches, joint):
    return [hit for b in branches
            for hit in failure_plane_hits(ARM, X_GOAL, theta_s, closed_points(b), range(3))[joint]]


def two_link_ik(l1, l2, target):
    """Closed-form 2R inverse kinematics: (first link angle, elbow angle) pairs."""
    r2 = float(target @ target)
    cos_elbow = (r2 - l1 * l1 - l2 * l2) / (2 * l1 * l2)
    if abs(cos_elbow) > 1:
        return []
    out = []
    for elbow in {np.arccos(cos_elbow), -np.arccos(cos_elbow)}:
        first = np.arctan2(target[1], target[0]) - np.arctan2(l2 * np.sin(elbow),
                                                               l1 + l2 * np.cos(elbow))
        out.append((first, elbow))
    return out


def exact_failure_plane_ik(theta_s, joint):
    """All configurations of H_joint(θ_s) reaching x_g: the 2R arm left when one joint locks."""
    locked = theta_s[joint]
    rigid = 1 + np.exp(1j * locked)  # two unit links joined at the locked angle
    length, offset = abs(rigid), np.angle(rigid)
    out = []
    if joint == 0:
        elbow = np.array([np.cos(locked), np.sin(locked)])
        out = [(locked, a - locked, b) for a, b in two_link_ik(1.0, 1.0, X_GOAL - elbow)]
    elif joint == 1:
        out = [(a - offset, locked, a + b - (a - offset) - locked)
               for a, b in two_link_ik(length, 1.0, X_GOAL)]
    else:
        out = [(a, b - offset, locked) for a, b in two_link_ik(1.0, length, X_GOAL)]
    return [np.array(theta) for theta in out]


@pytest.fixture(scope='module')
def goal_branches():
    return trace_self_motion_manifolds(ARM, X_GOAL, np.random.default_rng(5))


def test_hits_lie_on_the_goal_and_in_the_failure_plane(goal_branches):
    rng = np.random.default_rng(2)
    for theta_s in rng.uniform(-np.pi, np.pi, (15, 3)):
        for joint in range(3):
            for hit in all_hits(theta_s, goal_branches, joint):
                assert np.linalg.norm(ARM.forward_kinematics(hit.theta) - X_GOAL) < 1e-9
                assert wrap_angle(hit.theta[joint] - theta_s[joint]) == pytest.approx(0, abs=1e-12)


def test_every_exact_failure_plane_solution_is_found(goal_branches):
    """Brute force: every 2R solution in H_i (away from the folded singular set) is a hit."""
    rng = np.random.default_rng(3)
    compared = 0
    for theta_s in rng.uniform(-np.pi, np.pi, (8, 3)):
        for joint in range(3):
            hits = [h.theta for h in all_hits(theta_s, goal_branches, joint)]
            for exact in exact_failure_plane_ik(theta_s, joint):
                assert np.linalg.norm(ARM.forward_kinematics(exact) - X_GOAL) < 1e-9
                if np.linalg.svd(jacobian(ARM, exact))[1][-1] < 0.05:
                    continue  # a branch crossing: either branch may carry the hit
                compared += 1
                assert any(np.linalg.norm(configuration_difference(exact, h, PERIODIC)) < 1e-6
                           for h in hits), (np.degrees(theta_s), joint, np.degrees(exact))
    assert compared >= 30


def test_crossings_skip_the_wrap_jump():
    values = np.array([3.0, 3.1, -3.1, -3.0])  # crosses ±π, not the level 0
    assert not len(crossing_segments(values, np.array([0.0]), periodic=True)[0])
    assert [s.tolist() for s in crossing_segments(values, np.array([3.12]), periodic=True)] \
        == [[0], [1]]
    assert [s.tolist() for s in crossing_segments(np.array([-0.1, 0.1]), np.array([0.0]),
                                                  periodic=False)] == [[0], [0]]


@pytest.mark.parametrize('periodic', [False, True])
def test_crossings_are_the_sign_changes_of_the_difference(periodic):
    """The pairs against the definition written with whole arrays, and `first_only`.

    The kernel looks each segment's levels up among the sorted ones; the cases here hold
    what that lookup could miss: curves lifted over several turns, levels equal to a
    sample or a turn away from one, steps near π, and angles too large or not finite.
    """
    rng = np.random.default_rng(7)
    for case in range(2000):
        values = np.cumsum(rng.normal(0.0, rng.choice([0.01, 0.4, 2.5]), rng.integers(1, 40)))
        values += rng.choice([0.0, 0.0, 7.0, -20.0])
        if periodic and case % 3 == 0:
            values = np.angle(np.exp(1j * values))
        levels = rng.uniform(-3.0, 3.0, rng.integers(0, 6))
        for c in range(len(levels)):
            if rng.random() < 0.3:  # a sample exactly, or that sample some turns away
                levels[c] = rng.choice(values) + 2.0 * np.pi * rng.integers(-3, 4)
        if case % 50 == 0:
            values[rng.integers(len(values))] = rng.choice([np.nan, np.inf, 3e6])
            levels = np.append(levels, rng.choice([np.nan, -np.inf, 5e7]))
        difference = values[None, :] - levels[:, None]
        if periodic:
            difference = wrap_angle(difference)
        with np.errstate(invalid='ignore'):
            sign = difference < 0.0
            change = sign[:, 1:] != sign[:, :-1]
            if periodic:
                change &= np.abs(np.diff(difference, axis=1)) < np.pi
        which, segment = crossing_segments(values, levels, periodic)
        assert np.array_equal(np.stack([which, segment]), np.stack(np.nonzero(change))), case
        first, at = crossing_segments(values, levels, periodic, first_only=True)
        assert np.array_equal(first, np.flatnonzero(change.any(axis=1)))
        assert at.tolist() == [np.flatnonzero(row)[0] for row in change[first]]


@pytest.mark.parametrize('name', sorted(TABLE_I))
def test_table_one_hits(goal_branches, name):
    """For each θ_s of Table I our exact H_i ∩ M_g holds a point within 3 deg of the paper's hit.

    The paper's hits sit 0.01-0.02 m off x_g near the folded θ2 = ±180°, so the exact
    intersections differ from them by up to 3.0° (fig3a, H3: -157.0 against -154.0).
    """
    _, theta_deg, paper_hits = TABLE_I[name]
    theta_s = np.radians(theta_deg)
    for joint, paper in enumerate(np.radians(paper_hits)):
        differences = [np.degrees(np.max(np.abs(configuration_difference(h.theta, paper,
                                                                         PERIODIC))))
                       for h in all_hits(theta_s, goal_branches, joint)]
        assert min(differences) <= 3.0 + 1e-9, (joint, differences)
        assert np.linalg.norm(ARM.forward_kinematics(paper) - X_GOAL) > 0.009  # the paper's offset


@pytest.mark.parametrize('name', sorted(TABLE_I))
def test_table_one_start_is_in_our_theta_S(name):
    """The paper's θ_s, among our Fig. 3-like obstacles, is obstacle-free and passes eq. (6)."""
    scene = load_scene(SCENES / f'{name}.yaml')
    start, theta_deg, _ = TABLE_I[name]
    theta_s = project_to_preimage(ARM, np.array(start), np.radians(theta_deg))
    assert np.degrees(np.max(np.abs(theta_s - np.radians(theta_deg)))) < 0.5
    checker = CollisionChecker(ARM, scene.obstacles)
    assert checker.min_clearance(theta_s[None])[0] > 0
    result = plan(scene)
    gaps = configuration_difference(result.necessary_starts, theta_s, PERIODIC)
    nearest = np.min(np.max(np.abs(gaps), axis=1))
    assert np.degrees(nearest) < 1.5  # Θ_s: one point per continuation step (0.05 rad)
    goal = [mark_obstacle_free(b, checker) for b in result.goal_manifolds]
    for joint in range(3):
        free_hits = [h for b in goal for first, count in b.free_arcs()
                     for h in failure_plane_hits(ARM, X_GOAL, theta_s,
                                                 b.arc_points(first, count), range(3))[joint]]
        assert free_hits, f'H_{joint + 1} misses M_g^F'
    # It is even a failure-tolerant start with a verified surface.
    assert plan(scene, start_configuration=theta_s).feasible


def test_a_loop_free_all_round_comes_as_two_laps(goal_branches):
    from ftplan_ros.core.collision.checker import CollisionChecker
    from ftplan_ros.core.paper.failure_planes import goal_free_arcs
    free = [mark_obstacle_free(b, CollisionChecker(ARM, [])) for b in goal_branches]
    for arc in goal_free_arcs(free, 0.0):
        branch = free[arc.branch]
        assert arc.count == 2 * len(branch) and arc.lap == len(branch)
        points = branch.arc_points(arc.first, arc.count)
        assert np.allclose(points[arc.lap:], points[:arc.lap] + branch.period)

