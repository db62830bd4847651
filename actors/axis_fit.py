"""The axis of a body of revolution in any pose (standing, lying, leaning), from the
surface points a depth camera sees of it.

A cylinder's surface normals are all perpendicular to its axis, so the axis is the
direction the normals avoid: the eigenvector of the smallest eigenvalue of their scatter
matrix (normals of an end cap, parallel to the axis, are dropped and the direction taken
again). Across the axis, a circle of the known body radius is fitted to the points: its
centre is a point of the axis. A joint least-squares refinement then moves direction and
point together. Used by perception (``actors/perception_round.py`` and
``actors/perception_segments.py``); plain numpy/scipy, no robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

NORMAL_STRIDE = 3  # [px] baseline of the tangents a normal is made from
CAP_COS = 0.6  # a normal this parallel to the axis (|cos|) is an end cap's
MAX_POINTS = 600  # the refinement uses an even subsample


@dataclass
class AxisFit:
    """An axis: ``point`` on it (map frame), unit ``direction`` (pointing up, z >= 0),
    the RMS distance of the side's points to the cylinder [m], and which points are on the
    side (not an end cap)."""

    point: np.ndarray
    direction: np.ndarray
    rms: float
    side: np.ndarray  # (N, 3) the points on the cylinder's side


def surface_normals(grid: np.ndarray, stride: int = NORMAL_STRIDE) -> tuple[np.ndarray, np.ndarray]:
    """(points, unit normals) from points laid out as in the image (NaN off the object):
    the cross product of the tangents ``stride`` pixels along the row and the column.
    Tangents across a depth jump (3x the median step) give no normal."""
    a, b, c = grid[:-stride, :-stride], grid[:-stride, stride:], grid[stride:, :-stride]
    ok = np.isfinite(a).all(-1) & np.isfinite(b).all(-1) & np.isfinite(c).all(-1)
    tu, tv, p = (b - a)[ok], (c - a)[ok], a[ok]
    if len(p) == 0:
        return p, p
    lu, lv = np.linalg.norm(tu, axis=1), np.linalg.norm(tv, axis=1)
    step = float(np.median(np.concatenate([lu, lv])))
    keep = (lu < 3 * step) & (lv < 3 * step) & (lu > 0.2 * step) & (lv > 0.2 * step)
    n = np.cross(tu[keep], tv[keep])
    ln = np.linalg.norm(n, axis=1)
    good = ln > 1e-12
    return p[keep][good], n[good] / ln[good, None]


def _least_direction(normals: np.ndarray) -> np.ndarray:
    w, v = np.linalg.eigh(normals.T @ normals)
    return v[:, 0]


def axis_candidates(points: np.ndarray, normals: np.ndarray) -> list[np.ndarray]:
    """Directions the normals are most nearly perpendicular to, robust to an end cap, most
    supported first. Candidates (the normals' least direction, the vertical, the points'
    longest spread) are each refined on the normals they leave on the side; near-duplicates
    (within 10 degrees) are dropped. Seen end-on, a lying can's flat cap fits the vertical
    as well as its side fits the true axis: both are returned, the shape decides."""
    cands = [_least_direction(normals), np.array([0.0, 0.0, 1.0])]
    if len(points) > 3:
        q = points - points.mean(axis=0)
        cands.append(np.linalg.eigh(q.T @ q)[1][:, -1])
    out: list[tuple[np.ndarray, int]] = []  # (direction, how many normals support it)
    for a in cands:
        for _ in range(3):
            side = np.abs(normals @ a) < CAP_COS
            if side.sum() < 10:
                break
            a = _least_direction(normals[side])
        a = a if a[2] >= 0 else -a
        if all(abs(float(a @ b)) < math.cos(math.radians(10)) for b, _ in out):
            out.append((a, int((np.abs(normals @ a) < 0.3).sum())))
    out.sort(key=lambda t: -t[1])
    return [a for a, _ in out]


def axis_direction(points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """The best supported of :func:`axis_candidates`."""
    return axis_candidates(points, normals)[0]


def _basis(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors perpendicular to ``a`` and to each other."""
    t = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(a, t)
    u /= np.linalg.norm(u)
    return u, np.cross(a, u)


def fit_axis(
    pts: np.ndarray, normals: np.ndarray, radius: float, view_from: np.ndarray, direction: np.ndarray | None = None
) -> AxisFit | None:
    """The axis of a cylinder of ``radius`` through surface points and their normals (as
    :func:`surface_normals` gives them), seen from ``view_from`` (the camera's position:
    the axis is behind the surface), starting from ``direction`` (default: the best
    candidate). None when too few normals."""
    if len(pts) < 20:
        return None
    a = axis_direction(pts, normals) if direction is None else direction
    side = pts[np.abs(normals @ a) < CAP_COS]
    if len(side) < 15:
        return None
    if len(side) > MAX_POINTS:
        side = side[np.linspace(0, len(side) - 1, MAX_POINTS).astype(int)]
    o = side.mean(axis=0)
    # start: the surface's centroid pushed back by the radius, away from the camera
    away = o - view_from
    away -= (away @ a) * a
    away /= np.linalg.norm(away) or 1.0
    return refine_axis(side, radius, o + radius * away, a)


def refine_axis(points: np.ndarray, radius: float, point: np.ndarray, direction: np.ndarray) -> AxisFit:
    """The cylinder of ``radius`` that ``points`` lie on, from a first guess of a point on
    its axis and its direction (Huber-weighted least squares over both)."""
    return _fit_surface(points, point, direction, lambda s: radius)


def refine_profile_axis(points: np.ndarray, radii, point: np.ndarray, direction: np.ndarray, base_low: bool) -> AxisFit:
    """The body of revolution whose radius at ``h`` above its base is ``radii(h)`` (an
    array function) that ``points`` lie on, from a first guess of its axis; its base is
    the end of the points along ``direction`` that is lowest (``base_low``) or highest.
    A tapered body (a cup) fits no cylinder; its whole profile fixes its axis."""

    def radius_along(s):
        lo, hi = np.percentile(s, (0.5, 99.5))
        return radii(np.clip(s - lo if base_low else hi - s, 0.0, None))

    return _fit_surface(points, point, direction, radius_along)


def _fit_surface(points: np.ndarray, point: np.ndarray, direction: np.ndarray, radius_along) -> AxisFit:
    """The axis (direction and point, Huber-weighted least squares) of the body of
    revolution ``points`` lie on, whose radius at a point's position ``s`` along the axis
    is ``radius_along(s)`` (arrays)."""
    if len(points) > MAX_POINTS:
        points = points[np.linspace(0, len(points) - 1, MAX_POINTS).astype(int)]
    u, v = _basis(direction)

    def unit(theta, phi):
        return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])

    def residual(x):
        d = unit(x[0], x[1])
        r = points - (point + x[2] * u + x[3] * v)
        s = r @ d
        return np.linalg.norm(r - np.outer(s, d), axis=1) - radius_along(s)

    theta0 = math.acos(min(1.0, max(-1.0, float(direction[2]))))
    phi0 = math.atan2(direction[1], direction[0])
    res = least_squares(residual, [theta0, phi0, 0.0, 0.0], loss="huber", f_scale=0.002, max_nfev=60)
    d = unit(res.x[0], res.x[1])
    e = residual(res.x)
    return AxisFit(
        point=point + res.x[2] * u + res.x[3] * v,
        direction=d if d[2] >= 0 else -d,
        rms=float(np.sqrt(np.mean(e * e))),
        side=points,
    )
