"""Sensor models: the RGB-D camera's geometry here; wheel odometry in sim/odometry.py and
the LDS-01 lidar in sim/lidar.py (both re-exported)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from common.quiet_pybullet import pybullet as p

from .lidar import Lidar, LidarModel
from .odometry import OdomNoise, WheelOdometry

__all__ = ["CameraModel", "Lidar", "LidarModel", "OdomNoise", "WheelOdometry"]


@dataclass
class CameraModel:
    """Pinhole RGB-D camera on camera_optical_frame (z forward, x right, y down).
    Defaults follow a RealSense D435 colour stream: 69.4 deg horizontal field of view."""

    width: int = 320
    height: int = 240
    hfov_deg: float = 69.4
    near: float = 0.05  # render clip plane
    far: float = 10.0
    min_range: float = 0.10  # depth outside [min_range, max_range] -> NaN (no return)
    max_range: float = 8.0

    @property
    def fx(self):
        return (self.width / 2) / math.tan(math.radians(self.hfov_deg) / 2)

    @property
    def vfov_deg(self):
        return math.degrees(2 * math.atan((self.height / 2) / self.fx))

    def K(self):
        f = self.fx
        return [f, 0.0, (self.width - 1) / 2, 0.0, f, (self.height - 1) / 2, 0.0, 0.0, 1.0]

    def projection(self):
        return p.computeProjectionMatrixFOV(self.vfov_deg, self.width / self.height, self.near, self.far)

    @staticmethod
    def view(pos, orn):
        """View matrix from the optical frame's world pose."""
        R = np.array(p.getMatrixFromQuaternion(orn)).reshape(3, 3)
        fwd, down = R[:, 2], R[:, 1]
        target = np.asarray(pos) + fwd
        return p.computeViewMatrix(list(pos), target.tolist(), (-down).tolist())

    def linearize(self, depth_buffer: np.ndarray) -> np.ndarray:
        """OpenGL depth buffer -> metric z-depth (float32, NaN where no valid return)."""
        n, f = self.near, self.far
        z = (f * n / (f - (f - n) * depth_buffer)).astype(np.float32)
        z[(z < self.min_range) | (z > self.max_range)] = np.nan
        return z
