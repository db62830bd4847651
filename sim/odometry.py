"""Wheel odometry as ``diff_drive_controller`` computes it, with the errors of a real robot.

On a TurtleBot3 with the manipulator (ROBOTIS' ros2_control bring-up), ``/odom`` comes
from ``diff_drive_controller``: distance and heading from the two wheel encoders alone.
The OpenCR's gyro goes out separately, on the IMU's own topic (:mod:`sim.imu`).
:class:`WheelOdometry` integrates the simulated wheel joint angles the same way, through
an error model drawn once per episode from the world seed:

* the encoders count 4096 ticks a turn (the XM430's), so wheel angles are quantised;
* both wheels' effective radius is off by a few per cent (tyre wear and load, a
  mis-calibrated radius): a common scale error, N(0, ``wheel_scale``);
* the two radii differ a little, N(0, ``wheel_mismatch``): the error that bends a
  straight line when the heading comes from the wheels;
* each wheel's travel picks up a random walk of ``wheel_noise`` m per square-root metre
  (encoder quantisation, small slips).

``heading="imu"`` takes the heading from the gyro instead (``turtlebot3_node``'s
``use_imu: true``, the TurtleBot3 without the manipulator), with the gyro's errors
(``gyro_*``: a residual bias after start-up calibration, its random walk, white noise, a
scale-factor error). ``OdomNoise.exact()`` turns every error off.

With the defaults, raw odometry is off by 2.2 % of the distance on average after 10 m
(an L-shaped drive, 40 seeds; 4.5 % at the 90th percentile, 5.8 % at worst):
tests/test_sim_sensors.py drives it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .robot import WHEEL_RADIUS, WHEEL_SEPARATION

HEADINGS = ("imu", "wheels")


@dataclass(frozen=True)
class OdomNoise:
    """The odometry error model (see the module docstring). Units: m, rad, s."""

    wheel_noise: float = 0.003  # m per sqrt(m) travelled, per wheel (random walk)
    radius_bias: float = 0.0  # both wheels' radius this much too long (0.002 = 0.2 %)
    wheel_scale: float = 0.02  # sigma of both wheels' common scale error, drawn once
    wheel_mismatch: float = 0.001  # sigma of the right wheel's scale relative to the left
    heading: str = "wheels"  # "wheels" (diff_drive_controller) or "imu" (the gyro)
    gyro_bias: float = math.radians(0.05)  # sigma of the initial bias [rad/s]
    gyro_bias_walk: float = math.radians(0.005)  # bias random walk [rad/s / sqrt(s)]
    gyro_noise: float = math.radians(0.01)  # angle random walk [rad / sqrt(s)]
    gyro_scale: float = 0.01  # sigma of the gyro's scale-factor error, drawn once
    encoder_ticks: int = 4096  # encoder ticks per wheel turn (0: exact angles)

    def __post_init__(self):
        if self.heading not in HEADINGS:
            raise ValueError(f"OdomNoise.heading must be one of {HEADINGS}, not {self.heading!r}")

    @classmethod
    def exact(cls, **changes) -> "OdomNoise":
        """No error at all (``changes`` set single terms, e.g. ``radius_bias=0.05``)."""
        return replace(cls(0.0, 0.0, 0.0, 0.0, "wheels", 0.0, 0.0, 0.0, 0.0, 0), **changes)


def episode_rng(seed: int) -> np.random.Generator:
    """The odometry's random stream for a world seed (its own, apart from the lidar's)."""
    return np.random.default_rng([int(seed), 7])


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


class WheelOdometry:
    """Dead reckoning in the odom frame (the start pose), updated every control tick from
    the wheel joint angles [rad] and, for the gyro, the body's true yaw [rad].

    State: ``x, y, yaw`` (pose), ``v, w`` (twist), ``distance`` (m driven, summed |ds|),
    ``turned`` (rad turned, summed |dyaw|), ``t`` (s integrated). The episode's draws are
    ``scale_left``, ``scale_right`` (wheel scale factors) and ``gyro_scale_factor``;
    ``bias`` is the gyro's current bias [rad/s].
    """

    def __init__(self, noise: OdomNoise, rng: np.random.Generator):
        self.noise = n = noise
        self.rng = rng
        e = rng.normal(0.0, 1.0, 4)  # drawn once per episode, in a fixed order
        common, mismatch = n.wheel_scale * e[0], n.wheel_mismatch * e[1]
        self.scale_left = 1.0 + n.radius_bias + common - mismatch / 2
        self.scale_right = 1.0 + n.radius_bias + common + mismatch / 2
        self.gyro_scale_factor = 1.0 + n.gyro_scale * e[2]
        self.bias = n.gyro_bias * e[3]
        self.x = self.y = self.yaw = 0.0
        self.v = self.w = 0.0
        self.distance = self.turned = self.t = 0.0
        self._last: tuple[float, float] | None = None  # the wheel readings of the last step
        self._last_yaw: float | None = None
        self._noisy = n.wheel_noise > 0 or n.gyro_noise > 0 or n.gyro_bias_walk > 0

    def _ticks(self, angle: float) -> float:
        """A wheel angle as the encoder reports it (whole ticks, back in radians)."""
        n = self.noise.encoder_ticks
        if n <= 0:
            return angle
        tick = 2 * math.pi / n
        return math.floor(angle / tick) * tick

    def reset(self, wheel_left: float, wheel_right: float, yaw: float | None = None):
        """Take the current readings as the reference (no motion integrated)."""
        self._last = (self._ticks(wheel_left), self._ticks(wheel_right))
        self._last_yaw = yaw

    def update(self, wheel_left: float, wheel_right: float, dt: float, yaw: float | None = None):
        """Integrate one step. ``yaw`` (the body's true yaw, what the gyro senses) is needed
        for ``heading="imu"``; without it the heading comes from the wheels."""
        if self._last is None:
            self.reset(wheel_left, wheel_right, yaw)
            return
        n = self.noise
        wheel_left, wheel_right = self._ticks(wheel_left), self._ticks(wheel_right)
        dl = (wheel_left - self._last[0]) * WHEEL_RADIUS
        dr = (wheel_right - self._last[1]) * WHEEL_RADIUS
        self._last = (wheel_left, wheel_right)
        # four draws a tick, used or not: left, right encoder; gyro noise, bias walk
        e = self.rng.standard_normal(4).tolist() if self._noisy else (0.0, 0.0, 0.0, 0.0)
        if n.wheel_noise > 0:
            dl += e[0] * n.wheel_noise * math.sqrt(abs(dl))
            dr += e[1] * n.wheel_noise * math.sqrt(abs(dr))
        dl *= self.scale_left
        dr *= self.scale_right
        ds = (dl + dr) / 2
        if n.heading == "imu" and yaw is not None and self._last_yaw is not None:
            true_dth = _wrap(yaw - self._last_yaw)
            sq = math.sqrt(dt)
            dth = true_dth * self.gyro_scale_factor + self.bias * dt + n.gyro_noise * sq * e[2]
            self.bias += n.gyro_bias_walk * sq * e[3]
        else:
            dth = (dr - dl) / WHEEL_SEPARATION
        self._last_yaw = yaw
        mid = self.yaw + dth / 2
        self.x += ds * math.cos(mid)
        self.y += ds * math.sin(mid)
        self.yaw = _wrap(self.yaw + dth)
        self.distance += abs(ds)
        self.turned += abs(dth)
        self.t += dt
        if dt > 0:
            self.v, self.w = ds / dt, dth / dt

    # ---------------- covariances (row-major 6x6: x, y, z, roll, pitch, yaw) ----------------
    def heading_variance(self) -> float:
        """Variance of the yaw error the model predicts by now [rad^2]."""
        n, t = self.noise, self.t
        if n.heading == "wheels":
            per_m = n.wheel_mismatch / WHEEL_SEPARATION
            d = self.distance
            return (per_m * d) ** 2 + 2 * n.wheel_noise**2 * d / WHEEL_SEPARATION**2
        return (
            (n.gyro_bias * t) ** 2
            + n.gyro_bias_walk**2 * t**3 / 3
            + n.gyro_noise**2 * t
            + (n.gyro_scale * self.turned) ** 2
        )

    def pose_covariance(self) -> list[float]:
        """Dead reckoning's growing uncertainty: distance scale and heading error mapped to
        x/y (isotropic), the yaw variance; z, roll and pitch are not estimated (1e6)."""
        n, d = self.noise, self.distance
        var_yaw = 1e-6 + self.heading_variance()
        var_xy = 1e-6 + (n.wheel_scale * d) ** 2 + n.wheel_noise**2 * d / 2 + var_yaw * d * d / 3
        cov = [0.0] * 36
        cov[0] = cov[7] = var_xy
        cov[14] = cov[21] = cov[28] = 1e6
        cov[35] = var_yaw
        return cov

    def twist_covariance(self) -> list[float]:
        """Velocity uncertainty: the scale errors times the speed, plus a floor."""
        n = self.noise
        cov = [0.0] * 36
        cov[0] = 1e-4 + (n.wheel_scale * self.v) ** 2
        cov[7] = 1e-6  # no sideways slip in a differential drive
        cov[14] = cov[21] = cov[28] = 1e6
        cov[35] = 1e-4 + (n.gyro_scale * self.w) ** 2 + n.gyro_bias**2
        return cov
