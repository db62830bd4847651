"""Occupancy grid derived from a world's geometry, and map_server's PGM + YAML pair.

Cells covered by walls, furniture or the place location are occupied (100). Free cells that
the robot's start cell reaches by 4-connected flood fill are free (0); everything else
(outside the house, inside closed furniture) is unknown (-1), as a SLAM map would be.
"""

from __future__ import annotations

import array
import math
from collections import deque
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from common.pgm import is_pgm, read_pgm

from .marked_yaml import compose_yaml
from .world_spec import WorldError, WorldSpec

RESOLUTION = 0.05


@dataclass
class GridMap:
    data: np.ndarray  # int8 [rows=y, cols=x], row 0 at origin y (OccupancyGrid order)
    resolution: float
    origin: tuple  # (x, y) of the lower-left corner of cell (0, 0)

    @property
    def width(self):
        return self.data.shape[1]

    @property
    def height(self):
        return self.data.shape[0]

    def cell(self, x, y):
        return int(math.floor((y - self.origin[1]) / self.resolution)), int(
            math.floor((x - self.origin[0]) / self.resolution)
        )

    def value_at(self, x, y):
        r, c = self.cell(x, y)
        if 0 <= r < self.height and 0 <= c < self.width:
            return int(self.data[r, c])
        return -1


def build_grid(spec: WorldSpec, resolution: float = RESOLUTION, height: float | None = None) -> GridMap:
    """The world's occupancy grid. ``height`` [m] None: every static box is an obstacle
    (the grid the robot plans on); a number: a slice at that height above the floor, as a
    lidar there sees it: the boxes whose vertical extent (0..sz) covers it, and the
    objects tall enough (what a map built from the scan should show)."""
    x0, y0, x1, y1 = spec.bounds
    w = int(math.ceil((x1 - x0) / resolution - 1e-9))
    h = int(math.ceil((y1 - y0) / resolution - 1e-9))
    xs = x0 + (np.arange(w) + 0.5) * resolution
    ys = y0 + (np.arange(h) + 0.5) * resolution
    X, Y = np.meshgrid(xs, ys)
    occ = np.zeros((h, w), dtype=bool)
    half_cell = resolution / 2
    obstacles = spec.obstacles if height is None else [ob for ob in spec.obstacles if ob.sz >= height]
    for ob in obstacles:
        # a cell is occupied if the obstacle covers any part of it (conservative)
        c, s = math.cos(ob.yaw), math.sin(ob.yaw)
        dx, dy = X - ob.x, Y - ob.y
        u, v = c * dx + s * dy, -s * dx + c * dy
        ext = half_cell * (abs(c) + abs(s))  # a cell's half-extent along the box's axes
        occ |= (np.abs(u) <= ob.sx / 2 + ext - 1e-9) & (np.abs(v) <= ob.sy / 2 + ext - 1e-9)
    if height is not None:
        from .objects import CATEGORIES

        for o in spec.objects:  # standing objects as discs (a lidar sees the bottle)
            cat = CATEGORIES[o.category]
            if cat.height >= height:
                occ |= np.hypot(X - o.x, Y - o.y) <= cat.radius + half_cell
    grid = np.full((h, w), -1, dtype=np.int8)
    grid[occ] = 100
    # flood fill the free space reachable from the robot's start
    gm = GridMap(grid, resolution, (x0, y0))
    r0, c0 = gm.cell(spec.robot_start[0], spec.robot_start[1])
    if 0 <= r0 < h and 0 <= c0 < w and not occ[r0, c0]:
        seen = np.zeros_like(occ)
        seen[r0, c0] = True
        q = deque([(r0, c0)])
        while q:
            r, c = q.popleft()
            for rr, cc in ((r + 1, c), (r - 1, c), (r, c + 1), (r, c - 1)):
                if 0 <= rr < h and 0 <= cc < w and not seen[rr, cc] and not occ[rr, cc]:
                    seen[rr, cc] = True
                    q.append((rr, cc))
        grid[seen] = 0
    return gm


def occupancy_grid_msg(gm: GridMap, stamp=None, frame_id="map"):
    """nav_msgs/OccupancyGrid for a GridMap."""
    from nav_msgs.msg import OccupancyGrid

    msg = OccupancyGrid()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
        msg.info.map_load_time = stamp
    msg.info.resolution = float(gm.resolution)
    msg.info.width = gm.width
    msg.info.height = gm.height
    msg.info.origin.position.x = float(gm.origin[0])
    msg.info.origin.position.y = float(gm.origin[1])
    msg.info.origin.orientation.w = 1.0
    msg.data = array.array("b", gm.data.astype(np.int8).ravel().tobytes())
    return msg


def write_pgm_yaml(gm: GridMap, out_pgm: str | Path) -> tuple[Path, Path]:
    """map_server format: P5 PGM (254 free, 0 occupied, 205 unknown; top row = max y) + YAML."""
    out_pgm = Path(out_pgm)
    if out_pgm.suffix != ".pgm":
        out_pgm = out_pgm.with_suffix(".pgm")
    out_pgm.parent.mkdir(parents=True, exist_ok=True)
    img = np.full(gm.data.shape, 205, dtype=np.uint8)
    img[gm.data == 0] = 254
    img[gm.data == 100] = 0
    img = np.flipud(img)
    with open(out_pgm, "wb") as f:
        f.write(f"P5\n# actorbt sim map, resolution {gm.resolution}\n{gm.width} {gm.height}\n255\n".encode())
        f.write(img.tobytes())
    out_yaml = out_pgm.with_suffix(".yaml")
    out_yaml.write_text(
        f"image: {out_pgm.name}\n"
        f"mode: trinary\n"
        f"resolution: {gm.resolution}\n"
        f"origin: [{gm.origin[0]:.6g}, {gm.origin[1]:.6g}, 0.0]\n"
        f"negate: 0\n"
        f"occupied_thresh: 0.65\n"
        f"free_thresh: 0.196\n"
    )  # as ROS map_saver: 205 (p = 0.196) reads back as unknown
    return out_pgm, out_yaml


def read_pgm_yaml(path_yaml: str | Path) -> GridMap:
    """Read a map_server pair back (any mode; see :func:`read_map`)."""
    return read_map(path_yaml).grid


# ---------------------------------------------------------------------------------------
# map_server maps: YAML (checked with file:line:column) + PGM (P5/P2, 8 or 16 bit) or PNG

MAP_KEYS = {"image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh", "mode"}
OCCUPIED_MIN = 65  # cells >= this are obstacles (nav2's costmap default, 0.65)
FREE_MAX = 19  # cells <= this are free (map_saver's 0.196)


@dataclass
class MapFile:
    """A map_server map as read: the grid in OccupancyGrid values (-1 unknown, 0..100), the
    YAML's path and the mode. ``occupied`` / ``free`` classify the cells for a world."""

    grid: GridMap
    path: Path
    mode: str

    @property
    def occupied(self) -> np.ndarray:
        return self.grid.data >= OCCUPIED_MIN

    @property
    def free(self) -> np.ndarray:
        return (self.grid.data >= 0) & (self.grid.data <= FREE_MAX)


def is_map_yaml(text: str) -> bool:
    """Whether a YAML text is a map_server map (a mapping with 'image' and 'resolution')
    rather than a world description. Broken YAML is not a map (the world parser reports it)."""
    import yaml

    try:
        root = yaml.compose(text)
    except yaml.YAMLError:
        return False
    if not isinstance(root, yaml.MappingNode):
        return False
    keys = {k.value for k, _ in root.value if isinstance(k, yaml.ScalarNode)}
    return {"image", "resolution"} <= keys


def _image_pixels(path: Path, where: str):
    """(lightness 0..1 [rows, cols] top row first, alpha 0..1 or None) of a map image."""
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise WorldError(f"{where}: cannot read the image {path}: {e.strerror or e}") from None
    if is_pgm(raw):
        return read_pgm(raw, str(path), WorldError), None
    import cv2  # PNG, BMP...: as map_server (SDL_image) reads them

    img = cv2.imdecode(np.frombuffer(raw, np.uint8), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise WorldError(f"{where}: cannot decode the image {path}")
    scale = 65535.0 if img.dtype == np.uint16 else 255.0
    img = img.astype(np.float64) / scale
    if img.ndim == 2:
        return img, None
    alpha = img[..., 3] if img.shape[2] == 4 else None
    return img[..., :3].mean(axis=2), alpha  # map_server averages the colour channels


def read_map(path_yaml: str | Path) -> MapFile:
    """Read a map_server map as ``map_server`` does: trinary (default), scale or raw mode,
    ``negate``, the two thresholds; errors name the YAML's file:line:column.
    The origin's yaw must be 0 (an axis-aligned grid)."""
    path_yaml = Path(path_yaml)
    try:
        text = path_yaml.read_text()
    except OSError as e:
        raise WorldError(f"{path_yaml}: cannot read: {e.strerror or e}") from None
    root, ctx = compose_yaml(text, str(path_yaml), "empty map YAML")
    top = ctx.mapping(root, "map")
    ctx.keys(top, MAP_KEYS, "map")
    for req in ("image", "resolution", "origin"):
        if req not in top:
            raise ctx.err(root, f"map: missing '{req}'")
    img_node = top["image"][1]
    image = Path(ctx.str_(img_node, "image"))
    if not image.is_absolute():
        image = path_yaml.parent / image
    res = ctx.num(top["resolution"][1], "resolution", positive=True)
    onode = top["origin"][1]
    origin = ctx.vec(onode, 3, "origin")
    if abs(origin[2]) > 1e-9:
        raise ctx.err(
            onode,
            f"origin: yaw {origin[2]:g} rad is not supported (only axis-aligned maps, yaw 0); rotate the image instead",
        )
    negate = ctx.int_(top["negate"][1], "negate") if "negate" in top else 0
    if negate not in (0, 1):
        raise ctx.err(top["negate"][1], f"negate must be 0 or 1, got {negate}")
    occ_t = ctx.num(top["occupied_thresh"][1], "occupied_thresh") if "occupied_thresh" in top else 0.65
    free_t = ctx.num(top["free_thresh"][1], "free_thresh") if "free_thresh" in top else 0.196
    if not 0 <= free_t < occ_t <= 1:
        raise ctx.err(root, f"need 0 <= free_thresh < occupied_thresh <= 1, got {free_t:g} and {occ_t:g}")
    mode = ctx.str_(top["mode"][1], "mode") if "mode" in top else "trinary"
    if mode not in ("trinary", "scale", "raw"):
        raise ctx.err(top["mode"][1], f"mode: unknown '{mode}' (trinary, scale or raw)")
    img_where = f"{path_yaml}:{img_node.start_mark.line + 1}:{img_node.start_mark.column + 1}"
    light, alpha = _image_pixels(image, img_where)
    light = np.flipud(light)  # the image's top row is the map's last row (max y)
    alpha = np.flipud(alpha) if alpha is not None else None
    data = np.full(light.shape, -1, dtype=np.int8)
    if mode == "raw":  # the pixel value is the cell value (255 -> -1)
        v = np.rint(light * 255).astype(np.int64)
        data[v <= 100] = v[v <= 100]
    else:
        p = light if negate else 1.0 - light  # occupancy probability
        data[p > occ_t] = 100
        data[p < free_t] = 0
        if mode == "scale":
            band = (p >= free_t) & (p <= occ_t)
            data[band] = np.rint(99 * (p[band] - free_t) / (occ_t - free_t)).astype(np.int8)
            if alpha is not None:
                data[alpha < 1.0] = -1  # transparent pixels are unknown in scale mode
    return MapFile(GridMap(data, res, (origin[0], origin[1])), path_yaml, mode)


def lidar_height() -> float:
    """Height of the lidar's beam above the floor [m]: the ``base_scan`` frame's z in
    ``base_footprint``, summed along the URDF's fixed joints (0.132 m for the Waffle Pi)."""
    import xml.etree.ElementTree as ET

    urdf = Path(__file__).resolve().parent / "models" / "mobile_manipulator.urdf"
    parent_of: dict[str, tuple[str, float]] = {}  # link -> (its parent link, its z there)
    for j in ET.parse(urdf).getroot().iter("joint"):
        o = j.find("origin")
        z = float(o.get("xyz", "0 0 0").split()[2]) if o is not None else 0.0
        parent, child = j.find("parent"), j.find("child")
        if parent is None or child is None:
            raise ValueError(f"{urdf}: joint {j.get('name')!r} needs a <parent> and a <child>")
        parent_of[child.get("link", "")] = (parent.get("link", ""), z)
    link, z = "base_scan", 0.0
    while link in parent_of and link != "base_footprint":
        link, dz = parent_of[link]
        z += dz
    return z
