"""Smoothing the localiser's output: a Kalman filter on the robot's map pose, with the
odometry as its motion and each filter update's estimate as a measurement.

Why: AMCL's estimate jitters from one update to the next (in the simulated house by
0.8 cm at the median and 2 cm at the 90th percentile, a few tenths of a degree), and
map -> odom, hence every map-frame pose, jumps by that much at each update (every 0.25 m
or 0.2 rad of motion). A robot that measures an object from a metre away, drives up to
it and grasps it with 1 cm to spare sees such a jump as the object moving. The odometry's
own error over 0.25 m is a few millimetres, so a filter that trusts it between updates
and blends each estimate in by its relative confidence removes most of the jitter and
follows the real drift: the gain settles near 0.3 with the defaults.

A large innovation (``reset_xy``, ``reset_yaw``: beyond what drift explains, e.g. after a
global relocalisation) is taken at once: the smoother never holds on to a wrong pose.
Axes are filtered independently (x and y in the map frame, yaw), which is enough for the
small, isotropic corrections it is meant for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .amcl import compose, inverse
from .odometry import Pose


@dataclass
class SmootherParams:
    drift_per_m: float = 0.03  # [m/m] odometry position error per metre driven (1 sigma)
    drift_per_rad: float = 0.01  # [m/rad] ... per radian turned
    yaw_per_rad: float = 0.02  # [rad/rad] odometry heading error per radian turned
    yaw_per_m: float = 0.01  # [rad/m] ... per metre driven
    meas_xy: float = 0.02  # [m] the estimate's jitter (1 sigma)
    meas_yaw: float = 0.01  # [rad]
    reset_xy: float = 0.15  # [m] an innovation beyond this is taken at once
    reset_yaw: float = 0.12  # [rad]


class PoseSmoother:
    """The robot's map pose, predicted with the odometry and corrected by each estimate."""

    def __init__(self, params: SmootherParams | None = None) -> None:
        self.p = params or SmootherParams()
        self.pose: Pose | None = None  # (x, y, yaw), map frame, at odometry pose self.odom
        self.odom: Pose | None = None
        self.var_xy = self.var_yaw = 0.0
        self.resets = 0

    def reset(self, pose, odom) -> None:
        """Take ``pose`` (map frame, at odometry pose ``odom``) as it is."""
        self.pose, self.odom = tuple(pose), tuple(odom)
        self.var_xy, self.var_yaw = self.p.meas_xy**2, self.p.meas_yaw**2

    def update(self, estimate, odom) -> Pose:
        """Blend in ``estimate`` (map frame) taken at odometry pose ``odom``; returns the
        smoothed pose there."""
        p = self.p
        estimate, odom = tuple(float(v) for v in estimate), tuple(float(v) for v in odom)
        if self.pose is None:
            self.reset(estimate, odom)
            return estimate  # reset took it as it is (the same tuple)
        # predict: move the smoothed pose by the odometry's step (in the robot's frame)
        step = compose(inverse(self.odom), odom)
        pred = compose(self.pose, step)
        d, a = math.hypot(step[0], step[1]), abs(step[2])
        var_xy = self.var_xy + (p.drift_per_m * d + p.drift_per_rad * a) ** 2
        var_yaw = self.var_yaw + (p.yaw_per_rad * a + p.yaw_per_m * d) ** 2
        # correct
        ex, ey = estimate[0] - pred[0], estimate[1] - pred[1]
        eyaw = math.remainder(estimate[2] - pred[2], 2 * math.pi)
        if math.hypot(ex, ey) > p.reset_xy or abs(eyaw) > p.reset_yaw:
            self.resets += 1
            self.reset(estimate, odom)
            return self.pose
        k_xy = var_xy / (var_xy + p.meas_xy**2)
        k_yaw = var_yaw / (var_yaw + p.meas_yaw**2)
        self.pose = (pred[0] + k_xy * ex, pred[1] + k_xy * ey, math.remainder(pred[2] + k_yaw * eyaw, 2 * math.pi))
        self.odom = odom
        self.var_xy, self.var_yaw = (1 - k_xy) * var_xy, (1 - k_yaw) * var_yaw
        return self.pose

    def map_to_odom(self) -> Pose:
        """map -> odom (x, y, yaw) that puts the robot at the smoothed pose."""
        return compose(self.pose, inverse(self.odom))


class LocalHold:
    """Keeps map -> odom still while the robot manoeuvres near where it last stood still.

    A robot that looks at an object, drives half a metre up to it and grasps it works in
    the map frame, but what it needs is that frame to stay rigid with the odometry for
    that half metre: its object was measured with one correction, its grasp is aimed with
    a later one, and the localiser's estimate wanders by a couple of centimetres over such
    a drive (more than the grasp allows). So once the robot stands still, the correction
    it had is kept (the anchor) until it has moved ``radius`` away from there; the newer
    corrections are then applied at once. Inside the radius the map frame moves with the
    odometry alone, whose error over half a metre is a few millimetres. Turning on the
    spot also ends the hold, after ``max_turn`` [rad] in all: the gyro's scale error (about
    1 % of the angle) is what the localiser corrects there (looking around in steps).
    Only a correction the robot has had is worth keeping: until the localiser knows
    map -> odom (a global localisation converging), it does not hold.
    """

    def __init__(
        self, radius: float = 0.75, max_turn: float = 0.6, still_speed: float = 0.01, still_turn: float = 0.03
    ) -> None:
        self.radius, self.max_turn = radius, max_turn
        self.still_speed, self.still_turn = still_speed, still_turn
        self.anchor: tuple[float, float] | None = None  # odometry (x, y) where the robot last stood still
        self.turned = 0.0  # [rad] turned since then, either way
        self._last: tuple[float, Pose] | None = None  # (t, odometry pose) of the previous message

    @property
    def holding(self) -> bool:
        return self.anchor is not None

    def on_odometry(self, t: float, odom) -> bool:
        """The newest odometry pose at time ``t``; True when a hold has just ended. The
        speeds come from the poses (a driver's twist may be missing)."""
        last, self._last = self._last, (t, tuple(odom))
        if last is None or t <= last[0]:
            return False
        turn = abs(math.remainder(odom[2] - last[1][2], 2 * math.pi))
        if self.anchor is not None:
            self.turned += turn
            if (
                math.hypot(odom[0] - self.anchor[0], odom[1] - self.anchor[1]) > self.radius
                or self.turned > self.max_turn
            ):
                self.anchor = None
                return True
            return False
        dt = t - last[0]
        v = math.hypot(odom[0] - last[1][0], odom[1] - last[1][1]) / dt
        if v < self.still_speed and turn / dt < self.still_turn:
            self.anchor = (float(odom[0]), float(odom[1]))
            self.turned = 0.0
        return False

    def release(self) -> None:
        self.anchor = None
