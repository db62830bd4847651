"""A clean occupancy grid made to look like a real SLAM map (gmapping, slam_toolbox).

:func:`slam_like` remaps a clean grid, e.g. the house's ``actorbt sim map --height`` export,
as a lidar SLAM would have left it after one drive through the places ``drive`` lists,
all from one seed:

* the map frame is where the drive started, turned by ``rotation`` (3° by default): the
  walls are staircases, the origin is non-zero and not on the source's cell lattice;
* only what the lidar saw is known: rays (360 a turn, 3.5 m, range noise) cast every
  :data:`POSE_STEP` along the drive mark the floor they cross free and the cell they stop
  in occupied. Inside walls, behind furniture and outside the house stay unknown;
* walls between rooms are one cell thin (of a wall two cells thick, one face is floor; of
  two cells of hits where beams overshot a thin wall, the one with fewer hits is floor);
  wall faces are ragged (cells pushed one cell into the room); a few wall cells are 1-cell
  gaps, and through some gaps in the outer walls rays leak into the unknown outside
  (1-cell free streaks, 0.2-1 m);
* lidar noise: single occupied cells and pairs in the open floor;
* unknown patches inside the rooms, away from where the robot drove (up to 0.4 m across).

The result is trinary (100 / 0 / -1) at the source's resolution. :class:`MapFrame` takes
places in the source's frame to the new map's frame (for a locations file).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .gridmap import GridMap

LIDAR_RANGE = 3.5  # [m] the LDS-01's
LIDAR_MIN = 0.12  # [m]
BEAMS = 360
POSE_STEP = 0.3  # [m] between two scans along the drive
DRIVE_CLEARANCE = 0.25  # [m] the drive keeps this far from obstacles
RANGE_NOISE = 0.015  # range noise per metre (sigma)
SEEN_NEAR_DRIVE = 0.5  # [m] no unknown patch this close to the drive (the lidar saw it all)


@dataclass(frozen=True)
class MapFrame:
    """The SLAM map's frame in the source's: ``p_map = R(rotation) (p - pivot)``."""

    rotation: float  # [rad]
    pivot: tuple  # (x, y) [m] in the source frame: the map's (0, 0)

    def to_map(self, x, y, theta=0.0):
        """(x, y, theta) in the source frame -> in the map frame."""
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        dx, dy = x - self.pivot[0], y - self.pivot[1]
        return c * dx - s * dy, s * dx + c * dy, _wrap(theta + self.rotation)

    def to_source(self, x, y):
        """(x, y) in the map frame -> in the source frame (arrays too)."""
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        return self.pivot[0] + c * x + s * y, self.pivot[1] - s * x + c * y


@dataclass
class SlamMap:
    """What :func:`slam_like` made: the map, its frame, and where it put its flaws
    (cells as (row, col) of the map) for tests to look at."""

    grid: GridMap
    frame: MapFrame
    gaps: list = field(default_factory=list)  # 1-cell gaps in walls
    speckles: list = field(default_factory=list)  # occupied noise in the floor
    patches: list = field(default_factory=list)  # unknown patches in the floor (centre cells)
    drive: list = field(default_factory=list)  # (x, y) map frame: where the scans were taken


def _wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def slam_like(
    src: GridMap,
    drive,
    seed: int = 0,
    rotation: float = math.radians(3.0),
    gap_rate: float = 0.02,
    speckle_rate: float = 0.003,
    bump_rate: float = 0.03,
    patch_per_m2: float = 0.15,
) -> SlamMap:
    """``src`` (100 occupied, 0 free, -1 unknown) as a SLAM map made while driving through
    ``drive`` ((x, y) in ``src``'s frame, in order; the first is the map's origin), turned
    by ``rotation`` [rad]. Rates: the share of wall cells made gaps / bumps, of floor cells
    that become speckles; unknown patches per m² of floor."""
    rng = np.random.default_rng(seed)
    res = src.resolution
    frame = MapFrame(rotation, (float(drive[0][0]), float(drive[0][1])))

    # the truth in the map frame, walls one cell thin: of a wall two cells thick with floor
    # either side, one cell (per stretch of wall, either face) is floor, then the map is
    # turned (nearest cell: a thin wall stays one cell, in steps)
    data = _thin_walls(src.data, rng)
    known = data >= 0
    rows, cols = np.nonzero(known)
    xs = src.origin[0] + np.array([cols.min(), cols.max() + 1]) * res
    ys = src.origin[1] + np.array([rows.min(), rows.max() + 1]) * res
    corners = [frame.to_map(x, y)[:2] for x in xs for y in ys]
    mx, my = zip(*corners)
    margin = 0.6 + float(rng.uniform(0.0, res))  # off the source's cell lattice
    origin = (round(min(mx) - margin, 4), round(min(my) - margin, 4))
    w = int(math.ceil((max(mx) - min(mx) + 2 * margin) / res))
    h = int(math.ceil((max(my) - min(my) + 2 * margin) / res))
    X, Y = np.meshgrid(origin[0] + (np.arange(w) + 0.5) * res, origin[1] + (np.arange(h) + 0.5) * res)
    sx, sy = frame.to_source(X, Y)
    r = np.floor((sy - src.origin[1]) / res).astype(int)
    c = np.floor((sx - src.origin[0]) / res).astype(int)
    inside = (r >= 0) & (r < src.height) & (c >= 0) & (c < src.width)
    truth = np.full((h, w), -1, np.int8)
    truth[inside] = data[r[inside], c[inside]]
    grid = GridMap(truth, res, origin)

    # the drive and the scans along it
    pts = [frame.to_map(x, y)[:2] for x, y in drive]
    path = _drive_path(grid, pts)
    hits, passes = _scan(grid, path, rng)
    occ = hits > 0
    free = (passes > 0) & ~occ
    out = SlamMap(GridMap(np.full((h, w), -1, np.int8), res, origin), frame, drive=path)

    def nbr(mask, dr, dc):  # mask shifted: nbr(m, 0, 1)[r, c] = m[r, c + 1]
        o = np.zeros_like(mask)
        o[max(-dr, 0) : h - max(dr, 0), max(-dc, 0) : w - max(dc, 0)] = mask[
            max(dr, 0) : h - max(-dr, 0), max(dc, 0) : w - max(-dc, 0)
        ]
        return o

    # beams that overshoot a thin wall leave a second cell of hits behind it: of two
    # wall cells between floor cells, the one with fewer hits is floor (the map keeps
    # walls one cell thin, as the source's)
    for dr, dc in ((0, 1), (1, 0)):
        pair = occ & nbr(occ, dr, dc) & nbr(free, -dr, -dc) & nbr(free, 2 * dr, 2 * dc)
        other = nbr(hits, dr, dc)
        weaker = pair & (hits < other)  # this cell goes
        stronger = pair & (hits >= other)  # the next one goes
        drop = weaker | nbr(stronger, -dr, -dc)
        occ &= ~drop
        free |= drop

    face = occ & (nbr(free, 0, 1) | nbr(free, 0, -1) | nbr(free, 1, 0) | nbr(free, -1, 0))
    # ragged faces: a cell of floor next to the face becomes wall
    for r, c in np.argwhere(face & (rng.random((h, w)) < bump_rate)):
        opts = [
            (r + dr, c + dc)
            for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0))
            if 0 <= r + dr < h and 0 <= c + dc < w and free[r + dr, c + dc]
        ]
        if opts:
            rr, cc = opts[rng.integers(len(opts))]
            occ[rr, cc], free[rr, cc] = True, False
    # 1-cell gaps, four cells apart at least; through an outer wall some rays leak out
    taken = np.zeros((h, w), bool)
    for r, c in rng.permutation(np.argwhere(face & (rng.random((h, w)) < gap_rate))):
        if taken[max(r - 4, 0) : r + 5, max(c - 4, 0) : c + 5].any() or not occ[r, c]:
            continue
        taken[r, c] = True
        occ[r, c], free[r, c] = False, True
        out.gaps.append((int(r), int(c)))
        for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0)):
            if (
                0 <= r - dr < h
                and 0 <= c - dc < w
                and 0 <= r + dr < h
                and 0 <= c + dc < w
                and free[r - dr, c - dc]
                and not free[r + dr, c + dc]
                and not occ[r + dr, c + dc]
                and rng.random() < 0.5
            ):
                n = int(rng.integers(4, 20))  # 0.2 .. 1 m of free cells outside
                for k in range(1, n + 1):
                    rr, cc = r + k * dr, c + k * dc
                    if not (0 <= rr < h and 0 <= cc < w) or occ[rr, cc]:
                        break
                    free[rr, cc] = True
                break

    # unknown patches in the floor, away from the drive
    near_drive = np.zeros((h, w), bool)
    rad = int(round(SEEN_NEAR_DRIVE / res))
    for x, y in path:
        r, c = grid.cell(x, y)
        near_drive[max(r - rad, 0) : r + rad + 1, max(c - rad, 0) : c + rad + 1] = True
    floor_m2 = free.sum() * res**2
    cand = np.argwhere(free & ~near_drive)
    for _ in range(int(rng.poisson(patch_per_m2 * floor_m2)) if cand.size else 0):
        r, c = cand[rng.integers(len(cand))]
        a, b = rng.uniform(0.5, 4.0, 2)  # semi-axes [cells]: 0.05 .. 0.4 m across
        rr, cc = np.ogrid[-4:5, -4:5]
        blob = (rr / a) ** 2 + (cc / b) ** 2 <= 1.0
        if r < 4 or c < 4 or r + 5 > h or c + 5 > w:
            continue
        sl = (slice(r - 4, r + 5), slice(c - 4, c + 5))
        cut = blob & free[sl] & ~near_drive[sl]
        free[sl] &= ~cut
        out.patches.append((int(r), int(c)))
    # lidar noise: single cells and pairs in the open floor
    cand = np.argwhere(free & ~taken)
    for r, c in cand[rng.choice(len(cand), int(speckle_rate * len(cand)), replace=False)]:
        cells = [(r, c)] + ([(r, c + 1)] if rng.random() < 0.3 else [])
        if all(0 <= rr < h and 0 <= cc < w and free[rr, cc] and not taken[rr, cc] for rr, cc in cells):
            for rr, cc in cells:
                occ[rr, cc], free[rr, cc] = True, False
            out.speckles.append((int(r), int(c)))

    data = out.grid.data
    data[free] = 0
    data[occ] = 100
    return out


def write_slam_like(src_yaml, out_pgm, places: dict, seed: int = 0, rotation: float = math.radians(3.0)) -> tuple:
    """Read the map_server map ``src_yaml``, make it :func:`slam_like` with the drive
    through ``places`` (name -> (x, y[, theta]) in its frame, in order, the first where the
    drive starts) and write it as a trinary PGM + YAML at ``out_pgm``, and ``places`` in
    the new map's frame as a locations file beside it (``<stem>_locations.yaml``).
    Returns (map YAML, locations YAML, :class:`SlamMap`)."""
    from .gridmap import read_map, write_pgm_yaml
    from .map_world import write_locations

    m = slam_like(read_map(src_yaml).grid, [v[:2] for v in places.values()], seed, rotation)
    _, yml = write_pgm_yaml(m.grid, out_pgm)
    moved = {}
    for name, v in places.items():
        x, y, theta = m.frame.to_map(v[0], v[1], v[2] if len(v) > 2 else 0.0)
        moved[name] = (x, y, theta) if len(v) > 2 else (x, y)
    locs = write_locations(yml.with_name(yml.stem + "_locations.yaml"), moved)
    return yml, locs, m


def _thin_walls(data: np.ndarray, rng) -> np.ndarray:
    """``data`` with its walls two cells thick between floor cells thinned to one: per
    connected stretch of such wall, the cells of one face (chosen from ``rng``) become floor."""
    import cv2

    occ, free = data >= 65, data == 0
    out = data.copy()
    h, w = data.shape
    for axis in (0, 1):
        o, f = (occ, free) if axis == 1 else (occ.T, free.T)
        pair = np.zeros_like(o)  # pair[r, c]: o[r, c], o[r, c + 1], floor at c - 1 and c + 2
        pair[:, 1:-2] = o[:, 1:-2] & o[:, 2:-1] & f[:, :-3] & f[:, 3:]
        n, labels = cv2.connectedComponents(pair.astype(np.uint8), connectivity=8)
        far = rng.random(n) < 0.5  # per stretch: the cell at c + 1 goes, else the one at c
        rr, cc = np.nonzero(pair)
        cc = cc + far[labels[rr, cc]]
        if axis == 0:
            rr, cc = cc, rr
        out[rr, cc] = 0
    return out


def _drive_path(grid: GridMap, pts) -> list[tuple[float, float]]:
    """Poses every POSE_STEP along shortest ways (DRIVE_CLEARANCE from obstacles, 8-connected)
    joining ``pts`` in order; a place the drive cannot reach is scanned from where it is."""
    import cv2

    free = grid.data == 0
    d = cv2.distanceTransform(free.astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    ok = free & (d * grid.resolution >= DRIVE_CLEARANCE)
    h, w = ok.shape
    out: list[tuple[float, float]] = []

    def xy(r, c):
        return grid.origin[0] + (c + 0.5) * grid.resolution, grid.origin[1] + (r + 0.5) * grid.resolution

    cells = [grid.cell(x, y) for x, y in pts]
    for a, b in zip(cells, cells[1:] + [None]):
        out.append(xy(*a))
        if b is None or not ok[a] or not ok[b]:
            continue
        prev = np.full((h, w), -1, np.int64)
        prev[a] = a[0] * w + a[1]
        q = deque([a])
        while q:
            r, c = q.popleft()
            if (r, c) == b:
                break
            for dr, dc in ((0, 1), (0, -1), (1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1)):
                rr, cc = r + dr, c + dc
                if 0 <= rr < h and 0 <= cc < w and ok[rr, cc] and prev[rr, cc] < 0:
                    prev[rr, cc] = r * w + c
                    q.append((rr, cc))
        if prev[b] < 0:
            continue
        way, k = [], b[0] * w + b[1]
        while k != a[0] * w + a[1]:
            way.append(divmod(int(k), w))
            k = prev[divmod(int(k), w)]
        way.reverse()
        step = max(1, int(round(POSE_STEP / grid.resolution)))
        out.extend(xy(r, c) for r, c in way[step - 1 : -1 : step])
    return out


def _scan(grid: GridMap, poses, rng):
    """Per cell: how many beams ended in it (hits) and crossed it (passes)."""
    res, h, w = grid.resolution, grid.height, grid.width
    hits = np.zeros((h, w), np.int32)
    passes = np.zeros((h, w), np.int32)
    steps = np.arange(LIDAR_MIN, LIDAR_RANGE, res / 3)
    for x, y in poses:
        ang = rng.uniform(0, 2 * math.pi / BEAMS) + np.arange(BEAMS) * 2 * math.pi / BEAMS
        px = x + np.cos(ang)[:, None] * steps
        py = y + np.sin(ang)[:, None] * steps
        r = np.floor((py - grid.origin[1]) / res).astype(int)
        c = np.floor((px - grid.origin[0]) / res).astype(int)
        inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
        val = np.full(r.shape, -1, np.int8)
        val[inside] = grid.data[r[inside], c[inside]]
        stop = val != 0
        first = np.where(stop.any(1), stop.argmax(1), steps.size)
        hit = (first < steps.size) & (val[np.arange(BEAMS), np.minimum(first, steps.size - 1)] == 100)
        # the measured range: the true one with noise (sigma max(1 cm, 1.5 %): the scan
        # matcher's pose error and the lidar's own)
        true = np.where(first < steps.size, steps[np.minimum(first, steps.size - 1)], LIDAR_RANGE)
        meas = true + rng.normal(0, 1, BEAMS) * np.maximum(0.01, RANGE_NOISE * true)
        # the beam clears the cells a cell short of its end, never past the true surface
        k = np.minimum(np.searchsorted(steps, meas - res), first)
        cross = (np.arange(steps.size)[None, :] < k[:, None]) & inside
        np.add.at(passes, (r[cross], c[cross]), 1)
        hx = x + np.cos(ang) * meas
        hy = y + np.sin(ang) * meas
        hr = np.floor((hy - grid.origin[1]) / res).astype(int)
        hc = np.floor((hx - grid.origin[0]) / res).astype(int)
        good = hit & (hr >= 0) & (hr < h) & (hc >= 0) & (hc < w)
        np.add.at(hits, (hr[good], hc[good]), 1)
    # a cell crossed far more often than hit is floor (log-odds: hit 0.9, miss 0.3)
    hits[hits * 0.9 < passes * 0.3] = 0
    return hits, passes
