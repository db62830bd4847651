"""Sensor models: wheel odometry with noise, and the RGB-D camera's geometry."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from ._pybullet import pybullet as p

from .robot import WHEEL_RADIUS, WHEEL_SEPARATION


@dataclass
class OdomNoise:
    """Wheel-encoder noise. Each wheel's travel picks up a random walk of ``wheel_noise``
    metres per square-root metre travelled (independent of the update rate: after 1 m a
    wheel is off by ``wheel_noise`` m, 1 sigma), plus a constant scale error
    ``radius_bias`` (a mis-calibrated wheel radius: 0.002 = 0.2 % too long)."""
    wheel_noise: float = 0.005
    radius_bias: float = 0.0


class WheelOdometry:
    """Dead reckoning from the two wheel joint angles, in the odom frame (the start pose)."""

    def __init__(self, noise: OdomNoise, rng: np.random.Generator):
        self.noise = noise
        self.rng = rng
        self.x = self.y = self.yaw = 0.0
        self.v = self.w = 0.0
        self._last = None

    def update(self, wheel_left: float, wheel_right: float, dt: float):
        if self._last is None:
            self._last = (wheel_left, wheel_right)
            return
        dl = (wheel_left - self._last[0]) * WHEEL_RADIUS
        dr = (wheel_right - self._last[1]) * WHEEL_RADIUS
        self._last = (wheel_left, wheel_right)
        n = self.noise
        if n.wheel_noise > 0:
            e = self.rng.normal(0.0, 1.0, 2)
            dl += e[0] * n.wheel_noise * math.sqrt(abs(dl))
            dr += e[1] * n.wheel_noise * math.sqrt(abs(dr))
        dl *= 1.0 + n.radius_bias
        dr *= 1.0 + n.radius_bias
        ds = (dl + dr) / 2
        dth = (dr - dl) / WHEEL_SEPARATION
        mid = self.yaw + dth / 2
        self.x += ds * math.cos(mid)
        self.y += ds * math.sin(mid)
        self.yaw = math.atan2(math.sin(self.yaw + dth), math.cos(self.yaw + dth))
        if dt > 0:
            self.v, self.w = ds / dt, dth / dt


@dataclass
class CameraModel:
    """Pinhole RGB-D camera on camera_optical_frame (z forward, x right, y down).
    Defaults follow a RealSense D435 colour stream: 69.4 deg horizontal field of view."""
    width: int = 320
    height: int = 240
    hfov_deg: float = 69.4
    near: float = 0.05          # render clip plane
    far: float = 10.0
    min_range: float = 0.10     # depth outside [min_range, max_range] -> NaN (no return)
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
