"""A transform tree, as tf2's buffer keeps it: frames joined by timed transforms, looked up
between any two frames at a time.

Feed it the ``geometry_msgs/TransformStamped`` entries of ``/tf`` (dynamic: a short
history per edge, interpolated) and ``/tf_static`` (static: one value, valid at every
time); ask ``lookup(target, source, t)`` for the 4 × 4 matrix that maps points in
``source`` to ``target`` (tf2's ``lookupTransform(target, source, time)``). This is the
plain-Python half; who subscribes the topics is the caller's business.

Frames follow REP 105: ``map`` → ``odom`` (the localiser) → ``base_footprint`` (odometry)
→ ``base_link`` → sensors and arm links (the robot description).
"""

from __future__ import annotations

import bisect
import builtins
import math
from dataclasses import dataclass, field
from typing import Any, Iterable

import numpy as np

#: how much history a dynamic edge keeps [s] (tf2's default cache is 10 s)
CACHE_SECONDS = 10.0


class TransformError(LookupError):
    """No transform between two frames at that time: unknown frame, two trees, or a time
    outside the history (the message says which)."""


def quaternion_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    """Rotation (3, 3) of a quaternion (normalised first)."""
    n = math.sqrt(x * x + y * y + z * z + w * w) or 1.0
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def matrix_quaternion(R: np.ndarray) -> tuple[float, float, float, float]:
    """Quaternion (x, y, z, w) of a rotation matrix (3, 3)."""
    w = math.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    return x, y, z, w


def transform_matrix(translation: Iterable[float], quaternion: Iterable[float]) -> np.ndarray:
    """Homogeneous transform (4, 4) from (x, y, z) and a quaternion (x, y, z, w)."""
    T = np.eye(4)
    T[:3, :3] = quaternion_matrix(*quaternion)
    T[:3, 3] = tuple(translation)
    return T


def planar(x: float, y: float, yaw: float) -> np.ndarray:
    """Homogeneous transform (4, 4) of a pose in the plane."""
    T = np.eye(4)
    c, s = math.cos(yaw), math.sin(yaw)
    T[:2, :2] = ((c, -s), (s, c))
    T[:2, 3] = (x, y)
    return T


def pose2d(T: np.ndarray) -> tuple[float, float, float]:
    """(x [m], y [m], yaw [rad]) of a homogeneous transform."""
    return float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0])


def invert(T: np.ndarray) -> np.ndarray:
    """The inverse of a rigid transform."""
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -T[:3, :3].T @ T[:3, 3]
    return out


def interpolate(Ta: np.ndarray, Tb: np.ndarray, f: float) -> np.ndarray:
    """The transform a fraction ``f`` of the way from ``Ta`` to ``Tb`` (linear position,
    rotation along the shortest arc)."""
    out = np.eye(4)
    out[:3, 3] = (1 - f) * Ta[:3, 3] + f * Tb[:3, 3]
    Rr = Ta[:3, :3].T @ Tb[:3, :3]
    angle = math.acos(max(-1.0, min(1.0, (np.trace(Rr) - 1) / 2)))
    if angle < 1e-9:
        out[:3, :3] = Tb[:3, :3]
        return out
    axis = np.array([Rr[2, 1] - Rr[1, 2], Rr[0, 2] - Rr[2, 0], Rr[1, 0] - Rr[0, 1]]) / (2 * math.sin(angle))
    a = f * angle
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    out[:3, :3] = Ta[:3, :3] @ (np.eye(3) + math.sin(a) * k + (1 - math.cos(a)) * (k @ k))
    return out


@dataclass
class _Edge:
    """The transform parent → child: one value (static) or a timed history."""

    parent: str
    static: bool
    times: list[float] = field(default_factory=list)
    values: list[np.ndarray] = field(default_factory=list)

    def add(self, t: float, T: np.ndarray) -> None:
        if self.static:
            self.times, self.values = [t], [T]
            return
        i = bisect.bisect_right(self.times, t)
        self.times.insert(i, t)
        self.values.insert(i, T)
        cut = bisect.bisect_left(self.times, self.times[-1] - CACHE_SECONDS)
        if cut:
            del self.times[:cut], self.values[:cut]

    def at(self, t: float | None, child: str) -> np.ndarray:
        if self.static or t is None:
            return self.values[-1]
        times = self.times
        if t > times[-1] or t < times[0]:
            if len(times) == 1 and abs(t - times[0]) < 1e-9:
                return self.values[0]
            when = "after the latest" if t > times[-1] else "before the oldest"
            raise TransformError(
                f"{self.parent} -> {child} at t={t:.3f} s is {when} transform "
                f"(known from {times[0]:.3f} to {times[-1]:.3f} s)"
            )
        i = bisect.bisect_left(times, t)
        if times[i] == t:
            return self.values[i]
        ta, tb = times[i - 1], times[i]
        return interpolate(self.values[i - 1], self.values[i], (t - ta) / (tb - ta))


class TransformBuffer:
    """Frames joined by transforms; see the module docstring."""

    def __init__(self) -> None:
        self._edges: dict[str, _Edge] = {}  # child -> its edge from the parent

    # -- feeding ---------------------------------------------------------------------
    def set(self, parent: str, child: str, T: np.ndarray, t: float = 0.0, static: bool = False) -> None:
        """Record ``parent`` → ``child`` (maps points in ``child`` to ``parent``) at time ``t``."""
        parent, child = parent.lstrip("/"), child.lstrip("/")
        edge = self._edges.get(child)
        if edge is None or edge.parent != parent or edge.static != static:
            edge = self._edges[child] = _Edge(parent, static)
        edge.add(t, T)

    def add_message(self, msg: Any, static: bool = False) -> None:
        """Record every ``TransformStamped`` of a ``tf2_msgs/TFMessage`` (or one alone)."""
        for ts in getattr(msg, "transforms", [msg]):
            tr, q = ts.transform.translation, ts.transform.rotation
            stamp = ts.header.stamp
            self.set(
                ts.header.frame_id,
                ts.child_frame_id,
                transform_matrix((tr.x, tr.y, tr.z), (q.x, q.y, q.z, q.w)),
                stamp.sec + stamp.nanosec * 1e-9,
                static,
            )

    # -- asking ----------------------------------------------------------------------
    def frames(self) -> builtins.set[str]:  # builtins: the class's own set() shadows the type here
        return set(self._edges) | {e.parent for e in self._edges.values()}

    def can_transform(self, target: str, source: str, t: float | None = None) -> bool:
        try:
            self.lookup(target, source, t)
            return True
        except TransformError:
            return False

    def lookup(self, target: str, source: str, t: float | None = None) -> np.ndarray:
        """The transform (4, 4) mapping points in ``source`` to ``target`` at time ``t``
        (``None``: the latest of each edge)."""
        target, source = target.lstrip("/"), source.lstrip("/")
        up_source = self._to_root(source, t)
        up_target = self._to_root(target, t)
        common = next((f for f in up_source if f in up_target), None)
        if common is None:
            raise TransformError(
                f"{target} and {source} are not connected (known frames: {', '.join(sorted(self.frames())) or 'none'})"
            )
        return invert(up_target[common]) @ up_source[common]

    def _to_root(self, frame: str, t: float | None) -> dict[str, np.ndarray]:
        """Each ancestor of ``frame`` (itself included) -> the transform frame → ancestor."""
        if frame not in self._edges and frame not in self.frames():
            raise TransformError(f"unknown frame {frame!r} (known: {', '.join(sorted(self.frames())) or 'none'})")
        chain = {frame: np.eye(4)}
        T = np.eye(4)
        while frame in self._edges:
            edge = self._edges[frame]
            T = edge.at(t, frame) @ T
            frame = edge.parent
            if frame in chain:
                raise TransformError(f"the transforms form a loop through {frame!r}")
            chain[frame] = T
        return chain
