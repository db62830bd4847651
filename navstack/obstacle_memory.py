"""What the depth camera saw, remembered once it is out of view.

The camera looks ahead and down, and sees nothing nearer than ``min_range``: a can the
base drives up to, or passes, leaves its view before the base is done with it, and the
base's rear swings into it as it turns away. :class:`ObstacleMemory` keeps each image's
obstacle points, in a frame that does not jump (the odometry's), and forgets

* the remembered points that a newer image has in view: that image shows what is there
  now (a can that was picked up, a box that was moved);
* points older than ``keep`` seconds (the odometry drifts), or farther than ``radius``
  from the camera.

It keeps one point per ``cell`` (the newest), so it stays small. In Nav2 the local
costmap's obstacle layer does this, clearing by ray tracing instead of by view.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ObstacleMemory"]


class ObstacleMemory:
    """Obstacle points (x, y) in one fixed frame, from a depth camera's images."""

    def __init__(
        self, keep: float, min_range: float, max_range: float, *, cell: float = 0.025, radius: float = 3.0
    ) -> None:
        self.keep, self.min_range, self.max_range = keep, min_range, max_range
        self.cell, self.radius = cell, radius
        self._pts = np.zeros((0, 3))  # x, y, time seen

    def __len__(self) -> int:
        return len(self._pts)

    def points(self) -> np.ndarray:
        """(N, 2) the remembered points."""
        return self._pts[:, :2]

    def update(self, pts: np.ndarray, T_cam: np.ndarray, k, width: int, height: int, now: float) -> None:
        """Add an image's obstacle points ``pts`` ((N, 2), the memory's frame), seen from
        the camera's optical frame at ``T_cam`` (4 x 4, in the memory's frame; z up from
        the floor) with intrinsics ``k`` (CameraInfo.k) and image size, at time ``now``."""
        mem = self._pts[now - self._pts[:, 2] <= self.keep]
        if len(mem):
            # each remembered point just above the floor, in the camera's optical frame
            T = np.linalg.inv(T_cam)
            q = np.column_stack([mem[:, :2], np.full(len(mem), 0.03)]) @ T[:3, :3].T + T[:3, 3]
            z = q[:, 2]
            with np.errstate(divide="ignore", invalid="ignore"):
                u = k[0] * q[:, 0] / z + k[2]
                v = k[4] * q[:, 1] / z + k[5]
            seen = (z > self.min_range) & (z < self.max_range) & (u >= 0) & (u < width) & (v >= 0) & (v < height)
            mem = mem[~seen]
        mem = np.vstack([np.column_stack([pts, np.full(len(pts), now)]), mem])
        mem = mem[np.hypot(mem[:, 0] - T_cam[0, 3], mem[:, 1] - T_cam[1, 3]) < self.radius]
        _, first = np.unique(np.floor(mem[:, :2] / self.cell).astype(np.int64), axis=0, return_index=True)
        self._pts = mem[np.sort(first)]
