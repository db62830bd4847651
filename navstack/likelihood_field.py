"""AMCL's likelihood-field laser model, vectorised over particles and beams.

The map is turned once into a distance map (``scipy.ndimage.distance_transform_edt``),
clamped at ``max_dist`` (AMCL's ``laser_likelihood_max_dist``), ``max_dist`` outside the
map. AMCL's holds, per cell, the distance from its centre to the nearest occupied cell's
centre (``surface=False, upsample=1``); that puts the zero level half a cell inside every
wall, which biases the pose by about a centimetre or two wherever walls are seen from one
side only. By default the map is therefore refined (``upsample`` sub-cells per cell) and
the distance is to the occupied cells' edges, from outside and (``signed``) inside:
lookups stay one gather, the map costs 25 times the memory (4 MB for the house).

Inside a wall the signed distance runs to the nearest face, which for the far half of
the wall is its far face; beams whose range noise (3 % of the range for an LDS-01) carries
them past the middle of a 10 cm wall then pull the pose towards the wall, by 4-5 cm at a
metre or two. Where unknown space lies behind the wall (outside the house, inside closed
furniture) ``unknown_is_obstacle`` makes wall and unknown one solid block whose only face
is the one seen from the free side, which removes that bias (4.3 -> 0.1 cm in the
simulated open floor); thin walls between two rooms keep it (AMCL's likelihood field has
the same limit). A beam
ending at distance ``d`` from the nearest obstacle has

    pz = z_hit * exp(-d^2 / (2 sigma_hit^2)) + z_rand / range_max

and beams at or beyond ``range_max`` (no return) or below ``range_min`` are skipped, as
in AMCL. Two ways to combine the beams of a particle are offered:

* ``"product"`` (default): the product ``exp(gamma * sum(log pz))``, the beams' joint
  likelihood (``gamma`` < 1 flattens it; 1 measured best with 60 beams);
* ``"amcl"``: AMCL's ad hoc weight ``1 + sum(pz^3)``: much flatter, it tracks to about
  15 cm in bench_localisation and cannot tell a relocalisation's hypotheses apart.

Both are returned as log-weights.

Everything is numpy on float32 arrays: N particles x K beams cost N cosines and sines,
then (N, K) multiply-adds, one gather and the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .map_io import OccupancyMap


@dataclass
class LaserModelParams:
    z_hit: float = 0.5
    z_rand: float = 0.5
    sigma_hit: float = 0.1  # TB3's nav2 config: 0.2 (RMS error 40 vs 24 mm in bench_localisation)
    max_dist: float = 2.0  # laser_likelihood_max_dist [m]
    combine: str = "product"  # "product" (tempered log-likelihood) or "amcl" (1 + sum pz^3)
    gamma: float = 1.0  # temperature of the product (1: independent beams)
    surface: bool = True  # distances to the occupied cells' edges (centres - res/2), not centres
    signed: bool = True  # and inside obstacles, the distance out to their edge (not 0)
    upsample: int = 5  # distance map at resolution / upsample (1 cm for 5 cm maps)
    interpolate: bool = False  # bilinear distance lookups (4 gathers) instead of the cell's value
    unknown_is_obstacle: bool = True  # unknown cells (outside the walls, inside furniture) are
    #                                    solid: a wall's far face, where unknown space begins, is no
    #                                    surface a beam can end on (see the module docstring)


class LikelihoodField:
    """The distance map of an :class:`OccupancyMap` and the beam model on it."""

    def __init__(self, occ_map: OccupancyMap, params: LaserModelParams | None = None, occupied_threshold: int = 65):
        self.map = occ_map
        self.params = p = params or LaserModelParams()
        occ = occ_map.occupied(occupied_threshold)
        if p.unknown_is_obstacle:
            occ = occ | (occ_map.data < 0)
        res = occ_map.resolution
        #: distance [m] from each map cell's centre to the nearest occupied cell's centre
        self.clearance = ndimage.distance_transform_edt(~occ) * res if occ.any() else np.full(occ.shape, np.inf)
        f = max(1, int(p.upsample))
        if f > 1:
            occ = np.repeat(np.repeat(occ, f, axis=0), f, axis=1)
        fres = res / f
        if occ.any():
            dist = ndimage.distance_transform_edt(~occ) * fres
            if p.surface:
                dist = np.maximum(dist - fres / 2, 0.0)
                if p.signed:  # inside obstacles: the distance out to their surface
                    inside = np.maximum(ndimage.distance_transform_edt(occ) * fres - fres / 2, 0.0)
                    dist = np.where(occ, inside, dist)
        else:
            dist = np.full(occ.shape, np.inf)
        dist = np.minimum(dist, p.max_dist)
        # one cell of border at max_dist: indices clipped into the border read "far"
        padded = np.full((occ.shape[0] + 2, occ.shape[1] + 2), p.max_dist, dtype=np.float32)
        padded[1:-1, 1:-1] = dist
        self.distance = dist.astype(np.float32)  # (rows, cols) at resolution / upsample [m]
        self._flat = padded.ravel()
        self._w2 = occ.shape[1] + 2
        self._hmax = occ.shape[0] + 1
        self._wmax = occ.shape[1] + 1
        ox, oy, oyaw = occ_map.origin
        self._origin = (ox, oy)
        self._rot = (np.cos(oyaw), np.sin(oyaw)) if oyaw else None
        self._inv_res = 1.0 / fres
        self._two_sigma2 = 2.0 * p.sigma_hit**2

    # -- lookups ---------------------------------------------------------------------------
    def distance_at(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Distance [m] from map points to the nearest obstacle (max_dist off the map)."""
        ox, oy = self._origin
        dx, dy = x - ox, y - oy
        if self._rot is not None:
            c, s = self._rot
            dx, dy = c * dx + s * dy, -s * dx + c * dy
        if self.params.interpolate:
            # bilinear between cell centres: shift by half a cell, +1 for the border
            gx = np.clip(dx * self._inv_res + 0.5, 0.0, self._wmax - 1e-3)
            gy = np.clip(dy * self._inv_res + 0.5, 0.0, self._hmax - 1e-3)
            fx, fy = np.floor(gx), np.floor(gy)
            tx, ty = gx - fx, gy - fy
            i = (fy.astype(np.int32)) * self._w2 + fx.astype(np.int32)
            f = self._flat
            top = f.take(i) * (1 - tx) + f.take(i + 1) * tx
            bot = f.take(i + self._w2) * (1 - tx) + f.take(i + self._w2 + 1) * tx
            return top * (1 - ty) + bot * ty
        # +1 for the border; truncation toward zero maps (-1, 0) to the border cell 0
        col = np.clip((dx * self._inv_res + 1.0).astype(np.int32), 0, self._wmax)
        row = np.clip((dy * self._inv_res + 1.0).astype(np.int32), 0, self._hmax)
        return self._flat.take(row * self._w2 + col)

    def endpoints(self, poses: np.ndarray, beam_xy: np.ndarray):
        """Map-frame beam end points (N, K) x 2 for laser poses (N, 3) and end points
        in the laser frame (K, 2)."""
        c = np.cos(poses[:, 2]).astype(np.float32)[:, None]
        s = np.sin(poses[:, 2]).astype(np.float32)[:, None]
        bx, by = beam_xy[None, :, 0], beam_xy[None, :, 1]
        x = poses[:, 0:1].astype(np.float32) + c * bx - s * by
        y = poses[:, 1:2].astype(np.float32) + s * bx + c * by
        return x, y

    def beam_distances(self, poses: np.ndarray, beam_xy: np.ndarray) -> np.ndarray:
        """(N, K) distances from each beam's end point to the nearest obstacle [m]."""
        x, y = self.endpoints(poses, beam_xy)
        return self.distance_at(x, y)

    # -- the model ---------------------------------------------------------------------------
    def beam_likelihoods(self, d: np.ndarray, range_max: float) -> np.ndarray:
        p = self.params
        return p.z_hit * np.exp(-(d * d) / self._two_sigma2) + p.z_rand / range_max

    def log_weights(self, poses: np.ndarray, beam_xy: np.ndarray, range_max: float) -> tuple[np.ndarray, np.ndarray]:
        """Log-weights (N,) of laser poses (N, 3) for the beams ending at ``beam_xy``
        (K, 2, laser frame; only valid returns) under the chosen combination, and the
        mean per-beam likelihood (N,) (a scale-free match measure)."""
        if len(beam_xy) == 0:
            return np.zeros(len(poses)), np.ones(len(poses))
        pz = self.beam_likelihoods(self.beam_distances(poses, beam_xy), range_max)
        logpz = np.log(pz)
        mean_log = logpz.mean(axis=1, dtype=np.float64)
        if self.params.combine == "amcl":
            logw = np.log1p((pz.astype(np.float64) ** 3).sum(axis=1))
        else:
            logw = self.params.gamma * logpz.sum(axis=1, dtype=np.float64)
        return logw, np.exp(mean_log)


def beam_endpoints_laser_frame(ranges: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """(K, 2) end points of beams in the laser frame."""
    r = np.asarray(ranges, np.float32)
    a = np.asarray(angles, np.float32)
    return np.stack([r * np.cos(a), r * np.sin(a)], axis=1)
