"""Worlds built from a map_server map (``--world map.yaml``), with an optional locations file.

The map's occupied cells become walls and the boundary between free and unknown space
becomes walls too (unknown is outside: the robot must never drive into it). Wall cells are
merged into boxes (greedy maximal rectangles), so a 200 x 200 map makes hundreds of bodies,
not tens of thousands. The cleanup a real SLAM map needs: occupied speckles in open floor
are dropped, small unknown holes in the floor become floor, unknown pockets enclosed by
obstacles (the inside of furniture) become solid.

Locations file (the common ROS demo form; metres, radians, map frame)::

    start: [0.5, 0.2, 0.0]       # or 'home': where the robot starts
    place: [3.0, 1.0, 1.57]      # or 'pallet' / 'drop': the place location (a pallet box)
    kitchen: [4.2, 2.0, 0.0]     # every other name: a search location
    hall: [1.0, 3.5]

Without it (or for what it leaves out) the start is the spot with most clearance near the
map's origin, the place location a free spot near the start, and the search locations a few
spread reachable spots. The objects (one of every registered category and a box distractor) are placed from
the seed at reachable spots within :data:`NEAR_LOCATION` of a search location.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

import categories as registry

from .gridmap import read_map
from .marked_yaml import compose_yaml
from .objects import CATEGORIES
from .world_spec import Box, PlacedObject, WorldError, WorldSpec

WALL_HEIGHT = 0.6  # [m] as sim/worlds/house.yaml's walls
WALL_RGBA = (0.82, 0.80, 0.74, 1.0)
PALLET = (0.6, 0.4, 0.12)  # [m] place location size, as house.yaml's pallet
PALLET_RGBA = (0.76, 0.60, 0.35, 1.0)
REACH_RADIUS = 0.25  # [m] the robot's centre needs this clearance (navstack plans with 0.20)
OBJECT_CLEARANCE = 0.30  # [m] objects keep this far from walls, the pallet, the start, each other
PASSAGE = 0.15  # [m] an object leaves at least twice this of the robot's way free
NEAR_LOCATION = 1.5  # [m] objects lie at most this far from a search location
SPECKLE_CELLS = 2  # occupied blobs this small with floor all round are lidar noise
HOLE_AREA = 0.05  # [m^2] unknown holes in the floor up to this size are floor
FIRST_OBJECTS = ("can", "bottle", "box")  # placed first, in this order (older seeds keep
# their layout); then one of every other category
START_NAMES, PLACE_NAMES = ("start", "home"), ("place", "pallet", "drop")


def map_world_objects() -> list[str]:
    """What a map world holds: one object of every registered category and a distractor."""
    return list(FIRST_OBJECTS) + [c for c in registry.names() if c not in FIRST_OBJECTS]


def build_map_world(path: str | Path, seed: int = 0, locations: str | Path | None = None) -> WorldSpec:
    """The :class:`WorldSpec` of a map_server map YAML ``path``, objects placed from ``seed``,
    named places from the ``locations`` YAML (see the module's docstring)."""
    mf = read_map(path)
    res = mf.grid.resolution
    occ, free, (r0, c0) = _crop(mf.occupied, mf.free)
    pad = 2  # unknown cells all round: the map edge is outside
    occ, free = np.pad(occ, pad), np.pad(free, pad)
    ox = mf.grid.origin[0] + (c0 - pad) * res
    oy = mf.grid.origin[1] + (r0 - pad) * res
    occ, free = clean(occ, free, res)
    if not free.any():
        raise WorldError(f"{path}: the map has no free space (no cell lighter than free_thresh)")
    walls = occ | (~occ & ~free & _dilate(free))  # the free/unknown boundary is a wall too
    g = _Grid(free, walls, res, (ox, oy))
    h, w = free.shape
    bounds = (ox, oy, ox + w * res, oy + h * res)
    spec = WorldSpec(name=Path(path).stem, source=str(path), bounds=bounds, seed=seed)
    spec.walls = [
        Box(
            f"wall_{i}",
            ox + (c + cw / 2) * res,
            oy + (r + rh / 2) * res,
            cw * res,
            rh * res,
            WALL_HEIGHT,
            0.0,
            WALL_RGBA,
        )
        for i, (r, c, rh, cw) in enumerate(merge_rectangles(walls))
    ]
    named = read_locations(locations) if locations is not None else {}
    _check_locations(named, g, locations)
    start = _pick(named, START_NAMES)
    if start is not None:
        x, y, yaw, node, ctx = start
        if g.clearance_at(x, y) < REACH_RADIUS:
            raise ctx.err(
                node,
                f"start ({x:g}, {y:g}) is {max(g.clearance_at(x, y), 0):.2f} m from a "
                f"wall; the robot needs {REACH_RADIUS} m",
            )
        spec.robot_start = (x, y, yaw)
    else:
        spec.robot_start = _in(path, g.auto_start)
    reach = g.reachable(spec.robot_start[:2])
    rng = np.random.default_rng(seed)
    place = _pick(named, PLACE_NAMES)
    spec.place = _in(path, _place_box, g, reach, spec.robot_start, place)
    searched = [v for k, v in named.items() if k not in START_NAMES + PLACE_NAMES]
    for x, y, _, node, ctx in searched:
        snapped = g.snap(reach, x, y, 0.5)
        if snapped is None:
            raise ctx.err(
                node,
                f"location ({x:g}, {y:g}) cannot be reached from the start "
                f"{spec.robot_start[:2]} (no spot with {REACH_RADIUS} m clearance "
                "within 0.5 m of it connects to the start)",
            )
        spec.search_locations.append(snapped)
    if not searched:
        spec.search_locations = g.spread(reach, spec.robot_start[:2])
    spec.objects = _place_objects(g, reach, spec, rng)
    return spec


def _in(path, fn, *args):
    """``fn(*args)``, its WorldError naming the map's file."""
    try:
        return fn(*args)
    except WorldError as e:
        if str(e).startswith(str(path)) or ":" in str(e).split(" ")[0]:
            raise
        raise WorldError(f"{path}: {e}") from None


# ---------------------------------------------------------------------------------------
# the grid: cleanup, walls, boxes


def _crop(occ: np.ndarray, free: np.ndarray):
    """Both masks cropped to the known cells' bounding box (SLAM maps are mostly unknown),
    and the crop's first (row, col)."""
    known = occ | free
    if not known.any():
        return occ, free, (0, 0)
    rows, cols = np.flatnonzero(known.any(1)), np.flatnonzero(known.any(0))
    sl = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
    return occ[sl], free[sl], (int(rows[0]), int(cols[0]))


def _dilate(mask: np.ndarray, radius: int = 1) -> np.ndarray:
    """8-neighbourhood dilation by ``radius`` cells."""
    import cv2

    k = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    return cv2.dilate(mask.astype(np.uint8), k).astype(bool)


def _components(mask: np.ndarray, connectivity: int = 8):
    import cv2

    n, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=connectivity)
    return n, labels, stats


def clean(occ: np.ndarray, free: np.ndarray, res: float):
    """A SLAM map's noise removed: occupied speckles (<= SPECKLE_CELLS cells, floor all
    round) become floor; unknown holes up to HOLE_AREA m² inside the floor become floor;
    unknown pockets with no floor next to them (the inside of furniture) become solid."""
    occ, free = occ.copy(), free.copy()
    n, labels, stats = _components(occ, 8)
    for label in np.flatnonzero(stats[1:, 4] <= SPECKLE_CELLS) + 1:
        blob = labels == label
        ring = _dilate(blob) & ~blob
        if free[ring].all():
            occ[blob], free[blob] = False, True
    unknown = ~occ & ~free
    n, labels, stats = _components(unknown, 4)
    h, w = occ.shape
    hole_cells = HOLE_AREA / res**2
    for i in range(1, n):
        x, y, bw, bh, area = stats[i]
        if x == 0 or y == 0 or x + bw == w or y + bh == h:
            continue  # reaches the map's edge: outside
        sl = (slice(max(y - 1, 0), y + bh + 1), slice(max(x - 1, 0), x + bw + 1))
        blob = labels[sl] == i
        ring = _dilate(blob) & ~blob
        if not free[sl][ring].any():
            occ[sl][blob] = True  # enclosed by obstacles: solid
        elif area <= hole_cells:
            free[sl][blob] = True  # a small gap in the floor's coverage
    return occ, free


def merge_rectangles(mask: np.ndarray) -> list[tuple[int, int, int, int]]:
    """Cover the True cells of ``mask`` with disjoint rectangles (row, col, rows, cols),
    greedily: from the first uncovered cell in row order, the longer of "run right, then
    grow down" and "run down, then grow right" (so vertical walls are one box, too)."""
    rem = mask.astype(bool).copy()
    h, w = rem.shape
    out = []
    for r in range(h):
        while True:
            cols = np.flatnonzero(rem[r])
            if cols.size == 0:
                break
            c = int(cols[0])
            cands = []
            # right, then down
            run = rem[r, c:]
            cw = int(np.argmin(run)) if not run.all() else run.size
            rh = 1
            while r + rh < h and rem[r + rh, c : c + cw].all():
                rh += 1
            cands.append((rh * cw, rh, cw))
            # down, then right
            col = rem[r:, c]
            rh2 = int(np.argmin(col)) if not col.all() else col.size
            cw2 = 1
            while c + cw2 < w and rem[r : r + rh2, c + cw2].all():
                cw2 += 1
            cands.append((rh2 * cw2, rh2, cw2))
            _, rh, cw = max(cands)
            rem[r : r + rh, c : c + cw] = False
            out.append((r, c, rh, cw))
    return out


class _Grid:
    """The cleaned map: free cells, walls, clearance [m] of each free cell."""

    def __init__(self, free, walls, res, origin):
        import cv2

        self.free, self.walls, self.res, self.origin = free, walls, res, origin
        d = cv2.distanceTransform(free.astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        # centre-to-centre distance to the nearest non-free cell, less half a cell: to its edge
        self.clear = np.where(free, d * res - res / 2, 0.0)

    def cell(self, x, y):
        return int(math.floor((y - self.origin[1]) / self.res)), int(math.floor((x - self.origin[0]) / self.res))

    def xy(self, r, c):
        return self.origin[0] + (c + 0.5) * self.res, self.origin[1] + (r + 0.5) * self.res

    def inside(self, r, c):
        return 0 <= r < self.free.shape[0] and 0 <= c < self.free.shape[1]

    def clearance_at(self, x, y) -> float:
        r, c = self.cell(x, y)
        return float(self.clear[r, c]) if self.inside(r, c) else -1.0

    def reachable(self, xy) -> np.ndarray:
        """Cells the robot's centre reaches from ``xy``: REACH_RADIUS clear, connected
        (so an opening narrower than the robot separates)."""
        ok = self.clear >= REACH_RADIUS - 1e-9
        _, labels, _ = _components(ok, 8)
        r, c = self.cell(*xy)
        return labels == labels[r, c] if self.inside(r, c) and ok[r, c] else np.zeros_like(ok)

    def auto_start(self):
        """A spot in the open near the map's origin (0, 0), where SLAM started, in the
        largest reachable region: the nearest with clearance >= 0.5 m (or the most there is)."""
        ok = self.clear >= REACH_RADIUS - 1e-9
        n, labels, stats = _components(ok, 8)
        if n <= 1:
            raise WorldError(f"no free spot with {REACH_RADIUS} m clearance for the robot in the map")
        big = labels == 1 + int(np.argmax(stats[1:, 4]))
        rr, cc = np.nonzero(big)
        xs, ys = self.xy(rr, cc)
        cl = self.clear[rr, cc]
        open_ = cl >= min(0.5, cl.max()) - 1e-9
        i = np.flatnonzero(open_)[np.argmin(np.hypot(xs[open_], ys[open_]))]
        return (float(xs[i]), float(ys[i]), 0.0)

    def snap(self, reach, x, y, within):
        """The reachable cell nearest (x, y), within ``within`` m; None if there is none."""
        rr, cc = np.nonzero(reach)
        if rr.size == 0:
            return None
        xs, ys = self.xy(rr, cc)
        d = np.hypot(xs - x, ys - y)
        i = int(np.argmin(d))
        if d[i] > within:
            return None
        return (float(x), float(y)) if d[i] <= self.res else (float(xs[i]), float(ys[i]))

    def spread(self, reach, start, most=10):
        """A few reachable spots far apart (farthest-point sampling from the start, at least
        two, spaced by the region's size up to 2.5 m), in the open (clearance >= 0.7 m
        where there is such)."""
        spacing = min(2.5, max(1.0, math.sqrt(reach.sum() * self.res**2 / 6)))
        for need in (0.7, 0.5, 0.4, 0.0):  # views from the open, not from corners
            rr, cc = np.nonzero(reach & (self.clear >= need))
            if rr.size >= 10:
                break
        if rr.size == 0:
            return []
        xs, ys = self.xy(rr, cc)
        d = np.hypot(xs - start[0], ys - start[1])
        out: list[tuple[float, float]] = []
        while len(out) < most:
            i = int(np.argmax(d))
            if d[i] < spacing and len(out) >= 2 or d[i] <= 0:
                break
            out.append((float(xs[i]), float(ys[i])))
            d = np.minimum(d, np.hypot(xs - xs[i], ys - ys[i]))
        return out

    def splits(self, reach, blocked) -> bool:
        """Whether ``reach`` less the ``blocked`` cells (an object's footprint grown by
        the robot's) falls apart near them: the object would close a doorway or a
        corridor (locally, within 1.2 m: a house has loops, and a detour round the whole
        house is no way). Pockets under 0.1 m² cut off in a corner do not count."""
        rr, cc = np.nonzero(blocked)
        if rr.size == 0:
            return False
        m = int(math.ceil(1.2 / self.res))
        sl = (slice(max(rr.min() - m, 0), rr.max() + m + 1), slice(max(cc.min() - m, 0), cc.max() + m + 1))

        def parts(mask):
            _, _, stats = _components(mask, 8)
            return int((stats[1:, 4] * self.res**2 >= 0.1).sum())

        return parts(reach[sl] & ~blocked[sl]) > parts(reach[sl])

    def line_of_sight(self, a, b) -> bool:
        """No wall cell on the segment a-b (sampled every half cell)."""
        n = max(2, int(math.hypot(b[0] - a[0], b[1] - a[1]) / (self.res / 2)) + 1)
        for t in np.linspace(0, 1, n):
            r, c = self.cell(a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]))
            if not self.inside(r, c) or self.walls[r, c]:
                return False
        return True


# ---------------------------------------------------------------------------------------
# locations


def read_locations(path: str | Path) -> dict:
    """``name -> (x, y, yaw, node, ctx)`` from a locations YAML (``name: [x, y, theta]`` or
    ``[x, y]``; metres, radians); errors name file:line:column."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise WorldError(f"{path}: cannot read the locations file: {e.strerror or e}") from None
    root, ctx = compose_yaml(text, str(path), "empty locations file (expected name: [x, y, theta] lines)")
    out = {}
    for name, (knode, vnode) in ctx.mapping(root, "locations").items():
        items = ctx.seq(vnode, f"location '{name}'")
        if len(items) not in (2, 3):
            raise ctx.err(vnode, f"location '{name}' must be [x, y, theta] or [x, y], got {len(items)} numbers")
        vals = [ctx.num(i, f"location '{name}'") for i in items]
        out[name] = (vals[0], vals[1], vals[2] if len(vals) == 3 else 0.0, vnode, ctx)
    for group in (START_NAMES, PLACE_NAMES):
        both = sorted((n for n in group if n in out), key=lambda n: out[n][3].start_mark.index)
        if len(both) > 1:
            raise out[both[1]][4].err(out[both[1]][3], f"both '{both[0]}' and '{both[1]}' are given; keep one")
    return out


def write_locations(path: str | Path, named: dict) -> Path:
    """Write a locations YAML (see the module's docstring): ``named`` maps a name to
    (x, y) or (x, y, theta) [m, rad]. Returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(f"{name}: [{', '.join(f'{float(v):.4f}' for v in xy)}]\n" for name, xy in named.items()))
    return path


def _pick(named: dict, names):
    for n in names:
        if n in named:
            return named[n]
    return None


def _check_locations(named: dict, g: _Grid, path) -> None:
    for name, (x, y, _, node, ctx) in named.items():
        r, c = g.cell(x, y)
        if not g.inside(r, c) or not (g.free[r, c] or g.walls[r, c]):
            raise ctx.err(node, f"location '{name}' ({x:g}, {y:g}) is outside the map's known space")
        if not g.free[r, c]:
            raise ctx.err(node, f"location '{name}' ({x:g}, {y:g}) is in a wall")


def _place_box(g: _Grid, reach, start, place) -> Box:
    """The pallet: at the named location (its footprint on free floor, the robot able to
    come within 0.8 m of it), else on open floor 1-3 m from the start."""
    sx, sy, sz = PALLET
    if place is not None:
        x, y, yaw, node, ctx = place
        box = Box("pallet", x, y, sx, sy, sz, yaw, PALLET_RGBA)
        rr, cc = np.nonzero(g.walls | ~g.free)
        px, py = g.xy(rr, cc)
        if (box.distance(px, py) < g.res * 0.71).any():
            raise ctx.err(
                node, f"place location ({x:g}, {y:g}): the pallet ({sx} x {sy} m) overlaps a wall or unknown space"
            )
        if g.snap(reach, x, y, 0.8) is None:
            raise ctx.err(node, f"place location ({x:g}, {y:g}) cannot be reached from the start")
        return box
    rr, cc = np.nonzero(reach)
    xs, ys = g.xy(rr, cc)
    d = np.hypot(xs - start[0], ys - start[1])
    cl = g.clear[rr, cc]
    xs_all, ys_all = g.xy(*np.indices(reach.shape))
    for need in (0.8, 0.6, 0.45):  # room to go round it; less if the map is cramped
        ok = (cl >= need) & (d >= 1.0)
        if ok.any():
            for i in np.flatnonzero(ok)[np.argsort(np.abs(d[ok] - 1.5))][:50]:
                box = Box("pallet", float(xs[i]), float(ys[i]), sx, sy, sz, 0.0, PALLET_RGBA)
                if not g.splits(reach, box.distance(xs_all, ys_all) < REACH_RADIUS + PASSAGE):
                    return box
    raise WorldError(
        "no open floor near the start for the place location; name one in the locations file ('place: [x, y, theta]')"
    )


def _place_objects(g: _Grid, reach, spec: WorldSpec, rng) -> list[PlacedObject]:
    """One of each of :func:`map_world_objects` at a random reachable spot within NEAR_LOCATION of a
    search location (each object at another location when there are enough), in sight of it."""
    rr, cc = np.nonzero(reach)
    xs, ys = g.xy(rr, cc)
    cl = g.clear[rr, cc]
    sx, sy, _ = spec.robot_start
    placed: list[tuple[float, float, float]] = []
    out = []
    locs = list(spec.search_locations) or [spec.robot_start[:2]]
    order = [locs[i] for i in rng.permutation(len(locs))]
    xs_all, ys_all = g.xy(*np.indices(reach.shape))
    for k, cat in enumerate(map_world_objects()):
        r = CATEGORIES[cat].radius
        ok = (cl >= OBJECT_CLEARANCE + r) & (np.hypot(xs - sx, ys - sy) >= 0.26 + r + OBJECT_CLEARANCE)
        if spec.place is not None:
            ok &= spec.place.distance(xs, ys) >= r + OBJECT_CLEARANCE
        for px, py, pr in placed:
            ok &= np.hypot(xs - px, ys - py) >= r + pr + OBJECT_CLEARANCE
        found = None
        for j in range(len(order)):  # this object's location first, then the others
            lx, ly = order[(k + j) % len(order)]
            near = np.flatnonzero(ok & (np.hypot(xs - lx, ys - ly) <= NEAR_LOCATION))
            for i in rng.permutation(near)[:200]:
                disc = np.hypot(xs_all - xs[i], ys_all - ys[i]) < r + REACH_RADIUS + PASSAGE
                if g.line_of_sight((lx, ly), (xs[i], ys[i])) and not g.splits(reach, disc):
                    found = (float(xs[i]), float(ys[i]))
                    break
            if found:
                break
        if found is None:
            raise WorldError(
                f"{spec.source}: cannot place the {cat}: no reachable spot with "
                f"{OBJECT_CLEARANCE} m clearance within {NEAR_LOCATION} m of a search location"
            )
        placed.append((found[0], found[1], r))
        out.append(PlacedObject(f"{cat}_1", cat, found[0], found[1], float(rng.uniform(-math.pi, math.pi))))
    return out
