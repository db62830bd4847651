"""The direction of a scan's walls, modulo 90 degrees: a heading measurement that does not drift.

Indoors, most walls (and the furniture along them) are parallel or perpendicular to each
other. The direction of a scan's walls in the base frame, taken together with the walls'
direction in the map, gives the robot's heading in the map up to a multiple of 90 degrees,
however far it drove: the SLAM uses it to keep the heading from drifting between loop
closures (:attr:`navstack.slam.SlamParams.wall_heading`).

:func:`wall_direction`:

1. the rotation under which the returns' two axis projections are sharpest (a histogram
   of 4 cm bins per axis, every degree of 90), for a start;
2. lines along either axis: peaks of the histogram of each return's distance across that
   axis (at least 10 cm apart), a line being the returns within 2.5 sigma of their range
   noise of a peak, at least ``min_points`` of them spread over ``min_length`` along it,
   8 or more a metre (a wall 3 m off at 70 degrees to the beams has 6), and no wider across
   than their noise (a mean squared distance of 1.4 sigma^2: 0.9 for a wall's returns cut
   at 2.5 sigma, 2.1 for clutter spread evenly over the band);
3. all lines share one direction (those across it turned by 90 degrees): the normal that
   minimises the sum of their weighted squared distances from their lines, the smallest
   eigenvector of their summed scatter matrices (each return weighted by 1 / its range
   noise^2). The spread of the eigenvalues is the direction's information.

Steps 2 and 3 are repeated from the new direction. Points are (x [m], y [m]); angles [rad].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

QUARTER = math.pi / 2


@dataclass(frozen=True)
class WallDirection:
    angle: float  # the walls' direction in the points' frame, modulo 90 degrees, in [-45, 45) [rad]
    sigma: float  # its standard deviation by the lines' scatter [rad]
    lines: int  # lines it was fitted to


def wall_direction(
    points: np.ndarray,
    noise: np.ndarray,
    min_points: int = 10,
    min_length: float = 0.4,
    iterations: int = 4,
) -> WallDirection | None:
    """The direction of the walls among ``points`` (K, 2), each with its range noise
    ``noise`` (K,) [m]; None when no line of ``min_points`` returns over ``min_length`` [m]
    is found."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    sigma = np.asarray(noise, dtype=np.float64).reshape(-1)
    if len(pts) < 2 * min_points:
        return None
    w = 1.0 / sigma**2
    angle = _sharpest_rotation(pts, w)
    for _ in range(iterations):
        scatter, lines = _line_scatter(pts, w, sigma, angle, min_points, min_length)
        if lines == 0:
            return None
        values, vectors = np.linalg.eigh(scatter)
        normal = vectors[:, 0]
        angle = math.remainder(math.atan2(normal[1], normal[0]) - QUARTER, QUARTER)
    spread = max(float(values[1] - values[0]), 1e-12)
    return WallDirection(_wrap_quarter(angle), 1.0 / math.sqrt(spread), lines)


def nearest_turn(angle: float, reference: float) -> float:
    """``angle`` plus the multiple of 90 degrees that brings it nearest to ``reference``."""
    return reference + math.remainder(angle - reference, QUARTER)


def _wrap_quarter(angle: float) -> float:
    return (angle + QUARTER / 2) % QUARTER - QUARTER / 2


def _sharpest_rotation(pts: np.ndarray, w: np.ndarray, bin_size: float = 0.04) -> float:
    """The rotation in [-45, 45) degrees, by the degree, under which the weighted histograms
    of the points' two coordinates are most concentrated (sum of squared bin masses)."""
    best, best_angle = -1.0, 0.0
    for deg in range(-45, 45):
        a = math.radians(deg)
        c, s = math.cos(a), math.sin(a)
        score = 0.0
        for v in (c * pts[:, 0] + s * pts[:, 1], -s * pts[:, 0] + c * pts[:, 1]):
            h = np.bincount(((v - v.min()) / bin_size).astype(np.int64), weights=w)
            score += float((h * h).sum())
        if score > best:
            best, best_angle = score, a
    return best_angle


def _line_scatter(pts, w, sigma, angle, min_points, min_length, bin_size=0.02, max_spread=1.4, min_density=8.0):
    """The summed weighted scatter matrices of the lines along and across ``angle``, those
    across turned by 90 degrees so that all share one normal; and how many lines."""
    c, s = math.cos(angle), math.sin(angle)
    u = c * pts[:, 0] + s * pts[:, 1]
    v = -s * pts[:, 0] + c * pts[:, 1]
    total = np.zeros((2, 2))
    lines = 0
    for across_axis, (along, across) in enumerate(((u, v), (v, u))):
        centres = _histogram_peaks(across, w, bin_size)
        if len(centres) == 0:
            continue
        dist = np.abs(across[:, None] - centres[None, :])
        nearest = dist.argmin(axis=1)
        close = dist[np.arange(len(pts)), nearest] < np.maximum(2.5 * sigma, 0.03)
        for q in range(len(centres)):
            member = close & (nearest == q)
            count, length = int(member.sum()), float(np.ptp(along[member])) if member.any() else 0.0
            if count < min_points or length < min_length or count < min_density * length:
                continue  # too short, or too sparse for a wall the beams swept
            p, wq = pts[member], w[member]
            d = p - (wq[:, None] * p).sum(axis=0) / wq.sum()
            m = (wq[:, None, None] * d[:, :, None] * d[:, None, :]).sum(axis=0)
            normal = np.array([c, s]) if across_axis else np.array([-s, c])
            if normal @ m @ normal > max_spread * member.sum():
                continue  # wider than its returns' noise: a band of clutter, not a wall
            if across_axis:  # a line across the direction: turned by 90 degrees
                m = np.array([[m[1, 1], -m[0, 1]], [-m[0, 1], m[0, 0]]])
            total += m
            lines += 1
    return total, lines


def _histogram_peaks(values: np.ndarray, w: np.ndarray, bin_size: float, apart: float = 0.1) -> np.ndarray:
    """The local maxima of the weighted histogram of ``values``, smoothed by 1.5 bins, each
    the highest within ``apart`` [m] (two walls that near are one wall's noise)."""
    lo = float(values.min()) - 0.1
    bins = ((values - lo) / bin_size).astype(np.int64)
    h = gaussian_filter1d(np.bincount(bins, weights=w, minlength=int(bins.max()) + 3), 1.5)
    peaks = np.nonzero((h[1:-1] > h[:-2]) & (h[1:-1] >= h[2:]))[0] + 1
    kept: list[int] = []
    for i in peaks[np.argsort(-h[peaks])]:
        if all(abs(int(i) - j) * bin_size >= apart for j in kept):
            kept.append(int(i))
    return lo + (np.sort(np.array(kept, dtype=np.int64)) + 0.5) * bin_size
