"""navstack.wall_heading: the direction of a scan's walls, modulo 90 degrees."""

import math

import numpy as np
import pytest

from navstack.wall_heading import nearest_turn, wall_direction

NOISE = (0.01, 0.03)  # the LDS-01's: 1 cm or 3 % of the range


def _room_scan(walls, rng, beams=360, range_max=3.5, clutter=0):
    """Returns of a laser at the origin in a room of ``walls`` [(x0, y0, x1, y1)], with
    the LDS-01's noise, and ``clutter`` returns scattered at random; and their noise."""
    angles = np.radians(np.arange(beams) * 360.0 / beams)
    d = np.column_stack([np.cos(angles), np.sin(angles)])
    ranges = np.full(beams, np.inf)
    for x0, y0, x1, y1 in walls:
        e = np.array([x1 - x0, y1 - y0])
        a = np.array([x0, y0])
        det = d[:, 0] * (-e[1]) - d[:, 1] * (-e[0])
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (a[0] * (-e[1]) - a[1] * (-e[0])) / det
            u = (d[:, 0] * a[1] - d[:, 1] * a[0]) / det
        hit = (np.abs(det) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1)
        ranges = np.where(hit & (t < ranges), t, ranges)
    keep = ranges < range_max
    r = ranges[keep]
    sigma = np.maximum(NOISE[0], NOISE[1] * r)
    r = r + sigma * rng.standard_normal(len(r))
    pts = r[:, None] * d[keep]
    if clutter:
        extra = rng.uniform(-2, 2, size=(clutter, 2))
        pts = np.vstack([pts, extra])
        sigma = np.concatenate([sigma, np.full(clutter, 0.03)])
    return pts, sigma


def _rotated(walls, angle):
    c, s = math.cos(angle), math.sin(angle)
    return [(c * x0 - s * y0, s * x0 + c * y0, c * x1 - s * y1, s * x1 + c * y1) for x0, y0, x1, y1 in walls]


ROOM = [(-2, -1.5, 2.5, -1.5), (2.5, -1.5, 2.5, 2), (2.5, 2, -2, 2), (-2, 2, -2, -1.5), (0.8, 0.5, 1.6, 0.5)]


@pytest.mark.parametrize("degrees", [0.0, 7.3, -31.0, 44.0, 63.0])
def test_a_rooms_walls_give_its_turn_modulo_90_degrees(degrees):
    rng = np.random.default_rng(1)
    errors, sigmas = [], []
    for _ in range(20):
        pts, noise = _room_scan(_rotated(ROOM, math.radians(degrees)), rng)
        found = wall_direction(pts, noise)
        assert found is not None and found.lines >= 4
        errors.append(math.remainder(found.angle - math.radians(degrees), math.pi / 2))
        sigmas.append(found.sigma)
        assert -math.pi / 4 <= found.angle < math.pi / 4
    errors = np.degrees(errors)
    # unbiased, and about as scattered as its own sigma says (within a factor of two)
    assert abs(errors.mean()) < 0.15 and errors.std() < 0.4
    assert 0.5 < errors.std() / np.degrees(np.median(sigmas)) < 2.5


def test_clutter_between_the_walls_does_not_turn_them():
    rng = np.random.default_rng(2)
    pts, noise = _room_scan(_rotated(ROOM, math.radians(12.0)), rng, clutter=60)
    found = wall_direction(pts, noise)
    assert found is not None
    assert abs(math.degrees(math.remainder(found.angle - math.radians(12.0), math.pi / 2))) < 0.5


def test_no_walls_no_direction():
    rng = np.random.default_rng(3)
    scattered = rng.uniform(-2, 2, size=(200, 2))
    assert wall_direction(scattered, np.full(200, 0.03)) is None
    assert wall_direction(np.zeros((5, 2)), np.full(5, 0.01)) is None


def test_nearest_turn_adds_the_multiple_of_90_degrees_nearest_the_reference():
    q = math.pi / 2
    assert nearest_turn(0.1, 0.0) == pytest.approx(0.1)
    assert nearest_turn(0.1, q) == pytest.approx(q + 0.1)
    assert nearest_turn(0.1, -3.0) == pytest.approx(-2 * q + 0.1)
    assert nearest_turn(-0.7, 0.8) == pytest.approx(q - 0.7)
