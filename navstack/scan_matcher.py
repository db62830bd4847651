"""Correlative scan matching (Olson 2009) by branch and bound (Hess et al. 2016), plus ICP.

A scan is a set of points in the robot's base frame. It is matched against a
:class:`LikelihoodMap`: per cell, ``exp(-d^2 / (2 sigma^2))`` with ``d`` the distance to
the nearest occupied cell (``scipy.ndimage.distance_transform_edt``), so a point scores
1 on an obstacle and falls off smoothly. The score of a pose is the mean over the points
(0..1). :class:`CorrelativeMatcher` searches a window of x, y (whole cells) and yaw
(steps small enough that the farthest point moves at most a cell) around a prior pose
and returns the best pose on that lattice, exactly:

* a pyramid of max-pooled maps: level ``h`` holds, per cell, the maximum of the
  ``2^h x 2^h`` cells above and to the right, so a level-h score bounds the score of
  every translation in that block from above;
* level-synchronous branch and bound: the top level's blocks (for every yaw) are scored;
  a greedy descent from the best gives a first achievable score; then every level keeps
  only the blocks whose bound beats the best achievable score so far and splits them in
  four. Everything is numpy batches of gathers.

The covariance comes from the scores around the best pose (Olson's estimate: a weighted
second moment with weights ``exp((score - best) / score_scale)``), plus the lattice's own
quantisation. :func:`icp` refines a pose off the lattice against reference points
(point-to-line, lines fitted to the reference's neighbours).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree


# -- poses and points ----------------------------------------------------------------------------
def transform(pose, points: np.ndarray) -> np.ndarray:
    """(K, 2) points in the frame of ``pose`` (x [m], y [m], yaw [rad]) -> parent frame."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return np.column_stack([pose[0] + c * pts[:, 0] - s * pts[:, 1], pose[1] + s * pts[:, 0] + c * pts[:, 1]])


def scan_points(ranges, angles, range_max: float, range_min: float = 0.0, sensor_offset=(0.0, 0.0, 0.0)) -> np.ndarray:
    """The returns of a scan as (K, 2) points [m] in the base frame (the sensor at
    ``sensor_offset`` (x, y, yaw) in it); beams without a return are dropped."""
    r = np.asarray(ranges, dtype=np.float64)
    a = np.asarray(angles, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(r) & (r >= range_min) & (r < range_max)
    pts = np.column_stack([r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok])])
    return transform(sensor_offset, pts)


# -- the map -------------------------------------------------------------------------------------
class LikelihoodMap:
    """A smoothed likelihood map and its max-pooled pyramid (for branch and bound).

    ``value[row, col]`` is the likelihood (0..1) of cell (col, row), whose lower-left
    corner is ``origin + (col, row) * resolution``. The map is padded by ``pad`` cells
    (value 0) so that a search window never indexes outside it.
    """

    def __init__(
        self, occupied: np.ndarray, resolution: float, origin, sigma: float = 0.05, levels: int = 3, pad: int = 0
    ):
        self.resolution = float(resolution)
        self.sigma = float(sigma)
        occ = np.pad(np.asarray(occupied, dtype=bool), pad)
        self.origin = (float(origin[0]) - pad * self.resolution, float(origin[1]) - pad * self.resolution)
        if occ.any():
            d = ndimage.distance_transform_edt(~occ) * self.resolution
            self.value = np.exp(-0.5 * (d / self.sigma) ** 2).astype(np.float32)
        else:
            self.value = np.zeros(occ.shape, dtype=np.float32)
        # level h: max over the 2^h x 2^h block whose lower-left cell is this one
        self.pyramid = [self.value]
        for h in range(1, levels + 1):
            k = 2**h
            self.pyramid.append(ndimage.maximum_filter(self.value, size=k, origin=-(k // 2), mode="constant", cval=0.0))

    @classmethod
    def from_points(
        cls, points: np.ndarray, resolution: float = 0.05, sigma: float = 0.05, margin: float = 1.0, levels: int = 3
    ) -> LikelihoodMap:
        """From (N, 2) obstacle points [m] (a point marks its cell occupied), covering
        them plus ``margin`` [m]."""
        occ, lo = _raster(points, resolution, margin)
        occ = occ > 0
        return cls(occ, resolution, (lo[0], lo[1]), sigma, levels)

    @classmethod
    def from_density(
        cls,
        points: np.ndarray,
        resolution: float = 0.05,
        sigma: float = 0.05,
        margin: float = 1.0,
        levels: int = 3,
        floor: float = 1e-6,
        weights: np.ndarray | None = None,
    ) -> LikelihoodMap:
        """From (N, 2) obstacle points [m] as a density: each point spread bilinearly over
        its four nearest cells (so a cell keeps where in it the points fell), blurred by a
        Gaussian of ``sigma`` [m], then divided by its local maximum (within 3 sigma; at
        least ``floor`` points per cell) so that walls seen often and seldom both peak at 1
        while keeping their profile. Unlike the binary map, its maximum follows the points'
        mean to well under a cell (for :func:`refine`). ``weights`` (N,) weigh the points
        (e.g. by 1 / range noise^2: far returns are noisier, and near the maximum range
        biased short, since only the ones whose noise made them short come back)."""
        hist, lo = _raster(points, resolution, margin, bilinear=True, weights=weights)
        dens = ndimage.gaussian_filter(hist, sigma / resolution, mode="constant")
        self = cls.__new__(cls)
        self.resolution, self.sigma = float(resolution), float(sigma)
        self.origin = (float(lo[0]), float(lo[1]))
        k = 2 * int(math.ceil(3 * sigma / resolution)) + 1
        peak = np.maximum(ndimage.maximum_filter(dens, size=k, mode="constant"), floor)
        self.value = (dens / peak).astype(np.float32)
        self.pyramid = [self.value] + [
            ndimage.maximum_filter(self.value, size=2**h, origin=-(2**h // 2), mode="constant", cval=0.0)
            for h in range(1, levels + 1)
        ]
        return self

    @property
    def levels(self) -> int:
        return len(self.pyramid) - 1

    def score(self, pose, points: np.ndarray) -> float:
        """The mean likelihood of the points (base frame) at ``pose`` (0 off the map)."""
        return float(self._lookup(0, transform(pose, points)).mean()) if len(points) else 0.0

    def _lookup(self, level: int, xy: np.ndarray) -> np.ndarray:
        m = self.pyramid[level]
        c = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.int64)
        r = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.int64)
        ok = (c >= 0) & (c < m.shape[1]) & (r >= 0) & (r < m.shape[0])
        return np.where(ok, m[np.clip(r, 0, m.shape[0] - 1), np.clip(c, 0, m.shape[1] - 1)], 0.0)


def _raster(points, resolution: float, margin: float, bilinear: bool = False, weights=None):
    """Points counted per cell of a grid covering them plus margin: (counts (H, W), origin)."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    lo = np.floor((pts.min(axis=0) - margin) / resolution) * resolution
    hi = pts.max(axis=0) + margin
    w, h = np.ceil((hi - lo) / resolution).astype(int) + 2
    grid = np.zeros((h, w), dtype=np.float64)
    gx, gy = (pts[:, 0] - lo[0]) / resolution, (pts[:, 1] - lo[1]) / resolution
    if not bilinear:
        np.add.at(grid, (gy.astype(int), gx.astype(int)), 1.0)
        return grid, lo
    # a cell's value stands for its centre: split each point over the 4 nearest centres
    fx, fy = gx - 0.5, gy - 0.5
    c0, r0 = np.floor(fx).astype(int), np.floor(fy).astype(int)
    ax, ay = fx - c0, fy - r0
    pw = 1.0 if weights is None else np.asarray(weights, dtype=np.float64)
    for dc, dr, wgt in ((0, 0, (1 - ax) * (1 - ay)), (1, 0, ax * (1 - ay)), (0, 1, (1 - ax) * ay), (1, 1, ax * ay)):
        np.add.at(grid, (r0 + dr, c0 + dc), wgt * pw)
    return grid, lo


def refine(
    lmap: LikelihoodMap,
    points: np.ndarray,
    pose,
    iterations: int = 20,
    tol: float = 1e-5,
    weights: np.ndarray | None = None,
):
    """Gauss-Newton on the bilinearly interpolated map (as Hector SLAM): the pose off the
    lattice that maximises the points' mean value, from ``pose`` (a step that lowers the
    score is halved). Use a map finer than the lattice (:meth:`LikelihoodMap.from_density`
    at 1-2 cm): bilinear interpolation is flat between two equal cell values, so on a
    coarse map the optimum is only known to a cell. ``weights`` (K,) weigh the points'
    residuals (e.g. by 1 / range noise^2). Returns (pose, score)."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    sw = None if weights is None else np.sqrt(np.asarray(weights, dtype=np.float64))
    x = np.array(pose, dtype=np.float64)
    res = lmap.resolution
    score, r, J = _value_and_jacobian(lmap, pts, x, sw)
    for _ in range(iterations):
        if J is None:
            break
        step = -np.linalg.solve(J.T @ J + 1e-9 * np.eye(3), J.T @ r)
        # a trust region: at most a cell and half a degree per iteration
        scale = min(1.0, res / max(abs(step[0]), abs(step[1]), 1e-12), math.radians(0.5) / max(abs(step[2]), 1e-12))
        step *= scale
        for _ in range(4):
            s2, r2, J2 = _value_and_jacobian(lmap, pts, x + step, sw)
            if s2 >= score:
                break
            step /= 2
        else:
            break
        x, score, r, J = x + step, s2, r2, J2
        if np.abs(step[:2]).max() < tol and abs(step[2]) < tol:
            break
    return (float(x[0]), float(x[1]), float(x[2])), score


def _value_and_jacobian(lmap: LikelihoodMap, pts: np.ndarray, x: np.ndarray, sw=None):
    """The mean bilinear value of the points at pose x, the residuals 1 - value and their
    Jacobian over (x, y, yaw); J None when too few points are on the map."""
    m, res = lmap.value, lmap.resolution
    h, w = m.shape
    c, s = math.cos(x[2]), math.sin(x[2])
    rx, ry = c * pts[:, 0] - s * pts[:, 1], s * pts[:, 0] + c * pts[:, 1]
    gx = (x[0] + rx - lmap.origin[0]) / res - 0.5  # in cell-centre coordinates
    gy = (x[1] + ry - lmap.origin[1]) / res - 0.5
    c0, r0 = np.floor(gx).astype(np.int64), np.floor(gy).astype(np.int64)
    ok = (c0 >= 0) & (c0 < w - 1) & (r0 >= 0) & (r0 < h - 1)
    if ok.sum() < 3:
        return 0.0, None, None
    c0, r0, ax, ay = c0[ok], r0[ok], gx[ok] - c0[ok], gy[ok] - r0[ok]
    v00, v10, v01, v11 = m[r0, c0], m[r0, c0 + 1], m[r0 + 1, c0], m[r0 + 1, c0 + 1]
    val = (v00 * (1 - ax) + v10 * ax) * (1 - ay) + (v01 * (1 - ax) + v11 * ax) * ay
    dvx = ((v10 - v00) * (1 - ay) + (v11 - v01) * ay) / res  # d value / d x [1/m]
    dvy = ((v01 - v00) * (1 - ax) + (v11 - v10) * ax) / res
    J = -np.column_stack([dvx, dvy, -ry[ok] * dvx + rx[ok] * dvy])
    if sw is None:
        return float(val.sum() / len(pts)), 1.0 - val, J
    w = sw[ok]
    return float((w * w * val).sum() / (sw * sw).sum()), w * (1.0 - val), J * w[:, None]


# -- the matcher -----------------------------------------------------------------------------------
@dataclass
class MatchResult:
    pose: tuple  # the best pose (x [m], y [m], yaw [rad])
    score: float  # its mean likelihood, 0..1
    covariance: np.ndarray  # (3, 3) over x [m], y [m], yaw [rad]
    evaluated: int = 0  # candidate blocks scored (the search's cost)


@dataclass
class MatcherParams:
    window_xy: float = 0.3  # search +- this around the prior [m]
    window_yaw: float = math.radians(15)  # and +- this [rad]
    yaw_step: float | None = None  # [rad]; None: the farthest point moves <= 1 cell
    max_points: int = 360  # subsample the scan to at most this many points
    score_scale: float = 0.02  # covariance weights exp((s - best) / score_scale)
    cov_floor: tuple = field(default_factory=lambda: (0.01, 0.01, math.radians(0.5)))  # [m, m, rad] sigmas


class CorrelativeMatcher:
    """Exhaustive (exact on the lattice) x, y, yaw search by branch and bound."""

    def __init__(self, params: MatcherParams | None = None):
        self.params = params or MatcherParams()

    def match(
        self,
        lmap: LikelihoodMap,
        points: np.ndarray,
        prior,
        window_xy: float | None = None,
        window_yaw: float | None = None,
    ) -> MatchResult:
        """The best pose of the base frame in ``lmap``'s frame for the (K, 2) base-frame
        ``points``, within the window around ``prior`` (x [m], y [m], yaw [rad])."""
        p = self.params
        wxy = p.window_xy if window_xy is None else window_xy
        wyaw = p.window_yaw if window_yaw is None else window_yaw
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if len(pts) == 0:
            return MatchResult(tuple(prior), 0.0, np.diag([1e2, 1e2, 1e1]), 0)
        if len(pts) > p.max_points:
            pts = pts[np.linspace(0, len(pts) - 1, p.max_points).astype(int)]
        res = lmap.resolution
        reach = float(np.hypot(pts[:, 0], pts[:, 1]).max())
        dyaw = p.yaw_step or min(math.acos(max(-1.0, 1 - res**2 / (2 * max(reach, res) ** 2))), 0.1)
        n_yaw = int(math.ceil(wyaw / dyaw))
        yaws = prior[2] + dyaw * np.arange(-n_yaw, n_yaw + 1)
        n_xy = int(math.ceil(wxy / res))
        H = lmap.levels
        top = 2**H

        # every yaw's points, in cells relative to the window's lower-left translation
        c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
        ox = prior[0] - n_xy * res - lmap.origin[0]
        oy = prior[1] - n_xy * res - lmap.origin[1]
        px = np.floor((c * pts[:, 0] - s * pts[:, 1] + ox) / res).astype(np.int64)  # (Y, K)
        py = np.floor((s * pts[:, 0] + c * pts[:, 1] + oy) / res).astype(np.int64)
        span = 2 * n_xy + 1  # translations per axis
        evaluated = 0

        def bound(level, yi, tx, ty):
            nonlocal evaluated
            evaluated += len(yi)
            m = lmap.pyramid[level]
            cc = px[yi] + tx[:, None]
            rr = py[yi] + ty[:, None]
            ok = (cc >= 0) & (cc < m.shape[1]) & (rr >= 0) & (rr < m.shape[0])
            v = m[np.clip(rr, 0, m.shape[0] - 1), np.clip(cc, 0, m.shape[1] - 1)]
            return np.where(ok, v, 0.0).mean(axis=1)

        def children(yi, tx, ty, half):
            d = np.array([[0, 0], [half, 0], [0, half], [half, half]])
            cy = np.repeat(yi, 4)
            cx = (tx[:, None] + d[:, 0]).ravel()
            cyy = (ty[:, None] + d[:, 1]).ravel()
            keep = (cx < span) & (cyy < span)
            return cy[keep], cx[keep], cyy[keep]

        g = np.arange(0, span, top)
        yi, tx, ty = (a.ravel() for a in np.meshgrid(np.arange(len(yaws)), g, g, indexing="ij"))
        ub = bound(H, yi, tx, ty)
        # a first achievable score: greedy descent from the best top-level block
        i = int(np.argmax(ub))
        gy, gx, gyy = yi[i : i + 1], tx[i : i + 1], ty[i : i + 1]
        for level in range(H - 1, -1, -1):
            gy, gx, gyy = children(gy, gx, gyy, 2**level)
            b = bound(level, gy, gx, gyy)
            j = int(np.argmax(b))
            gy, gx, gyy = gy[j : j + 1], gx[j : j + 1], gyy[j : j + 1]
        best = float(b[j])
        best_c = (int(gy[0]), int(gx[0]), int(gyy[0]))
        # level-synchronous branch and bound
        for level in range(H - 1, -1, -1):
            keep = ub > best
            yi, tx, ty = children(yi[keep], tx[keep], ty[keep], 2**level)
            if len(yi) == 0:
                break
            ub = bound(level, yi, tx, ty)
        else:
            j = int(np.argmax(ub))
            if ub[j] > best:
                best, best_c = float(ub[j]), (int(yi[j]), int(tx[j]), int(ty[j]))

        byi, bx, by = best_c
        pose = (prior[0] + (bx - n_xy) * res, prior[1] + (by - n_xy) * res, float(yaws[byi]))
        cov = self._covariance(lmap, pts, pose, best, res, dyaw)
        return MatchResult(pose, best, cov, evaluated)

    def _covariance(self, lmap, pts, pose, best, res, dyaw) -> np.ndarray:
        """Olson's estimate from the scores of the 3 x 3 x 3 lattice neighbours (x2 steps)."""
        p = self.params
        d = np.array([-2, 0, 2])
        dx, dy, dt = (a.ravel() for a in np.meshgrid(d * res, d * res, d * dyaw, indexing="ij"))
        scores = np.array([lmap.score((pose[0] + a, pose[1] + b, pose[2] + t), pts) for a, b, t in zip(dx, dy, dt)])
        w = np.exp((scores - best) / p.score_scale)
        w /= w.sum()
        D = np.column_stack([dx, dy, dt])
        mu = w @ D
        cov = (D - mu).T @ (D * w[:, None]) + np.diag(np.square(p.cov_floor))
        return cov


# -- ICP -------------------------------------------------------------------------------------------
class IcpReference:
    """Reference points for point-to-line ICP, with their KD-tree and line normals, made
    once for every alignment against them (a keyframe is the reference of several links).

    Each reference point's line is the principal axis of its ``neighbours`` nearest
    reference points (so noisy or grid-quantised walls give clean normals)."""

    def __init__(self, reference: np.ndarray, neighbours: int = 6, tree: cKDTree | None = None):
        self.points = np.asarray(reference, dtype=np.float64).reshape(-1, 2)
        self.usable = len(self.points) >= neighbours
        self.tree = tree or cKDTree(self.points)
        self.normals = self.centres = np.zeros((0, 2))
        if self.usable:
            _, nb = self.tree.query(self.points, k=neighbours)
            q = self.points[nb] - self.points[nb].mean(axis=1, keepdims=True)
            cxx, cyy, cxy = (q[..., 0] ** 2).sum(1), (q[..., 1] ** 2).sum(1), (q[..., 0] * q[..., 1]).sum(1)
            theta = 0.5 * np.arctan2(2 * cxy, cxx - cyy)  # the principal (line) direction
            self.normals = np.column_stack([-np.sin(theta), np.cos(theta)])
            self.centres = self.points[nb].mean(axis=1)

    def align(self, points: np.ndarray, prior, iterations: int = 15, max_dist: float = 0.2, tol: float = 1e-4):
        """The pose (x [m], y [m], yaw [rad]) that puts the (K, 2) base-frame ``points``
        onto the reference, from ``prior``; pairs farther than ``max_dist`` [m] are
        dropped. Returns (pose, rms residual [m], inlier fraction)."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        if not self.usable or len(pts) < 3:
            return tuple(prior), float("inf"), 0.0
        x = np.array(prior, dtype=np.float64)
        rms, frac = float("inf"), 0.0
        for _ in range(iterations):
            w = transform(x, pts)
            dist, j = self.tree.query(w, distance_upper_bound=max_dist)
            ok = np.isfinite(dist)
            frac = float(ok.mean())
            if ok.sum() < 3:
                break
            n, cen, wp = self.normals[j[ok]], self.centres[j[ok]], w[ok]
            r = ((wp - cen) * n).sum(axis=1)
            # linearised in (dx, dy, dyaw) about the current pose, rotation about its origin
            rel = wp - x[:2]
            J = np.column_stack([n[:, 0], n[:, 1], -rel[:, 1] * n[:, 0] + rel[:, 0] * n[:, 1]])
            # Huber-like weights against the odd wrong pair
            k = 0.05
            wt = np.where(np.abs(r) <= k, 1.0, k / np.abs(r))
            A = J.T @ (J * wt[:, None]) + 1e-9 * np.eye(3)
            step = -np.linalg.solve(A, J.T @ (wt * r))
            x = x + step
            rms = float(np.sqrt(np.mean(r**2)))
            if np.abs(step[:2]).max() < tol and abs(step[2]) < tol:
                break
        x[2] = math.remainder(x[2], 2 * math.pi)
        return (float(x[0]), float(x[1]), float(x[2])), rms, frac


def icp(
    reference: np.ndarray,
    points: np.ndarray,
    prior,
    iterations: int = 15,
    max_dist: float = 0.2,
    neighbours: int = 6,
    tol: float = 1e-4,
    tree: cKDTree | None = None,
):
    """Point-to-line ICP (:class:`IcpReference`) of the (K, 2) base-frame ``points`` onto
    the (N, 2) ``reference`` points, from ``prior``: (pose, rms residual [m], inlier
    fraction)."""
    return IcpReference(reference, neighbours, tree).align(points, prior, iterations, max_dist, tol)
