"""Positions read from whatever shape a pose or a path has, for the Nav2 nodes.

Nav2 passes ``geometry_msgs/PoseStamped`` and ``nav_msgs/Path`` messages; actorbt's own
actors answer with tuples (``get_pose() -> (x, y, yaw)``) and lists of points. The nodes
that measure distances accept all of these, without importing any message package.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["path_length", "path_points", "xy"]


def xy(pose: Any) -> tuple[float, float]:
    """The (x, y) of a pose [m]: a sequence ``(x, y, ...)``, a mapping with ``x`` and
    ``y`` (or ``position``/``pose`` holding one), or an object with those attributes
    (``PoseStamped.pose.position``).

    Raises:
        ValueError: none of these shapes.
    """
    for _ in range(4):  # PoseStamped -> Pose -> Point, as mappings or attributes
        if isinstance(pose, (list, tuple)) and len(pose) >= 2 and all(_number(v) for v in pose[:2]):
            return float(pose[0]), float(pose[1])
        if isinstance(pose, dict):
            if _number(pose.get("x")) and _number(pose.get("y")):
                return float(pose["x"]), float(pose["y"])
            inner = pose.get("pose", pose.get("position"))
        else:
            x, y = getattr(pose, "x", None), getattr(pose, "y", None)
            if _number(x) and _number(y):
                return float(x), float(y)  # type: ignore[arg-type]
            inner = getattr(pose, "pose", getattr(pose, "position", None))
        if inner is None:
            break
        pose = inner
    raise ValueError(
        f"cannot read a position from {type(pose).__name__} {str(pose)[:60]!r}, expected (x, y, ...), "
        "{'x': .., 'y': ..} or a PoseStamped"
    )


def path_points(path: Any) -> list[tuple[float, float]]:
    """The (x, y) points of a path: a sequence of poses, or an object or mapping whose
    ``poses`` is one (``nav_msgs/Path``). ``None`` is an empty path."""
    if path is None:
        return []
    poses = path.get("poses") if isinstance(path, dict) else getattr(path, "poses", path)
    return [xy(p) for p in poses or ()]


def path_length(points: list[tuple[float, float]]) -> float:
    """The length of a polyline [m]."""
    return sum(math.dist(a, b) for a, b in zip(points, points[1:]))


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)
