"""The compiled distance kernels (core/collision/distance_kernels.py) against brute force."""

import numpy as np
import pytest
from shape_references import random_link_shape, random_pose

from ftplan_ros.core.collision import checker as checker_module
from ftplan_ros.core.collision.distance_kernels import (
    BOX,
    CAPSULE,
    CODES,
    CYLINDER,
    SPHERE,
    link_box_clearance,
    link_clearance_over_box,
    planar_joint_points,
    planar_link_clearances,
    segment_distance,
    segment_signed_distance,
)
from ftplan_ros.core.model.geometry import signed_distance


@pytest.mark.parametrize('links', [(1.0, 1.0, 1.0), (0.7, 1.2, 0.5, 0.9)])
def test_link_box_clearance_is_below_every_configuration_of_the_box(links, rng):
    """A lower bound over the box, by dense sampling; tight for tiny boxes."""
    lengths = np.array(links)
    n = len(lengths)
    centres = np.hstack([rng.uniform(-2.5, 2.5, (8, 2)), rng.uniform(-0.3, 0.3, (8, 1))])
    radii = rng.uniform(0.05, 0.4, 8)
    points = np.zeros((n + 1, 2))
    closest = np.inf
    for _ in range(150):
        centre = rng.uniform(-np.pi, np.pi, n)
        half = rng.uniform(0.0, 0.4, n) * rng.choice([1e-4, 1.0])
        planar_joint_points(lengths, centre, points)
        corners = centre + half * rng.uniform(-1.0, 1.0, (3000, n))
        corners[:2] = centre + half * np.array([1.0, -1.0])[:, None]  # two opposite corners
        sampled = planar_link_clearances(lengths, 0.0, centres, radii, corners).min(axis=0)
        for k in range(n):
            bound = link_box_clearance(points, k, lengths[k], centre[:k + 1].sum(), half,
                                       centres, radii)
            assert bound <= sampled[k], (k, centre, half)
            if half.max() < 1e-3:
                closest = min(closest, sampled[k] - bound)
                assert sampled[k] - bound < 1e-3, (k, centre, half)
    assert closest < 1e-4


def test_link_clearance_over_box_is_sound_and_decides_what_either_bound_does(rng):
    """The clearance at the centre is exact; clear is sound by dense sampling and True
    wherever the lever or the fan bound alone says so."""
    lengths = np.array([1.0, 0.8, 0.6])
    centres = np.hstack([rng.uniform(-2.2, 2.2, (6, 2)), rng.uniform(-0.2, 0.2, (6, 1))])
    radii = rng.uniform(0.05, 0.3, 6)
    arms = np.array([[lengths[a:k + 1].sum() for a in range(3)] for k in range(3)])
    points = np.zeros((4, 2))
    outcomes, by_fan = set(), 0
    for _ in range(400):
        centre = rng.uniform(-np.pi, np.pi, 3)
        half = rng.uniform(0.0, 0.15, 3)
        reach = rng.choice([0.0, 0.05])
        planar_joint_points(lengths, centre, points)
        corners = centre + half * rng.uniform(-1.0, 1.0, (1500, 3))
        sampled = planar_link_clearances(lengths, 0.0, centres, radii, corners).min(axis=0)
        at_centre = planar_link_clearances(lengths, 0.0, centres, radii, centre[None])[0]
        for k in range(3):
            motion = float(half @ arms[k]) + 1e-9
            nearest, clear = link_clearance_over_box(points, k, lengths[k],
                                                     centre[:k + 1].sum(), half, motion,
                                                     centres, radii, reach)
            assert nearest == at_centre[k]
            lever = at_centre[k] - reach > motion
            fan = link_box_clearance(points, k, lengths[k], centre[:k + 1].sum(), half,
                                     centres, radii) > reach
            assert clear or not (lever or fan)
            assert not clear or sampled[k] > reach, (k, centre, half)
            outcomes.add(clear)
            by_fan += clear and not lever
    assert outcomes == {True, False} and by_fan > 10


def test_segment_distance_against_brute_force(rng):
    t = np.linspace(0.0, 1.0, 601)
    cases = [rng.uniform(-1.0, 1.0, (4, 3)) for _ in range(40)]
    p = rng.uniform(-1.0, 1.0, 3)
    cases += [np.array([p, p, [1.0, 0, 0], [0, 1.0, 0]]),   # a point and a segment
              np.array([p, p, p + 0.3, p + 0.3]),           # two points
              np.array([[0, 0, 0], [1.0, 0, 0], [0, 0.2, 0], [1.0, 0.2, 0]]),   # parallel
              np.array([[0, 0, 0], [1.0, 0, 0], [2.0, 0.1, 0], [3.0, 0.1, 0]]),  # collinear-ish
              np.array([[0, 0, 0], [1.0, 0, 0], [0.5, -1.0, 0], [0.5, 1.0, 0]])]  # crossing
    for p1, q1, p2, q2 in cases:
        first = p1 + t[:, None] * (q1 - p1)
        second = p2 + t[:, None] * (q2 - p2)
        brute = np.linalg.norm(first[:, None] - second[None], axis=2).min()
        value = segment_distance(p1, q1, p2, q2)
        step = (np.linalg.norm(q1 - p1) + np.linalg.norm(q2 - p2)) / 600
        assert brute - step - 1e-12 <= value <= brute + 1e-12


@pytest.mark.parametrize('kind', ['sphere', 'box', 'cylinder', 'capsule'])
def test_segment_signed_distance_against_brute_force(kind, rng):
    code = CODES[kind]
    assert code in (SPHERE, BOX, CYLINDER, CAPSULE)
    shape = random_link_shape(kind, rng)
    parameters = checker_module.shape_parameters(shape)
    t = np.linspace(0.0, 1.0, 20001)[:, None]
    for _ in range(20):
        frame = random_pose(rng, 0.2)
        start, end = rng.uniform(-0.5, 0.5, (2, 3))
        points = start + t * (end - start)
        brute = float(signed_distance(shape, (points - frame[:3, 3]) @ frame[:3, :3]).min())
        exact = segment_signed_distance(code, parameters, frame, start, end, np.inf)
        assert brute - 1e-4 <= exact <= brute + 1e-9
        enough = brute - 0.05
        early = segment_signed_distance(code, parameters, frame, start, end, enough)
        assert early <= brute + 1e-9
        assert early >= enough or abs(early - exact) < 1e-12
