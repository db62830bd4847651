"""Wheel odometry with its heading from the IMU, as the navstack's nodes keep it.

A TurtleBot3 with the manipulator publishes ``/odom`` from ``diff_drive_controller``:
distance and heading from the wheels alone, so a wheel radius a few per cent off turns
every rotation by as much. The OpenCR's gyro (``/imu_broadcaster/imu``) measures the
rotation itself. :class:`GyroOdometry` keeps a second odometry frame ("fused") that
advances by the wheels' distance along the gyro's heading change, as robot_localization
would fuse the two; the localiser and the mapper run on it.

What goes on ``/tf`` must still be map -> odom for the robot's own odom frame (the wheels'),
since odom -> base_footprint is the controller's: :meth:`GyroOdometry.map_to_wheel_odom`
turns a map -> fused transform into that, at the newest odometry pose. Without IMU
messages (or with ones too old) the heading change is the wheels', and the fused frame
is the wheel frame.
"""

from __future__ import annotations

import bisect
import math
from collections import deque

from .amcl import compose, inverse
from .odometry import Pose

#: [s] an IMU reading this much older than the odometry's stamp is too old to use
IMU_STALE = 0.1
#: [s] a stop at least this long measures the gyro's bias (what it turns while the wheels
#: stand still); a shorter one says too little against the gyro's white noise
BIAS_MIN_STILL = 1.0


def _wrap(a: float) -> float:
    return math.remainder(a, 2 * math.pi)


class GyroOdometry:
    """The fused odometry pose (x, y, yaw) [m, rad] from /odom poses and IMU headings.

    The fused heading is the IMU's at its newest reading plus what the wheels turned since
    (the IMU's message for a stamp may come after the odometry's), plus a constant offset
    that keeps the heading continuous whenever the IMU (re)appears. While the wheels
    stand still the heading does not change: the gyro's bias would turn a robot that
    waits for a look or a grasp. What the gyro turns during such a stop is its bias
    (``bias``, rad/s): a MEMS gyro's bias wanders after its start-up calibration, and each
    stop of ``BIAS_MIN_STILL`` or more measures it afresh, to be taken off the headings
    until the next."""

    def __init__(self, maxlen: int = 400) -> None:
        self._imu: deque = deque(maxlen=maxlen)  # (t, unwrapped yaw), by stamp
        self._wheel_yaw: deque = deque(maxlen=maxlen)  # (t, unwrapped wheel yaw)
        self._last: tuple[float, Pose] | None = None  # (t, wheel pose) of the last fuse
        self._offset: float | None = None  # fused yaw - the IMU's (None: not anchored)
        self.fused: Pose | None = None  # the newest fused pose
        self.wheel: Pose | None = None  # the newest wheel pose
        self.imu_used = 0  # odometry steps turned by the gyro
        self.bias = 0.0  # [rad/s] the gyro's, from the last long stop
        self._still: tuple[float, float] | None = None  # (first, last) stamp of the stop under way
        self.gyro_heading = False  # the newest fused heading came from the gyro

    def reset(self) -> None:
        """Forget everything (a new run: time went backwards)."""
        self._imu.clear()
        self._wheel_yaw.clear()
        self._last = self._offset = self.fused = self.wheel = self._still = None
        self.bias = 0.0
        self.gyro_heading = False

    def on_imu(self, t: float, yaw: float) -> None:
        """The IMU's heading [rad] at stamp ``t`` [s] (its orientation's yaw)."""
        _append_unwrapped(self._imu, t, yaw)

    def _heading(self, t: float, wheel_yaw: float, fallback: float) -> float:
        """The fused heading at ``t``; ``fallback`` (the wheels' alone) without the IMU."""
        reading = _at_or_before(self._imu, t)
        if reading is None or t - reading[0] > IMU_STALE:
            self._offset = None  # re-anchor when it comes back
            self.gyro_heading = False
            return fallback
        t_k, imu_yaw = reading
        imu_yaw -= self.bias * t_k
        since = wheel_yaw - _interpolate(self._wheel_yaw, t_k, wheel_yaw)  # turned since t_k
        if self._offset is None:
            self._offset = fallback - (imu_yaw + since)
        self.imu_used += 1
        self.gyro_heading = True
        return self._offset + imu_yaw + since

    def fuse(self, t: float, wheel) -> Pose:
        """The fused pose at stamp ``t`` from the wheel pose there (x, y, yaw)."""
        wheel = tuple(float(v) for v in wheel)
        if self._last is not None and t < self._last[0]:
            self.reset()
        _append_unwrapped(self._wheel_yaw, t, wheel[2])
        wheel_yaw = self._wheel_yaw[-1][1]
        if self._last is None:
            self.fused, self._offset = wheel, None
            self._heading(t, wheel_yaw, wheel[2])  # anchor to the IMU if it is there
        else:
            _, w0 = self._last
            dth_wheels = _wrap(wheel[2] - w0[2])
            mid = w0[2] + dth_wheels / 2
            ds = (wheel[0] - w0[0]) * math.cos(mid) + (wheel[1] - w0[1]) * math.sin(mid)
            assert self.fused is not None  # set by every fuse, as _last is
            x, y, yaw = self.fused
            if ds == 0.0 and dth_wheels == 0.0:
                # the wheels stand still: so does the robot, whatever the gyro's bias says
                # (a zero-velocity update); the heading re-anchors to the IMU when it moves
                self._offset = None
                self._still = (self._still[0] if self._still else self._last[0], t)
                new_yaw = yaw
            else:
                self._end_stop()
                new_yaw = self._heading(t, wheel_yaw, yaw + dth_wheels)
            mid = (yaw + new_yaw) / 2
            self.fused = (x + ds * math.cos(mid), y + ds * math.sin(mid), new_yaw)
        self._last = (t, wheel)
        self.wheel = wheel
        return (self.fused[0], self.fused[1], _wrap(self.fused[2]))

    def _end_stop(self) -> None:
        """The robot moves again: a long enough stop gives the gyro's bias."""
        if self._still is None:
            return
        first, last = self._still
        self._still = None
        if last - first < BIAS_MIN_STILL or not self._imu or self._imu[0][0] > first or self._imu[-1][0] < last:
            return
        turned = _interpolate(self._imu, last, 0.0) - _interpolate(self._imu, first, 0.0)
        self.bias = turned / (last - first)

    def map_to_wheel_odom(self, map_to_fused) -> tuple:
        """map -> the wheels' odom frame, from map -> the fused frame, at the newest pose."""
        if self.fused is None:
            return tuple(map_to_fused)
        return compose(compose(tuple(map_to_fused), self.fused), inverse(self.wheel))


def _append_unwrapped(history: deque, t: float, yaw: float) -> None:
    """Add (t, yaw) with yaw unwrapped against the newest entry (a stamp going back
    starts the history again)."""
    if history:
        t_prev, prev = history[-1]
        if t < t_prev:
            history.clear()
        else:
            yaw = prev + _wrap(yaw - prev)
    history.append((t, yaw))


def _at_or_before(history: deque, t: float):
    """The newest entry stamped at or before ``t`` (a hair after counts), or None."""
    for entry in reversed(history):
        if entry[0] <= t + 1e-6:
            return entry
    return None


def _stamp(entry: tuple) -> float:
    return entry[0]


def _interpolate(history: deque, t: float, default: float) -> float:
    """The value interpolated at ``t`` (the nearest end outside the history)."""
    if not history:
        return default
    i = bisect.bisect_left(history, t, key=_stamp)
    if i <= 0:
        return history[0][1]
    if i >= len(history):
        return history[-1][1]
    (t0, a), (t1, b) = history[i - 1], history[i]
    return a + (b - a) * ((t - t0) / (t1 - t0) if t1 > t0 else 1.0)
