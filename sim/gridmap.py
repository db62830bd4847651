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

from .description import WorldSpec

RESOLUTION = 0.05


@dataclass
class GridMap:
    data: np.ndarray        # int8 [rows=y, cols=x], row 0 at origin y (OccupancyGrid order)
    resolution: float
    origin: tuple           # (x, y) of the lower-left corner of cell (0, 0)

    @property
    def width(self):
        return self.data.shape[1]

    @property
    def height(self):
        return self.data.shape[0]

    def cell(self, x, y):
        return int(math.floor((y - self.origin[1]) / self.resolution)), \
            int(math.floor((x - self.origin[0]) / self.resolution))

    def value_at(self, x, y):
        r, c = self.cell(x, y)
        if 0 <= r < self.height and 0 <= c < self.width:
            return int(self.data[r, c])
        return -1


def build_grid(spec: WorldSpec, resolution: float = RESOLUTION) -> GridMap:
    x0, y0, x1, y1 = spec.bounds
    w = int(math.ceil((x1 - x0) / resolution - 1e-9))
    h = int(math.ceil((y1 - y0) / resolution - 1e-9))
    xs = x0 + (np.arange(w) + 0.5) * resolution
    ys = y0 + (np.arange(h) + 0.5) * resolution
    X, Y = np.meshgrid(xs, ys)
    occ = np.zeros((h, w), dtype=bool)
    half_cell = resolution / 2
    for ob in spec.obstacles:
        # a cell is occupied if the obstacle covers any part of it (conservative)
        c, s = math.cos(ob.yaw), math.sin(ob.yaw)
        dx, dy = X - ob.x, Y - ob.y
        u, v = c * dx + s * dy, -s * dx + c * dy
        ext = half_cell * (abs(c) + abs(s))    # a cell's half-extent along the box's axes
        occ |= (np.abs(u) <= ob.sx / 2 + ext - 1e-9) & (np.abs(v) <= ob.sy / 2 + ext - 1e-9)
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
        f"free_thresh: 0.196\n")   # as ROS map_saver: 205 (p = 0.196) reads back as unknown
    return out_pgm, out_yaml


def read_pgm_yaml(path_yaml: str | Path) -> GridMap:
    """Read a map_server pair back (trinary)."""
    import yaml

    path_yaml = Path(path_yaml)
    meta = yaml.safe_load(path_yaml.read_text())
    raw = (path_yaml.parent / meta["image"]).read_bytes()
    # header: magic, optional comments, width height, maxval
    fields, pos = [], 0
    while len(fields) < 4:
        while raw[pos:pos + 1].isspace():
            pos += 1
        if raw[pos:pos + 1] == b"#":
            pos = raw.index(b"\n", pos) + 1
            continue
        end = pos
        while not raw[end:end + 1].isspace():
            end += 1
        fields.append(raw[pos:end])
        pos = end
    pos += 1
    w, h = int(fields[1]), int(fields[2])
    img = np.flipud(np.frombuffer(raw[pos:pos + w * h], dtype=np.uint8).reshape(h, w))
    data = np.full((h, w), -1, dtype=np.int8)
    p = (255 - img.astype(float)) / 255.0
    data[p > meta["occupied_thresh"]] = 100
    data[p < meta["free_thresh"]] = 0
    return GridMap(data, float(meta["resolution"]), tuple(meta["origin"][:2]))
