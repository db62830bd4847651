"""Path planning for the mobile base on an inflated occupancy grid.

:class:`GridPlanner` searches the 8-connected grid of a :class:`Costmap` with
Dijkstra (scipy's compiled ``csgraph``), paying for each step its length times
``1 + cost_weight * inflation cost``, so paths keep away from walls where there
is room and squeeze through doors where there is not. Diagonal steps may not cut
the corner of a lethal cell.

The cell path is then smoothed by line-of-sight shortcuts: a shortcut is taken
only when every point of it (sampled every quarter cell) is outside the lethal
zone and at least as far from obstacles as the stretch of path it replaces (up
to ``robot_radius + smoothing_margin``). The smoothed path is re-checked against
the lethal zone before it is returned, so every straight segment between its
waypoints is collision-free for the round footprint.

The search graph is built once per planner; build one planner per map.
"""

from __future__ import annotations

import math
import time
from typing import Any
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .failure import FailureReason
from .grid import Costmap, OccupancyGrid, inflate

__all__ = ["BasePath", "GridPlanner", "plan_base_path"]

_SQRT2 = math.sqrt(2.0)


@dataclass(frozen=True)
class BasePath:
    """Result of a base planning query, in the map frame.

    Attributes:
        waypoints: (x, y) points [m], the given start first and the given goal
            last; the straight segments between them are collision-free.
            Empty on failure.
        length: path length [m] (NaN on failure).
        raw_length: length of the grid path before smoothing [m].
        min_clearance: smallest distance from the path to an obstacle [m].
        planning_time: wall-clock time of the query [s].
        failure: None on success, else why it failed.
        message: the failure in words ("" on success).
    """

    waypoints: tuple[tuple[float, float], ...]
    length: float
    raw_length: float
    min_clearance: float
    planning_time: float
    failure: FailureReason | None = None
    message: str = ""

    @property
    def ok(self) -> bool:
        """True when ``waypoints`` is a collision-free path."""
        return self.failure is None

    def raise_for_failure(self) -> None:
        """Raise the :class:`~planning.errors.PlanningError` subclass for ``failure``."""
        if self.failure is not None:
            raise self.failure.error_type(self.message)


class GridPlanner:
    """Shortest cost-aware paths on one costmap.

    Args:
        costmap: the inflated grid (see :func:`planning.grid.inflate`).
        cost_weight: how much the inflation cost lengthens a step (0 = pure
            shortest path).
        smoothing_margin: clearance beyond ``robot_radius`` that a shortcut
            keeps when the original path had it [m].
    """

    def __init__(self, costmap: Costmap, *, cost_weight: float = 3.0, smoothing_margin: float = 0.1) -> None:
        self.costmap = costmap
        self.cost_weight = float(cost_weight)
        self.smoothing_margin = float(smoothing_margin)
        self._graph = self._build_graph()

    def _build_graph(self) -> Any:  # a scipy.sparse.csr_matrix
        cm = self.costmap
        h, w = cm.lethal.shape
        free = ~cm.lethal
        idx = np.arange(h * w).reshape(h, w)
        srcs, dsts, weights = [], [], []
        res = cm.grid.resolution
        for dr, dc in ((0, 1), (1, 0), (1, 1), (1, -1)):
            r0, r1 = max(0, -dr), h - max(0, dr)
            c0, c1 = max(0, -dc), w - max(0, dc)
            a = (slice(r0, r1), slice(c0, c1))
            b = (slice(r0 + dr, r1 + dr), slice(c0 + dc, c1 + dc))
            ok = free[a] & free[b]
            if dr and dc:  # no corner cutting
                ok &= free[(slice(r0 + dr, r1 + dr), slice(c0, c1))] & free[(slice(r0, r1), slice(c0 + dc, c1 + dc))]
            step = res * (_SQRT2 if dr and dc else 1.0)
            wgt = step * (1.0 + self.cost_weight * 0.5 * (cm.cost[a] + cm.cost[b]))
            ia, ib, wv = idx[a][ok], idx[b][ok], wgt[ok]
            srcs += [ia, ib]
            dsts += [ib, ia]
            weights += [wv, wv]
        n = h * w
        from scipy.sparse import csr_matrix  # here, not at import: scipy is slow to import

        return csr_matrix((np.concatenate(weights), (np.concatenate(srcs), np.concatenate(dsts))), shape=(n, n))

    # ---------------------------------------------------------------- helpers
    def _check_end(self, xy: Sequence[float], what: str) -> tuple[tuple[int, int] | None, str]:
        cm, grid = self.costmap, self.costmap.grid
        try:
            x, y = (float(v) for v in xy)
        except (TypeError, ValueError):
            return None, f"{what} must be (x, y) in metres, got {xy!r}"
        if not (math.isfinite(x) and math.isfinite(y)):
            return None, f"{what} ({x}, {y}) is not finite"
        rc = grid.cell_of(x, y)
        if not grid.contains(*rc):
            h, w = grid.shape
            x0, y0 = grid.origin
            return None, (
                f"{what} ({x:.2f}, {y:.2f}) is outside the map "
                f"x {x0:.2f}..{x0 + w * grid.resolution:.2f}, y {y0:.2f}..{y0 + h * grid.resolution:.2f} m"
            )
        if cm.unknown[rc]:
            return None, f"{what} ({x:.2f}, {y:.2f}) is on unknown space"
        if cm.lethal[rc]:
            return None, (
                f"{what} ({x:.2f}, {y:.2f}) is blocked: {cm.clearance[rc]:.3f} m from an obstacle, "
                f"the robot radius is {cm.robot_radius:.3f} m"
            )
        return rc, ""

    def segment_cells(self, p, q) -> tuple[np.ndarray, np.ndarray] | None:
        """(rows, cols) of the cells under segment p -> q (x, y) [m], sampled every quarter
        cell from p to q; None if it leaves the map."""
        grid = self.costmap.grid
        p, q = np.asarray(p, dtype=float), np.asarray(q, dtype=float)
        n = max(2, int(math.ceil(float(np.linalg.norm(q - p)) / (0.25 * grid.resolution))) + 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        pts = p + (q - p) * t
        cols = np.floor((pts[:, 0] - grid.origin[0]) / grid.resolution).astype(int)
        rows = np.floor((pts[:, 1] - grid.origin[1]) / grid.resolution).astype(int)
        h, w = grid.shape
        if rows.min() < 0 or cols.min() < 0 or rows.max() >= h or cols.max() >= w:
            return None
        return rows, cols

    def _segment_clearance(self, p: np.ndarray, q: np.ndarray) -> float:
        """Smallest clearance over points of segment p -> q [m]; -1 if it leaves the map."""
        cells = self.segment_cells(p, q)
        if cells is None or self.costmap.lethal[cells].any():
            return -1.0
        return float(self.costmap.clearance[cells].min())

    def _smooth(self, pts: list[np.ndarray], clear: np.ndarray) -> list[np.ndarray]:
        want = self.costmap.robot_radius + self.smoothing_margin
        out = [pts[0]]
        i = 0
        while i < len(pts) - 1:
            j = i + 1
            # Walk forward while the shortcut i -> j + 1 is as safe as the path it replaces.
            while j + 1 < len(pts):
                need = min(want, float(clear[i : j + 2].min()))
                if self._segment_clearance(pts[i], pts[j + 1]) + 1e-9 < need:
                    break
                j += 1
            out.append(pts[j])
            i = j
        return out

    # ------------------------------------------------------------------ query
    def plan(self, start: Sequence[float], goal: Sequence[float]) -> BasePath:
        """A collision-free path from ``start`` (x, y) to ``goal`` (x, y) [m, map frame].

        Never raises for an impossible query: the result says why.
        """
        t0 = time.perf_counter()
        cm, grid = self.costmap, self.costmap.grid

        def fail(reason: FailureReason, message: str) -> BasePath:
            return BasePath((), math.nan, math.nan, math.nan, time.perf_counter() - t0, reason, message)

        s_rc, why = self._check_end(start, "start")
        if s_rc is None:
            return fail(FailureReason.START_INVALID if "must be" not in why else FailureReason.INVALID_INPUT, why)
        g_rc, why = self._check_end(goal, "goal")
        if g_rc is None:
            return fail(FailureReason.GOAL_INVALID if "must be" not in why else FailureReason.INVALID_INPUT, why)
        w = grid.shape[1]
        s_i, g_i = s_rc[0] * w + s_rc[1], g_rc[0] * w + g_rc[1]
        from scipy.sparse.csgraph import dijkstra

        dist, pred = dijkstra(self._graph, directed=True, indices=s_i, return_predecessors=True)
        if not math.isfinite(dist[g_i]):
            return fail(
                FailureReason.NO_PATH,
                f"no path from {tuple(start)} to {tuple(goal)}: the goal is not connected to the start "
                f"for a robot of radius {cm.robot_radius:.3f} m (blocked or unknown space)",
            )
        cells = [g_i]
        while cells[-1] != s_i:
            cells.append(int(pred[cells[-1]]))
        cells.reverse()
        rows, cols = np.divmod(np.asarray(cells), w)
        centres = np.column_stack(
            [grid.origin[0] + (cols + 0.5) * grid.resolution, grid.origin[1] + (rows + 0.5) * grid.resolution]
        )
        pts = [np.asarray(start, dtype=float)] + list(centres[1:-1]) + [np.asarray(goal, dtype=float)]
        clear = cm.clearance[rows, cols]
        raw_length = float(np.sum(np.linalg.norm(np.diff(np.array(pts), axis=0), axis=1)))
        path = self._smooth(pts, clear) if len(pts) > 2 else pts
        # Dense re-check of what is returned (the grid path itself is safe by
        # construction, so falling back to it cannot fail).
        seg_clear = [self._segment_clearance(a, b) for a, b in zip(path[:-1], path[1:])]
        if min(seg_clear, default=float(cm.clearance[s_rc])) < 0:
            path = pts
            seg_clear = [self._segment_clearance(a, b) for a, b in zip(path[:-1], path[1:])]
            if min(seg_clear, default=0.0) < 0:
                return fail(FailureReason.RECHECK_FAILED, "the grid path failed its re-check (start or goal cell edge)")
        length = float(np.sum(np.linalg.norm(np.diff(np.array(path), axis=0), axis=1))) if len(path) > 1 else 0.0
        return BasePath(
            waypoints=tuple((float(p[0]), float(p[1])) for p in path),
            length=length,
            raw_length=raw_length,
            min_clearance=min(seg_clear, default=float(cm.clearance[s_rc])),
            planning_time=time.perf_counter() - t0,
        )


def plan_base_path(
    grid: OccupancyGrid,
    start: Sequence[float],
    goal: Sequence[float],
    *,
    robot_radius: float,
    inflation_radius: float | None = None,
    unknown_is_obstacle: bool = True,
    cost_weight: float = 3.0,
) -> BasePath:
    """One-shot helper: inflate ``grid``, build a :class:`GridPlanner` and plan.

    For repeated queries on one map, build the planner once instead.
    """
    costmap = inflate(grid, robot_radius, inflation_radius=inflation_radius, unknown_is_obstacle=unknown_is_obstacle)
    return GridPlanner(costmap, cost_weight=cost_weight).plan(start, goal)
