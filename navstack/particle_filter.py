"""A Monte Carlo localisation particle filter (AMCL's, vectorised with numpy).

* **Motion**: AMCL's differential-drive odometry model (``nav2_amcl::DifferentialMotionModel``):
  an odometry step is rot1, trans, rot2; each particle gets them with Gaussian noise of
  standard deviation ``sqrt(alpha1 rot^2 + alpha2 trans^2)`` (rotations) and
  ``sqrt(alpha3 trans^2 + alpha4 (rot1^2 + rot2^2))`` (translation), rotations folded so
  that driving backwards is no turn.
* **Measurement**: the likelihood field (:mod:`navstack.likelihood_field`).
* **Resampling**: low-variance (systematic), with KLD sampling picking the particle count
  (bins 0.5 m x 0.5 m x 10 degrees, ``kld_err``, ``kld_z``, between ``min_particles`` and
  ``max_particles``) and, when ``alpha_slow``/``alpha_fast`` are set, augmented MCL's
  random particles (probability ``max(0, 1 - w_fast / w_slow)``).
* **Estimate**: particles are binned as for KLD; bins touching each other (26
  neighbours, heading wrapping round) form clusters; the pose is the weighted mean of the
  heaviest cluster (circular mean for the heading), with its covariance.
* **Global localisation**: uniform over free cells (AMCL's), or scan-informed: a coarse
  search scores the scan at poses on a grid over the free space and seeds the particles
  round the best of them. ``best_places`` gives its best distinct poses, each refined by a
  local search (``refine``), to check that a converged estimate is the only place that fits.

All randomness comes from one ``numpy.random.Generator`` (``seed``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.special import ndtri  # the normal quantile (scipy.stats costs ~1.5 s to import)

from .likelihood_field import LaserModelParams, LikelihoodField
from .map_io import OccupancyMap

TWO_PI = 2 * math.pi


def wrap(a):
    """Angles to [-pi, pi)."""
    return (np.asarray(a) + math.pi) % TWO_PI - math.pi


def wrap1(a: float) -> float:
    return (a + math.pi) % TWO_PI - math.pi


@dataclass
class FilterParams:
    min_particles: int = 500
    max_particles: int = 2000
    kld_err: float = 0.05  # pf_err
    kld_z: float = 0.99  # pf_z, a probability (its normal quantile is used)
    # TB3's nav2 config has 0.2 each (noise std 45 % of the motion); 0.05 (22 %) still
    # covers 2 % odometry errors with room and halves the worst error (bench_localisation)
    alpha1: float = 0.05  # rotation noise from rotation
    alpha2: float = 0.05  # rotation noise from translation
    alpha3: float = 0.05  # translation noise from translation
    alpha4: float = 0.05  # translation noise from rotation
    # where the odometry's heading is a gyro's (GyroOdometry: its bias taken off at each
    # stop, its scale within a few per cent), its turns are good to a few per cent and
    # driving straight hardly turns it: the rotation noises are these instead. The wheels'
    # 0.05 spread the headings by 13 degrees per metre, which on open floor, where the
    # lidar sees nothing to correct them, soon leaves the filter lost
    gyro_alpha1: float = 0.005  # rotation noise from rotation (7 %)
    gyro_alpha2: float = 0.001  # rotation noise from translation (1.8 deg per metre)
    alpha_slow: float = 0.0  # recovery_alpha_slow (0: no random particles)
    alpha_fast: float = 0.0  # recovery_alpha_fast
    bin_size: tuple = (0.5, 0.5, math.radians(10))  # KLD and cluster bins (x, y, yaw)
    free_clearance: float = 0.0  # random/uniform particles only where the map is this far from obstacles [m]
    # scan-informed global localisation
    search_spacing: float = 0.2  # candidate positions [m]
    search_headings: int = 48  # candidate headings over a turn
    search_beams: int = 30
    search_sigma: float = 0.15  # likelihood field sigma for the coarse search [m]
    search_keep: int = 400  # best candidates seeded
    search_uniform: float = 0.1  # share of seeded particles drawn uniformly instead


@dataclass
class Estimate:
    pose: np.ndarray  # (x, y, yaw) [m, m, rad]
    cov: np.ndarray  # 3x3
    weight: float  # share of the weight in the chosen cluster
    clusters: int

    @property
    def std_xy(self) -> float:
        return float(math.sqrt(max(self.cov[0, 0] + self.cov[1, 1], 0.0)))

    @property
    def std_yaw(self) -> float:
        return float(math.sqrt(max(self.cov[2, 2], 0.0)))


class ParticleFilter:
    """Particles (N, 3) and their normalised weights over an :class:`OccupancyMap`."""

    field: LikelihoodField  # made by set_map (from the laser model of the one before)

    def __init__(
        self,
        occ_map: OccupancyMap,
        params: FilterParams | None = None,
        laser: LaserModelParams | None = None,
        seed: int | None = None,
    ):
        self.params = params or FilterParams()
        self.rng = np.random.default_rng(seed)
        self._z = float(ndtri(self.params.kld_z))
        self.w_slow = 0.0
        self.w_fast = 0.0
        self.particles = np.zeros((0, 3))
        self.weights = np.zeros(0)
        self.set_map(occ_map, laser)

    # -- map -------------------------------------------------------------------------------
    def set_map(self, occ_map: OccupancyMap, laser: LaserModelParams | None = None) -> None:
        self.map = occ_map
        self.field = LikelihoodField(occ_map, laser or (self.field.params if hasattr(self, "field") else None))
        free = occ_map.free()
        if self.params.free_clearance > 0:
            free &= self.field.clearance >= self.params.free_clearance
        if not free.any():
            free = occ_map.free()
        fx, fy = occ_map.cell_centres(free)
        self._free_xy = np.stack([fx, fy], axis=1)
        if len(self._free_xy) == 0:
            raise ValueError("the map has no free cell")
        # bin index bounds, from the map's corners
        cx, cy = occ_map.to_world(
            np.array([0, occ_map.width, 0, occ_map.width]), np.array([0, 0, occ_map.height, occ_map.height])
        )
        bx, by = self.params.bin_size[:2]
        self._bin_lo = (math.floor(cx.min() / bx) - 1, math.floor(cy.min() / by) - 1)
        self._bin_hi = (math.floor(cx.max() / bx) + 1, math.floor(cy.max() / by) + 1)

    # -- initialisation ------------------------------------------------------------------
    def initialise(self, pose, cov, n: int | None = None) -> None:
        """Particles from a Gaussian round ``pose`` (x, y, yaw) with 3x3 covariance ``cov``."""
        n = n or self.params.max_particles
        cov = np.asarray(cov, float).reshape(3, 3)
        cov = (cov + cov.T) / 2 + np.eye(3) * 1e-12
        p = self.rng.multivariate_normal(np.asarray(pose, float), cov, size=n, method="cholesky")
        p[:, 2] = wrap(p[:, 2])
        self._set(p)

    def uniform_poses(self, n: int) -> np.ndarray:
        idx = self.rng.integers(len(self._free_xy), size=n)
        res = self.map.resolution
        xy = self._free_xy[idx] + self.rng.uniform(-res / 2, res / 2, size=(n, 2))
        return np.column_stack([xy, self.rng.uniform(-math.pi, math.pi, size=n)])

    def global_localisation(self) -> None:
        """AMCL's: max_particles particles uniform over the free cells."""
        self._set(self.uniform_poses(self.params.max_particles))

    def global_search(self, beam_xy: np.ndarray, range_max: float) -> tuple[np.ndarray, np.ndarray]:
        """Coarse scan matching over the whole map: candidate poses (M, 3) on a grid of
        ``search_spacing`` x ``search_headings`` over the free space, and their log-scores."""
        p = self.params
        res = self.map.resolution
        step = max(1, int(round(p.search_spacing / res)))
        free = self.map.free() & (self.field.clearance >= max(self.params.free_clearance, res))
        rows, cols = np.nonzero(free)
        # a lattice with a random phase, so repeated searches look at different points
        off_r, off_c = self.rng.integers(step, size=2)
        keep = ((rows - off_r) % step == 0) & ((cols - off_c) % step == 0)
        x, y = self.map.to_world(cols[keep] + 0.5, rows[keep] + 0.5)
        h = p.search_headings
        yaw0 = self.rng.uniform(0, TWO_PI / h)
        yaws = wrap(yaw0 + np.arange(h) * TWO_PI / h)
        k = len(beam_xy)
        if k > p.search_beams:
            beam_xy = beam_xy[np.linspace(0, k - 1, p.search_beams).round().astype(int)]
        # each heading rotates the beams once; positions then only translate them
        c, s = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
        bx = (c * beam_xy[None, :, 0] - s * beam_xy[None, :, 1]).astype(np.float32)  # (H, K)
        by = (s * beam_xy[None, :, 0] + c * beam_xy[None, :, 1]).astype(np.float32)
        two_s2 = 2 * p.search_sigma**2
        lp = self.field.params
        floor = lp.z_rand / range_max
        scores = np.empty((len(x), h), dtype=np.float32)
        xf, yf = x.astype(np.float32), y.astype(np.float32)
        chunk = max(1, 400_000 // max(1, h * len(beam_xy)))
        for i in range(0, len(x), chunk):
            ex = xf[i : i + chunk, None, None] + bx[None]
            ey = yf[i : i + chunk, None, None] + by[None]
            d = self.field.distance_at(ex, ey)
            pz = lp.z_hit * np.exp(-(d * d) / two_s2) + floor
            scores[i : i + chunk] = np.log(pz).sum(axis=2)
        poses = np.column_stack([np.repeat(x, h), np.repeat(y, h), np.tile(yaws, len(x))])
        return poses, scores.ravel()

    def global_localisation_informed(self, beam_xy: np.ndarray, range_max: float, keep_share: float = 0.0) -> None:
        """Seed max_particles round the best poses of :meth:`global_search` (and a share
        uniformly), so that a kidnapped robot finds itself with one scan's evidence.
        ``keep_share`` of them are instead drawn from the current particles, so that a
        false alarm costs nothing: the next measurement update decides between them."""
        p = self.params
        poses, scores = self.global_search(beam_xy, range_max)
        keep = min(p.search_keep, len(scores))
        best = np.argpartition(-scores, keep - 1)[:keep]
        n = p.max_particles
        n_old = int(round(keep_share * n)) if len(self.particles) else 0
        old = self.particles[self.rng.choice(len(self.particles), size=n_old, p=self.weights)] if n_old else None
        n_uni = int(round(p.search_uniform * n))
        pick = best[self.rng.integers(keep, size=n - n_uni - n_old)]
        jitter = np.column_stack(
            [
                self.rng.normal(0, p.search_spacing / 2, size=(len(pick), 2)),
                self.rng.normal(0, math.pi / p.search_headings, size=len(pick)),
            ]
        )
        seeded = poses[pick] + jitter
        seeded[:, 2] = wrap(seeded[:, 2])
        parts = [seeded, self.uniform_poses(n_uni)] + ([old] if old is not None else [])
        self._set(np.vstack(parts))

    def refine(self, pose, beam_xy: np.ndarray, range_max: float) -> np.ndarray:
        """The pose near ``pose`` (x, y, yaw) where the beams (K, 2, base frame) fit the
        map best under the laser model: a local grid search, 7 x 7 x 7 poses on three
        ever finer steps (6, 3, 1.5 cm and 0.04, 0.02, 0.01 rad), reaching about 30 cm
        and 0.2 rad away. A global localisation's particles sample the pose only as
        densely as they were seeded, and a standstill does not spread them."""
        pose = np.asarray(pose, float)
        g = np.arange(-3, 4)
        for step_xy, step_yaw in ((0.06, 0.04), (0.03, 0.02), (0.015, 0.01)):
            dx, dy, da = np.meshgrid(g * step_xy, g * step_xy, g * step_yaw, indexing="ij")
            cand = pose + np.column_stack([dx.ravel(), dy.ravel(), da.ravel()])
            logw, _ = self.field.log_weights(cand, beam_xy, range_max)
            pose = cand[int(np.argmax(logw))]
        pose[2] = wrap1(pose[2])
        return pose

    def best_places(self, beam_xy: np.ndarray, range_max: float, k: int, near: float, near_yaw: float) -> np.ndarray:
        """Up to ``k`` poses (k, 3) where the beams fit the map best, at least ``near`` [m]
        or ``near_yaw`` [rad] apart: the best of :meth:`global_search`'s candidates, each
        refined (:meth:`refine`)."""
        poses, scores = self.global_search(beam_xy, range_max)
        scores = scores.astype(np.float64)
        picked: list[np.ndarray] = []
        while len(picked) < k and np.isfinite(scores).any():
            q = poses[int(np.argmax(scores))]
            picked.append(q)
            same = (np.hypot(poses[:, 0] - q[0], poses[:, 1] - q[1]) <= near) & (
                np.abs(wrap(poses[:, 2] - q[2])) <= near_yaw
            )
            scores[same] = -np.inf
        return np.array([self.refine(q, beam_xy, range_max) for q in picked]).reshape(-1, 3)

    def _set(self, particles: np.ndarray) -> None:
        self.particles = np.ascontiguousarray(particles, dtype=np.float64)
        self.weights = np.full(len(particles), 1.0 / len(particles))
        self.w_slow = self.w_fast = 0.0

    # -- motion -----------------------------------------------------------------------------
    def predict(self, old, new, gyro: bool = False) -> None:
        """Move the particles by the odometry step from pose ``old`` to ``new`` (odom frame);
        ``gyro``: the odometry's heading is a gyro's (see :class:`FilterParams`)."""
        p = self.params
        alpha1, alpha2 = (p.gyro_alpha1, p.gyro_alpha2) if gyro else (p.alpha1, p.alpha2)
        dx, dy = new[0] - old[0], new[1] - old[1]
        trans = math.hypot(dx, dy)
        rot1 = 0.0 if trans < 0.01 else wrap1(math.atan2(dy, dx) - old[2])
        rot2 = wrap1(wrap1(new[2] - old[2]) - rot1)
        r1n = min(abs(rot1), abs(wrap1(rot1 - math.pi)))
        r2n = min(abs(rot2), abs(wrap1(rot2 - math.pi)))
        sd_r1 = math.sqrt(alpha1 * r1n**2 + alpha2 * trans**2)
        sd_t = math.sqrt(p.alpha3 * trans**2 + p.alpha4 * (r1n**2 + r2n**2))
        sd_r2 = math.sqrt(alpha1 * r2n**2 + alpha2 * trans**2)
        n = len(self.particles)
        noise = self.rng.standard_normal((n, 3))
        r1 = rot1 - sd_r1 * noise[:, 0]
        t = trans - sd_t * noise[:, 1]
        r2 = rot2 - sd_r2 * noise[:, 2]
        th = self.particles[:, 2] + r1
        self.particles[:, 0] += t * np.cos(th)
        self.particles[:, 1] += t * np.sin(th)
        self.particles[:, 2] = wrap(th + r2)

    # -- measurement --------------------------------------------------------------------------
    def update(self, beam_xy: np.ndarray, range_max: float) -> float:
        """Weigh the particles by the beams ending at ``beam_xy`` (K, 2, base frame).
        Returns the weighted mean per-beam likelihood (augmented MCL's w_avg)."""
        logw, match = self.field.log_weights(self.particles, beam_xy, range_max)
        logw = logw + np.log(np.maximum(self.weights, 1e-300))
        logw -= logw.max()
        w = np.exp(logw)
        w_avg = float(np.dot(self.weights, match))
        self.weights = w / w.sum()
        p = self.params
        if p.alpha_slow > 0 and p.alpha_fast > 0:
            if self.w_slow == 0.0:
                self.w_slow = self.w_fast = w_avg
            else:
                self.w_slow += p.alpha_slow * (w_avg - self.w_slow)
                self.w_fast += p.alpha_fast * (w_avg - self.w_fast)
        return w_avg

    @property
    def random_share(self) -> float:
        """Augmented MCL's share of random particles at the next resampling."""
        if self.w_slow <= 0:
            return 0.0
        return max(0.0, 1.0 - self.w_fast / self.w_slow)

    def effective_size(self) -> float:
        return float(1.0 / np.sum(self.weights**2))

    # -- resampling ---------------------------------------------------------------------------
    def _bins(self, particles: np.ndarray) -> np.ndarray:
        """(N, 3) integer bin indices, clipped to the map's bounds."""
        bx, by, ba = self.params.bin_size
        ix = np.clip(np.floor(particles[:, 0] / bx).astype(np.int64), self._bin_lo[0], self._bin_hi[0])
        iy = np.clip(np.floor(particles[:, 1] / by).astype(np.int64), self._bin_lo[1], self._bin_hi[1])
        na = int(math.ceil(TWO_PI / ba))
        ia = np.floor((particles[:, 2] + math.pi) / ba).astype(np.int64) % na
        return np.column_stack([ix - self._bin_lo[0], iy - self._bin_lo[1], ia])

    def _keys(self, bins: np.ndarray) -> np.ndarray:
        nx = self._bin_hi[0] - self._bin_lo[0] + 1
        ny = self._bin_hi[1] - self._bin_lo[1] + 1
        return (bins[:, 2] * ny + bins[:, 1]) * nx + bins[:, 0]

    def kld_limit(self, k: np.ndarray) -> np.ndarray:
        """KLD sampling's particle count for k occupied bins (Fox 2003), clamped."""
        p = self.params
        k = np.asarray(k, float)
        km1 = np.maximum(k - 1, 1)
        b = 2.0 / (9.0 * km1)
        n = np.ceil(km1 / (2 * p.kld_err) * (1 - b + np.sqrt(b) * self._z) ** 3)
        n = np.where(k <= 1, p.min_particles, n)
        return np.clip(n, p.min_particles, p.max_particles).astype(np.int64)

    def resample(self) -> None:
        """Low-variance resampling, KLD-limited, with augmented MCL's random particles."""
        p = self.params
        m = p.max_particles
        cum = np.cumsum(self.weights)
        cum[-1] = 1.0
        u = (self.rng.random() + np.arange(m)) / m
        idx = np.searchsorted(cum, u, side="right")
        idx = np.minimum(idx, len(cum) - 1)
        self.rng.shuffle(idx)  # a random order, so that any prefix is a fair draw
        new = self.particles[idx]
        share = self.random_share
        if share > 0:
            rnd = self.rng.random(m) < share
            if rnd.any():
                new[rnd] = self.uniform_poses(int(rnd.sum()))
            self.w_slow = self.w_fast = 0.0  # as AMCL: no spiral into randomness
        # KLD: the first count c that exceeds the limit for the bins the first c fill
        keys = self._keys(self._bins(new))
        _, first = np.unique(keys, return_index=True)
        is_first = np.zeros(m, dtype=np.int64)
        is_first[first] = 1
        k = np.cumsum(is_first)
        counts = np.arange(1, m + 1)
        over = np.nonzero(counts > self.kld_limit(k))[0]
        n = int(over[0]) + 1 if len(over) else m
        n = max(n, p.min_particles)
        self.particles = np.ascontiguousarray(new[:n])
        self.weights = np.full(n, 1.0 / n)

    # -- estimate --------------------------------------------------------------------------------
    def clusters(self) -> np.ndarray:
        """Cluster label (0..C-1) of every particle: connected occupied bins."""
        bins = self._bins(self.particles)
        shape = (
            self._bin_hi[0] - self._bin_lo[0] + 1,
            self._bin_hi[1] - self._bin_lo[1] + 1,
            int(math.ceil(TWO_PI / self.params.bin_size[2])),
        )
        occ = np.zeros(shape, dtype=bool)
        occ[bins[:, 0], bins[:, 1], bins[:, 2]] = True
        lab, nlab = ndimage.label(occ, structure=np.ones((3, 3, 3), dtype=bool))
        if nlab > 1:  # the heading wraps round: join clusters across the last and first bins
            parent = np.arange(nlab + 1)

            def find(a):
                while parent[a] != a:
                    parent[a] = parent[parent[a]]
                    a = parent[a]
                return a

            first, last = lab[:, :, 0], lab[:, :, -1]
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    shifted = np.roll(np.roll(last, di, axis=0), dj, axis=1)
                    both = (first > 0) & (shifted > 0) & (first != shifted)
                    for a, b in set(zip(first[both].tolist(), shifted[both].tolist())):
                        ra, rb = find(a), find(b)
                        if ra != rb:
                            parent[max(ra, rb)] = min(ra, rb)
            roots = np.array([find(a) for a in range(nlab + 1)])
            _, lab_map = np.unique(roots, return_inverse=True)
            lab = lab_map[lab]
        return lab[bins[:, 0], bins[:, 1], bins[:, 2]] - 1

    def estimate(self) -> Estimate:
        """The weighted mean and covariance of the heaviest cluster."""
        labels = self.clusters()
        w = self.weights
        cw = np.bincount(labels, weights=w)
        best = int(np.argmax(cw))
        sel = labels == best
        return _weighted_pose(self.particles[sel], w[sel], float(cw[best]), len(cw))

    def mean(self) -> Estimate:
        """The weighted mean and covariance of all particles (one cluster)."""
        return _weighted_pose(self.particles, self.weights, 1.0, 1)


def _weighted_pose(p: np.ndarray, w: np.ndarray, share: float, clusters: int) -> Estimate:
    w = w / w.sum()
    mx, my = float(w @ p[:, 0]), float(w @ p[:, 1])
    myaw = math.atan2(float(w @ np.sin(p[:, 2])), float(w @ np.cos(p[:, 2])))
    d = np.column_stack([p[:, 0] - mx, p[:, 1] - my, wrap(p[:, 2] - myaw)])
    cov = (d * w[:, None]).T @ d
    return Estimate(np.array([mx, my, myaw]), cov, share, clusters)
