"""Obstacles below the laser's plane, from a depth camera: the navigator's second
observation source (in Nav2, a depth camera's point cloud in the costmap's obstacle layer).

The laser scans one plane, 0.17 m up on a TurtleBot3: a can lying on the floor, a flat box
or a toy is under it, and a base that sees only the scan drives into them and pushes them
along. The depth camera sees them. Each depth image is turned into the points that stand
out of the floor: back-projected through the pinhole intrinsics, put into base_footprint
by the camera's mounting, and kept when they are

* between ``min_height`` (above the floor's depth noise) and ``max_height`` (the robot's
  own height: higher things it passes under) above the floor,
* between ``min_range`` and ``max_range`` from the camera (nearer, the arm and what it
  holds may be in view; farther, the depth noise grows and the path there is far off),
* and outside the base's own outline.

Only their x, y are kept: the navigator checks them against the path ahead as it does
the scan's beams.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class DepthObstacleParams:
    """Which depth pixels are obstacles (units: m)."""

    stride: int = 4  # use every stride-th pixel in each direction
    min_height: float = 0.015  # above the floor (a jenga block lying flat is 24 mm)
    max_height: float = 0.40
    min_range: float = 0.25  # from the camera, along its view
    max_range: float = 1.5
    self_box: tuple = (-0.23, 0.10, 0.18)  # x_min, x_max, |y| max of the base itself


def depth_obstacle_points(
    depth: np.ndarray,
    fx: float,
    fy: float,
    cx: float,
    cy: float,
    T_base_cam: np.ndarray,
    params: DepthObstacleParams | None = None,
) -> np.ndarray:
    """(N, 2) x, y in base_footprint of the depth image's obstacle points.

    Args:
        depth: (H, W) metres along the optical axis, NaN or 0 where there is no return
        fx, fy, cx, cy: the pinhole intrinsics [px]
        T_base_cam: 4 x 4 pose of the camera's optical frame in base_footprint
        params: the band and ranges kept (defaults: DepthObstacleParams())
    """
    p = params or DepthObstacleParams()
    s = max(1, int(p.stride))
    d = np.asarray(depth, dtype=float)[::s, ::s]
    rows, cols = np.mgrid[0 : depth.shape[0] : s, 0 : depth.shape[1] : s]
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(d) & (d >= p.min_range) & (d <= p.max_range)
    if not ok.any():
        return np.zeros((0, 2))
    z = d[ok]
    cam = np.column_stack([(cols[ok] - cx) / fx * z, (rows[ok] - cy) / fy * z, z])
    pts = cam @ T_base_cam[:3, :3].T + T_base_cam[:3, 3]
    x0, x1, ymax = p.self_box
    keep = (
        (pts[:, 2] >= p.min_height)
        & (pts[:, 2] <= p.max_height)
        & ~((pts[:, 0] >= x0) & (pts[:, 0] <= x1) & (np.abs(pts[:, 1]) <= ymax))
    )
    return pts[keep, :2]


__all__ = ["DepthObstacleParams", "depth_obstacle_points"]
