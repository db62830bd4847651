"""Frontier exploration: where to drive next to see more of a map that is being built.

A frontier cell is a free cell next to unknown space. Neighbouring frontier cells form a
frontier; one too short for the robot to see through is ignored. For each frontier the
goal is the reachable cell nearest to its middle (the robot centre may stand there,
reached through free space from the robot) that leaves the robot room to turn round;
the chosen frontier is the one with the shortest path there, discounted for its size,
so that the robot finishes a room before it drives off to a small gap far away
(Yamauchi's nearest-frontier rule, weighted).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from .errors import InvalidInputError
from .grid import Costmap

__all__ = ["Frontier", "frontiers", "next_frontier", "path_distances"]

#: 8-connected steps (row, col, length in cells)
_STEPS = [
    (-1, 0, 1.0),
    (1, 0, 1.0),
    (0, -1, 1.0),
    (0, 1, 1.0),
    (-1, -1, math.sqrt(2)),
    (-1, 1, math.sqrt(2)),
    (1, -1, math.sqrt(2)),
    (1, 1, math.sqrt(2)),
]


@dataclass(frozen=True)
class Frontier:
    """One frontier: its size [cells], its middle (x, y) [m], the goal (x, y, yaw) to drive
    to and the path length there [m] (inf when no reachable cell is near it)."""

    size: int
    middle: tuple[float, float]
    goal: tuple[float, float, float] | None
    distance: float


def path_distances(costmap: Costmap, start: tuple[float, float]) -> np.ndarray:
    """Path length [m] from ``start`` to every cell the robot centre may occupy, through
    such cells (8-connected); inf where it cannot go. A start inside a lethal cell (the
    robot's own cell is often marked as it maps) begins from the nearest free cell."""
    g = costmap.grid
    free = ~costmap.lethal
    h, w = free.shape
    dist = np.full((h, w), np.inf)
    r, c = g.cell_of(*start)
    if not (g.contains(r, c) and free[r, c]):
        rows, cols = np.nonzero(free)
        if rows.size == 0:
            return dist
        k = int(np.argmin((rows - r) ** 2 + (cols - c) ** 2))
        r, c = int(rows[k]), int(cols[k])
    # Dijkstra with a deque is enough here: two step lengths, settled lazily
    dist[r, c] = 0.0
    queue = deque([(r, c)])
    res = g.resolution
    while queue:
        r, c = queue.popleft()
        d = dist[r, c]
        for dr, dc, step in _STEPS:
            rr, cc = r + dr, c + dc
            if 0 <= rr < h and 0 <= cc < w and free[rr, cc]:
                nd = d + step * res
                if nd < dist[rr, cc] - 1e-9:
                    dist[rr, cc] = nd
                    queue.append((rr, cc))
    return dist


def frontiers(
    costmap: Costmap,
    start: tuple[float, float],
    *,
    min_size: float = 0.3,
    goal_radius: float = 1.0,
    min_unknown: float = 0.5,
    goal_margin: float = 0.1,
) -> list[Frontier]:
    """Every frontier of ``costmap``'s grid at least ``min_size`` [m] long, nearest first.

    Args:
        costmap: the map being built, inflated for the robot (unknown cells are obstacles)
        start: where the robot is (x, y) [m]
        min_size: shorter frontiers are ignored [m]
        goal_radius: a goal is a reachable cell within this distance of the frontier [m]
        min_unknown: frontiers onto an unknown pocket smaller than this [m^2], closed in by
            the map (under a bed, inside a counter, behind a wardrobe), are ignored: the
            laser cannot see into it from anywhere, and there is nothing there to map
    """
    from scipy import ndimage

    if not (min_size >= 0 and goal_radius > 0 and min_unknown >= 0 and goal_margin >= 0):
        raise InvalidInputError("min_size, min_unknown and goal_margin must be >= 0 and goal_radius > 0 m")
    g = costmap.grid
    data = g.data
    free = (data >= 0) & (data < 50)
    unknown = data < 0
    # the unknown worth exploring: pockets of it that are big, or open to the map's edge
    pockets, n_pockets = ndimage.label(unknown, structure=np.ones((3, 3), bool))
    if n_pockets:
        area = ndimage.sum_labels(unknown, pockets, index=np.arange(1, n_pockets + 1)) * g.resolution**2
        edge = np.unique(np.concatenate([pockets[0], pockets[-1], pockets[:, 0], pockets[:, -1]]))
        worth = area >= min_unknown
        worth[edge[edge > 0] - 1] = True
        unknown = unknown & np.concatenate([[False], worth])[pockets]
    near_unknown = ndimage.binary_dilation(unknown, structure=np.ones((3, 3), bool))
    cells = free & near_unknown
    labels, n = ndimage.label(cells, structure=np.ones((3, 3), bool))
    if n == 0:
        return []
    dist = path_distances(costmap, start)
    reach_rows, reach_cols = np.nonzero(np.isfinite(dist))
    reach_x, reach_y = g.center_of(reach_rows, reach_cols)  # arrays, elementwise
    roomy = costmap.clearance[reach_rows, reach_cols] >= costmap.robot_radius + goal_margin
    sizes = ndimage.sum_labels(cells, labels, index=np.arange(1, n + 1))
    out = []
    for k in range(n):
        size = int(sizes[k])
        if size * g.resolution < min_size:
            continue
        rows, cols = np.nonzero(labels == k + 1)
        # the frontier cell nearest the cells' mean: a curved frontier's mean may be off it
        mr, mc = rows.mean(), cols.mean()
        i = int(np.argmin((rows - mr) ** 2 + (cols - mc) ** 2))
        mx, my = g.center_of(int(rows[i]), int(cols[i]))
        goal, d = None, math.inf
        if reach_rows.size:
            near = np.hypot(reach_x - mx, reach_y - my) <= goal_radius
            if near.any():
                near_roomy = near & roomy
                cand = np.nonzero(near_roomy if near_roomy.any() else near)[0]
                # the reachable cell nearest the frontier's middle: from there the robot
                # sees furthest into the unknown
                j = cand[np.argmin(np.hypot(reach_x[cand] - mx, reach_y[cand] - my))]
                gx, gy = float(reach_x[j]), float(reach_y[j])
                goal = (gx, gy, math.atan2(my - gy, mx - gx))
                d = float(dist[reach_rows[j], reach_cols[j]])
        out.append(Frontier(size, (mx, my), goal, d))
    out.sort(key=lambda f: f.distance)
    return out


def next_frontier(
    costmap: Costmap,
    start: tuple[float, float],
    *,
    avoid: list | tuple = (),
    avoid_radius: float = 0.5,
    size_weight: float = 0.02,
    **kwargs,
) -> Frontier | None:
    """The frontier to explore next: reachable, not near a point of ``avoid`` (goals that
    failed before), with the smallest path length minus ``size_weight`` [m per cell] times
    its size. None when the map has no reachable frontier left: the exploration is done."""
    best, best_cost = None, math.inf
    for f in frontiers(costmap, start, **kwargs):
        if f.goal is None or any(math.dist(f.goal[:2], a[:2]) < avoid_radius for a in avoid):
            continue
        cost = f.distance - size_weight * f.size
        if cost < best_cost:
            best, best_cost = f, cost
    return best
