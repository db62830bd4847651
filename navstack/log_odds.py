"""An occupancy grid updated in log-odds from 2-D laser scans, growing as the robot explores.

Each cell holds ``l = log(p / (1 - p))`` (0: unknown, p = 0.5). A scan updates every cell
at most once (as Cartographer does, so that the many beams crossing the cells near the
sensor do not count many times):

* the cell of each return (a beam ending in ``[range_min, range_max)``) gets ``l_occ``;
* the cells a beam crosses before its end get ``l_free``; a return takes priority over a
  crossing in the same scan;
* a beam without a return (``+inf``, ``>= range_max``) clears up to ``clear_range``
  (default: ``range_max``), more weakly (``l_miss``: a laser drops returns on dark or
  shiny surfaces too, and 2 % drop-outs would otherwise clear cells behind the walls),
  and marks no hit; NaN beams and returns below ``range_min`` are ignored.

Values are clamped to ``[l_min, l_max]`` so that a cell stays changeable. The ray trace
is vectorised: every beam is sampled every ``trace_step`` cells (half a cell by default)
and the samples' cell indices are scattered into a window around the sensor, so a
360-beam LDS-01 scan costs about a millisecond.

:meth:`LogOddsGrid.to_map` gives map_server's trinary :class:`~navstack.map_io.OccupancyMap`:
occupied (100) where p >= ``occupied_thresh`` (0.65), free (0) where p <= ``free_thresh``
(0.25), else unknown (-1).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .map_io import OccupancyMap


def logit(p: float) -> float:
    return math.log(p / (1.0 - p))


@dataclass
class LogOddsParams:
    resolution: float = 0.05  # [m / cell]
    l_occ: float = 0.85  # added to a return's cell (p 0.7)
    l_free: float = -0.4  # added to a crossed cell (p 0.4)
    l_miss: float = -0.1  # added to a cell crossed by a beam without a return: a
    #                                   drop-out (dark or shiny surface) is no proof of free space
    l_min: float = -2.0  # clamp (p 0.12)
    l_max: float = 3.5  # clamp (p 0.97)
    trace_step: float = 0.5  # ray sampling step [cells]
    free_margin: float = 0.0  # stop clearing this far before a return [m]
    far_range: float = math.inf  # returns farther than this [m] add only far_occ: a
    far_occ: float = 0.4  # far return is noisy, and a stray one behind a wall
    #                                   stays (no later beam clears it); below the occupied
    #                                   threshold, it takes two to mark a cell
    grow_margin: float = 2.0  # grow the grid by at least this much at a time [m]
    occupied_thresh: float = 0.65  # to_map(): occupied at p >= this
    free_thresh: float = 0.25  # to_map(): free at p <= this


class LogOddsGrid:
    """A growing log-odds occupancy grid in the map frame (axis-aligned, no rotation).

    ``logodds[row, col]`` (float32) is cell (col, row), whose lower-left corner is at
    ``origin + (col, row) * resolution``; row 0 is the lowest y, as in nav_msgs.
    """

    def __init__(self, params: LogOddsParams | None = None, origin=(0.0, 0.0), shape=(0, 0)):
        self.params = p = params or LogOddsParams()
        self.resolution = float(p.resolution)
        self.origin = (float(origin[0]), float(origin[1]))  # corner of cell (0, 0) [m]
        self.logodds = np.zeros(shape, dtype=np.float32)

    # -- geometry ------------------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int]:
        return self.logodds.shape

    def extent(self) -> tuple[float, float, float, float]:
        """(x0, y0, x1, y1) [m] covered by the grid."""
        h, w = self.shape
        x0, y0 = self.origin
        return x0, y0, x0 + w * self.resolution, y0 + h * self.resolution

    def cell_of(self, x, y):
        """Integer (col, row) of map points [m] (may lie outside the grid)."""
        res = self.resolution
        return (
            np.floor((np.asarray(x) - self.origin[0]) / res).astype(np.int64),
            np.floor((np.asarray(y) - self.origin[1]) / res).astype(np.int64),
        )

    def ensure(self, x0: float, y0: float, x1: float, y1: float) -> None:
        """Grow the grid (keeping its cells' positions) to cover [x0, x1] x [y0, y1] [m]."""
        res, m = self.resolution, self.params.grow_margin
        h, w = self.shape
        if h and w:
            gx0, gy0, gx1, gy1 = self.extent()
            if x0 >= gx0 and y0 >= gy0 and x1 <= gx1 and y1 <= gy1:
                return
            # grow by whole cells, with a margin, so that growing is rare (amortised)
            add_l = int(math.ceil((gx0 - x0) / res + m / res)) if x0 < gx0 else 0
            add_b = int(math.ceil((gy0 - y0) / res + m / res)) if y0 < gy0 else 0
            add_r = int(math.ceil((x1 - gx1) / res + m / res)) if x1 > gx1 else 0
            add_t = int(math.ceil((y1 - gy1) / res + m / res)) if y1 > gy1 else 0
            grown = np.zeros((h + add_b + add_t, w + add_l + add_r), dtype=np.float32)
            grown[add_b : add_b + h, add_l : add_l + w] = self.logodds
            self.logodds = grown
            self.origin = (gx0 - add_l * res, gy0 - add_b * res)
        else:
            # first scan: snap the origin to the cell lattice through (0, 0)
            ox = math.floor((x0 - m) / res) * res
            oy = math.floor((y0 - m) / res) * res
            w = int(math.ceil((x1 + m - ox) / res))
            h = int(math.ceil((y1 + m - oy) / res))
            self.logodds = np.zeros((h, w), dtype=np.float32)
            self.origin = (ox, oy)

    # -- the update ----------------------------------------------------------------------
    def integrate(
        self, sensor_pose, ranges, angles, range_max: float, range_min: float = 0.0, clear_range: float | None = None
    ) -> None:
        """Add one scan taken from ``sensor_pose`` (x [m], y [m], yaw [rad], map frame).

        Args:
            sensor_pose: the laser's pose in the map frame (x [m], y [m], yaw [rad])
            ranges: (K,) beam ranges [m]; inf or >= range_max: no return; NaN: ignored
            angles: (K,) beam angles in the sensor frame [rad]
            range_max: the sensor's maximum range [m]
            range_min: returns below this are ignored [m]
            clear_range: how far a beam without a return clears [m]; None: range_max
        """
        p = self.params
        r = np.asarray(ranges, dtype=np.float64)
        a = np.asarray(angles, dtype=np.float64)
        sx, sy, syaw = (float(v) for v in sensor_pose)
        clear = float(range_max if clear_range is None else clear_range)
        with np.errstate(invalid="ignore"):
            hit = np.isfinite(r) & (r >= range_min) & (r < range_max)
            miss = ~np.isnan(r) & ~hit & (r >= range_min)  # no return: clear only
        length = np.where(hit, r - p.free_margin, np.where(miss, clear, 0.0))
        keep = length > 0
        if not keep.any():
            return
        length, a, hit, r = length[keep], a[keep], hit[keep], r[keep]
        c, s = np.cos(a + syaw), np.sin(a + syaw)
        reach = max(float(length.max()), float(r[hit].max()) if hit.any() else 0.0) + self.resolution
        self.ensure(sx - reach, sy - reach, sx + reach, sy + reach)

        res = self.resolution
        # a window around the sensor, in cells: all the scan's cells fall in it
        c0, r0 = self.cell_of(sx - reach, sy - reach)
        c1, r1 = self.cell_of(sx + reach, sy + reach)
        c0, r0 = max(int(c0), 0), max(int(r0), 0)
        h, w = self.shape
        c1, r1 = min(int(c1) + 1, w), min(int(r1) + 1, h)
        ww = c1 - c0
        delta = np.zeros((r1 - r0) * ww, dtype=np.float32)

        # free: samples every trace_step cells along each beam, short of its end (only the
        # samples that exist: np.repeat, not a (beams x max samples) mask)
        step = p.trace_step * res
        count = np.ceil(length / step - 0.5).astype(np.int64)  # samples at (i + 0.5) step
        total = int(count.sum())
        kk = np.repeat(np.arange(len(count)), count)
        start = np.cumsum(count) - count
        tt = (np.arange(total) - np.repeat(start, count) + 0.5) * step
        fc = ((sx - self.origin[0] + tt * c[kk]) / res).astype(np.int64)  # >= 0: no floor needed
        fr = ((sy - self.origin[1] + tt * s[kk]) / res).astype(np.int64)
        idx = (fr - r0) * ww + (fc - c0)
        if p.l_miss != p.l_free and not hit.all():
            # the beams without a return first, so that a crossing by a returned beam wins
            from_miss = ~hit[kk]
            delta[idx[from_miss]] = p.l_miss
            delta[idx[~from_miss]] = p.l_free
        else:
            delta[idx] = p.l_free
        # returns: assigned after the free cells, so a return wins over a crossing
        if hit.any():
            hc, hr = self.cell_of(sx + r[hit] * c[hit], sy + r[hit] * s[hit])
            delta[(hr - r0) * ww + (hc - c0)] = np.where(r[hit] > p.far_range, p.far_occ, p.l_occ)
        win = self.logodds[r0:r1, c0:c1]
        np.clip(win + delta.reshape(win.shape), p.l_min, p.l_max, out=win)

    # -- reading -------------------------------------------------------------------------
    def probability(self) -> np.ndarray:
        """The occupancy probability of each cell (0.5 where unknown)."""
        return 1.0 / (1.0 + np.exp(-self.logodds))

    def occupied(self) -> np.ndarray:
        return self.logodds >= logit(self.params.occupied_thresh)

    def free(self) -> np.ndarray:
        return self.logodds <= logit(self.params.free_thresh)

    def to_map(self) -> OccupancyMap:
        """map_server's trinary map: 100 occupied, 0 free, -1 unknown (same cells)."""
        if self.logodds.size == 0:
            raise ValueError("the grid is empty: integrate a scan first")
        data = np.full(self.shape, -1, dtype=np.int8)
        data[self.free()] = 0
        data[self.occupied()] = 100
        return OccupancyMap(data, self.resolution, (self.origin[0], self.origin[1], 0.0))

    def clear(self) -> None:
        """Forget every observation (keep the extent)."""
        self.logodds[:] = 0.0
