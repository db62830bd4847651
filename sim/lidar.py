"""The LDS-01 laser scanner of the TurtleBot3: 360 beams in one batch ray cast.

The scan is taken in the ``base_scan`` frame (URDF: on the lidar turret, 0.132 m above the
floor; x forward, beams counter-clockwise from x). Beam ``i`` points at ``i`` degrees.
Each scan is one ``rayTestBatch`` against the pybullet geometry (walls, furniture, objects,
the pallet; never the 2-D occupancy grid), skipping the robot's own body: the robot's
links are in their own collision group (:data:`sim.robot.ROBOT_COLLISION_GROUP`) and the
rays leave that group out. Objects lower than the scan plane (a 122 mm can, the 120 mm
pallet) are below the beams and not seen, as on the real robot.

Ranges follow REP 117: ``+inf`` where nothing is within ``range_max``; a hit closer than
``range_min`` is ``-inf`` (too close to measure). Noise is Gaussian with a standard
deviation of ``max(sigma_min, sigma_rel * range)``, from the world seed's own stream.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from common.quiet_pybullet import pybullet as p

SCAN_FRAME = "base_scan"


def episode_rng(seed: int) -> np.random.Generator:
    """The lidar's noise stream for a world seed (its own, apart from the odometry's)."""
    return np.random.default_rng([int(seed), 11])


@dataclass(frozen=True)
class LidarModel:
    """LDS-01 (ROBOTIS HLS-LFCD2) defaults: 360 beams at 1 degree, 0.12-3.5 m, 5 Hz."""

    beams: int = 360
    range_min: float = 0.12
    range_max: float = 3.5
    rate_hz: float = 5.0
    sigma_min: float = 0.01  # m
    sigma_rel: float = 0.03  # of the range

    @property
    def angle_min(self) -> float:
        return 0.0

    @property
    def angle_increment(self) -> float:
        return 2 * math.pi / self.beams

    @property
    def angle_max(self) -> float:
        return self.angle_increment * (self.beams - 1)

    @property
    def scan_time(self) -> float:
        return 1.0 / self.rate_hz

    def angles(self) -> np.ndarray:
        return self.angle_min + self.angle_increment * np.arange(self.beams)


class Lidar:
    """Casts scans for one pybullet client: ``scan(pos, orn)`` -> ranges (float32, m).

    ``ray_mask`` selects the collision groups a ray may hit (all but the robot's).
    ``noise=False`` gives exact ranges (tests); the noise stream is ``rng``.
    """

    def __init__(self, cid: int, model: LidarModel, rng: np.random.Generator, ray_mask: int = -1, noise: bool = True):
        self.cid = cid
        self.model = model
        self.rng = rng
        self.ray_mask = ray_mask
        self.noise = noise
        a = model.angles()
        self._dirs = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)  # in base_scan
        self.scans = 0
        self.seconds = 0.0  # wall time spent casting (for benchmarks)

    def scan(self, pos, orn) -> np.ndarray:
        """One scan from the base_scan frame's world pose (position, quaternion xyzw)."""
        t0 = time.perf_counter()
        m = self.model
        R = np.asarray(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
        world_dirs = self._dirs @ R.T
        start = np.broadcast_to(np.asarray(pos, dtype=float), world_dirs.shape)
        end = start + m.range_max * world_dirs
        hits = p.rayTestBatch(start.tolist(), end.tolist(), collisionFilterMask=self.ray_mask, physicsClientId=self.cid)
        frac = np.fromiter((h[2] if h[0] >= 0 else np.inf for h in hits), dtype=float, count=m.beams)
        ranges = frac * m.range_max
        if self.noise:
            # one draw per beam, hit or not: beam i always takes the i-th number of its scan
            e = self.rng.standard_normal(m.beams)
            hit = np.isfinite(ranges)
            ranges[hit] += np.maximum(m.sigma_min, m.sigma_rel * ranges[hit]) * e[hit]
            ranges[hit & (ranges > m.range_max)] = np.inf  # pushed out of range by the noise
        ranges[ranges < m.range_min] = -np.inf
        self.scans += 1
        self.seconds += time.perf_counter() - t0
        return ranges.astype(np.float32)
