"""The OpenCR board's IMU as ``imu_broadcaster`` publishes it on a TurtleBot3 with the
manipulator (``/imu_broadcaster/imu``, sensor_msgs/Imu, frame ``imu_link``).

The board fuses its gyro and accelerometer into an orientation; on a flat floor that is
roll = pitch = 0 and a heading that drifts with the gyro. :class:`Gyro` integrates the
body's true rotation through the gyro's error model (:class:`sim.odometry.OdomNoise`'s
``gyro_*`` terms: a residual bias after start-up calibration, its random walk, white
noise and a scale-factor error, all drawn from the world seed), so the heading it reports
drifts as a real one does. The wheel odometry (``/odom``) does not use it:
``diff_drive_controller`` computes the heading from the wheels alone.
"""

from __future__ import annotations

import math

import numpy as np

from .odometry import OdomNoise

IMU_FRAME = "imu_link"
GRAVITY = 9.80665  # [m/s^2]


def episode_rng(seed: int) -> np.random.Generator:
    """The gyro's random stream for a world seed (apart from the odometry's and lidar's)."""
    return np.random.default_rng([int(seed), 11])


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


class Gyro:
    """The IMU's yaw rate and heading [rad/s, rad], updated every control tick from the
    body's true yaw; ``accel`` is the forward acceleration [m/s^2] from the base's speed."""

    def __init__(self, noise: OdomNoise, rng: np.random.Generator):
        self.noise = n = noise
        self.rng = rng
        e = rng.normal(0.0, 1.0, 2)  # drawn once per episode
        self.scale = 1.0 + n.gyro_scale * e[0]
        self.bias = n.gyro_bias * e[1]
        self.yaw = 0.0  # the board's heading (its own start is 0)
        self.rate = 0.0
        self.accel = 0.0
        self._true_yaw: float | None = None  # None: the next update() takes it as the reference
        self._speed = 0.0

    def reset(self) -> None:
        """Take the body's next yaw as the reference (the robot was put somewhere by hand:
        a teleport is no rotation the gyro feels)."""
        self._true_yaw = None

    def update(self, true_yaw: float, speed: float, dt: float) -> None:
        """One control tick: ``true_yaw`` [rad] the body's yaw, ``speed`` [m/s] forward."""
        if self._true_yaw is None or dt <= 0:
            self._true_yaw, self._speed = true_yaw, speed
            return
        n, sq = self.noise, math.sqrt(dt)
        e = self.rng.standard_normal(2)
        dth = _wrap(true_yaw - self._true_yaw) * self.scale + self.bias * dt + n.gyro_noise * sq * float(e[0])
        self.bias += n.gyro_bias_walk * sq * float(e[1])
        self.yaw = _wrap(self.yaw + dth)
        self.rate = dth / dt
        self.accel = (speed - self._speed) / dt
        self._true_yaw, self._speed = true_yaw, speed

    def rate_variance(self) -> float:
        """[(rad/s)^2] of one rate reading: the bias and the white noise."""
        n = self.noise
        return n.gyro_bias**2 + n.gyro_noise**2
