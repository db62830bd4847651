"""navstack.scan_matcher: correlative matching (branch and bound) against a known offset, ICP."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from navstack.scan_matcher import (
    CorrelativeMatcher,
    IcpReference,
    LikelihoodMap,
    MatcherParams,
    icp,
    scan_points,
    transform,
)
from navstack.synthetic import cast, world_boxes

FIXTURES = Path(__file__).parent / "fixtures"
ANGLES = np.arange(360) * 2 * math.pi / 360
OFFSET = (-0.15, 0.0, 0.0)  # the LDS-01 behind the base's centre


@pytest.fixture(scope="module")
def boxes():
    return world_boxes(FIXTURES / "house_world.yaml")


def points_at(boxes, pose, rng, noise=True):
    """A noisy LDS-01 scan at the base pose, as base-frame points."""
    sx, sy, _ = transform(pose, [OFFSET[:2]])[0].tolist() + [0]
    r = cast(boxes, (sx, sy), ANGLES + pose[2], 3.5)
    if noise:
        fin = np.isfinite(r)
        r = np.where(fin, r + rng.normal(0, 1, r.shape) * np.maximum(0.01, 0.03 * np.where(fin, r, 0)), r)
    return scan_points(r, ANGLES, 3.5, 0.12, OFFSET)


def reference(boxes, poses, rng):
    return np.vstack([transform(p, points_at(boxes, p, rng)) for p in poses])


@pytest.mark.parametrize(
    "true, prior",
    [
        ((2.62, 1.47, 0.21), (2.50, 1.55, 0.30)),  # living room
        ((7.93, 3.12, -1.0), (8.15, 3.00, -0.80)),  # kitchen: 22 cm and 11 degrees off
        ((2.0, 6.0, 2.5), (1.8, 6.2, 2.5 - 0.2)),  # bedroom
    ],
)
def test_correlative_match_finds_a_known_offset(boxes, true, prior):
    rng = np.random.default_rng(1)
    ref = reference(boxes, [(true[0] + 0.3, true[1], 0.0), (true[0], true[1] - 0.3, 1.5)], rng)
    lmap = LikelihoodMap.from_points(ref, 0.05, sigma=0.05)
    pts = points_at(boxes, true, rng)
    res = CorrelativeMatcher(MatcherParams(window_xy=0.3, window_yaw=math.radians(15))).match(lmap, pts, prior)
    assert math.hypot(res.pose[0] - true[0], res.pose[1] - true[1]) <= 0.05
    assert abs(math.remainder(res.pose[2] - true[2], 2 * math.pi)) <= math.radians(1.5)
    assert res.score > 0.5 and res.score > lmap.score(prior, pts) + 0.2
    # the covariance is a covariance, about the lattice's size
    assert np.allclose(res.covariance, res.covariance.T) and np.all(np.linalg.eigvalsh(res.covariance) > 0)
    assert math.sqrt(res.covariance[0, 0]) < 0.1
    # ICP refines off the lattice to about a centimetre
    pose, rms, inliers = icp(ref, pts, res.pose)
    assert math.hypot(pose[0] - true[0], pose[1] - true[1]) < 0.02
    assert abs(math.remainder(pose[2] - true[2], 2 * math.pi)) < math.radians(0.5)
    assert inliers > 0.9 and rms < 0.06


def test_one_icp_reference_aligns_several_scans_as_icp_does(boxes):
    rng = np.random.default_rng(4)
    ref = reference(boxes, [(2.6, 1.5, 0.2)], rng)
    made = IcpReference(ref)
    for true, prior in [((2.7, 1.45, 0.25), (2.65, 1.5, 0.2)), ((2.5, 1.6, 0.1), (2.55, 1.55, 0.15))]:
        pts = points_at(boxes, true, rng)
        assert made.align(pts, prior) == icp(ref, pts, prior)
        assert math.dist(made.align(pts, prior)[0][:2], true[:2]) < 0.02
    # too few reference points for a normal: the prior, no fit
    assert IcpReference(ref[:3]).align(pts, prior) == (prior, float("inf"), 0.0)


def test_branch_and_bound_equals_the_exhaustive_search(boxes):
    rng = np.random.default_rng(2)
    true = (5.0, 2.0, 0.4)
    lmap = LikelihoodMap.from_points(reference(boxes, [true], rng), 0.05, sigma=0.05)
    pts = points_at(boxes, true, rng)[::3]
    prior = (5.08, 1.93, 0.45)
    m = CorrelativeMatcher(MatcherParams(window_xy=0.2, window_yaw=math.radians(6), yaw_step=math.radians(1)))
    res = m.match(lmap, pts, prior)
    best = max(
        lmap.score((prior[0] + i * 0.05, prior[1] + j * 0.05, prior[2] + math.radians(k)), pts)
        for i in range(-4, 5)
        for j in range(-4, 5)
        for k in range(-6, 7)
    )
    assert res.score == pytest.approx(best, abs=1e-6)
    n_all = 9 * 9 * 13
    assert res.evaluated < n_all  # the bound prunes


def test_a_wide_window_recovers_a_large_offset(boxes):
    # a loop-closure-like search: 0.6 m and 25 degrees off
    rng = np.random.default_rng(3)
    true = (7.5, 5.6, math.pi)
    ref = reference(boxes, [true, (7.0, 5.4, 0.0)], rng)
    lmap = LikelihoodMap.from_points(ref, 0.05)
    pts = points_at(boxes, true, rng)
    prior = (7.0, 5.9, math.pi + math.radians(25))
    res = CorrelativeMatcher().match(lmap, pts, prior, window_xy=0.8, window_yaw=math.radians(30))
    assert math.hypot(res.pose[0] - true[0], res.pose[1] - true[1]) <= 0.05
    assert res.score > 0.5


def test_empty_scans_and_maps_do_not_crash():
    lmap = LikelihoodMap(np.zeros((10, 10), bool), 0.05, (0, 0))
    res = CorrelativeMatcher().match(lmap, np.zeros((0, 2)), (0.2, 0.2, 0.0))
    assert res.score == 0.0 and res.pose == (0.2, 0.2, 0.0)
    res = CorrelativeMatcher().match(lmap, np.array([[1.0, 0.0]]), (0.2, 0.2, 0.0))
    assert res.score == 0.0
    assert scan_points([np.inf, np.nan, 0.05, 1.0], [0, 0.1, 0.2, 0.3], 3.5, 0.12).shape == (1, 2)
