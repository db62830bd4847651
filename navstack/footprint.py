"""The base's footprint as a box, and whether a velocity command sweeps it into something.

The planner inflates the map for a round robot of ``robot_radius`` (0.20 m), but the base
is a box reaching 0.21 m behind the wheels' axle: its rear corners are 0.26 m from the
axle's middle. Driving straight, the box stays within the planned corridor; turning, even
on an arc, its rear swings sideways by 0.21 m per radian, into a can or a carton that
stood two centimetres from its side. Nav2's controllers check the footprint polygon along
each candidate trajectory for the same reason; :func:`sweep_hits` does it for one command,
:func:`turn_hits` for a whole turn in place.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["box_distance", "sweep_hits", "turn_hits"]


def box_distance(pts: np.ndarray, box: tuple) -> np.ndarray:
    """Distance [m] of (N, 2) points in the base frame from the footprint ``box`` (x_min,
    x_max, |y| max); 0 inside it."""
    x0, x1, ymax = box
    dx = np.maximum(np.maximum(x0 - pts[:, 0], pts[:, 0] - x1), 0.0)
    dy = np.maximum(np.abs(pts[:, 1]) - ymax, 0.0)
    return np.hypot(dx, dy)


def sweep_hits(
    pts: np.ndarray,
    pose: tuple,
    v: float,
    w: float,
    duration: float,
    box: tuple,
    *,
    pad: float = 0.02,
) -> bool:
    """Would driving (``v`` [m/s], ``w`` [rad/s]) from ``pose`` (x, y, yaw) for ``duration``
    seconds bring one of the obstacle points ``pts`` ((N, 2), same frame as the pose)
    within ``pad`` of the footprint ``box``, nearer than it is now? A point already that
    near is hit only if the motion closes in on it: the base may always drive away from
    something it touches, and a point inside the box (the robot itself) never counts.
    Checked every 2 cm of travel and 3 degrees of turn."""
    if not len(pts) or (v == 0.0 and w == 0.0) or duration <= 0.0:
        return False
    x, y, yaw = pose
    reach = math.hypot(max(-box[0], box[1]), box[2]) + abs(v) * duration + pad
    pts = pts[np.hypot(pts[:, 0] - x, pts[:, 1] - y) < reach]
    if not len(pts):
        return False
    dx, dy = pts[:, 0] - x, pts[:, 1] - y
    d0 = None  # the points' distances now (t = 0)
    steps = max(1, math.ceil(max(abs(v) * duration / 0.02, abs(w) * duration / math.radians(3))))
    for t in np.linspace(0.0, duration, steps + 1):
        # the unicycle's displacement after t, in the start's frame
        th = w * t
        if abs(w) > 1e-9:
            px, py = v / w * math.sin(th), v / w * (1.0 - math.cos(th))
        else:
            px, py = v * t, 0.0
        ox, oy = math.cos(yaw) * px - math.sin(yaw) * py, math.sin(yaw) * px + math.cos(yaw) * py
        c, s = math.cos(yaw + th), math.sin(yaw + th)
        qx, qy = dx - ox, dy - oy
        d = box_distance(np.column_stack([c * qx + s * qy, -s * qx + c * qy]), box)
        if d0 is None:
            d0 = d
        elif np.any((d < pad) & (d < d0 - 1e-3)):
            return True
    return False


def turn_hits(pts: np.ndarray, pose: tuple, angle: float, box: tuple, *, pad: float = 0.02) -> bool:
    """Would turning in place by ``angle`` [rad] (positive: counter-clockwise) sweep the
    footprint into one of ``pts``? (:func:`sweep_hits` for the whole turn.)"""
    return sweep_hits(pts, pose, 0.0, math.copysign(1.0, angle), abs(angle), box, pad=pad)
