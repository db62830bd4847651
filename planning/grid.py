"""Occupancy grids and their inflation into a costmap for a round robot.

:class:`OccupancyGrid` mirrors ``nav_msgs/OccupancyGrid`` (values -1 unknown,
0..100 occupancy probability, row-major with the row index along y) without
importing ROS; :meth:`OccupancyGrid.from_msg` reads a message duck-typed.

:class:`Costmap` is the grid inflated for a circular footprint, nav2 style:

* ``lethal``: the robot centre may not be there, because the footprint would
  overlap an obstacle (or unknown space) — clearance below ``robot_radius``;
* ``cost`` in [0, 1]: 0 beyond ``inflation_radius`` from every obstacle,
  rising towards 1 at ``robot_radius``; the planner pays it so that paths keep
  to the middle of corridors and doors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence, overload

import numpy as np

from .errors import InvalidInputError

__all__ = ["OccupancyGrid", "Costmap", "inflate"]


@dataclass(frozen=True, eq=False)  # holds arrays: compared by identity
class OccupancyGrid:
    """A 2-D occupancy grid in the map frame.

    Attributes:
        data: (height, width) int8 array; ``data[row, col]`` is the cell whose
            centre is at ``origin + ((col + 0.5) * resolution, (row + 0.5) *
            resolution)``; -1 unknown, 0 free .. 100 occupied.
        resolution: cell size [m].
        origin: map-frame position of the corner of cell (0, 0) [m]; the grid
            is axis-aligned (nav_msgs origin yaw 0).
    """

    data: np.ndarray
    resolution: float
    origin: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self) -> None:
        arr = np.asarray(self.data)
        if arr.ndim != 2 or arr.size == 0:
            raise InvalidInputError(f"grid data must be a non-empty 2-D array, got shape {arr.shape}")
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise InvalidInputError(f"resolution must be > 0 m, got {self.resolution!r}")
        object.__setattr__(self, "data", arr.astype(np.int8, copy=False))
        object.__setattr__(self, "origin", (float(self.origin[0]), float(self.origin[1])))

    @classmethod
    def from_msg(cls, msg: Any) -> OccupancyGrid:
        """Read a ``nav_msgs.msg.OccupancyGrid`` (only yaw-free origins)."""
        info = msg.info
        q = info.origin.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        if abs(yaw) > 1e-6:
            raise InvalidInputError(f"rotated map origins are not supported (yaw {yaw:.4f} rad)")
        data = np.asarray(msg.data, dtype=np.int8).reshape(info.height, info.width)
        return cls(data, float(info.resolution), (float(info.origin.position.x), float(info.origin.position.y)))

    @property
    def shape(self) -> tuple[int, int]:
        """(height, width) in cells."""
        return self.data.shape

    def cell_of(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell containing map point (x, y) [m]; may be outside."""
        return (
            int(math.floor((y - self.origin[1]) / self.resolution)),
            int(math.floor((x - self.origin[0]) / self.resolution)),
        )

    @overload
    def center_of(self, row: int, col: int) -> tuple[float, float]: ...
    @overload
    def center_of(self, row: np.ndarray, col: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...

    def center_of(self, row: int | np.ndarray, col: int | np.ndarray) -> tuple[float | np.ndarray, float | np.ndarray]:
        """Map position (x, y) [m] of a cell centre (of each cell, elementwise, for arrays)."""
        return (
            self.origin[0] + (col + 0.5) * self.resolution,
            self.origin[1] + (row + 0.5) * self.resolution,
        )

    def contains(self, row: int, col: int) -> bool:
        """True when (row, col) is inside the grid."""
        h, w = self.shape
        return 0 <= row < h and 0 <= col < w


@dataclass(frozen=True, eq=False)
class Costmap:
    """An occupancy grid inflated for a circular robot.

    Attributes:
        grid: the source grid.
        robot_radius: footprint radius [m] (circumscribed, around the centre
            the planner moves).
        inflation_radius: distance from obstacles beyond which cells cost 0 [m].
        clearance: (height, width) distance from each cell centre to the
            nearest obstacle or unknown cell [m] (0 on them).
        obstacle: (height, width) bool, occupied or (if ``unknown_is_obstacle``)
            unknown cells.
        unknown: (height, width) bool, unknown cells.
        lethal: (height, width) bool, cells the robot centre may not enter.
        cost: (height, width) float in [0, 1], the inflation cost.
    """

    grid: OccupancyGrid
    robot_radius: float
    inflation_radius: float
    clearance: np.ndarray = field(repr=False)
    obstacle: np.ndarray = field(repr=False)
    unknown: np.ndarray = field(repr=False)
    lethal: np.ndarray = field(repr=False)
    cost: np.ndarray = field(repr=False)


def with_obstacles(grid: OccupancyGrid, circles: Sequence[tuple[float, float, float]]) -> OccupancyGrid:
    """A copy of ``grid`` with each circle (x, y, radius) [m] marked occupied: perceived
    objects that the static map does not know about (nav2's obstacle layer)."""
    if not circles:
        return grid
    data = grid.data.copy()
    rows, cols = np.indices(data.shape)
    cx = grid.origin[0] + (cols + 0.5) * grid.resolution
    cy = grid.origin[1] + (rows + 0.5) * grid.resolution
    for x, y, r in circles:
        data[(cx - x) ** 2 + (cy - y) ** 2 <= r * r] = 100
    return OccupancyGrid(data, grid.resolution, grid.origin)


def inflate(
    grid: OccupancyGrid,
    robot_radius: float,
    *,
    inflation_radius: float | None = None,
    occupied_threshold: int = 65,
    unknown_is_obstacle: bool = True,
) -> Costmap:
    """Inflate ``grid`` for a round robot of ``robot_radius`` [m].

    Args:
        grid: the occupancy grid.
        robot_radius: footprint radius [m].
        inflation_radius: where the cost falls to 0 [m]; default
            ``robot_radius + 0.25``.
        occupied_threshold: cells with occupancy >= this are obstacles
            (map_server's default ``occupied_thresh`` 0.65).
        unknown_is_obstacle: treat unknown (-1) cells as obstacles.
    """
    if not (math.isfinite(robot_radius) and robot_radius >= 0):
        raise InvalidInputError(f"robot_radius must be >= 0 m, got {robot_radius!r}")
    infl = robot_radius + 0.25 if inflation_radius is None else float(inflation_radius)
    if not (math.isfinite(infl) and infl >= robot_radius):
        raise InvalidInputError(
            f"inflation_radius must be >= robot_radius ({robot_radius} m), got {inflation_radius!r}"
        )
    data = grid.data
    unknown = data < 0
    obstacle = data >= occupied_threshold
    if unknown_is_obstacle:
        obstacle = obstacle | unknown
    if obstacle.any():
        # Distance from a free cell centre to the nearest obstacle cell's edge:
        # centre-to-centre distance minus half a cell (conservative for the
        # footprint, which must not overlap the obstacle cell).
        from scipy import ndimage  # here, not at import: scipy costs ~1 s of every start-up

        dist = ndimage.distance_transform_edt(~obstacle) * grid.resolution
        clearance = np.maximum(dist - 0.5 * grid.resolution, 0.0)
        clearance[obstacle] = 0.0
    else:
        clearance = np.full(data.shape, np.inf)
    lethal = obstacle | (clearance < robot_radius)
    span = max(infl - robot_radius, 1e-9)
    cost = np.clip((infl - clearance) / span, 0.0, 1.0) ** 2
    cost[lethal] = 1.0
    return Costmap(grid, float(robot_radius), infl, clearance, obstacle, unknown, lethal, cost)
