"""Ways out for a robot that stands where the inflated map says it may not.

The map can put the robot inside the inflation: a wall drawn thick, a speckle of a map
being built, or a nook the robot drove into while the map was still being drawn (the
far side of a wardrobe is mapped only once the robot is beside it). A planner refuses
such a start, so the navigator first leaves it:

* :func:`plan_out_of` goes straight to the nearest cell the robot may stand on, if that
  way never comes nearer to an obstacle than the start;
* failing that, the way it came: the shortest way through cells about as clear as the
  start, as far as ``winding`` metres, to the nearest such cell.
"""

from __future__ import annotations

import heapq
import logging
import math
from dataclasses import replace

import numpy as np

from planning.base_planner import BasePath, GridPlanner

log = logging.getLogger(__name__)

#: a way out may pass this much nearer to an obstacle than the start [cells]: the map's
#: walls are whole cells, so the way the robot came in reads a cell tighter here and there
SQUEEZE_CELLS = 1.0


def plan_out_of(planner: GridPlanner, start, goal, escape_distance: float, winding: float = 0.0) -> BasePath | None:
    """A path from a start inside the inflation to ``goal`` (x, y) [m]: through the
    nearest cell the robot may stand on, within ``escape_distance`` [m], if the straight
    way there never comes nearer to an obstacle than the start; else, with ``winding``
    > 0, along :func:`way_out` at most that long. None when there is neither."""
    return _straight_out(planner, start, goal, escape_distance) or (
        _winding_out(planner, start, goal, winding) if winding > 0 else None
    )


def _straight_out(planner: GridPlanner, start, goal, escape_distance: float) -> BasePath | None:
    cm = planner.costmap
    grid = cm.grid
    res = grid.resolution
    reach = int(math.ceil(escape_distance / res))
    r0, c0 = grid.cell_of(*start[:2])
    h, w = cm.lethal.shape
    rows = slice(max(r0 - reach, 0), min(r0 + reach + 1, h))
    cols = slice(max(c0 - reach, 0), min(c0 + reach + 1, w))
    rr, cc = np.nonzero(~cm.lethal[rows, cols])
    if not len(rr):
        return None
    xs, ys = grid.center_of(rr + rows.start, cc + cols.start)
    d = np.hypot(xs - start[0], ys - start[1])
    for i in np.argsort(d)[:20]:
        if d[i] > escape_distance:
            break
        via = (float(xs[i]), float(ys[i]))
        if not _never_closer(planner, start, via):
            continue
        rest = planner.plan(via, goal)
        if rest.ok:
            log.info(
                "start (%.2f, %.2f) is inside the inflation: leaving through (%.2f, %.2f)", start[0], start[1], *via
            )
            return _prepend(rest, [(float(start[0]), float(start[1]))], float(d[i]))
    return None


def _winding_out(planner: GridPlanner, start, goal, winding: float) -> BasePath | None:
    for way in way_out(planner, start, winding):
        rest = planner.plan(way[-1], goal)
        if rest.ok:
            log.info(
                "start (%.2f, %.2f) is deep inside the inflation: leaving the way it came, through (%.2f, %.2f)",
                start[0],
                start[1],
                *way[-1],
            )
            length = sum(math.dist(a, b) for a, b in zip(way, way[1:]))
            return _prepend(rest, way[:-1], length)
    return None


def way_out(planner: GridPlanner, start, winding: float, tries: int = 5) -> list[list[tuple[float, float]]]:
    """Up to ``tries`` ways [(x, y), ...] from ``start`` to cells the robot may stand on,
    shortest first, each at most ``winding`` [m] long and through cells no nearer to an
    obstacle than the start (less SQUEEZE_CELLS). A way starts at ``start`` and ends on
    the free cell's centre; exits nearer than half a metre to a shorter way's are left
    out (they would be the same way out)."""
    cm = planner.costmap
    grid = cm.grid
    res = grid.resolution
    h, w = cm.lethal.shape
    r0, c0 = grid.cell_of(*start[:2])
    if not grid.contains(r0, c0) or cm.obstacle[r0, c0]:
        return []
    floor = min(cm.clearance[r0, c0], cm.robot_radius) - SQUEEZE_CELLS * res
    limit = winding / res
    dist = {(r0, c0): 0.0}
    parent: dict[tuple[int, int], tuple[int, int]] = {}
    heap = [(0.0, r0, c0)]
    exits: list[tuple[int, int]] = []
    while heap and len(exits) < tries:
        d, r, c = heapq.heappop(heap)
        if d > dist.get((r, c), math.inf):
            continue
        if not cm.lethal[r, c]:
            if all(math.hypot(r - er, c - ec) * res >= 0.5 for er, ec in exits):
                exits.append((r, c))
            continue  # a way out ends on the first free cell
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                rn, cn = r + dr, c + dc
                if (dr or dc) and grid.contains(rn, cn) and cm.clearance[rn, cn] >= floor:
                    dn = d + math.hypot(dr, dc)
                    if dn <= limit and dn < dist.get((rn, cn), math.inf):
                        dist[(rn, cn)], parent[(rn, cn)] = dn, (r, c)
                        heapq.heappush(heap, (dn, rn, cn))
    ways = []
    for cell in exits:
        cells = [cell]
        while cells[-1] != (r0, c0):
            cells.append(parent[cells[-1]])
        centres = [grid.center_of(r, c) for r, c in reversed(cells[:-1])]
        ways.append([(float(start[0]), float(start[1]))] + centres)
    return ways


def _never_closer(planner: GridPlanner, a, b) -> bool:
    """Whether the straight way a -> b (x, y) [m] stays on the map and never comes nearer
    to an obstacle than the robot is at ``a``."""
    cells = planner.segment_cells(a, b)
    if cells is None:
        return False
    clear = planner.costmap.clearance[cells]
    return bool(clear[0] > 0 and clear.min() >= min(clear[0], planner.costmap.robot_radius) - 1e-6)


def _prepend(rest: BasePath, waypoints: list, length: float) -> BasePath:
    return replace(rest, waypoints=tuple(waypoints) + rest.waypoints, length=rest.length + length)


__all__ = ["plan_out_of", "way_out"]
