"""Occupancy maps: nav_msgs/OccupancyGrid's layout, and map_server's YAML + PGM pair.

An :class:`OccupancyMap` holds the grid as ``nav_msgs/OccupancyGrid`` does: ``data[row, col]``
is an int8 (-1 unknown, 0 free .. 100 occupied), row 0 at the map origin, ``resolution``
metres a cell, and the origin (x, y, yaw) is the map-frame pose of the corner of cell (0, 0).

:func:`read_map_yaml` reads what ``map_server`` reads (the YAML keys ``image``,
``resolution``, ``origin``, ``negate``, ``occupied_thresh``, ``free_thresh`` and ``mode``:
``trinary`` (default), ``scale`` or ``raw``), for PGM images (P5 binary or P2 ASCII,
8 or 16 bits); :func:`write_map_yaml` writes what ``map_saver`` writes (trinary).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from common.pgm import read_pgm

FREE = 0
OCCUPIED = 100
UNKNOWN = -1


class MapError(ValueError):
    """A map file or message that cannot be read."""


@dataclass(frozen=True)
class OccupancyMap:
    data: np.ndarray  # int8 (height, width), row 0 at the origin
    resolution: float  # [m / cell]
    origin: tuple = (0.0, 0.0, 0.0)  # map-frame pose (x, y, yaw) of cell (0, 0)'s corner

    def __post_init__(self) -> None:
        arr = np.asarray(self.data)
        if arr.ndim != 2 or arr.size == 0:
            raise MapError(f"map data must be a non-empty 2-D array, got shape {arr.shape}")
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise MapError(f"map resolution must be > 0, got {self.resolution!r}")
        origin = tuple(float(v) for v in self.origin) + (0.0,) * (3 - len(self.origin))
        object.__setattr__(self, "data", arr.astype(np.int8, copy=False))
        object.__setattr__(self, "origin", origin[:3])

    # -- geometry ------------------------------------------------------------------------
    @property
    def height(self) -> int:
        return self.data.shape[0]

    @property
    def width(self) -> int:
        return self.data.shape[1]

    def to_grid(self, x, y):
        """Map-frame points to continuous grid coordinates (col, row), in cells."""
        ox, oy, oyaw = self.origin
        dx, dy = np.asarray(x, float) - ox, np.asarray(y, float) - oy
        if oyaw:
            c, s = math.cos(oyaw), math.sin(oyaw)
            dx, dy = c * dx + s * dy, -s * dx + c * dy
        return dx / self.resolution, dy / self.resolution

    def to_world(self, col, row):
        """Continuous grid coordinates (col, row) [cells] to map-frame points (x, y)."""
        gx, gy = np.asarray(col, float) * self.resolution, np.asarray(row, float) * self.resolution
        ox, oy, oyaw = self.origin
        if oyaw:
            c, s = math.cos(oyaw), math.sin(oyaw)
            gx, gy = c * gx - s * gy, s * gx + c * gy
        return gx + ox, gy + oy

    def cell_centres(self, mask: np.ndarray):
        """Map-frame (x, y) arrays of the centres of the cells where ``mask`` is true."""
        rows, cols = np.nonzero(mask)
        return self.to_world(cols + 0.5, rows + 0.5)

    def value_at(self, x: float, y: float) -> int:
        """The cell value at a map point; UNKNOWN outside the grid."""
        gx, gy = self.to_grid(x, y)
        c, r = int(math.floor(gx)), int(math.floor(gy))
        if 0 <= r < self.height and 0 <= c < self.width:
            return int(self.data[r, c])
        return UNKNOWN

    # -- classification (as AMCL reads a map: 0 free, 100 occupied, the rest unknown) ------
    def occupied(self, threshold: int = 65) -> np.ndarray:
        return self.data >= threshold

    def free(self, threshold: int = 19) -> np.ndarray:
        return (self.data >= 0) & (self.data <= threshold)

    # -- messages --------------------------------------------------------------------------
    @classmethod
    def from_msg(cls, msg) -> OccupancyMap:
        """From a ``nav_msgs/msg/OccupancyGrid``."""
        info = msg.info
        q = info.origin.orientation
        yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
        n = info.width * info.height
        data = np.frombuffer(bytes(np.asarray(msg.data, dtype=np.int8).tobytes()), dtype=np.int8)
        if data.size != n:
            raise MapError(f"OccupancyGrid has {data.size} cells, width x height = {n}")
        return cls(
            data.reshape(info.height, info.width).copy(),
            float(info.resolution),
            (info.origin.position.x, info.origin.position.y, yaw),
        )

    def to_msg(self, frame_id: str = "map", stamp=None):
        """A ``nav_msgs/msg/OccupancyGrid``."""
        import array

        from nav_msgs.msg import OccupancyGrid

        msg = OccupancyGrid()
        msg.header.frame_id = frame_id
        if stamp is not None:
            msg.header.stamp = stamp
            msg.info.map_load_time = stamp
        msg.info.resolution = float(self.resolution)
        msg.info.width, msg.info.height = self.width, self.height
        msg.info.origin.position.x, msg.info.origin.position.y = self.origin[0], self.origin[1]
        msg.info.origin.orientation.z = math.sin(self.origin[2] / 2)
        msg.info.origin.orientation.w = math.cos(self.origin[2] / 2)
        msg.data = array.array("b", self.data.tobytes())
        return msg


# -- map_server files --------------------------------------------------------------------------
def read_map_yaml(path: str | Path) -> OccupancyMap:
    """Read a map_server YAML file and its image into an :class:`OccupancyMap`."""
    path = Path(path)
    try:
        meta = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as e:
        raise MapError(f"{path}: {e}") from None
    if not isinstance(meta, dict):
        raise MapError(f"{path}: expected a mapping")
    missing = {"image", "resolution", "origin"} - set(meta)
    if missing:
        raise MapError(f"{path}: missing {', '.join(sorted(missing))}")
    mode = meta.get("mode", "trinary")
    if mode not in ("trinary", "scale", "raw"):
        raise MapError(f"{path}: mode must be trinary, scale or raw, got {mode!r}")
    occ_t = float(meta.get("occupied_thresh", 0.65))
    free_t = float(meta.get("free_thresh", 0.25))
    negate = bool(meta.get("negate", 0))
    image = Path(meta["image"])
    if not image.is_absolute():
        image = path.parent / image
    # the image's top row is the map's highest y
    bright = np.flipud(read_pgm(image.read_bytes(), str(image), MapError))
    if mode == "raw":
        value = np.rint(bright * 255)
        data = np.where(value <= 100, value, UNKNOWN).astype(np.int8)
    else:
        p = bright if negate else 1.0 - bright  # occupancy probability, as map_server
        data = np.full(p.shape, UNKNOWN, dtype=np.int8)
        data[p > occ_t] = OCCUPIED
        data[p < free_t] = FREE
        if mode == "scale":
            mid = (p >= free_t) & (p <= occ_t)
            data[mid] = np.rint(99 * (p[mid] - free_t) / (occ_t - free_t)).astype(np.int8)
    origin = meta["origin"]
    if len(origin) < 2:
        raise MapError(f"{path}: origin needs [x, y, yaw]")
    return OccupancyMap(data, float(meta["resolution"]), tuple(float(v) for v in origin[:3]))


def write_map_yaml(m: OccupancyMap, out_yaml: str | Path) -> tuple[Path, Path]:
    """Write map_saver's trinary pair: P5 PGM (254 free, 0 occupied, 205 unknown) + YAML."""
    out_yaml = Path(out_yaml).with_suffix(".yaml")
    out_pgm = out_yaml.with_suffix(".pgm")
    img = np.full(m.data.shape, 205, dtype=np.uint8)
    img[(m.data >= 0) & (m.data <= 19)] = 254
    img[m.data >= 65] = 0
    out_pgm.write_bytes(f"P5\n{m.width} {m.height}\n255\n".encode() + np.flipud(img).tobytes())
    out_yaml.write_text(
        f"image: {out_pgm.name}\nmode: trinary\nresolution: {m.resolution}\n"
        f"origin: [{m.origin[0]:.6g}, {m.origin[1]:.6g}, {m.origin[2]:.6g}]\n"
        f"negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    return out_yaml, out_pgm


def write_trajectory_tum(poses, path: str | Path) -> Path:
    """Write (t [s], x [m], y [m], yaw [rad]) poses in the TUM format that trajectory
    tools (evo, the TUM RGB-D benchmark's scripts) read: ``t x y z qx qy qz qw`` per line,
    z 0 and the yaw as a quaternion about z."""
    path = Path(path)
    lines = [f"{t:.6f} {x:.6f} {y:.6f} 0 0 0 {math.sin(yaw / 2):.9f} {math.cos(yaw / 2):.9f}" for t, x, y, yaw in poses]
    path.write_text("# t x y z qx qy qz qw: the SLAM keyframes in the map frame\n" + "\n".join(lines) + "\n")
    return path


def read_trajectory_tum(path: str | Path) -> list[tuple[float, float, float, float]]:
    """(t, x, y, yaw) per line of a TUM trajectory file (the yaw from the quaternion)."""
    out = []
    for n, line in enumerate(Path(path).read_text().splitlines(), 1):
        if not line.strip() or line.startswith("#"):
            continue
        f = line.split()
        if len(f) != 8:
            raise MapError(f"{path}:{n}: expected 't x y z qx qy qz qw', got {len(f)} fields")
        t, x, y, _, qx, qy, qz, qw = (float(v) for v in f)
        out.append((t, x, y, math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))))
    return out
