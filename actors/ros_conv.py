"""Small conversions between ROS messages and plain values, shared by the actors."""

from __future__ import annotations

import math
from typing import Sequence

from builtin_interfaces.msg import Duration


def duration_msg(seconds: float) -> Duration:
    sec = math.floor(seconds)
    return Duration(sec=int(sec), nanosec=min(int(round((seconds - sec) * 1e9)), 999_999_999))


def yaw_of(q) -> float:
    """Yaw [rad] of a geometry_msgs Quaternion."""
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def pose2d(msg) -> tuple[float, float, float]:
    """(x, y, yaw) of a PoseStamped or Odometry message."""
    pose = msg.pose.pose if hasattr(msg.pose, "pose") else msg.pose
    return pose.position.x, pose.position.y, yaw_of(pose.orientation)


def wrap(a: float) -> float:
    """Angle wrapped to [-pi, pi)."""
    return (a + math.pi) % (2 * math.pi) - math.pi


def named(names: Sequence[str], values: Sequence[float], wanted: Sequence[str]) -> list[float]:
    """The values of ``wanted`` joints from a JointState's name/value lists."""
    index = {n: i for i, n in enumerate(names)}
    return [float(values[index[n]]) if index.get(n) is not None and index[n] < len(values) else 0.0 for n in wanted]
