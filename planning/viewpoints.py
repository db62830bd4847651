"""Search viewpoints: a few places from which the robot's camera sees all of a map.

A search needs places to look around from. In a world the project knows they can be
listed by hand; on any other map (one the robot built, a user's SLAM map) they are
chosen here: candidate places on a lattice of the reachable free space, each seeing the
free cells within ``view_range`` along unobstructed grid rays, then a greedy set cover
(the classic art-gallery heuristic) until ``coverage`` of the reachable floor is seen,
ordered as a nearest-neighbour tour from the start.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .errors import InvalidInputError
from .grid import Costmap

__all__ = ["viewpoints"]

RAYS = 90  # directions cast from each candidate (4 degrees apart)


def _reachable(costmap: Costmap, start: tuple[float, float]) -> np.ndarray:
    """Cells the robot centre can reach from ``start`` (the nearest free cell to it)."""
    from scipy import ndimage

    free = ~costmap.lethal
    labels, n = ndimage.label(free)
    if n == 0:
        return np.zeros_like(free)
    g = costmap.grid
    r, c = g.cell_of(*start)
    if g.contains(r, c) and labels[r, c]:
        return labels == labels[r, c]
    rows, cols = np.nonzero(free)
    k = int(np.argmin((rows - r) ** 2 + (cols - c) ** 2))
    return labels == labels[rows[k], cols[k]]


def _visible(see_through: np.ndarray, r0: int, c0: int, steps: int) -> np.ndarray:
    """Flat indices of the cells seen from (r0, c0): along RAYS rays, up to ``steps``
    cells, each ray stopping at the first cell it cannot see through."""
    h, w = see_through.shape
    ang = np.linspace(0.0, 2 * math.pi, RAYS, endpoint=False)
    k = np.arange(1, steps + 1)
    rr = np.rint(r0 + np.outer(np.sin(ang), k)).astype(int)
    cc = np.rint(c0 + np.outer(np.cos(ang), k)).astype(int)
    inside = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
    rr, cc = np.clip(rr, 0, h - 1), np.clip(cc, 0, w - 1)
    clear = see_through[rr, cc] & inside
    # a ray sees up to and including its first blocked cell (the wall's face)
    seen = np.cumprod(np.concatenate([np.ones((RAYS, 1), bool), clear[:, :-1]], axis=1), axis=1).astype(bool)
    seen &= inside
    return np.unique(rr[seen] * w + cc[seen])


def viewpoints(
    costmap: Costmap,
    start: tuple[float, float],
    *,
    view_range: float = 2.5,
    spacing: float = 0.5,
    coverage: float = 0.9,
    min_gain: float = 0.01,
    max_views: int = 30,
    seen_from: Sequence[tuple[float, float]] = (),
) -> list[tuple[float, float]]:
    """Places (x, y) [m] from which the reachable floor of ``costmap`` is seen.

    Args:
        costmap: the inflated map; candidates are cells the robot centre may occupy and
            can reach from ``start``.
        start: where the robot is (x, y) [m]; the tour begins nearest to it.
        view_range: how far the camera sees an object [m].
        spacing: the candidate lattice step [m].
        coverage: the fraction of the reachable floor to be seen before stopping.
        min_gain: a place must show at least this fraction of the floor not yet seen
            (the greedy cover's tail otherwise adds places for corners of a few cells).
            Objects stand by the furniture, where those corners are: in house_hard, 0.02
            stopped at 14 places, short of ``coverage``, and over 20 seeds their views
            saw 117 of 120 objects; 0.01 takes 19 places, which saw 119
            (bench/bench_search_views.py).
        max_views: at most this many places.
        seen_from: places already looked around from (a search's given locations): the
            floor they see counts as seen, and only places for the rest are returned.

    Returns the places in visiting order; empty when nothing is reachable.
    """
    if not (view_range > 0 and spacing > 0 and 0 < coverage <= 1 and max_views >= 1):
        raise InvalidInputError("view_range and spacing must be > 0 m, coverage in (0, 1], max_views >= 1")
    g = costmap.grid
    reach = _reachable(costmap, start)
    if not reach.any():
        return []
    # the floor to be seen: free cells near the reachable area (objects stand there too)
    see_through = ~costmap.obstacle
    step = max(1, int(round(spacing / g.resolution)))
    rows, cols = np.nonzero(reach)
    pick = (rows % step == 0) & (cols % step == 0)
    cand = list(zip(rows[pick].tolist(), cols[pick].tolist())) or [(int(rows[0]), int(cols[0]))]
    steps = max(1, int(view_range / g.resolution))
    seen_by = [_visible(see_through, r, c, steps) for r, c in cand]
    floor = np.zeros(g.data.size, bool)
    for s in seen_by:
        floor[s] = True
    floor &= see_through.ravel()
    target = floor.sum()
    covered = np.zeros_like(floor)
    for x, y in seen_from:
        r, c = g.cell_of(float(x), float(y))
        if g.contains(r, c):
            covered[_visible(see_through, r, c, steps)] = True
    covered &= floor
    chosen: list[int] = []
    while covered.sum() < coverage * target and len(chosen) < max_views:
        gains = [int(np.count_nonzero(floor[s] & ~covered[s])) for s in seen_by]
        best = int(np.argmax(gains))
        if gains[best] == 0 or ((chosen or seen_from) and gains[best] < min_gain * target):
            break
        chosen.append(best)
        covered[seen_by[best]] = True
        covered &= floor
    places = [g.center_of(*cand[i]) for i in chosen]
    # nearest-neighbour tour from the start
    tour, here = [], (float(start[0]), float(start[1]))
    while places:
        k = min(range(len(places)), key=lambda i: math.dist(places[i], here))
        here = places.pop(k)
        tour.append(here)
    return tour
