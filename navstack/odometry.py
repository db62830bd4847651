"""Odometry as the navstack nodes keep it: a short history of (time, pose) read from
``/odom``, interpolated at a scan's stamp, and the message fields they need."""

from __future__ import annotations

import bisect
import math
from collections import deque

__all__ = ["OdomHistory", "Pose", "as_pose", "yaw_of", "seconds", "interpolate_pose"]

#: a planar pose (x [m], y [m], yaw [rad])
Pose = tuple[float, float, float]


def as_pose(p) -> Pose:
    """``p`` (x, y, yaw: a tuple, a list, an array row) as a pose of plain floats."""
    return float(p[0]), float(p[1]), float(p[2])


def yaw_of(q) -> float:
    """Heading [rad] of a geometry_msgs Quaternion (planar robots: roll, pitch ignored)."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def seconds(stamp) -> float:
    """A builtin_interfaces/Time in seconds."""
    return stamp.sec + stamp.nanosec * 1e-9


def interpolate_pose(a, b, f: float):
    """The planar pose a fraction ``f`` of the way from ``a`` to ``b`` (yaw the short way)."""
    dyaw = math.remainder(b[2] - a[2], 2 * math.pi)
    return (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), math.remainder(a[2] + f * dyaw, 2 * math.pi))


class OdomHistory:
    """The latest ``maxlen`` odometry poses (x, y, yaw) by stamp."""

    def __init__(self, maxlen: int = 200) -> None:
        self.entries: deque = deque(maxlen=maxlen)  # (t, (x, y, yaw))

    def __len__(self) -> int:
        return len(self.entries)

    def add(self, t: float, pose) -> bool:
        """Record a pose; a stamp older than the newest means a new run (the history
        restarts) and returns True."""
        restarted = bool(self.entries) and t < self.entries[-1][0]
        if restarted:
            self.entries.clear()
        self.entries.append((t, tuple(pose)))
        return restarted

    def latest(self):
        return self.entries[-1][1] if self.entries else None

    def at(self, t: float):
        """The pose interpolated at ``t`` (the nearest end outside the history; None when
        empty)."""
        h = self.entries
        if not h:
            return None
        times = [s for s, _ in h]
        i = bisect.bisect_left(times, t)
        if i <= 0:
            return h[0][1]
        if i >= len(times):
            return h[-1][1]
        (t0, a), (t1, b) = h[i - 1], h[i]
        return interpolate_pose(a, b, (t - t0) / (t1 - t0) if t1 > t0 else 1.0)
